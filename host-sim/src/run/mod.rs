//! The runners and the one pipeline that drives them: [`mechanism`] steps a
//! mechanism's simulation, [`converter`] the converter's twin; both tell their states,
//! rows and log lines to an [`Observer`]. [`simulate`] picks the runner of a run's
//! source, [`dispatch`] its precision and gathers the observers (the CSV writer, the
//! pictures' recorder), and [`execute`] is `host-sim run`: files, pictures, summary,
//! exit code. [`replay`] is `host-sim replay`: a bench log on the converter's twin;
//! [`fmu`] is `host-sim fmu`: the converter's twin packaged as an FMI 2.0 FMU.

pub mod columns;
pub mod converter;
pub mod fmu;
pub mod interrupt;
pub mod mechanism;
pub mod observed;
pub mod progress;
pub mod replay;
pub mod switching;

use crate::error::{report_run_error, temp_path, RunError, EXIT_INTERRUPTED, EXIT_OK};
use crate::model::scenarios::Source;
use crate::options::{Output, RunOptions};
use crate::output::csv::{CsvWriter, Sink};
use crate::output::pictures::{self, Recorder};
use crate::output::{Observer, Observers};
use converter::{log_paths, CccSummary, End};
use mechanism::Summary;
use std::fmt;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
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
            Report::Mechanism(s) if s.interrupted => EXIT_INTERRUPTED,
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
/// to it ([`log_paths`]), through [`to_files`].
pub fn run_to_file(
    opts: &RunOptions,
    path: &Path,
    rec: Option<&mut Recorder>,
) -> Result<Report, RunError> {
    let mut targets = vec![path.to_path_buf()];
    if opts.scenario.is_converter() {
        let (events, switches) = log_paths(path);
        targets.extend([events, switches]);
    }
    let mut report = to_files(&targets, |csv| dispatch(opts, csv, rec))?;
    if let (Report::Converter(s), [_, events, switches]) = (&mut report, &targets[..]) {
        s.logs = Some((events.display().to_string(), switches.display().to_string()));
    }
    Ok(report)
}

/// Runs `run` with a CSV writer whose state table goes to the first of `targets` and
/// its logs to the others. Each file is written to its [`temp_path`] and renamed into
/// place when the run is over (completed, failed at a step or interrupted: its rows up
/// to there are whole), so that a crash never leaves half a file; a run that fails
/// before its first row (its set-up) leaves none.
pub fn to_files<R>(
    targets: &[PathBuf],
    run: impl FnOnce(CsvWriter<'_>) -> Result<R, RunError>,
) -> Result<R, RunError> {
    let temps: Vec<_> = targets.iter().map(|p| temp_path(p)).collect();
    let result = write_temps(targets, &temps, run);
    let keep = matches!(
        result,
        Ok(_) | Err(RunError::Step { .. } | RunError::Integrator { .. })
    );
    for (tmp, target) in temps.iter().zip(targets) {
        if tmp == target {
            // A device or a pipe, written in place.
        } else if keep {
            if let Err(error) = std::fs::rename(tmp, target) {
                let _ = std::fs::remove_file(tmp);
                return Err(RunError::write(&target.display().to_string(), error));
            }
        } else {
            let _ = std::fs::remove_file(tmp);
        }
    }
    result
}

/// [`to_files`]'s run: its CSV writer on the files `temps`, named in errors by
/// `targets`.
fn write_temps<R>(
    targets: &[PathBuf],
    temps: &[PathBuf],
    run: impl FnOnce(CsvWriter<'_>) -> Result<R, RunError>,
) -> Result<R, RunError> {
    let names: Vec<String> = targets.iter().map(|p| p.display().to_string()).collect();
    let mut files = Vec::new();
    for (tmp, name) in temps.iter().zip(&names) {
        files.push(
            File::create(tmp)
                .map(BufWriter::new)
                .map_err(|error| RunError::write(name, error))?,
        );
    }
    let mut sinks = files
        .iter_mut()
        .zip(&names)
        .map(|(f, name)| Sink::new(f, name.clone()));
    let Some(state) = sinks.next() else {
        return Err(RunError::Setup("no output file".to_string()));
    };
    run(CsvWriter::new(state, sinks.collect()))
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

/// Refuses, before anything is written, an output path of `opts` (`--out` and a
/// converter's logs next to it, `--plot`, `--animate`) that names its input, the run
/// file: the run would overwrite the model it runs; and two output files that are one
/// file (`--out a.svg --animate a.svg`): the second would overwrite the first.
pub fn refuse_inputs(opts: &RunOptions) -> Result<(), RunError> {
    let mut files: Vec<PathBuf> = opts.animate.clone();
    if let Output::File(out) = &opts.out {
        files.push(out.clone());
        if opts.scenario.is_converter() {
            let (events, switches) = log_paths(out);
            files.extend([events, switches]);
        }
    }
    let places: Vec<PathBuf> = files.iter().map(|p| place(p)).collect();
    for (k, a) in places.iter().enumerate() {
        if let Some(j) = places[..k].iter().position(|b| b == a) {
            return Err(RunError::Usage(crate::error::usage_err(format!(
                "the outputs {} and {} are one file: the second would overwrite the \
                 first; name two files",
                files[j].display(),
                files[k].display()
            ))));
        }
    }
    let Source::File { path: input, .. } = &opts.scenario else {
        return Ok(());
    };
    files.extend(opts.plot.clone());
    match overwritten(&[Path::new(input)], &files) {
        Some((p, _)) => Err(RunError::Usage(crate::error::usage_err(format!(
            "the output {} is the run file itself: the run would overwrite its model; \
             name another file",
            p.display()
        )))),
        None => Ok(()),
    }
}

/// The first of `outputs` that is the same file as one of `inputs` (both exist and
/// canonicalize to the same path), and that input.
pub fn overwritten<'a, 'b>(
    inputs: &[&'b Path],
    outputs: &'a [PathBuf],
) -> Option<(&'a PathBuf, &'b Path)> {
    let inputs: Vec<_> = inputs
        .iter()
        .filter_map(|p| p.canonicalize().ok().map(|c| (c, *p)))
        .collect();
    outputs.iter().find_map(|o| {
        let o_canon = o.canonicalize().ok()?;
        inputs
            .iter()
            .find(|(c, _)| *c == o_canon)
            .map(|(_, input)| (o, *input))
    })
}

/// Where `path` will be written: the file itself when it exists (links followed),
/// else its folder's canonical path joined with its name, else `path` as given.
fn place(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let folder = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (folder.canonicalize(), path.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => path.to_path_buf(),
    }
}

/// Runs `host-sim run` with `opts`: the CSV to the file (with a converter's logs next
/// to it) or `stdout` (no logs), the pictures, the summary to the other stream (unless
/// quiet), errors to `stderr`; returns the exit code.
pub fn execute(opts: &RunOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    if let Err(e) = refuse_inputs(opts).and_then(|()| pictures::check(opts)) {
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
