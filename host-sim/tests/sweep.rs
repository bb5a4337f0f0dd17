//! `host-sim sweep`: the table and the heat-maps do not depend on the thread count,
//! each row is what the variant's run alone gives (the oracle: the variant written as a
//! run file by a text edit of the base, run through `host-sim run`'s code path), a bad
//! variant or sweep file is refused before anything runs. Short runs for the debug
//! build.

mod common;

use common::{files, read, run, TempDir};
use host_sim::batch::{self, Outcome};
use host_sim::{parse_run_file, RunOptions, ScenarioId, Source};
use std::collections::BTreeMap;
use std::path::Path;

/// A 2 × 2 sweep of S2 over 0.08 s: the oscillating mass (a key of the converter that
/// no command-line option reaches) and the motor torque. Every variant breaks away
/// before 0.08 s.
const SWEEP: &str = r#"
base = "ccc-s2"
[set]
"run.t_end" = 0.08
[[axis]]
key = "converter.mass"
label = "oscillating mass, kg"
values = [4.0, 8.0]
[[axis]]
key = "run.motor"
values = [10, 14.0]
[[heatmap]]
metric = "first_breakaway"
[[heatmap]]
metric = "load_work"
x = "run.motor"
y = "converter.mass"
"#;

fn sweep_file(dir: &TempDir, text: &str) -> String {
    let path = dir.join("grid.toml");
    std::fs::write(&path, text).expect("write the sweep file");
    path
}

/// The table's rows as maps from column name to cell (no cell of this sweep is quoted).
fn rows(csv: &[u8]) -> Vec<BTreeMap<String, String>> {
    let text = String::from_utf8(csv.to_vec()).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .map(|h| h.to_string())
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[test]
fn the_same_files_on_one_thread_or_two_and_each_row_is_its_run_alone() {
    let dir = TempDir::new("sweep");
    let file = sweep_file(&dir, SWEEP);
    let (one, two) = (dir.join("one"), dir.join("two"));
    let (code, out, err) = run(&[
        "sweep",
        &file,
        "--out-dir",
        &one,
        "--threads",
        "1",
        "--progress",
        "none",
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(err.is_empty(), "{err}");
    assert!(
        out.contains("4 variants of ccc-s2 (2 converter.mass × 2 run.motor) on 1 thread"),
        "{out}"
    );
    assert!(out.contains("4 completed"), "{out}");
    let (code, _, err) = run(&[
        "sweep",
        &file,
        "--out-dir",
        &two,
        "--threads",
        "2",
        "--progress",
        "lines",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("4/4 100%"), "{err}");
    let (a, b) = (files(Path::new(&one)), files(Path::new(&two)));
    let names: Vec<&str> = a.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "heatmap1-first_breakaway.png",
            "heatmap1-first_breakaway.svg",
            "heatmap2-load_work.png",
            "heatmap2-load_work.svg",
            "sweep.csv"
        ]
    );
    assert_eq!(a, b, "1 and 2 threads wrote different files");

    // The oracle: each variant as its own run file, made by editing the base file's
    // text (not its TOML tree), run by the code of `host-sim run --out`.
    let table = rows(&a["sweep.csv"]);
    assert_eq!(table.len(), 4);
    let base = ScenarioId::CccS2.file_text();
    assert!(
        base.contains("mass = 6.0 ")
            && base.contains("motor = 12.0 ")
            && base.contains("t_end = 1.0\n")
    );
    for (k, row) in table.iter().enumerate() {
        assert_eq!(row["job"], k.to_string());
        let (mass, motor) = (&row["converter.mass"], &row["run.motor"]);
        // Grid order: the first axis outermost.
        assert_eq!(mass, ["4", "4", "8", "8"][k]);
        assert_eq!(motor, ["10", "14", "10", "14"][k]);
        let text = base
            .replacen("mass = 6.0 ", &format!("mass = {mass}.0 "), 1)
            .replacen("motor = 12.0 ", &format!("motor = {motor}.0 "), 1)
            .replacen("t_end = 1.0\n", "t_end = 0.08\n", 1);
        let alone = parse_run_file(&text, "alone.toml").expect("the edited file parses");
        let opts = RunOptions::from_source(Source::from_file("alone", alone));
        let csv = dir.path.join(format!("alone{k}.csv"));
        let Outcome::Converter(Ok(s)) = batch::run_one(&opts, &csv) else {
            panic!("variant {k} alone did not run")
        };
        let a = &s.audit;
        let want = [
            ("end", "completed".to_string()),
            ("steps", s.steps.to_string()),
            ("time", s.time.to_string()),
            (
                "first_breakaway",
                s.first_breakaway.expect("breaks away").0.to_string(),
            ),
            ("events", s.event_count().to_string()),
            ("switches", s.switches.to_string()),
            ("shaft_angle", s.shaft_angle.to_string()),
            ("motor_work", a.motor_work.to_string()),
            ("load_work", a.load_work.to_string()),
            ("load_power", (a.load_work / s.time).to_string()),
            ("impact_loss", a.impact_loss.to_string()),
            ("message", String::new()),
        ];
        for (col, v) in want {
            assert_eq!(row[col], v, "variant {k}, column {col}");
        }
        assert!(s.steps == 800 && a.load_work > 0.0, "variant {k}: {s}");
    }
    // The heavier mass breaks away later, the stronger motor sooner (the physics the
    // sweep is for: the table is not just numbers in the right places).
    let t = |k: usize| table[k]["first_breakaway"].parse::<f64>().unwrap();
    assert!(
        t(0) < t(2) && t(1) < t(3) && t(1) < t(0) && t(3) < t(2),
        "{table:?}"
    );

    // The heat-map shows the same values: each cell's value is printed in a grid this
    // small, rounded to 4 significant digits.
    let svg = String::from_utf8(a["heatmap1-first_breakaway.svg"].clone()).unwrap();
    for k in 0..4 {
        let shown: f64 = format!("{:.3e}", t(k)).parse().unwrap();
        assert!(
            svg.contains(&format!(">{shown}<")),
            "{shown} not in the heat-map"
        );
    }
    let png = &a["heatmap1-first_breakaway.png"];
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn a_bad_variant_or_sweep_file_runs_nothing() {
    let dir = TempDir::new("sweep-bad");
    let out = dir.join("out");
    let bad_mass = SWEEP.replace("values = [4.0, 8.0]", "values = [4.0, -8.0]");
    let file = sweep_file(&dir, &bad_mass);
    let (code, _, err) = run(&["sweep", &file, "--out-dir", &out]);
    assert_eq!(code, 2, "{err}");
    // Variants 2 and 3 have the negative mass; the message names them and the field.
    assert!(
        err.contains("variant 2 (converter.mass = -8, run.motor = 10)"),
        "{err}"
    );
    assert!(
        err.contains("variant 3 (converter.mass = -8, run.motor = 14)"),
        "{err}"
    );
    assert!(err.contains("mass"), "{err}");
    assert!(!err.contains("variant 0"), "{err}");
    assert!(err.contains("nothing was run"), "{err}");
    assert!(!Path::new(&out).exists(), "the output directory was made");

    let cases = [
        (
            SWEEP.replace("converter.mass", "converter.weight"),
            "weight",
        ),
        (
            SWEEP.replace("base = \"ccc-s2\"", "base = \"nope.toml\""),
            "cannot read",
        ),
        (
            SWEEP.replace("metric = \"load_work\"", "metric = \"power\""),
            "metric = 'power': unknown",
        ),
        (
            SWEEP.replace("values = [10, 14.0]", "from = 1.0"),
            "axis 2 ('run.motor'): give either values",
        ),
    ];
    for (text, want) in cases {
        let file = sweep_file(&dir, &text);
        let (code, _, err) = run(&["sweep", &file, "--out-dir", &out]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(want), "{err:?} lacks {want:?}");
        assert!(!Path::new(&out).exists());
    }
    for (args, want) in [
        (&["sweep"][..], "not provided:\n  --out-dir <DIR>\n  <FILE>"),
        (&["sweep", "f.toml"][..], "not provided:\n  --out-dir <DIR>"),
        (
            &["sweep", "f.toml", "--out-dir", "o", "--progress", "dots"][..],
            "invalid value 'dots' for '--progress <STYLE>'",
        ),
        (
            &["sweep", "f.toml", "--out-dir", "o", "--threads", "0"][..],
            "--threads",
        ),
    ] {
        let (code, _, err) = run(args);
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    let (code, _, err) = run(&["sweep", &dir.join("missing.toml"), "--out-dir", &out]);
    assert_eq!(code, 1);
    assert!(err.contains("cannot read sweep file"), "{err}");
}

#[test]
fn keep_runs_writes_each_variant_like_batch() {
    let dir = TempDir::new("sweep-keep");
    let file = sweep_file(
        &dir,
        &SWEEP.replace("values = [4.0, 8.0]", "values = [4.0]"),
    );
    let out = dir.join("out");
    let (code, _, err) = run(&["sweep", &file, "--out-dir", &out, "--keep-runs", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.is_empty(), "--quiet: {err}");
    let f = files(Path::new(&out));
    for name in ["000-v0.csv", "000-v0.events.csv", "001-v1.switches.csv"] {
        assert!(f.contains_key(name), "{name} missing: {:?}", f.keys());
    }
    // The variant's CSV is the run alone's: same rows as `host-sim run` with --motor.
    let alone = dir.join("alone.csv");
    let (code, _, err) = run(&[
        "run", "ccc-s2", "--t-end", "0.08", "--motor", "14", "--out", &alone, "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    // Mass 4 is not S2's 6: compare the variant with mass 6 instead.
    let file6 = sweep_file(
        &dir,
        &SWEEP.replace("values = [4.0, 8.0]", "values = [6.0]"),
    );
    let out6 = dir.join("out6");
    let (code, _, err) = run(&[
        "sweep",
        &file6,
        "--out-dir",
        &out6,
        "--keep-runs",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        read(&Path::new(&out6).join("001-v1.csv")),
        read(Path::new(&alone))
    );
}

// The example sweeps shipped with host-sim stay valid (every variant a valid run file)
// and small enough to run in seconds.
#[test]
fn example_sweeps_parse() {
    for (name, variants) in [("mass-motor", 30), ("geometry", 20), ("loop-step", 90)] {
        let path = format!("{}/sweeps/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let s = host_sim::sweep::parse_sweep(&text, &path, |b| {
            let id = ScenarioId::from_name(b).ok_or("not a built-in")?;
            match host_sim::runfile::parse_value(id.file_text(), b).map_err(|e| e.to_string())? {
                toml::Value::Table(t) => Ok((t, b.to_string())),
                _ => Err("not a table".into()),
            }
        })
        .unwrap();
        let v = s.variants().unwrap();
        assert_eq!(v.len(), variants, "{name}");
        assert_eq!(s.heatmaps.len(), 2, "{name}");
        for (k, (_, tree)) in v.into_iter().enumerate() {
            host_sim::run_file_from_value(toml::Value::Table(tree), name)
                .unwrap_or_else(|e| panic!("{name} variant {k}: {e}"));
        }
    }
}

/// A variant that ends at a singularity of the mechanism (S2 without load: the engaged
/// lever carries nothing, the rocker swings out until both diode branches are stretched,
/// |DH| = rod + lever, at 0.3239 s) is a row that says so, not a failure of the sweep.
#[test]
fn a_variant_at_a_singularity_is_a_row() {
    let dir = TempDir::new("sweep-singular");
    let text = "base = \"ccc-s2\"\n[set]\n\"run.t_end\" = 0.33\n[[axis]]\nkey = \"run.load\"\nvalues = [0.0]\n";
    let file = sweep_file(&dir, text);
    let out = dir.join("out");
    let (code, stdout, err) = run(&["sweep", &file, "--out-dir", &out, "--progress", "none"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains("1 variants of ccc-s2 (1 run.load) on 1 thread")
            && stdout.contains(": 0 completed, 1 at a singularity of the mechanism"),
        "{stdout}"
    );
    // An end at a singularity exits 0, as `ccc-s1`'s does: not a failed variant.
    assert!(!err.contains("variant 0 (run.load = 0)"), "{err}");
    let table = rows(&read(&Path::new(&out).join("sweep.csv")));
    assert_eq!(table.len(), 1);
    let row = &table[0];
    assert_eq!(
        (row["exit"].as_str(), row["end"].as_str()),
        ("0", "singularity")
    );
    let t: f64 = row["time"].parse().unwrap();
    // Regression value: the twin's last good state before the stretched diode,
    // 0.3239 s, as measured (tests/f32.rs pins the same).
    assert!((t - 0.3239).abs() < 2e-4, "{t}");
    // It broke away long before (there is no load to hold the shaft).
    assert!(
        row["first_breakaway"].parse::<f64>().unwrap() < 0.1,
        "{row:?}"
    );
}
