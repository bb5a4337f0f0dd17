//! `host-sim batch`: the runs of a batch file, N at a time, with output files that do
//! not depend on N.
//!
//! Two layers:
//! - [`run_jobs`], a small reusable job runner: a slice of jobs on N scoped threads that
//!   take the next job index from a shared counter; the results come back in job order,
//!   and the caller's thread gets a [`Progress`] callback as each job finishes (a
//!   progress bar needs nothing more). Parameter sweeps are meant to build on it.
//! - the batch command: [`parse_batch`] checks every line of the file before anything
//!   runs, [`run_one`] runs one line exactly as `host-sim run <line> --out FILE` would
//!   (same code path, so the same bytes), [`write_table`] writes `batch.csv`, and
//!   [`execute`] ties them together for the command line.
//!
//! Why the files cannot depend on the thread count: each job builds its own model and
//! workspace and writes only its own files (named by job index, not by finishing
//! order); the jobs share nothing but the job counter; the table is written after all
//! jobs finished, from the results gathered by job index. Only the progress lines on
//! `stderr` come in finishing order.

use crate::ccc::{self, CccSummary, End};
use crate::cli::{parse_args, BatchOptions, Command, RunOptions, HINT};
use crate::run::{RunError, Steps, Summary};
use crate::scenarios::Source;
use std::borrow::Cow;
use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;
use std::time::Instant;

/// A finished job, as [`run_jobs`] reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// The job's index in the slice.
    pub job: usize,
    /// Jobs finished so far, this one included (1..=`total`).
    pub done: usize,
    /// Jobs in all.
    pub total: usize,
}

/// Runs `work(k, &jobs[k])` for every job on `threads` worker threads (at least 1, at
/// most one per job) and returns the results in job order, whatever order they finish
/// in. `progress` is called on the caller's thread once per job, as each one finishes
/// (so it may hold non-`Send` state such as a terminal handle).
///
/// The workers take the next job index from a shared atomic counter, so a long job
/// does not hold up the others; a result travels back to the caller with its index.
/// A panic in `work` or `progress` is resumed on the caller's thread once every worker
/// has stopped.
pub fn run_jobs<J, R, W, P>(jobs: &[J], threads: usize, work: W, mut progress: P) -> Vec<R>
where
    J: Sync,
    R: Send,
    W: Fn(usize, &J) -> R + Sync,
    P: FnMut(Progress, &R),
{
    let total = jobs.len();
    let workers = threads.clamp(1, total.max(1));
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<R>> = (0..total).map(|_| None).collect();
    thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        for _ in 0..workers {
            let tx = tx.clone();
            let (next, work) = (&next, &work);
            scope.spawn(move || loop {
                // Relaxed is enough: the counter only hands out distinct indices; the
                // results reach the caller through the channel, which synchronizes.
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = jobs.get(k) else { break };
                if tx.send((k, work(k, job))).is_err() {
                    // The caller stopped listening (its progress callback panicked).
                    break;
                }
            });
        }
        // The workers hold the only senders left: the loop ends when they all stop.
        drop(tx);
        for (done, (job, result)) in rx.iter().enumerate() {
            progress(
                Progress {
                    job,
                    done: done + 1,
                    total,
                },
                &result,
            );
            results[job] = Some(result);
        }
    });
    // Every index below `total` was taken by exactly one worker, and a worker that
    // panicked has made `thread::scope` panic above, so every slot is filled.
    results
        .into_iter()
        .map(|r| r.expect("every job reported its result"))
        .collect()
}

/// One run of a batch file.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchRun {
    /// Its line in the file, from 1.
    pub line: usize,
    /// The line's arguments (those of `host-sim run`), comment removed.
    pub args: Vec<String>,
    /// The parsed options (their `out` is unused: [`run_one`] is given the file).
    pub opts: RunOptions,
}

/// A line of a batch file that is not a valid run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadLine {
    /// The line, from 1.
    pub line: usize,
    /// What is wrong (the message `host-sim run` would give, or why the batch refuses
    /// the line).
    pub message: String,
}

impl fmt::Display for BadLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

/// Parses a batch file: one run a line, written like the arguments of `host-sim run`;
/// `#` starts a comment, blank lines are skipped. Each run is checked as `host-sim run`
/// checks it before its first step (its options, and its step count and step size in
/// its precision: [`Steps::check`]). `--out` is refused: the batch names the files.
/// Errors: every bad line, in file order.
pub fn parse_batch(text: &str) -> Result<Vec<BatchRun>, Vec<BadLine>> {
    let (mut runs, mut bad) = (Vec::new(), Vec::new());
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let code = raw.split('#').next().unwrap_or("");
        let args: Vec<&str> = code.split_whitespace().collect();
        if args.is_empty() {
            continue;
        }
        match parse_line(&args) {
            Ok(opts) => runs.push(BatchRun {
                line,
                args: args.iter().map(|a| a.to_string()).collect(),
                opts,
            }),
            Err(message) => bad.push(BadLine { line, message }),
        }
    }
    if bad.is_empty() {
        Ok(runs)
    } else {
        Err(bad)
    }
}

fn parse_line(args: &[&str]) -> Result<RunOptions, String> {
    if let Some(a) = args
        .iter()
        .find(|a| **a == "--out" || a.starts_with("--out="))
    {
        return Err(format!(
            "{a}: not in a batch (the batch names each run's files in --out-dir)"
        ));
    }
    if let Some(a) = args.iter().find(|a| {
        ["--plot", "--animate", "--fps", "--slow"]
            .iter()
            .any(|o| **a == *o || a.starts_with(&format!("{o}=")))
    }) {
        return Err(format!(
            "{a}: not in a batch (draw a job's pictures with host-sim plot or run)"
        ));
    }
    match parse_args(std::iter::once("run").chain(args.iter().copied())) {
        Ok(Command::Run(opts)) => {
            Steps::check(&opts).map_err(|e| e.to_string())?;
            Ok(opts)
        }
        Ok(_) => Err("help is not a run".to_string()),
        Err(e) => Err(e.0),
    }
}

/// The CSV file name of job `job` of `total`: the index with at least 3 digits (as
/// many as the last index needs, so that the names sort in job order) and the
/// scenario (a run file: its stem), e.g. `003-ccc-s2.csv`.
pub fn file_name(job: usize, total: usize, scenario: &Source) -> String {
    let width = total.saturating_sub(1).to_string().len().max(3);
    format!("{job:0width$}-{}.csv", scenario.label())
}

/// What one run of a batch did.
// One per job, gathered once: the size difference of the summaries (a converter's
// carries its motor law and settings) costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Outcome {
    /// A mechanism scenario: its summary, or why it failed.
    Mechanism(Result<Summary, RunError>),
    /// A converter scenario: its summary (a failed step is its [`End::Stopped`]), or
    /// why it could not run.
    Converter(Result<CccSummary, RunError>),
}

impl Outcome {
    /// The exit status `host-sim run` gives for this run alone.
    pub fn exit_code(&self) -> u8 {
        match self {
            Outcome::Mechanism(Ok(_)) => crate::EXIT_OK,
            Outcome::Converter(Ok(s)) => s.exit_code(),
            Outcome::Mechanism(Err(e)) | Outcome::Converter(Err(e)) => e.exit_code(),
        }
    }

    /// How the run ended, one word: `completed`, `singularity` (at a singularity of
    /// the mechanism: `ccc-s1`'s expected end, or the diode's rods and levers in line),
    /// `failed` (a step failed otherwise) or `error` (setup, options, files).
    pub fn end(&self) -> &'static str {
        match self {
            Outcome::Mechanism(Ok(_))
            | Outcome::Converter(Ok(CccSummary {
                end: End::Completed,
                ..
            })) => "completed",
            Outcome::Converter(Ok(CccSummary {
                end: End::Stopped { error, .. },
                ..
            })) if error.at_singularity() => "singularity",
            Outcome::Converter(Ok(_))
            | Outcome::Mechanism(Err(RunError::Step { .. } | RunError::Integrator { .. })) => {
                "failed"
            }
            Outcome::Mechanism(Err(_)) | Outcome::Converter(Err(_)) => "error",
        }
    }

    /// The error of a run that did not complete, as `host-sim run` reports it.
    pub fn message(&self) -> Option<String> {
        match self {
            Outcome::Mechanism(Ok(_)) => None,
            Outcome::Converter(Ok(s)) => match &s.end {
                End::Completed => None,
                End::Stopped { error, .. } => Some(format!("step {} failed: {error}", s.steps + 1)),
            },
            Outcome::Mechanism(Err(e)) | Outcome::Converter(Err(e)) => Some(e.to_string()),
        }
    }
}

/// Runs `opts` with its CSV to `csv` (and a converter's logs next to it): the code of
/// `host-sim run --out`, without the printing.
pub fn run_one(opts: &RunOptions, csv: &Path) -> Outcome {
    if opts.scenario.is_converter() {
        Outcome::Converter(ccc::run_to_files(opts, csv))
    } else {
        Outcome::Mechanism(crate::run_to_file(opts, csv))
    }
}

/// Runs `opts` writing nothing (the CSV and logs go to [`io::sink`]): the outcome
/// only, as a parameter sweep needs it. The same code path as [`run_one`], so the same
/// summary.
pub fn run_quiet(opts: &RunOptions) -> Outcome {
    let mut csv = io::sink();
    if opts.scenario.is_converter() {
        let sink = ccc::Sink {
            w: &mut csv,
            target: "nowhere".into(),
        };
        Outcome::Converter(ccc::dispatch(opts, sink, None, None))
    } else {
        Outcome::Mechanism(crate::dispatch(opts, &mut csv, "nowhere", None))
    }
}

/// The columns of `batch.csv` (described in `host-sim help`).
pub const TABLE_COLUMNS: [&str; 15] = [
    "job",
    "line",
    "scenario",
    "args",
    "file",
    "exit",
    "end",
    "steps",
    "time",
    "rows",
    "first_breakaway",
    "events",
    "switches",
    "audit_residual",
    "message",
];

/// Writes `batch.csv`: the header, then one row per run in job order (`runs[k]` gave
/// `outcomes[k]`). Numbers in `{}` Display (shortest round-trip); no wall times, so
/// the table depends on nothing but the runs.
pub fn write_table(w: &mut dyn Write, runs: &[BatchRun], outcomes: &[Outcome]) -> io::Result<()> {
    writeln!(w, "{}", TABLE_COLUMNS.join(","))?;
    let total = runs.len();
    for (job, (run, outcome)) in runs.iter().zip(outcomes).enumerate() {
        let some = |x: Option<String>| x.unwrap_or_default();
        // steps, time, rows, first_breakaway, events, switches, audit_residual
        let numbers: [Option<String>; 7] = match outcome {
            Outcome::Mechanism(Ok(s)) => [
                Some(s.steps.to_string()),
                Some(s.time.to_string()),
                Some(s.rows.to_string()),
                None,
                None,
                None,
                None,
            ],
            Outcome::Mechanism(Err(
                RunError::Step { steps, rows, .. } | RunError::Integrator { steps, rows, .. },
            )) => [
                Some(steps.to_string()),
                None,
                Some(rows.to_string()),
                None,
                None,
                None,
                None,
            ],
            Outcome::Converter(Ok(s)) => [
                Some(s.steps.to_string()),
                Some(s.time.to_string()),
                Some(s.rows.to_string()),
                s.first_breakaway.map(|(t, _)| t.to_string()),
                Some(s.event_count().to_string()),
                Some(s.switches.to_string()),
                Some(s.audit.residual().to_string()),
            ],
            Outcome::Mechanism(Err(_)) | Outcome::Converter(Err(_)) => Default::default(),
        };
        write!(
            w,
            "{job},{},{},{},{},{},{}",
            run.line,
            run.opts.scenario.name(),
            cell(&run.args.join(" ")),
            cell(&file_name(job, total, &run.opts.scenario)),
            outcome.exit_code(),
            outcome.end()
        )?;
        for n in numbers {
            write!(w, ",{}", some(n))?;
        }
        writeln!(w, ",{}", cell(&some(outcome.message())))?;
    }
    Ok(())
}

/// A CSV cell: quoted (with inner quotes doubled) when it holds a comma, a quote or a
/// line break (error messages name groups like `RRR(5,6)`).
pub(crate) fn cell(s: &str) -> Cow<'_, str> {
    if s.contains([',', '"', '\n', '\r']) {
        Cow::Owned(format!("\"{}\"", s.replace('"', "\"\"")))
    } else {
        Cow::Borrowed(s)
    }
}

/// Runs `host-sim batch` with `opts`: checks the whole file first (a bad line: exit
/// code 2, before anything runs), runs the lines on `opts.threads` threads with a
/// progress line on `stderr` per finished run (unless quiet), writes `batch.csv`,
/// reports each failed run on `stderr` in job order and a closing summary on `stdout`
/// (unless quiet). Exit code 0 when every run gave 0, else 1.
pub fn execute(opts: &BatchOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    let file = opts.file.display();
    let text = match fs::read_to_string(&opts.file) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: cannot read batch file {file}: {e}");
            return crate::EXIT_FAILURE;
        }
    };
    let runs = match parse_batch(&text) {
        Ok(runs) if runs.is_empty() => {
            let _ = writeln!(
                stderr,
                "host-sim: batch file {file}: no runs (only blank lines and comments)\n{HINT}"
            );
            return crate::EXIT_USAGE;
        }
        Ok(runs) => runs,
        Err(bad) => {
            for b in &bad {
                let _ = writeln!(stderr, "host-sim: batch file {file} {b}");
            }
            let _ = writeln!(stderr, "nothing was run; {HINT}");
            return crate::EXIT_USAGE;
        }
    };
    let dir = &opts.out_dir;
    if let Err(e) = fs::create_dir_all(dir) {
        let _ = writeln!(stderr, "host-sim: cannot create {}: {e}", dir.display());
        return crate::EXIT_FAILURE;
    }
    let total = runs.len();
    let start = Instant::now();
    let outcomes = run_jobs(
        &runs,
        opts.threads,
        |job, run: &BatchRun| {
            run_one(
                &run.opts,
                &dir.join(file_name(job, total, &run.opts.scenario)),
            )
        },
        |p, outcome| {
            if !opts.quiet {
                let _ = writeln!(
                    stderr,
                    "batch     [{}/{}] job {} (line {}: {}): {}",
                    p.done,
                    p.total,
                    p.job,
                    runs[p.job].line,
                    runs[p.job].args.join(" "),
                    outcome.end()
                );
            }
        },
    );
    let wall = start.elapsed();
    let table = dir.join("batch.csv");
    let written = File::create(&table).and_then(|f| {
        let mut w = BufWriter::new(f);
        write_table(&mut w, &runs, &outcomes)?;
        w.flush()
    });
    if let Err(e) = written {
        let _ = writeln!(stderr, "host-sim: cannot write {}: {e}", table.display());
        return crate::EXIT_FAILURE;
    }
    let mut failed = 0;
    for (job, (run, outcome)) in runs.iter().zip(&outcomes).enumerate() {
        if outcome.exit_code() != crate::EXIT_OK {
            failed += 1;
            let _ = writeln!(
                stderr,
                "host-sim: job {job} (line {}: {}): {}",
                run.line,
                run.args.join(" "),
                outcome.message().unwrap_or_default()
            );
        }
    }
    if !opts.quiet {
        let threads = opts.threads.clamp(1, total);
        let _ = writeln!(
            stdout,
            "batch     {total} runs of {file} on {threads} thread{} in {:.3} s: {} succeeded, {failed} failed\ntable     {}",
            if threads == 1 { "" } else { "s" },
            wall.as_secs_f64(),
            total - failed,
            table.display()
        )
        .and_then(|_| stdout.flush());
    }
    if failed == 0 {
        crate::EXIT_OK
    } else {
        crate::EXIT_FAILURE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    // The results come back in job order although later jobs finish first, and the
    // progress callback sees every job once.
    #[test]
    fn results_in_job_order_whatever_the_finishing_order() {
        let jobs: Vec<u64> = (0..12).collect();
        for threads in [1, 2, 3, 64] {
            let mut seen = Vec::new();
            let out = run_jobs(
                &jobs,
                threads,
                |k, &j| {
                    // The first job is by far the longest: with 2 threads or more,
                    // the others finish while it runs.
                    thread::sleep(Duration::from_millis(if j == 0 { 100 } else { 1 }));
                    (k, j * j)
                },
                |p, r: &(usize, u64)| {
                    assert_eq!(p.job, r.0);
                    assert_eq!(p.total, 12);
                    seen.push((p.done, p.job));
                },
            );
            let want: Vec<(usize, u64)> = jobs.iter().map(|&j| (j as usize, j * j)).collect();
            assert_eq!(out, want, "{threads} threads");
            assert_eq!(
                seen.iter().map(|s| s.0).collect::<Vec<_>>(),
                (1..=12).collect::<Vec<_>>()
            );
            let mut order: Vec<usize> = seen.iter().map(|s| s.1).collect();
            if threads > 1 {
                // The long first job finished after a later one.
                assert_ne!(order[0], 0, "{threads} threads: {order:?}");
            }
            order.sort_unstable();
            assert_eq!(order, (0..12).collect::<Vec<_>>());
        }
    }

    #[test]
    fn no_jobs() {
        let out: Vec<u8> = run_jobs(&[] as &[u8], 2, |_, &j| j, |_, _| panic!("no job"));
        assert!(out.is_empty());
    }

    #[test]
    fn batch_lines() {
        let text = "\
# loads
ccc-s2 --load 600 --t-end 0.3   # trailing comment

  five-bar\t--f32
";
        let runs = parse_batch(text).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0].line, 2);
        assert_eq!(runs[0].args, ["ccc-s2", "--load", "600", "--t-end", "0.3"]);
        assert_eq!(runs[0].opts.load, Some(600.0));
        assert_eq!(runs[1].line, 4);
        assert!(runs[1].opts.f32);
        assert_eq!(parse_batch("# nothing\n\n"), Ok(vec![]));
    }

    #[test]
    fn bad_lines_name_their_number() {
        let text = "\
five-bar
ccc-s3
five-bar --out x.csv
five-bar --h 1e-300
ccc-s1 --ccw
--help
run five-bar
";
        let bad = parse_batch(text).unwrap_err();
        let got: Vec<(usize, &str)> = bad.iter().map(|b| (b.line, b.message.as_str())).collect();
        let want = [
            (2, "unknown scenario 'ccc-s3'"),
            (3, "--out: not in a batch"),
            (4, "steps"),
            (5, "--ccw: ccc-s1"),
            (6, "help is not a run"),
            (7, "unknown scenario 'run'"),
        ];
        assert_eq!(got.len(), want.len(), "{got:?}");
        for ((line, msg), (wl, wm)) in got.iter().zip(want) {
            assert_eq!(*line, wl, "{msg}");
            assert!(msg.contains(wm), "line {line}: {msg:?} lacks {wm:?}");
        }
        assert!(bad[0].to_string().starts_with("line 2: "));
    }

    // The example batch shipped with host-sim stays valid.
    #[test]
    fn example_batch_parses() {
        let runs = parse_batch(include_str!("../batches/loads.batch")).unwrap();
        assert!(runs.len() >= 4);
    }

    #[test]
    fn file_names_sort_in_job_order() {
        use crate::ScenarioId;
        let s = |id: ScenarioId| Source::from(id);
        assert_eq!(file_name(3, 10, &s(ScenarioId::CccS2)), "003-ccc-s2.csv");
        assert_eq!(
            file_name(7, 1000, &s(ScenarioId::FiveBar)),
            "007-five-bar.csv"
        );
        assert_eq!(
            file_name(7, 1001, &s(ScenarioId::FiveBar)),
            "0007-five-bar.csv"
        );
        assert_eq!(
            file_name(0, 0, &s(ScenarioId::SliderCrank)),
            "000-slider-crank.csv"
        );
        // A run file's runs are named by its stem.
        let file = ScenarioId::FiveBar.run_file().unwrap();
        let f = Source::from_file("dir/my-linkage.toml", file);
        assert_eq!(file_name(2, 3, &f), "002-my-linkage.csv");
    }

    #[test]
    fn cells_with_commas_are_quoted() {
        assert_eq!(cell("a b"), "a b");
        assert_eq!(cell("RRR(5,6)"), "\"RRR(5,6)\"");
        assert_eq!(cell("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
