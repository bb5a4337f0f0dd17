//! The pieces of `structomat.sweep` (a sweep file's variants as Dask tasks): reading
//! and checking the sweep file as `host-sim sweep` does ([`sweep_plan`]), running a
//! batch of its variants with the GIL released ([`sweep_run`]: host-sim's
//! [`sweep::run_job`], on any worker), and writing `sweep.csv` and the heat-maps from
//! the gathered outcomes in grid order ([`sweep_write`]: host-sim's
//! [`sweep::write_outputs`]). Every piece reads the sweep file itself, so that a task
//! carries only the file's path and its variants' numbers.

use crate::errors::error;
use crate::run::with_signals;
use host_sim::sweep::{self, Job, Outcome, Sweep, ENDS};
use pyo3::prelude::*;
use std::path::Path;

/// An outcome as it crosses to Python and back: `(exit, end, steps, metrics,
/// message)`.
pub type Wire = (u8, String, Option<u64>, Vec<Option<f64>>, Option<String>);

/// The sweep file `path` read and checked, and its variants ready to run; errors as
/// `host-sim sweep` reports them (every bad variant, one a line).
fn plan(path: &str) -> PyResult<(Sweep, Vec<Job>)> {
    let file = Path::new(path);
    let text = std::fs::read_to_string(file)
        .map_err(|e| error(format!("cannot read sweep file {path}: {e}")))?;
    let dir = file.parent().unwrap_or(Path::new("."));
    let s = sweep::parse_sweep(&text, path, |b| sweep::load_base(b, dir))
        .map_err(|e| error(e.to_string()))?;
    let jobs = sweep::prepare(&s).map_err(|bad| error(bad.join("\n")))?;
    Ok((s, jobs))
}

/// The number of variants of the sweep file `path` (all checked).
#[pyfunction]
pub fn sweep_plan(path: &str) -> PyResult<usize> {
    plan(path).map(|(_, jobs)| jobs.len())
}

/// Runs the variants `which` (grid-order numbers) of the sweep file `path`, in order,
/// with the GIL released; their outcomes as [`Wire`] tuples. A variant whose run fails
/// is an outcome saying how it ended, never an exception.
#[pyfunction]
pub fn sweep_run(py: Python<'_>, path: &str, which: Vec<usize>) -> PyResult<Vec<Wire>> {
    let (_, jobs) = plan(path)?;
    let total = jobs.len();
    if let Some(k) = which.iter().find(|&&k| k >= total) {
        return Err(error(format!("{path}: no variant {k} (it has {total})")));
    }
    let (outcomes, signal) = with_signals(py, || {
        which
            .iter()
            .map(|&k| {
                let o = sweep::run_job(&jobs[k], k, total, None);
                (
                    o.exit,
                    o.end.to_string(),
                    o.steps,
                    o.metrics.to_vec(),
                    o.message,
                )
            })
            .collect()
    });
    // Ctrl-C: the variant under way stopped after its step, the rest not run; the
    // batch's outcomes are not a sweep's and are dropped.
    match signal {
        Some(e) => Err(e),
        None => Ok(outcomes),
    }
}

/// Writes `sweep.csv` and the heat-maps of the sweep file `path` into `out_dir`
/// (created if missing) from `outcomes`, every variant's in grid order; returns the
/// table's path and the heat-maps' SVG paths.
#[pyfunction]
pub fn sweep_write(
    path: &str,
    out_dir: &str,
    outcomes: Vec<Wire>,
) -> PyResult<(String, Vec<String>)> {
    let (s, jobs) = plan(path)?;
    if outcomes.len() != jobs.len() {
        return Err(error(format!(
            "{path}: {} outcomes for {} variants",
            outcomes.len(),
            jobs.len()
        )));
    }
    let mut runs = Vec::with_capacity(outcomes.len());
    for (k, (exit, end, steps, metrics, message)) in outcomes.into_iter().enumerate() {
        let end = ENDS.iter().find(|e| **e == end).ok_or_else(|| {
            error(format!(
                "variant {k}: no end '{end}' (one of {})",
                ENDS.join(", ")
            ))
        })?;
        let mut o = Outcome {
            exit,
            end,
            steps,
            message,
            ..Outcome::default()
        };
        if metrics.len() != o.metrics.len() {
            return Err(error(format!(
                "variant {k}: {} metrics, {} expected",
                metrics.len(),
                o.metrics.len()
            )));
        }
        o.metrics.copy_from_slice(&metrics);
        runs.push(o);
    }
    let out = Path::new(out_dir);
    std::fs::create_dir_all(out).map_err(|e| error(format!("cannot create {out_dir}: {e}")))?;
    let variants: Vec<Vec<usize>> = jobs.into_iter().map(|j| j.idx).collect();
    let (table, pictures) = sweep::write_outputs(out, &s, &variants, &runs).map_err(error)?;
    Ok((
        table.display().to_string(),
        pictures.iter().map(|p| p.display().to_string()).collect(),
    ))
}
