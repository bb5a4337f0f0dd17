//! The package's exceptions: `structomat.Error` (a `RuntimeError`) for every error of a
//! run, with host-sim's message, and its subclass `structomat.TwinError` for a step of
//! the twin that the core refused (the twin keeps its last good state).

use host_sim::RunError;
use pyo3::create_exception;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

create_exception!(
    structomat,
    Error,
    PyRuntimeError,
    "An error of structomat: bad options, a run file that does not parse or validate, \
     a run that cannot be set up or whose step failed. The message is host-sim's \
     (the core's for a failed step). A run that failed after its first row carries \
     what it computed up to there as `.result`."
);

create_exception!(
    structomat,
    TwinError,
    Error,
    "A step of structomat.Twin refused or failed (the core's message): the twin keeps \
     the state of its last good step and can be stepped again."
);

/// `structomat.Error` with host-sim's message of `e`.
pub fn run_error(e: &RunError) -> PyErr {
    Error::new_err(e.to_string())
}

/// `structomat.Error` with `message`.
pub fn error(message: impl Into<String>) -> PyErr {
    Error::new_err(message.into())
}
