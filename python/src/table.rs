//! The observer of a Python run: it gathers the state table and each log column by
//! column, every number as the `f64` that host-sim's CSV text of it parses to, so that
//! `structomat.run(...).columns[name]` equals the CSV's column read back, bit for bit.
//! In `f64` that is the value itself (the CSV writes the shortest text that
//! round-trips); an `f32` run's CSV writes the `f32`'s shortest text, which as an
//! `f64` is not the `f32` widened, so it is formatted and parsed as the CSV's reader
//! would.

use host_sim::output::{Cell, Observer, Tables};
use host_sim::RunError;
use structomat::Real;

/// One column of a table.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// Numbers (an empty cell is NaN, a whole number its `f64`).
    Num(Vec<f64>),
    /// Names (a mode, a coordinate choice, an event kind), each distinct name kept once:
    /// row `k`'s name is `names[codes[k]]`. A mode's name repeats on every row, so a row
    /// costs a comparison with the row before it, not a `String` (made during the run,
    /// freed after it: outside its wall, the larger part of Python's cost beyond the run).
    Text(Names),
}

/// A column of names, each distinct one stored once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Names {
    /// The distinct names, in order of first appearance.
    pub names: Vec<String>,
    /// Each row's index into `names`.
    pub codes: Vec<u32>,
}

impl Names {
    /// Appends `s`: the previous row's code when the name repeats, else the index of its
    /// first appearance (a column holds a handful of names: a linear search).
    fn push(&mut self, s: &str) {
        let code = match self.codes.last() {
            Some(&c) if self.names.get(c as usize).is_some_and(|n| n == s) => c,
            _ => match self.names.iter().position(|n| n == s) {
                Some(i) => i as u32,
                None => {
                    self.names.push(s.to_string());
                    (self.names.len() - 1) as u32
                }
            },
        };
        self.codes.push(code);
    }
}

/// A table: its column names and columns, in CSV order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// The header.
    pub names: Vec<String>,
    /// The columns (empty before the first row: their kinds come from it).
    pub columns: Vec<Column>,
    /// Rows gathered.
    pub rows: usize,
}

/// The `f64` that the CSV's text of `v` parses to (see the module's docs).
pub fn as_csv<T: Real>(v: T) -> f64 {
    if core::mem::size_of::<T>() == 8 {
        v.to_f64()
    } else {
        // The shortest round-trip text of an f32 always parses (NaN, inf included).
        format!("{v}").parse().unwrap_or(f64::NAN)
    }
}

impl Table {
    fn new(names: Vec<String>) -> Self {
        Table {
            names,
            columns: Vec::new(),
            rows: 0,
        }
    }

    /// Appends `row`: its cells' kinds fix the columns' kinds at the first row; a later
    /// name in a number column (or a number in a name column) is an error naming the
    /// column, never a silent NaN.
    fn push<T: Real>(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        if row.len() != self.names.len() {
            return Err(RunError::Setup(format!(
                "a row of {} cells in a table of {} columns",
                row.len(),
                self.names.len()
            )));
        }
        if self.rows == 0 {
            self.columns = row
                .iter()
                .map(|c| match c {
                    Cell::Text(_) => Column::Text(Names::default()),
                    _ => Column::Num(Vec::new()),
                })
                .collect();
        }
        for ((cell, col), name) in row.iter().zip(&mut self.columns).zip(&self.names) {
            match (cell, col) {
                (Cell::Num(v), Column::Num(c)) => c.push(as_csv(*v)),
                (Cell::Int(n), Column::Num(c)) => c.push(*n as f64),
                (Cell::Empty, Column::Num(c)) => c.push(f64::NAN),
                (Cell::Text(s), Column::Text(c)) => c.push(s),
                (Cell::Empty, Column::Text(c)) => c.push(""),
                _ => {
                    return Err(RunError::Setup(format!(
                        "column {name}: a name and a number in one column"
                    )))
                }
            }
        }
        self.rows += 1;
        Ok(())
    }
}

/// A run's tables, gathered: the state table and the logs (a converter's events and
/// switches; none for a mechanism).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gathered {
    /// The state table.
    pub state: Table,
    /// The logs, in log order.
    pub logs: Vec<Table>,
}

impl<T: Real> Observer<T> for Gathered {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        self.state = Table::new(tables.columns.to_vec());
        self.logs = tables
            .logs
            .iter()
            .map(|cols| Table::new(cols.iter().map(|c| c.to_string()).collect()))
            .collect();
        Ok(())
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        self.state.push(row)
    }
    fn on_event(&mut self, log: usize, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        match self.logs.get_mut(log) {
            Some(t) => t.push(row),
            None => Err(RunError::Setup(format!("no log {log}"))),
        }
    }
}
