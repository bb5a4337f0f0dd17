//! The pieces of `structomat.design` (a design search whose generations are Dask
//! tasks): the next generation's designs from the scores so far ([`design_ask`]: the
//! optimizer replayed from its seed, host-sim's [`search::replay`]), one design's
//! score at every operating point with the GIL released ([`design_evaluate`], on any
//! worker), the best design of a finished search ([`design_best`]), and the same
//! search on host-sim's thread pool ([`design_search`], the oracle of the Python
//! tests). Every piece reads the design file itself, so that a task carries only the
//! file's path and one design.

use crate::errors::error;
use crate::run::with_signals;
use host_sim::jobs::design::evolution::Score;
use host_sim::jobs::design::file::{read_design, Design};
use host_sim::jobs::design::search::{self, replay};
use pyo3::prelude::*;
use std::path::Path;

/// A score as it crosses to Python and back: `(violation, objective)`.
pub type Wire = (f64, f64);

/// A best design: `(free values, violation, objective)`.
pub type Best = (Vec<f64>, f64, f64);

fn plan(path: &str) -> PyResult<Design> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| error(format!("cannot read design file {path}: {e}")))?;
    read_design(&text, Path::new(path)).map_err(|e| error(e.to_string()))
}

fn scores(history: Vec<Vec<Wire>>) -> Vec<Vec<Score>> {
    history
        .into_iter()
        .map(|g| {
            g.into_iter()
                .map(|(violation, objective)| Score {
                    violation,
                    objective,
                })
                .collect()
        })
        .collect()
}

/// The designs of the next generation of the design file `path`'s search after the
/// generations scored in `history`; `None` when the search is done.
#[pyfunction]
pub fn design_ask(path: &str, history: Vec<Vec<Wire>>) -> PyResult<Option<Vec<Vec<f64>>>> {
    let d = plan(path)?;
    let mut de = replay(&d, &scores(history));
    Ok((!de.done()).then(|| de.ask()))
}

/// The score of design `x` of the design file `path` at every operating point, the
/// GIL released.
#[pyfunction]
pub fn design_evaluate(py: Python<'_>, path: &str, x: Vec<f64>) -> PyResult<Wire> {
    let d = plan(path)?;
    if x.len() != d.free.len() {
        return Err(error(format!(
            "{path}: {} values for {} free parameters",
            x.len(),
            d.free.len()
        )));
    }
    let (s, signal) = with_signals(py, || {
        let evals: Vec<_> = d
            .points
            .iter()
            .map(|p| host_sim::jobs::design::evaluate::evaluate(&d, &x, p))
            .collect();
        search::score(&d, &evals)
    });
    if let Some(e) = signal {
        return Err(e);
    }
    Ok((s.violation, s.objective))
}

/// The best design of the search of `path` scored in `history`.
#[pyfunction]
pub fn design_best(path: &str, history: Vec<Vec<Wire>>) -> PyResult<Option<Best>> {
    let d = plan(path)?;
    let de = replay(&d, &scores(history));
    Ok(de.best().map(|(x, s)| (x, s.violation, s.objective)))
}

/// The whole search of `path` on host-sim's pool of `threads` threads, the GIL
/// released: its best design.
#[pyfunction]
pub fn design_search(py: Python<'_>, path: &str, threads: usize) -> PyResult<Option<Best>> {
    let d = plan(path)?;
    let o = py.detach(|| search::search(&d, threads, &mut |_, _| {}, &mut |_, _| {}));
    Ok(o.best_row()
        .map(|r| (r.x.clone(), r.score.violation, r.score.objective)))
}
