//! The CSV writer: the state table to one sink, each log to its own. Numbers in `{}`
//! Display of the run's scalar (shortest round-trip), names bare, empty cells empty.

use super::{Cell, Observer, Tables};
use crate::error::RunError;
use std::io::{self, Write};
use structomat::Real;

/// A writer and its name for error messages (a path or `stdout`).
pub struct Sink<'a> {
    /// Where the lines go.
    pub w: &'a mut dyn Write,
    /// Its name in errors.
    pub target: String,
}

impl<'a> Sink<'a> {
    /// `w` named `target`.
    pub fn new(w: &'a mut dyn Write, target: impl Into<String>) -> Self {
        Sink {
            w,
            target: target.into(),
        }
    }

    fn err(&self, error: io::Error) -> RunError {
        RunError::write(&self.target, error)
    }

    fn line(&mut self, text: &str) -> Result<(), RunError> {
        writeln!(self.w, "{text}").map_err(|e| self.err(e))
    }

    fn row<T: Real>(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        write_row(self.w, row).map_err(|e| self.err(e))
    }
}

/// Writes one CSV row of `row`'s cells.
pub fn write_row<T: Real>(w: &mut dyn Write, row: &[Cell<'_, T>]) -> io::Result<()> {
    for (k, cell) in row.iter().enumerate() {
        if k > 0 {
            w.write_all(b",")?;
        }
        match cell {
            Cell::Num(v) => write!(w, "{v}")?,
            Cell::Int(n) => write!(w, "{n}")?,
            Cell::Text(s) => w.write_all(s.as_bytes())?,
            Cell::Empty => {}
        }
    }
    w.write_all(b"\n")
}

/// The CSV of a run: the state table, and the logs when given (a converter's events
/// and switches, next to a state CSV in a file).
pub struct CsvWriter<'a> {
    /// The state table's sink.
    pub state: Sink<'a>,
    /// The logs' sinks, in log order (none: the logs are not written).
    pub logs: Vec<Sink<'a>>,
}

impl<'a> CsvWriter<'a> {
    /// The state table to `state`, the logs to `logs`.
    pub fn new(state: Sink<'a>, logs: Vec<Sink<'a>>) -> Self {
        CsvWriter { state, logs }
    }
}

impl<T: Real> Observer<T> for CsvWriter<'_> {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        self.state.line(&tables.columns.join(","))?;
        for (sink, columns) in self.logs.iter_mut().zip(tables.logs) {
            sink.line(&columns.join(","))?;
        }
        Ok(())
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        self.state.row(row)
    }
    fn on_event(&mut self, log: usize, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        match self.logs.get_mut(log) {
            Some(sink) => sink.row(row),
            None => Ok(()),
        }
    }
    fn on_end(&mut self) -> Result<(), RunError> {
        self.state.w.flush().map_err(|e| self.state.err(e))?;
        for sink in &mut self.logs {
            sink.w.flush().map_err(|e| sink.err(e))?;
        }
        Ok(())
    }
}
