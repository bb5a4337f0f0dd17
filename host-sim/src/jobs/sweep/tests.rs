//! The sweep's grid, ranges, progress bar and table, unit by unit.

use super::*;

fn axis(key: &str, values: &[f64]) -> Axis {
    Axis {
        key: key.into(),
        label: key.into(),
        values: values.iter().map(|v| Value::Float(*v)).collect(),
    }
}

#[test]
fn grid_first_axis_outermost() {
    let axes = [axis("a", &[1.0, 2.0]), axis("b", &[1.0, 2.0, 3.0])];
    let g = grid(&axes, 100).unwrap();
    let want: Vec<Vec<usize>> = vec![
        vec![0, 0],
        vec![0, 1],
        vec![0, 2],
        vec![1, 0],
        vec![1, 1],
        vec![1, 2],
    ];
    assert_eq!(g, want);
    assert_eq!(grid(&[], 100).unwrap(), vec![Vec::<usize>::new()]);
    let err = grid(&axes, 5).unwrap_err();
    assert!(err.contains("more than 5 variants"), "{err}");
    assert!(err.contains("3 × b"), "{err}");
}

#[test]
fn ranges_hit_both_ends() {
    assert_eq!(range(8.0, 16.0, 5).unwrap(), [8.0, 10.0, 12.0, 14.0, 16.0]);
    // 0.1 steps: a running sum would end at 0.30000000000000004.
    let r = range(0.0, 0.3, 4).unwrap();
    assert_eq!(r[3], 0.3);
    assert!((r[1] - 0.1).abs() < 1e-16);
    assert_eq!(range(5.0, 1.0, 3).unwrap(), [5.0, 3.0, 1.0]);
    assert!(range(0.0, 1.0, 1).unwrap_err().contains("steps = 1"));
    assert!(range(0.0, f64::NAN, 3).unwrap_err().contains("finite"));
}

#[test]
fn dotted_keys() {
    let mut t: Table = "[run]\nmotor = 12.0\n[[link]]\nmass = 1.0\n[[link]]\nmass = 2.0\n"
        .parse()
        .unwrap();
    set_dotted(&mut t, "run.motor", Value::Float(10.0)).unwrap();
    set_dotted(&mut t, "converter.mass", Value::Float(40.0)).unwrap();
    set_dotted(&mut t, "link.1.mass", Value::Float(3.0)).unwrap();
    assert_eq!(t["run"]["motor"].as_float(), Some(10.0));
    assert_eq!(t["converter"]["mass"].as_float(), Some(40.0));
    assert_eq!(t["link"][1]["mass"].as_float(), Some(3.0));
    assert_eq!(t["link"][0]["mass"].as_float(), Some(1.0));
    let e = set_dotted(&mut t, "link.2.mass", Value::Float(1.0)).unwrap_err();
    assert!(e.contains("'link.2' is out of the array of 2"), "{e}");
    let e = set_dotted(&mut t, "run.motor.x", Value::Float(1.0)).unwrap_err();
    assert!(e.contains("'run.motor' is a float"), "{e}");
    assert!(set_dotted(&mut t, "run..x", Value::Float(1.0)).is_err());
    assert!(set_dotted(&mut t, "", Value::Float(1.0)).is_err());
}

#[test]
fn progress_bar_text() {
    let s = progress_bar(10, 40, Duration::from_secs(30));
    assert_eq!(
        s,
        "sweep  [######..................] 10/40  25%  0:30 elapsed  ~1:30 left"
    );
    let s = progress_bar(40, 40, Duration::from_secs(3725));
    assert!(s.contains("[########################] 40/40 100%  1:02:05 elapsed"));
    assert!(!s.contains("left"));
    assert!(progress_bar(0, 0, Duration::ZERO).contains("0/1"));
}

/// What a terminal shows of `bytes` on its last line: printable characters
/// overwrite at the cursor, `\r` returns it to the start, `ESC [ K` erases from it
/// to the end, `\n` starts a new line.
fn screen(bytes: &[u8]) -> String {
    let text = std::str::from_utf8(bytes).unwrap();
    let (mut line, mut cursor): (Vec<char>, usize) = (Vec::new(), 0);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\r' => cursor = 0,
            '\n' => {
                line.clear();
                cursor = 0;
            }
            '\x1b' => {
                assert_eq!(chars.next(), Some('['));
                assert_eq!(chars.next(), Some('K'));
                line.truncate(cursor);
            }
            c => {
                if cursor < line.len() {
                    line[cursor] = c;
                } else {
                    line.push(c);
                }
                cursor += 1;
            }
        }
    }
    line.into_iter().collect()
}

// The bar's last redraw is shorter (no estimate left): it must not leave the end of
// the one before on the line.
#[test]
fn progress_bar_redraw_clears_the_line() {
    let long = progress_bar(1, 2, Duration::from_secs(30));
    let short = progress_bar(2, 2, Duration::from_secs(60));
    assert!(short.len() < long.len(), "{long:?} {short:?}");
    let mut w = Vec::new();
    redraw(&mut w, &long, false).unwrap();
    assert_eq!(screen(&w), long);
    let mut before_last = w.clone();
    redraw(&mut w, &short, false).unwrap();
    assert_eq!(screen(&w), short);
    assert_eq!(w, format!("\r\x1b[K{long}\r\x1b[K{short}").into_bytes());
    // The emulator sees stale text where the line is not cleared.
    before_last.extend(format!("\r{short}").bytes());
    assert_ne!(screen(&before_last), short);
    let mut w = Vec::new();
    redraw(&mut w, &short, true).unwrap();
    assert!(w.ends_with(b"\n"));
}

fn base(name: &str) -> Result<(Table, String), String> {
    match name {
        "b" => Ok((
            "[run]\nmotor = 12.0\nload = 800.0\n".parse().unwrap(),
            "built-in b".into(),
        )),
        _ => Err("no such base".into()),
    }
}

const GOOD: &str = r#"
base = "b"
[set]
"run.t_end" = 0.3
[[axis]]
key = "converter.mass"
label = "mass, kg"
values = [20, 40.0]
[[axis]]
key = "run.drive"
values = ["cw", "ccw"]
[[axis]]
key = "run.motor"
from = 8.0
to = 16.0
steps = 3
[[heatmap]]
metric = "load_power"
x = "run.motor"
"#;

#[test]
fn sweep_file() {
    let s = parse_sweep(GOOD, "s.toml", base).unwrap();
    assert_eq!(s.base_origin, "built-in b");
    assert_eq!(s.axes.len(), 3);
    assert_eq!(s.axes[0].numbers(), Some(vec![20.0, 40.0]));
    assert_eq!(s.axes[1].numbers(), None);
    assert_eq!(s.axes[2].numbers(), Some(vec![8.0, 12.0, 16.0]));
    // y defaults to the first other numeric axis: the drive axis is skipped.
    assert_eq!(
        s.heatmaps,
        [HeatSpec {
            metric: Metric::LoadPower,
            x: 2,
            y: Some(0)
        }]
    );
    let v = s.variants().unwrap();
    assert_eq!(v.len(), 12);
    let (idx, tree) = &v[7];
    assert_eq!(idx, &[1, 0, 1]);
    assert_eq!(tree["run"]["t_end"].as_float(), Some(0.3));
    assert_eq!(tree["run"]["load"].as_float(), Some(800.0));
    assert_eq!(tree["run"]["motor"].as_float(), Some(12.0));
    assert_eq!(tree["run"]["drive"].as_str(), Some("cw"));
    assert_eq!(tree["converter"]["mass"].as_float(), Some(40.0));
    assert_eq!(
        s.describe(idx),
        "converter.mass = 40, run.drive = cw, run.motor = 12"
    );
    // The default heat-map: first breakaway over the first two numeric axes.
    let plain = GOOD.split("[[heatmap]]").next().unwrap();
    let s = parse_sweep(plain, "s.toml", base).unwrap();
    assert_eq!(
        s.heatmaps,
        [HeatSpec {
            metric: Metric::FirstBreakaway,
            x: 0,
            y: Some(2)
        }]
    );
}

#[test]
fn bad_sweep_files_say_what_is_wrong() {
    let cases: [(&str, &str); 11] = [
        ("base = \"nope\"", "base = 'nope': no such base"),
        ("base = \"b\"\nbogus = 1", "unknown field `bogus`"),
        ("base = 1", "invalid type"),
        (
            "base = \"b\"\n[set]\n\"run.motor.x\" = 1",
            "[set] key 'run.motor.x': 'run.motor' is a float",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nvalues = []",
            "axis 1 ('a'): values: empty",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nfrom = 1.0\nto = 2.0",
            "give either values",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nfrom = 1.0\nto = 2.0\nsteps = 1",
            "axis 1 ('a'): steps = 1",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nvalues = [1]\n[[axis]]\nkey = \"a\"\nvalues = [2]",
            "axis 2 ('a'): the key is already an axis",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nvalues = [1]\n[[heatmap]]\nmetric = \"speed\"",
            "metric = 'speed': unknown (known: time, first_breakaway",
        ),
        (
            "base = \"b\"\n[[axis]]\nkey = \"a\"\nvalues = [\"x\"]\n[[heatmap]]\nmetric = \"time\"\nx = \"a\"",
            "x = 'a': the axis has values that are not numbers",
        ),
        (
            "base = \"b\"\nthreads = 0",
            "threads = 0: must be 1..=",
        ),
    ];
    for (text, want) in cases {
        let e = parse_sweep(text, "s.toml", base).unwrap_err().to_string();
        assert!(e.starts_with("s.toml:"), "{e}");
        assert!(e.contains(want), "{text:?}: {e:?} lacks {want:?}");
        assert!(!e.contains('\n'), "{e:?}");
    }
    let big = "base = \"b\"\n[[axis]]\nkey = \"a\"\nfrom = 0.0\nto = 1.0\nsteps = 1000\n[[axis]]\nkey = \"b\"\nfrom = 0.0\nto = 1.0\nsteps = 11";
    let e = parse_sweep(big, "s.toml", base).unwrap_err().to_string();
    assert!(e.contains("more than 10000 variants"), "{e}");
}

#[test]
fn heat_grids_per_fixed_value() {
    let s = parse_sweep(GOOD, "s.toml", base).unwrap();
    let v: Vec<Vec<usize>> = s.variants().unwrap().into_iter().map(|v| v.0).collect();
    // Each variant's load power is a code of its axis indices, so every cell shows
    // where it came from.
    let outcomes: Vec<Outcome> = v
        .iter()
        .map(|idx| {
            let mut o = Outcome::default();
            let code = (100 * idx[0] + 10 * idx[1] + idx[2]) as f64;
            o.metrics[7] = if code == 112.0 { None } else { Some(code) };
            o
        })
        .collect();
    let g = heat_grids(&s, &s.heatmaps[0], &v, &outcomes);
    assert_eq!(g.len(), 2);
    assert_eq!(g[0].fixed, "run.drive = cw");
    assert_eq!(g[1].fixed, "run.drive = ccw");
    assert_eq!(g[0].x, [8.0, 12.0, 16.0]);
    assert_eq!(g[0].y, [20.0, 40.0]);
    let z = |c: &[Option<f64>]| c.iter().map(|x| x.map(|v| v as i64)).collect::<Vec<_>>();
    // Row iy = the mass index, column ix = the motor index.
    assert_eq!(
        z(&g[0].z),
        [Some(0), Some(1), Some(2), Some(100), Some(101), Some(102)]
    );
    assert_eq!(
        z(&g[1].z),
        [Some(10), Some(11), Some(12), Some(110), Some(111), None]
    );
}

#[test]
fn metric_names_round_trip() {
    for m in Metric::ALL {
        assert_eq!(Metric::from_name(m.name()), Some(m));
    }
    assert_eq!(Metric::from_name("nope"), None);
    let mut o = Outcome::default();
    o.metrics[1] = Some(0.25);
    assert_eq!(o.get(Metric::FirstBreakaway), Some(0.25));
    assert_eq!(o.get(Metric::Time), None);
}
