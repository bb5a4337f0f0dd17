//! `host-sim batch`: the files do not depend on the thread count nor on the run, each
//! run's files are those of `host-sim run` alone, a bad line is refused before anything
//! runs. Through the library entry point [`host_sim::main_with`]; the runs are short for
//! the debug build.

mod common;

use common::{files, number_after, read, run, utf8, TempDir};
use host_sim::batch::TABLE_COLUMNS;
use std::path::Path;

/// A batch of every scenario, short runs. The longest run comes first, so that on 2
/// threads later jobs finish before it (a table written in finishing order would
/// show). Two runs fail: a converter's step (exit 1) and a mechanism's step (exit 1).
const BATCH: &str = "\
# the longest first
ccc-s2 --t-end 0.08          # breaks away at 0.0666 s
five-bar --t-end 0.05 --every 5

slider-crank --t-end 1
ccc-s1 --t-end 0.02
ccc-s2 --t-end 0.02 --ccw --motor 10 --load 600
five-bar --f32 --t-end 0.02
ccc-s2 --h 0.05              # far too coarse: a failed step
five-bar --h 0.2             # the same for a mechanism
";

/// The lines of [`BATCH`] that are runs: (line number, arguments).
fn batch_lines() -> Vec<(usize, Vec<&'static str>)> {
    BATCH
        .lines()
        .enumerate()
        .filter_map(|(k, l)| {
            let args: Vec<&str> = l
                .split('#')
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect();
            (!args.is_empty()).then_some((k + 1, args))
        })
        .collect()
}

/// Writes `text` as a batch file in `dir`; returns its path.
fn batch_file(dir: &TempDir, text: &str) -> String {
    let path = dir.join("runs.batch");
    std::fs::write(&path, text).expect("write the batch file");
    path
}

/// Runs `host-sim batch FILE --out-dir DIR --threads N`; returns (exit, stdout, stderr).
fn batch(file: &str, out_dir: &str, threads: usize) -> (u8, String, String) {
    let n = threads.to_string();
    run(&["batch", file, "--out-dir", out_dir, "--threads", &n])
}

/// The two directories hold the same file names with the same bytes.
fn assert_same_files(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "{what}: file lists"
    );
    for (name, bytes) in &fa {
        assert!(bytes == &fb[name], "{what}: {name} differs");
    }
}

// 1 thread and 2 threads write the same files, byte for byte; a second run on 2
// threads too. The table is in job order although on 2 threads a later job finished
// first.
#[test]
fn one_and_two_threads_write_the_same_bytes() {
    let tmp = TempDir::new("batch-threads");
    let file = batch_file(&tmp, BATCH);
    let dirs = ["t1", "t2", "t2-again"].map(|d| tmp.join(d));
    let mut stderrs = Vec::new();
    for (dir, threads) in dirs.iter().zip([1, 2, 2]) {
        let (code, out, err) = batch(&file, dir, threads);
        // Two runs fail, so the batch exits 1; it still writes everything.
        assert_eq!(code, 1, "{threads} threads: {err}");
        assert!(out.contains("8 runs") && out.contains("2 failed"), "{out}");
        assert!(!err.contains("panicked"), "{err}");
        stderrs.push(err);
    }
    let n = batch_lines().len();
    // Per run a CSV, per converter run two logs, and the table.
    let converters = batch_lines()
        .iter()
        .filter(|(_, a)| a[0].starts_with("ccc"))
        .count();
    assert_eq!(files(Path::new(&dirs[0])).len(), n + 2 * converters + 1);
    assert_same_files(Path::new(&dirs[0]), Path::new(&dirs[1]), "1 vs 2 threads");
    assert_same_files(Path::new(&dirs[1]), Path::new(&dirs[2]), "2 threads twice");
    // On 2 threads the first job (the longest) was not the first to finish: the
    // equality above is not the trivial one of a serial order.
    let first_done = stderrs[1]
        .lines()
        .find(|l| l.contains("[1/8]"))
        .expect("a progress line");
    assert!(
        !first_done.contains("job 0 "),
        "2 threads: job 0 finished first: {first_done}"
    );
}

// Each run's files in the batch are byte for byte those of `host-sim run <line> --out
// FILE` alone; the table has one row per run in job order, with its outcome.
#[test]
fn each_run_as_alone_and_the_table() {
    let tmp = TempDir::new("batch-alone");
    let file = batch_file(&tmp, BATCH);
    let dir = tmp.join("out");
    let (code, _, err) = batch(&file, &dir, 2);
    assert_eq!(code, 1, "{err}");
    let dir = Path::new(&dir);
    let lines = batch_lines();
    let table = String::from_utf8(read(&dir.join("batch.csv"))).expect("utf-8 table");
    let mut rows = table.lines();
    assert_eq!(rows.next(), Some(TABLE_COLUMNS.join(",").as_str()));
    let rows: Vec<Vec<&str>> = rows
        .map(|r| r.splitn(TABLE_COLUMNS.len(), ',').collect())
        .collect();
    assert_eq!(rows.len(), lines.len());
    let col = |name: &str| {
        TABLE_COLUMNS
            .iter()
            .position(|c| *c == name)
            .expect("a column")
    };
    for (job, ((line, args), row)) in lines.iter().zip(&rows).enumerate() {
        let name = row[col("file")];
        assert_eq!(row[col("job")], job.to_string());
        assert_eq!(row[col("line")], line.to_string());
        assert_eq!(row[col("scenario")], args[0]);
        assert_eq!(row[col("args")], args.join(" "));
        assert_eq!(name, format!("{job:03}-{}.csv", args[0]));

        // The same run alone.
        let alone = tmp.join(&format!("alone-{job}.csv"));
        let mut cmd = vec!["run"];
        cmd.extend(args);
        cmd.extend(["--quiet", "--out", &alone]);
        let (code, _, _) = run(&cmd);
        assert_eq!(row[col("exit")], code.to_string(), "job {job}");
        let mut pairs = vec![(dir.join(name), Path::new(&alone).to_path_buf())];
        if args[0].starts_with("ccc") {
            let (e, s) = host_sim::ccc::log_paths(&dir.join(name));
            let (ae, as_) = host_sim::ccc::log_paths(Path::new(&alone));
            pairs.extend([(e, ae), (s, as_)]);
        }
        for (in_batch, by_itself) in pairs {
            assert!(
                read(&in_batch) == read(&by_itself),
                "job {job} ({}): {} differs from the run alone",
                args.join(" "),
                in_batch.display()
            );
        }
    }
    // The outcomes.
    let end: Vec<&str> = rows.iter().map(|r| r[col("end")]).collect();
    assert_eq!(
        end,
        [
            "completed",
            "completed",
            "completed",
            "completed",
            "completed",
            "completed",
            "failed",
            "failed"
        ]
    );
    let s2 = &rows[0];
    assert_eq!(s2[col("steps")], "800");
    assert_eq!(s2[col("time")].parse::<f64>().ok(), Some(0.08));
    assert_eq!(s2[col("rows")], "801");
    let breakaway: f64 = s2[col("first_breakaway")]
        .parse()
        .expect("a breakaway time");
    // Regression value: S2's first breakaway, 0.0666 s, as the twin measures it.
    assert!((breakaway - 0.0666).abs() < 1e-4, "{breakaway}");
    assert!(s2[col("events")].parse::<u64>().expect("events") >= 2);
    let residual: f64 = s2[col("audit_residual")].parse().expect("a residual");
    assert!(residual.abs() < 1e-6, "{residual}");
    assert_eq!(s2[col("message")], "");
    // five-bar every 5th step: 50 steps, 11 rows; no converter columns.
    let fb = &rows[1];
    assert_eq!((fb[col("steps")], fb[col("rows")]), ("50", "11"));
    assert_eq!(fb[col("first_breakaway")], "");
    assert_eq!(fb[col("audit_residual")], "");
    // The failed runs say why; the mechanism's has no end time.
    for failed in &rows[6..] {
        assert_eq!(failed[col("exit")], "1");
        assert!(failed[col("message")].contains("failed"), "{failed:?}");
    }
    assert_eq!(rows[7][col("time")], "");
    assert!(err.contains("job 6 (line 9: ccc-s2 --h 0.05)"), "{err}");
}

// A bad line is refused with its line number and what is wrong, before anything runs:
// no output directory, no file.
#[test]
fn a_bad_line_is_refused_before_anything_runs() {
    let tmp = TempDir::new("batch-bad");
    let text = "\
# fine
five-bar --t-end 0.01

ccc-s2 --load -5
five-bar --out x.csv
";
    let file = batch_file(&tmp, text);
    let dir = tmp.join("out");
    let (code, out, err) = batch(&file, &dir, 2);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty(), "{out}");
    let lines: Vec<&str> = err.lines().collect();
    assert!(lines[0].contains("line 4: --load: -5 is negative"), "{err}");
    assert!(lines[1].contains("line 5: --out"), "{err}");
    assert!(
        err.contains("nothing was run") && err.contains("host-sim help"),
        "{err}"
    );
    assert!(
        !Path::new(&dir).exists(),
        "the output directory was created"
    );

    // No runs at all; a missing file (exit 1, a file error); bad options of batch.
    let empty = batch_file(&tmp, "# only a comment\n\n");
    let (code, _, err) = batch(&empty, &dir, 1);
    assert_eq!(code, 2);
    assert!(err.contains("no runs"), "{err}");
    let (code, _, err) = batch(utf8(&tmp.path.join("missing.batch")), &dir, 1);
    assert_eq!(code, 1);
    assert!(err.contains("cannot read batch file"), "{err}");
    let (code, _, err) = run(&["batch", &file, "--out-dir", &dir, "--threads", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("--threads"), "{err}");
    assert!(!Path::new(&dir).exists());
}

/// An end at a singularity of the mechanism has one exit status, whichever scenario
/// meets it (issue 17, item 4): `ccc-s1` (free mode, the diode rods in line at 0.324 s)
/// and `ccc-s2 --load 0` (nothing holds the shaft: both diode branches stretched at
/// 0.3239 s) and a general mechanism, `mechanisms/stretched-four-bar.toml` (its coupler
/// and rocker stretch in line at t* = acos 0.65 s), all end "singularity" with exit 0,
/// in the batch's table and alone (on the code before, `ccc-s2 --load 0` and the
/// four-bar exited 1 with "step failed").
#[test]
fn an_end_at_a_singularity_has_one_exit_status() {
    let tmp = TempDir::new("batch-singular");
    let four_bar = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/mechanisms/stretched-four-bar.toml"
    );
    let lines = [
        vec!["ccc-s1", "--t-end", "0.4"],
        vec!["ccc-s2", "--load", "0", "--t-end", "0.33"],
        vec![four_bar],
    ];
    let text: String = lines.iter().map(|l| l.join(" ") + "\n").collect();
    let file = batch_file(&tmp, &text);
    let dir = tmp.join("out");
    let (code, _, err) = batch(&file, &dir, 1);
    assert_eq!(code, 0, "{err}");
    let table = String::from_utf8(read(&Path::new(&dir).join("batch.csv"))).expect("utf-8");
    let col = |name: &str| {
        TABLE_COLUMNS
            .iter()
            .position(|c| *c == name)
            .expect("a column")
    };
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .map(|r| r.splitn(TABLE_COLUMNS.len(), ',').collect())
        .collect();
    assert_eq!(rows.len(), 3);
    for (args, row) in lines.iter().zip(&rows) {
        assert_eq!(
            (row[col("exit")], row[col("end")]),
            ("0", "singularity"),
            "{args:?}"
        );
        // The message says how it ended, as the run's summary does: not "failed".
        let message = row[col("message")];
        assert!(!message.contains("failed"), "{args:?}: {message}");
        if args[0] != four_bar {
            assert!(
                message.starts_with("\"at the mechanism's singularity: "),
                "{args:?}: {message}"
            );
        }
        let alone = tmp.join("alone.csv");
        let mut cmd = vec!["run"];
        cmd.extend(args.iter().copied());
        cmd.extend(["--out", &alone]);
        let (code, out, err) = run(&cmd);
        assert_eq!(code, 0, "{args:?}: {err}");
        let said = format!("{out}{err}");
        if args[0] == four_bar {
            // Located past the last step (0.862 s), within 1e-5 s of the analytic t*
            // (the bound; the summary prints 6 decimals), though the run drives
            // the rocker's angle there (a dead point of the crank's), whose speed grows
            // without bound toward t*: located in the first coordinates too
            // (`Alternatives::locate_singularity`; it was 4.0e-4 s late, at the
            // rocker's own limit).
            let t = number_after(&said, "ended at a singularity at t = ");
            let t_star = 0.65f64.acos();
            eprintln!("located {t} s, t* = {t_star} s");
            assert!(t > 0.862 && (t - t_star).abs() < 1e-5, "{said}");
            assert!(said.contains("(group RRR("), "{said}");
        } else {
            assert!(
                said.contains("at the mechanism's singularity"),
                "{args:?}: {said}"
            );
        }
    }
}

/// A run file whose path holds a comma and a quote (`T_r=800,motor="12".toml`) is one
/// cell of `batch.csv`'s scenario column, quoted as the CSV standard says: every record
/// has the header's columns (the path unquoted shifted every later column of its row).
/// Oracle: the csv crate's reader.
#[test]
fn a_scenario_named_with_a_comma_is_one_cell() {
    let tmp = TempDir::new("batch-comma");
    let scenarios = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/five-bar.toml");
    let text = std::fs::read_to_string(scenarios).expect("five-bar's run file");
    let file = tmp.join("T_r=800,motor=\"12\".toml");
    std::fs::write(&file, text).expect("write the run file");
    let batch_path = batch_file(
        &tmp,
        &format!("{file} --t-end 0.01\nfive-bar --t-end 0.01\n"),
    );
    let dir = tmp.join("out");
    let (code, _, err) = batch(&batch_path, &dir, 1);
    assert_eq!(code, 0, "{err}");
    let mut reader = csv::Reader::from_path(Path::new(&dir).join("batch.csv")).expect("batch.csv");
    let header = reader.headers().expect("a header").clone();
    assert_eq!(header.len(), TABLE_COLUMNS.len());
    let scenario = TABLE_COLUMNS
        .iter()
        .position(|c| *c == "scenario")
        .expect("a column");
    let records: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("a record")).collect();
    assert_eq!(records.len(), 2);
    for r in &records {
        assert_eq!(r.len(), TABLE_COLUMNS.len(), "{r:?}");
    }
    assert_eq!(&records[0][scenario], file.as_str());
    assert_eq!(&records[1][scenario], "five-bar");
}
