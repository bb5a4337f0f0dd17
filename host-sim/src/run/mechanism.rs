//! The mechanism runner: steps a mechanism's [`Simulation`], tells the observers every
//! state and written row, and gathers the summary.

use super::columns::{Column, Layout};
use super::interrupt;
use super::progress::Progress;
use super::switching::{SwitchRecord, Switching};
use crate::error::{Fig, RunError, Sci};
use crate::model::runfile::{Body, Integrator};
use crate::options::{precision, RunOptions, Steps};
use crate::output::csv::{CsvWriter, Sink};
use crate::output::{Cell, Observer, State, Tables};
use std::fmt;
use std::time::{Duration, Instant};
use structomat::integrator::{Adaptive, AdaptiveError, AdaptiveSettings};
use structomat::simulation::singular::at_singularity;
use structomat::structomat::GroupKind;
use structomat::{Real, Simulation, StepError};

/// The time mean of a generalized speed over the second half of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct MeanSpeed {
    /// The coordinate (0-based).
    pub coord: usize,
    /// Start of the averaged span, s (the first step time of the second half).
    pub from: f64,
    /// Its end, s.
    pub to: f64,
    /// The time mean `∫ q̇ dt / (to - from) = (q(to) - q(from)) / (to - from)` (rad/s or
    /// m/s): exact for the integrated state, where a mean of the step samples is biased
    /// by `O(h)`.
    pub value: f64,
    /// Whether the coordinate is an angle (a motor element R drives it).
    pub angular: bool,
}

/// A run's end at a singularity of the mechanism.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularEnd {
    /// The located time, s (inside the step after the last state written).
    pub time: f64,
    /// The group and the cause (`group RRR(2,3): ...`), or the mass matrix's.
    pub cause: String,
}

impl SingularEnd {
    /// The end the core's error `e` (its time located) describes.
    fn of(e: &StepError) -> Self {
        let cause = match e {
            StepError::Group { group, fault, .. } => format!("group {group}: {fault}"),
            StepError::SingularMassMatrix { .. } => {
                "the reduced mass matrix is singular".to_string()
            }
            other => other.to_string(),
        };
        SingularEnd {
            time: e.time(),
            cause,
        }
    }
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
    /// The worst step's balance relative to its energy scale (fixed steps; the
    /// adaptive integrator's intervals are not checked).
    pub worst: f64,
    /// Steps redone in sub-steps.
    pub redone: u64,
    /// Sub-steps taken by them.
    pub substeps: u64,
    /// Steps redone because a coarser division broke the energy balance.
    pub redone_energy: u64,
    /// Steps redone because a coarser division's error estimate was over the local
    /// tolerance (`structomat::simulation::substeps`).
    pub redone_error: u64,
    /// Steps accepted in 16 sub-steps with their error estimate still over it.
    pub inexact: u64,
    /// The largest accepted error estimate relative to the local tolerance.
    pub worst_error: f64,
    /// When the first of the `inexact` steps ended, s.
    pub first_inexact: Option<f64>,
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
    /// Whether SIGINT or SIGTERM stopped the run before `t_end` (after the row of its
    /// last state was written).
    pub interrupted: bool,
    /// Where the run ended at a singularity of the mechanism (the constraints losing
    /// rank), located inside the step that met it: its expected end, exit status 0.
    pub singular: Option<SingularEnd>,
    /// The motors' warnings: a characteristic that rises again past a speed (set-up),
    /// a motor driven out of its working zone (the first time, with its numbers).
    pub warnings: Vec<String>,
    /// The energy balance the core metered with the state (with either integrator; the
    /// worst step's is checked on the fixed steps only).
    pub balance: Metered,
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
            write!(f, "{}", Fig(*v))?;
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
            "steps     {} of h = {} s, t = 0 .. {} s, {} CSV rows",
            self.steps,
            self.h,
            Fig(self.time),
            self.rows
        )?;
        if self.interrupted {
            writeln!(
                f,
                "interrupted at t = {} s (SIGINT or SIGTERM): the files hold the run up to there",
                Fig(self.time)
            )?;
        }
        if let Some(end) = &self.singular {
            writeln!(
                f,
                "end       ended at a singularity at t = {} s ({}); the files hold the run up to the last step before it",
                Sci(end.time),
                end.cause
            )?;
        }
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
                "speed     time mean of qd{} over t in [{:.4}, {:.4}] s: {} {}",
                m.coord + 1,
                m.from,
                m.to,
                Fig(m.value),
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
        writeln!(
            f,
            "energy    K + V: start {} + {} = {} J, end {} + {} = {} J",
            Fig(k0),
            Fig(v0),
            Fig(e0),
            Fig(k1),
            Fig(v1),
            Fig(e1)
        )?;
        let b = &self.balance;
        write!(
            f,
            "balance   work of the motors {} J + loads {} J, end - start - work = {:.3e} J",
            Fig(b.motor_work),
            Fig(b.load_work),
            -b.residual
        )?;
        match self.adaptive {
            None => {
                writeln!(f, "; worst step {:.1e} of its energy scale", b.worst)?;
                writeln!(
                    f,
                    "substeps  {} steps redone in {} sub-steps: {} for the energy balance, {} for the local error (DP5's 5(4) estimate)",
                    b.redone, b.substeps, b.redone_energy, b.redone_error
                )?;
                if b.inexact > 0 {
                    let from = b
                        .first_inexact
                        .map_or_else(String::new, |t| format!(", the first at t = {} s", Fig(t)));
                    writeln!(
                        f,
                        "warning   {} steps over the local error tolerance even in 16 sub-steps{from} (the worst at {:.1e} times it): from there on the motion is less accurate than the tolerance asks (the energy balance still holds on every step); a smaller h makes fewer such steps",
                        b.inexact,
                        b.worst_error
                    )?;
                }
            }
            Some(_) => writeln!(
                f,
                " (adaptive steps: kept by the error control, not checked)"
            )?,
        }
        for w in &self.warnings {
            writeln!(f, "warning   {w}")?;
        }
        if !self.switches.is_empty() {
            let n = self.switches.len();
            writeln!(
                f,
                "switches  {n} {} of coordinates at dead points of the drivers (the CSV stays in the first coordinates and columns throughout):",
                if n == 1 { "change" } else { "changes" }
            )?;
            for s in &self.switches {
                write!(f, "          t = {:.6} s: {} -> {} (", s.time, s.from, s.to)?;
                // The conditioning is the worst group's (a dyad's |sin| of its
                // transmission angle): before the switch, then after it.
                if s.group == "-" {
                    write!(f, "back to the first coordinates: ")?;
                } else {
                    write!(f, "{} at ", s.group)?;
                }
                writeln!(
                    f,
                    "conditioning {:.3e}, then {:.3e})",
                    s.conditioning[0], s.conditioning[1]
                )?;
            }
        }
        if let Some(r) = &self.max_reaction {
            writeln!(
                f,
                "reaction  max {} N at {}, t = {} s",
                Fig(r.value),
                r.joint,
                Fig(r.time)
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
    let (
        Steps {
            n,
            t_end,
            short_last,
            ..
        },
        h,
    ) = Steps::of::<T>(opts)?;
    let every = opts.every.max(1);
    let setup = |e: structomat::SetupError| {
        RunError::Setup(format!("cannot set up {}: {e}", opts.scenario.name()))
    };
    let mut sim = scenario.simulation_with_step(h).map_err(setup)?;
    if short_last {
        // The n-th step lands on t_end; the golden runs, whose t_end is a multiple of h,
        // keep their n·h.
        sim.end_at(T::c(t_end)).map_err(setup)?;
    }
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
    let mut motors = MotorWatch::of(opts);
    let e0 = sim.energy();
    let energy_start = (e0.kinetic.to_f64(), e0.potential.to_f64());

    let start = Instant::now();
    let mut step_wall = Duration::ZERO;
    let mut rows = 0u64;
    let mut max: Option<(usize, f64, f64)> = None;
    // (t, q1) at the start of the mean speed's span.
    let mut from: Option<(f64, f64)> = None;
    let first_averaged = n.div_ceil(2);
    let mut progress = Progress::new(t_end, opts.quiet);
    obs.on_start(&Tables {
        columns: &layout.names,
        logs: &[],
    })?;
    let mut row: Vec<Cell<'_, T>> = Vec::with_capacity(layout.columns.len());
    let mut steps = 0u64;
    let mut first_inexact: Option<f64> = None;
    let outcome = loop {
        // Kinetostatics at the current state (the one at `steps`).
        if let Err(error) = sim.kinetostatics() {
            break Err(Failure::Step {
                kinetostatics: true,
                error,
            });
        }
        if let Some(s) = switching.as_mut() {
            s.evaluate(&sim);
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
        if steps >= first_averaged && from.is_none() {
            from = Some((sim.time().to_f64(), value(Column::Q(0)).to_f64()));
        }
        obs.on_state(State::Mechanism(&sim));
        let stop = interrupt::requested();
        // The last state is always written (`--every N` or not, stopped or not).
        if steps % every == 0 || steps == n || stop {
            write_row(&layout, &sim, &switching, &mut row, obs)?;
            rows += 1;
        }
        if steps == n || stop {
            break Ok(stop);
        }
        progress.tick(sim.time().to_f64());
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
            // The last good state's row, if `--every` skipped it (its kinetostatics
            // passed before the step).
            if steps % every != 0 && sim.kinetostatics().is_ok() {
                if let Some(s) = switching.as_mut() {
                    s.evaluate(&sim);
                }
                write_row(&layout, &sim, &switching, &mut row, obs)?;
                rows += 1;
            }
            break Err(failure.located(&sim, &mut switching));
        }
        steps += 1;
        if first_inexact.is_none() && sim.balance().inexact > 0 {
            first_inexact = Some(sim.time().to_f64());
        }
        motors.check(&sim, &switching);
    };
    let wall = start.elapsed();
    progress.finish();
    obs.on_end()?;
    let (interrupted, singular) = match outcome {
        Ok(stop) => (stop, None),
        Err(Failure::Singular(e)) => (false, Some(SingularEnd::of(&e))),
        Err(Failure::Step {
            kinetostatics,
            error,
        }) => {
            return Err(RunError::Step {
                steps,
                kinetostatics,
                rows,
                error,
                warnings: motors.warnings,
            })
        }
        Err(Failure::Integrator(error)) => return Err(RunError::Integrator { steps, rows, error }),
    };
    let e1 = sim.energy();
    if let Some(s) = switching.as_mut() {
        s.evaluate(&sim);
    }
    // The first coordinates, also while another choice drives.
    let at = |c: Column| {
        switching
            .as_ref()
            .and_then(|s| s.value(c, &sim))
            .unwrap_or_else(|| Layout::value(c, &sim))
            .to_f64()
    };
    let (q_end, qd_end): (Vec<f64>, Vec<f64>) = (0..model.dof())
        .map(|j| (at(Column::Q(j)), at(Column::Qd(j))))
        .unzip();
    let mean_speed = from.filter(|_| model.dof() > 0).map(|(t0, q0)| {
        let (t1, q1) = (sim.time().to_f64(), at(Column::Q(0)));
        MeanSpeed {
            coord: 0,
            from: t0,
            to: t1,
            // A span of no length (a run of one step): the speed there.
            value: if t1 > t0 {
                (q1 - q0) / (t1 - t0)
            } else {
                at(Column::Qd(0))
            },
            angular,
        }
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
        interrupted,
        singular,
        warnings: motors.warnings,
        balance: {
            let b = sim.balance();
            Metered {
                motor_work: b.motor_work.to_f64(),
                load_work: b.load_work.to_f64(),
                residual: b.residual().to_f64(),
                worst: b.worst.to_f64(),
                redone: b.redone,
                substeps: b.substeps,
                redone_energy: b.redone_energy,
                redone_error: b.redone_error,
                inexact: b.inexact,
                worst_error: b.worst_error.to_f64(),
                first_inexact,
            }
        },
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

/// Writes the row of `sim`'s state (its kinetostatics done) in the columns of `layout`
/// to `obs`, in `row`'s buffer.
fn write_row<T: Real>(
    layout: &Layout,
    sim: &Simulation<T>,
    switching: &Option<Switching<T>>,
    row: &mut Vec<Cell<'_, T>>,
    obs: &mut dyn Observer<T>,
) -> Result<(), RunError> {
    row.clear();
    row.extend(layout.columns.iter().map(|c| {
        let v = switching
            .as_ref()
            .and_then(|s| s.value(*c, sim))
            .unwrap_or_else(|| Layout::value(*c, sim));
        Cell::Num(v)
    }));
    obs.on_row(row)
}

/// The motors' working zones ([`crate::model::runfile::MotorSpec::working_zone`]) and the warnings about
/// them.
struct MotorWatch {
    /// Per driver with a quadratic characteristic: its coordinate, its zone (rad/s),
    /// whether it was warned about.
    zones: Vec<(usize, (f64, f64), bool)>,
    /// The warnings so far (set-up's first).
    warnings: Vec<String>,
}

impl MotorWatch {
    /// The drivers' motors of `opts`'s run file, with their set-up warnings.
    fn of(opts: &RunOptions) -> MotorWatch {
        let mut w = MotorWatch {
            zones: Vec::new(),
            warnings: Vec::new(),
        };
        let Ok(file) = opts.scenario.run_file() else {
            return w;
        };
        let Body::Mechanism(m) = &file.body else {
            return w;
        };
        for (k, d) in m.drivers.iter().enumerate() {
            let Some(motor) = d.motor else { continue };
            if let Some(text) = motor.warning() {
                w.warnings
                    .push(format!("driver {} (q{}): {text}", k + 1, k + 1));
            }
            if let Some(zone) = motor.working_zone() {
                w.zones.push((k, zone, false));
            }
        }
        w
    }

    /// Warns, once per motor, when its speed at `sim`'s state has left its working zone
    /// (past the zone's ends by more than 1e-6 of its width: a motor settling at `ω_s`
    /// may overshoot it by rounding).
    fn check<T: Real>(&mut self, sim: &Simulation<T>, switching: &Option<Switching<T>>) {
        // The drivers' own speeds: the first coordinates', also while another choice
        // drives.
        let first = switching.as_ref().map(|s| s.first_qd(sim));
        let qd = first.as_ref().map_or(sim.qd(), |q| &q[..]);
        for (k, (lo, hi), warned) in self.zones.iter_mut() {
            let w = qd.get(*k).map_or(0.0, |v| v.to_f64());
            let slack = 1e-6 * (*hi - *lo).clamp(1.0, 1e6);
            if *warned || (*lo - slack..=*hi + slack).contains(&w) {
                continue;
            }
            *warned = true;
            self.warnings.push(format!(
                "driver {} (q{}): at t = {} s its motor turns at {} rad/s, outside its working \
                 zone [{}, {}] rad/s: the characteristic's torque there grows with the speed \
                 (past the upper end) or the motor turns backward (below 0), and the motion \
                 may run away",
                *k + 1,
                *k + 1,
                Sci(sim.time().to_f64()),
                Sci(w),
                Sci(*lo),
                Sci(*hi)
            ));
        }
    }
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
    /// The next step met a singularity of the mechanism, located inside it: the run's
    /// end (the error's time is the located one).
    Singular(StepError),
}

impl Failure {
    /// The next step's failure.
    fn step(error: StepError) -> Self {
        Failure::Step {
            kinetostatics: false,
            error,
        }
    }

    /// A step's failure at a singularity of the mechanism (or its energy balance broken
    /// on the way into one) with the time located inside the step
    /// ([`Simulation::locate_singularity`], in every choice of coordinates when the
    /// mechanism has alternatives: [`Switching::locate_singularity`]):
    /// [`Failure::Singular`]; the others as they are.
    fn located<T: Real>(self, sim: &Simulation<T>, switching: &mut Option<Switching<T>>) -> Self {
        match self {
            Failure::Step {
                kinetostatics: false,
                error,
            } if at_singularity(&error) || matches!(error, StepError::EnergyBalance { .. }) => {
                let mut scratch = Box::new(structomat::Workspace::new());
                let span = if at_singularity(&error) { 1 } else { 2 };
                let found = match switching.as_mut() {
                    Some(s) => s.locate_singularity(sim, &mut scratch, span),
                    None => sim.locate_singularity(&mut scratch, span),
                };
                match found {
                    Some((_, e)) => Failure::Singular(e),
                    None => Failure::step(error),
                }
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
