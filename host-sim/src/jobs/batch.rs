//! `host-sim batch`: the runs of a batch file, N at a time, with output files that do
//! not depend on N.
//!
//! On the worker pool ([`super::pool::run_jobs`]): [`parse_batch`] checks every line
//! of the file before anything runs, [`run_one`] runs one line exactly as `host-sim run
//! <line> --out FILE` would (the same pipeline, [`crate::run::run_to_file`], so the
//! same bytes), [`write_table`] writes `batch.csv`, and [`execute`] ties them together
//! for the command line.
//!
//! Why the files cannot depend on the thread count: each job builds its own model and
//! workspace and writes only its own files (named by job index, not by finishing
//! order); the jobs share nothing but the job counter; the table is written after all
//! jobs finished, from the results gathered by job index. Only the progress lines on
//! `stderr` come in finishing order.

use super::pool::run_jobs;
use crate::error::{RunError, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, HINT};
use crate::model::scenarios::Source;
use crate::options::args::parse_run_line;
use crate::options::{BatchOptions, RunOptions, Steps};
use crate::run::converter::{CccSummary, End};
use crate::run::interrupt;
use crate::run::mechanism::Summary;
use crate::run::{self, Report};
use std::borrow::Cow;
use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::Instant;

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
    let opts = parse_run_line(args)?;
    Steps::check(&opts).map_err(|e| e.to_string())?;
    Ok(opts)
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
            Outcome::Mechanism(Ok(s)) if s.interrupted => EXIT_INTERRUPTED,
            Outcome::Mechanism(Ok(_)) => EXIT_OK,
            Outcome::Converter(Ok(s)) => s.exit_code(),
            Outcome::Mechanism(Err(e)) | Outcome::Converter(Err(e)) => e.exit_code(),
        }
    }

    /// How the run ended, one word: `completed`, `singularity` (at a singularity of
    /// the mechanism: `ccc-s1`'s expected end, or the diode's rods and levers in line),
    /// `failed` (a step failed otherwise) or `error` (setup, options, files).
    pub fn end(&self) -> &'static str {
        match self {
            Outcome::Mechanism(Ok(s)) if s.interrupted => "interrupted",
            Outcome::Mechanism(Ok(s)) if s.singular.is_some() => "singularity",
            Outcome::Converter(Ok(CccSummary {
                end: End::Interrupted,
                ..
            })) => "interrupted",
            Outcome::Mechanism(Ok(_))
            | Outcome::Converter(Ok(CccSummary {
                end: End::Completed,
                ..
            })) => "completed",
            Outcome::Converter(Ok(s)) if s.end.at_singularity() => "singularity",
            Outcome::Converter(Ok(_))
            | Outcome::Mechanism(Err(RunError::Step { .. } | RunError::Integrator { .. })) => {
                "failed"
            }
            Outcome::Mechanism(Err(RunError::NotRun))
            | Outcome::Converter(Err(RunError::NotRun)) => "not run",
            Outcome::Mechanism(Err(_)) | Outcome::Converter(Err(_)) => "error",
        }
    }

    /// The error of a run that did not complete, as `host-sim run` reports it.
    pub fn message(&self) -> Option<String> {
        match self {
            Outcome::Mechanism(Ok(_)) => None,
            Outcome::Converter(Ok(s)) => match &s.end {
                End::Completed => None,
                End::Interrupted => Some("interrupted (SIGINT or SIGTERM)".to_string()),
                End::Stopped {
                    error,
                    expected: true,
                } => Some(format!("at the mechanism's singularity: {error}")),
                End::Stopped { error, .. } => Some(format!("step {} failed: {error}", s.steps + 1)),
            },
            Outcome::Mechanism(Err(e)) | Outcome::Converter(Err(e)) => Some(e.to_string()),
        }
    }
}

impl Outcome {
    /// The outcome of a run of `opts` that gave `r`.
    pub fn of(opts: &RunOptions, r: Result<Report, RunError>) -> Outcome {
        match r {
            Ok(Report::Mechanism(s)) => Outcome::Mechanism(Ok(s)),
            Ok(Report::Converter(s)) => Outcome::Converter(Ok(s)),
            Err(e) if opts.scenario.is_converter() => Outcome::Converter(Err(e)),
            Err(e) => Outcome::Mechanism(Err(e)),
        }
    }
}

/// Runs `opts` with its CSV to `csv` (and a converter's logs next to it): the code of
/// `host-sim run --out`, without the printing.
pub fn run_one(opts: &RunOptions, csv: &Path) -> Outcome {
    Outcome::of(opts, run::run_to_file(opts, csv, None))
}

/// Runs `opts` writing nothing: the outcome only, as a parameter sweep needs it. The
/// same code path as [`run_one`], so the same summary.
pub fn run_quiet(opts: &RunOptions) -> Outcome {
    Outcome::of(opts, run::run_quiet(opts))
}

/// The columns of `batch.csv` (described in `host-sim help batch`).
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
            cell(run.opts.scenario.name()),
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
            return EXIT_FAILURE;
        }
    };
    let runs = match parse_batch(&text) {
        Ok(runs) if runs.is_empty() => {
            let _ = writeln!(
                stderr,
                "host-sim: batch file {file}: no runs (only blank lines and comments)\n{HINT}"
            );
            return EXIT_USAGE;
        }
        Ok(runs) => runs,
        Err(bad) => {
            for b in &bad {
                let _ = writeln!(stderr, "host-sim: batch file {file} {b}");
            }
            let _ = writeln!(stderr, "nothing was run; {HINT}");
            return EXIT_USAGE;
        }
    };
    let dir = &opts.out_dir;
    if let Err(e) = fs::create_dir_all(dir) {
        let _ = writeln!(stderr, "host-sim: cannot create {}: {e}", dir.display());
        return EXIT_FAILURE;
    }
    let total = runs.len();
    let start = Instant::now();
    let outcomes = run_jobs(
        &runs,
        opts.threads,
        |job, run: &BatchRun| {
            // SIGINT or SIGTERM: the runs under way finish their rows and files as
            // interrupted; the others do not start.
            if interrupt::requested() {
                return Outcome::of(&run.opts, Err(RunError::NotRun));
            }
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
        return EXIT_FAILURE;
    }
    let stopped = interrupt::requested();
    let mut failed = 0;
    for (job, (run, outcome)) in runs.iter().zip(&outcomes).enumerate() {
        if stopped && outcome.exit_code() == EXIT_INTERRUPTED {
            continue;
        }
        if outcome.exit_code() != EXIT_OK {
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
    let cut = outcomes
        .iter()
        .filter(|o| o.exit_code() == EXIT_INTERRUPTED)
        .count();
    if !opts.quiet {
        if stopped {
            let _ = writeln!(
                stdout,
                "batch     interrupted (SIGINT or SIGTERM): {cut} of {total} runs interrupted or not run (the table's end column says which); the files hold the runs up to there"
            );
        }
        let threads = opts.threads.clamp(1, total);
        let _ = writeln!(
            stdout,
            "batch     {total} runs of {file} on {threads} thread{} in {:.3} s: {} succeeded, {failed} failed\ntable     {}",
            if threads == 1 { "" } else { "s" },
            wall.as_secs_f64(),
            total - failed - if stopped { cut } else { 0 },
            table.display()
        )
        .and_then(|_| stdout.flush());
    }
    if stopped {
        EXIT_INTERRUPTED
    } else if failed == 0 {
        EXIT_OK
    } else {
        EXIT_FAILURE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            (7, "unexpected argument 'five-bar'"),
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
        let runs = parse_batch(include_str!("../../batches/loads.batch")).unwrap();
        assert!(runs.len() >= 4);
    }

    #[test]
    fn file_names_sort_in_job_order() {
        use crate::model::scenarios::ScenarioId;
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
