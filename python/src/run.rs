//! `structomat._core.run`: a run of host-sim's one pipeline ([`host_sim::run::simulate`],
//! the runner `host-sim run` drives) observed by [`Gathered`] instead of the CSV
//! writer, with the GIL released and Ctrl-C answered; and `scenarios`, the built-ins.

use crate::errors::run_error;
use crate::options::run_options;
use crate::table::{Column, Gathered, Table};
use host_sim::ccc::{CccSummary, End};
use host_sim::run::{interrupt, simulate, Report};
use host_sim::{RunError, RunOptions, ScenarioId, Summary};
use numpy::PyArray1;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

/// How often a run under way asks the interpreter for its signals (Ctrl-C): a
/// KeyboardInterrupt arrives within this plus one step and the last row.
pub const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// Runs `f` with the GIL released, polling the interpreter's signals every
/// [`SIGNAL_POLL`] through host-sim's interrupt hook (this thread's): a signal
/// handler's exception (KeyboardInterrupt) makes the runners stop (a run after its
/// present step, a sweep's variants not started) and is returned beside `f`'s value.
pub fn with_signals<R: Send>(py: Python<'_>, f: impl FnOnce() -> R + Send) -> (R, Option<PyErr>) {
    py.detach(|| {
        let caught: Rc<RefCell<Option<PyErr>>> = Rc::new(RefCell::new(None));
        let seen = Rc::clone(&caught);
        let mut last = Instant::now();
        let hook = move || {
            if seen.borrow().is_some() {
                return true;
            }
            if last.elapsed() < SIGNAL_POLL {
                return false;
            }
            last = Instant::now();
            match Python::attach(|py| py.check_signals()) {
                Ok(()) => false,
                Err(e) => {
                    *seen.borrow_mut() = Some(e);
                    true
                }
            }
        };
        let out = interrupt::with_hook(hook, f);
        let signal = caught.borrow_mut().take();
        (out, signal)
    })
}

/// Runs `opts` in its precision with the GIL released and Ctrl-C answered
/// ([`with_signals`]): the run stops after its present step and the signal's exception
/// is returned as the third value.
pub fn observed(
    py: Python<'_>,
    opts: &RunOptions,
) -> (Gathered, Result<Report, RunError>, Option<PyErr>) {
    let ((gathered, report), signal) = with_signals(py, || {
        let mut gathered = Gathered::default();
        let report = if opts.f32 {
            simulate::<f32>(opts, &mut gathered)
        } else {
            simulate::<f64>(opts, &mut gathered)
        };
        (gathered, report)
    });
    (gathered, report, signal)
}

/// Runs `source` (a built-in scenario's name or a run file's path) with the keyword
/// `overrides` of `host-sim run`'s options, and returns `(columns, events, switches,
/// summary, failure)`: the state table and the converter's two logs (dicts of column
/// name to a float64 array, or a list of str for a column of names; the logs are
/// empty dicts for a mechanism), the summary's figures (a dict), and `None` or the
/// message of a step that failed after the run began (the tables hold the run up to
/// there; `host-sim run` exits 1 then). Errors before the first row raise
/// `structomat.Error`; Ctrl-C raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (source, overrides=None))]
pub fn run<'py>(
    py: Python<'py>,
    source: &str,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let opts = run_options(source, overrides)?;
    let (gathered, report, signal) = observed(py, &opts);
    if let Some(e) = signal {
        return Err(e);
    }
    let (summary, failure) = match &report {
        Ok(Report::Converter(s)) => (converter_summary(py, s)?, converter_failure(s)),
        Ok(Report::Mechanism(s)) => (mechanism_summary(py, s)?, None),
        // A step failed after rows were written: they are the result up to there.
        Err(e @ (RunError::Step { .. } | RunError::Integrator { .. })) => {
            let d = PyDict::new(py);
            d.set_item("scenario", opts.scenario.name())?;
            d.set_item("end", "failed")?;
            d.set_item("error", e.to_string())?;
            d.set_item("exit_code", e.exit_code())?;
            d.set_item("rows", gathered.state.rows)?;
            (d, Some(e.to_string()))
        }
        Err(e) => return Err(run_error(e)),
    };
    let Gathered { state, logs } = gathered;
    let mut logs = logs.into_iter();
    let (events, switches) = match (logs.next(), logs.next()) {
        (Some(e), Some(s)) => (table_dict(py, e)?, table_dict(py, s)?),
        _ => (PyDict::new(py), PyDict::new(py)),
    };
    PyTuple::new(
        py,
        [
            table_dict(py, state)?.into_any(),
            events.into_any(),
            switches.into_any(),
            summary.into_any(),
            failure.into_pyobject(py)?.into_any(),
        ],
    )
}

/// The built-in scenarios: `(name, description)` pairs, as `host-sim list` lists them.
#[pyfunction]
pub fn scenarios() -> Vec<(&'static str, &'static str)> {
    ScenarioId::ALL
        .iter()
        .map(|s| (s.name(), s.description()))
        .collect()
}

/// A table as a dict of column name to a float64 array (a list of str for names),
/// its number columns moved into numpy without a copy, each distinct name made a
/// Python str once and shared by its rows.
pub fn table_dict<'py>(py: Python<'py>, t: Table) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let mut columns = t.columns.into_iter();
    for name in &t.names {
        match columns.next() {
            Some(Column::Num(v)) => d.set_item(name, PyArray1::from_vec(py, v))?,
            Some(Column::Text(c)) => {
                let made: Vec<Bound<'py, PyString>> =
                    c.names.iter().map(|s| PyString::new(py, s)).collect();
                let rows = c
                    .codes
                    .iter()
                    .map(|&k| made.get(k as usize).cloned())
                    .collect::<Option<Vec<_>>>()
                    .ok_or_else(|| {
                        PyRuntimeError::new_err(format!(
                            "column {name}: a name's code past its names"
                        ))
                    })?;
                d.set_item(name, PyList::new(py, rows)?)?
            }
            None => d.set_item(name, PyArray1::<f64>::zeros(py, 0, false))?,
        }
    }
    Ok(d)
}

/// The message of a converter run that ended at a failed step it did not expect
/// (`host-sim run` exits 1 then); `None` otherwise.
fn converter_failure(s: &CccSummary) -> Option<String> {
    match &s.end {
        End::Stopped {
            error,
            expected: false,
        } => Some(format!(
            "{}: step {} failed: {error}",
            s.scenario,
            s.steps + 1
        )),
        _ => None,
    }
}

/// A converter run's summary as a dict (the figures of `host-sim run`'s summary; its
/// text as `text`).
fn converter_summary<'py>(py: Python<'py>, s: &CccSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("kind", "converter")?;
    d.set_item("scenario", &s.scenario)?;
    d.set_item("settings", s.settings.to_string())?;
    d.set_item("precision", s.precision)?;
    d.set_item("h", s.h)?;
    d.set_item("t_end", s.t_end)?;
    d.set_item("steps", s.steps)?;
    d.set_item("time", s.time)?;
    d.set_item("rows", s.rows)?;
    let events = PyDict::new(py);
    for (name, n) in &s.events {
        events.set_item(name, n)?;
    }
    d.set_item("events", events)?;
    d.set_item("event_count", s.event_count())?;
    d.set_item("first_breakaway", s.first_breakaway)?;
    d.set_item("switches", s.switches)?;
    d.set_item("impacts", s.impacts)?;
    let a = &s.audit;
    let audit = PyDict::new(py);
    audit.set_item("motor_work", a.motor_work)?;
    audit.set_item("load_work", a.load_work)?;
    audit.set_item("impact_loss", a.impact_loss)?;
    audit.set_item("kinetic", a.kinetic)?;
    audit.set_item("potential", a.potential)?;
    audit.set_item("initial", a.initial)?;
    audit.set_item("residual", a.residual())?;
    d.set_item("audit", audit)?;
    d.set_item("relative_residual", s.relative_residual())?;
    d.set_item("mode", s.mode.name())?;
    d.set_item("coords", s.coords.name())?;
    d.set_item("shaft_angle", s.shaft_angle)?;
    // The twin's largest lag behind the clock, s, if it spreads its events; else None.
    d.set_item("lag", s.lag)?;
    let (end, error) = match &s.end {
        End::Completed => ("completed", None),
        End::Stopped {
            error,
            expected: true,
        } => ("singularity", Some(error.to_string())),
        End::Stopped { error, .. } => ("failed", Some(error.to_string())),
        End::Interrupted => ("interrupted", None),
    };
    d.set_item("end", end)?;
    d.set_item("error", error)?;
    d.set_item("exit_code", s.exit_code())?;
    times(&d, s.wall, s.step_wall, s.steps)?;
    d.set_item("text", s.to_string())?;
    Ok(d)
}

/// A mechanism run's summary as a dict.
fn mechanism_summary<'py>(py: Python<'py>, s: &Summary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("kind", "mechanism")?;
    d.set_item("scenario", &s.scenario)?;
    d.set_item("formula", &s.formula)?;
    d.set_item("precision", s.precision)?;
    d.set_item("h", s.h)?;
    d.set_item("steps", s.steps)?;
    d.set_item("time", s.time)?;
    d.set_item("rows", s.rows)?;
    d.set_item("q", &s.q)?;
    d.set_item("qd", &s.qd)?;
    d.set_item("energy_start", s.energy_start)?;
    d.set_item("energy_end", s.energy_end)?;
    let b = &s.balance;
    let balance = PyDict::new(py);
    balance.set_item("motor_work", b.motor_work)?;
    balance.set_item("load_work", b.load_work)?;
    balance.set_item("residual", b.residual)?;
    balance.set_item("worst", b.worst)?;
    balance.set_item("redone", b.redone)?;
    balance.set_item("substeps", b.substeps)?;
    balance.set_item("redone_energy", b.redone_energy)?;
    balance.set_item("redone_error", b.redone_error)?;
    balance.set_item("inexact", b.inexact)?;
    balance.set_item("worst_error", b.worst_error)?;
    balance.set_item("first_inexact", b.first_inexact)?;
    d.set_item("balance", balance)?;
    d.set_item(
        "mean_speed",
        s.mean_speed
            .as_ref()
            .map(|m| (m.coord, m.from, m.to, m.value)),
    )?;
    d.set_item(
        "max_reaction",
        s.max_reaction
            .as_ref()
            .map(|m| (m.joint.clone(), m.value, m.time)),
    )?;
    d.set_item(
        "singular",
        s.singular.as_ref().map(|e| (e.time, e.cause.clone())),
    )?;
    d.set_item("warnings", &s.warnings)?;
    let switches: Vec<_> = s
        .switches
        .iter()
        .map(|w| {
            (
                w.time,
                w.from.clone(),
                w.to.clone(),
                w.group.clone(),
                w.conditioning[0],
                w.conditioning[1],
            )
        })
        .collect();
    d.set_item("switches", switches)?;
    d.set_item("adaptive", s.adaptive)?;
    let end = match (s.interrupted, &s.singular) {
        (true, _) => "interrupted",
        (false, Some(_)) => "singularity",
        (false, None) => "completed",
    };
    d.set_item("end", end)?;
    d.set_item("exit_code", Report::Mechanism(s.clone()).exit_code())?;
    times(&d, s.wall, s.step_wall, s.steps)?;
    d.set_item("text", s.to_string())?;
    Ok(d)
}

/// The wall times of a run of `steps` steps: `wall` and `step_wall` (s), `ns_per_step`
/// (inside the core's step).
fn times(d: &Bound<'_, PyDict>, wall: Duration, step_wall: Duration, steps: u64) -> PyResult<()> {
    d.set_item("wall", wall.as_secs_f64())?;
    d.set_item("step_wall", step_wall.as_secs_f64())?;
    d.set_item(
        "ns_per_step",
        step_wall.as_secs_f64() * 1e9 / steps.max(1) as f64,
    )
}
