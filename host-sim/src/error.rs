//! The errors of a run and of a command line, and the process exit codes: the bottom
//! layer, which every other imports.

use std::fmt;
use std::io;
use structomat::StepError;

/// Exit code of a successful command.
pub const EXIT_OK: u8 = 0;
/// Exit code of a failed run (a step error, a file error, a setup error).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code of a bad command line.
pub const EXIT_USAGE: u8 = 2;

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
                kinetostatics: false,
                rows,
                error,
            } => {
                write!(
                    f,
                    "step {} failed ({rows} rows written): {error}",
                    steps + 1
                )
            }
            RunError::Step {
                steps,
                kinetostatics: true,
                rows,
                error,
            } => {
                write!(
                    f,
                    "kinetostatics after step {steps} failed ({rows} rows written): {error}"
                )
            }
            RunError::Integrator { steps, rows, error } => write!(
                f,
                "output interval {} failed ({rows} rows written): the adaptive integrator: {error}",
                steps + 1
            ),
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
