//! One design at one operating point: the run-file tree parsed as `host-sim run`
//! parses a file, the linkage's assembly over the crank's whole turn, then the twin
//! stepped to the horizon with the constraints measured at every state, and the
//! objective.
//!
//! The diode's margin is measured host-side from the twin's public state: the reach
//! |DH| (D: point 2 of the rocker, link 3; H: the shaft) against the shorter
//! stretched branch, rod + lever (links 5 + 6 and 7 + 8); margin = min(rod + lever) −
//! |DH|, in m, 0 when a branch is stretched (the twin's `TwinStepError::Diode`).
//!
//! The run stops at the first step that ends in the jam (every lever locked, the
//! shaft held: the machine stands still and a design that gets there has failed;
//! unless the jam is allowed), at a failed step, or at the horizon. The stepping is the twin's own
//! ([`new_twin`], `Twin::step`); the winner's files come from `host-sim run`'s
//! pipeline.

use super::file::{Constraints, Design, Objective, Point};
use crate::model::scenarios::{CccScenario, Source};
use crate::options::{RunOptions, Steps};
use crate::run::converter::{new_twin, settings};
use crate::run::interrupt;
use std::f64::consts::TAU;
use structomat::ccc::{initial_pose, Inputs, Mode, MotorInput, Twin, TwinStepError};
use toml::Value;

/// Crank angles at which the assembly is checked: every 5°.
pub const ASSEMBLY_ANGLES: usize = 72;

/// How an evaluation ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// The twin reached the horizon.
    Completed,
    /// A step ended in the jam; the run stopped there.
    Jammed,
    /// A step failed (the diode stretched, a group that does not assemble, ...).
    Failed,
    /// The linkage does not assemble at some crank angle: not run.
    Unassembled,
    /// The design's run file or twin cannot be set up: not run.
    Invalid,
    /// SIGINT or SIGTERM.
    Interrupted,
}

impl Ended {
    /// Its word in `designs.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Ended::Completed => "completed",
            Ended::Jammed => "jammed",
            Ended::Failed => "failed",
            Ended::Unassembled => "unassembled",
            Ended::Invalid => "invalid",
            Ended::Interrupted => "interrupted",
        }
    }
}

/// What one design did at one operating point.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// How it ended.
    pub ended: Ended,
    /// Time of the last good state, s.
    pub time: f64,
    /// The horizon, s.
    pub horizon: f64,
    /// Time of the first state in the jam, s.
    pub jam_at: Option<f64>,
    /// The smallest diode margin over the states, m (`NaN`: not run).
    pub min_margin: f64,
    /// Crank angles (of [`ASSEMBLY_ANGLES`]) at which the linkage does not assemble.
    pub unassembled: usize,
    /// Time of the first breakaway, s.
    pub first_breakaway: Option<f64>,
    /// Motor and load work over the run, J.
    pub motor_work: f64,
    /// Load work over the run, J.
    pub load_work: f64,
    /// Motor and load work over the last half of the horizon, J.
    pub half_work: (f64, f64),
    /// Mean power to the load over the last half of the horizon, W (`NaN` unless
    /// completed).
    pub mean_power: f64,
    /// Shaft angle turned, rad (CCW positive).
    pub shaft_angle: f64,
    /// Why it did not complete.
    pub message: Option<String>,
}

impl Evaluation {
    fn not_run(ended: Ended, horizon: f64, message: String) -> Evaluation {
        Evaluation {
            ended,
            time: 0.0,
            horizon,
            jam_at: None,
            min_margin: f64::NAN,
            unassembled: 0,
            first_breakaway: None,
            motor_work: f64::NAN,
            load_work: f64::NAN,
            half_work: (f64::NAN, f64::NAN),
            mean_power: f64::NAN,
            shaft_angle: f64::NAN,
            message: Some(message),
        }
    }

    /// Load work over motor work over the run (`NaN` without motor work).
    pub fn efficiency(&self) -> f64 {
        if self.motor_work > 0.0 {
            self.load_work / self.motor_work
        } else {
            f64::NAN
        }
    }

    /// The violations of `c`, each ≥ 0 and 0 when it holds, in the order
    /// [`VIOLATIONS`]: the jam (the share of the horizon lost to it), the margin
    /// (δ − the smallest margin, over δ; 1 when it cannot be measured), the assembly
    /// (the share of crank angles where it fails), the horizon (the share not reached).
    /// A design not run violates every constraint it could not be checked against
    /// by 1.
    pub fn violations(&self, c: &Constraints) -> [f64; 4] {
        let share = |t: f64| ((self.horizon - t) / self.horizon).clamp(0.0, 1.0);
        let not_run = matches!(self.ended, Ended::Unassembled | Ended::Invalid);
        let jam = match self.jam_at {
            Some(t) => share(t).max(f64::MIN_POSITIVE),
            None if not_run => 1.0,
            None => 0.0,
        };
        let margin = if self.min_margin.is_nan() {
            1.0
        } else if c.margin > 0.0 {
            ((c.margin - self.min_margin) / c.margin).clamp(0.0, 1.0)
        } else if self.min_margin <= 0.0 {
            1.0
        } else {
            0.0
        };
        let assembly = match self.ended {
            Ended::Invalid => 1.0,
            _ => self.unassembled as f64 / ASSEMBLY_ANGLES as f64,
        };
        let horizon = match self.ended {
            Ended::Completed => 0.0,
            // Stopped by the jam: counted once, as the jam.
            Ended::Jammed => 0.0,
            _ => share(self.time).max(f64::MIN_POSITIVE),
        };
        [
            if c.no_jam { jam } else { 0.0 },
            margin,
            if c.assembly { assembly } else { 0.0 },
            if c.horizon { horizon } else { 0.0 },
        ]
    }

    /// The objective to minimise: minus the mean power, or the first breakaway
    /// (`NaN` when there is none).
    pub fn objective(&self, o: Objective) -> f64 {
        match o {
            Objective::MeanPower => -self.mean_power,
            Objective::FirstBreakaway => self.first_breakaway.unwrap_or(f64::NAN),
        }
    }
}

/// The constraints' names, in [`Evaluation::violations`] order (`designs.csv`'s
/// columns `v_<name>`).
pub const VIOLATIONS: [&str; 4] = ["jam", "margin", "assembly", "horizon"];

/// The run options of design `x` at `point` (its run file's, quiet), or why it has
/// none: the run file's message.
pub fn options(d: &Design, x: &[f64], point: &Point) -> Result<RunOptions, String> {
    let tree = d.tree(x, point)?;
    let name = format!("{} design ({})", d.origin, d.describe(x));
    let file = crate::model::runfile::run_file_from_value(Value::Table(tree), &name)
        .map_err(|e| e.to_string())?;
    let mut opts = RunOptions::from_source(Source::from_file("design".to_string(), file));
    opts.quiet = true;
    Steps::check(&opts).map_err(|e| format!("{name}: {e}"))?;
    Ok(opts)
}

/// The crank angles, of [`ASSEMBLY_ANGLES`] from the initial one, at which the
/// converter of `s` does not assemble with the swing link at its initial angle.
pub fn unassembled(s: &CccScenario) -> usize {
    let mut params = s.converter.params::<f64>();
    params.drive = s.drive;
    let crank = s.converter.crank_deg.to_radians();
    let swing = s.converter.swing_deg.to_radians();
    (0..ASSEMBLY_ANGLES)
        .filter(|&k| {
            let at = crank + TAU * k as f64 / ASSEMBLY_ANGLES as f64;
            initial_pose(&params, at, swing).is_none()
        })
        .count()
}

/// The diode's margin of `twin`'s state, m: the shorter stretched branch (rod +
/// lever) minus the reach |DH|.
pub fn diode_margin(twin: &Twin<f64>) -> f64 {
    let p = twin.params();
    let reach = (twin.joint_position(3, 2) - p.h).norm();
    let full = |rod: usize, lever: usize| p.link(rod).length + p.link(lever).length;
    full(5, 6).min(full(7, 8)) - reach
}

/// Evaluates design `x` at `point` (in f64).
pub fn evaluate(d: &Design, x: &[f64], point: &Point) -> Evaluation {
    let horizon = point.horizon;
    if interrupt::requested() {
        return Evaluation::not_run(Ended::Interrupted, horizon, "not run".into());
    }
    let opts = match options(d, x, point) {
        Ok(o) => o,
        Err(e) => return Evaluation::not_run(Ended::Invalid, horizon, e),
    };
    let Some(s) = settings(&opts) else {
        return Evaluation::not_run(Ended::Invalid, horizon, "not a converter".into());
    };
    let bad = unassembled(&s);
    if bad > 0 {
        let mut e = Evaluation::not_run(
            Ended::Unassembled,
            horizon,
            format!("does not assemble at {bad} of {ASSEMBLY_ANGLES} crank angles"),
        );
        e.unassembled = bad;
        return e;
    }
    match run(&opts, &s, horizon, d.constraints.no_jam) {
        Ok(e) => e,
        Err(m) => Evaluation::not_run(Ended::Invalid, horizon, m),
    }
}

/// Steps the twin of `s` to the horizon (or the first jam, when `stop_at_jam`, or a
/// failed step), measuring the margin at every state.
fn run(
    opts: &RunOptions,
    s: &CccScenario,
    horizon: f64,
    stop_at_jam: bool,
) -> Result<Evaluation, String> {
    let (Steps { n, .. }, h) = Steps::of::<f64>(opts).map_err(|e| e.to_string())?;
    let motor = s.motor.motor::<f64>().map_err(|e| format!("motor: {e}"))?;
    let inputs = Inputs {
        motor: MotorInput::Law(motor),
        load: s.load,
        measured: None,
    };
    let mut twin = new_twin("design", s, h, inputs).map_err(|e| e.to_string())?;
    let half = n / 2;
    let mut min_margin = diode_margin(&twin);
    let mut first_breakaway = None;
    let mut at_half = (0.0, 0.0);
    let mut ended = Ended::Completed;
    let mut jam_at = None;
    let mut message = None;
    let mut steps = 0u64;
    while steps < n {
        if interrupt::requested() {
            ended = Ended::Interrupted;
            message = Some("interrupted (SIGINT or SIGTERM)".into());
            break;
        }
        if steps == half {
            let a = twin.audit();
            at_half = (a.motor_work, a.load_work);
        }
        if let Err(e) = twin.step(&inputs) {
            if matches!(e, TwinStepError::Diode { .. }) {
                min_margin = min_margin.min(0.0);
            }
            ended = Ended::Failed;
            message = Some(format!("step {} failed: {e}", steps + 1));
            break;
        }
        steps += 1;
        min_margin = min_margin.min(diode_margin(&twin));
        if first_breakaway.is_none() {
            first_breakaway = twin
                .events()
                .iter()
                .find(|e| !e.from.shaft_turning() && e.to.shaft_turning())
                .map(|e| e.time);
        }
        if twin.mode() == Mode::Jam && jam_at.is_none() {
            jam_at = Some(twin.time());
            message = Some(format!("jammed at t = {} s", twin.time()));
            if stop_at_jam {
                ended = Ended::Jammed;
                break;
            }
        }
    }
    let a = twin.audit();
    let half_work = (a.motor_work - at_half.0, a.load_work - at_half.1);
    let span = (n - half) as f64 * h;
    let mean_power = if ended == Ended::Completed && span > 0.0 {
        half_work.1 / span
    } else {
        f64::NAN
    };
    if !min_margin.is_finite() {
        min_margin = 0.0;
    }
    Ok(Evaluation {
        ended,
        time: twin.time(),
        horizon,
        jam_at,
        min_margin,
        unassembled: 0,
        first_breakaway,
        motor_work: a.motor_work,
        load_work: a.load_work,
        half_work,
        mean_power,
        shaft_angle: twin.shaft_angle(),
        message,
    })
}
