//! `host-sim design`: the diode's margin the search measures is the one an independent
//! computation from the run's state CSV gives, a design that violates it at a single
//! step is infeasible, the search gives the same designs bit for bit on 1 and 2
//! threads, the winner keeps its verdict and objective at h/2, a bad design file is
//! refused with the field named. Short horizons and small populations for the debug
//! build (the optimizer's convergence on Rosenbrock and a constrained quadratic is
//! tested in `src/jobs/design/evolution.rs`).

mod common;

use common::{files, run, TempDir};
use host_sim::jobs::design::at_half_step;
use host_sim::jobs::design::evaluate::{evaluate, Ended};
use host_sim::jobs::design::file::{parse_design, Design};
use host_sim::jobs::design::search::{search, Outcome};
use host_sim::jobs::sweep::load_base;
use std::path::Path;

/// S2 against 150 N·m (it runs on) for 0.05 s, with two free parameters around the
/// reference; 2 generations of 4.
const DESIGN: &str = r#"
base = "ccc-s2"
[[free]]
key = "converter.mass"
min = 4.0
max = 8.0
[[free]]
key = "converter.rocker_d"
min = 0.3
max = 0.4
[[point]]
load = 150.0
motor = 12.0
horizon = 0.05
[constraints]
margin = 0.005
[search]
population = 4
generations = 1
seed = 3
"#;

fn design(text: &str) -> Design {
    parse_design(text, "test.toml", |b| load_base(b, Path::new("."))).expect("a good design file")
}

/// The diode's margin at every row of a converter state CSV, from the link angles
/// alone: D = F + |FE|·u(θ4) + rocker_d·u(θ3) (E on the swing link, D on the rocker,
/// SPEC 3), margin = min(rod + lever) − |DH|, with the reference converter's values.
fn margins_from_csv(text: &str) -> Vec<f64> {
    let mut lines = text.lines();
    let names: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |n: &str| names.iter().position(|c| *c == n).expect(n);
    let (t3, t4) = (col("theta3"), col("theta4"));
    // The angle columns are numbers (the mode's columns are names).
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            let mut r = vec![f64::NAN; names.len()];
            for k in [t3, t4] {
                r[k] = cells[k].parse().expect("an angle");
            }
            r
        })
        .collect();
    let (f, h) = ((0.20, 0.50), (1.10, 0.0));
    let (swing, rocker_d, full) = (0.100, 0.350, 0.650 + 0.300);
    rows.iter()
        .map(|r| {
            let dx = f.0 + swing * r[t4].cos() + rocker_d * r[t3].cos();
            let dy = f.1 + swing * r[t4].sin() + rocker_d * r[t3].sin();
            full - ((dx - h.0).powi(2) + (dy - h.1).powi(2)).sqrt()
        })
        .collect()
}

// The margin the design search measures at every step is the one the run's CSV gives
// (an independent computation from the link angles); with δ between the smallest and
// the second smallest margin, exactly one state violates |DH| ≤ rod + lever − δ, and
// that single step makes the design infeasible; with δ just under the smallest, it is
// feasible.
#[test]
fn a_single_step_under_the_margin_is_infeasible() {
    let dir = TempDir::new("design-margin");
    let csv = dir.join("s2.csv");
    let (code, _, err) = run(&[
        "run", "ccc-s2", "--load", "150", "--t-end", "0.05", "--out", &csv, "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let margins = margins_from_csv(&String::from_utf8(std::fs::read(&csv).unwrap()).unwrap());
    assert_eq!(margins.len(), 501);
    let mut sorted = margins.clone();
    sorted.sort_by(f64::total_cmp);
    let (m1, m2) = (sorted[0], sorted[1]);
    assert!(m1 < m2 && m1 > 0.0, "{m1} {m2}");

    let base = design(DESIGN);
    let point = base.points[0];
    let e = evaluate(&base, &[], &point);
    assert_eq!(e.ended, Ended::Completed, "{:?}", e.message);
    assert!(
        (e.min_margin - m1).abs() < 1e-12,
        "{} vs {m1}",
        e.min_margin
    );

    let with_margin = |delta: f64| {
        let mut d = base.clone();
        d.constraints.margin = delta;
        let e = evaluate(&d, &[], &point);
        let v = e.violations(&d.constraints);
        (v, host_sim::jobs::design::search::score(&d, &[e]))
    };
    let delta = 0.5 * (m1 + m2);
    let (v, s) = with_margin(delta);
    // The margin's violation is the share of δ missing at the smallest margin, that
    // of the run's own CSV.
    assert!((v[1] - (delta - m1) / delta).abs() < 1e-12, "{v:?}");
    assert_eq!([v[0], v[2], v[3]], [0.0; 3]);
    assert!(!s.is_feasible(), "{s:?}");
    let (v, s) = with_margin(m1 - 1e-9);
    assert_eq!(v, [0.0; 4]);
    assert!(s.is_feasible(), "{s:?}");
}

fn bits(o: &Outcome) -> Vec<u64> {
    o.rows
        .iter()
        .flat_map(|r| {
            r.x.iter()
                .chain([&r.score.violation, &r.score.objective])
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        })
        .collect()
}

// The same search on 1 and 2 threads: the same designs, scores and best, bit for bit;
// and the command's files byte for byte.
#[test]
fn one_and_two_threads_give_the_same_designs() {
    let d = design(DESIGN);
    let one = search(&d, 1, &mut |_, _| {}, &mut |_, _| {});
    let two = search(&d, 2, &mut |_, _| {}, &mut |_, _| {});
    assert_eq!(one.rows.len(), 8);
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(one.best, two.best);
    // The best is the first of the best scores, by Deb's order.
    let best = one.best_row().expect("a best design");
    assert!(one
        .rows
        .iter()
        .all(|r| best.score.compare(&r.score) != std::cmp::Ordering::Greater));

    let dir = TempDir::new("design-threads");
    let file = dir.join("d.toml");
    std::fs::write(&file, DESIGN).unwrap();
    let mut outs = Vec::new();
    for t in ["1", "2"] {
        let out = dir.join(&format!("out{t}"));
        let (code, stdout, err) = run(&[
            "design",
            &file,
            "--out-dir",
            &out,
            "--threads",
            t,
            "--no-winner",
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(stdout.contains("design    8 designs of ccc-s2"), "{stdout}");
        outs.push(files(Path::new(&out)));
    }
    assert_eq!(outs[0], outs[1]);
    for f in [
        "designs.csv",
        "best.toml",
        "convergence.svg",
        "convergence.png",
    ] {
        assert!(outs[0].contains_key(f), "{f}");
    }
    // best.toml is a run file that `host-sim run` takes.
    let (code, _, err) = run(&[
        "run",
        &dir.join("out1/best.toml"),
        "--t-end",
        "0.01",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
}

// The winner re-run at half the step keeps its verdict and its objective within 1 %:
// the oracle is the convergence of the fixed-step integration, not a stored value.
#[test]
fn the_winner_keeps_its_verdict_at_half_the_step() {
    let d = design(&DESIGN.replace("horizon = 0.05", "horizon = 0.2"));
    let o = search(&d, 2, &mut |_, _| {}, &mut |_, _| {});
    let best = o.best_row().expect("a best design");
    assert!(best.score.is_feasible(), "{:?}", best.evals);
    let half = at_half_step(&d, &best.x).expect("h/2");
    let s = host_sim::jobs::design::search::score(&d, &half);
    assert!(s.is_feasible(), "{half:?}");
    let rel = (s.objective - best.score.objective).abs() / best.score.objective.abs();
    assert!(
        rel < 0.01,
        "{} vs {}: {rel}",
        s.objective,
        best.score.objective
    );
    assert!(
        best.score.objective < 0.0,
        "mean power > 0: {:?}",
        best.score
    );
}

// A bad design file is refused before anything runs, the field named.
#[test]
fn bad_design_files_name_the_field() {
    let cases: [(&str, &str, &str); 8] = [
        (
            "min = 4.0",
            "min = 9.0",
            "free 1 ('converter.mass'): min = 9, max = 8",
        ),
        ("converter.rocker_d", "converter.rocker_dd", "rocker_dd"),
        ("horizon = 0.05", "horizon = -1.0", "point 1: horizon = -1"),
        ("load = 150.0", "load = nan", "point 1: load = NaN"),
        (
            "margin = 0.005",
            "margin = -0.1",
            "constraints margin = -0.1",
        ),
        ("population = 4", "population = 3", "search population = 3"),
        (
            "[search]",
            "[objective]\nmetric = \"speed\"\n[search]",
            "objective metric = 'speed'",
        ),
        ("seed = 3", "seed = 3\ncolour = 1", "colour"),
    ];
    let dir = TempDir::new("design-bad");
    for (from, to, want) in cases {
        let text = DESIGN.replace(from, to);
        assert_ne!(text, DESIGN, "{from}");
        let e = parse_design(&text, "t.toml", |b| load_base(b, Path::new("."))).expect_err(to);
        assert!(e.to_string().contains(want), "{to}: {e}");
        let path = dir.join("bad.toml");
        std::fs::write(&path, &text).unwrap();
        let out = dir.join("out");
        let (code, _, err) = run(&["design", &path, "--out-dir", &out]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("nothing was run"), "{err}");
        assert!(!Path::new(&out).exists(), "{to}: files written");
    }
    // A point's motor with the motor free: refused.
    let text = DESIGN
        .replace("key = \"converter.rocker_d\"", "key = \"run.motor\"")
        .replace("min = 0.3\nmax = 0.4", "min = 8.0\nmax = 16.0");
    let e = parse_design(&text, "t.toml", |b| load_base(b, Path::new("."))).expect_err("motor");
    assert!(e.to_string().contains("point 1: motor"), "{e}");
}
