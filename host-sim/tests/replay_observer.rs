//! `host-sim replay --observer`: the prototype's bench log replayed with the core's
//! observer correcting the twin from the log's encoders.
//!
//! Oracles: the machine's own records (its encoder counts, its clutch log
//! `tests/data/bench1_clutch_log.csv`), issue 19's targets (every figure named "issue"
//! is the issue's, not computed here), a fault injected into the log at a known
//! instant, and a log the twin wrote itself (no model error).

use host_sim::plot::Table;
use host_sim::run::replay::ReplaySummary;
use std::f64::consts::TAU;

mod common;
use common::{data, replay_of, run, TempDir};

/// ccc-s2's run file (SPEC's nominal machine) with the initial crank angle `deg`.
fn spec_from(dir: &TempDir, deg: f64) -> String {
    let text = host_sim::ScenarioId::CccS2
        .file_text()
        .replace("crank_deg = 105.0", &format!("crank_deg = {deg:.1}"));
    assert!(text.contains(&format!("crank_deg = {deg:.1}")));
    let path = dir.join("spec.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `log` replayed on the run file `params` with the observer (tuned for nominal
/// parameters), matched against its clutch log `clutch`, the run written to `out`.
fn observed(log: &str, clutch: &str, params: &str, out: &str) -> ReplaySummary {
    observed_tuned(log, clutch, params, "nominal", out)
}

/// [`observed`] with the observer's `tuning` (`nominal` or `identified`).
fn observed_tuned(log: &str, clutch: &str, params: &str, tuning: &str, out: &str) -> ReplaySummary {
    replay_of(&[
        log,
        "--params",
        params,
        "--observer",
        tuning,
        "--clutch-log",
        clutch,
        "--out",
        out,
    ])
}

/// The events of the matching within 1 ms of the machine's.
fn within_1_ms(m: &host_sim::run::replay::Matching) -> usize {
    m.pairs
        .iter()
        .filter(|p| p.dt().is_some_and(|d| d.abs() <= 1e-3))
        .count()
}

/// The observed replay `s` of the log `name` followed the machine: its `events` in the
/// clutch log's sequence, at least `within` of them within 1 ms, the crank's residual
/// RMS after 20 ms at most `rms` counts, no diagnostic.
fn follows(name: &str, s: &ReplaySummary, events: usize, within: usize, rms: f64) {
    let o = s.observed.as_ref().expect("the observer's summary");
    let m = s.matching.as_ref().expect("a clutch log");
    assert_eq!(m.counts(), (events, events), "{name}: {m}");
    assert_eq!(m.first_mismatch(), None, "{name}: {m}");
    assert!(o.residual_settled.rms() <= rms, "{name}: {o}");
    let n = within_1_ms(m);
    assert!(n >= within, "{name}: {n} of {events} within 1 ms: {m}");
    assert!(o.onsets.is_empty(), "{name}: {o}");
}

/// bench1 with `edit(t, row)` applied to each data row's cells.
fn edited(dir: &TempDir, name: &str, edit: impl Fn(f64, &mut Vec<String>)) -> String {
    let text = std::fs::read_to_string(data("bench1.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for l in lines {
        let mut c: Vec<String> = l.split(',').map(str::to_string).collect();
        let t: f64 = c[0].parse().unwrap();
        edit(t, &mut c);
        out.push_str(&format!("{}\n", c.join(",")));
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

/// Issue 19: "the observer with SPEC's nominal parameters (not identified), from a
/// crank angle 5° off: crank residual RMS ≤ 1 count after the first 20 ms, every
/// clutch event within 1 ms". The filter starts from the first count (as a Kalman
/// filter's state does from its first measurement). The oracles: the log's counts and
/// its clutch log. Measured: crank residual RMS 0.363 counts after 20 ms (largest 3),
/// the machine's 21 events in its sequence (open loop the sequences part at the 14th
/// pair), every one within 1 ms (the worst the jam's catch, 0.70 ms late), no
/// diagnostic; the friction estimate 0.046 N·m·s/rad and the oscillating mass 6.29 kg
/// (SPEC's 6) at the end.
/// Then the columns in the CSV, the summary's lines.
#[test]
fn bench1_observed_from_5_degrees_off_follows_the_machine_s_sequence() {
    let dir = TempDir::new("observe-bench1");
    let params = spec_from(&dir, 110.0);
    let out = dir.join("b1.csv");
    let (log, clutch) = (data("bench1.csv"), data("bench1_clutch_log.csv"));
    let s = observed(&log, &clutch, &params, &out);
    follows("bench1", &s, 21, 21, 1.0);
    let o = s.observed.as_ref().expect("the observer's summary");
    assert!(o.residual_settled.largest.0.abs() <= 4, "{o}");
    // The friction's estimate is a friction (non-negative) and of a bearing's size
    // (`identify` finds 0.050 N·m·s/rad at A): measured 0.046 at the end.
    assert!((0.005..=0.1).contains(&o.estimates.1), "{o}");
    // The mass's estimate moved from SPEC's 6 kg towards the machine's (`identify`
    // finds 6.45) and stays within the tuning's 25 %: measured 6.29 at the end.
    assert!((6.05..=7.5).contains(&o.estimates.2), "{o}");
    // Open loop from the same start the sequences part (issue: at 0.33 s from 105°).
    let open = replay_of(&[
        &log,
        "--params",
        &params,
        "--clutch-log",
        &clutch,
        "--out",
        &dir.join("open.csv"),
    ]);
    assert!(open.matching.unwrap().first_mismatch().is_some());

    let table = Table::from_csv(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(table.len(), 1001);
    let nu = table.column("crank_innovation").unwrap();
    let late: Vec<f64> = nu.iter().skip(21).copied().collect();
    let rms = (late.iter().map(|x| x * x).sum::<f64>() / late.len() as f64).sqrt();
    assert!((rms - o.innovation_settled.rms()).abs() < 1e-9);
    for c in [
        "crank_sigma",
        "shaft_innovation",
        "crank_torque_estimate",
        "crank_friction_estimate",
        "oscillating_mass",
        "clutch_slip",
        "load_bias",
    ] {
        assert!(table.column(c).is_some(), "{c}");
    }

    let (code, text, err) = run(&[
        "replay",
        &log,
        "--params",
        &params,
        "--observer",
        "--clutch-log",
        &clutch,
        "--out",
        &dir.join("cli.csv"),
    ]);
    assert_eq!(code, 0, "{err}");
    for want in [
        "with the observer (corrected from the encoders)",
        "observer  crank innovation (measured - predicted) RMS",
        "after 0.02 s: innovation RMS",
        "(after the update)",
        "estimated at the end: the crank's unknown torque",
        "paired in order: all the same",
        "diagnostics:",
    ] {
        assert!(text.contains(want), "{want}: {text}");
    }
}

/// The observer at other operating points: three logs the twin wrote of a known
/// machine off SPEC's (`tests/data/README.md`: T_r = 1000 N·m with a 14 N·m motor, 800
/// with 10, 600 with 12), replayed with SPEC's nominal parameters as bench1 is above;
/// they stand in for the kept-back logs. Oracles: each log's own counts and
/// clutch log. All keep the machine's sequence, event for event, and raise no
/// diagnostic (their loads are their set points, their encoders read smoothly). The
/// 600/12 log meets issue 19's marks (RMS ≤ 1 count after 20 ms, measured 0.94; every
/// event within 1 ms): its crank reverses in I6 at 0.51 s, where the crank's angle is
/// set by the locked lever's pin, and the lever the twin locked 2.1 mrad off the
/// machine's is moved by the crank's innovation there (`held_gain`; without it 3.60
/// counts, the twin's crank 48 counts past the machine's). The rest are regression
/// values (measured): RMS 0.37 and 0.56 counts; 20 of 20 events within 1 ms, 18 of
/// 21 (the first release 7.5 ms early, at 9.1 ms, while the filter settles from the
/// first count; a catch6 1.9 ms early; the jam's catch 2.2 ms late after a creep in
/// I6 at 0.4 rad/s). (The 400/12 log of the same machine leaves the machine's
/// sequence at its 32nd event, 0.92 s: docs/observer.md, "The known machine's logs".)
#[test]
fn the_observer_keeps_a_known_machine_s_sequence_at_other_operating_points() {
    let dir = TempDir::new("observe-known");
    let params = spec_from(&dir, 110.0);
    for (name, rms, within, events) in [
        ("known-1000Nm-14Nm", 0.45, 20, 20),
        ("known-800Nm-10Nm", 0.65, 18, 21),
        ("known-600Nm-12Nm", 1.0, 21, 21),
    ] {
        let (log, clutch) = (
            data(&format!("{name}.csv")),
            data(&format!("{name}_clutch_log.csv")),
        );
        let s = observed(
            &log,
            &clutch,
            &params,
            &dir.join(&format!("{name}-run.csv")),
        );
        follows(name, &s, events, within, rms);
    }
}

/// The observer tuned for an identified twin (`--observer identified`) on
/// `known-machine.toml`, bench1's identified machine. On bench1 itself (the real
/// machine's log; the twin's parameters fitted to it, not the machine's own) it meets
/// issue 19's marks for an observed twin: crank residual RMS ≤ 1 count after 20 ms
/// (measured 0.78), every one of the clutch log's 21 events within 1 ms (the worst
/// 0.88 ms), no diagnostic. On that machine's own logs at four operating points
/// (`tests/data`, `make_known_logs.py`: 1000/14, 800/10, 600/12 and 400/12 N·m) it keeps every sequence with no
/// diagnostic; the RMS bound is the 1 count (measured 0.44 to 0.60), the
/// events within 1 ms are regression values (measured: all but one of 36 at 400/12,
/// 1.9 ms off).
#[test]
fn the_identified_tuning_follows_an_identified_twin_s_machine() {
    let dir = TempDir::new("observe-identified");
    let params = data("known-machine.toml");
    for (name, events, within) in [
        ("bench1", 21, 21),
        ("known-1000Nm-14Nm", 20, 20),
        ("known-800Nm-10Nm", 21, 21),
        ("known-600Nm-12Nm", 21, 21),
        ("known-400Nm-12Nm", 36, 35),
    ] {
        let clutch = if name == "bench1" {
            data("bench1_clutch_log.csv")
        } else {
            data(&format!("{name}_clutch_log.csv"))
        };
        let s = observed_tuned(
            &data(&format!("{name}.csv")),
            &clutch,
            &params,
            "identified",
            &dir.join(&format!("{name}-run.csv")),
        );
        follows(name, &s, events, within, 1.0);
    }
}

/// The identified tuning on a twin identified a little off its machine: the known
/// machine's logs (`known-machine.toml`, an identification of bench1 without the
/// friction at F) observed on `bench1-identified.toml` (bench1 identified with it: the
/// masses 1 to 2 % apart, F's friction 0.011 N·m·s/rad more), as a machine identified
/// once and observed later. The oracle is the machine's log and clutch log; the marks
/// are issue 19's (every event within 1 ms, crank RMS ≤ 1 count after 20 ms, no
/// diagnostic). Measured: 0.51, 0.60 and 0.83 counts, every event within 0.50, 0.41
/// and 0.63 ms. Without the locked lever's update (`held_gain` 0, the tuning before)
/// the 600/12 sequence parted at 0.55 s (a torque estimate learnt in A68 held through
/// the crank's reversal in the next I6 phase, where nothing else corrects it). At
/// 400/12 the observed twin still parts at 0.92 s, where open loop keeps the sequence
/// with no event more than 0.84 ms off (docs/observer.md, "A twin a little off").
#[test]
fn an_identified_twin_a_little_off_follows_its_machine() {
    let dir = TempDir::new("observe-identified-off");
    let params = data("bench1-identified.toml");
    for (name, events) in [
        ("known-1000Nm-14Nm", 20),
        ("known-800Nm-10Nm", 21),
        ("known-600Nm-12Nm", 21),
    ] {
        let s = observed_tuned(
            &data(&format!("{name}.csv")),
            &data(&format!("{name}_clutch_log.csv")),
            &params,
            "identified",
            &dir.join(&format!("{name}-run.csv")),
        );
        follows(name, &s, events, events, 1.0);
    }
}

/// Issue 19's third diagnostic, "a load that differs from the set point", on an
/// identified twin (`--observer identified`, `known-machine.toml`): bench1 with its
/// load column set to 600 or 1000 N·m (the machine ran at 800) is named `load-bias`,
/// and only that (measured onsets 0.341 s and 0.354 s: the torque estimate's average
/// while the shaft turns departs from its average while it is held by over 0.6 N·m);
/// at 800 (the log as recorded) nothing is named
/// (`the_identified_tuning_follows_an_identified_twin_s_machine`).
#[test]
fn a_load_off_its_set_point_is_named_on_an_identified_twin() {
    let dir = TempDir::new("observe-load");
    let params = data("known-machine.toml");
    for load in ["600.0", "1000.0"] {
        let log = edited(&dir, &format!("load-{load}.csv"), |_, c| {
            c[2] = load.to_string();
        });
        let s = replay_of(&[
            &log,
            "--params",
            &params,
            "--observer",
            "identified",
            "--out",
            &dir.join(&format!("load-{load}-run.csv")),
        ]);
        let o = s.observed.unwrap();
        let t = o
            .first("load-bias")
            .unwrap_or_else(|| panic!("{load} N·m named: {o}"));
        assert!((0.2..=0.5).contains(&t), "{load} N·m: {t}: {o}");
        assert!(
            o.onsets.iter().all(|(_, name)| *name == "load-bias"),
            "{load} N·m: {o}"
        );
    }
}

/// A slipping clutch injected into bench1 (issue 19: "shift the shaft counts at one
/// instant"): the shaft's count 8 higher from t = 0.15 s on, where the machine holds
/// its shaft (I6 from 0.106 s to 0.179 s in its clutch log), is named clutch-slip
/// within 10 ms; the unshifted log names none.
#[test]
fn a_slipping_clutch_injected_into_bench1_is_named_within_10_ms() {
    let dir = TempDir::new("observe-slip");
    let log = edited(&dir, "slip.csv", |t, c| {
        if t >= 0.15 - 1e-9 {
            let s: i64 = c[4].parse().unwrap();
            c[4] = (s + 8).to_string();
        }
    });
    let s = replay_of(&[&log, "--observer", "--out", &dir.join("slip-run.csv")]);
    let o = s.observed.unwrap();
    let t = o
        .first("clutch-slip")
        .unwrap_or_else(|| panic!("named: {o}"));
    assert!((0.15..=0.16).contains(&t), "within 10 ms: {t}: {o}");
    let clean = replay_of(&[
        &data("bench1.csv"),
        "--observer",
        "--out",
        &dir.join("c.csv"),
    ]);
    assert_eq!(clean.observed.unwrap().first("clutch-slip"), None);
}

/// A twin that parts from its machine is named, where it does: the known machine's log
/// at 400/12 N·m (`tests/data`) observed on SPEC's nominal twin from 5° off, whose
/// sequence parts from the machine's (README, "The observer": no tuning found keeps
/// it), raises `twin-parted`, first before the clutch logs' first mismatch (measured
/// 0.579 s, the mismatch at 0.921 s). The oracle is the replay's CSV, the log's counts
/// against the twin's (whole counts, the observer's residual within one of them): at
/// each row that raised it the crank's residual had been past 15 counts for the 10 rows
/// up to it (the observer's `part_counts` 16 and `part_steps` 10), and it is raised at
/// each row that ends 10 rows past 17. bench1 and the known machine's other logs raise
/// no diagnostic (`follows`).
#[test]
fn a_twin_parted_from_the_machine_is_named() {
    let dir = TempDir::new("observe-parted");
    let params = spec_from(&dir, 110.0);
    let out = dir.join("p400.csv");
    let s = observed(
        &data("known-400Nm-12Nm.csv"),
        &data("known-400Nm-12Nm_clutch_log.csv"),
        &params,
        &out,
    );
    let o = s.observed.as_ref().expect("the observer's summary");
    let m = s.matching.as_ref().expect("a clutch log");
    let parted = o
        .first("twin-parted")
        .unwrap_or_else(|| panic!("named: {o}"));
    let mismatch = m
        .first_mismatch()
        .and_then(|k| m.pairs[k].machine.map(|e| e.time))
        .unwrap_or_else(|| panic!("the sequences part: {m}"));
    assert!(
        parted < mismatch,
        "{parted} s, the mismatch at {mismatch} s: {o}"
    );
    let table = Table::from_csv(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let (res, flag) = (
        table.column("crank_residual").unwrap(),
        table.column("twin_parted").unwrap(),
    );
    let (mut low, mut high) = (0, 0);
    for (k, (r, f)) in res.iter().zip(flag).enumerate().skip(1) {
        low = if r.abs() > 15.0 { low + 1 } else { 0 };
        high = if r.abs() > 17.0 { high + 1 } else { 0 };
        let raised = *f == 1.0;
        assert!(
            !raised || low >= 10,
            "row {k}: residual {r}, {low} rows past 15"
        );
        assert!(
            raised || high < 10,
            "row {k}: residual {r}, {high} rows past 17"
        );
    }
}

/// A log the twin wrote itself (S2 at the log's step, through the bench's encoder
/// law): with no model error the observed twin makes the same events (kinds and modes,
/// the log's oracle) and raises no diagnostic; its residual is not 0 (the issue's
/// target): the estimates (which have nothing to find here) move with the counts
/// (measured bounds below).
#[test]
fn a_log_the_twin_wrote_observed_makes_the_same_events() {
    let dir = TempDir::new("observe-self");
    let params = dir.join("s2-1ms.toml");
    let text = host_sim::ScenarioId::CccS2
        .file_text()
        .replace("h = 1e-4", "h = 1e-3");
    std::fs::write(&params, text).unwrap();
    let csv = dir.join("s2.csv");
    let (code, _, err) = run(&["run", &params, "--out", &csv, "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let table = Table::from_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let col = |n| table.column(n).unwrap_or_else(|| panic!("column {n}"));
    let (t, theta1, shaft, motor) = (
        col("t"),
        col("theta1"),
        col("shaft_angle"),
        col("motor_torque"),
    );
    let counts = |x: f64| (x / (TAU / 4096.0)).floor() as i64;
    let mut log = String::from("t,motor_torque,load_torque,crank_counts,shaft_counts\n");
    for k in 0..t.len() {
        log.push_str(&format!(
            "{:.6},{},800.0,{},{}\n",
            t[k],
            motor[k],
            counts(theta1[k]),
            counts(-shaft[k])
        ));
    }
    let log_path = dir.join("s2-log.csv");
    std::fs::write(&log_path, log).unwrap();
    let plain = replay_of(&[&log_path, "--params", &params, "--out", &dir.join("p.csv")]);
    let s = replay_of(&[
        &log_path,
        "--params",
        &params,
        "--observer",
        "--out",
        &dir.join("o.csv"),
    ]);
    let o = s.observed.as_ref().unwrap();
    // Regression values (measured: RMS 0.63 counts, largest 6 at 0.488 s, in I6 near
    // the crank's reversal): the target is 0, which the open loop meets (below).
    assert!(s.crank.largest.0.abs() <= 6, "{}", s.crank);
    assert!(s.crank.rms() <= 0.75, "{}", s.crank);
    assert!(o.onsets.is_empty(), "{o}");
    let ev = |p: &str| std::fs::read_to_string(dir.join(p)).unwrap();
    let (a, b) = (ev("p.events.csv"), ev("o.events.csv"));
    let kinds = |s: &str| -> Vec<Vec<String>> {
        s.lines()
            .map(|l| l.split(',').skip(1).take(3).map(String::from).collect())
            .collect()
    };
    // The same modes in the same order, each by the same kind of event (none taken
    // early as an input change: the torque estimate, which the prediction adds to the
    // motor's input, stays put while the counts agree with the twin).
    assert_eq!(kinds(&a), kinds(&b));
    // Each within 1 ms of the plain replay's, the jam within 3 ms (regression values,
    // measured: 0.67 ms at worst, the first release; the jam 0.83 ms late: the crank
    // creeps into it a count in several ms, where the counts place it least).
    let times = |s: &str| -> Vec<f64> {
        s.lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().parse().unwrap())
            .collect()
    };
    let (ta, tb) = (times(&a), times(&b));
    let last = ta.len() - 1;
    for (k, (x, y)) in ta.iter().zip(&tb).enumerate() {
        let bound = if k == last { 3e-3 } else { 1e-3 };
        assert!((x - y).abs() <= bound, "{k}: {x} {y}");
    }
    assert_eq!(plain.crank.largest.0, 0);
}

/// Bad logs are refused with --observer as without, the line and column named (exit
/// status 2), nothing written: a NaN count, a gap in t.
#[test]
fn bad_logs_are_named_errors_with_the_observer() {
    let dir = TempDir::new("observe-bad");
    let nan = edited(&dir, "nan.csv", |t, c| {
        if (t - 0.004).abs() < 1e-9 {
            c[3] = "NaN".into();
        }
    });
    let text = std::fs::read_to_string(data("bench1.csv")).unwrap();
    let mut rows: Vec<&str> = text.lines().collect();
    rows.remove(101);
    let gap = dir.join("gap.csv");
    std::fs::write(&gap, rows.join("\n")).unwrap();
    let out = dir.join("out.csv");
    for (path, want) in [
        (
            nan,
            "nan.csv: line 6, column crank_counts: NaN is not finite",
        ),
        (gap, "gap.csv: line 102, column t: t = 0.101 s is 0.002"),
    ] {
        let (code, _, err) = run(&["replay", &path, "--observer", "--out", &out]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(want), "{err}");
    }
    assert!(!std::path::Path::new(&out).exists());
}
