//! `host-sim replay --observer`: what the observer adds to a replay — the bench's
//! encoders as the twin's measurements, the columns of its innovations and
//! diagnostics, and their summary.

use super::replay::Residuals;
use crate::error::Fig;
use crate::model::bench::{BenchLog, COUNTS_PER_TURN};
use crate::output::Cell;
use std::fmt;
use structomat::ccc::{Diagnostic, Encoder, Measurement, Twin, Update};
use structomat::Real;

/// The columns an observed replay appends after the residuals': the crank's innovation
/// (measured - predicted, counts) and its standard deviation after the update (counts),
/// the shaft's innovation since the last mode change (counts), the crank's unknown
/// torque estimated (N·m, CCW, added to the motor's), the crank bearing's unknown
/// viscous friction estimated (N·m·s/rad, its torque `-c ω1` added to the motor's), the
/// oscillating mass the twin carries (kg: the estimate, with a tuning that estimates
/// it), and each diagnostic (1 when raised at the step).
pub const OBSERVER_COLUMNS: [&str; 12] = [
    "crank_innovation",
    "crank_sigma",
    "shaft_innovation",
    "crank_torque_estimate",
    "crank_friction_estimate",
    "oscillating_mass",
    "crank_jump",
    "shaft_jump",
    "clutch_slip",
    "failed_catch",
    "load_bias",
    "twin_parted",
];

/// The columns before the diagnostics': one for each diagnostic follows, in
/// [`Diagnostic::ALL`]'s order (a diagnostic added to the core without its column fails
/// to compile here).
const ESTIMATE_COLUMNS: usize = 6;
const _: () = assert!(OBSERVER_COLUMNS.len() == ESTIMATE_COLUMNS + Diagnostic::ALL.len());

/// The statistics are taken after this time, s: the observer's settling from a wrong
/// initial state (issue 19: "after the first 20 ms").
pub const SETTLE: f64 = 0.02;

/// The encoders of the log's sample `k`: the crank's, absolute (the bench's law counts
/// `floor(θ1 / (2π/4096))` from θ1 = 0), and the shaft's from 0 in the drive direction.
pub fn measurement<T: Real>(log: &BenchLog, k: usize) -> Option<Measurement<T>> {
    let encoder = |counts: i64| Encoder {
        counts,
        per_turn: COUNTS_PER_TURN,
        zero: T::zero(),
    };
    Some(Measurement {
        crank: Some(encoder(*log.crank.get(k)?)),
        shaft: Some(encoder(*log.shaft.get(k)?)),
        rocker: None,
    })
}

/// A quantity's statistics over samples, in counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Samples.
    pub samples: u64,
    /// Sum of squares, counts².
    pub sum_squares: f64,
    /// The largest in magnitude (the first of them), counts, and its time, s.
    pub largest: (f64, f64),
}

impl Stats {
    fn add(&mut self, x: f64, time: f64) {
        self.samples += 1;
        self.sum_squares += x * x;
        if x.abs() > self.largest.0.abs() || self.samples == 1 {
            self.largest = (x, time);
        }
    }

    /// The root mean square, counts (`NaN` without samples).
    pub fn rms(&self) -> f64 {
        if self.samples == 0 {
            f64::NAN
        } else {
            (self.sum_squares / self.samples as f64).sqrt()
        }
    }
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "RMS {:.3} counts, largest {:+.3} counts at t = {} s, over {} samples",
            self.rms(),
            self.largest.0,
            Fig(self.largest.1),
            self.samples
        )
    }
}

/// What the observer did over a replay.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObservedSummary {
    /// The crank's innovations (measured - predicted), counts, over every step.
    pub innovation: Stats,
    /// The same after [`SETTLE`].
    pub innovation_settled: Stats,
    /// The crank's residual (measured - twin after the update) after [`SETTLE`].
    pub residual_settled: Residuals,
    /// Each diagnostic's onsets (raised at a step, not at the one before): time, s,
    /// and name.
    pub onsets: Vec<(f64, &'static str)>,
    /// Steps each diagnostic was raised at, in [`Diagnostic::ALL`]'s order.
    pub steps: [u64; Diagnostic::ALL.len()],
    /// The energy the corrections put in, J (the audit's own term).
    pub correction_energy: f64,
    /// The crank's unknown torque (N·m), its bearing's unknown viscous friction
    /// (N·m·s/rad) and the oscillating mass (kg) estimated at the last step.
    pub estimates: (f64, f64, f64),
    last: [bool; Diagnostic::ALL.len()],
}

impl ObservedSummary {
    /// Adds the state row of `twin` after the step whose update is `up` (`None`: the
    /// start), the crank residual `residual` (counts), to the statistics and appends
    /// its [`OBSERVER_COLUMNS`] cells.
    pub fn add<T: Real>(
        &mut self,
        twin: &Twin<T>,
        up: Option<Update<T>>,
        sigma: T,
        residual: i64,
        cells: &mut Vec<Cell<'static, T>>,
    ) {
        let Some(up) = up else {
            cells.extend([Cell::Empty; OBSERVER_COLUMNS.len()]);
            return;
        };
        let time = twin.time().to_f64();
        let res = std::f64::consts::TAU / f64::from(COUNTS_PER_TURN);
        let nu = up.innovation.map(|n| n.to_f64() / res);
        if let Some(n) = nu {
            self.innovation.add(n, time);
            if time > SETTLE {
                self.innovation_settled.add(n, time);
            }
        }
        if time > SETTLE {
            self.residual_settled.add(residual, time);
        }
        self.correction_energy = twin.audit().correction.to_f64();
        self.estimates = (up.torque.to_f64(), up.friction.to_f64(), up.mass.to_f64());
        let num = |x: Option<f64>| x.map_or(Cell::Empty, |x| Cell::Num(T::c(x)));
        cells.extend([
            num(nu),
            num(Some(sigma.to_f64().sqrt() / res)),
            num(up.shaft_innovation.map(|x| x.to_f64())),
            num(Some(up.torque.to_f64())),
            num(Some(up.friction.to_f64())),
            num(Some(up.mass.to_f64())),
        ]);
        for (k, d) in Diagnostic::ALL.into_iter().enumerate() {
            let on = up.diagnostics.contains(d);
            cells.push(Cell::Int(u64::from(on)));
            if on {
                self.steps[k] += 1;
                if !self.last[k] {
                    self.onsets.push((time, d.name()));
                }
            }
            self.last[k] = on;
        }
    }

    /// The first onset of diagnostic `name`, s.
    pub fn first(&self, name: &str) -> Option<f64> {
        self.onsets
            .iter()
            .find(|(_, n)| *n == name)
            .map(|(t, _)| *t)
    }
}

impl fmt::Display for ObservedSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "observer  crank innovation (measured - predicted) {}",
            self.innovation
        )?;
        writeln!(
            f,
            "          after {SETTLE} s: innovation {}; {} (after the update)",
            self.innovation_settled, self.residual_settled
        )?;
        writeln!(
            f,
            "          the corrections' energy {} J (the audit's own term)",
            Fig(self.correction_energy)
        )?;
        writeln!(
            f,
            "          estimated at the end: the crank's unknown torque {} N·m, its bearing's viscous friction {} N·m·s/rad, the oscillating mass {} kg",
            Fig(self.estimates.0),
            Fig(self.estimates.1),
            Fig(self.estimates.2)
        )?;
        if self.onsets.is_empty() {
            return write!(f, "          diagnostics: none");
        }
        let counts: Vec<String> = Diagnostic::ALL
            .iter()
            .zip(self.steps)
            .filter(|(_, n)| *n > 0)
            .map(|(d, n)| format!("{} at {n} steps", d.name()))
            .collect();
        write!(f, "          diagnostics: {}; onsets:", counts.join(", "))?;
        const SHOWN: usize = 20;
        for (t, n) in self.onsets.iter().take(SHOWN) {
            write!(f, " {n} {}", Fig(*t))?;
        }
        if self.onsets.len() > SHOWN {
            write!(f, " ... ({} more)", self.onsets.len() - SHOWN)?;
        }
        Ok(())
    }
}
