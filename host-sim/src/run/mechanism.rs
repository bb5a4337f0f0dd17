//! The mechanism runner: steps a mechanism's [`Simulation`], tells the observers every
//! state and written row, and gathers the summary.

use super::columns::{Column, Layout};
use super::switching::{SwitchRecord, Switching};
use crate::error::RunError;
use crate::model::runfile::Integrator;
use crate::options::{precision, RunOptions, Steps};
use crate::output::csv::{CsvWriter, Sink};
use crate::output::{Cell, Observer, State, Tables};
use std::fmt;
use std::time::{Duration, Instant};
use structomat::integrator::{Adaptive, AdaptiveError, AdaptiveSettings};
use structomat::simulation::singular::at_singularity;
use structomat::structomat::GroupKind;
use structomat::{Real, Simulation, StepError};

/// The mean of a generalized speed over the second half of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct MeanSpeed {
    /// The coordinate (0-based).
    pub coord: usize,
    /// First time of the averaged samples, s.
    pub from: f64,
    /// Last time, s.
    pub to: f64,
    /// Arithmetic mean of the step samples `from..=to` (rad/s or m/s).
    pub value: f64,
    /// Whether the coordinate is an angle (a motor element R drives it).
    pub angular: bool,
}

/// The largest reaction force magnitude of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct MaxReaction {
    /// Its CSV column name (e.g. `R2_1`).
    pub joint: String,
    /// Magnitude, N.
    pub value: f64,
    /// When, s.
    pub time: f64,
}

/// A run's energy balance as the core metered it (`structomat::Balance`), J.
#[derive(Clone, Debug, PartialEq)]
pub struct Metered {
    /// Work of the motors, integrated with the state.
    pub motor_work: f64,
    /// Work of the constant loads.
    pub load_work: f64,
    /// Work in minus the change of K + V.
    pub residual: f64,
    /// The worst step's balance relative to its energy scale.
    pub worst: f64,
    /// Steps redone in sub-steps.
    pub redone: u64,
    /// Sub-steps taken by them.
    pub substeps: u64,
}

/// What a run did (printed as a few lines by its `Display`).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// The scenario's name (a built-in's, or the run file's path).
    pub scenario: String,
    /// Its structomatic formula.
    pub formula: String,
    /// `f64` or `f32`.
    pub precision: &'static str,
    /// Step size, s.
    pub h: f64,
    /// Steps taken.
    pub steps: u64,
    /// Final simulated time, s.
    pub time: f64,
    /// CSV data rows written (including the one at t = 0).
    pub rows: u64,
    /// Final coordinates.
    pub q: Vec<f64>,
    /// Final speeds.
    pub qd: Vec<f64>,
    /// Mean of the first coordinate's speed over the second half of the run.
    pub mean_speed: Option<MeanSpeed>,
    /// Kinetic and potential energy at the start, J.
    pub energy_start: (f64, f64),
    /// Kinetic and potential energy at the end, J.
    pub energy_end: (f64, f64),
    /// Work of the drives, J (N·m·rad or N·m): the trapezoidal rule over the steps of
    /// the power `Σ motor_torque · q̇`. Without other non-conservative loads,
    /// `end - start - work` measures the integration error (plus the rule's `O(h²)`).
    pub drive_work: f64,
    /// The energy balance the core metered with the state, when every step was a
    /// fixed DP5 step (`None` with the adaptive integrator, whose intervals are not
    /// metered).
    pub balance: Option<Metered>,
    /// Largest reaction force magnitude over every step (revolute `|F|`, prismatic `|N|`).
    pub max_reaction: Option<MaxReaction>,
    /// With `integrator = "adaptive"`: its steps accepted and rejected in all (`steps`
    /// counts the output intervals then).
    pub adaptive: Option<(u64, u64)>,
    /// Wall time of the whole run (stepping, kinetostatics, CSV).
    pub wall: Duration,
    /// Wall time inside `Simulation::step` only.
    pub step_wall: Duration,
    /// The changes of independent coordinates at dead points of the drivers.
    pub switches: Vec<SwitchRecord>,
}

impl Summary {
    /// Nanoseconds per step inside `Simulation::step`.
    pub fn ns_per_step(&self) -> f64 {
        per_step(self.step_wall, self.steps)
    }
    /// Nanoseconds per step of the whole run.
    pub fn total_ns_per_step(&self) -> f64 {
        per_step(self.wall, self.steps)
    }
}

fn per_step(d: Duration, steps: u64) -> f64 {
    d.as_secs_f64() * 1e9 / steps.max(1) as f64
}

struct List<'a>(&'a [f64]);

impl fmt::Display for List<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (k, v) in self.0.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{v:.6}")?;
        }
        f.write_str("]")
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scenario  {}: {} ({})",
            self.scenario, self.formula, self.precision
        )?;
        writeln!(
            f,
            "steps     {} of h = {} s, t = 0 .. {:.6} s, {} CSV rows",
            self.steps, self.h, self.time, self.rows
        )?;
        if let Some((accepted, rejected)) = self.adaptive {
            writeln!(
                f,
                "adaptive  DP5(4): {accepted} steps ({rejected} rejected) over the {} output intervals",
                self.steps
            )?;
        }
        writeln!(
            f,
            "final     q = {}, qd = {}",
            List(&self.q),
            List(&self.qd)
        )?;
        if let Some(m) = &self.mean_speed {
            write!(
                f,
                "speed     mean qd{} over t in [{:.4}, {:.4}] s: {:.6} {}",
                m.coord + 1,
                m.from,
                m.to,
                m.value,
                if m.angular { "rad/s" } else { "m/s" }
            )?;
            if m.angular {
                write!(f, " = {:.4} rpm", m.value * 60.0 / core::f64::consts::TAU)?;
            }
            writeln!(f)?;
        }
        let (k0, v0) = self.energy_start;
        let (k1, v1) = self.energy_end;
        let (e0, e1) = (k0 + v0, k1 + v1);
        writeln!(f, "energy    K + V: start {k0:.6} + {v0:.6} = {e0:.6} J, end {k1:.6} + {v1:.6} = {e1:.6} J")?;
        match &self.balance {
            Some(b) => writeln!(
                f,
                "balance   work of the motors {:.6} J + loads {:.6} J, end - start - work = {:.3e} J; \
                 worst step {:.1e} of its energy scale, {} steps redone in {} sub-steps",
                b.motor_work, b.load_work, -b.residual, b.worst, b.redone, b.substeps
            )?,
            None => writeln!(
                f,
                "balance   work of the drives {:.6} J (trapezoid; adaptive intervals are not metered), \
                 end - start - work = {:.3e} J",
                self.drive_work,
                e1 - e0 - self.drive_work
            )?,
        }
        if !self.switches.is_empty() {
            writeln!(
                f,
                "switches  {} changes of coordinates at dead points of the drivers (CSV: accelerations, torques and reactions NaN while another choice drives):",
                self.switches.len()
            )?;
            for s in &self.switches {
                writeln!(
                    f,
                    "          t = {:.6} s: {} -> {} ({} at {:.3e}, then {:.3e})",
                    s.time, s.from, s.to, s.group, s.conditioning[0], s.conditioning[1]
                )?;
            }
        }
        if let Some(r) = &self.max_reaction {
            writeln!(
                f,
                "reaction  max {:.6} N at {}, t = {:.6} s",
                r.value, r.joint, r.time
            )?;
        }
        write!(
            f,
            "wall      {:.6} s: {:.0} ns/step in Simulation::step, {:.0} ns/step with kinetostatics and CSV",
            self.wall.as_secs_f64(),
            self.ns_per_step(),
            self.total_ns_per_step()
        )
    }
}

/// Runs the mechanism scenario of `opts` in scalar `T`, telling `obs` its states and
/// rows ([`Observer::on_end`] also on a step error, before the error is returned). The
/// scenario (a built-in's embedded run file or a file's contents) is built by the
/// structomatic analysis of [`crate::model::analysis`]. A converter scenario is a
/// [`RunError::Setup`]: [`super::converter::simulate`] runs those.
pub fn simulate<T: Real>(
    opts: &RunOptions,
    obs: &mut dyn Observer<T>,
) -> Result<Summary, RunError> {
    let precision = precision::<T>();
    let scenario = opts.scenario.build::<T>().map_err(RunError::Setup)?;
    let (Steps { n, .. }, h) = Steps::of::<T>(opts)?;
    let every = opts.every.max(1);
    let mut sim = scenario
        .simulation_with_step(h)
        .map_err(|e| RunError::Setup(format!("cannot set up {}: {e}", opts.scenario.name())))?;
    let mut adaptive = match opts.scenario.run_file().map(|f| f.run.integrator) {
        Ok(Integrator::Adaptive { rtol, atol, h_max }) => Some(
            Adaptive::new(AdaptiveSettings {
                rtol: T::c(rtol),
                atol: T::c(atol),
                h0: h.min(T::c(h_max)),
                h_max: T::c(h_max),
                ..AdaptiveSettings::default()
            })
            .map_err(|e| RunError::Setup(format!("{}: {e}", opts.scenario.name())))?,
        ),
        _ => None,
    };
    // Coordinate switching at dead points: fixed steps only (the adaptive intervals
    // are not metered, and their error control is not the switch's).
    let mut switching = match adaptive {
        None => Switching::new(opts, &sim).map_err(RunError::Setup)?,
        Some(_) => None,
    };
    let (mut accepted, mut rejected) = (0u64, 0u64);
    let model = sim.model().clone();
    let layout = Layout::new(&model);
    let forces: Vec<usize> = (0..layout.columns.len())
        .filter(|&k| layout.columns[k].is_reaction_force())
        .collect();
    let angular = model
        .groups()
        .iter()
        .find(|g| g.coord == Some(0))
        .is_some_and(|g| g.kind == GroupKind::MotorR);
    let e0 = sim.energy();
    let energy_start = (e0.kinetic.to_f64(), e0.potential.to_f64());

    let start = Instant::now();
    let mut step_wall = Duration::ZERO;
    let mut rows = 0u64;
    let mut max: Option<(usize, f64, f64)> = None;
    let (mut sum, mut count, mut from) = (0.0f64, 0u64, None);
    let first_averaged = n.div_ceil(2);
    let drive_power = |sim: &Simulation<T>, switching: &Option<Switching<T>>| -> f64 {
        let ws = sim.workspace();
        let first = switching.as_ref().map(|s| s.first_qd(sim));
        let qd = first.as_ref().map_or(sim.qd(), |q| &q[..]);
        model
            .drives()
            .iter()
            .zip(ws.motor.iter())
            .map(|(d, tau)| tau.to_f64() * qd.get(d.coord as usize).map_or(0.0, |v| v.to_f64()))
            .sum()
    };
    let (mut drive_work, mut power) = (0.0f64, drive_power(&sim, &switching));
    let half_h = 0.5 * h.to_f64();
    obs.on_start(&Tables {
        columns: &layout.names,
        logs: &[],
    })?;
    let mut row: Vec<Cell<'_, T>> = Vec::with_capacity(layout.columns.len());
    let mut steps = 0u64;
    let outcome = loop {
        // Kinetostatics at the current state (the one at `steps`).
        if let Err(error) = sim.kinetostatics() {
            break Err(Failure::Step {
                kinetostatics: true,
                error,
            });
        }
        let value = |c: Column| {
            switching
                .as_ref()
                .and_then(|s| s.value(c, &sim))
                .unwrap_or_else(|| Layout::value(c, &sim))
        };
        for &k in &forces {
            let v = value(layout.columns[k]).to_f64();
            if v.is_nan() {
                continue;
            }
            if max.is_none_or(|(_, m, _)| v > m) {
                max = Some((k, v, sim.time().to_f64()));
            }
        }
        if steps >= first_averaged {
            sum += value(Column::Qd(0)).to_f64();
            count += 1;
            from.get_or_insert(sim.time().to_f64());
        }
        obs.on_state(State::Mechanism(&sim));
        if steps % every == 0 {
            row.clear();
            row.extend(layout.columns.iter().map(|c| Cell::Num(value(*c))));
            obs.on_row(&row)?;
            rows += 1;
        }
        if steps == n {
            break Ok(());
        }
        let t0 = Instant::now();
        let r = match adaptive.as_mut() {
            None => match switching.as_mut() {
                Some(s) => s.step(&mut sim).map_err(Failure::step),
                None => sim.step().map_err(Failure::step),
            },
            Some(a) => match sim.step_adaptive(a) {
                Ok(stats) => {
                    accepted += u64::from(stats.accepted);
                    rejected += u64::from(stats.rejected);
                    Ok(())
                }
                Err(AdaptiveError::System(e)) => Err(Failure::step(e)),
                Err(e) => Err(Failure::Integrator(e.to_string())),
            },
        };
        step_wall += t0.elapsed();
        if let Err(failure) = r {
            break Err(failure.located(&sim));
        }
        steps += 1;
        let p = drive_power(&sim, &switching);
        drive_work += half_h * (power + p);
        power = p;
    };
    let wall = start.elapsed();
    obs.on_end()?;
    match outcome {
        Ok(()) => {}
        Err(Failure::Step {
            kinetostatics,
            error,
        }) => {
            return Err(RunError::Step {
                steps,
                kinetostatics,
                rows,
                error,
            })
        }
        Err(Failure::Integrator(error)) => return Err(RunError::Integrator { steps, rows, error }),
    }
    let e1 = sim.energy();
    let (q_end, qd_end): (Vec<f64>, Vec<f64>) = (0..model.dof())
        .map(|j| {
            let at = |c: Column| {
                switching
                    .as_ref()
                    .and_then(|s| s.value(c, &sim))
                    .unwrap_or_else(|| Layout::value(c, &sim))
                    .to_f64()
            };
            (at(Column::Q(j)), at(Column::Qd(j)))
        })
        .unzip();
    let mean_speed = (model.dof() > 0 && count > 0).then(|| MeanSpeed {
        coord: 0,
        from: from.unwrap_or(0.0),
        to: sim.time().to_f64(),
        value: sum / count as f64,
        angular,
    });
    Ok(Summary {
        scenario: opts.scenario.name().to_string(),
        formula: model.formula().to_string(),
        precision,
        h: h.to_f64(),
        steps,
        time: sim.time().to_f64(),
        rows,
        q: q_end,
        qd: qd_end,
        mean_speed,
        energy_start,
        energy_end: (e1.kinetic.to_f64(), e1.potential.to_f64()),
        drive_work,
        balance: (sim.balance().unaudited == 0).then(|| {
            let b = sim.balance();
            Metered {
                motor_work: b.motor_work.to_f64(),
                load_work: b.load_work.to_f64(),
                residual: b.residual().to_f64(),
                worst: b.worst.to_f64(),
                redone: b.redone,
                substeps: b.substeps,
            }
        }),
        max_reaction: max.map(|(k, value, time)| MaxReaction {
            joint: layout.names[k].clone(),
            value,
            time,
        }),
        adaptive: adaptive.map(|_| (accepted, rejected)),
        wall,
        step_wall,
        switches: switching.map(|s| s.log).unwrap_or_default(),
    })
}

/// Why the stepping loop of [`simulate`] stopped early.
enum Failure {
    /// The next step (or output interval) failed, or the kinetostatics at the current
    /// state did.
    Step {
        kinetostatics: bool,
        error: StepError,
    },
    /// The adaptive integrator gave up.
    Integrator(String),
}

impl Failure {
    /// The next step's failure.
    fn step(error: StepError) -> Self {
        Failure::Step {
            kinetostatics: false,
            error,
        }
    }

    /// A step's failure at a singularity of the mechanism with the time located inside
    /// the step ([`Simulation::locate_failure`]); the others as they are.
    fn located<T: Real>(self, sim: &Simulation<T>) -> Self {
        match self {
            Failure::Step {
                kinetostatics: false,
                error,
            } if at_singularity(&error) => {
                let mut scratch = Box::new(structomat::Workspace::new());
                let error = match sim.locate_failure(&mut scratch) {
                    Some(t) => error.at_time(t.to_f64()),
                    None => error,
                };
                Failure::step(error)
            }
            f => f,
        }
    }
}

/// [`simulate`] with the CSV to `csv` only (`target` names it in errors); the CSV is
/// flushed before returning, also on a step error.
pub fn simulate_csv<T: Real>(
    opts: &RunOptions,
    csv: &mut dyn std::io::Write,
    target: &str,
) -> Result<Summary, RunError> {
    let mut w = CsvWriter::new(Sink::new(csv, target), Vec::new());
    simulate::<T>(opts, &mut w)
}
