//! What a run's output is made of: the [`Observer`] interface that a runner drives as
//! it steps, and the observers: the CSV writer ([`csv`]: the state table and the
//! converter's logs), the plots' table ([`plot::Table`]) and the animation's frames
//! ([`animate::Frames`]), gathered for `--plot` and `--animate` by
//! [`pictures::Recorder`].
//!
//! A runner calls [`Observer::on_start`] once with its tables' columns, then
//! [`Observer::on_state`] at t = 0 and after every step, [`Observer::on_row`] for every
//! row of the state table it writes, [`Observer::on_event`] for every line of a log
//! (the converter's mode changes and coordinate switches), and [`Observer::on_end`]
//! once when it stops (also when a step failed). A row is a slice of [`Cell`]s in the
//! run's scalar, so that every observer sees the same values and the CSV writes each
//! number as the scalar prints it.

pub mod animate;
pub mod csv;
pub mod pictures;
pub mod plot;

use crate::error::RunError;
use structomat::ccc::Twin;
use structomat::{Real, Simulation};

/// A cell of a row: a number in the run's scalar, a whole number, a name, or empty
/// (past a converter mode's DOF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell<'a, T> {
    /// A number (written in its shortest round-trip form).
    Num(T),
    /// A whole number (a mode's code).
    Int(u64),
    /// A name (a mode, a coordinate choice, an event kind).
    Text(&'a str),
    /// Nothing.
    Empty,
}

impl<T: Real> Cell<'_, T> {
    /// The cell as a number: a name or an empty cell is NaN.
    pub fn to_f64(&self) -> f64 {
        match self {
            Cell::Num(v) => v.to_f64(),
            Cell::Int(n) => *n as f64,
            Cell::Text(_) | Cell::Empty => f64::NAN,
        }
    }
}

/// A state a runner reached (at t = 0 and after every step).
#[derive(Clone, Copy)]
pub enum State<'a, T: Real> {
    /// A mechanism's simulation (its kinetostatics at this state done).
    Mechanism(&'a Simulation<T>),
    /// The converter's twin.
    Converter(&'a Twin<T>),
}

/// The columns of a run's tables: the state table's, and each log's (none for a
/// mechanism; the converter's events and switches).
#[derive(Clone, Copy, Debug)]
pub struct Tables<'a> {
    /// The state table's column names.
    pub columns: &'a [String],
    /// Each log's column names, in log order ([`Observer::on_event`]'s `log`).
    pub logs: &'a [&'a [&'a str]],
}

/// What a runner tells the run's outputs as it goes (see the module's docs for the
/// order). Every method has a default that ignores it.
pub trait Observer<T: Real> {
    /// The run starts: its tables' columns.
    fn on_start(&mut self, _tables: &Tables<'_>) -> Result<(), RunError> {
        Ok(())
    }
    /// A state, at t = 0 and after every step.
    fn on_state(&mut self, _state: State<'_, T>) {}
    /// A row of the state table.
    fn on_row(&mut self, _row: &[Cell<'_, T>]) -> Result<(), RunError> {
        Ok(())
    }
    /// A line of log `log` (an index into [`Tables::logs`]).
    fn on_event(&mut self, _log: usize, _row: &[Cell<'_, T>]) -> Result<(), RunError> {
        Ok(())
    }
    /// The run stopped (at its end, or at a failed step): flush.
    fn on_end(&mut self) -> Result<(), RunError> {
        Ok(())
    }
}

/// Several observers, told in order; the first error stops the telling.
#[derive(Default)]
pub struct Observers<'a, T: Real>(pub Vec<&'a mut dyn Observer<T>>);

impl<T: Real> Observer<T> for Observers<'_, T> {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        self.0.iter_mut().try_for_each(|o| o.on_start(tables))
    }
    fn on_state(&mut self, state: State<'_, T>) {
        for o in self.0.iter_mut() {
            o.on_state(state);
        }
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        self.0.iter_mut().try_for_each(|o| o.on_row(row))
    }
    fn on_event(&mut self, log: usize, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        self.0.iter_mut().try_for_each(|o| o.on_event(log, row))
    }
    fn on_end(&mut self) -> Result<(), RunError> {
        self.0.iter_mut().try_for_each(|o| o.on_end())
    }
}
