//! Bench logs: what a test bench recorded from a converter built to SPEC 3's drawing
//! (`../shared/bench/README.md`), read and validated for `host-sim replay`.
//!
//! A **bench log** is a CSV with the columns [`LOG_COLUMNS`] (others are ignored),
//! sampled at a uniform rate from t = 0: the motor torque from its current sensor
//! (N·m, CCW positive), the brake's set point T_r (N·m), and two encoders of
//! [`COUNTS_PER_TURN`] counts a turn: the crank's, `floor(θ1 / (2π/4096))` of SPEC's
//! crank angle q1 (CCW from +x, not wrapped), and the output shaft's, positive in the
//! drive direction, 0 at t = 0. A **clutch log** is a CSV with the columns
//! [`CLUTCH_COLUMNS`]: each change of the diode's state, time-stamped, with the event
//! that caused it and the modes before and after, in host-sim's names.
//!
//! Every error names the file, the line (from 1, the header's is 1) and the column.

use super::runfile::MAX_CONVERTER_LOAD;
use crate::error::Sci;
use std::fmt;
use std::path::Path;
use structomat::ccc::{EventKind, Mode};

/// The columns of a bench log, in the README's order.
pub const LOG_COLUMNS: [&str; 5] = [
    "t",
    "motor_torque",
    "load_torque",
    "crank_counts",
    "shaft_counts",
];

/// The columns of a clutch log.
pub const CLUTCH_COLUMNS: [&str; 4] = ["t", "event", "from", "to"];

/// Encoder counts a turn, of the crank's and of the shaft's encoder.
pub const COUNTS_PER_TURN: u32 = 4096;

/// The sample times' tolerated jitter, a fraction of the sample period: 1 % (10 µs at
/// 1 kHz, ten times the 1 µs the logs print); a missing sample (a jump of 2 periods) or
/// a clock that drifts by more is refused.
pub const JITTER: f64 = 0.01;

/// The most samples a log may have (the most steps a run may take).
pub const MAX_SAMPLES: usize = 100_000_000;

/// The event names a clutch log may give: the changes of the diode's state, the twin's
/// event kinds but the start.
pub const CLUTCH_EVENTS: [EventKind; 7] = [
    EventKind::Inputs,
    EventKind::Catch(6),
    EventKind::Catch(8),
    EventKind::Release(6),
    EventKind::Release(8),
    EventKind::Breakaway,
    EventKind::ShaftStop,
];

/// The encoder law of the bench's encoders: the count of an angle `theta`, rad, at
/// [`COUNTS_PER_TURN`] counts a turn, `floor(theta / (2π/4096))`.
pub fn encoder_counts(theta: f64) -> i64 {
    let resolution = std::f64::consts::TAU / f64::from(COUNTS_PER_TURN);
    // `as` saturates: an angle of more than 2^63 counts is no machine's.
    (theta / resolution).floor() as i64
}

/// A bad bench or clutch log: `FILE: line L, column C: MESSAGE` (line and column when
/// known).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogError {
    /// The file's path, or the name the caller gave its text.
    pub origin: String,
    /// The line, from 1 (the header's).
    pub line: Option<u64>,
    /// The column's name.
    pub column: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for LogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.origin)?;
        if let Some(l) = self.line {
            write!(f, ": line {l}")?;
        }
        if let Some(c) = &self.column {
            let sep = if self.line.is_some() { "," } else { ":" };
            write!(f, "{sep} column {c}")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for LogError {}

/// The largest count a log may hold, either sense: 2^53, the last whole number every
/// float holds exactly.
pub const MAX_COUNTS: u64 = 1 << 53;

/// A bench log, validated: at least two samples, t strictly increasing and uniform from
/// 0, every value finite, the counts whole numbers within ±[`MAX_COUNTS`], the shaft's
/// 0 at the first sample, 0 ≤ the load < [`MAX_CONVERTER_LOAD`].
#[derive(Clone, Debug, PartialEq)]
pub struct BenchLog {
    /// The file's path (or the name given to its text).
    pub origin: String,
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Motor torque on the crank, N·m, CCW positive.
    pub motor: Vec<f64>,
    /// The brake's set point T_r, N·m.
    pub load: Vec<f64>,
    /// Crank encoder, counts.
    pub crank: Vec<i64>,
    /// Shaft encoder, counts, positive in the drive direction.
    pub shaft: Vec<i64>,
}

impl BenchLog {
    /// Samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No samples (never, for a validated log).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The sample period, s: the mean over the log, `(t_last - t_0) / (n - 1)`.
    pub fn period(&self) -> f64 {
        match (self.t.first(), self.t.last()) {
            (Some(a), Some(b)) if self.t.len() > 1 => (b - a) / (self.t.len() - 1) as f64,
            _ => f64::NAN,
        }
    }

    /// The last sample's time, s.
    pub fn duration(&self) -> f64 {
        self.t.last().copied().unwrap_or(0.0)
    }

    /// The log's first `n` samples (all of them if it has fewer).
    pub fn head(&self, n: usize) -> BenchLog {
        let n = n.min(self.len());
        BenchLog {
            origin: self.origin.clone(),
            t: self.t[..n].to_vec(),
            motor: self.motor[..n].to_vec(),
            load: self.load[..n].to_vec(),
            crank: self.crank[..n].to_vec(),
            shaft: self.shaft[..n].to_vec(),
        }
    }

    /// Reads and validates the bench log at `path`.
    pub fn read(path: &Path) -> Result<BenchLog, LogError> {
        read_with(path, BenchLog::parse)
    }

    /// Parses and validates the text of a bench log named `origin`.
    pub fn parse(text: &str, origin: &str) -> Result<BenchLog, LogError> {
        let table = Cells::parse(text, origin, &LOG_COLUMNS)?;
        let mut log = BenchLog {
            origin: origin.to_string(),
            t: Vec::new(),
            motor: Vec::new(),
            load: Vec::new(),
            crank: Vec::new(),
            shaft: Vec::new(),
        };
        for (line, row) in &table.rows {
            let at = |k: usize| Cell {
                origin,
                line: *line,
                column: LOG_COLUMNS[k],
                text: row[k].as_str(),
            };
            log.t.push(at(0).number()?);
            log.motor.push(at(1).number()?);
            let load = at(2).number()?;
            if load < 0.0 {
                return Err(at(2).err(format!(
                    "{load} N·m is negative (the brake's set point T_r >= 0)"
                )));
            }
            if load >= MAX_CONVERTER_LOAD {
                return Err(at(2).err(format!(
                    "{} N·m is too large: the twin's clutch tolerances lose their meaning \
                     from {} N·m",
                    Sci(load),
                    Sci(MAX_CONVERTER_LOAD)
                )));
            }
            log.load.push(load);
            log.crank.push(at(3).count()?);
            let shaft = at(4).count()?;
            // The twin's shaft starts at 0: the log's must (a counter's offset would
            // read as a shaft residual of that many counts, and identify would fit it).
            if log.shaft.is_empty() && shaft != 0 {
                return Err(at(4).err(format!(
                    "{shaft} at the first sample: the shaft's count is 0 at t = 0 (subtract the counter's start from the column)"
                )));
            }
            log.shaft.push(shaft);
        }
        check_times(&log.t, &table.rows, origin)?;
        Ok(log)
    }
}

/// The times `t` of the rows `rows` (their lines): at least two, strictly increasing,
/// every interval within [`JITTER`] of the median one, t_k within [`JITTER`] periods of
/// k·h from t_0 = 0 (h the mean period).
fn check_times(t: &[f64], rows: &[(u64, Vec<String>)], origin: &str) -> Result<(), LogError> {
    let err = |k: usize, message: String| LogError {
        origin: origin.to_string(),
        line: rows.get(k).map(|r| r.0),
        column: Some("t".to_string()),
        message,
    };
    if t.len() < 2 {
        return Err(LogError {
            origin: origin.to_string(),
            line: None,
            column: None,
            message: format!(
                "{} samples: a log needs two at least (its sample period is the twin's step)",
                t.len()
            ),
        });
    }
    for k in 1..t.len() {
        if t[k] <= t[k - 1] {
            return Err(err(
                k,
                format!(
                    "t = {} s is not after the previous sample's {} s (t must increase)",
                    t[k],
                    t[k - 1]
                ),
            ));
        }
    }
    let mut dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    let median = dt[dt.len() / 2];
    for k in 1..t.len() {
        let d = t[k] - t[k - 1];
        if (d - median).abs() > JITTER * median {
            return Err(err(
                k,
                format!(
                    "t = {} s is {} s after the previous sample where the log's period is {} s \
                     (a missing sample or a non-uniform t: a log must be sampled uniformly)",
                    t[k], d, median
                ),
            ));
        }
    }
    let h = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    if t[0].abs() > JITTER * h {
        return Err(err(
            0,
            format!(
                "the log starts at t = {} s, not 0 (the twin starts from its run file's \
                 initial state at t = 0)",
                t[0]
            ),
        ));
    }
    for (k, tk) in t.iter().enumerate() {
        if (tk - k as f64 * h).abs() > JITTER * h {
            return Err(err(
                k,
                format!(
                    "t = {tk} s is off sample {k}'s time {} s by more than {JITTER} of the \
                     period {h} s (a drifting clock: a log must be sampled uniformly)",
                    k as f64 * h
                ),
            ));
        }
    }
    Ok(())
}

/// One event of a clutch log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClutchEvent {
    /// Time, s.
    pub time: f64,
    /// What fired.
    pub kind: EventKind,
    /// The mode before.
    pub from: Mode,
    /// The mode after.
    pub to: Mode,
}

/// A clutch log, validated: times finite, ≥ 0 and in order; known event and mode
/// names.
#[derive(Clone, Debug, PartialEq)]
pub struct ClutchLog {
    /// The file's path (or the name given to its text).
    pub origin: String,
    /// The events in the log's order.
    pub events: Vec<ClutchEvent>,
}

impl ClutchLog {
    /// The events up to time `t` (s), inclusive.
    pub fn until(&self, t: f64) -> ClutchLog {
        ClutchLog {
            origin: self.origin.clone(),
            events: self
                .events
                .iter()
                .filter(|e| e.time <= t)
                .copied()
                .collect(),
        }
    }

    /// Reads and validates the clutch log at `path`.
    pub fn read(path: &Path) -> Result<ClutchLog, LogError> {
        read_with(path, ClutchLog::parse)
    }

    /// Parses and validates the text of a clutch log named `origin`.
    pub fn parse(text: &str, origin: &str) -> Result<ClutchLog, LogError> {
        let table = Cells::parse(text, origin, &CLUTCH_COLUMNS)?;
        let mut events: Vec<ClutchEvent> = Vec::new();
        for (line, row) in &table.rows {
            let at = |k: usize| Cell {
                origin,
                line: *line,
                column: CLUTCH_COLUMNS[k],
                text: row[k].as_str(),
            };
            let time = at(0).number()?;
            if time < 0.0 {
                return Err(at(0).err(format!("t = {time} s is before the log's start, 0")));
            }
            if let Some(last) = events.last() {
                if time < last.time {
                    return Err(at(0).err(format!(
                        "t = {time} s is before the previous event's {} s (events in time order)",
                        last.time
                    )));
                }
            }
            let kind = CLUTCH_EVENTS
                .into_iter()
                .find(|k| k.name() == row[1])
                .ok_or_else(|| {
                    at(1).err(format!(
                        "'{}' is no event of the diode (known: {})",
                        row[1],
                        CLUTCH_EVENTS.map(EventKind::name).join(", ")
                    ))
                })?;
            events.push(ClutchEvent {
                time,
                kind,
                from: at(2).mode()?,
                to: at(3).mode()?,
            });
        }
        Ok(ClutchLog {
            origin: origin.to_string(),
            events,
        })
    }
}

/// The file at `path` read and given to `parse` with its path as its name.
fn read_with<L>(path: &Path, parse: fn(&str, &str) -> Result<L, LogError>) -> Result<L, LogError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| LogError {
        origin: origin.clone(),
        line: None,
        column: None,
        message: format!("cannot read: {e}"),
    })?;
    parse(&text, &origin)
}

/// A CSV reader of `text` as host-sim reads its CSVs: no header of its own (the
/// caller reads the first record as one), cells trimmed, rows of any width (the caller
/// names the line of a row of another width).
pub fn csv_reader(text: &str) -> ::csv::Reader<&[u8]> {
    ::csv::ReaderBuilder::new()
        .has_headers(false)
        .trim(::csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes())
}

/// A CSV's cells of the wanted columns: each data row's line and its cells in the
/// order of the columns asked for.
struct Cells {
    rows: Vec<(u64, Vec<String>)>,
}

impl Cells {
    /// The rows of `text` (named `origin`) in the columns `wanted`, each present once
    /// in the header; every row as wide as the header.
    fn parse(text: &str, origin: &str, wanted: &[&str]) -> Result<Cells, LogError> {
        let err = |line: Option<u64>, column: Option<&str>, message: String| LogError {
            origin: origin.to_string(),
            line,
            column: column.map(str::to_string),
            message,
        };
        let mut reader = csv_reader(text);
        let mut records = reader.records();
        let header = match records.next() {
            Some(r) => r.map_err(|e| err(Some(1), None, e.to_string()))?,
            None => return Err(err(None, None, "empty file (no header)".to_string())),
        };
        let names: Vec<&str> = header.iter().collect();
        let mut at = Vec::new();
        for w in wanted {
            let mut found = names.iter().enumerate().filter(|(_, n)| *n == w);
            match (found.next(), found.next()) {
                (Some((k, _)), None) => at.push(k),
                (Some(_), Some(_)) => {
                    return Err(err(
                        Some(1),
                        Some(w),
                        "named twice in the header".to_string(),
                    ))
                }
                (None, _) => {
                    return Err(err(
                        Some(1),
                        Some(w),
                        format!(
                            "missing from the header ({}); a log of this kind has the columns {}",
                            names.join(","),
                            wanted.join(", ")
                        ),
                    ))
                }
            }
        }
        let mut rows = Vec::new();
        for record in records {
            let record = record.map_err(|e| {
                let line = e.position().map(|p| p.line());
                err(line, None, e.to_string())
            })?;
            let line = record.position().map_or(0, |p| p.line());
            if record.len() == 1 && record.get(0) == Some("") {
                // A blank line.
                continue;
            }
            if record.len() != names.len() {
                return Err(err(
                    Some(line),
                    None,
                    format!("{} cells, the header has {}", record.len(), names.len()),
                ));
            }
            if rows.len() == MAX_SAMPLES {
                return Err(err(
                    Some(line),
                    None,
                    format!("more than {MAX_SAMPLES} rows"),
                ));
            }
            rows.push((
                line,
                at.iter()
                    .map(|&k| record.get(k).unwrap_or("").to_string())
                    .collect(),
            ));
        }
        Ok(Cells { rows })
    }
}

/// One cell, for its checks and its errors.
struct Cell<'a> {
    origin: &'a str,
    line: u64,
    column: &'static str,
    text: &'a str,
}

impl Cell<'_> {
    fn err(&self, message: String) -> LogError {
        LogError {
            origin: self.origin.to_string(),
            line: Some(self.line),
            column: Some(self.column.to_string()),
            message,
        }
    }

    /// A finite number.
    fn number(&self) -> Result<f64, LogError> {
        if self.text.is_empty() {
            return Err(self.err("empty (a number expected)".to_string()));
        }
        let v: f64 = self
            .text
            .parse()
            .map_err(|_| self.err(format!("'{}' is not a number", self.text)))?;
        if !v.is_finite() {
            return Err(self.err(format!("{} is not finite", self.text)));
        }
        Ok(v)
    }

    /// A whole number of encoder counts.
    fn count(&self) -> Result<i64, LogError> {
        if let Ok(n) = self.text.parse::<i64>() {
            // The residuals subtract counts, and identify takes them as f64: past 2^53
            // neither is exact (and at i64's ends a difference overflows).
            if n.unsigned_abs() > MAX_COUNTS {
                return Err(self.err(format!(
                    "{n} counts is past ±2^53, where a count is no longer exact in a float"
                )));
            }
            return Ok(n);
        }
        let v = self.number()?;
        Err(self.err(format!("{v} is not a whole number of counts")))
    }

    /// A mode's name.
    fn mode(&self) -> Result<Mode, LogError> {
        Mode::ALL
            .into_iter()
            .find(|m| m.name() == self.text)
            .ok_or_else(|| {
                self.err(format!(
                    "'{}' is no mode of the converter (known: {})",
                    self.text,
                    Mode::ALL.map(Mode::name).join(", ")
                ))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "t,motor_torque,load_torque,crank_counts,shaft_counts\n\
                        0.000,12.0,800.0,1194,0\n\
                        0.001,12.1,800.0,1194,0\n\
                        0.002,11.9,800.0,1195,1\n";

    #[test]
    fn a_good_log() {
        let log = BenchLog::parse(GOOD, "g.csv").unwrap();
        assert_eq!(log.len(), 3);
        assert_eq!(log.crank, [1194, 1194, 1195]);
        assert_eq!(log.shaft, [0, 0, 1]);
        assert!((log.period() - 1e-3).abs() < 1e-15);
        // Columns in another order, and one more, are read by name.
        let other = "shaft_counts,x,t,crank_counts,load_torque,motor_torque\n\
                     0,a,0,5,1,2\n3,b,0.5,6,1,2\n";
        let log = BenchLog::parse(other, "o.csv").unwrap();
        assert_eq!((log.crank[1], log.shaft[1], log.t[1]), (6, 3, 0.5));
    }

    /// Each bad log is refused with its line and column named.
    #[test]
    fn bad_logs_are_named() {
        let header = "t,motor_torque,load_torque,crank_counts,shaft_counts";
        for (text, want) in [
            (
                "t,motor_torque,crank_counts,shaft_counts\n0,1,2,3\n".to_string(),
                "b.csv: line 1, column load_torque: missing from the header",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,NaN,2,3,4\n"),
                "b.csv: line 3, column motor_torque: NaN is not finite",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,2,nan,4\n"),
                "b.csv: line 3, column crank_counts: nan is not finite",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,2,3,4.5\n"),
                "b.csv: line 3, column shaft_counts: 4.5 is not a whole number",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,-2,3,4\n"),
                "b.csv: line 3, column load_torque: -2 N·m is negative",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,2,3\n"),
                "b.csv: line 3: 4 cells, the header has 5",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.002,1,2,3,4\n0.001,1,2,3,4\n"),
                "b.csv: line 4, column t: t = 0.001 s is not after",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,2,3,4\n0.003,1,2,3,4\n0.004,1,2,3,4\n"),
                "b.csv: line 4, column t: t = 0.003 s is 0.002 s after the previous sample",
            ),
            (
                format!("{header}\n1,1,2,3,0\n1.001,1,2,3,4\n"),
                "b.csv: line 2, column t: the log starts at t = 1 s, not 0",
            ),
            (
                format!("{header}\n0,1,2,3,0\n"),
                "b.csv: 1 samples: a log needs two at least",
            ),
            (
                format!("{header},t\n0,1,2,3,4,0\n"),
                "b.csv: line 1, column t: named twice",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,,2,3,4\n"),
                "b.csv: line 3, column motor_torque: empty",
            ),
            (
                format!("{header}\n0,1,2,3,5000\n0.001,1,2,3,5001\n"),
                "b.csv: line 2, column shaft_counts: 5000 at the first sample: the shaft's count is 0 at t = 0",
            ),
            (
                format!("{header}\n0,1,2,-9223372036854775808,0\n0.001,1,2,3,0\n"),
                "b.csv: line 2, column crank_counts: -9223372036854775808 counts is past ±2^53",
            ),
            (
                format!("{header}\n0,1,2,3,0\n0.001,1,2,3,9007199254740993\n"),
                "b.csv: line 3, column shaft_counts: 9007199254740993 counts is past ±2^53",
            ),
        ] {
            let e = BenchLog::parse(&text, "b.csv").unwrap_err().to_string();
            assert!(e.starts_with(want), "{text:?}: {e}");
        }
    }

    #[test]
    fn clutch_logs() {
        let log = ClutchLog::parse(
            "t,event,from,to\n0.026870,release8,I8,I0\n0.836675,catch8,I6,jam\n",
            "c.csv",
        )
        .unwrap();
        assert_eq!(log.events.len(), 2);
        assert_eq!(log.events[1].kind, EventKind::Catch(8));
        assert_eq!(
            (log.events[1].from, log.events[1].to),
            (Mode::I6, Mode::Jam)
        );
        for (text, want) in [
            (
                "t,event,from\n",
                "c.csv: line 1, column to: missing from the header",
            ),
            (
                "t,event,from,to\n0.1,catch7,I0,I6\n",
                "c.csv: line 2, column event: 'catch7' is no event",
            ),
            (
                "t,event,from,to\n0.1,catch6,I0,I9\n",
                "c.csv: line 2, column to: 'I9' is no mode",
            ),
            (
                "t,event,from,to\n0.2,catch6,I0,I6\n0.1,catch8,I6,A68\n",
                "c.csv: line 3, column t: t = 0.1 s is before the previous event's",
            ),
        ] {
            let e = ClutchLog::parse(text, "c.csv").unwrap_err().to_string();
            assert!(e.starts_with(want), "{text:?}: {e}");
        }
    }

    /// The encoder law against hand-counted values: 105° is 1194.67 counts.
    #[test]
    fn encoder_law() {
        assert_eq!(encoder_counts(105f64.to_radians()), 1194);
        assert_eq!(encoder_counts(0.0), 0);
        assert_eq!(encoder_counts(-1e-12), -1);
        assert_eq!(encoder_counts(std::f64::consts::TAU), 4096);
    }
}
