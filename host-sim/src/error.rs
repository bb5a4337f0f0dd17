//! The errors of a run and of a command line, the process exit codes, the number
//! formats of messages and the whole-file writes: the bottom layer, which every other
//! imports.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};
use structomat::StepError;

/// Exit code of a successful command.
pub const EXIT_OK: u8 = 0;
/// Exit code of a failed run (a step error, a file error, a setup error).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code of a bad command line.
pub const EXIT_USAGE: u8 = 2;
/// Exit code of a run stopped by SIGINT or SIGTERM (128 + SIGINT, the shells' rule),
/// after its files were completed and its summary marked interrupted.
pub const EXIT_INTERRUPTED: u8 = 130;

/// A number in a message, to six significant digits with the trailing zeros dropped:
/// plain between 1e-3 and 1e6 in magnitude (`0.25`, `-65`, `7.33038`), else with an
/// exponent (`1e12`, `4.2e-42`), never 40 digits or a `0.000000` that hides a small
/// value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sci(pub f64);

impl fmt::Display for Sci {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 || !v.is_finite() {
            return write!(f, "{v}");
        }
        let e = format!("{v:.5e}");
        let (mantissa, exp) = e.split_once('e').unwrap_or((&e, "0"));
        let exp: i32 = exp.parse().unwrap_or(0);
        if (-3..6).contains(&exp) {
            let decimals = usize::try_from(5 - exp).unwrap_or(0);
            f.write_str(trim_zeros(&format!("{v:.decimals$}")))
        } else {
            write!(f, "{}e{exp}", trim_zeros(mantissa))
        }
    }
}

/// `1.500` → `1.5`, `2.000` → `2`; a number without a decimal point as it is.
fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// A figure of a summary: six decimals (`7.340182`) between 1e-3 and 1e9 in magnitude,
/// else six significant decimals with an exponent (`4.218000e-5`, `1.000000e12`); an
/// exact zero as `0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fig(pub f64);

impl fmt::Display for Fig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 {
            f.write_str("0")
        } else if !v.is_finite() || (1e-3..1e9).contains(&v.abs()) {
            write!(f, "{v:.6}")
        } else {
            write!(f, "{v:.6e}")
        }
    }
}

/// The hint appended to argument errors.
pub const HINT: &str = "run `host-sim help` for usage";

/// A bad command line: the one-line message names the argument and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UsageError(pub String);

impl fmt::Display for UsageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// A [`UsageError`] of a message.
pub fn usage_err(msg: impl Into<String>) -> UsageError {
    UsageError(msg.into())
}

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The options are unusable (too many steps, a step that underflows in `f32`):
    /// exit code 2.
    Usage(UsageError),
    /// The scenario could not be built or set up: exit code 1.
    Setup(String),
    /// A step (or the kinetostatics after it) failed; the rows before it were written:
    /// exit code 1.
    Step {
        /// Steps completed before the failure.
        steps: u64,
        /// Whether the kinetostatics at the state after `steps` steps failed (else the
        /// next step did).
        kinetostatics: bool,
        /// CSV data rows written (including the one at t = 0).
        rows: u64,
        /// The core's error (it names the group, the time and the cause).
        error: StepError,
        /// The run's warnings before it (a motor driven out of its working zone).
        warnings: Vec<String>,
    },
    /// The adaptive integrator gave up between two output times (a step below its
    /// smallest, too many steps or rejections); the rows before were written: exit
    /// code 1.
    Integrator {
        /// Output intervals completed before the failure.
        steps: u64,
        /// CSV data rows written (including the one at t = 0).
        rows: u64,
        /// What the integrator reported.
        error: String,
    },
    /// A batch's or a sweep's run not started: SIGINT or SIGTERM came first (exit code
    /// 130, as the interrupted runs').
    NotRun,
    /// A command stopped by SIGINT or SIGTERM before its result was whole (exit code
    /// 130): what it was doing, and that nothing was written.
    Interrupted(&'static str),
    /// Writing the CSV failed: exit code 1.
    Write {
        /// The file's path, or `stdout`.
        target: String,
        /// The I/O error.
        error: io::Error,
    },
}

impl RunError {
    /// The process exit code for this error: 2 for bad options, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            RunError::Usage(_) => EXIT_USAGE,
            RunError::NotRun | RunError::Interrupted(_) => EXIT_INTERRUPTED,
            _ => EXIT_FAILURE,
        }
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Usage(e) => write!(f, "{e}"),
            RunError::Setup(e) => f.write_str(e),
            RunError::Step {
                steps,
                kinetostatics,
                rows,
                error,
                warnings,
            } => {
                if *kinetostatics {
                    write!(
                        f,
                        "kinetostatics after step {steps} failed ({rows} rows written): {error}"
                    )?;
                } else {
                    write!(
                        f,
                        "step {} failed ({rows} rows written): {error}",
                        steps + 1
                    )?;
                }
                for w in warnings {
                    write!(f, "; warning: {w}")?;
                }
                Ok(())
            }
            RunError::Integrator { steps, rows, error } => write!(
                f,
                "output interval {} failed ({rows} rows written): the adaptive integrator: {error}",
                steps + 1
            ),
            RunError::NotRun => {
                f.write_str("not run: interrupted (SIGINT or SIGTERM) before it started")
            }
            RunError::Interrupted(what) => {
                write!(
                    f,
                    "interrupted (SIGINT or SIGTERM) during {what}: nothing written"
                )
            }
            RunError::Write { target, error } => write!(f, "cannot write {target}: {error}"),
        }
    }
}

impl std::error::Error for RunError {}

impl RunError {
    /// The error of writing `target` (a path, or `stdout`).
    pub fn write(target: &str, error: io::Error) -> RunError {
        RunError::Write {
            target: target.to_string(),
            error,
        }
    }
}

/// Reports a run's error on `stderr` (with the usage hint for bad options); returns its
/// exit code. A broken pipe on `stdout` (`host-sim run ... | head`: the reader stopped)
/// is not an error of the run.
pub fn report_run_error(e: RunError, stderr: &mut dyn io::Write) -> u8 {
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

/// Reports a failed write of a command's output on `stderr`; returns the exit code (0
/// for a broken pipe: the reader stopped).
pub fn report_write(stderr: &mut dyn io::Write, target: &str, e: &io::Error) -> u8 {
    if e.kind() == io::ErrorKind::BrokenPipe {
        return EXIT_OK;
    }
    let _ = writeln!(stderr, "host-sim: cannot write {target}: {e}");
    EXIT_FAILURE
}

/// The temporary file a whole-file write of `path` goes to first: in the same folder
/// (so the rename stays on one file system), hidden, named after this process; `path`
/// itself when it exists and is not a regular file (`/dev/null`, `/dev/full`, a pipe:
/// a rename would replace the device by a file).
pub fn temp_path(path: &Path) -> PathBuf {
    if path.exists() && !path.is_file() {
        return path.to_path_buf();
    }
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.part", std::process::id()))
}

/// Writes `bytes` to `path` whole: to [`temp_path`] first, renamed over `path` when
/// complete, so that a crash never leaves half a file (the temporary file is removed
/// when the write fails).
pub fn write_whole(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let tmp = temp_path(path);
    if tmp == path {
        return std::fs::write(path, bytes);
    }
    let r = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}
