//! The runners and the one pipeline that drives them: [`mechanism`] steps a
//! mechanism's simulation, [`converter`] the converter's twin; both tell their states,
//! rows and log lines to an [`Observer`]. [`simulate`] picks the runner of a run's
//! source, [`dispatch`] its precision and gathers the observers (the CSV writer, the
//! pictures' recorder), and [`execute`] is `host-sim run`: files, pictures, summary,
//! exit code.

pub mod columns;
pub mod converter;
pub mod mechanism;
pub mod switching;

use crate::error::{report_run_error, RunError, EXIT_OK};
use crate::options::{Output, RunOptions};
use crate::output::csv::{CsvWriter, Sink};
use crate::output::pictures::{self, Recorder};
use crate::output::{Observer, Observers};
use converter::{log_paths, CccSummary, End};
use mechanism::Summary;
use std::fmt;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use structomat::Real;

/// What a run did: a mechanism's summary or the converter's.
// One per run: the size difference of the summaries (a converter's carries its motor
// law and settings) costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Report {
    /// A mechanism run.
    Mechanism(Summary),
    /// A converter run (a failed step is its [`End::Stopped`]).
    Converter(CccSummary),
}

impl Report {
    /// The exit status of the run: 0, or 1 when a converter's step failed unexpectedly.
    pub fn exit_code(&self) -> u8 {
        match self {
            Report::Mechanism(_) => EXIT_OK,
            Report::Converter(s) => s.exit_code(),
        }
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Report::Mechanism(s) => s.fmt(f),
            Report::Converter(s) => s.fmt(f),
        }
    }
}

/// Runs `opts` in scalar `T` on its runner (the converter's twin for a converter
/// source, else the mechanism's simulation), telling `obs` as it goes.
pub fn simulate<T: Real>(opts: &RunOptions, obs: &mut dyn Observer<T>) -> Result<Report, RunError> {
    if opts.scenario.is_converter() {
        converter::simulate(opts, obs).map(Report::Converter)
    } else {
        mechanism::simulate(opts, obs).map(Report::Mechanism)
    }
}

/// Runs `opts` in its precision (`--f32` or `f64`) with `csv` and, when given, the
/// pictures' recorder as its observers.
pub fn dispatch(
    opts: &RunOptions,
    mut csv: CsvWriter<'_>,
    rec: Option<&mut Recorder>,
) -> Result<Report, RunError> {
    fn go<T: Real>(
        opts: &RunOptions,
        csv: &mut CsvWriter<'_>,
        rec: Option<&mut Recorder>,
    ) -> Result<Report, RunError> {
        let mut obs = Observers::<T>(vec![csv]);
        if let Some(r) = rec {
            obs.0.push(r);
        }
        simulate(opts, &mut obs)
    }
    if opts.f32 {
        go::<f32>(opts, &mut csv, rec)
    } else {
        go::<f64>(opts, &mut csv, rec)
    }
}

/// Runs `opts` with its CSV to the file `path` and, for the converter, the logs next
/// to it ([`log_paths`]).
pub fn run_to_file(
    opts: &RunOptions,
    path: &Path,
    rec: Option<&mut Recorder>,
) -> Result<Report, RunError> {
    let create = |p: &Path| {
        File::create(p)
            .map(BufWriter::new)
            .map_err(|error| RunError::write(&p.display().to_string(), error))
    };
    let mut csv = create(path)?;
    let state = Sink::new(&mut csv, path.display().to_string());
    if !opts.scenario.is_converter() {
        return dispatch(opts, CsvWriter::new(state, Vec::new()), rec);
    }
    let (events, switches) = log_paths(path);
    let (mut ev, mut sw) = (create(&events)?, create(&switches)?);
    let names = (events.display().to_string(), switches.display().to_string());
    let logs = vec![
        Sink::new(&mut ev, names.0.clone()),
        Sink::new(&mut sw, names.1.clone()),
    ];
    let mut report = dispatch(opts, CsvWriter::new(state, logs), rec)?;
    if let Report::Converter(s) = &mut report {
        s.logs = Some(names);
    }
    Ok(report)
}

/// Runs `opts` writing nothing (the CSV goes to [`io::sink`]): the report only, as a
/// parameter sweep needs it. The same code path as [`run_to_file`], so the same
/// summary (without the logs' names).
pub fn run_quiet(opts: &RunOptions) -> Result<Report, RunError> {
    let mut nowhere = io::sink();
    dispatch(
        opts,
        CsvWriter::new(Sink::new(&mut nowhere, "nowhere"), Vec::new()),
        None,
    )
}

/// Runs `host-sim run` with `opts`: the CSV to the file (with a converter's logs next
/// to it) or `stdout` (no logs), the pictures, the summary to the other stream (unless
/// quiet), errors to `stderr`; returns the exit code.
pub fn execute(opts: &RunOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    if let Err(e) = pictures::check(opts) {
        return report_run_error(e, stderr);
    }
    let mut rec = Recorder::for_options(opts);
    let result = match &opts.out {
        Output::Stdout => {
            let csv = CsvWriter::new(Sink::new(stdout, "stdout"), Vec::new());
            dispatch(opts, csv, rec.as_mut()).map(|s| (s, false))
        }
        Output::File(path) => run_to_file(opts, path, rec.as_mut()).map(|s| (s, true)),
    };
    let result = result.and_then(|r| match &rec {
        Some(rec) => pictures::write(opts, rec).map(|_| r),
        None => Ok(r),
    });
    match result {
        Ok((report, to_stdout)) => {
            if !opts.quiet {
                let to: &mut dyn Write = if to_stdout { stdout } else { stderr };
                let _ = writeln!(to, "{report}").and_then(|_| to.flush());
            }
            if let Report::Converter(CccSummary {
                end:
                    End::Stopped {
                        error,
                        expected: false,
                    },
                steps,
                rows,
                ..
            }) = &report
            {
                let _ = writeln!(
                    stderr,
                    "host-sim: {}: step {} failed ({rows} rows written): {error}",
                    opts.scenario.name(),
                    steps + 1,
                );
            }
            report.exit_code()
        }
        Err(e) => report_run_error(e, stderr),
    }
}
