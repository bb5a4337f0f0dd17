//! Pictures: plots, animations and heat maps, checked against independent oracles (an
//! XML parser, a PNG decoder, a GIF decoder, the core twin stepped on its own).
//!
//! With `PICTURES_DIR=/some/dir` the tests also leave their pictures there to look at
//! (a heat map of made-up data and a few animation frames as PNG).

mod common;

use common::{read, run, utf8, TempDir};
use host_sim::animate::{self, Frames};
use host_sim::draw::{heatmap, pt, Color, Figure, HeatMap, Stroke};
use host_sim::pictures::Recorder;
use host_sim::{RunOptions, ScenarioId};
use std::path::Path;
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
use structomat::motor::Motor;

/// A PNG's size and 8-bit RGB(A) pixels, decoded by the `png` crate.
fn decode_png(bytes: &[u8]) -> (u32, u32, usize, Vec<u8>) {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .expect("PNG header");
    let mut buf = vec![0; dec.output_buffer_size().expect("buffer size")];
    let info = dec.next_frame(&mut buf).expect("PNG frame");
    buf.truncate(info.buffer_size());
    (info.width, info.height, info.color_type.samples(), buf)
}

fn keep(name: &str, bytes: &[u8]) {
    if let Ok(dir) = std::env::var("PICTURES_DIR") {
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(Path::new(&dir).join(name), bytes);
    }
}

#[test]
fn png_has_the_size_and_the_line_where_it_was_drawn() {
    let mut f = Figure::new(120, 80);
    let red = Color::rgb(220, 0, 0);
    f.line(pt(10.0, 40.0), pt(110.0, 40.0), Stroke::solid(red, 4.0));
    let (w, h, samples, px) = decode_png(&f.to_png().expect("png"));
    assert_eq!((w, h, samples), (120, 80, 3));
    let at = |x: usize, y: usize| &px[(y * w as usize + x) * 3..][..3];
    // On the line (y 38..42): red; away from it: the white background.
    assert_eq!(at(60, 40), [220, 0, 0]);
    assert_eq!(at(60, 39), [220, 0, 0]);
    assert_eq!(at(60, 10), [255, 255, 255]);
    assert_eq!(at(5, 40), [255, 255, 255], "before the line's start");
    // Exactly the line's pixels differ from the background (4 px x 100 px), give or
    // take the anti-aliased ends.
    let inked = px.chunks_exact(3).filter(|p| *p != [255, 255, 255]).count();
    assert!((400..=420).contains(&inked), "{inked}");
}

#[test]
fn text_is_drawn_with_the_shipped_font() {
    use host_sim::draw::{Anchor, Text, TextSize};
    let mut f = Figure::new(200, 40);
    f.text(Text::new(
        pt(100.0, 20.0),
        "t = 0.25 s",
        TextSize::Small,
        Anchor::Middle,
    ));
    let (w, _, _, px) = decode_png(&f.to_png().expect("png"));
    let inked: Vec<(usize, usize)> = px
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| p[0] < 128)
        .map(|(k, _)| (k % w as usize, k / w as usize))
        .collect();
    assert!(inked.len() > 40, "the glyphs leave ink: {}", inked.len());
    // Centred: the ink spans about the text's width (10 characters) around x = 100.
    let (x0, x1) = inked
        .iter()
        .fold((usize::MAX, 0), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let width = TextSize::Small.width("t = 0.25 s");
    assert!((x0 as f64) >= 100.0 - width / 2.0 - 1.0 && (x1 as f64) <= 100.0 + width / 2.0 + 1.0);
    assert!(x1 - x0 > (width * 0.7) as usize);
}

/// `host-sim run ccc-s2 --plot DIR` over 0.2 s.
fn s2_plots(dir: &TempDir) -> std::path::PathBuf {
    let plots = dir.path.join("plots");
    let (code, _, err) = run(&[
        "run",
        "ccc-s2",
        "--t-end",
        "0.2",
        "--out",
        &dir.join("ccc-s2.csv"),
        "--plot",
        utf8(&plots),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    plots
}

const S2_PLOTS: [&str; 7] = [
    "crank",
    "motor_torque",
    "reactions",
    "speeds",
    "clutch_torques",
    "mode",
    "energy",
];

#[test]
fn converter_plots_are_well_formed_svg_and_png() {
    let dir = TempDir::new("pics-s2");
    let plots = s2_plots(&dir);
    // Legend names expected in each plot (one per series).
    let legends: [(&str, &[&str]); 4] = [
        ("speeds", &["lever 6", "lever 8", "shaft", "rocker speed"]),
        ("clutch_torques", &["c6 (lever 6)", "c8 (lever 8)"]),
        (
            "energy",
            &[
                "kinetic",
                "potential",
                "motor work",
                "load work",
                "impact losses",
            ],
        ),
        (
            "reactions",
            &[
                "A",
                "B",
                "C",
                "E",
                "F",
                "D (rod 5)",
                "D (rod 7)",
                "G",
                "I",
                "H (lever 6)",
                "H (lever 8)",
            ],
        ),
    ];
    for stem in S2_PLOTS {
        let svg = String::from_utf8(read(&plots.join(format!("{stem}.svg")))).expect("utf-8");
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{stem}.svg: {e}"));
        assert_eq!(doc.root_element().tag_name().name(), "svg");
        let texts: Vec<&str> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text())
            .collect();
        assert!(texts.iter().any(|t| t.contains("t, s")), "{stem}: x label");
        if let Some((_, names)) = legends.iter().find(|(s, _)| *s == stem) {
            for name in *names {
                assert!(texts.contains(name), "{stem}: legend {name:?} in {texts:?}");
            }
            // One curve per series: each series's colour strokes at least one polyline
            // (a curve is several polylines only where it has gaps).
            let polylines: Vec<_> = doc
                .descendants()
                .filter(|n| n.has_tag_name("polyline"))
                .collect();
            assert!(
                polylines.len() >= names.len(),
                "{stem}: {} polylines",
                polylines.len()
            );
        }
        let (w, h, _, px) = decode_png(&read(&plots.join(format!("{stem}.png"))));
        assert_eq!(w, host_sim::plot::WIDTH, "{stem}");
        assert!(h >= 250, "{stem}: {h}");
        assert!(
            px.chunks_exact(3).any(|p| p != [255, 255, 255]),
            "{stem}: not blank"
        );
    }
    // The mode plot names every mode on its axis.
    let svg = String::from_utf8(read(&plots.join("mode.svg"))).expect("utf-8");
    for m in ["free", "I0", "I6", "I8", "jam", "A6", "A8", "A68", "coast"] {
        assert!(svg.contains(&format!(">{m}</text>")), "{m}");
    }
}

#[test]
fn plot_command_draws_what_run_plot_draws() {
    let dir = TempDir::new("pics-replot");
    let plots = s2_plots(&dir);
    let again = dir.path.join("again");
    let (code, out, err) = run(&["plot", &dir.join("ccc-s2.csv"), "--out-dir", utf8(&again)]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("14 files"), "{out}");
    for stem in S2_PLOTS {
        for ext in ["svg", "png"] {
            let name = format!("{stem}.{ext}");
            assert!(
                read(&plots.join(&name)) == read(&again.join(&name)),
                "{name} differs"
            );
        }
    }
}

#[test]
fn mechanism_plots_and_animation() {
    let dir = TempDir::new("pics-five-bar");
    let plots = dir.path.join("plots");
    let gif = dir.join("fb.gif");
    let (code, _, err) = run(&[
        "run",
        "five-bar",
        "--t-end",
        "0.5",
        "--out",
        &dir.join("fb.csv"),
        "--plot",
        utf8(&plots),
        "--animate",
        &gif,
        "--fps",
        "10",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    for stem in ["coordinates", "torques", "reactions"] {
        let svg = String::from_utf8(read(&plots.join(format!("{stem}.svg")))).expect("utf-8");
        roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{stem}: {e}"));
    }
    let svg = String::from_utf8(read(&plots.join("coordinates.svg"))).expect("utf-8");
    for name in ["q1", "q2", "qd1", "qd2"] {
        assert!(svg.contains(&format!(">{name}</text>")), "{name}");
    }
    // 0.5 s at 10 frames a second: frames at 0, 0.1, ..., 0.5.
    let frames = gif_frames(&read(Path::new(&gif)));
    assert_eq!(frames, 6);
    // Every frame of both mechanisms: each crank's first point stays on its ground
    // pivot (the mechanisms' description: crank 1 turns about ground point 0).
    for scenario in [ScenarioId::FiveBar, ScenarioId::SliderCrank] {
        let frames = mechanism_frames(scenario, 1.0);
        assert_eq!(frames.frames.len(), 11, "{scenario:?}");
        let a = frames.ground[0];
        for fr in &frames.frames {
            let p = fr.links[0].points[0];
            assert!(
                (p[0] - a[0]).abs() < 1e-12 && (p[1] - a[1]).abs() < 1e-12,
                "{p:?} vs {a:?}"
            );
        }
        if let Ok(dir) = std::env::var("PICTURES_DIR") {
            let path = Path::new(&dir).join(format!("{}-frame-05.png", scenario.name()));
            animate::write_frame(&frames, 5, &path).expect("frame");
        }
    }
}

/// A mechanism scenario over `t_end` s with a frame every 0.1 s.
fn mechanism_frames(scenario: ScenarioId, t_end: f64) -> Frames {
    let mut opts = RunOptions::new(scenario);
    opts.t_end = Some(t_end);
    let mut rec = Recorder {
        table: None,
        frames: Some(Frames::new(scenario.name(), 10, 1.0)),
    };
    host_sim::run::simulate::<f64>(&opts, &mut rec).expect("runs");
    rec.frames.expect("frames")
}

/// Frames of a GIF, decoded by the `gif` crate (its screen must be the frame size).
fn gif_frames(bytes: &[u8]) -> usize {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut dec = opts
        .read_info(std::io::Cursor::new(bytes))
        .expect("GIF header");
    assert_eq!(
        (dec.width() as u32, dec.height() as u32),
        animate::FRAME_SIZE
    );
    let mut n = 0;
    while dec.read_next_frame().expect("GIF frame").is_some() {
        n += 1;
    }
    n
}

/// S2 with the pictures' recorder, `t_end` s; the frames.
fn s2_frames(t_end: f64, fps: u32, slow: f64) -> Frames {
    let mut opts = RunOptions::new(ScenarioId::CccS2);
    opts.t_end = Some(t_end);
    let mut rec = Recorder {
        table: None,
        frames: Some(Frames::new("ccc-s2", fps, slow)),
    };
    host_sim::run::simulate::<f64>(&opts, &mut rec).expect("S2 runs");
    rec.frames.expect("frames")
}

#[test]
fn animation_frames_are_the_twins_joint_positions() {
    // 0.1 s at 25 fps, 4 times slower: a frame every 0.01 s = 100 steps.
    let frames = s2_frames(0.1, 25, 4.0);
    assert_eq!(frames.frames.len(), 11);
    // The oracle: the core's twin stepped on its own with S2's settings.
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 800.0,
        measured: None,
    };
    let mut twin = Twin::new(
        CccParams::<f64>::reference(),
        TwinSettings::reference(1e-4),
        inputs,
    )
    .expect("twin");
    for (k, fr) in frames.frames.iter().enumerate() {
        assert_eq!(fr.step, 100 * k as u64, "frame {k} at step");
        while twin.steps() < fr.step {
            twin.step(&inputs).expect("step");
        }
        assert!((fr.t - twin.time()).abs() < 1e-12);
        assert_eq!(fr.mode, Some(twin.mode()));
        for l in &fr.links {
            for (j, p) in l.points.iter().enumerate() {
                // The rocker's third point is D (the twin's point 2).
                let q = twin.joint_position(l.link, j);
                assert_eq!(*p, [q.x, q.y], "frame {k}, link {}, point {j}", l.link);
            }
        }
        assert_eq!(fr.clutch, twin.clutch_torques());
        assert_eq!(fr.shaft_angle, twin.shaft_angle());
    }
    // The pictures of a few frames, to look at.
    if let Ok(dir) = std::env::var("PICTURES_DIR") {
        let frames = s2_frames(1.0, 25, 1.0);
        for k in [0, 2, 7, 15, 22] {
            let path = Path::new(&dir).join(format!("s2-frame-{k:02}.png"));
            let _ = std::fs::create_dir_all(&dir);
            animate::write_frame(&frames, k, &path).expect("frame");
        }
    }
}

#[test]
fn animations_are_valid_and_deterministic() {
    let dir = TempDir::new("pics-anim");
    let args = |svg: &str, gif: &str, plots: &str| {
        run(&[
            "run",
            "ccc-s2",
            "--t-end",
            "0.1",
            "--quiet",
            "--out",
            &dir.join("s2.csv"),
            "--animate",
            svg,
            "--animate",
            gif,
            "--fps",
            "20",
            "--slow",
            "2",
            "--plot",
            plots,
        ])
    };
    let (a_svg, a_gif, a_plots) = (dir.join("a.svg"), dir.join("a.gif"), dir.join("a"));
    let (b_svg, b_gif, b_plots) = (dir.join("b.svg"), dir.join("b.gif"), dir.join("b"));
    for (s, g, p) in [(&a_svg, &a_gif, &a_plots), (&b_svg, &b_gif, &b_plots)] {
        let (code, _, err) = args(s, g, p);
        assert_eq!(code, 0, "{err}");
    }
    assert!(
        read(Path::new(&a_svg)) == read(Path::new(&b_svg)),
        "SVG bytes differ"
    );
    assert!(
        read(Path::new(&a_gif)) == read(Path::new(&b_gif)),
        "GIF bytes differ"
    );
    for stem in S2_PLOTS {
        for ext in ["svg", "png"] {
            let name = format!("{stem}.{ext}");
            let (a, b) = (
                Path::new(&a_plots).join(&name),
                Path::new(&b_plots).join(&name),
            );
            assert!(read(&a) == read(&b), "{name} differs");
        }
    }
    // 0.1 s at 20 fps x 2: a frame every 0.025 s, 5 frames.
    assert_eq!(gif_frames(&read(Path::new(&a_gif))), 5);
    let svg = String::from_utf8(read(Path::new(&a_svg))).expect("utf-8");
    let doc = roxmltree::Document::parse(&svg).expect("animated SVG parses");
    let animates: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("animate"))
        .collect();
    assert!(!animates.is_empty());
    // Every value list has one value a frame; the loop lasts 5 frames of 1/20 s.
    for a in animates
        .iter()
        .filter(|a| a.attribute("keyTimes").is_none())
    {
        let values = a.attribute("values").expect("values");
        assert_eq!(values.split(';').count(), 5, "{values}");
        assert_eq!(a.attribute("dur"), Some("0.25s"));
    }
    // The caption says the mode at t = 0.
    assert!(svg.contains("mode I8"), "the start mode in the caption");
}

#[test]
fn bad_picture_options_are_clear_errors() {
    let dir = TempDir::new("pics-bad");
    let file = dir.join("a-file");
    std::fs::write(&file, "x").expect("write");
    let under_file = format!("{file}/plots");
    let gif_under_file = format!("{file}/x.gif");
    let cases: [(&[&str], u8, &str); 10] = [
        (
            &["run", "ccc-s2", "--animate", "x.gif", "--fps", "0"],
            2,
            "--fps: 0 is out of range",
        ),
        (
            &["run", "ccc-s2", "--animate", "x.gif", "--fps", "51"],
            2,
            "--fps: 51",
        ),
        (
            &["run", "ccc-s2", "--animate", "x.gif", "--slow", "0"],
            2,
            "--slow: 0 is out of range",
        ),
        (
            &["run", "ccc-s2", "--animate", "x.gif", "--slow", "nan"],
            2,
            "--slow",
        ),
        (
            &["run", "ccc-s2", "--animate", "x.mp4"],
            2,
            "no .svg or .gif extension",
        ),
        (
            &["run", "ccc-s2", "--animate", "a.gif", "--animate", "b.gif"],
            2,
            "one .svg and one .gif",
        ),
        (
            &["run", "ccc-s2", "--fps", "10"],
            2,
            "required arguments were not provided:\n  --animate <FILE>",
        ),
        (
            &["run", "ccc-s2", "--animate", "x.gif", "--slow", "1000"],
            2,
            "more than 5000",
        ),
        (
            &[
                "run",
                "ccc-s2",
                "--t-end",
                "0.01",
                "--quiet",
                "--plot",
                &under_file,
            ],
            1,
            "cannot write",
        ),
        (
            &[
                "run",
                "five-bar",
                "--t-end",
                "0.01",
                "--quiet",
                "--animate",
                &gif_under_file,
            ],
            1,
            "cannot write",
        ),
    ];
    for (args, want, needle) in cases {
        let (code, _, err) = run(args);
        assert_eq!(code, want, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // host-sim plot: a missing CSV, a file that is not a run's CSV, bad arguments.
    let (code, _, err) = run(&["plot", &dir.join("none.csv"), "--out-dir", &dir.join("o")]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("cannot read"), "{err}");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "a,b\n1,2\n").expect("write");
    let (code, _, err) = run(&["plot", &bad, "--out-dir", &dir.join("o")]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("not a host-sim run CSV"), "{err}");
    let (code, _, err) = run(&["plot", &bad]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not provided:\n  --out-dir <DIR>"), "{err}");
}

fn made_up_heatmap(nx: usize, ny: usize) -> HeatMap {
    let x: Vec<f64> = (0..nx).map(|i| 8.0 + 2.0 * i as f64).collect();
    let y: Vec<f64> = (0..ny).map(|j| 400.0 + 100.0 * j as f64).collect();
    let mut z = Vec::new();
    for yj in &y {
        for xi in &x {
            // A made-up "first breakaway time": later with more load, earlier with more
            // motor torque; none where the motor cannot beat the load.
            z.push((yj / xi < 90.0).then(|| 0.002 * yj / xi * (1.0 + 0.1 * (xi * 0.7).sin())));
        }
    }
    HeatMap {
        title: "First breakaway (made-up data)".into(),
        x_label: "motor torque, N·m".into(),
        y_label: "load T_r, N·m".into(),
        z_label: "first breakaway, s".into(),
        x,
        y,
        z,
    }
}

#[test]
fn heatmap_svg_png_and_errors() {
    let h = made_up_heatmap(6, 5);
    let f = heatmap(&h);
    let svg = f.to_svg();
    let doc = roxmltree::Document::parse(&svg).expect("heat map SVG parses");
    let cells_without = h.z.iter().filter(|z| z.is_none()).count();
    assert!(cells_without > 0 && cells_without < h.z.len());
    // Every cell is a rectangle of its own colour: count the rectangles of the grey of
    // the cells without a value (plus the legend's swatch).
    let grey = doc
        .descendants()
        .filter(|n| n.has_tag_name("rect") && n.attribute("fill") == Some("#cdcdcd"))
        .count();
    assert_eq!(grey, cells_without + 1);
    // Labels at the cell centres: every x and y value is printed.
    let texts: Vec<&str> = doc.descendants().filter_map(|n| n.text()).collect();
    for v in ["8", "18", "400", "800"] {
        assert!(texts.contains(&v), "{v} in {texts:?}");
    }
    // Small grid: the values are printed in the cells.
    let printed = texts.iter().filter(|t| t.starts_with("0.")).count();
    assert!(printed >= h.z.len() - cells_without, "{printed}");
    let png = f.to_png().expect("png");
    let (w, hh, _, _) = decode_png(&png);
    assert_eq!((w, hh), (f.width, f.height));
    assert!(png == heatmap(&h).to_png().expect("png"), "deterministic");
    keep("heatmap-small.png", &png);
    let big = heatmap(&made_up_heatmap(40, 30));
    keep("heatmap-big.png", &big.to_png().expect("png"));
    // Mismatched lengths: an error, not a panic.
    let mut bad = made_up_heatmap(3, 3);
    bad.z.pop();
    let e = heatmap(&bad).to_png().expect_err("8 values for 9 cells");
    assert!(e.to_string().contains("8 z values for 3 x 3 cells"), "{e}");
}
