//! A run's keyword overrides (`structomat.run("ccc-s2", t_end=0.2, load=500)`), turned
//! into host-sim's [`RunArgs`] and checked by the same code as `host-sim run`'s command
//! line ([`RunArgs::options`]): the same defaults, the same checks, the same messages.
//! A number goes over as Python's `repr` (the shortest text that round-trips, as
//! Rust's parser reads it back to the same `float`).

use crate::errors::error;
use host_sim::options::args::RunArgs;
use host_sim::{Output, RunOptions};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt};

/// The keywords of a run and of a twin, as `host-sim run`'s options (`t_end` is
/// `--t-end`; `step` is `--h`'s alias).
pub const RUN_KEYWORDS: [&str; 10] = [
    "h",
    "step",
    "t_end",
    "every",
    "f32",
    "f64",
    "motor",
    "load",
    "ccw",
    "spread_events",
];

/// The text of a number keyword `name`: a Python `int` (or an object with `__index__`,
/// a numpy integer) as its `int`'s `repr`, anything else that converts to a float (a
/// `float`, a numpy float) as that `float`'s `repr` (the repr of a subclass may not be
/// a number: numpy 2 writes `np.float64(500.0)`); a `bool` or anything else is a
/// `TypeError` naming the keyword.
fn number(name: &str, v: &Bound<'_, PyAny>) -> PyResult<String> {
    let refused = || -> PyResult<String> {
        Err(PyTypeError::new_err(format!(
            "{name}: a number expected, got {}",
            v.get_type().name()?
        )))
    };
    if v.is_instance_of::<PyBool>() {
        return refused();
    }
    let py = v.py();
    if v.is_instance_of::<PyInt>() || v.hasattr("__index__")? {
        let int = py.get_type::<PyInt>().call1((v,))?;
        return Ok(int.repr()?.to_string());
    }
    match v.extract::<f64>() {
        Ok(x) => Ok(PyFloat::new(py, x).repr()?.to_string()),
        Err(_) => refused(),
    }
}

/// A flag keyword `name`: a Python `bool`.
fn flag(name: &str, v: &Bound<'_, PyAny>) -> PyResult<bool> {
    if !v.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: True or False expected, got {}",
            v.get_type().name()?
        )));
    }
    v.extract()
}

/// The options of a run of `source` (a built-in's name or a run file's path) with the
/// keyword `overrides`, as `host-sim run SOURCE --KEY VALUE ...` would take them; the
/// CSV is not written anywhere (the caller observes the run), no summary is printed.
/// Errors: an unknown keyword or a value of the wrong type is a `TypeError` naming it;
/// a value host-sim refuses, or a run file that does not read, is `structomat.Error`
/// with host-sim's message.
pub fn run_options(source: &str, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<RunOptions> {
    let mut args = RunArgs {
        scenario: source.to_string(),
        quiet: true,
        ..RunArgs::default()
    };
    if let Some(kw) = overrides {
        for (key, value) in kw.iter() {
            let key: String = key.extract()?;
            // `None` is the option not given.
            if value.is_none() {
                continue;
            }
            let text = |v: &Bound<'_, PyAny>| number(&key, v).map(Some);
            match key.as_str() {
                "h" | "step" => args.time.h = text(&value)?,
                "t_end" => args.time.t_end = text(&value)?,
                "every" => args.every = text(&value)?,
                "motor" => args.converter.motor = text(&value)?,
                "load" => args.converter.load = text(&value)?,
                "f32" => args.f32 = flag(&key, &value)?,
                "f64" => args.f64 = flag(&key, &value)?,
                "ccw" => args.converter.ccw = flag(&key, &value)?,
                "spread_events" => args.spread_events = flag(&key, &value)?,
                _ => {
                    return Err(PyTypeError::new_err(format!(
                        "unexpected keyword argument '{key}' (the keywords of a run: {})",
                        RUN_KEYWORDS.join(", ")
                    )))
                }
            }
        }
    }
    if args.f32 && args.f64 {
        return Err(error("f32 and f64: give one of them"));
    }
    let mut opts = args.options().map_err(|e| error(e.0))?;
    opts.out = Output::Stdout;
    Ok(opts)
}
