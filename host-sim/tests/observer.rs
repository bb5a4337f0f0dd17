//! The one observer interface: what a runner tells its observers, counted by an
//! observer of the test's own and checked against the run's summary and the step
//! arithmetic (a row at t = 0 and every N-th step; the converter also at its last
//! state), and the CSV writer driven through [`host_sim::run::simulate`] against the
//! bytes `host-sim run` writes.

use host_sim::output::csv::{CsvWriter, Sink};
use host_sim::output::{Cell, Observer, State, Tables};
use host_sim::run::{self, Report};
use host_sim::{RunError, RunOptions, ScenarioId};
use structomat::Real;

/// Counts every call, and checks that each row is as wide as its table.
#[derive(Default)]
struct Count {
    starts: usize,
    ends: usize,
    columns: usize,
    log_widths: Vec<usize>,
    mechanism_states: u64,
    converter_states: u64,
    rows: u64,
    events: [u64; 2],
    first_time: Option<f64>,
}

impl<T: Real> Observer<T> for Count {
    fn on_start(&mut self, tables: &Tables<'_>) -> Result<(), RunError> {
        self.starts += 1;
        self.columns = tables.columns.len();
        self.log_widths = tables.logs.iter().map(|l| l.len()).collect();
        Ok(())
    }
    fn on_state(&mut self, state: State<'_, T>) {
        match state {
            State::Mechanism(_) => self.mechanism_states += 1,
            State::Converter(_) => self.converter_states += 1,
        }
    }
    fn on_row(&mut self, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        assert_eq!(row.len(), self.columns, "row width");
        self.first_time.get_or_insert(row[0].to_f64());
        self.rows += 1;
        Ok(())
    }
    fn on_event(&mut self, log: usize, row: &[Cell<'_, T>]) -> Result<(), RunError> {
        assert_eq!(row.len(), self.log_widths[log], "log {log} width");
        self.events[log] += 1;
        Ok(())
    }
    fn on_end(&mut self) -> Result<(), RunError> {
        self.ends += 1;
        Ok(())
    }
}

#[test]
fn a_mechanism_run_tells_every_state_and_row() {
    let mut opts = RunOptions::new(ScenarioId::FiveBar);
    opts.h = Some(1e-3);
    opts.t_end = Some(0.01);
    opts.every = 3;
    let mut count = Count::default();
    let Report::Mechanism(s) = run::simulate::<f64>(&opts, &mut count).expect("runs") else {
        panic!("five-bar is a mechanism")
    };
    assert_eq!((count.starts, count.ends), (1, 1));
    // 10 steps: 11 states; rows at steps 0, 3, 6, 9 and the last state's, step 10.
    assert_eq!(s.steps, 10);
    assert_eq!((count.mechanism_states, count.converter_states), (11, 0));
    assert_eq!((count.rows, s.rows), (5, 5));
    assert_eq!(count.first_time, Some(0.0));
    assert!(count.log_widths.is_empty());
    assert_eq!(count.events, [0, 0]);
}

#[test]
fn a_converter_run_tells_every_state_row_and_log_line() {
    let mut opts = RunOptions::new(ScenarioId::CccS2);
    opts.t_end = Some(0.01);
    opts.every = 7;
    let mut count = Count::default();
    let Report::Converter(s) = run::simulate::<f64>(&opts, &mut count).expect("runs") else {
        panic!("ccc-s2 is the converter")
    };
    assert_eq!((count.starts, count.ends), (1, 1));
    // 100 steps of 1e-4 s: 101 states; rows at steps 0, 7, ..., 98 (15) and the last.
    assert_eq!(s.steps, 100);
    assert_eq!((count.converter_states, count.mechanism_states), (101, 0));
    assert_eq!((count.rows, s.rows), (16, 16));
    // Regression values: the converter CSV's 46 columns and the event and switch
    // logs' 8 and 6, as the headers are (host-sim/scenarios/README.md lists them).
    assert_eq!(count.columns, 46);
    assert_eq!(count.log_widths, [8, 6]);
    assert_eq!(count.events, [s.event_count(), s.switches]);
    // S2 starts with the start event (the start mode's choice).
    assert!(count.events[0] >= 1);
}

// The CSV writer as an observer of the pipeline writes the bytes `host-sim run` does,
// in f32 too (the numbers as the scalar prints them).
#[test]
fn the_csv_observer_writes_what_the_command_writes() {
    for (scenario, f32) in [("five-bar", false), ("five-bar", true), ("ccc-s2", false)] {
        let args = ["run", scenario, "--t-end", "0.005", "--quiet"];
        let args: Vec<&str> = if f32 {
            [&args[..], &["--f32"]].concat()
        } else {
            args.to_vec()
        };
        let (mut cli, mut err) = (Vec::new(), Vec::new());
        assert_eq!(host_sim::main_with(&args, &mut cli, &mut err), 0);
        let mut opts = RunOptions::new(ScenarioId::from_name(scenario).expect("built-in"));
        opts.t_end = Some(0.005);
        opts.f32 = f32;
        let mut csv = Vec::new();
        let mut w = CsvWriter::new(Sink::new(&mut csv, "memory"), Vec::new());
        if f32 {
            run::simulate::<f32>(&opts, &mut w).expect("runs");
        } else {
            run::simulate::<f64>(&opts, &mut w).expect("runs");
        }
        assert!(!csv.is_empty());
        assert_eq!(csv, cli, "{args:?}");
    }
}
