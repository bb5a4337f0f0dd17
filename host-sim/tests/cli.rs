//! Command-line tests of `host-sim`, through the built binary (exit codes, streams,
//! files) and the library.

use std::path::PathBuf;
use std::process::Command;

/// Runs the binary; returns (exit code, stdout, stderr).
fn host_sim(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("run host-sim");
    let code = out
        .status
        .code()
        .expect("exit code (not killed by a signal)");
    (
        code,
        String::from_utf8(out.stdout).expect("utf-8 stdout"),
        String::from_utf8(out.stderr).expect("utf-8 stderr"),
    )
}

/// A CSV: header names and numeric rows.
struct Csv {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn parse(text: &str) -> Csv {
        let mut lines = text.lines();
        let names: Vec<String> = lines
            .next()
            .expect("header")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                let row: Vec<f64> = l
                    .split(',')
                    .map(|v| v.parse().unwrap_or_else(|_| panic!("not a number: {v:?}")))
                    .collect();
                assert_eq!(row.len(), names.len(), "row width: {l}");
                row
            })
            .collect();
        Csv { names, rows }
    }

    fn col(&self, name: &str) -> Vec<f64> {
        let k = self
            .names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no column {name}"));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// A fresh path in the temp directory for this test.
fn temp_path(name: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("host-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_file(&p);
    p
}

/// 70 rpm in rad/s: the slider-crank's synchronous speed.
const RPM70: f64 = 70.0 * std::f64::consts::TAU / 60.0;

// (a) Bad arguments: exit 2, a message naming the argument, a hint, nothing on stdout.
#[test]
fn bad_arguments_exit_2_naming_the_argument() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["run", "four-bar"], &["four-bar", "scenario"]),
        (
            &["run", "five-bar", "--h", "-1"],
            &["--h", "-1", "positive"],
        ),
        (
            &["run", "five-bar", "--h", "abc"],
            &["--h", "abc", "not a number"],
        ),
        (&["run", "five-bar", "--h", "0"], &["--h", "positive"]),
        (&["run", "five-bar", "--h", "inf"], &["--h", "finite"]),
        (&["run", "five-bar", "--t-end", "NaN"], &["--t-end"]),
        (
            &["run", "five-bar", "--t-end", "-5"],
            &["--t-end", "positive"],
        ),
        (
            &["run", "five-bar", "--every", "0"],
            &["--every", "at least 1"],
        ),
        (&["run", "five-bar", "--every", "x"], &["--every", "'x'"]),
        (
            &["run", "five-bar", "--frobnicate"],
            &["--frobnicate", "unexpected argument"],
        ),
        (&["run", "five-bar", "--h"], &["--h", "a value is required"]),
        (
            &["run", "five-bar", "--out"],
            &["--out", "a value is required"],
        ),
        (&["run", "five-bar", "--h", "1e-300"], &["steps"]),
        (&["run"], &["required arguments were not provided"]),
        (&["jump"], &["jump", "unrecognized subcommand"]),
        (&[], &["requires a subcommand"]),
    ];
    for (args, needles) in cases {
        let (code, out, err) = host_sim(args);
        assert_eq!(code, 2, "{args:?}: exit code; stderr: {err}");
        assert!(out.is_empty(), "{args:?}: stdout should be empty: {out}");
        let first = err.lines().next().unwrap_or("");
        for n in *needles {
            assert!(first.contains(n), "{args:?}: message {first:?} lacks {n:?}");
        }
        // Our own checks of a value point to `host-sim help`, clap's to `--help`.
        assert!(
            err.contains("host-sim help") || err.contains("try '--help'"),
            "{args:?}: no hint: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

// Each command's help lists its own options: run's, not batch's or sweep's; the
// reference below them is the command's own.
#[test]
fn help_per_command() {
    for args in [
        &["run", "--help"][..],
        &["help", "run"],
        &["run", "five-bar", "--help"],
    ] {
        let (code, out, err) = host_sim(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(out.starts_with("Simulate a scenario"), "{args:?}: {out}");
        assert!(
            out.contains("Usage: host-sim run [OPTIONS] <SCENARIO|FILE.toml>"),
            "{out}"
        );
        for run_only in [
            "--t-end <SECONDS>",
            "--every <N>",
            "--animate <FILE>",
            "--ccw",
            "CSV columns",
        ] {
            assert!(out.contains(run_only), "{args:?} lacks {run_only}: {out}");
        }
        for other in [
            "--out-dir",
            "--threads",
            "--keep-runs",
            "--progress",
            "Batch files",
        ] {
            assert!(!out.contains(other), "{args:?} has {other}: {out}");
        }
    }
    let (code, out, _) = host_sim(&["batch", "--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("--out-dir <DIR>") && out.contains("--threads <N>"),
        "{out}"
    );
    assert!(
        out.contains("Batch files") && !out.contains("--every"),
        "{out}"
    );
    let (code, out, _) = host_sim(&["sweep", "--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("[possible values: bar, lines, none]"), "{out}");
    assert!(
        out.contains("--keep-runs") && !out.contains("--every"),
        "{out}"
    );
    // -h is help everywhere, a summary of the same options.
    let (code, short, _) = host_sim(&["run", "-h"]);
    assert_eq!(code, 0);
    assert!(
        short.contains("--t-end <SECONDS>") && !short.contains("CSV columns"),
        "{short}"
    );
}

#[test]
fn version_is_the_crates() {
    for flag in ["--version", "-V"] {
        let (code, out, err) = host_sim(&[flag]);
        assert_eq!(code, 0, "{err}");
        assert_eq!(out, format!("host-sim {}\n", env!("CARGO_PKG_VERSION")));
    }
}

// A misspelled option is refused with the option it was probably meant to be.
#[test]
fn misspelled_options_get_a_suggestion() {
    for (typo, meant) in [
        ("--tt-end", "--t-end"),
        ("--evry", "--every"),
        ("--animat", "--animate"),
    ] {
        let (code, out, err) = host_sim(&["run", "five-bar", typo, "1"]);
        assert_eq!(code, 2, "{typo}: {err}");
        assert!(out.is_empty());
        assert!(
            err.contains(&format!("unexpected argument '{typo}'"))
                && err.contains(&format!("a similar argument exists: '{meant}'")),
            "{typo}: {err}"
        );
    }
    let (code, _, err) = host_sim(&["batc", "b.batch"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("a similar subcommand exists: 'batch'"),
        "{err}"
    );
}

// A repeated option is an error, not the last value silently winning.
#[test]
fn repeated_options_are_refused() {
    for args in [
        &["run", "five-bar", "--t-end", "1", "--t-end", "2"][..],
        &["run", "five-bar", "--t-end=1", "--t-end", "2"],
        &["run", "five-bar", "--h", "1e-3", "--step", "2e-3"],
        &["run", "five-bar", "--quiet", "--quiet"],
        &["run", "five-bar", "--f32", "--f32"],
        &["run", "five-bar", "--out", "a.csv", "--out", "b.csv"],
        &[
            "batch",
            "b",
            "--out-dir",
            "o",
            "--threads",
            "1",
            "--threads",
            "2",
        ],
    ] {
        let (code, out, err) = host_sim(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?}: {out}");
        assert!(
            err.contains("cannot be used multiple times"),
            "{args:?}: {err}"
        );
    }
    // --animate alone may be given twice (one .svg, one .gif).
    let (code, _, err) = host_sim(&[
        "run",
        "five-bar",
        "--animate",
        "a.svg",
        "--animate",
        "b.svg",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("one .svg and one .gif at most"), "{err}");
}

// The step size keeps its spelling --h (and takes --step); -h stays help.
#[test]
fn step_size_spellings() {
    let args = ["run", "five-bar", "--t-end", "0.005", "--quiet"];
    let (code, h, err) = host_sim(&[&args[..], &["--h", "1e-3"]].concat());
    assert_eq!(code, 0, "{err}");
    // 0.005 s in steps of 1 ms: the header and 6 rows, the last at t = 0.005.
    let csv = Csv::parse(&h);
    assert_eq!(csv.rows.len(), 6);
    assert!((csv.col("t")[5] - 0.005).abs() < 1e-15, "{h}");
    for other in [&["--h=1e-3"][..], &["--step", "1e-3"], &["--step=1e-3"]] {
        let (code, out, err) = host_sim(&[&args[..], other].concat());
        assert_eq!(code, 0, "{other:?}: {err}");
        assert_eq!(out, h, "{other:?}");
    }
    let (code, out, _) = host_sim(&[&args[..], &["-h"]].concat());
    assert_eq!(code, 0);
    assert!(
        out.contains("--h <SECONDS>") && out.contains("--step"),
        "{out}"
    );
}

// (b) Five-bar for 10 steps: header plus 11 rows, the expected columns.
#[test]
fn five_bar_short_run_writes_header_and_11_rows() {
    let (code, out, err) = host_sim(&["run", "five-bar", "--t-end", "0.01"]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    let want = "t,q1,qd1,qdd1,q2,qd2,qdd2,motor_torque1,R1_0,drive_torque1,R2_0,drive_torque2,R3_1,R4_2,R3_4";
    assert_eq!(csv.names.join(","), want);
    assert_eq!(csv.rows.len(), 11);
    let t = csv.col("t");
    assert_eq!(t[0], 0.0);
    assert!((t[10] - 0.01).abs() < 1e-12, "last t = {}", t[10]);
    assert!(csv.rows.iter().flatten().all(|v| v.is_finite()));
    // Thesis table 7 start: q1 = 80°, q2 = 70°, from rest.
    assert!((csv.col("q1")[0] - 80f64.to_radians()).abs() < 1e-15);
    assert!((csv.col("q2")[0] - 70f64.to_radians()).abs() < 1e-15);
    assert_eq!(csv.col("qd1")[0], 0.0);
    // The summary goes to stderr when the CSV goes to stdout.
    assert!(
        err.contains("five-bar") && err.contains("Z(0) + R(1) + R(2) + RRR(3,4)"),
        "{err}"
    );
    assert!(err.contains("ns/step"), "{err}");
}

// (c) Determinism: two runs give byte-identical CSV; --out FILE writes the same bytes.
#[test]
fn two_runs_give_byte_identical_csv() {
    let args = ["run", "five-bar", "--t-end", "0.05", "--every", "2"];
    let (c1, a, _) = host_sim(&args);
    let (c2, b, _) = host_sim(&args);
    assert_eq!((c1, c2), (0, 0));
    assert!(!a.is_empty());
    assert_eq!(a.as_bytes(), b.as_bytes());

    let path = temp_path("determinism.csv");
    let p = path.to_str().expect("utf-8 temp path");
    let (code, out, err) = host_sim(&[
        "run", "five-bar", "--t-end", "0.05", "--every", "2", "--out", p,
    ]);
    assert_eq!(code, 0, "{err}");
    let file = std::fs::read(&path).expect("read the CSV");
    let _ = std::fs::remove_file(&path);
    assert_eq!(file, a.as_bytes());
    // With --out FILE the summary goes to stdout, nothing to stderr.
    assert!(out.contains("five-bar") && out.contains("ns/step"), "{out}");
    assert!(err.is_empty(), "{err}");
}

/// `|a - b| <= rtol * max(|a|, |b|)`.
fn rel_close(a: f64, b: f64, rtol: f64) -> bool {
    (a - b).abs() <= rtol * a.abs().max(b.abs())
}

// (d) Kinetostatics vs forward dynamics: the driving torque the motion requires equals
// the applied one; link 2 of the five-bar has no motor, so its driving torque is 0.
#[test]
fn drive_torque_equals_motor_torque() {
    let (code, out, err) = host_sim(&["run", "five-bar", "--t-end", "0.5", "--every", "5"]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    assert_eq!(csv.rows.len(), 101);
    let (m, d1, d2, t) = (
        csv.col("motor_torque1"),
        csv.col("drive_torque1"),
        csv.col("drive_torque2"),
        csv.col("t"),
    );
    for k in 0..csv.rows.len() {
        assert_eq!(m[k], 10.0, "five-bar motor is 10 N·m at t = {}", t[k]);
        assert!(
            rel_close(d1[k], m[k], 1e-9),
            "t = {}: drive_torque1 {} vs motor_torque1 {}",
            t[k],
            d1[k],
            m[k]
        );
        assert!(
            d2[k].abs() < 1e-9,
            "t = {}: drive_torque2 = {}",
            t[k],
            d2[k]
        );
    }
}

// (e) The SPEC's acceptance criterion: the slider-crank's asynchronous motor settles at
// its synchronous 70 rpm: mean q̇1 over t in [5, 10] s within 1 %.
#[test]
fn slider_crank_mean_speed_is_70_rpm() {
    let (code, out, err) = host_sim(&["run", "slider-crank", "--every", "10"]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    assert_eq!(
        csv.names.join(","),
        "t,q1,qd1,qdd1,motor_torque1,R1_0,drive_torque1,R2_1,R2_3,N3_0,M3_0"
    );
    assert_eq!(csv.rows.len(), 101);
    let (t, qd) = (csv.col("t"), csv.col("qd1"));
    assert!((t[100] - 10.0).abs() < 1e-9, "last t = {}", t[100]);
    let second_half: Vec<f64> = t
        .iter()
        .zip(&qd)
        .filter(|(t, _)| **t >= 5.0 - 1e-9)
        .map(|(_, v)| *v)
        .collect();
    assert_eq!(second_half.len(), 51);
    let mean = second_half.iter().sum::<f64>() / second_half.len() as f64;
    assert!(
        (mean - RPM70).abs() <= 0.01 * RPM70,
        "mean qd1 over [5, 10] s = {mean} rad/s ({} rpm), want 70 rpm ± 1 %",
        mean * 60.0 / std::f64::consts::TAU
    );
    // The same physics check as (d) on the asynchronous motor (its torque varies).
    let (m, d) = (csv.col("motor_torque1"), csv.col("drive_torque1"));
    for k in 0..m.len() {
        assert!(
            rel_close(d[k], m[k], 1e-9),
            "t = {}: drive_torque1 {} vs motor_torque1 {}",
            t[k],
            d[k],
            m[k]
        );
    }
    // The summary's mean (over every step of the second half) agrees.
    assert!(err.contains("rpm"), "{err}");
}

// (f) The core in f32.
#[test]
fn f32_runs() {
    let (code, out, err) = host_sim(&["run", "five-bar", "--t-end", "0.01", "--f32"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("(f32)"), "{err}");
    let csv = Csv::parse(&out);
    assert_eq!(csv.rows.len(), 11);
    assert!(csv.rows.iter().flatten().all(|v| v.is_finite()));
    let (_, out64, _) = host_sim(&["run", "five-bar", "--t-end", "0.01"]);
    let csv64 = Csv::parse(&out64);
    assert_eq!(csv.names, csv64.names);
    let (q, q64) = (csv.col("q1"), csv64.col("q1"));
    assert!(
        rel_close(q[10], q64[10], 1e-5),
        "f32 q1 {} vs f64 {}",
        q[10],
        q64[10]
    );
    let (d, m) = (csv.col("drive_torque1"), csv.col("motor_torque1"));
    assert!(d.iter().zip(&m).all(|(d, m)| rel_close(*d, *m, 1e-3)));
}

#[test]
fn every_n_writes_every_nth_step() {
    let (code, out, err) = host_sim(&[
        "run", "five-bar", "--t-end", "0.01", "--every", "3", "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "--quiet: {err}");
    let t = Csv::parse(&out).col("t");
    // Every third step, and the last state (step 10 of 10) whatever N.
    assert_eq!(t.len(), 5);
    for (k, want) in [0.0, 0.003, 0.006, 0.009, 0.01].iter().enumerate() {
        assert!((t[k] - want).abs() < 1e-12, "t = {t:?}");
    }
}

#[test]
fn step_error_keeps_rows_and_exits_1() {
    // h = 0.1 s is far too large for the five-bar: the explicit step blows up and the
    // core reports the failing evaluation.
    let path = temp_path("step-error.csv");
    let p = path.to_str().expect("utf-8 temp path");
    let (code, out, err) = host_sim(&["run", "five-bar", "--h", "0.1", "--out", p]);
    let text = std::fs::read_to_string(&path).expect("the rows before the error are written");
    let _ = std::fs::remove_file(&path);
    assert_eq!(code, 1, "stderr: {err}");
    assert!(out.is_empty(), "no summary on failure: {out}");
    assert!(err.contains("failed") && err.contains("t = "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let csv = Csv::parse(&text);
    assert!(!csv.rows.is_empty() && csv.rows[0][0] == 0.0);
    assert!(
        err.contains(&format!("({} rows written)", csv.rows.len())),
        "{err}"
    );
}

#[test]
fn file_errors_name_the_path_and_exit_1() {
    let dir = temp_path("no-such-dir");
    let path = dir.join("out.csv");
    let p = path.to_str().expect("utf-8 temp path");
    let (code, out, err) = host_sim(&["run", "five-bar", "--t-end", "0.01", "--out", p]);
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(err.contains(p), "{err}");
    if cfg!(target_os = "linux") && std::path::Path::new("/dev/full").exists() {
        let (code, _, err) =
            host_sim(&["run", "five-bar", "--t-end", "0.01", "--out", "/dev/full"]);
        assert_eq!(code, 1, "{err}");
        assert!(err.contains("/dev/full"), "{err}");
    }
}

#[test]
fn help_and_list() {
    for args in [&["help"][..], &["--help"], &["-h"]] {
        let (code, out, err) = host_sim(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(
            out.contains("Usage: host-sim <COMMAND>") && out.contains("Commands:"),
            "{args:?}: {out}"
        );
        for command in ["list", "run", "analyze", "batch", "sweep", "plot", "help"] {
            assert!(
                out.contains(&format!("\n  {command} ")),
                "{args:?} lacks {command}: {out}"
            );
        }
    }
    let (code, out, err) = host_sim(&["list"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 4, "{out}");
    assert!(
        lines[0].starts_with("slider-crank") && lines[0].contains("Z(0) + R(1) + RRT(2,3)"),
        "{out}"
    );
    assert!(
        lines[1].starts_with("five-bar") && lines[1].contains("Z(0) + R(1) + R(2) + RRR(3,4)"),
        "{out}"
    );
    // The converter starts from its 2-DOF sequence (thesis eq. 3.1), free or in I0.
    let ccc = "Z(0) + R(1) + R(4) + RRR(2,3) + RRR(5,6) + RRR(7,8)";
    assert!(
        lines[2].starts_with("ccc-s1") && lines[2].contains(&format!("{ccc} (free, crank+swing)")),
        "{out}"
    );
    assert!(
        lines[3].starts_with("ccc-s2") && lines[3].contains(&format!("{ccc} (I0, crank+swing)")),
        "{out}"
    );
}

#[test]
fn library_entry_point_matches_the_binary() {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = host_sim::main_with(
        ["run", "five-bar", "--t-end", "0.005", "--quiet"],
        &mut out,
        &mut err,
    );
    assert_eq!(code, host_sim::EXIT_OK);
    assert!(err.is_empty());
    let (_, bin, _) = host_sim(&["run", "five-bar", "--t-end", "0.005", "--quiet"]);
    assert_eq!(out, bin.as_bytes());

    let mut opts = host_sim::RunOptions::new(host_sim::ScenarioId::SliderCrank);
    opts.t_end = Some(0.1);
    let mut csv = Vec::new();
    let s = host_sim::simulate::<f64>(&opts, &mut csv, "memory").expect("run");
    assert_eq!((s.steps, s.rows), (10, 11));
    assert_eq!(s.formula, "Z(0) + R(1) + RRT(2,3)");
}
