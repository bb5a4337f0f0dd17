//! The automatic structomatic analysis (`host_sim::analysis`) against independent
//! oracles: the core's hand-built sequences (`structomat::mechanisms`, the converter's
//! `structomat::ccc::mode_model`), the converter's own assembly (`initial_pose`), loop
//! closure of every joint after assembly, and Grübler's count.

mod common;

use host_sim::analysis::{analyze, build_model, AnalysisError};
use host_sim::runfile::{parse_run_file, Body, JointKind, Mechanism};
use host_sim::ScenarioId;
use structomat::ccc::{initial_pose, mode_model, CccParams, Coordinates, Mode};
use structomat::mechanisms::{five_bar_model, slider_crank_model};
use structomat::Simulation;

fn mechanism(text: &str) -> Mechanism {
    match parse_run_file(text, "test.toml") {
        Ok(f) => match f.body {
            Body::Mechanism(m) => m,
            Body::Converter(_) => panic!("a converter file"),
        },
        Err(e) => panic!("{e}\n{text}"),
    }
}

fn formula(m: &Mechanism) -> String {
    let a = analyze(m).unwrap_or_else(|e| panic!("analysis: {e}"));
    let model = build_model::<f64>(m, &a).unwrap_or_else(|e| panic!("model: {e}"));
    model.formula().to_string()
}

/// Assembles `m` at `q0` (rad) and returns the simulation; panics on failure.
fn assemble(m: &Mechanism, q0: &[f64]) -> Simulation<f64> {
    let a = analyze(m).expect("analysis");
    let model = build_model::<f64>(m, &a).expect("model");
    let qd0 = vec![0.0; q0.len()];
    Simulation::new(model, q0, &qd0, 1e-3).unwrap_or_else(|e| panic!("assembly: {e}"))
}

/// The largest gap between the two points of any revolute joint after assembly, m: an
/// oracle independent of the groups (it uses only the file's points and the bodies'
/// poses).
fn worst_gap(m: &Mechanism, sim: &Simulation<f64>) -> f64 {
    let world = |body: usize, point: usize| -> [f64; 2] {
        if body == 0 {
            return m.ground[point].at;
        }
        let b = &sim.workspace().body[body];
        let p = m.links[body - 1].points[point];
        [
            b.o.x + b.c * p[0] - b.s * p[1],
            b.o.y + b.s * p[0] + b.c * p[1],
        ]
    };
    let mut worst = 0.0f64;
    for j in &m.joints {
        if let JointKind::Revolute { points } = j.kind {
            let p = world(points[0].body, points[0].point);
            let q = world(points[1].body, points[1].point);
            worst = worst.max(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt());
        }
    }
    worst
}

#[test]
fn built_in_mechanisms_give_the_cores_formulas() {
    let sc = ScenarioId::SliderCrank
        .run_file()
        .expect("slider-crank.toml");
    let Body::Mechanism(m) = &sc.body else {
        panic!("mechanism")
    };
    let core = slider_crank_model::<f64>(None).expect("core slider-crank");
    assert_eq!(formula(m), core.formula().to_string());
    assert_eq!(formula(m), "Z(0) + R(1) + RRT(2,3)");

    let fb = ScenarioId::FiveBar.run_file().expect("five-bar.toml");
    let Body::Mechanism(m) = &fb.body else {
        panic!("mechanism")
    };
    let core = five_bar_model::<f64>(2.5, None).expect("core five-bar");
    assert_eq!(formula(m), core.formula().to_string());
    assert_eq!(formula(m), "Z(0) + R(1) + R(2) + RRR(3,4)");
}

/// The converter's linkage as a general mechanism file: `drivers` are `(link, joint,
/// angle)`; lever 6 is left out and rod 5 pinned to the ground point `G6` when
/// `lock6`. Link angles (the guesses) are those of the core's `initial_pose`.
fn converter_file(
    pose: &[f64; 9],
    p: &CccParams<f64>,
    lock6: bool,
    drivers: &[(&str, &str, f64)],
) -> String {
    let deg = |k: usize| pose[k].to_degrees();
    let g6 = [
        p.h.x + pose[6].cos() * p.links[5].length,
        p.h.y + pose[6].sin() * p.links[5].length,
    ];
    let mut t = String::from("name = \"ccc-linkage\"\n");
    for (name, at) in [
        ("A", [p.a.x, p.a.y]),
        ("F", [p.f.x, p.f.y]),
        ("H", [p.h.x, p.h.y]),
        ("G6", g6),
    ] {
        t += &format!(
            "[[ground]]\nname = \"{name}\"\nat = [{:?}, {:?}]\n",
            at[0], at[1]
        );
    }
    let names = [
        "crank", "coupler", "rocker", "swing", "rod5", "lever6", "rod7", "lever8",
    ];
    for (k, name) in names.iter().enumerate() {
        if lock6 && k == 5 {
            continue;
        }
        let b = p.links[k];
        t += &format!(
            "[[link]]\nname = \"{name}\"\nlength = {:?}\nmass = {:?}\ninertia = {:?}\nangle_deg = {:?}\n",
            b.length,
            b.mass,
            b.inertia,
            deg(k + 1)
        );
        if k == 2 {
            t += &format!("points = {{ D = [{:?}, 0.0] }}\n", p.rocker_d);
        }
    }
    let mut joints = vec![
        ("A", "A", "crank.start"),
        ("B", "crank.end", "coupler.start"),
        ("C", "coupler.end", "rocker.end"),
        ("E", "swing.end", "rocker.start"),
        ("F", "F", "swing.start"),
        ("D5", "rocker.D", "rod5.start"),
        ("D7", "rocker.D", "rod7.start"),
        ("I", "rod7.end", "lever8.end"),
        ("H8", "H", "lever8.start"),
    ];
    if lock6 {
        joints.push(("G", "rod5.end", "G6"));
    } else {
        joints.push(("G", "rod5.end", "lever6.end"));
        joints.push(("H6", "H", "lever6.start"));
    }
    for (name, a, b) in joints {
        t += &format!(
            "[[joint]]\nname = \"{name}\"\ntype = \"revolute\"\npoints = [\"{a}\", \"{b}\"]\n"
        );
    }
    for (link, joint, q) in drivers {
        t += &format!("[[driver]]\nlink = \"{link}\"\njoint = \"{joint}\"\nq0_deg = {q:?}\n");
    }
    t + "[run]\nh = 1e-4\nt_end = 0.1\n"
}

#[test]
fn converter_linkage_matches_the_cores_mode_models() {
    let p = CccParams::<f64>::reference();
    let (q1, q2) = (105f64.to_radians(), 90f64.to_radians());
    let pose = initial_pose(&p, q1, q2).expect("reference pose");
    // I0 with the crank and the swing link driven (the diode's levers free).
    let text = converter_file(
        &pose,
        &p,
        false,
        &[("crank", "A", 105.0), ("swing", "F", 90.0)],
    );
    let m = mechanism(&text);
    let (core, _) = mode_model(&p, Mode::I0, Coordinates::CrankSwing, &pose).expect("I0");
    assert_eq!(formula(&m), core.formula().to_string());
    assert_eq!(
        formula(&m),
        "Z(0) + R(1) + R(4) + RRR(2,3) + RRR(5,6) + RRR(7,8)"
    );
    // Assembled from the file, every link sits where the core's converter puts it.
    let sim = assemble(&m, &[q1, q2]);
    for (k, want) in pose.iter().enumerate().skip(1) {
        let got = sim.workspace().body[k].theta;
        let d = (got - want + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        assert!(d.abs() < 1e-9, "link {k}: {got} vs {want}");
    }
    assert!(worst_gap(&m, &sim) < 1e-12, "{}", worst_gap(&m, &sim));

    // I6: lever 6 locked (its pin G a ground point), the crank alone drives: a triad.
    let text = converter_file(&pose, &p, true, &[("crank", "A", 105.0)]);
    let m = mechanism(&text);
    let (core, _) = mode_model(&p, Mode::I6, Coordinates::Crank, &pose).expect("I6");
    assert_eq!(formula(&m), core.formula().to_string());
    assert_eq!(formula(&m), "Z(0) + R(1) + RR-RR-RR(2,3,4,5) + RRR(6,7)");
    let sim = assemble(&m, &[q1]);
    assert!(worst_gap(&m, &sim) < 1e-9, "{}", worst_gap(&m, &sim));

    // Other drivers, other sequences: the crank and the coupler (about B).
    let text = converter_file(
        &pose,
        &p,
        false,
        &[
            ("crank", "A", 105.0),
            ("coupler", "B", pose[2].to_degrees()),
        ],
    );
    let (core, _) = mode_model(&p, Mode::I0, Coordinates::CrankCoupler, &pose).expect("I0");
    assert_eq!(formula(&mechanism(&text)), core.formula().to_string());
}

const HEAD: &str = "[run]\nh = 0.001\nt_end = 0.01\n";

fn ground(points: &[(&str, f64, f64)]) -> String {
    points
        .iter()
        .map(|(n, x, y)| format!("[[ground]]\nname = \"{n}\"\nat = [{x:?}, {y:?}]\n"))
        .collect()
}

fn bars(links: &[(&str, f64, f64)]) -> String {
    links
        .iter()
        .map(|(n, l, a)| {
            format!("[[link]]\nname = \"{n}\"\nlength = {l:?}\nmass = 1.0\ninertia = 0.01\nangle_deg = {a:?}\n")
        })
        .collect()
}

fn pins(joints: &[(&str, &str, &str)]) -> String {
    joints
        .iter()
        .map(|(n, a, b)| {
            format!("[[joint]]\nname = \"{n}\"\ntype = \"revolute\"\npoints = [\"{a}\", \"{b}\"]\n")
        })
        .collect()
}

/// Watt's six-bar (the four-bar A-B-C-D, then a dyad from the coupler's extra point and
/// a ground pivot): two dyads in sequence.
#[test]
fn watt_six_bar() {
    let mut t = String::from(HEAD);
    t += &ground(&[("A", 0.0, 0.0), ("D", 1.0, 0.0), ("G", 2.0, 0.0)]);
    t += &bars(&[
        ("crank", 0.3, 80.0),
        ("coupler", 1.0, 10.0),
        ("rocker", 0.8, 90.0),
        ("link4", 0.9, -20.0),
        ("link5", 0.9, 100.0),
    ]);
    t += &pins(&[
        ("A", "A", "crank.start"),
        ("B", "crank.end", "coupler.start"),
        ("C", "coupler.end", "rocker.end"),
        ("D", "D", "rocker.start"),
        ("E", "coupler.end", "link4.start"),
        ("F", "link4.end", "link5.end"),
        ("G", "G", "link5.start"),
    ]);
    t += "[[driver]]\nlink = \"crank\"\njoint = \"A\"\nq0_deg = 80.0\n";
    let m = mechanism(&t);
    assert_eq!(formula(&m), "Z(0) + R(1) + RRR(2,3) + RRR(4,5)");
    let sim = assemble(&m, &[80f64.to_radians()]);
    assert!(worst_gap(&m, &sim) < 1e-12, "{}", worst_gap(&m, &sim));
}

/// A Stephenson six-bar driven so that no dyad fits after the crank: the ternary link
/// `plate` hangs on three binary links (one from the crank, two from the ground), the
/// class-III group the thesis calls the triad.
#[test]
fn stephenson_six_bar_needs_the_triad() {
    let mut t = String::from(HEAD);
    t += &ground(&[("A", 0.0, 0.0), ("K2", 1.2, 0.0), ("K3", 1.0, 0.3)]);
    // Angles near an assembly (plate level, T1 about 0.8 m from B at 30°).
    t += &bars(&[
        ("crank", 0.25, 60.0),
        ("b1", 0.8, 30.0),
        ("b2", 0.65, 70.0),
        ("b3", 0.75, 80.0),
    ]);
    t += "[[link]]\nname = \"plate\"\nmass = 2.0\ninertia = 0.05\ncog = [0.3, 0.1]\nangle_deg = 0.0\n\
          points = { T1 = [0.0, 0.0], T2 = [0.6, 0.0], T3 = [0.3, 0.4] }\n";
    t += &pins(&[
        ("A", "A", "crank.start"),
        ("J1", "crank.end", "b1.start"),
        ("J2", "K2", "b2.start"),
        ("J3", "K3", "b3.start"),
        ("T1", "b1.end", "plate.T1"),
        ("T2", "b2.end", "plate.T2"),
        ("T3", "b3.end", "plate.T3"),
    ]);
    t += "[[driver]]\nlink = \"crank\"\njoint = \"A\"\nq0_deg = 60.0\n";
    let m = mechanism(&t);
    // 3·5 − 2·7 = 1 degree of freedom.
    let a = analyze(&m).expect("analysis");
    assert_eq!(a.dof, 1);
    assert_eq!(formula(&m), "Z(0) + R(1) + RR-RR-RR(2,3,4,5)");
    let out = host_sim::analysis::report(&m, &a, &build_model::<f64>(&m, &a).expect("model"));
    assert!(out.contains("RR-RR-RR(2,3,4,5)  links 2 \"b1\""), "{out}");
    // Newton assembles the triad from the guesses: every pin closes.
    let sim = assemble(&m, &[60f64.to_radians()]);
    assert!(worst_gap(&m, &sim) < 1e-9, "{}", worst_gap(&m, &sim));
}

#[test]
fn leftover_links_and_wrong_driver_counts_are_named() {
    // Two sliders joined by three prismatic joints (TTT): 3·2 − 2·3 = 0 DOF, no driver,
    // but no group of the library places them.
    let t = format!(
        "{HEAD}{}[[link]]\nname = \"s1\"\nmass = 1.0\ninertia = 0.0\n[[link]]\nname = \"s2\"\nmass = 1.0\ninertia = 0.0\n\
         [[joint]]\nname = \"P1\"\ntype = \"prismatic\"\nslider = \"s1.origin\"\nguide = \"A\"\n\
         [[joint]]\nname = \"P2\"\ntype = \"prismatic\"\nslider = \"s2.origin\"\nguide = \"A\"\nguide_angle_deg = 90.0\n\
         [[joint]]\nname = \"P12\"\ntype = \"prismatic\"\nslider = \"s2.origin\"\nguide = \"s1.origin\"\nguide_angle_deg = 45.0\n",
        ground(&[("A", 0.0, 0.0)])
    );
    let e = analyze(&mechanism(&t)).unwrap_err();
    assert!(matches!(e, AnalysisError::Leftover { .. }), "{e:?}");
    let msg = e.to_string();
    for needle in ["\"s1\"", "\"s2\"", "\"P1\"", "\"P2\"", "\"P12\"", "Z(0)"] {
        assert!(msg.contains(needle), "{needle} in {msg}");
    }

    // The five-bar with one driver only: too few; with a third: too many.
    let five = ScenarioId::FiveBar.file_text();
    let one = five.replace(
        "# q2: no motor on link 2.\n[[driver]]\nlink = \"crank2\"\njoint = \"E\"\nq0_deg = 70.0\nqd0 = 0.0\n",
        "",
    );
    assert_ne!(one, five, "the test's edit applies");
    let e = analyze(&mechanism(&one)).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("too few drivers")
            && msg.contains("2 degrees of freedom")
            && msg.contains("1 driver"),
        "{msg}"
    );
    let three = format!("{five}\n[[driver]]\nlink = \"coupler\"\njoint = \"B\"\nq0_deg = 30.0\n");
    let msg = analyze(&mechanism(&three)).unwrap_err().to_string();
    assert!(
        msg.contains("too many drivers") && msg.contains("3 driver"),
        "{msg}"
    );

    // A driver on a joint that does not join its link is a file error, named.
    let mut t = String::from(HEAD);
    t += &ground(&[("A", 0.0, 0.0), ("D", 1.0, 0.0)]);
    t += &bars(&[
        ("crank", 0.3, 80.0),
        ("coupler", 1.0, 10.0),
        ("rocker", 0.8, 90.0),
    ]);
    t += &pins(&[
        ("A", "A", "crank.start"),
        ("B", "crank.end", "coupler.start"),
        ("D", "D", "rocker.start"),
    ]);
    t += "[[driver]]\nlink = \"crank\"\njoint = \"A\"\nq0_deg = 80.0\n\
          [[driver]]\nlink = \"rocker\"\njoint = \"D\"\nq0_deg = 90.0\n\
          [[driver]]\nlink = \"coupler\"\njoint = \"D\"\nq0_deg = 10.0\n";
    let e = parse_run_file(&t, "x.toml").unwrap_err();
    assert_eq!(e.field, "driver[2].joint", "{e}");
    assert!(
        e.to_string().contains("does not join link \"coupler\""),
        "{e}"
    );
}

#[test]
fn analyze_command_prints_the_formula_and_reports_failures() {
    let (code, out, err) = common::run(&["analyze", "five-bar"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("formula   Z(0) + R(1) + R(2) + RRR(3,4)"),
        "{out}"
    );
    assert!(out.contains("DOF       2"), "{out}");
    assert!(
        out.contains("RRR(3,4)  links 3 \"coupler\", 4 \"rocker\""),
        "{out}"
    );
    let (code, out, _) = common::run(&["analyze", "ccc-s2"]);
    assert_eq!(code, 0);
    assert!(out.contains("R(1) + R(4) + RRR(2,3)"), "{out}");

    let dir = common::TempDir::new("analyze");
    let path = dir.join("bad.toml");
    // Remove the pin C: 4 links, 4 joints, 4 DOF against 2 drivers.
    let text = ScenarioId::FiveBar.file_text();
    let cut = text.replace("[[joint]]\nname = \"C\"\ntype = \"revolute\"\npoints = [\"coupler.end\", \"rocker.end\"]\n", "");
    assert_ne!(cut, text);
    std::fs::write(&path, cut).expect("write");
    let (code, _, err) = common::run(&["analyze", &path]);
    assert_eq!(code, 1);
    assert!(
        err.contains("too few drivers") && err.contains("4 degrees of freedom"),
        "{err}"
    );
}
