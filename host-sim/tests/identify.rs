//! `host-sim identify`: the converter's parameters fitted to a bench log.
//!
//! Oracles: the prototype's log `tests/data/bench1.csv` and its clutch log (the
//! machine's own events and encoders: the identified twin's open-loop replay must
//! reproduce them, issue 19's targets); a log that the twin itself wrote with known
//! perturbed parameters (a mass +7 %, a viscous friction of 0.03 N·m·s/rad at the
//! crank, a motor-torque offset of 0.2 N·m), identified back to those values; logs of
//! a known machine (bench1's identified one) at other loads and motor torques,
//! identified back; the same
//! inputs twice give the same bytes; bad inputs are refused with the field named.
//!
//! The identifications replay the log a few hundred times: they run at release speed
//! (`cargo test --release -p host-sim --test identify`, as CI's release step does) and
//! are ignored in a debug build.

use host_sim::cli::{parse_args, Command};
use host_sim::jobs::identify;
use host_sim::plot::Table;
use host_sim::run::replay;

mod common;
use common::{counts, data, run, TempDir};

/// The options of `host-sim identify ARGS`, as the command line parses them.
fn identify_options(args: &[&str]) -> host_sim::options::IdentifyOptions {
    let cmd = parse_args([&["identify"][..], args].concat()).unwrap_or_else(|e| panic!("{e:?}"));
    let Command::Identify(opts) = cmd else {
        panic!("not identify: {cmd:?}")
    };
    opts
}

/// `host-sim replay LOG --params PARAMS --clutch-log CLUTCH --out OUT`, parsed from its
/// command line as a user's, run: its summary.
fn replay_file(log: &str, params: &str, clutch: &str, out: &str) -> replay::ReplaySummary {
    let cmd = parse_args([
        "replay",
        log,
        "--params",
        params,
        "--clutch-log",
        clutch,
        "--out",
        out,
    ])
    .unwrap_or_else(|e| panic!("{e:?}"));
    let Command::Replay(opts) = cmd else {
        panic!("not a replay")
    };
    replay::run(&opts).unwrap_or_else(|e| panic!("{e}"))
}

/// The value and σ of `key` in a fit.
fn value_of(fit: &identify::Fit, key: &str) -> (f64, f64) {
    let p = fit
        .params
        .iter()
        .find(|p| p.param.key() == key)
        .unwrap_or_else(|| panic!("{key} not fitted"));
    (p.value, p.sigma)
}

/// Identified from bench1 and its clutch log (the default parameters), the open-loop
/// replay of bench1 with the identified file reproduces the machine: the same 21
/// events in the same order, each within 0.5 ms, and a crank residual RMS of at most
/// 2 counts (issue 19's targets; measured on x86_64: 0.210 counts, the largest event
/// difference 0.043 ms, from SPEC's 261 counts and 2 ms). The fit explains the log to
/// its encoders' resolution: its residual standard deviation is within 10 % of the
/// counts' quantization alone, 1/√12 counts (measured 0.276 against 0.289; without
/// the friction at F among the parameters, 0.443). The file is a converter run file
/// that `replay --params` and `run` load; identifying twice writes the same bytes.
/// Its values are those of `tests/data/bench1-identified.toml`, the fixture the
/// observer's tests and `checks/observer-sweep` take as bench1's identification (its
/// header comments, name and description, which name the paths, aside).
#[test]
#[cfg_attr(debug_assertions, ignore = "release speed: cargo test --release")]
fn bench1_identified_replays_its_clutch_log() {
    let dir = TempDir::new("identify-bench1");
    let (log, clutch) = (data("bench1.csv"), data("bench1_clutch_log.csv"));
    let out = dir.join("bench1-twin.toml");
    let args = [&log[..], "--clutch-log", &clutch, "--out", &out, "--quiet"];
    let fit = identify::run(&identify_options(&args)).unwrap_or_else(|e| panic!("{e}"));
    let first = std::fs::read(&out).unwrap();
    let text = String::from_utf8(first.clone()).unwrap();
    let quantization = 1.0 / 12f64.sqrt();
    assert!(fit.s <= 1.1 * quantization, "s = {} counts", fit.s);
    for p in &fit.params {
        assert!(
            p.value >= p.bounds.0 && p.value <= p.bounds.1,
            "{:?} out of its bounds",
            p
        );
        assert!(p.sigma.is_finite() && p.sigma > 0.0, "{p:?}");
        assert!(text.contains(&p.param.key()), "{text}");
    }

    // The identified file replayed by `host-sim replay`, as a user would.
    let replay_out = dir.join("replay.csv");
    let s = replay_file(&log, &out, &clutch, &replay_out);
    assert!(s.crank.rms() <= 2.0, "{s}");
    let m = s.matching.as_ref().expect("a clutch log");
    assert_eq!(m.counts(), (21, 21), "{m}");
    assert_eq!(m.first_mismatch(), None, "{m}");
    for p in &m.pairs {
        let dt = p.dt().expect("both events");
        assert!(dt.abs() <= 0.5e-3, "{m}");
    }
    // `run` takes the file too (S2's motor and load with the identified machine).
    let (code, _, err) = run(&[
        "run",
        &out,
        "--t-end",
        "0.05",
        "--out",
        &dir.join("run.csv"),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");

    // The committed fixture is what `identify` writes today.
    let values = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| {
                !(l.starts_with('#') || l.starts_with("name =") || l.starts_with("description ="))
            })
            .map(str::to_string)
            .collect()
    };
    let fixture = std::fs::read_to_string(data("bench1-identified.toml")).unwrap();
    assert_eq!(
        values(&text),
        values(&fixture),
        "tests/data/bench1-identified.toml is not what identify writes of bench1"
    );

    // Deterministic: the same inputs, the same bytes.
    identify::run(&identify_options(&args)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        std::fs::read(&out).unwrap(),
        first,
        "a second identification differs"
    );
}

/// Identified from bench1's first 0.5 s alone (the log and the clutch log cut there),
/// the twin predicts the rest of the machine's run: the open-loop replay of the whole
/// log keeps all 21 events in order, each of the 5 after 0.5 s within 0.5 ms, and the
/// crank's residual after 0.5 s is at most 2 counts RMS (issue 19's targets for an
/// identified twin, here on samples the fit has not seen; measured on x86_64: 0.032 ms
/// and 0.19 counts, where the six parameters without the friction at F missed by
/// 0.21 ms and 0.37 counts).
#[test]
#[cfg_attr(debug_assertions, ignore = "release speed: cargo test --release")]
fn bench1_identified_from_its_first_half_predicts_the_second() {
    const CUT: f64 = 0.5;
    let dir = TempDir::new("identify-half");
    let (log, clutch) = (data("bench1.csv"), data("bench1_clutch_log.csv"));
    let before = |text: &str, t_col: usize| -> String {
        let mut lines = text.lines();
        let mut out = format!("{}\n", lines.next().unwrap());
        for l in lines {
            let t: f64 = l.split(',').nth(t_col).unwrap().trim().parse().unwrap();
            if t <= CUT + 1e-9 {
                out.push_str(l);
                out.push('\n');
            }
        }
        out
    };
    let (half, half_clutch) = (dir.join("half.csv"), dir.join("half_clutch.csv"));
    std::fs::write(&half, before(&std::fs::read_to_string(&log).unwrap(), 0)).unwrap();
    std::fs::write(
        &half_clutch,
        before(&std::fs::read_to_string(&clutch).unwrap(), 0),
    )
    .unwrap();
    let out = dir.join("half-twin.toml");
    let args = [
        &half[..],
        "--clutch-log",
        &half_clutch,
        "--out",
        &out,
        "--quiet",
    ];
    let fit = identify::run(&identify_options(&args)).unwrap_or_else(|e| panic!("{e}"));
    assert!(fit.replay.matching.as_ref().unwrap().counts().0 < 21);

    let replay_out = dir.join("whole.csv");
    let s = replay_file(&log, &out, &clutch, &replay_out);
    let m = s.matching.as_ref().expect("a clutch log");
    assert_eq!(m.counts(), (21, 21), "{m}");
    assert_eq!(m.first_mismatch(), None, "{m}");
    let late: Vec<f64> = m
        .pairs
        .iter()
        .filter(|p| p.machine.is_some_and(|e| e.time > CUT))
        .map(|p| p.dt().expect("both events"))
        .collect();
    assert_eq!(late.len(), 5, "{m}");
    assert!(late.iter().all(|dt| dt.abs() <= 0.5e-3), "{m}");
    let table = Table::from_csv(&std::fs::read_to_string(&replay_out).unwrap()).unwrap();
    let (t, res) = (
        table.column("t").unwrap(),
        table.column("crank_residual").unwrap(),
    );
    let after: Vec<f64> = t
        .iter()
        .zip(res)
        .filter(|(t, _)| **t > CUT)
        .map(|(_, r)| *r)
        .collect();
    assert_eq!(after.len(), 500);
    let rms = (after.iter().map(|r| r * r).sum::<f64>() / after.len() as f64).sqrt();
    assert!(rms <= 2.0, "crank RMS after {CUT} s: {rms} counts");
}

/// A log the twin wrote itself (S2 at 1 ms with the oscillating mass +7 %, 6.42 kg,
/// viscous friction 0.03 N·m·s/rad at the crank's joint A, and a motor-torque sensor
/// that reads 0.2 N·m low) is identified back to those values, each within 3 of its
/// stated σ, from SPEC's machine (6 kg, no friction, no offset).
#[test]
#[cfg_attr(debug_assertions, ignore = "release speed: cargo test --release")]
fn a_log_of_known_parameters_is_identified_back() {
    let dir = TempDir::new("identify-oracle");
    let truth = [
        ("converter.mass", 6.42),
        ("converter.friction.viscous.A", 0.03),
        ("converter.motor_offset", 0.2),
    ];
    let s2 = host_sim::ScenarioId::CccS2.file_text();
    let text = s2
        .replace("h = 1e-4", "h = 1e-3")
        .replace("mass = 6.0 ", "mass = 6.42 ")
        .replacen(
            "\n[[converter.link]]",
            "\n[converter.friction]\nviscous = { A = 0.03 }\n\n[[converter.link]]",
            1,
        );
    assert!(text.contains("h = 1e-3") && text.contains("mass = 6.42") && text.contains("A = 0.03"));
    let params = dir.join("truth.toml");
    std::fs::write(&params, &text).unwrap();
    let csv = dir.join("truth.csv");
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
    // The sensor reads 0.2 N·m below the 12 N·m the twin was driven with.
    let mut log = String::from("t,motor_torque,load_torque,crank_counts,shaft_counts\n");
    for k in 0..t.len() {
        log.push_str(&format!(
            "{:.6},{},800.0,{},{}\n",
            t[k],
            motor[k] - 0.2,
            counts(theta1[k]),
            counts(-shaft[k])
        ));
    }
    let log_path = dir.join("truth-log.csv");
    std::fs::write(&log_path, log).unwrap();

    let out = dir.join("identified.toml");
    let fit = identify::run(&identify_options(&[
        &log_path,
        "--fit",
        "converter.mass,converter.friction.viscous.A,converter.motor_offset",
        "--out",
        &out,
        "--quiet",
    ]))
    .unwrap_or_else(|e| panic!("{e}"));
    for (key, want) in truth {
        let (v, sigma) = value_of(&fit, key);
        assert!(sigma.is_finite() && sigma > 0.0, "{key}: σ {sigma}");
        assert!(
            (v - want).abs() <= 3.0 * sigma,
            "{key}: identified {v} ± {sigma}, truth {want}"
        );
    }
}

/// Logs of a known machine at operating points other than bench1's (`tests/data`'s
/// README: bench1's identified machine, `known-machine.toml`, run by the twin at
/// T_r = 1000 N·m with a 14 N·m motor and at 800 N·m with 10 N·m, in bench1's format,
/// the torque sensor's noise included), as the kept-back logs of the same machine at
/// other loads and motor torques are: identified from SPEC's machine with the default
/// parameters and each clutch log, each replay meets issue 19's targets (the same
/// events, each within 0.5 ms; crank RMS ≤ 2 counts) and every parameter comes back
/// within 3 σ of the machine's. The search over the whole log from SPEC's machine
/// alone settled in another valley on both (the crank 4.0 counts RMS and an event
/// 2.5 ms off; 0.91 counts and 0.90 ms), and so did the first horizon from one start
/// on the second (0.42 counts, 0.75 ms: its link 2 5.45 kg and E 0.0156 for 5.36 and
/// 0.0141); `identify::fit`'s horizons and starts find the machine (0.18 counts and
/// 0.02 ms; 0.29 and 0.09).
#[test]
#[cfg_attr(debug_assertions, ignore = "release speed: cargo test --release")]
fn a_known_machine_at_other_operating_points_is_identified_back() {
    let machine = host_sim::runfile::parse_value(
        &std::fs::read_to_string(data("known-machine.toml")).unwrap(),
        "known-machine.toml",
    )
    .unwrap();
    // A friction the machine's file leaves out is 0 (the run file's default: the known
    // machine has none at F).
    let truth = |key: &str| -> f64 {
        let mut v = &machine;
        for part in key.split('.') {
            v = match part.parse::<usize>() {
                Ok(k) => &v.as_array().unwrap()[k],
                Err(_) => match v.get(part) {
                    Some(v) => v,
                    None if key.starts_with("converter.friction.") => return 0.0,
                    None => panic!("{key}: no {part}"),
                },
            };
        }
        v.as_float().unwrap_or_else(|| panic!("{key}: {v:?}"))
    };
    for name in ["known-1000Nm-14Nm", "known-800Nm-10Nm"] {
        let dir = TempDir::new("identify-known");
        let (log, clutch) = (
            data(&format!("{name}.csv")),
            data(&format!("{name}_clutch_log.csv")),
        );
        let out = dir.join("identified.toml");
        let args = [&log[..], "--clutch-log", &clutch, "--out", &out, "--quiet"];
        let fit = identify::run(&identify_options(&args)).unwrap_or_else(|e| panic!("{e}"));
        let s = &fit.replay;
        assert!(s.crank.rms() <= 2.0, "{name}: {s}");
        let m = s.matching.as_ref().expect("a clutch log");
        let machine_events = std::fs::read_to_string(&clutch).unwrap().lines().count() - 1;
        assert_eq!(m.counts(), (machine_events, machine_events), "{name}: {m}");
        assert_eq!(m.first_mismatch(), None, "{name}: {m}");
        for p in &m.pairs {
            let dt = p.dt().expect("both events");
            assert!(dt.abs() <= 0.5e-3, "{name}: {m}");
        }
        for p in &fit.params {
            let (key, want) = (p.param.key(), truth(&p.param.key()));
            assert!(
                (p.value - want).abs() <= 3.0 * p.sigma,
                "{name}: {key}: identified {} ± {}, the machine's {want}",
                p.value,
                p.sigma
            );
        }
    }
}

/// Bad inputs are refused before any replay, the field named: a log without a column,
/// an empty stage of keys to fit, an unknown key to fit, a key given twice (in one
/// stage or two), no iterations, a mechanism as the base.
#[test]
fn bad_inputs_are_named() {
    let dir = TempDir::new("identify-bad");
    let good = std::fs::read_to_string(data("bench1.csv")).unwrap();
    let no_shaft: String = good
        .lines()
        .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string() + "\n")
        .collect();
    let bad_log = dir.join("no-shaft.csv");
    std::fs::write(&bad_log, no_shaft).unwrap();
    let out = dir.join("out.toml");
    let log = data("bench1.csv");
    let cases: [(Vec<&str>, &str); 7] = [
        (vec![&bad_log, "--out", &out], "shaft_counts"),
        (
            vec![
                &log,
                "--fit",
                "converter.mass;;converter.link.2.mass",
                "--out",
                &out,
            ],
            "empty stage",
        ),
        (
            vec![
                &log,
                "--fit",
                "converter.mass;converter.mass",
                "--out",
                &out,
            ],
            "twice",
        ),
        (
            vec![&log, "--fit", "converter.mas", "--out", &out],
            "converter.mas",
        ),
        (
            vec![
                &log,
                "--fit",
                "converter.mass,converter.mass",
                "--out",
                &out,
            ],
            "twice",
        ),
        (vec![&log, "--max-iters", "0", "--out", &out], "--max-iters"),
        (
            vec![&log, "--params", "five-bar", "--out", &out],
            "--params",
        ),
    ];
    for (args, named) in cases {
        let (code, _, err) = run(&[&["identify"][..], &args].concat());
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(named), "{args:?}: {err}");
    }
    assert!(!std::path::Path::new(&out).exists());
}

/// `converter.motor_offset` is added to the log's torque: a log whose torque column
/// reads 0.5 N·m low, replayed with an offset of 0.5, is the log itself replayed
/// (every residual and event the same), and 0 (the default) changes nothing.
#[test]
fn the_motor_offset_is_added_to_the_measured_torque() {
    let dir = TempDir::new("identify-offset");
    let text = std::fs::read_to_string(data("bench1.csv")).unwrap();
    let mut low = String::new();
    for (k, line) in text.lines().enumerate() {
        if k == 0 {
            low.push_str(line);
        } else {
            let c: Vec<&str> = line.split(',').collect();
            let m: f64 = c[1].parse().unwrap();
            low.push_str(&format!("{},{},{},{},{}", c[0], m - 0.5, c[2], c[3], c[4]));
        }
        low.push('\n');
    }
    let low_log = dir.join("low.csv");
    std::fs::write(&low_log, low).unwrap();
    let s2 = host_sim::ScenarioId::CccS2.file_text();
    let offset = dir.join("offset.toml");
    std::fs::write(
        &offset,
        s2.replace("[converter]\n", "[converter]\nmotor_offset = 0.5\n"),
    )
    .unwrap();
    let zero = dir.join("zero.toml");
    std::fs::write(
        &zero,
        s2.replace("[converter]\n", "[converter]\nmotor_offset = 0\n"),
    )
    .unwrap();
    let summary = |log: &str, params: &str, out: &str| {
        let cmd = parse_args(["replay", log, "--params", params, "--out", out]).unwrap();
        let Command::Replay(opts) = cmd else { panic!() };
        replay::run(&opts).unwrap()
    };
    let a = summary(&low_log, &offset, &dir.join("a.csv"));
    let b = summary(&data("bench1.csv"), "ccc-s2", &dir.join("b.csv"));
    let c = summary(&data("bench1.csv"), &zero, &dir.join("c.csv"));
    // The torque differs in its last bits (x - 0.5 + 0.5): the residuals agree to a count.
    assert!((a.crank.rms() - b.crank.rms()).abs() < 1.0, "{a}\n{b}");
    assert_eq!((c.crank, c.shaft), (b.crank, b.shaft));
    assert_eq!(
        std::fs::read(dir.join("c.csv")).unwrap(),
        std::fs::read(dir.join("b.csv")).unwrap()
    );
}

/// A parameter whose base value is 0 has no search range (±10 % of 0): asked to fit
/// it, identify refuses before any replay, naming it, and writes nothing (it fitted
/// nothing and gave every parameter a NaN σ).
#[test]
fn a_parameter_at_zero_is_refused_by_name() {
    let dir = TempDir::new("identify-zero");
    let s2 = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/ccc-s2.toml");
    let text = std::fs::read_to_string(s2).unwrap();
    assert!(text.contains("mass_inertia = 0.0400"));
    let params = dir.join("zero.toml");
    std::fs::write(
        &params,
        text.replacen("mass_inertia = 0.0400", "mass_inertia = 0.0", 1),
    )
    .unwrap();
    let out = dir.join("identified.toml");
    let log = data("bench1.csv");
    let e = identify::run(&identify_options(&[
        &log,
        "--params",
        &params,
        "--fit",
        "converter.mass,converter.mass_inertia",
        "--out",
        &out,
        "--quiet",
    ]));
    let Err(e) = e else {
        panic!("identify fitted a parameter of base value 0")
    };
    assert_eq!(e.exit_code(), 2, "{e}");
    let text = e.to_string();
    assert!(
        text.contains("converter.mass_inertia") && text.contains("is 0"),
        "{text}"
    );
    assert!(!std::path::Path::new(&out).exists());
}
