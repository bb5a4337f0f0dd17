//! # host-sim
//!
//! A command-line simulator of the built-in mechanisms of the `structomat` core
//! ([`structomat::mechanisms`]): `host-sim list`, `host-sim run <scenario> [options]`
//! (CSV of the state, the applied and kinetostatic driving torques and the joint
//! reactions, plus a summary), `host-sim batch` (below), `host-sim help`.
//!
//! It also runs the Constantinesco torque converter's scenarios S1 and S2 (SPEC 3) on
//! the core's digital twin: `host-sim run ccc-s1|ccc-s2 [--motor N·M] [--load N·M]
//! [--ccw]` writes the state CSV, the logs of the mode changes and of the coordinate
//! switches, and a summary ([`ccc`]).
//!
//! `host-sim batch FILE --out-dir DIR [--threads N]` runs the runs listed in a batch
//! file (one `host-sim run` argument list a line) N at a time, each into its own files,
//! plus a table `batch.csv` of their outcomes; the files are byte for byte the same for
//! any N and the same as each run alone ([`batch`]). Its job runner, [`run_jobs`], runs
//! any slice of jobs on N threads and returns the results in job order.
//!
//! Pictures: `host-sim run ... --plot DIR` draws the run's plots (SVG and PNG),
//! `--animate FILE.svg|FILE.gif` animates the mechanism ([`pictures`], [`plot`],
//! [`animate`]); `host-sim plot RUN.csv --out-dir DIR` plots a CSV a run wrote; [`draw`]
//! renders figures (and heat maps of sweeps) to SVG and PNG.
//!
//! The output is deterministic: the same command writes the same bytes on every run,
//! in debug and release builds, on 1 or N threads (the core's math is `libm`; the
//! golden SHA-256 hashes of every built-in scenario's CSV are pinned in
//! `host-sim/tests/golden.rs`).
//!
//! Mechanisms and converter runs can also be described in run files (TOML,
//! [`runfile`]): `host-sim run FILE.toml [options]`, the options overriding the file's
//! values; the built-in scenarios ship as such files (`host-sim/scenarios/*.toml`,
//! embedded). `host-sim analyze FILE.toml|<scenario>` prints the motion-transmission
//! sequence that [`analysis`] finds from a mechanism's joints and drivers.
//!
//! A parameter sweep runs files the way `host-sim run` does: [`runfile::parse_value`],
//! [`runfile::set_dotted`] (e.g. `converter.mass = 40`), [`run_file_from_value`], then
//! [`Source::from_file`] into [`RunOptions::from_source`] and [`batch::run_one`] (or
//! [`execute`]).
//!
//! The binary is a thin wrapper over [`main_with`]; tests and benches can call
//! [`parse_args`], [`simulate`] or [`main_with`] directly.

#![warn(missing_docs)]

pub mod analysis;
pub mod animate;
pub mod batch;
pub mod ccc;
pub mod cli;
pub mod columns;
pub mod draw;
pub mod pictures;
pub mod plot;
pub mod run;
pub mod runfile;
pub mod scenarios;
pub mod sweep;

pub use batch::{run_jobs, Progress};
pub use ccc::{CccScenario, CccSummary, End};
pub use cli::{
    parse_args, BatchOptions, Command, Output, PlotOptions, RunOptions, UsageError, HINT, USAGE,
};
pub use columns::{Column, Layout};
pub use run::{simulate, step_count, MaxReaction, MeanSpeed, RunError, Steps, Summary, MAX_STEPS};
pub use runfile::{parse_run_file, run_file_from_value, FileError, RunFile};
pub use scenarios::{ScenarioId, Source};

use std::ffi::OsString;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Exit code of a successful command.
pub const EXIT_OK: u8 = 0;
/// Exit code of a failed run (a step error, a file error, a setup error).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code of a bad command line.
pub const EXIT_USAGE: u8 = 2;

/// Runs the command line `args` (without the program name), writing to `stdout` and
/// `stderr`; returns the exit code. Never panics on user input.
pub fn main_with<I, S>(args: I, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8
where
    I: IntoIterator<Item = S>,
    S: Into<OsString>,
{
    match parse_args(args) {
        Ok(Command::Help) => match stdout
            .write_all(USAGE.as_bytes())
            .and_then(|_| stdout.flush())
        {
            Ok(()) => EXIT_OK,
            Err(e) => report_write(stderr, "stdout", &e),
        },
        Ok(Command::List) => match list(stdout).and_then(|_| stdout.flush()) {
            Ok(()) => EXIT_OK,
            Err(e) => report_write(stderr, "stdout", &e),
        },
        Ok(Command::Run(opts)) => execute(&opts, stdout, stderr),
        Ok(Command::Analyze(source)) => match analyze(&source) {
            Ok(text) => match stdout
                .write_all(text.as_bytes())
                .and_then(|_| stdout.flush())
            {
                Ok(()) => EXIT_OK,
                Err(e) => report_write(stderr, "stdout", &e),
            },
            Err(e) => {
                let _ = writeln!(stderr, "host-sim: analyze {}: {e}", source.name());
                EXIT_FAILURE
            }
        },
        Ok(Command::Batch(opts)) => batch::execute(&opts, stdout, stderr),
        Ok(Command::Plot(opts)) => pictures::plot_csv(&opts, stdout, stderr),
        Ok(Command::Sweep(opts)) => sweep::execute(&opts, stdout, stderr),
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}\n{HINT}");
            EXIT_USAGE
        }
    }
}

/// The text of `host-sim analyze`: for a mechanism, its formula, DOF and groups (the
/// structomatic analysis of [`analysis`]); for the converter, the formula of the mode
/// it starts in. Errors: why no sequence of the library's groups solves it, or why the
/// core refuses the model.
pub fn analyze(source: &Source) -> Result<String, String> {
    let file = source.run_file().map_err(|e| e.to_string())?;
    let mut text = format!("mechanism {}", source.name());
    if let Some(n) = &file.name {
        if n != source.name() {
            text.push_str(&format!(" ({n})"));
        }
    }
    text.push('\n');
    match &file.body {
        runfile::Body::Mechanism(m) => {
            let a = analysis::analyze(m).map_err(|e| e.to_string())?;
            let model = analysis::build_model::<f64>(m, &a).map_err(|e| {
                format!("the sequence was found but the core refuses the model: {e}")
            })?;
            text.push_str(&analysis::report(m, &a, &model));
        }
        runfile::Body::Converter(_) => {
            let c = source
                .converter()
                .ok_or_else(|| "not a converter".to_string())?;
            text.push_str(&format!(
                "formula   {} (the converter's twin: the mode and coordinates change as it runs; host-sim help)\n",
                c.start_formula()
            ));
        }
    }
    Ok(text)
}

/// Writes `host-sim list`: one line per scenario with its formula, description and
/// integration settings. A converter scenario's formula is that of its first mode's
/// first coordinate choice (the modes change it as they go: `host-sim help`).
pub fn list(w: &mut dyn Write) -> io::Result<()> {
    let mut lines = Vec::new();
    for s in ScenarioId::ALL {
        match s.build::<f64>() {
            None => {
                let Some(c) = s.converter() else { continue };
                lines.push((
                    s.name(),
                    c.start_formula(),
                    format!("{}; h = {} s, t_end = {} s", s.description(), c.h, c.t_end),
                ));
            }
            Some(Ok(sc)) => lines.push((
                s.name(),
                sc.model.formula().to_string(),
                format!(
                    "{}; h = {} s, t_end = {} s",
                    s.description(),
                    sc.h,
                    sc.t_end
                ),
            )),
            Some(Err(e)) => lines.push((s.name(), "?".to_string(), format!("cannot build: {e}"))),
        }
    }
    let wn = lines.iter().map(|l| l.0.len()).max().unwrap_or(0);
    let wf = lines.iter().map(|l| l.1.chars().count()).max().unwrap_or(0);
    for (name, formula, desc) in lines {
        writeln!(w, "{name:<wn$}  {formula:<wf$}  {desc}")?;
    }
    Ok(())
}

/// Runs `host-sim run` with `opts`: the CSV to the file or `stdout`, the summary to the
/// other stream (unless quiet), errors to `stderr`; returns the exit code. The converter
/// scenarios go to [`ccc::execute`].
pub fn execute(opts: &RunOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    if opts.scenario.is_converter() {
        return ccc::execute(opts, stdout, stderr);
    }
    if let Err(e) = pictures::check(opts) {
        return report_run_error(e, stderr);
    }
    let mut rec = pictures::Recorder::for_options(opts);
    let result = match &opts.out {
        Output::Stdout => dispatch(opts, stdout, "stdout", rec.as_mut()).map(|s| (s, false)),
        Output::File(path) => run_to_file_with(opts, path, rec.as_mut()).map(|s| (s, true)),
    };
    let result = result.and_then(|r| match &rec {
        Some(rec) => pictures::write(opts, rec).map(|_| r),
        None => Ok(r),
    });
    match result {
        Ok((summary, to_stdout)) => {
            if !opts.quiet {
                let to: &mut dyn Write = if to_stdout { stdout } else { stderr };
                let _ = writeln!(to, "{summary}").and_then(|_| to.flush());
            }
            EXIT_OK
        }
        Err(e) => report_run_error(e, stderr),
    }
}

/// Reports a run's error on `stderr` (with the usage hint for bad options); returns its
/// exit code. A broken pipe on `stdout` (`host-sim run ... | head`: the reader stopped)
/// is not an error of the run.
pub(crate) fn report_run_error(e: RunError, stderr: &mut dyn Write) -> u8 {
    match e {
        RunError::Write { target, error }
            if target == "stdout" && error.kind() == io::ErrorKind::BrokenPipe =>
        {
            EXIT_OK
        }
        e => {
            let _ = writeln!(stderr, "host-sim: {e}");
            if let RunError::Usage(_) = e {
                let _ = writeln!(stderr, "{HINT}");
            }
            e.exit_code()
        }
    }
}

/// Runs the mechanism scenario of `opts` with its CSV to the file `path`.
pub(crate) fn run_to_file(opts: &RunOptions, path: &Path) -> Result<Summary, RunError> {
    run_to_file_with(opts, path, None)
}

fn run_to_file_with(
    opts: &RunOptions,
    path: &Path,
    rec: Option<&mut pictures::Recorder>,
) -> Result<Summary, RunError> {
    let target = path.display().to_string();
    match File::create(path) {
        Ok(f) => dispatch(opts, &mut BufWriter::new(f), &target, rec),
        Err(error) => Err(RunError::Write { target, error }),
    }
}

pub(crate) fn dispatch(
    opts: &RunOptions,
    csv: &mut dyn Write,
    target: &str,
    rec: Option<&mut pictures::Recorder>,
) -> Result<Summary, RunError> {
    if opts.f32 {
        run::simulate_with::<f32>(opts, csv, target, rec)
    } else {
        run::simulate_with::<f64>(opts, csv, target, rec)
    }
}

fn report_write(stderr: &mut dyn Write, target: &str, e: &io::Error) -> u8 {
    if e.kind() == io::ErrorKind::BrokenPipe {
        return EXIT_OK;
    }
    let _ = writeln!(stderr, "host-sim: cannot write {target}: {e}");
    EXIT_FAILURE
}
