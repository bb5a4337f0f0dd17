//! Interrupted and failed runs leave whole files (issue 17, item 6): the real binary,
//! stopped by SIGINT or SIGTERM mid-run, finishes its row, completes its CSV and logs,
//! prints its summary marked interrupted and exits 130; a failed run writes no
//! pictures (no 0-byte files, no empty folder); an output that names the run file is
//! refused before anything is written; no progress line when `stderr` is not a
//! terminal.

mod common;

use common::{numeric_csv, TempDir};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Starts `host-sim ARGS`, waits until `file` holds more than `bytes` (the run is under
/// way: its temporary file grows), sends `signal` (`INT` or `TERM`) and waits for the
/// end; returns the exit code, stdout and stderr.
fn interrupt(args: &[&str], growing: &std::path::Path, signal: &str) -> (i32, String, String) {
    let child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start host-sim");
    let start = Instant::now();
    // The temporary files of the outputs, in their folder.
    let dir = growing.parent().expect("a folder");
    loop {
        let size: u64 = std::fs::read_dir(dir)
            .map(|d| {
                d.filter_map(|e| e.ok())
                    .filter_map(|e| e.metadata().ok())
                    .map(|m| m.len())
                    .sum()
            })
            .unwrap_or(0);
        if size > 20_000 || start.elapsed() > Duration::from_secs(60) {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let pid = child.id().to_string();
    let status = Command::new("kill")
        .args([&format!("-{signal}"), &pid])
        .status()
        .expect("kill");
    assert!(status.success());
    let out = child.wait_with_output().expect("wait for host-sim");
    (
        out.status.code().expect("an exit code, not killed"),
        String::from_utf8(out.stdout).expect("utf-8"),
        String::from_utf8(out.stderr).expect("utf-8"),
    )
}

/// Oracle: the file format itself; every row has the header's column count and parses
/// as numbers (a cut row fails both), the last row is the summary's final time.
#[test]
fn sigint_leaves_a_whole_csv_and_a_summary() {
    let dir = TempDir::new("whole-sigint");
    let out = dir.join("five.csv");
    let (code, summary, err) = interrupt(
        &["run", "five-bar", "--t-end", "1000", "--out", &out],
        std::path::Path::new(&out),
        "INT",
    );
    assert_eq!(code, 130, "{err}");
    assert!(summary.contains("interrupted at t = "), "{summary}");
    let text = std::fs::read_to_string(&out).expect("the CSV is in place");
    assert!(text.ends_with('\n'));
    let (names, rows) = numeric_csv(&text);
    assert!(rows.len() > 10, "{} rows", rows.len());
    assert!(rows.iter().flatten().all(|v| v.is_finite()));
    let t_last = rows.last().unwrap()[0];
    let said = common::number_after(&summary, "interrupted at t = ");
    assert!(
        (t_last - said).abs() <= 1e-6 * t_last.max(1.0),
        "{t_last} vs {said}"
    );
    assert_eq!(names[0], "t");
    // Only the CSV is left in the folder: no temporary file.
    assert_eq!(common::files(&dir.path).len(), 1);
}

/// The converter's event and switch logs are flushed and whole too (SIGTERM).
#[test]
fn sigterm_leaves_the_converters_logs() {
    let dir = TempDir::new("whole-sigterm");
    let out = dir.join("s2.csv");
    let (code, summary, err) = interrupt(
        &["run", "ccc-s2", "--t-end", "1000", "--out", &out],
        std::path::Path::new(&out),
        "TERM",
    );
    assert_eq!(code, 130, "{err}");
    assert!(summary.contains("interrupted"), "{summary}");
    for name in ["s2.csv", "s2.events.csv", "s2.switches.csv"] {
        let text = std::fs::read_to_string(dir.path.join(name)).expect("the file is there");
        assert!(!text.is_empty() && text.ends_with('\n'), "{name}");
        let width = text.lines().next().unwrap().split(',').count();
        for (k, l) in text.lines().enumerate() {
            assert_eq!(l.split(',').count(), width, "{name} row {k}: {l}");
        }
    }
    let events = std::fs::read_to_string(dir.path.join("s2.events.csv")).unwrap();
    assert!(
        events.lines().count() > 1,
        "the start event at least:\n{events}"
    );
}

/// A failing run (h = 0.1 s is far too large for the five-bar) writes no animation and
/// no plot folder: its pictures are all or nothing. Before, check() created them empty.
#[test]
fn a_failed_run_leaves_no_empty_pictures() {
    let dir = TempDir::new("whole-pictures");
    let (gif, plots, csv) = (dir.join("a.gif"), dir.join("plots"), dir.join("r.csv"));
    let (code, _, err) = common::run(&[
        "run",
        "five-bar",
        "--h",
        "0.1",
        "--out",
        &csv,
        "--animate",
        &gif,
        "--plot",
        &plots,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(!std::path::Path::new(&gif).exists(), "no 0-byte GIF");
    assert!(
        !std::path::Path::new(&plots).exists(),
        "no empty plot folder"
    );
    // The CSV holds the rows before the failure, whole.
    let (_, rows) = numeric_csv(&std::fs::read_to_string(&csv).unwrap());
    assert!(!rows.is_empty());
}

/// `--out` naming the run file is refused before anything is written: the model is
/// unchanged (byte for byte).
#[test]
fn an_output_that_names_the_run_file_is_refused() {
    let dir = TempDir::new("whole-self");
    let file = dir.join("five.toml");
    let text = host_sim::ScenarioId::FiveBar.file_text();
    std::fs::write(&file, text).unwrap();
    for flag in ["--out", "--plot"] {
        let (code, _, err) = common::run(&["run", &file, "--t-end", "0.01", flag, &file]);
        assert_eq!(code, 2, "{flag}: {err}");
        assert!(err.contains("is the run file itself"), "{err}");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), text, "{flag}");
    }
}

/// Two outputs that are one file (`--out a.svg --animate a.svg`, however spelled) are
/// refused before anything is written: the animation would overwrite the CSV. A file
/// already there is left as it was.
#[test]
fn two_outputs_that_are_one_file_are_refused() {
    let dir = TempDir::new("whole-twice");
    let first = dir.join("a.svg");
    std::fs::write(&first, "kept").unwrap();
    let again = format!("{}/./a.svg", dir.path.display());
    // Not there yet (b.gif): refused all the same, and nothing is written.
    let fresh = dir.join("b.gif");
    for (out, animate) in [(&first, &first), (&first, &again), (&fresh, &fresh)] {
        let args = ["run", "five-bar", "--t-end", "0.01", "--out", out];
        let (code, _, err) = common::run(&[&args[..], &["--animate", animate]].concat());
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("are one file"), "{err}");
        assert_eq!(std::fs::read_to_string(&first).unwrap(), "kept");
    }
    assert!(!Path::new(&fresh).exists());
}

/// With `stderr` a pipe (not a terminal), a run prints no progress line: `stderr`
/// holds nothing but the summary (no `\r`).
#[test]
fn no_progress_off_a_terminal() {
    let dir = TempDir::new("whole-progress");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "run",
            "five-bar",
            "--t-end",
            "1",
            "--quiet",
            "--out",
            &dir.join("r.csv"),
        ])
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(0));
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A batch stopped by SIGINT: the run under way finishes its rows and its whole CSV,
/// the runs not started are not run, `batch.csv` is whole and says which ("interrupted",
/// "not run", exit 130 each), the summary says interrupted and the exit status is 130.
#[test]
fn sigint_stops_a_batch_with_whole_files() {
    let dir = TempDir::new("whole-batch");
    let file = dir.join("runs.txt");
    std::fs::write(
        &file,
        "slider-crank --t-end 100000\nslider-crank --t-end 100000\nslider-crank\n",
    )
    .expect("write");
    let out = dir.join("out");
    let table = std::path::Path::new(&out).join("batch.csv");
    let (code, summary, err) = interrupt(
        &["batch", &file, "--out-dir", &out, "--threads", "1"],
        &table,
        "INT",
    );
    assert_eq!(code, 130, "{summary}{err}");
    assert!(summary.contains("batch     interrupted"), "{summary}");
    let text = std::fs::read_to_string(&table).expect("the table");
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 3, "{text}");
    // job, line, scenario, args, file, exit, end, ...
    assert_eq!((rows[0][5], rows[0][6]), ("130", "interrupted"), "{text}");
    for r in &rows[1..] {
        assert_eq!((r[5], r[6]), ("130", "not run"), "{text}");
    }
    let csv = std::fs::read_to_string(std::path::Path::new(&out).join(rows[0][4]))
        .expect("the interrupted run's CSV");
    let (_, data) = numeric_csv(&csv);
    assert!(data.len() > 10 && data.iter().flatten().all(|v| v.is_finite()));
    // Only the table and the interrupted run's CSV: no temporary file, none of the
    // runs that did not start.
    assert_eq!(common::files(std::path::Path::new(&out)).len(), 2);
}

/// `host-sim identify` stopped by SIGINT mid-search writes no run file (a half-fitted
/// one, its later replays stopped at their start, would read as identified) and exits
/// 130 naming the interruption; nothing is left in the output's folder.
#[test]
fn an_interrupted_identify_writes_no_run_file() {
    let dir = TempDir::new("identify-sigint");
    let out = dir.join("identified.toml");
    let child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["identify", "tests/data/bench1.csv", "--out", &out])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start host-sim");
    // bench1's search takes a minute in release, longer in debug: 2 s in, it is under way.
    std::thread::sleep(Duration::from_secs(2));
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(status.success());
    let done = child.wait_with_output().expect("wait for host-sim");
    let err = String::from_utf8_lossy(&done.stderr);
    assert_eq!(done.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted (SIGINT or SIGTERM) during identify"),
        "{err}"
    );
    assert!(!Path::new(&out).exists(), "a run file was written");
    let left: Vec<_> = std::fs::read_dir(&dir.path)
        .expect("the folder")
        .filter_map(|e| e.ok())
        .collect();
    assert!(left.is_empty(), "{left:?}");
}
