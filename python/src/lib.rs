//! # structomat-python
//!
//! The native part of the Python package `structomat` (`structomat._core`): host-sim's
//! runs ([`run`]: the one run pipeline of `host-sim run`, its CSV's values gathered
//! into numpy arrays instead of text) and the converter's twin stepped from Python
//! ([`twin`]). The pure-Python part (`python/structomat/__init__.py`) wraps them in
//! the package's classes; its type stubs are `__init__.pyi`.
//!
//! ## Layers
//!
//! 0. [`errors`]: the package's exceptions and the conversion of host-sim's errors.
//! 1. [`options`]: a run's keyword overrides, parsed as `host-sim run` parses its
//!    options.
//! 2. [`table`]: the observer that gathers a run's tables (the state table and the
//!    converter's logs) column by column.
//! 3. [`run`], [`twin`], [`sweep`] and [`design`]: the module's functions and classes.

pub mod design;
pub mod errors;
pub mod options;
pub mod run;
pub mod sweep;
pub mod table;
pub mod twin;

use pyo3::prelude::*;

/// The module `structomat._core`.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("TwinError", py.get_type::<errors::TwinError>())?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_plan, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_run, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_write, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_ask, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_best, m)?)?;
    m.add_function(wrap_pyfunction!(design::design_search, m)?)?;
    m.add_class::<twin::Twin>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
