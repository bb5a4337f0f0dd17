//! The twin: fixed-step DP5 on the current mode's model, with the mechanical diode's
//! events located inside the step from the dense output, the new mode chosen by SPEC 3's
//! consistency conditions, plastic impacts, and coordinate switches at dead points.
//!
//! Work per step is bounded: at most [`MAX_EVENTS_PER_STEP`] events, each located in at
//! most [`MAX_LOCATE_ITER`] evaluations and settled by at most 7 candidate modes; at
//! most [`MAX_RETRIES`] coordinate switches after a failed sub-step. When a step holds
//! more events than the bound, the rest of the step is integrated in the last mode
//! chosen and the pending sign changes are handled at the start of the next step (the
//! event functions are re-checked there): no event is lost, it is late by under one
//! step, and the twin cannot chatter.

use super::build::{driving_link, dyads_conditioning, initial_pose, BRANCHES, CRANK, ROCKER};
use super::mode::{Clutch, Coordinates, Mode};
use super::params::CccParams;
use super::slot::{
    physical, physical_energy, unwrap_near, Equations, Inputs, LinkState, Slot, QD, STATE, W_LOAD,
    W_MOTOR,
};
use crate::dynamics::finish_accelerations;
use crate::error::{GroupFault, GroupId, ModelError, StepError};
use crate::integrator::Dp5;
use crate::kinetostatics::reactions;
use crate::scalar::{Real, Vec2};
use crate::structomat::GroupData;
use core::fmt;
use nalgebra::{SMatrix, SVector};

/// Events per step at most (see the module docs for what happens past it).
pub const MAX_EVENTS_PER_STEP: usize = 4;
/// Evaluations spent locating one event at most (Illinois regula falsi).
pub const MAX_LOCATE_ITER: usize = 16;
/// Coordinate switches after a failed sub-step at most.
pub const MAX_RETRIES: usize = 2;
/// An event is located to this fraction of the step (1e-12 s at h = 1e-4 s; f32: 8 ulps,
/// see `Twin::locate`).
const THETA_TOL: f64 = 1e-8;
/// Ulps of the largest link speed by which a free lever must pass the shaft for a catch
/// to fire (see [`Twin::guards_of`]).
const CATCH_ULPS: f64 = 16.0;
/// Sub-steps tried in turn when a step breaks the energy balance (see
/// [`TwinSettings::energy_tol`]): at most 1 + 4 + 16 DP5 steps' work.
pub const SUBSTEPS: [u32; 3] = [1, 4, 16];

/// Settings fixed at start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinSettings<T> {
    /// The fixed step, s.
    pub h: T,
    /// `false`: no clutch at all (SPEC 3's free mode, thesis 7.1), the levers swing freely.
    pub clutch: bool,
    /// Initial crank angle q1, rad.
    pub crank: T,
    /// Initial swing-link angle q2, rad.
    pub swing: T,
    /// Initial crank speed, rad/s.
    pub crank_speed: T,
    /// Initial swing-link speed, rad/s.
    pub swing_speed: T,
    /// Under this normalized determinant of a group, other coordinate choices are tried
    /// (a dead point of the coordinates is coming); one is taken if it is at least 1.5
    /// times better.
    pub switch_below: T,
    /// Largest change of the audit residual over one step, relative to 1 J plus the
    /// motor work and the kinetic and potential energies. A step past it is redone in
    /// [`SUBSTEPS`]; if even the finest fails, the step fails with
    /// [`TwinError::Diverged`] and the twin keeps its last good state. S2's steps stay
    /// under 4e-11; S1's last steps before the diode stretches grow past 1e-9 each.
    /// Reference: 1e-9, or 1000 ulps of the scalar if that is larger (f32).
    pub energy_tol: T,
}

impl<T: Real> TwinSettings<T> {
    /// SPEC 3's initial state (q1 = 105°, q2 = 90°, at rest) with the diode, at step `h`.
    pub fn reference(h: T) -> Self {
        TwinSettings {
            h,
            clutch: true,
            crank: T::c(105f64.to_radians()),
            swing: T::c(90f64.to_radians()),
            crank_speed: T::zero(),
            swing_speed: T::zero(),
            switch_below: T::c(0.2),
            // f32 rounds the energies to ~1e-7 of their size: 1e3 ulps then.
            energy_tol: T::c(1e-9).max(T::EPS * T::c(1e3)),
        }
    }
}

/// What made the mode change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventKind {
    /// The consistent mode at the start.
    Start,
    /// The inputs changed and the mode was no longer consistent.
    Inputs,
    /// A free lever (6 or 8) reached the shaft's speed in the drive direction.
    Catch(u8),
    /// A locked or engaged lever's transmitted torque fell to 0.
    Release(u8),
    /// The locked levers' transmitted torque rose to the load T_r.
    Breakaway,
    /// The shaft's speed fell to 0.
    ShaftStop,
}

impl EventKind {
    /// A short name for logs.
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Start => "start",
            EventKind::Inputs => "inputs",
            EventKind::Catch(6) => "catch6",
            EventKind::Catch(_) => "catch8",
            EventKind::Release(6) => "release6",
            EventKind::Release(_) => "release8",
            EventKind::Breakaway => "breakaway",
            EventKind::ShaftStop => "shaft-stop",
        }
    }
}

/// A mode change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event<T> {
    /// Time, s.
    pub time: T,
    /// What fired.
    pub kind: EventKind,
    /// Mode before.
    pub from: Mode,
    /// Mode chosen.
    pub to: Mode,
    /// Transmitted torques `[c6, c8]` in the new mode, N·m.
    pub c: [T; 2],
    /// Kinetic energy lost in the plastic impact, J (0 without one).
    pub impact_loss: T,
    /// Relative speed of the levers projected away by the impact, rad/s.
    pub mismatch: T,
    /// Whether the new mode met every consistency condition (SPEC 3); `false` when
    /// none did and the least violating one was taken.
    pub consistent: bool,
    /// Largest distance between a joint placed by the old mode's model and by the new
    /// one at the event, m.
    pub position_gap: T,
    /// Largest difference between a link's speed in the new model and the speed it
    /// should have after the impact projection, rad/s.
    pub speed_gap: T,
}

/// A change of independent coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoordinateSwitch<T> {
    /// Time, s.
    pub time: T,
    /// The mode.
    pub mode: Mode,
    /// Coordinates before.
    pub from: Coordinates,
    /// Coordinates after.
    pub to: Coordinates,
    /// Smallest normalized determinant of the sequence before, and after.
    pub conditioning: [T; 2],
    /// Largest distance between a joint placed by the two sequences, m.
    pub position_gap: T,
    /// Largest difference between a link's angular speed in the two, rad/s.
    pub speed_gap: T,
}

/// A group that failed in one coordinate choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    /// The coordinate choice.
    pub coords: Coordinates,
    /// The group, in physical link numbers.
    pub group: GroupId,
    /// Why.
    pub fault: GroupFault,
}

/// Why the twin could not be set up or step. A failed step leaves the last good state.
#[derive(Clone, Debug, PartialEq)]
pub enum TwinError {
    /// A parameter is invalid.
    Model(ModelError),
    /// A setting or an input is invalid.
    Setting(&'static str),
    /// An evaluation failed (not a group: a non-finite input, a singular mass matrix).
    Step(StepError),
    /// Every coordinate choice of the mode fails here: a singularity of the mechanism
    /// itself (SPEC 3: its constraints lose rank), or a dead point of every choice the
    /// mode has.
    Mechanism {
        /// Time, s.
        time: f64,
        /// The mode.
        mode: Mode,
        /// The group that fails in each choice.
        failures: heapless::Vec<Failure, 3>,
    },
    /// One step breaks the energy balance past [`TwinSettings::energy_tol`] even in the
    /// finest [`SUBSTEPS`]: the motion runs into a singularity of the mechanism faster
    /// than the step can follow (the worst group's conditioning is then near 0), or
    /// the step is far too coarse for the motion. Names the worst-conditioned group.
    Diverged {
        /// Time at the start of the step, s.
        time: f64,
        /// The mode.
        mode: Mode,
        /// Change of the audit residual over the step, J.
        jump: f64,
        /// The worst-conditioned group of the sequence (fault: its conditioning).
        worst: Failure,
    },
    /// A diode branch's rod and lever came in line (stretched, |DH| = rod + lever, or
    /// folded) and the step could not go on: a singularity of the mechanism itself
    /// (SPEC 3, the end of S1). The branch's dyad loses rank; with the reference's equal
    /// branches both come in line at once, G and I meet, and the two branches'
    /// constraints become one. Replaces the [`TwinError::Mechanism`] or singular
    /// [`TwinError::Diverged`] error it explains.
    Diode {
        /// Time of the last good state, s (the failing step starts there).
        time: f64,
        /// The mode.
        mode: Mode,
        /// |DH| at the last good state, m.
        reach: f64,
        /// Per branch (rod 5 and lever 6, rod 7 and lever 8): |sin| of the angle between
        /// rod and lever at the last good state (0: in line).
        sines: [f64; 2],
        /// Per branch: whether it is named in line: |sin| under
        /// [`SINGULAR_CONDITIONING`], or closing so fast that it reaches 0 within
        /// [`DIODE_HORIZON_STEPS`] steps at its present rate.
        in_line: [bool; 2],
        /// Per branch: |sin| over its rate of decrease, s (the time to in line at the
        /// present rate; infinite when it is not closing).
        closing_in: [f64; 2],
        /// Rod plus lever of each branch, m (the stretched reach).
        stretched_reach: [f64; 2],
    },
    /// A turning shaft with J_s > 0 would leave both levers and coast: not modelled.
    Coasting {
        /// Time, s.
        time: f64,
    },
}

impl fmt::Display for TwinError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TwinError::Model(e) => write!(f, "converter: {e}"),
            TwinError::Setting(s) => write!(f, "converter: {s}"),
            TwinError::Step(e) => write!(f, "{e}"),
            TwinError::Mechanism {
                time,
                mode,
                failures,
            } => {
                write!(
                    f,
                    "t = {time:.6} s: mode {mode}: no coordinate choice drives the mechanism here (a singularity of the mechanism, or a dead point of every choice the mode has): "
                )?;
                for (k, x) in failures.iter().enumerate() {
                    let sep = if k == 0 { "" } else { "; " };
                    write!(f, "{sep}{} coordinates: {} {}", x.coords, x.group, x.fault)?;
                }
                Ok(())
            }
            TwinError::Diverged {
                time,
                mode,
                jump,
                worst,
            } => write!(
                f,
                "t = {time:.6} s: mode {mode}: one step breaks the energy balance by {jump:.3e} J even in {} sub-steps: {} (worst group in {} coordinates: {} {})",
                SUBSTEPS[SUBSTEPS.len() - 1],
                if self.at_singularity() {
                    "a singularity of the mechanism is near"
                } else {
                    "the step is too coarse for the motion"
                },
                worst.coords,
                worst.group,
                worst.fault
            ),
            TwinError::Diode {
                time,
                mode,
                reach,
                sines,
                stretched_reach,
                in_line,
                closing_in,
            } => {
                write!(
                    f,
                    "t = {time:.6} s: mode {mode}: a singularity of the mechanism: the diode's rods and levers in line, "
                )?;
                let mut first = true;
                for (k, (rod, lever)) in BRANCHES.into_iter().enumerate() {
                    let (Some(sine), Some(full), Some(true), Some(within)) = (
                        sines.get(k),
                        stretched_reach.get(k),
                        in_line.get(k).copied(),
                        closing_in.get(k),
                    ) else {
                        continue;
                    };
                    let sep = if first { "" } else { " and " };
                    let how = if *reach > full * 0.5 {
                        "stretched"
                    } else {
                        "folded"
                    };
                    write!(f, "{sep}RRR({rod},{lever}) {how} (|sin| {sine:.1e}")?;
                    if *sine >= SINGULAR_CONDITIONING {
                        write!(f, ", in line in {:.2} ms at its rate", within * 1e3)?;
                    }
                    f.write_str(")")?;
                    first = false;
                }
                write!(
                    f,
                    ", |DH| = {reach:.7} m of rod + lever = {:.7} m: their constraints lose rank, no coordinate choice drives it",
                    stretched_reach[0]
                )
            }
            TwinError::Coasting { time } => write!(
                f,
                "t = {time:.6} s: the shaft would coast free of both levers (J_s > 0), which is not modelled"
            ),
        }
    }
}

impl core::error::Error for TwinError {}

/// Below this conditioning of its worst group, a [`TwinError::Diverged`] step is taken
/// to run into a singularity of the mechanism rather than to be too coarse.
pub const SINGULAR_CONDITIONING: f64 = 1e-2;

/// A diode branch whose rod and lever come in line within this many steps at their
/// present rate counts as in line when a step fails ([`TwinError::Diode`]). In f64 the
/// branch's |sin| is under [`SINGULAR_CONDITIONING`] by then; in f32 rounding breaks
/// the energy balance 8 to 16 steps before (S1 at h = 1e-4 s: 0.3227 s against f64's
/// 0.3238 s), at |sin| of 3e-2 to 6e-2.
pub const DIODE_HORIZON_STEPS: f64 = 32.0;

impl TwinError {
    /// Whether the twin stopped at a singularity of the mechanism itself (SPEC 3: the
    /// end of S1), rather than at a bad input, a setting or a step too coarse.
    pub fn at_singularity(&self) -> bool {
        match self {
            TwinError::Mechanism { .. } | TwinError::Diode { .. } => true,
            TwinError::Diverged { worst, .. } => matches!(
                worst.fault,
                GroupFault::Singular { conditioning } if conditioning < SINGULAR_CONDITIONING
            ),
            _ => false,
        }
    }
}

impl From<ModelError> for TwinError {
    fn from(e: ModelError) -> Self {
        TwinError::Model(e)
    }
}

/// The energy audit (SPEC 3): `motor work = Δ(kinetic + potential) + load work + impact
/// losses`, each term in J since the start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Audit<T> {
    /// Work of the motor on the crank.
    pub motor_work: T,
    /// Work done against the load on the shaft.
    pub load_work: T,
    /// Kinetic energy lost in plastic impacts.
    pub impact_loss: T,
    /// Kinetic energy now (links and shaft).
    pub kinetic: T,
    /// Potential energy now (gravity).
    pub potential: T,
    /// Kinetic plus potential energy at the start.
    pub initial: T,
}

impl<T: Real> Audit<T> {
    /// `motor work - Δ(kinetic + potential) - load work - impact losses`, J.
    pub fn residual(&self) -> T {
        self.motor_work
            - (self.kinetic + self.potential - self.initial)
            - self.load_work
            - self.impact_loss
    }
}

/// Which event functions are watched, their values: `[catch6, catch8, release6,
/// release8, breakaway, shaft stop]`; an event fires when its function goes from ≤ 0 to
/// > 0 over a step.
type Guards<T> = [Option<T>; 6];

/// The event functions that are speeds (catches, shaft stop), as bits of [`fired`]:
/// the kinematics up to the velocities evaluate them, with no equations of motion and
/// no kinetostatics.
const SPEED_GUARDS: u8 = 0b10_0011;

/// The twin of one converter.
#[derive(Clone, Debug)]
pub struct Twin<T: Real> {
    params: CccParams<T>,
    settings: TwinSettings<T>,
    drive: T,
    /// The current slot, the backup and the candidate slot ([`Slots`]).
    slots: Slots<T>,
    reference: Slot<T>,
    dp5: Dp5<T, STATE>,
    y: SVector<T, STATE>,
    t: T,
    steps: u64,
    inputs: Inputs<T>,
    links: [LinkState<T>; 9],
    shaft_angle: T,
    c: [T; 2],
    joints: [Vec2<T>; 11],
    guards: Guards<T>,
    /// Time derivatives of the speed event functions at the last full evaluation
    /// (rad/s²; `None` for the others): the slopes of [`hermite_root`]'s interpolant.
    guard_rates: Guards<T>,
    /// The event functions at the start of the last DP5 step, if it had no event, and
    /// its length (s): a third sample of a torque function for [`quadratic_root`], a
    /// fifth of a speed function for [`hermite_root`].
    last_guards: Option<(Guards<T>, T)>,
    audit: Audit<T>,
    events: heapless::Vec<Event<T>, MAX_EVENTS_PER_STEP>,
    switches: heapless::Vec<CoordinateSwitch<T>, { MAX_RETRIES + 1 }>,
    candidates: heapless::Vec<(Mode, T), 8>,
    speed_gap: T,
    /// `c` came from the mode choice's screen (see [`Twin::try_candidate`]), or is the
    /// last one's, the kinetostatics deferred at a speed event (see
    /// [`Twin::finish_step`]), not from the current slot's kinetostatics: a state is
    /// committed only with the latter, which a re-evaluation of it (after a failed
    /// step) reproduces.
    c_screened: bool,
    /// The last candidate [`Twin::try_candidate`] judged is the reference model itself
    /// (I0, evaluated at the candidate's state), not the scratch slot: taking it swaps
    /// the two.
    cand_in_reference: bool,
}

/// Each group's unknowns, as a step found them.
type GroupUnknowns<T> = [[T; crate::config::MAX_GROUP_VARS]; crate::config::MAX_GROUPS];
/// Their cosines and sines (`GroupData::trig`).
type GroupTrig<T> = [[Vec2<T>; crate::config::MAX_GROUP_VARS]; crate::config::MAX_GROUPS];

/// The working state of a step, committed only when the whole step succeeds.
struct Work<T: Real> {
    t: T,
    y: SVector<T, STATE>,
    impact: T,
    switched: bool,
    /// The mode choice took a mode in this step, and with it the coordinate choice
    /// [`Twin::try_candidate`] found best at the event.
    chosen: bool,
}

impl<T: Real> Twin<T> {
    /// A twin of `params` from `settings`' initial state, its first mode chosen by the
    /// consistency conditions under `inputs`.
    pub fn new(
        params: CccParams<T>,
        settings: TwinSettings<T>,
        inputs: Inputs<T>,
    ) -> Result<Self, TwinError> {
        params.validate()?;
        if !(settings.h.finite() && settings.h > T::zero()) {
            return Err(TwinError::Setting("step h must be positive and finite"));
        }
        if !(settings.switch_below.finite()
            && settings.switch_below > T::zero()
            && settings.switch_below < T::one())
        {
            return Err(TwinError::Setting("switch_below must be in (0, 1)"));
        }
        if !(settings.energy_tol.finite() && settings.energy_tol > T::zero()) {
            return Err(TwinError::Setting("energy_tol must be positive and finite"));
        }
        for (x, what) in [
            (settings.crank, "the initial crank angle must be finite"),
            (
                settings.swing,
                "the initial swing-link angle must be finite",
            ),
            (
                settings.crank_speed,
                "the initial crank speed must be finite",
            ),
            (
                settings.swing_speed,
                "the initial swing-link speed must be finite",
            ),
        ] {
            if !x.finite() {
                return Err(TwinError::Setting(what));
            }
        }
        check_inputs(&inputs)?;
        let pose =
            initial_pose(&params, settings.crank, settings.swing).ok_or(TwinError::Setting(
                "the converter cannot assemble at the initial crank and swing angles",
            ))?;
        let mode = if settings.clutch {
            Mode::I0
        } else {
            Mode::Free
        };
        let (mut slot, mut spare) = (Slot::empty(), Slot::empty());
        let q = best_slot(&params, mode, &pose, 0.0, &mut slot, &mut spare)?;
        let mut y = SVector::<T, STATE>::zeros();
        // Initial link speeds: those of the crank and the swing link (the others follow
        // from the kinematics; the first choice of a 2-DOF mode is crank + swing link).
        let mut omega = [T::zero(); 9];
        omega[CRANK] = settings.crank_speed;
        omega[4] = settings.swing_speed;
        load_state(&slot, &q, &omega, &mut y);
        if y.iter().any(|v| !v.finite()) {
            return Err(TwinError::Setting("initial state is not finite"));
        }
        let mut twin = Twin {
            drive: params.drive.sign(),
            params,
            settings,
            reference: slot.clone(),
            slots: Slots {
                s: [slot.clone(), slot, spare],
                role: [0, 1, 2],
            },
            dp5: Dp5::new(),
            y,
            t: T::zero(),
            steps: 0,
            inputs,
            links: [LinkState::default(); 9],
            shaft_angle: T::zero(),
            c: [T::zero(); 2],
            joints: [Vec2::zeros(); 11],
            guards: [None; 6],
            guard_rates: [None; 6],
            last_guards: None,
            audit: Audit::default(),
            events: heapless::Vec::new(),
            switches: heapless::Vec::new(),
            candidates: heapless::Vec::new(),
            speed_gap: T::zero(),
            c_screened: false,
            cand_in_reference: false,
        };
        for (p, l) in twin.links.iter_mut().enumerate() {
            l.theta = pose[p];
        }
        let mut w = Work {
            t: T::zero(),
            y: twin.y,
            impact: T::zero(),
            switched: false,
            chosen: false,
        };
        twin.finish(&mut w, &inputs)?;
        if settings.clutch {
            twin.choose(&mut w, EventKind::Start, &inputs)?;
        }
        twin.settle_clutch_torques(&w, &inputs)?;
        twin.y = w.y;
        let links = twin.slots.cur().links(&twin.params);
        let audit = twin.audit_of(&links, &w);
        audit_finite(&audit, w.t)?;
        twin.commit(&w, audit, links);
        let (k, u) = (twin.audit.kinetic, twin.audit.potential);
        twin.audit.initial = k + u;
        Ok(twin)
    }

    /// One step of `h` under `inputs` (held over the step). On error the twin keeps the
    /// state of the last good step, including what it reports of that step (events,
    /// coordinate switches, the candidates of the last mode choice).
    pub fn step(&mut self, inputs: &Inputs<T>) -> Result<(), TwinError> {
        check_inputs(inputs)?;
        let changed = !same_inputs(&self.inputs, inputs);
        let saved = (self.group_unknowns(), self.group_trig());
        // The last good step's log: an attempt rewrites it. Usually empty (events and
        // switches are rare), so the copy costs next to nothing.
        let log = (
            self.events.clone(),
            self.switches.clone(),
            self.candidates.clone(),
        );
        let mut failure = TwinError::Setting("no sub-step division was tried");
        for (attempt, substeps) in SUBSTEPS.iter().enumerate() {
            self.events.clear();
            self.switches.clear();
            if changed || attempt > 0 {
                self.dp5.invalidate();
            }
            let mut w = self.work_from_state();
            let result = self
                .advance(&mut w, inputs, changed, *substeps)
                .and_then(|()| self.check_energy(&w));
            match result {
                Ok((audit, links)) => {
                    self.y = w.y;
                    self.steps += 1;
                    self.commit(&w, audit, links);
                    self.inputs = *inputs;
                    return Ok(());
                }
                Err(e) => {
                    self.restore(w.switched, &saved);
                    // A group that fails, or an energy balance that breaks, may be a
                    // step too coarse for a fast passage: finer sub-steps may pass it.
                    let retry =
                        matches!(e, TwinError::Mechanism { .. } | TwinError::Diverged { .. });
                    failure = e;
                    if !retry {
                        break;
                    }
                }
            }
        }
        (self.events, self.switches, self.candidates) = log;
        // A step that fails near the diode's limit is the mechanism's singularity, also
        // when rounding (f32) breaks the energy balance some steps before the groups'
        // conditioning falls under SINGULAR_CONDITIONING.
        if matches!(
            failure,
            TwinError::Mechanism { .. } | TwinError::Diverged { .. }
        ) {
            if let Some(e) = self.diode_in_line() {
                return Err(e);
            }
        }
        Err(failure)
    }

    /// [`TwinError::Diode`] if a diode branch's rod and lever are in line at the last
    /// good state: |sin| of their angle under [`SINGULAR_CONDITIONING`], or closing
    /// towards 0 fast enough to get there within [`DIODE_HORIZON_STEPS`] steps
    /// (d|sin Δ|/dt = sign(sin Δ)·cos Δ·(ω_rod − ω_lever), Δ = θ_rod − θ_lever).
    fn diode_in_line(&self) -> Option<TwinError> {
        let reach = (self.joint_position(ROCKER, 2) - self.params.h).norm();
        let horizon = DIODE_HORIZON_STEPS * self.h().to_f64();
        let mut sines = [1.0; 2];
        let mut stretched_reach = [0.0; 2];
        let mut in_line = [false; 2];
        let mut closing_in = [f64::INFINITY; 2];
        for (k, (rod, lever)) in BRANCHES.into_iter().enumerate() {
            let (r, l) = (self.link(rod), self.link(lever));
            let delta = r.theta - l.theta;
            let (sin, cos) = (delta.sin().to_f64(), delta.cos().to_f64());
            let rate = sin.signum() * cos * (r.omega - l.omega).to_f64();
            let sine = sin.abs();
            let within = if rate < 0.0 {
                sine / -rate
            } else {
                f64::INFINITY
            };
            let full = (self.params.link(rod).length + self.params.link(lever).length).to_f64();
            if let (Some(s), Some(fr), Some(il), Some(ci)) = (
                sines.get_mut(k),
                stretched_reach.get_mut(k),
                in_line.get_mut(k),
                closing_in.get_mut(k),
            ) {
                (*s, *fr, *ci) = (sine, full, within);
                *il = sine < SINGULAR_CONDITIONING || within < horizon;
            }
        }
        if !in_line.iter().any(|b| *b) {
            return None;
        }
        Some(TwinError::Diode {
            time: self.t.to_f64(),
            mode: self.slots.cur().mode,
            reach: reach.to_f64(),
            sines,
            stretched_reach,
            in_line,
            closing_in,
        })
    }

    /// A step's working state, starting from the twin's last good state.
    fn work_from_state(&self) -> Work<T> {
        Work {
            t: self.t,
            y: self.y,
            impact: T::zero(),
            switched: false,
            chosen: false,
        }
    }

    /// The audit at the end of a step in `w` (the slot holds its evaluation).
    fn audit_of(&self, links: &[LinkState<T>; 9], w: &Work<T>) -> Audit<T> {
        let shaft = shaft_speed(self.slots.cur().mode, links);
        let frames = self.slots.cur().frames();
        let (kinetic, potential) = physical_energy(&self.params, links, &frames, shaft);
        Audit {
            motor_work: w.y[W_MOTOR],
            load_work: w.y[W_LOAD],
            impact_loss: self.audit.impact_loss + w.impact,
            kinetic,
            potential,
            initial: self.audit.initial,
        }
    }

    /// The audit at the end of the step in `w` and the physical links it is computed
    /// from (the state [`Twin::commit`] takes), or an error if its residual moved past
    /// the tolerance over the step.
    fn check_energy(&self, w: &Work<T>) -> Result<(Audit<T>, [LinkState<T>; 9]), TwinError> {
        let links = self.slots.cur().links(&self.params);
        let a = self.audit_of(&links, w);
        audit_finite(&a, w.t)?;
        let jump = a.residual() - self.audit.residual();
        let scale = T::one() + a.motor_work.abs() + a.kinetic.abs() + a.potential.abs();
        if jump.abs() <= self.settings.energy_tol * scale {
            return Ok((a, links));
        }
        let (group, conditioning) = self.slots.cur().worst_group();
        Err(TwinError::Diverged {
            time: self.t.to_f64(),
            mode: self.slots.cur().mode,
            jump: jump.to_f64(),
            worst: Failure {
                coords: self.slots.cur().coords,
                group,
                fault: GroupFault::Singular {
                    conditioning: conditioning.to_f64(),
                },
            },
        })
    }

    /// Integrates from `w` to the end of the step in at most `substeps` DP5 steps
    /// between events, handling the events and coordinate switches on the way.
    fn advance(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        changed: bool,
        substeps: u32,
    ) -> Result<(), TwinError> {
        let t_end = T::c((self.steps + 1) as f64) * self.settings.h;
        if !t_end.finite() {
            return Err(TwinError::Setting(
                "the time n·h of the next step overflows the scalar type",
            ));
        }
        let h_max = self.settings.h / T::c(substeps as f64);
        if changed {
            // Inputs changed: re-evaluate here and see whether the mode still holds.
            // The torque functions jump with the load: no earlier sample fits.
            self.last_guards = None;
            self.finish(w, inputs)?;
            if self.settings.clutch && self.guards.iter().flatten().any(|g| *g > T::zero()) {
                self.choose(w, EventKind::Inputs, inputs)?;
            }
        }
        let mut retries = 0;
        let mut events = 0;
        while w.t < t_end {
            if self.slots.cur().mode == Mode::Jam {
                // At rest: nothing moves until the inputs make another mode consistent.
                w.t = t_end;
                self.finish(w, inputs)?;
                break;
            }
            let t0 = w.t;
            let y0 = w.y;
            let saved = self.group_unknowns();
            // The last sub-step takes what is left (no sliver of a step from rounding).
            let h = if t_end - t0 > h_max * T::c(1.5) {
                h_max
            } else {
                t_end - t0
            };
            let mut sys = Equations {
                slot: self.slots.cur_mut(),
                inputs,
                drive: self.drive,
            };
            match self.dp5.step(&mut sys, &mut w.t, &mut w.y, h) {
                Ok(_) => {}
                Err(e) => {
                    // Warm starts only: the step goes on from here (the cosines
                    // and sines are taken anew from these unknowns).
                    self.set_group_unknowns(&saved, None);
                    w.t = t0;
                    w.y = y0;
                    if retries >= MAX_RETRIES || !matches!(e, StepError::Group { .. }) {
                        return Err(self.physical_error(e));
                    }
                    retries += 1;
                    self.finish(w, inputs)?;
                    self.switch_coordinates(w, inputs, Some(e))?;
                    continue;
                }
            }
            let (g0, r0) = (self.guards, self.guard_rates);
            // Deferring the kinetostatics costs an extra look at the event functions:
            // only worth it when a speed function is near its crossing (within 4 steps
            // at its rate at the start).
            let may_defer = self.settings.clutch
                && events < MAX_EVENTS_PER_STEP
                && g0.iter().zip(r0.iter()).any(|(g, r)| match (g, r) {
                    (Some(g), Some(r)) => *g + T::c(4.0) * h * r.abs() > T::zero(),
                    _ => false,
                });
            self.finish_step(w, inputs, may_defer.then_some((&g0, h)))?;
            let fired = fired(&g0, &self.guards);
            if fired == 0 || events >= MAX_EVENTS_PER_STEP || !self.settings.clutch {
                self.last_guards = (fired == 0).then_some((g0, h));
                continue;
            }
            events += 1;
            let (theta, kind, evaluated) = self.locate(w, t0, h, (&g0, &r0), fired, inputs)?;
            self.last_guards = None;
            if !evaluated {
                let mut ye = SVector::<T, STATE>::zeros();
                self.dp5.dense(theta, &mut ye);
                w.t = t0 + theta * h;
                w.y = ye;
                // The mode choice reads the old mode's positions and speeds only (the
                // new mode is evaluated in full): no accelerations or kinetostatics.
                self.slots
                    .cur_mut()
                    .eval_speeds(w.t, &w.y)
                    .map_err(|e| self.physical_error(e))?;
            }
            self.choose(w, kind, inputs)?;
        }
        // Coordinates chosen at an event in this step stand until its end: the mode
        // choice took them by the same rule (the first conditioned at least
        // `switch_below`, else the best by 1.5) a fraction of the step ago. Scanning
        // again cost 24k instructions at S2's catches into A68, whose lever choice is
        // then at its dead point (the lever stops as it catches) and fails to assemble
        // each time. The next step's end scans as usual.
        if self.slots.cur().mode != Mode::Jam
            && !w.chosen
            && self.slots.cur().conditioning() < self.settings.switch_below
        {
            self.switch_coordinates(w, inputs, None)?;
        }
        if !same_bits(w.t, t_end) {
            w.t = t_end;
            self.dp5.invalidate();
        }
        self.settle_clutch_torques(w, inputs)
    }

    /// The kinetostatics of the state the step ends at, if its clutch torques are
    /// still the mode choice's screen's (the choice was the step's last evaluation).
    fn settle_clutch_torques(&mut self, w: &Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        if self.c_screened {
            self.finish_evaluated(w, inputs)?;
        }
        Ok(())
    }

    /// The slot new modes and coordinate choices are built in (with the parameters):
    /// the backup until the step first changes the current slot (the backup holds
    /// nothing the step needs until then), the candidate slot after. So
    /// [`Twin::take_candidate`] keeps the pre-step slot as the backup with one swap, no
    /// copy (a slot is 30 KB in f64).
    fn scratch(&mut self, switched: bool) -> (&mut Slot<T>, &CccParams<T>) {
        let (backup, cand) = self.slots.spares();
        (if switched { cand } else { backup }, &self.params)
    }

    /// The slot a candidate is built in: the scratch ([`Twin::scratch`]), or with
    /// `second` before the step changed the current slot (`switched` false), the
    /// candidate slot, the other one free then.
    fn build_slot(&mut self, switched: bool, second: bool) -> (&mut Slot<T>, &CccParams<T>) {
        if second && !switched {
            (self.slots.spares().1, &self.params)
        } else {
            self.scratch(switched)
        }
    }

    /// Makes the scratch slot ([`Twin::scratch`]), which holds the new mode or
    /// coordinates, the current one; the first time in a step the pre-step slot goes
    /// to the backup.
    fn take_candidate(&mut self, w: &mut Work<T>) {
        let r = &mut self.slots.role;
        if w.switched {
            r.swap(0, 2);
        } else {
            r.swap(0, 1);
            w.switched = true;
        }
    }

    /// Back to the state before the step: the pre-step slot (kept by
    /// [`Twin::take_candidate`] if the step changed it) with its group unknowns and
    /// their cosines and sines `saved`.
    fn restore(&mut self, switched: bool, saved: &(GroupUnknowns<T>, GroupTrig<T>)) {
        if switched {
            self.slots.role.swap(0, 1);
        }
        self.set_group_unknowns(&saved.0, Some(&saved.1));
        self.dp5.invalidate();
        self.last_guards = None;
        let mut w = self.work_from_state();
        // It evaluated at this very state before: this cannot fail, and if it did the
        // workspace would merely hold the failed evaluation.
        let inputs = self.inputs;
        let _ = self.finish(&mut w, &inputs);
    }

    fn group_unknowns(&self) -> GroupUnknowns<T> {
        self.per_group(|g| g.x)
    }

    fn group_trig(&self) -> GroupTrig<T> {
        self.per_group(|g| g.trig)
    }

    /// `field` of each group's data in the current slot's workspace.
    fn per_group<X: Default>(
        &self,
        field: impl Fn(&GroupData<T>) -> X,
    ) -> [X; crate::config::MAX_GROUPS] {
        let ws = &self.slots.cur().ws;
        core::array::from_fn(|k| ws.group.get(k).map_or_else(X::default, &field))
    }

    /// Sets the groups' unknowns `x` and, if given, their cosines and sines (those of
    /// `x`, saved with them: a re-evaluation then reproduces the saved state's bits).
    fn set_group_unknowns(&mut self, x: &GroupUnknowns<T>, trig: Option<&GroupTrig<T>>) {
        for (k, (g, x)) in self
            .slots
            .cur_mut()
            .ws
            .group
            .iter_mut()
            .zip(x.iter())
            .enumerate()
        {
            g.x = *x;
            if let Some(cs) = trig.and_then(|t| t.get(k)) {
                g.trig = *cs;
                g.trig_at = *x;
            }
        }
    }

    /// Evaluates the current slot at `w`'s state: equations of motion, accelerations,
    /// kinetostatics, the event functions.
    fn evaluate_at(&mut self, w: &Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        self.slots
            .cur_mut()
            .eval(w.t, &w.y, inputs, self.drive)
            .map_err(|e| self.physical_error(e))?;
        self.finish_evaluated(w, inputs)
    }

    /// [`Twin::evaluate_at`] where the integration goes on from `w`'s state: the next
    /// DP5 step from there takes its first stage from this evaluation.
    fn finish(&mut self, w: &mut Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        self.evaluate_at(w, inputs)?;
        self.seed_first_stage(w, inputs);
        Ok(())
    }

    /// Hands the slot's evaluation at `w`'s state (just made, in full) to the DP5
    /// stepper as the first stage of a step from there: after a mode change or a
    /// coordinate switch the rest of the step then takes 6 evaluations, not 7.
    fn seed_first_stage(&mut self, w: &Work<T>, inputs: &Inputs<T>) {
        let k1 = self.slots.cur().rates(&w.y, inputs, self.drive);
        self.dp5.seed(w.t, &w.y, &k1);
    }

    /// [`Twin::finish`] when the slot's workspace already holds the evaluation of `w`'s
    /// state (after an accepted DP5 step, whose last stage is `f(t1, y1)`, FSAL).
    fn finish_evaluated(&mut self, w: &Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        self.finish_step(w, inputs, None)
    }

    /// [`Twin::finish_evaluated`], except that with `defer` (the event functions `g0`
    /// at the start of the DP5 step of length `h` this state ends, the step to locate
    /// an event that fires) the kinetostatics waits when a speed function fired and
    /// the torque functions cannot have crossed (`torques_can_wait`): the step then goes
    /// on from the event inside it, and this state, with the clutch torques of the
    /// step's start (`c_screened`), is dropped. It spared 7-8k instructions of the
    /// 12-16k kinetostatics of a Newton-group model at S2's slowest event steps. Not
    /// inlined: inlined into `advance` it raised the f32 step's stack high-water from
    /// 9.0 to 11.7 KB (`tests/footprint.rs`).
    #[inline(never)]
    fn finish_step(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
        defer: Option<(&Guards<T>, T)>,
    ) -> Result<(), TwinError> {
        let slot = self.slots.cur_mut();
        finish_accelerations(&slot.model, &mut slot.ws);
        let links = self.slots.cur().links(&self.params);
        // The torque functions from the start's clutch torques: as at the start.
        let deferred = defer
            .filter(|(g0, h)| self.torques_can_wait(g0, *h))
            .is_some_and(|(g0, _)| {
                let g = self.guards_of(self.slots.cur(), &links, &self.c, inputs);
                fired(g0, &g) & SPEED_GUARDS != 0
            });
        if !deferred {
            let slot = self.slots.cur_mut();
            reactions(&slot.model, &mut slot.ws, w.t.to_f64())
                .map_err(|e| self.physical_error(e))?;
        }
        self.read_links(&links, inputs, deferred.then_some(self.c));
        Ok(())
    }

    /// Whether none of the torque functions in `g0` (a release, a breakaway) can cross
    /// 0 over the next `h`: each is below 0 by more than 16 times its change over
    /// the last step without an event (`last_guards`), scaled to `h`. A clutch torque
    /// is a smooth function of the motion (it changes on the time scale of the crank's
    /// turn, ~10 ms in S2): its rate does not grow 16-fold from one step of 1e-4 s to
    /// the next, and a jump (an event, new inputs) clears `last_guards`. A mode
    /// without torque functions (I0) can always wait. Were one to cross anyway, the
    /// mode choice at the speed event still checks every clutch torque.
    fn torques_can_wait(&self, g0: &Guards<T>, h: T) -> bool {
        let k = T::c(16.0);
        g0.iter().enumerate().all(|(i, g)| {
            let Some(a) = g else { return true };
            if SPEED_GUARDS & (1 << i) != 0 {
                return true;
            }
            let Some(b) = self
                .last_guards
                .and_then(|(gl, hp)| gl.get(i).copied().flatten().map(|b| (b, hp)))
                .map(|(b, hp)| (*a - b).abs() * (h / hp))
            else {
                return false;
            };
            *a + k * b < T::zero()
        })
    }

    /// The clutch torques and the event functions from the slot's workspace, which
    /// holds a full evaluation (accelerations and kinetostatics; or accelerations and
    /// the clutch torques `c`, from the mode choice's screen). Not inlined: inlined
    /// into the mode choice it added 3.7 KB to the f64 step's stack high-water
    /// (`tests/footprint.rs`: 19.1 KB instead of 15.5 KB).
    #[inline(never)]
    fn read_evaluation(&mut self, inputs: &Inputs<T>, c: Option<[T; 2]>) {
        let links = self.slots.cur().links(&self.params);
        self.read_links(&links, inputs, c);
    }

    /// [`Twin::read_evaluation`] with the slot's physical `links` at hand.
    fn read_links(&mut self, links: &[LinkState<T>; 9], inputs: &Inputs<T>, c: Option<[T; 2]>) {
        self.c_screened = c.is_some();
        self.c = c.unwrap_or_else(|| self.slots.cur().clutch_torques(&self.params, links));
        self.guards = self.guards_of(self.slots.cur(), links, &self.c, inputs);
        self.guard_rates = self.guard_rates_of(self.slots.cur(), links);
    }

    /// The time derivatives of [`Twin::guards_of`]'s speed functions at `slot`'s
    /// evaluated state (accelerations included): a catch's `d·(α_lever − α_shaft)`, the
    /// shaft stop's `-d·α_shaft` (the catch's tolerance taken as constant).
    fn guard_rates_of(&self, slot: &Slot<T>, links: &[LinkState<T>; 9]) -> Guards<T> {
        let mut r = [None; 6];
        if !self.settings.clutch {
            return r;
        }
        let d = self.drive;
        let mode = slot.mode;
        let shaft = shaft_accel(mode, links);
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(mode.clutches()).enumerate() {
            if clutch == Clutch::Free {
                r[k] = Some(d * (links.get(*lever).map_or(T::zero(), |s| s.alpha) - shaft));
            }
        }
        if mode.shaft_turning() {
            r[5] = Some(-d * shaft);
        }
        r
    }

    /// The event functions of `slot`'s mode at its evaluated state.
    fn guards_of(
        &self,
        slot: &Slot<T>,
        links: &[LinkState<T>; 9],
        c: &[T; 2],
        inputs: &Inputs<T>,
    ) -> Guards<T> {
        let mut g = [None; 6];
        if !self.settings.clutch {
            return g;
        }
        let d = self.drive;
        let mode = slot.mode;
        let shaft = shaft_speed(mode, links);
        let mut locked = T::zero();
        let mut any_locked = false;
        // A release fires when c_k falls below -1e-9 (T_r + 1 N·m) (f32: see torque_tol),
        // not below 0: with T_r = 0 an engaged lever carries exactly 0, and rounding
        // (1e-15 N·m) must not fire a release every few steps. The event moves by
        // 1e-9 N·m / ċ_k, nothing.
        let c_tol = torque_tol(inputs.load + T::one());
        // Likewise a catch fires when a free lever passes the shaft by more than
        // rounding: CATCH_ULPS ulps of the largest link speed (f64: ~1e-13 rad/s, the
        // event moves by nothing). A lever just released or just stopped with the shaft
        // leaves it at exactly the shaft's speed, and in f32 the rounding of its speed
        // (a sum of terms of the crank's magnitude) crossed 0 in the drive direction
        // and fired catches that changed nothing (S2 at h = 2e-4, t = 0.02879 s).
        let w_scale = speed_scale(links);
        let w_tol = T::EPS * T::c(CATCH_ULPS) * w_scale;
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(mode.clutches()).enumerate() {
            let w = links.get(*lever).map_or(T::zero(), |s| s.omega);
            match clutch {
                Clutch::Free => g[k] = Some(d * (w - shaft) - w_tol),
                Clutch::Locked => {
                    g[2 + k] = Some(-(c[k] + c_tol));
                    locked += c[k];
                    any_locked = true;
                }
                Clutch::Engaged => g[2 + k] = Some(-(c[k] + c_tol)),
            }
        }
        if any_locked {
            g[4] = Some(locked - inputs.load);
        }
        if mode.shaft_turning() {
            g[5] = Some(-d * shaft);
        }
        g
    }

    /// Locates the first crossing among the fired event functions inside the last
    /// DP5 step (`t0`, `h`) by Illinois regula falsi on the dense output; returns the
    /// fraction of the step just past the event, which event it is, and whether `w`
    /// and the slot hold that point, evaluated (the last evaluation was there).
    ///
    /// `(g0, r0)`: the event functions and the speed functions' rates at the step's
    /// start. A single speed function fired starts the iteration from the root of its
    /// Hermite interpolant over the step ([`hermite_root`]: the values and rates at
    /// both ends, and the value at the start of the step before if that step had no
    /// event; no evaluation), 4th- or 5th-order accurate. A single torque function
    /// (a release, a breakaway; each evaluation is a full one, kinetostatics included)
    /// starts from the root of its quadratic through the step's ends and the start of
    /// the step before ([`quadratic_root`]), if that step had no event.
    ///
    /// The iteration ends when the bracket is within the tolerance, or sooner when a
    /// point past the crossing is within the tolerance of the secant's crossing through
    /// it and the point before, both `near` the crossing (the secant's error is then
    /// second order in their distances, ~1e-10 of the tolerance), or, for the first
    /// point, of a Newton step back on the Hermite interpolant's slope. Near the
    /// crossing it aims just past it: the first point half the tolerance past the
    /// Hermite root, the next 0.4 tol past the crossing that Newton step or the
    /// secant places. S2's 18 speed events take 1 evaluation, its torque events 2–3,
    /// instead of 2–5: a bracket closed on both sides needs a point on each, and the
    /// cubic's guess was rarely within the tolerance.
    ///
    /// Not inlined, nor is [`Twin::try_candidate`]: with both inlined the f64 step's
    /// stack high-water was 20.6 KB instead of 16.7 KB (`tests/footprint.rs`).
    #[inline(never)]
    fn locate(
        &mut self,
        w: &mut Work<T>,
        t0: T,
        h: T,
        (g0, r0): (&Guards<T>, &Guards<T>),
        fired: u8,
        inputs: &Inputs<T>,
    ) -> Result<(T, EventKind, bool), TwinError> {
        let pick = |g: &Guards<T>| -> (T, usize) {
            let mut best = (T::c(f64::NEG_INFINITY), 0);
            for (k, v) in g.iter().enumerate() {
                if fired & (1 << k) != 0 {
                    if let Some(v) = v {
                        if *v > best.0 {
                            best = (*v, k);
                        }
                    }
                }
            }
            best
        };
        // The caller evaluates the state at the event in full after this.
        let speeds_only = fired & !SPEED_GUARDS == 0;
        let (mut lo, mut hi) = (T::zero(), T::one());
        let (mut glo, _) = pick(g0);
        let (mut ghi, mut which) = pick(&self.guards);
        let mut side = 0i8;
        let mut y = SVector::<T, STATE>::zeros();
        // THETA_TOL, or 8 ulps of the step's fraction if that is larger (f32: 9.5e-7),
        // so that the margin below moves the point by a few ulps at least.
        let tol = T::c(THETA_TOL).max(T::EPS * T::c(8.0));
        let k = fired.trailing_zeros() as usize;
        let single = fired.count_ones() == 1;
        let before = self
            .last_guards
            .and_then(|(g, hp)| g.get(k).copied().flatten().map(|v| (v, hp / h)));
        // Two points this close to each other bracket... or not, but their secant
        // places the crossing to about near²·|g''/g'| (θ units), 1e-10 in f64 for a
        // curvature |g''/g'| of 1 per step: far below `tol`.
        let near = (tol * T::c(0.01)).sqrt();
        let guess = match (
            g0.get(k),
            self.guards.get(k),
            r0.get(k),
            self.guard_rates.get(k),
        ) {
            (Some(Some(a)), Some(Some(b)), Some(Some(ra)), Some(Some(rb)))
                if single && speeds_only =>
            {
                hermite_root(*a, *b, *ra * h, *rb * h, before, tol)
            }
            (Some(Some(a)), Some(Some(b)), _, _) if single && !speeds_only => {
                before.and_then(|(gm, r)| quadratic_root(gm, r, *a, *b, tol))
            }
            _ => None,
        };
        let mut at_hi = false;
        let mut used = 0;
        // The last evaluated point (θ, its event function, not Illinois-scaled), and
        // the interpolant's slope at the guess, for the estimates below.
        let mut last: Option<(T, T)> = None;
        let mut slope = guess.map(|(_, s)| s);
        // The Hermite interpolant's slope where it is trusted to place the crossing
        // from one point past it: positive and within a factor 2 of the slope of the
        // chord over the step (a crossing far from linear is left to the secant).
        let chord = ghi - glo;
        let trusted =
            slope.filter(|s| speeds_only && *s >= chord * T::c(0.5) && *s <= chord * T::c(2.0));
        // The first point aims half the tolerance past the Hermite root, which is off
        // the crossing by under half the tolerance when the step before gives the
        // quartic (all of S2's 18 speed events): it lands past the crossing within the
        // tolerance and is located by the one evaluation (see `trusted` below).
        let mut guess = guess.map(|(th, _)| {
            if trusted.is_some() {
                th + tol * T::c(0.5)
            } else {
                th
            }
        });
        for _ in 0..MAX_LOCATE_ITER {
            if hi - lo <= tol {
                break;
            }
            used += 1;
            // Regula falsi's point, kept at least 0.4 of the tolerance inside the
            // bracket: once the crossing is that close to an end, the next point lands
            // past it and closes the bracket. (Bisecting whenever the point fell within
            // 1% of the bracket of an end, as before, turned the iteration into
            // bisection near convergence: every event of S2 took the 16 evaluations and
            // was located to about 1e-5 of the step, not to the tolerance.)
            // A function exactly 0 at `lo` (f32: the shaft's speed rounds to 0.0 over a
            // stretch of 5e-6 of the step around its stop) puts regula falsi's point on
            // `lo` for good: the margin crept up 0.4 tol per evaluation, the bracket
            // never closed and the event was placed at the step's end, past the lever's
            // reversal (S2 in f32 chose I0 instead of I8 at 0.3073 s). Bisect then.
            //
            // Near the crossing, a sharper estimate aims just past it (see `near`):
            // from the first evaluated point, a Newton step on the interpolant's slope;
            // from two, their secant.
            let margin = tol * T::c(0.4);
            let aimed = match (guess.take(), last) {
                (Some(th), _) => Some(th),
                (None, Some((tp, gp))) => slope.take().map(|s| tp - gp / s + margin),
                (None, None) => None,
            };
            let th = match aimed {
                Some(th) if th.finite() => th.max(lo + margin).min(hi - margin),
                _ if glo != T::zero() => {
                    let rf = (lo * ghi - hi * glo) / (ghi - glo);
                    if rf.finite() {
                        rf.max(lo + margin).min(hi - margin)
                    } else {
                        (lo + hi) * T::c(0.5)
                    }
                }
                _ => (lo + hi) * T::c(0.5),
            };
            self.dp5.dense(th, &mut y);
            w.t = t0 + th * h;
            w.y = y;
            if speeds_only {
                self.slots
                    .cur_mut()
                    .eval_speeds(w.t, &w.y)
                    .map_err(|e| self.physical_error(e))?;
                let links = self.slots.cur().links(&self.params);
                // The clutch torques are those of the last full evaluation: the
                // torque functions are not read (none of them fired).
                self.guards = self.guards_of(self.slots.cur(), &links, &self.c, inputs);
            } else {
                // A point of the bracket, not where the step goes on from: no seed.
                self.evaluate_at(w, inputs)?;
            }
            let (g, k) = pick(&self.guards);
            at_hi = g > T::zero();
            // The secant of this point and the last one, if they are `near`: the
            // crossing to ~near² (the curvature term), far below `tol`. The first
            // point, `near` the Hermite root, takes the interpolant's trusted slope
            // instead: a Newton step from it places the crossing to ~(g/s)² |g''/g'|
            // plus (g/s) times the slope's relative error (S2's second points landed
            // on the crossing this step predicts to 1e-13 of the step).
            let crossing = match (last, trusted) {
                (Some((tp, gp)), _) => Some((tp, gp))
                    .filter(|(tp, _)| (th - *tp).abs() <= near)
                    .map(|(tp, gp)| th - g * (th - tp) / (g - gp)),
                (None, Some(s)) => Some(th - g / s),
                (None, None) => None,
            }
            .filter(|r| r.finite());
            last = Some((th, g));
            if at_hi {
                hi = th;
                ghi = g;
                which = k;
                if side == 1 {
                    glo *= T::c(0.5);
                }
                side = 1;
                // Past the crossing by at most the tolerance: located, though no
                // point on the other side is that close (`lo` becomes the secant's
                // crossing, for the log below).
                if let Some(r) = crossing.filter(|r| th - *r <= tol && *r >= lo) {
                    lo = r;
                    break;
                }
            } else {
                lo = th;
                glo = g;
                if side == -1 {
                    ghi *= T::c(0.5);
                }
                side = -1;
            }
            // Next: aim just past the secant's crossing.
            if let Some(r) = crossing {
                guess = Some(r + margin);
            }
        }
        log::debug!(
            "event functions {fired:#08b}: located to {:?} of the step in {used} evaluations",
            hi - lo
        );
        let kind = match which {
            0 => EventKind::Catch(6),
            1 => EventKind::Catch(8),
            2 => EventKind::Release(6),
            3 => EventKind::Release(8),
            4 => EventKind::Breakaway,
            _ => EventKind::ShaftStop,
        };
        Ok((hi, kind, at_hi))
    }

    /// Physical angles of the slot's links, unwrapped against the last committed ones.
    fn slot_links_unwrapped(&self) -> [T; 9] {
        let links = self.slots.cur().links(&self.params);
        let mut out = [T::zero(); 9];
        for ((o, now), last) in out.iter_mut().zip(&links).zip(&self.links).skip(1) {
            *o = unwrap_near(now.theta, last.theta);
        }
        out
    }

    /// Chooses the consistent mode at `w`'s state (the current slot evaluated there)
    /// after event `kind`, projects the speeds if the new constraints need it (plastic
    /// impact), and switches to it.
    fn choose(
        &mut self,
        w: &mut Work<T>,
        kind: EventKind,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinError> {
        let time = w.t.to_f64();
        let from = self.slots.cur().mode;
        let pose = self.slot_links_unwrapped();
        let links = self.slots.cur().links(&self.params);
        let d = self.drive;
        let shaft = shaft_speed(from, &links);
        let scale_w = speed_scale(&links);
        let tol_w = speed_tol::<T>() * scale_w;
        // Which levers touch the shaft (may lock or engage), and the shaft's options.
        let mut contact = [false; 2];
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(from.clutches()).enumerate() {
            let rel = links.get(*lever).map_or_else(T::zero, |l| l.omega) - shaft;
            contact[k] = clutch != Clutch::Free
                || (rel.abs() <= tol_w)
                || kind == EventKind::Catch(*lever as u8);
        }
        let held_possible =
            !from.shaft_turning() || kind == EventKind::ShaftStop || shaft.abs() <= tol_w;
        let mut cands: heapless::Vec<(u8, Mode), 8> = heapless::Vec::new();
        for turning in [false, true] {
            if !turning && !held_possible {
                continue;
            }
            let hold = if turning {
                Clutch::Engaged
            } else {
                Clutch::Locked
            };
            let options = |k: usize| {
                if contact[k] {
                    [Clutch::Free, hold]
                } else {
                    [Clutch::Free, Clutch::Free]
                }
            };
            for c6 in options(0) {
                for c8 in options(1) {
                    let Some(m) = Mode::from_clutches([c6, c8], turning) else {
                        continue;
                    };
                    if !cands.iter().any(|(_, x)| *x == m) {
                        let _ = cands.push((preference(from, m, kind), m));
                    }
                }
            }
        }
        // Insertion sort by preference (stable: ties keep the enumeration order).
        for i in 1..cands.len() {
            for j in (1..=i).rev() {
                match cands.get_mut(j - 1..=j) {
                    Some([a, b]) if a.0 > b.0 => core::mem::swap(a, b),
                    _ => break,
                }
            }
        }
        // Generalized momentum space of the unconstrained diode: the 2-DOF model, plus the
        // shaft when it has inertia.
        let qr = best_slot(
            &self.params,
            Mode::I0,
            &pose,
            time,
            &mut self.reference,
            self.slots.spares().1,
        )?;
        let mut yr = SVector::<T, STATE>::zeros();
        for k in 0..2 {
            yr[k] = qr[k];
            let p = self.reference.map.coord_link[k] as usize;
            yr[QD + k] = links.get(p).map_or_else(T::zero, |l| l.omega);
        }
        self.reference
            .eval(w.t, &yr, inputs, d)
            .map_err(|e| self.physical_error(e))?;
        let js = self.params.shaft_inertia;
        let with_shaft = js > T::zero();
        let mut mass = SMatrix::<T, 3, 3>::identity();
        for r in 0..2 {
            for c in 0..2 {
                mass[(r, c)] = self.reference.ws.mass_q[(r, c)];
            }
        }
        if with_shaft {
            mass[(2, 2)] = js;
        }
        let u = SVector::<T, 3>::new(
            yr[QD],
            yr[QD + 1],
            if with_shaft { shaft } else { T::zero() },
        );
        let mut best: Option<(T, Mode)> = None;
        let mut chosen = None;
        // The state the reference's workspace was last evaluated at.
        let mut yr_at = yr;
        // Candidates the screen found clearly inconsistent, not built.
        let mut screened_out = false;
        // The clutch torques of the pick if they came from the screen (its model's
        // kinetostatics skipped, see `Twin::try_candidate`).
        let mut chosen_c = None;
        self.candidates.clear();
        for (_, m) in cands.iter().copied() {
            let rows = constraint_rows(m, with_shaft, |lever| self.reference.lever_row(lever));
            let Some((u_plus, loss)) = project(&mass, &u, &rows) else {
                let _ = self.candidates.push((m, T::c(f64::INFINITY)));
                continue; // rank-deficient constraints
            };
            let (violation, c) = match self.screen(m, from, &mut yr_at, &u_plus, w.t, inputs, tol_w)
            {
                Some((v, _)) if v > screen_margin::<T>() => {
                    screened_out = true;
                    (v, None)
                }
                screened => {
                    let c = screened.map(|(_, c)| c);
                    self.try_candidate(w, m, &pose, &u_plus, from, inputs, tol_w, c)?
                }
            };
            let _ = self.candidates.push((m, violation));
            if violation <= T::zero() {
                chosen = Some((m, loss, rows_mismatch(&rows, &u), true));
                chosen_c = c;
                break;
            }
            if best.as_ref().is_none_or(|(v, _)| violation < *v) {
                best = Some((violation, m));
            }
        }
        if chosen.is_none() && screened_out {
            // No candidate is consistent: the least violating one is taken, so every
            // candidate's violation is the built model's, as when none is screened.
            best = None;
            for i in 0..self.candidates.len() {
                let Some(&(m, mut v)) = self.candidates.get(i) else {
                    break;
                };
                if v.finite() {
                    let rows =
                        constraint_rows(m, with_shaft, |lever| self.reference.lever_row(lever));
                    if let Some((u_plus, _)) = project(&mass, &u, &rows) {
                        v = self
                            .try_candidate(w, m, &pose, &u_plus, from, inputs, tol_w, None)?
                            .0;
                    }
                }
                if let Some(c) = self.candidates.get_mut(i) {
                    c.1 = v;
                }
                if best.as_ref().is_none_or(|(b, _)| v < *b) {
                    best = Some((v, m));
                }
            }
        }
        let (m, loss, mismatch, consistent) = match chosen {
            Some(x) => x,
            None => {
                let Some((v, m)) = best else {
                    return Err(TwinError::Mechanism {
                        time,
                        mode: from,
                        failures: heapless::Vec::new(),
                    });
                };
                log::warn!(
                    "t = {time:.6} s: no mode is consistent after {}; taking {m} (violation {v:?})",
                    kind.name()
                );
                let rows = constraint_rows(m, with_shaft, |lever| self.reference.lever_row(lever));
                let (u_plus, loss) = project(&mass, &u, &rows).unwrap_or((u, T::zero()));
                self.try_candidate(w, m, &pose, &u_plus, from, inputs, tol_w, None)?;
                (m, loss, rows_mismatch(&rows, &u), false)
            }
        };
        if m.shaft_turning() && with_shaft && m.clutches().iter().all(|c| *c == Clutch::Free) {
            return Err(TwinError::Coasting { time });
        }
        // The candidate slot holds the chosen mode, evaluated: take it. If that was the
        // reference model, it becomes the scratch slot first (a swap, ~4k
        // instructions in f64), and the scratch's model is the reference's until the
        // next event repositions or rebuilds it.
        if self.cand_in_reference {
            let (backup, cand) = self.slots.spares();
            core::mem::swap(&mut self.reference, if w.switched { cand } else { backup });
        }
        self.take_candidate(w);
        w.chosen = true;
        w.y = self.cand_state(w);
        w.impact += loss;
        self.dp5.invalidate();
        if consistent {
            // `try_candidate` evaluated the chosen mode in full (kinetostatics
            // included, or its clutch torques `chosen_c` from the screen) at this very
            // state, `w.y` being read back from it: evaluating again would give the
            // same bits.
            self.read_evaluation(inputs, chosen_c);
            self.seed_first_stage(w, inputs);
        } else {
            self.finish(w, inputs)?;
        }
        let after = self.slots.cur().links(&self.params);
        let position_gap = joint_gap(&self.params, &links, &after);
        log::info!(
            "t = {time:.6} s: {} -> {m} ({}, {} coordinates, impact loss {loss:?} J)",
            from,
            kind.name(),
            self.slots.cur().coords
        );
        let _ = self.events.push(Event {
            time: w.t,
            kind,
            from,
            to: m,
            c: self.c,
            impact_loss: loss,
            mismatch,
            consistent,
            position_gap,
            speed_gap: self.speed_gap,
        });
        Ok(())
    }

    /// The state vector of the slot just taken (stored by [`Twin::try_candidate`]).
    fn cand_state(&self, w: &Work<T>) -> SVector<T, STATE> {
        let mut y = w.y;
        let n = self.slots.cur().map.dof.min(2);
        for k in 0..2 {
            y[k] = if k < n {
                self.slots.cur().ws.q[k]
            } else {
                T::zero()
            };
            y[QD + k] = if k < n {
                self.slots.cur().ws.qd[k]
            } else {
                T::zero()
            };
        }
        y
    }

    /// Builds mode `m` into the candidate slot at `pose` with the projected speeds
    /// `u_plus` (reference coordinates), evaluates it and returns how far it violates
    /// SPEC 3's consistency conditions (0: consistent), and the clutch torques it
    /// took from its screen (`screened`) if they made its kinetostatics unnecessary.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn try_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        pose: &[T; 9],
        u_plus: &SVector<T, 3>,
        from: Mode,
        inputs: &Inputs<T>,
        tol_w: T,
        screened: Option<[T; 2]>,
    ) -> Result<(T, Option<[T; 2]>), TwinError> {
        // Physical angular speeds after the impact, from the reference model's V.
        let mut omega = [T::zero(); 9];
        for (p, o) in omega.iter_mut().enumerate().skip(1) {
            let [v0, v1] = self.reference.omega_row(p);
            *o = v0 * u_plus[0] + v1 * u_plus[1];
        }
        // The first coordinate choice that assembles here, represents these speeds (a
        // choice at its dead point maps them wrongly: the lever of A68 cannot carry a
        // crank turning at its dead point) and is conditioned at least `switch_below`;
        // else the best conditioned of those that carry the speeds (a later one only if
        // 1.5 times better, as in `switch_coordinates`). Near its dead point a choice
        // still carries the speeds, but the rest of the step in it is far off: A6 ->
        // A68 with the lever at 0.003 lost 0.45 J of kinetic energy in one step.
        let scale_w = omega.iter().fold(T::one(), |a, w| a.max(w.abs()));
        // (conditioning, choice, speed gap) of the choice taken, and which slot holds
        // it (`Some(second)`, see `Twin::build_slot`; `None`: none, it was overwritten).
        let mut chosen: Option<(T, Coordinates, T)> = None;
        let mut kept: Option<bool> = None;
        // Before the step changed the current slot, two slots are free: the choice
        // kept so far stays in one while the next is built in the other, so none is
        // built twice (with one slot, a kept choice that a later, worse one overwrote
        // is built again at the end).
        let two = !w.switched;
        // A choice whose coordinate link stands still (under `speed_tol` of the largest
        // speed) while the mechanism moves (a shaft stop can leave it all at rest) is
        // at its dead point: it fails to assemble,
        // cannot carry the speeds, or carries them through a velocity ratio over 1e6,
        // conditioned far below any other choice that assembles, which it would have
        // to beat by 1.5. So it is tried only if no other choice assembled. At S2's
        // catches into A68 from a held shaft the lever stops as it catches (the rocker
        // reverses): its choice failed to build each time (19k instructions).
        let still = |w: T| !(w.abs() > speed_tol::<T>() * scale_w);
        let moving = !omega.iter().all(|w| still(*w));
        let dead = |c: Coordinates| {
            moving
                && driving_link(m, c)
                    .is_some_and(|p| still(omega.get(p).copied().unwrap_or(T::zero())))
        };
        let choices = m.coordinate_choices();
        let ordered = choices
            .iter()
            .filter(|c| !dead(**c))
            .chain(choices.iter().filter(|c| dead(**c)))
            .copied();
        // The reference model (screened: its evaluation succeeded) may be the pick
        // itself, the first choice of its mode, evaluated at the candidate's state.
        let mut live = choices.iter().copied().filter(|c| !dead(*c));
        let (c1, c2) = (live.next(), live.next());
        let first = c1.or(choices.first().copied());
        let in_reference =
            screened.is_some() && self.reference_is_candidate(w, m, first, &omega, scale_w);
        self.cand_in_reference = in_reference;
        // A dyads-only first choice whose conditioning at the pose (no build:
        // `dyads_conditioning`) is under `switch_below` is not the pick if the next
        // choice that assembles is conditioned at least `switch_below` and 1.5 times
        // better: that one is then built first, and alone. (S2's catch at 0.0632 s
        // built I6's swing choice, 0.13, before taking the crank's; the margins keep
        // rounding of the prediction from deciding.)
        let poor = c1
            .and_then(|c| dyads_conditioning(m, c, pose))
            .filter(|p| *p < self.settings.switch_below * T::c(1.0 - 1e-9));
        let skipped = !in_reference
            && match (poor, c2) {
                (Some(p), Some(c2)) => {
                    self.load_candidate(w, m, c2, pose, &omega, inputs, scale_w, false) && {
                        let cond = self.scratch(w.switched).0.conditioning();
                        cond >= self.settings.switch_below && cond > p * T::c(1.5 * (1.0 + 1e-9))
                    }
                }
                _ => false,
            };
        let ok = in_reference || skipped || {
            for coords in ordered {
                if chosen.is_some() && dead(coords) {
                    break;
                }
                let second = two && kept == Some(false);
                if !self.load_candidate(w, m, coords, pose, &omega, inputs, scale_w, second) {
                    if !two {
                        kept = None;
                    }
                    continue;
                }
                let cond = self.build_slot(w.switched, second).0.conditioning();
                if chosen.is_none_or(|(c, _, _)| cond > c * T::c(1.5)) {
                    chosen = Some((cond, coords, self.speed_gap));
                    kept = Some(second);
                } else if !two {
                    kept = None;
                }
                if chosen.is_some_and(|(c, _, _)| c >= self.settings.switch_below) {
                    break;
                }
            }
            match (chosen, kept) {
                (Some((_, _, gap)), Some(second)) => {
                    self.speed_gap = gap;
                    if second {
                        // The candidate slot becomes the scratch, where `take_candidate`
                        // takes the pick from (the other slot, free, becomes the candidate
                        // slot): a flip of roles, no copy.
                        self.slots.role.swap(1, 2);
                    }
                    true
                }
                (Some((_, coords, gap)), None) => {
                    self.speed_gap = gap;
                    // Overwritten by a later choice in the one free slot: built again at
                    // the scan's pose and speeds.
                    self.load_candidate(w, m, coords, pose, &omega, inputs, scale_w, false)
                }
                (None, _) => false,
            }
        };
        // The kinetostatics (the clutch torques) of the choice taken only, and not
        // even of it when the screen's clutch torques are clear of the conditions'
        // thresholds: the signs that decide then read the same from either (they
        // differ by rounding), and the screen's torques stand for the model's until
        // the next full evaluation (8.3k instructions of S2's worst event step).
        let clear = screened.filter(|c| torques_clear(m, c, inputs));
        let (cand, params) = if in_reference {
            (&mut self.reference, &self.params)
        } else {
            self.scratch(w.switched)
        };
        let ok = ok && {
            finish_accelerations(&cand.model, &mut cand.ws);
            clear.is_some() || reactions(&cand.model, &mut cand.ws, w.t.to_f64()).is_ok()
        };
        if !ok {
            return Ok((T::c(f64::INFINITY), None));
        }
        let links = cand.links(params);
        let c = clear.unwrap_or_else(|| cand.clutch_torques(params, &links));
        log::debug!(
            "candidate {m}: c = {:?}, alpha6 = {:?}, alpha8 = {:?}",
            c,
            links[6].alpha,
            links[8].alpha,
        );
        Ok((self.violation(m, from, &c, &links, inputs, tol_w), clear))
    }

    /// Whether the reference model is candidate `m` as [`Twin::try_candidate`] would
    /// build it: the same mode (I0) in `first`, the coordinate choice it tries first,
    /// conditioned at least `switch_below` (so the choice it would take) and evaluated
    /// exactly at the candidate's state (the coordinates at the pose, both models'
    /// `coordinates_at`, and the speeds `omega` of the coordinates' links, bit for
    /// bit), which it carries (its speed gap, stored as a built choice's, within the
    /// tolerance). Its evaluation is then the one a build would make: a dyads-only
    /// model at the same pose gives the same bits. At S2's shaft stops and releases
    /// into I0 this spares the build and evaluation of the candidate (~25k
    /// instructions) for a swap of the two slots ([`Twin::choose`]).
    fn reference_is_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        first: Option<Coordinates>,
        omega: &[T; 9],
        scale_w: T,
    ) -> bool {
        let r = &self.reference;
        if !(r.built
            && r.mode == m
            && Some(r.coords) == first
            && r.conditioning() >= self.settings.switch_below)
        {
            return false;
        }
        let q = [r.ws.q[0], r.ws.q[1]];
        let mut y = w.y;
        load_state(r, &q, omega, &mut y);
        let n = r.map.dof.min(2);
        let at_state =
            r.ws.qd
                .iter()
                .zip(y.iter().skip(QD))
                .take(n)
                .all(|(a, b)| same_bits(*a, *b));
        if !at_state {
            return false;
        }
        let mapped = r.links(&self.params);
        let off = (1..9).fold(T::zero(), |e, p| e.max((mapped[p].omega - omega[p]).abs()));
        if !(off <= speed_tol::<T>() * scale_w) {
            return false;
        }
        self.speed_gap = off;
        true
    }

    /// How far mode `m` (entered from `from`) with the clutch torques `c` and the
    /// physical links' speeds and accelerations `links` violates SPEC 3's consistency
    /// conditions, each relative to its scale (0: consistent): c_k ≥ 0 for a locked or
    /// engaged lever, Σc_k ≤ T_r over the locked ones, a free lever touching the shaft
    /// does not accelerate past it in the drive direction, a shaft starting from rest
    /// accelerates in the drive direction.
    fn violation(
        &self,
        m: Mode,
        from: Mode,
        c: &[T; 2],
        links: &[LinkState<T>; 9],
        inputs: &Inputs<T>,
        tol_w: T,
    ) -> T {
        let d = self.drive;
        let torque_scale = inputs.load + T::c(1.0) + c[0].abs() + c[1].abs();
        let tol_c = torque_tol(torque_scale);
        let alpha_scale = links.iter().fold(T::one(), |a, s| a.max(s.alpha.abs()));
        let tol_a = T::c(1e-9) * alpha_scale;
        let shaft_alpha = shaft_accel(m, links);
        let mut v = T::zero();
        let mut locked = T::zero();
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(m.clutches()).enumerate() {
            match clutch {
                Clutch::Locked | Clutch::Engaged => {
                    v += (-c[k] - tol_c).max(T::zero()) / torque_scale;
                    if clutch == Clutch::Locked {
                        locked += c[k];
                    }
                }
                Clutch::Free => {
                    // A free lever touching the shaft must not pass it in the drive
                    // direction.
                    let l = links.get(*lever).copied().unwrap_or_default();
                    let rel_w = l.omega - shaft_speed(m, links);
                    if rel_w.abs() <= tol_w {
                        let rel = d * (l.alpha - shaft_alpha);
                        v += (rel - tol_a).max(T::zero()) / alpha_scale;
                    }
                }
            }
        }
        if !m.shaft_turning() {
            v += (locked - inputs.load - tol_c).max(T::zero()) / torque_scale;
        } else if !from.shaft_turning() {
            // A shaft starting from rest turns in the drive direction.
            v += (-d * shaft_alpha - tol_a).max(T::zero()) / alpha_scale;
        }
        v
    }

    /// Mode `m`'s violation of SPEC 3's consistency conditions (as
    /// [`Twin::violation`]) from the reference model (I0, both levers free), without
    /// building `m`'s model, with its clutch torques (N·m): `None` if it cannot tell.
    /// At the state `yr` with the
    /// speeds `u_plus` after the impact projection, the reference's equations of motion
    /// `M q̈ = Q` with the shaft as a third coordinate (inertia J_s, possibly 0; the load
    /// -d·T_r on it while it turns) and `m`'s clutches as constraints on the
    /// accelerations, `J q̈ = -β` (a locked lever's `α_k = 0`, an engaged one's
    /// `α_k = α_s`, a held shaft's `α_s = 0`; `β`: the levers' bias accelerations), give
    /// `q̈` and the multipliers λ of the KKT system `[M Jᵀ; J 0] [q̈; -λ] = [Q; -β]`:
    /// λ_k is the torque lever k's clutch applies to it, so `c_k = -d·λ_k` (SPEC 3: the
    /// moment of everything else on the lever minus `I_H α_k`). The same motion as
    /// `m`'s own model, up to rounding.
    #[allow(clippy::too_many_arguments)]
    fn screen(
        &mut self,
        m: Mode,
        from: Mode,
        yr: &mut SVector<T, STATE>,
        u_plus: &SVector<T, 3>,
        t: T,
        inputs: &Inputs<T>,
        tol_w: T,
    ) -> Option<(T, [T; 2])> {
        let d = self.drive;
        // The reference evaluated at the candidate's speeds, unless the speeds `yr` its
        // workspace holds differ from them by under 1e-3 of the screen's margin
        // (relative to the largest speed): the bias accelerations, quadratic in the
        // speeds, then differ by 2e-3 of the margin at most. Without an impact (a
        // release, a catch located in time) the projection moves the speeds by rounding.
        // For the reference's own mode (I0) exactly at them: the reference is then the
        // candidate itself (see `Twin::reference_is_candidate`).
        let scale = u_plus.iter().fold(T::one(), |a, v| a.max(v.abs()));
        let moved = (0..2).fold(T::zero(), |a, k| a.max((yr[QD + k] - u_plus[k]).abs()));
        let exact = m == self.reference.mode;
        if !(moved <= screen_margin::<T>() * T::c(1e-3) * scale) || (exact && moved != T::zero()) {
            yr[QD] = u_plus[0];
            yr[QD + 1] = u_plus[1];
            if self.reference.eval(t, yr, inputs, d).is_err() {
                // The workspace holds no evaluation: the next screen evaluates again.
                yr[QD] = T::c(f64::NAN);
                return None;
            }
        }
        let r = &self.reference;
        let row = |lever: usize| r.lever_row(lever);
        let rows = constraint_rows(m, true, row);
        // The constraints' bias terms: the same combinations of the levers' bias
        // accelerations (first component; the shaft's bias is 0).
        let bias = constraint_rows(m, true, |lever| {
            SVector::<T, 3>::new(r.alpha_bias(lever), T::zero(), T::zero())
        });
        let mut kkt = SMatrix::<T, 6, 6>::identity();
        let mut rhs = SVector::<T, 6>::zeros();
        for i in 0..2 {
            for j in 0..2 {
                kkt[(i, j)] = r.ws.mass_q[(i, j)];
            }
            rhs[i] = r.ws.gen_force[i];
        }
        kkt[(2, 2)] = self.params.shaft_inertia;
        if m.shaft_turning() {
            rhs[2] = -d * inputs.load;
        }
        // At most the three coordinates' worth of constraints (3 rows per mode).
        for (i, (a, b)) in rows.iter().zip(bias.iter()).take(3).enumerate() {
            let k = 3 + i;
            for (j, aj) in a.iter().enumerate() {
                for at in [(k, j), (j, k)] {
                    if let Some(e) = kkt.get_mut(at) {
                        *e = *aj;
                    }
                }
            }
            if let Some(e) = kkt.get_mut((k, k)) {
                *e = T::zero();
            }
            if let Some(e) = rhs.get_mut(k) {
                *e = -b[0];
            }
        }
        let x = crate::linalg::solve(kkt, rhs)?;
        if x.iter().any(|v| !v.finite()) {
            return None;
        }
        // The multipliers in the order of `constraint_rows`: one per locked or engaged
        // lever, in branch order.
        let mut c = [T::zero(); 2];
        let mut i = 3;
        for (ck, clutch) in c.iter_mut().zip(m.clutches()) {
            if clutch != Clutch::Free {
                *ck = d * x.get(i).copied().unwrap_or(T::zero());
                i += 1;
            }
        }
        let mut links = [LinkState::default(); 9];
        for (p, l) in links.iter_mut().enumerate().skip(1) {
            let v = row(p);
            l.omega = v[0] * u_plus[0] + v[1] * u_plus[1];
            l.alpha = v[0] * x[0] + v[1] * x[1] + r.alpha_bias(p);
        }
        Some((self.violation(m, from, &c, &links, inputs, tol_w), c))
    }

    /// Builds mode `m` driven by `coords` at `pose` with the physical speeds `omega`
    /// into the candidate slot (`second`: the other free one, see
    /// [`Twin::build_slot`]), moving the model it holds if it is that one (see
    /// [`Slot::reposition`]), and evaluates its equations of motion (not the
    /// kinetostatics); `false` if it does not assemble, fails, or cannot carry the
    /// speeds (its gap is left in `speed_gap`).
    #[allow(clippy::too_many_arguments)]
    fn load_candidate(
        &mut self,
        w: &Work<T>,
        m: Mode,
        coords: Coordinates,
        pose: &[T; 9],
        omega: &[T; 9],
        inputs: &Inputs<T>,
        scale_w: T,
        second: bool,
    ) -> bool {
        let time = w.t.to_f64();
        let drive = self.drive;
        let (cand, params) = self.build_slot(w.switched, second);
        let q = match cand.reposition(params, m, coords, pose, time) {
            Ok(q) => q,
            Err(e) => {
                log::debug!("candidate {m} in {coords} coordinates does not assemble: {e:?}");
                return false;
            }
        };
        let mut y = w.y;
        load_state(cand, &q, omega, &mut y);
        if cand.eval(w.t, &y, inputs, drive).is_err() {
            return false;
        }
        let mapped = cand.links(params);
        let off = (1..9).fold(T::zero(), |e, p| e.max((mapped[p].omega - omega[p]).abs()));
        self.speed_gap = off;
        if !(off <= speed_tol::<T>() * scale_w) {
            log::debug!("candidate {m} in {coords} coordinates cannot carry the speeds (off by {off:?} rad/s)");
            return false;
        }
        true
    }

    /// Tries the mode's other coordinate choices at `w`'s state and takes the best
    /// conditioned if it beats the current one by 1.5 (`failed`: the current choice just
    /// failed, take any that works). Maps the state exactly and logs it.
    fn switch_coordinates(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        failed: Option<StepError>,
    ) -> Result<(), TwinError> {
        let time = w.t.to_f64();
        let mode = self.slots.cur().mode;
        let pose = self.slot_links_unwrapped();
        let links = self.slots.cur().links(&self.params);
        let now = self.slots.cur().conditioning();
        // (conditioning, choice, its coordinates) of the best other choice, which the
        // candidate slot holds.
        let mut best: Option<(T, Coordinates, [T; 2])> = None;
        // The current choice is not assembled again: it is at this very pose with
        // conditioning `now`, so it could only win the scan by keeping its place, and
        // another choice is taken only if it beats `now` by 1.5.
        let skip = Some(self.slots.cur().coords);
        // The reference slot is the spare: the mode choice builds it again.
        let (backup, cand) = self.slots.spares();
        let scratch = if w.switched { cand } else { backup };
        let mut failures = scan_choices(
            &self.params,
            mode,
            &pose,
            time,
            skip,
            scratch,
            &mut self.reference,
            |s, q| {
                let cond = s.conditioning();
                if best.as_ref().is_none_or(|(b, _, _)| cond > *b) {
                    best = Some((cond, s.coords, q));
                    Take::Keep
                } else {
                    Take::No
                }
            },
        )?;
        if failed.is_none() && best.is_none() {
            // No other choice assembles here: the current one still drives.
            return Ok(());
        }
        let Some((cond, coords, q)) = best else {
            if let Some(StepError::Group { group, fault, .. }) =
                failed.map(|e| physical(&self.slots.cur().map, e))
            {
                let _ = failures.insert(
                    0,
                    Failure {
                        coords: self.slots.cur().coords,
                        group,
                        fault,
                    },
                );
            }
            return Err(TwinError::Mechanism {
                time,
                mode,
                failures,
            });
        };
        if !(failed.is_some() || cond > now * T::c(1.5)) {
            return Ok(());
        }
        let from = self.slots.cur().coords;
        self.take_candidate(w);
        let omega: [T; 9] = core::array::from_fn(|p| links[p].omega);
        load_state(self.slots.cur(), &q, &omega, &mut w.y);
        self.dp5.invalidate();
        self.finish(w, inputs)?;
        let after = self.slots.cur().links(&self.params);
        let position_gap = joint_gap(&self.params, &links, &after);
        let speed_gap = (1..9).fold(T::zero(), |e, p| {
            e.max((after[p].omega - links[p].omega).abs())
        });
        log::info!("t = {time:.6} s: mode {mode}: coordinates {from} -> {coords} (conditioning {now:?} -> {cond:?})");
        let _ = self.switches.push(CoordinateSwitch {
            time: w.t,
            mode,
            from,
            to: coords,
            conditioning: [now, self.slots.cur().conditioning()],
            position_gap,
            speed_gap,
        });
        Ok(())
    }

    /// Makes the state after a successful step the twin's: physical links (angles
    /// unwrapped), shaft, clutch torques, reactions, the energy audit.
    fn commit(&mut self, w: &Work<T>, audit: Audit<T>, mut links: [LinkState<T>; 9]) {
        self.t = w.t;
        for (l, last) in links.iter_mut().zip(self.links.iter()).skip(1) {
            l.theta = unwrap_near(l.theta, last.theta);
        }
        if self.slots.cur().mode.shaft_turning() {
            let lever = if self.slots.cur().mode.clutches()[0] == Clutch::Engaged {
                6
            } else {
                8
            };
            self.shaft_angle += links[lever].theta - self.links[lever].theta;
        }
        self.links = links;
        self.joints = self.slots.cur().joint_reactions(&self.params, &links);
        self.audit = audit;
    }

    fn physical_error(&self, e: StepError) -> TwinError {
        match e {
            StepError::Group { .. } => {
                let StepError::Group { time, group, fault } = physical(&self.slots.cur().map, e)
                else {
                    return TwinError::Step(e);
                };
                let mut failures = heapless::Vec::new();
                let _ = failures.push(Failure {
                    coords: self.slots.cur().coords,
                    group,
                    fault,
                });
                TwinError::Mechanism {
                    time,
                    mode: self.slots.cur().mode,
                    failures,
                }
            }
            e => TwinError::Step(e),
        }
    }

    // ---- outputs ----

    /// Time, s.
    pub fn time(&self) -> T {
        self.t
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// The fixed step, s.
    pub fn h(&self) -> T {
        self.settings.h
    }
    /// The parameters.
    pub fn params(&self) -> &CccParams<T> {
        &self.params
    }
    /// The current mode.
    pub fn mode(&self) -> Mode {
        self.slots.cur().mode
    }
    /// The current independent coordinates.
    pub fn coordinates(&self) -> Coordinates {
        self.slots.cur().coords
    }
    /// Values of the current coordinates (`[..dof]`), rad.
    pub fn q(&self) -> &[T] {
        self.y
            .as_slice()
            .get(..self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }
    /// Their speeds, rad/s.
    pub fn qd(&self) -> &[T] {
        self.y
            .as_slice()
            .get(QD..QD + self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }
    /// Their accelerations, rad/s².
    pub fn qdd(&self) -> &[T] {
        self.slots
            .cur()
            .ws
            .qdd
            .get(..self.slots.cur().map.dof.min(2))
            .unwrap_or(&[])
    }
    /// Physical state of link `p` (1..=8).
    pub fn link(&self, p: usize) -> LinkState<T> {
        self.links.get(p).copied().unwrap_or_default()
    }
    /// World position of point `point` (0 or 1: a bar's first or second joint; 2: D on
    /// the rocker) of physical link `p`, m.
    pub fn joint_position(&self, p: usize, point: usize) -> Vec2<T> {
        let s = self.link(p);
        let x = match point {
            0 => T::zero(),
            1 => self.params.link(p).length,
            _ => self.params.rocker_d,
        };
        s.origin + Vec2::new(s.theta.cos(), s.theta.sin()) * x
    }
    /// Shaft speed, rad/s, CCW positive (0 while held).
    pub fn shaft_speed(&self) -> T {
        shaft_speed(self.slots.cur().mode, &self.links)
    }
    /// Shaft angle turned since the start, rad, CCW positive.
    pub fn shaft_angle(&self) -> T {
        self.shaft_angle
    }
    /// Transmitted torques `[c6, c8]`, N·m, positive in the drive direction.
    pub fn clutch_torques(&self) -> [T; 2] {
        self.c
    }
    /// Reactions at the physical joints ([`JOINTS`](super::slot::JOINTS)), N.
    pub fn joint_reactions(&self) -> &[Vec2<T>; 11] {
        &self.joints
    }
    /// Motor torque at the current state, N·m.
    pub fn motor_torque(&self) -> T {
        let c = self.link(CRANK);
        self.inputs.motor.torque(self.t, c.theta, c.omega)
    }
    /// The energy audit.
    pub fn audit(&self) -> Audit<T> {
        self.audit
    }
    /// Crank angle and speed minus the measured ones given with the last step's inputs.
    pub fn measurement_residual(&self) -> Option<(T, T)> {
        let c = self.link(CRANK);
        self.inputs
            .measured
            .map(|(a, w)| (c.theta - a, c.omega - w))
    }
    /// The mode changes of the last step (or of the setup).
    pub fn events(&self) -> &[Event<T>] {
        &self.events
    }
    /// The coordinate switches of the last step.
    pub fn switches(&self) -> &[CoordinateSwitch<T>] {
        &self.switches
    }
    /// The candidates of the last mode choice, in the order tried, with how far each
    /// violates SPEC 3's consistency conditions (0: consistent; infinite: its
    /// constraints are rank-deficient or it cannot assemble).
    pub fn candidates(&self) -> &[(Mode, T)] {
        &self.candidates
    }
    /// Smallest normalized determinant over the current sequence's groups.
    pub fn conditioning(&self) -> T {
        self.slots.cur().conditioning()
    }
    /// The current mode's core model.
    pub fn model(&self) -> &crate::model::Model<T> {
        &self.slots.cur().model
    }
}

// ---- helpers ----

/// Largest distance between the joints (both ends of every link, and D) of two
/// physical states, m, bounded from above without trigonometry: a joint at `x` along
/// a link whose origin moved by `Δo` and which turned by `Δθ` moved by at most
/// `|Δo| + 2|sin(Δθ/2)| x ≤ |Δo| + |Δθ| x`, exact to third order in `Δθ` (the states
/// compared agree to ~1e-13 m and rad). 18 `sin_cos` fewer than measuring each joint.
fn joint_gap<T: Real>(params: &CccParams<T>, a: &[LinkState<T>; 9], b: &[LinkState<T>; 9]) -> T {
    let mut gap = T::zero();
    for p in 1..9 {
        let reach = params.link(p).length.abs().max(params.rocker_d.abs());
        let turn = (unwrap_near(b[p].theta, a[p].theta) - a[p].theta).abs();
        gap = gap.max((a[p].origin - b[p].origin).norm() + turn * reach);
    }
    gap
}

/// Writes a slot's coordinates `q` and their speeds (the angular speeds `omega` of the
/// coordinates' links, rad/s) into a state vector; unused slots are zeroed.
fn load_state<T: Real>(slot: &Slot<T>, q: &[T; 2], omega: &[T; 9], y: &mut SVector<T, STATE>) {
    for (k, (qk, link)) in q.iter().zip(slot.map.coord_link.iter()).enumerate() {
        let active = k < slot.map.dof;
        y[k] = if active { *qk } else { T::zero() };
        y[QD + k] = if active {
            omega.get(*link as usize).copied().unwrap_or(T::zero())
        } else {
            T::zero()
        };
    }
}

/// Lower is preferred: whether the candidate agrees with the event that fired (0) or
/// not (1), then how many clutches and shaft states change from the current mode.
fn preference(from: Mode, to: Mode, kind: EventKind) -> u8 {
    let c = to.clutches();
    let agrees = match kind {
        EventKind::Catch(l) => c[if l == 6 { 0 } else { 1 }] != Clutch::Free,
        EventKind::Release(l) => c[if l == 6 { 0 } else { 1 }] == Clutch::Free,
        EventKind::Breakaway => to.shaft_turning(),
        EventKind::ShaftStop => !to.shaft_turning(),
        EventKind::Start | EventKind::Inputs => true,
    };
    let changes = from
        .clutches()
        .iter()
        .zip(c.iter())
        .filter(|(a, b)| a != b)
        .count() as u8
        + u8::from(from.shaft_turning() != to.shaft_turning());
    (if agrees { 0 } else { 8 }) + changes
}

/// Shaft speed, rad/s CCW: the engaged lever's in an A mode, 0 otherwise.
fn shaft_speed<T: Real>(mode: Mode, links: &[LinkState<T>; 9]) -> T {
    match mode.clutches() {
        _ if !mode.shaft_turning() => T::zero(),
        [Clutch::Engaged, _] => links[6].omega,
        _ => links[8].omega,
    }
}

fn shaft_accel<T: Real>(mode: Mode, links: &[LinkState<T>; 9]) -> T {
    match mode.clutches() {
        _ if !mode.shaft_turning() => T::zero(),
        [Clutch::Engaged, _] => links[6].alpha,
        _ => links[8].alpha,
    }
}

/// The velocity constraints of mode `m` in the reference space `(q̇1, q̇2, ω_s)`: a
/// locked lever stands still, an engaged one turns with the shaft (without shaft
/// inertia: with the other engaged lever), a held shaft stands still.
fn constraint_rows<T: Real>(
    m: Mode,
    with_shaft: bool,
    row: impl Fn(usize) -> SVector<T, 3>,
) -> heapless::Vec<SVector<T, 3>, 3> {
    let mut rows = heapless::Vec::new();
    let shaft = SVector::<T, 3>::new(T::zero(), T::zero(), T::one());
    let c = m.clutches();
    for (k, (_, lever)) in BRANCHES.iter().enumerate() {
        match c[k] {
            Clutch::Locked => {
                let _ = rows.push(row(*lever));
            }
            Clutch::Engaged if with_shaft => {
                let _ = rows.push(row(*lever) - shaft);
            }
            _ => {}
        }
    }
    if !with_shaft && c == [Clutch::Engaged, Clutch::Engaged] {
        let _ = rows.push(row(6) - row(8));
    }
    if with_shaft && !m.shaft_turning() && m != Mode::Free {
        let _ = rows.push(shaft);
    }
    rows
}

/// Plastic impact (SPEC 3): `u⁺ = u - M⁻¹Jᵀ(J M⁻¹ Jᵀ)⁻¹ J u`, and the kinetic energy
/// lost. `None` if the constraints are rank-deficient. Without shaft inertia the third
/// coordinate is unused (`M` has 1 there and `J`'s third column is 0).
fn project<T: Real>(
    mass: &SMatrix<T, 3, 3>,
    u: &SVector<T, 3>,
    rows: &[SVector<T, 3>],
) -> Option<(SVector<T, 3>, T)> {
    let minv = mass.try_inverse()?;
    let n = rows.len();
    // At most the three coordinates' worth of independent constraints.
    if n > 3 {
        return None;
    }
    if n == 0 {
        return Some((*u, T::zero()));
    }
    let mut gram = SMatrix::<T, 3, 3>::identity();
    let mut ju = SVector::<T, 3>::zeros();
    for (i, ri) in rows.iter().enumerate() {
        ju[i] = ri.dot(u);
        for (j, rj) in rows.iter().enumerate() {
            gram[(i, j)] = (ri.transpose() * minv * rj)[(0, 0)];
        }
    }
    // Rank: each pivot relative to its row's own weight.
    let chol = nalgebra::Cholesky::new(gram)?;
    let l = chol.l();
    for i in 0..n {
        if !(l[(i, i)] * l[(i, i)] > T::c(1e-10) * gram[(i, i)].max(T::EPS)) {
            return None;
        }
    }
    let lambda = chol.solve(&ju);
    let mut jt_l = SVector::<T, 3>::zeros();
    for (i, ri) in rows.iter().enumerate() {
        jt_l += ri * lambda[i];
    }
    let u_plus = u - minv * jt_l;
    let half = T::c(0.5);
    let loss = half * (u.transpose() * mass * u)[(0, 0)]
        - half * (u_plus.transpose() * mass * u_plus)[(0, 0)];
    Some((u_plus, loss.max(T::zero())))
}

fn rows_mismatch<T: Real>(rows: &[SVector<T, 3>], u: &SVector<T, 3>) -> T {
    rows.iter().fold(T::zero(), |m, r| m.max(r.dot(u).abs()))
}

/// The root in (0, 1) of the cubic Hermite interpolant of an event function over a
/// step, `p(0) = g0 ≤ 0 < p(1) = g1` with slopes `s0`, `s1` (per unit of the step's
/// fraction θ: h·dg/dt), to `tol`/100 ([`bracketed_root`]); with `before`, the value
/// `gm` at the start of the step before (θ = -r, `r` its length over this one's), of
/// the quartic that also passes there. No evaluation of the mechanism: the first
/// point of [`Twin::locate`]'s iteration, O(h⁴) from the true crossing (the quartic
/// O(h⁵)). In S2 the cubic's roots were off the crossings by up to 15 of
/// [`Twin::locate`]'s tolerances (1e-8 of the step), the quartic's by at most 0.41
/// (most by under 0.05). `None` if the values do not bracket a root.
fn hermite_root<T: Real>(
    g0: T,
    g1: T,
    s0: T,
    s1: T,
    before: Option<(T, T)>,
    tol: T,
) -> Option<(T, T)> {
    if !(s0.finite() && s1.finite()) {
        return None;
    }
    let one = T::one();
    let (two, three, six) = (T::c(2.0), T::c(3.0), T::c(6.0));
    // p(θ) = h00 g0 + h10 s0 + h01 g1 + h11 s1 and p'(θ).
    let cubic = |th: T| {
        let u = one - th;
        let value = (one + two * th) * u * u * g0
            + th * u * u * s0
            + th * th * (three - two * th) * g1
            + th * th * (th - one) * s1;
        let slope = six * th * (th - one) * (g0 - g1)
            + (three * th * th - T::c(4.0) * th + one) * s0
            + (three * th * th - two * th) * s1;
        (value, slope)
    };
    // The quartic through the value at the start of the step before too (θ = -r):
    // p + c θ²(θ-1)², which keeps the ends' values and slopes.
    let c = before
        .map(|(gm, r)| {
            let w = r * r * (r + one) * (r + one);
            (gm - cubic(-r).0) / w
        })
        .filter(|c| c.finite())
        .unwrap_or(T::zero());
    bracketed_root(
        |th: T| {
            let (v, d) = cubic(th);
            let u = th - one;
            (
                v + c * th * th * u * u,
                d + c * two * th * u * (two * th - one),
            )
        },
        g0,
        g1,
        tol,
    )
}

/// The root in (0, 1) of the quadratic through an event function's values `g0 ≤ 0`
/// and `g1 > 0` at the step's ends and `gm` at θ = -r (the start of the step before,
/// `r` its length over this one's), to `tol`/100; O(h³) from the true crossing. For
/// the torque functions, whose rates the evaluation does not give. `None` if the
/// values do not bracket a root.
fn quadratic_root<T: Real>(gm: T, r: T, g0: T, g1: T, tol: T) -> Option<(T, T)> {
    // p(θ) = g0 + a θ + b θ², p(1) = g1, p(-r) = gm.
    let b = (gm - g0 + r * (g1 - g0)) / (r * (T::one() + r));
    let a = g1 - g0 - b;
    if !(a.finite() && b.finite()) {
        return None;
    }
    bracketed_root(
        |th: T| (g0 + th * (a + th * b), a + T::c(2.0) * th * b),
        g0,
        g1,
        tol,
    )
}

/// The root in (0, 1) of an interpolant `p` (value, slope) of an event function with
/// `p(0) = g0 ≤ 0 < p(1) = g1`, to `tol`/100: safeguarded Newton from the linear
/// root (bisection whenever Newton leaves the bracket; at most 40 iterations, usually
/// 3), until a Newton step or the bracket is under `tol`/100. `None` if the values do not bracket a root.
fn bracketed_root<T: Real>(p: impl Fn(T) -> (T, T), g0: T, g1: T, tol: T) -> Option<(T, T)> {
    if !(g0 <= T::zero() && g1 > T::zero()) {
        return None;
    }
    let (mut a, mut b) = (T::zero(), T::one());
    let mut th = g0 / (g0 - g1);
    for _ in 0..40 {
        let (v, dv) = p(th);
        if v > T::zero() {
            b = th;
        } else {
            a = th;
        }
        let newton = th - v / dv;
        // Converged: a last Newton step this small may round onto an end of the
        // bracket, and bisecting from there took 20 more iterations.
        if newton.finite() && (newton - th).abs() <= tol * T::c(0.01) {
            th = newton.max(a).min(b);
            break;
        }
        let next = if newton.finite() && newton > a && newton < b {
            newton
        } else {
            (a + b) * T::c(0.5)
        };
        let moved = (next - th).abs();
        th = next;
        if moved <= tol * T::c(0.01) || b - a <= tol * T::c(0.01) {
            break;
        }
    }
    let (_, slope) = p(th);
    (th.finite() && slope.finite()).then_some((th, slope))
}

/// The twin's three working slots (30 KB each in f64) and their roles: the current
/// slot, the backup (the pre-step slot once a step changed the current one, see
/// [`Twin::scratch`]) and the candidate slot. The roles move, never the slots: taking
/// a candidate, restoring the backup or handing the backup's role to the slot that
/// holds a pick permutes `role` (a 30 KB swap cost 7.5k instructions per event).
#[derive(Clone, Debug)]
struct Slots<T: Real> {
    s: [Slot<T>; 3],
    /// Indices into `s` of the current slot, the backup and the candidate slot: a
    /// permutation of 0, 1, 2 (only ever swapped).
    role: [u8; 3],
}

impl<T: Real> Slots<T> {
    fn at(&self, k: usize) -> &Slot<T> {
        let [a, b, c] = &self.s;
        match self.role.get(k) {
            Some(0) => a,
            Some(1) => b,
            _ => c,
        }
    }

    /// The current slot: the mode and coordinates the twin integrates.
    fn cur(&self) -> &Slot<T> {
        self.at(0)
    }

    fn cur_mut(&mut self) -> &mut Slot<T> {
        let [a, b, c] = &mut self.s;
        match self.role.first() {
            Some(0) => a,
            Some(1) => b,
            _ => c,
        }
    }

    /// `(backup, candidate slot)`.
    fn spares(&mut self) -> (&mut Slot<T>, &mut Slot<T>) {
        let [a, b, c] = &mut self.s;
        // The roles are a permutation: the two spares are distinct slots.
        match (self.role.get(1), self.role.get(2)) {
            (Some(0), Some(1)) => (a, b),
            (Some(0), _) => (a, c),
            (Some(1), Some(0)) => (b, a),
            (Some(1), _) => (b, c),
            (_, Some(0)) => (c, a),
            _ => (c, b),
        }
    }
}

/// Which of the event functions went from ≤ 0 to > 0 (bit k: function k).
fn fired<T: Real>(g0: &Guards<T>, g1: &Guards<T>) -> u8 {
    let mut bits = 0u8;
    for (k, (a, b)) in g0.iter().zip(g1.iter()).enumerate() {
        if let (Some(a), Some(b)) = (a, b) {
            if *a <= T::zero() && *b > T::zero() {
                bits |= 1 << k;
            }
        }
    }
    bits
}

/// Builds into `slot` the first choice of `mode`'s coordinates that assembles at `pose`
/// well conditioned, else the best conditioned that assembles (`spare`: the scratch
/// slot the others are tried in); returns its coordinates. On an error `slot` is
/// half-built.
fn best_slot<T: Real>(
    params: &CccParams<T>,
    mode: Mode,
    pose: &[T; 9],
    time: f64,
    slot: &mut Slot<T>,
    spare: &mut Slot<T>,
) -> Result<[T; 2], TwinError> {
    // (conditioning, coordinates) of the best so far, which `slot` holds.
    let mut best: Option<(T, [T; 2])> = None;
    let failures = scan_choices(params, mode, pose, time, None, slot, spare, |s, q| {
        let cond = s.conditioning();
        if cond >= T::c(0.2) {
            best = Some((cond, q));
            Take::KeepAndStop
        } else if best.is_none_or(|(b, _)| cond > b) {
            best = Some((cond, q));
            Take::Keep
        } else {
            Take::No
        }
    })?;
    best.map(|(_, q)| q).ok_or(TwinError::Mechanism {
        time,
        mode,
        failures,
    })
}

/// What [`scan_choices`] does with a coordinate choice that assembles.
enum Take {
    /// Drops it.
    No,
    /// Keeps it (the best so far) and goes on.
    Keep,
    /// Keeps it and ends the scan.
    KeepAndStop,
}

/// Assembles `mode` at `pose` in each of its coordinate choices but `skip`, in order
/// (repositioning a slot that holds the choice already, see [`Slot::reposition`]), and
/// hands each that assembles to `take` with its coordinates. Each is built in
/// `slot` or `spare`, whichever does not hold the choice kept last, so that no choice
/// is built twice and no slot is copied or swapped (30 KB in f64) unless the choice
/// kept last ends up in `spare`: then the two are swapped once at the end. Returns the
/// groups that failed in the others; an error that is not a group's (a non-finite
/// input) ends the scan. `slot` holds the last choice kept, if any.
#[allow(clippy::too_many_arguments)]
fn scan_choices<T: Real>(
    params: &CccParams<T>,
    mode: Mode,
    pose: &[T; 9],
    time: f64,
    skip: Option<Coordinates>,
    slot: &mut Slot<T>,
    spare: &mut Slot<T>,
    mut take: impl FnMut(&Slot<T>, [T; 2]) -> Take,
) -> Result<heapless::Vec<Failure, 3>, TwinError> {
    let mut failures: heapless::Vec<Failure, 3> = heapless::Vec::new();
    // Whether `slot` holds the choice kept last; the next is built in the other.
    let (mut kept_in_slot, mut kept_any) = (false, false);
    for coords in mode.coordinate_choices().iter().copied() {
        if Some(coords) == skip {
            continue;
        }
        let target = if kept_in_slot {
            &mut *spare
        } else {
            &mut *slot
        };
        match target.reposition(params, mode, coords, pose, time) {
            Ok(q) => {
                let verdict = take(target, q);
                if !matches!(verdict, Take::No) {
                    kept_in_slot = !kept_in_slot;
                    kept_any = true;
                }
                if matches!(verdict, Take::KeepAndStop) {
                    break;
                }
            }
            Err(StepError::Group { group, fault, .. }) => {
                let _ = failures.push(Failure {
                    coords,
                    group,
                    fault,
                });
            }
            Err(e) => return Err(TwinError::Step(e)),
        }
    }
    if !kept_in_slot && kept_any {
        core::mem::swap(slot, spare);
    }
    Ok(failures)
}

/// The largest angular speed of the links (rad/s), at least 1: the scale of the
/// speed thresholds.
fn speed_scale<T: Real>(links: &[LinkState<T>; 9]) -> T {
    links.iter().fold(T::one(), |m, s| m.max(s.omega.abs()))
}

/// A candidate mode whose violation from the reference model ([`Twin::screen`]) is over
/// this is not built: its own model would find it violating too (the two differ by
/// rounding, ~1e-12 of the scales in f64). Near 0 the built model decides.
fn screen_margin<T: Real>() -> T {
    T::c(1e-6).max(T::EPS * T::c(1e4))
}

/// Whether mode `m`'s clutch torques `c` (N·m, from [`Twin::screen`]) are clear of
/// [`Twin::violation`]'s torque conditions by [`screen_margin`] of its torque scale:
/// each locked or engaged lever's `c_k` over its threshold, and a held shaft's locked
/// torques under `T_r`, by that much. Its own model's kinetostatics, which differ by
/// rounding, would then decide those conditions alike.
fn torques_clear<T: Real>(m: Mode, c: &[T; 2], inputs: &Inputs<T>) -> bool {
    let scale = inputs.load + T::one() + c[0].abs() + c[1].abs();
    let clear = torque_tol(scale) + screen_margin::<T>() * scale;
    let mut locked = T::zero();
    for (ck, clutch) in c.iter().zip(m.clutches()) {
        match clutch {
            Clutch::Free => {}
            Clutch::Locked | Clutch::Engaged => {
                if !(*ck > clear) {
                    return false;
                }
                if clutch == Clutch::Locked {
                    locked += *ck;
                }
            }
        }
    }
    m.shaft_turning() || locked < inputs.load - clear
}

/// Relative threshold on angular speeds (of the largest): whether a lever touches the
/// shaft, and whether a coordinate choice carries the speeds it is given. 1e-6, or 1000
/// ulps if that is larger (f32, 1.2e-4). A choice at its dead point is off by O(1); a
/// good one by rounding, amplified near a dead point: 2.3e-15 in f64 and 2.5e-6 (20
/// ulps) in f32 at S2's events, over f32's 1e-6, so that f32 refused every mode at the
/// first breakaway (0.0666 s) and went on in I0.
fn speed_tol<T: Real>() -> T {
    T::c(1e-6).max(T::EPS * T::c(1e3))
}

/// The threshold on transmitted torques for a torque scale `s` (T_r + 1 N·m, plus the
/// levers' torques in the consistency conditions): 1e-9 s, or if that is larger (f32)
/// 10 ulps of `s` plus 1e4 ulps of 1 N·m. A lever that carries nothing computes c as a
/// sum of the mechanism's own torques (up to hundreds of N·m) that cancel: S2 without
/// load rounds it to 6e-13 N·m at most in f64 and 2.4e-4 N·m in f32 (~2700 ulps of
/// 1 N·m in both), far over f32's 1e-9 (T_r + 1 N·m): it fired a release every few
/// steps. The f32 threshold is 1.2e-3 N·m at T_r = 0 and 2.1e-3 N·m at T_r = 800 N·m,
/// which moves a release by ~1e-5 s in S2.
fn torque_tol<T: Real>(s: T) -> T {
    (T::c(1e-9) * s).max(T::EPS * (T::c(10.0) * s + T::c(1e4)))
}

fn same_bits<T: Real>(a: T, b: T) -> bool {
    a.to_f64().to_bits() == b.to_f64().to_bits()
}

fn same_inputs<T: Real>(a: &Inputs<T>, b: &Inputs<T>) -> bool {
    use super::slot::MotorInput;
    let motor = match (a.motor, b.motor) {
        (MotorInput::Torque(x), MotorInput::Torque(y)) => same_bits(x, y),
        (MotorInput::Law(_), MotorInput::Law(_)) => true,
        _ => false,
    };
    motor && same_bits(a.load, b.load)
}

/// The audit's terms are finite, or the error that says they are not. The works are
/// integrated with the motion but not checked by its evaluations, and an energy can
/// overflow at finite speeds (`½ J_s ω²` with a huge J_s): past the scalar's range the
/// balance test would compare infinities and pass.
fn audit_finite<T: Real>(a: &Audit<T>, t: T) -> Result<(), TwinError> {
    let terms = [
        a.motor_work,
        a.load_work,
        a.impact_loss,
        a.kinetic,
        a.potential,
        a.initial,
        a.residual(),
    ];
    if terms.iter().all(|x| x.finite()) {
        Ok(())
    } else {
        Err(TwinError::Step(StepError::NonFinite {
            time: t.to_f64(),
            what: "the energy audit (a work or an energy overflows the scalar)",
        }))
    }
}

fn check_inputs<T: Real>(inputs: &Inputs<T>) -> Result<(), TwinError> {
    if !(inputs.load.finite() && inputs.load >= T::zero()) {
        return Err(TwinError::Setting(
            "the load torque T_r must be finite and ≥ 0",
        ));
    }
    match inputs.motor {
        super::slot::MotorInput::Torque(v) if !v.finite() => {
            return Err(TwinError::Setting("the motor torque must be finite"));
        }
        // A law's parameters are checked here; what a user function returns is checked
        // at every evaluation (a non-finite torque fails the step, state kept).
        super::slot::MotorInput::Law(m) if m.validate().is_err() => {
            return Err(TwinError::Setting(
                "the motor law's parameters must be finite",
            ));
        }
        _ => {}
    }
    if let Some((a, w)) = inputs.measured {
        if !(a.finite() && w.finite()) {
            return Err(TwinError::Setting(
                "the measured crank angle and speed must be finite",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{bracketed_root, hermite_root};

    /// An event function over a step (θ in [0, 1]) and its slope.
    fn quartic(th: f64) -> (f64, f64) {
        // (θ - 0.37)(θ² + 2)(θ + 3): one root in (0, 1), at 0.37.
        let (a, b, c) = (th - 0.37, th * th + 2.0, th + 3.0);
        (a * b * c, b * c + a * 2.0 * th * c + a * b)
    }

    #[test]
    fn the_quartic_through_the_step_before_finds_a_quartic_crossing() {
        let tol = 1e-8;
        let (g0, s0) = quartic(0.0);
        let (g1, s1) = quartic(1.0);
        let r = 0.8;
        let gm = quartic(-r).0;
        let (root, slope) = hermite_root(g0, g1, s0, s1, Some((gm, r)), tol).unwrap();
        // A quartic is its own interpolant: the root to the solver's tol/100.
        assert!((root - 0.37).abs() <= tol * 0.01, "{root}");
        assert!((slope - quartic(0.37).1).abs() <= 1e-9 * slope.abs());
        // The cubic alone is off by its interpolation error, far past the tolerance:
        // the step before's value is what brings the root to it.
        let (cubic, _) = hermite_root(g0, g1, s0, s1, None, tol).unwrap();
        assert!((cubic - 0.37).abs() > 100.0 * tol, "{cubic}");
    }

    #[test]
    fn the_cubic_finds_a_cubic_crossing() {
        let tol = 1e-8;
        // (θ - 0.61)(θ² + 1): Hermite's cubic is exact.
        let g = |th: f64| {
            (
                (th - 0.61) * (th * th + 1.0),
                th * th + 1.0 + (th - 0.61) * 2.0 * th,
            )
        };
        let ((g0, s0), (g1, s1)) = (g(0.0), g(1.0));
        let (root, _) = hermite_root(g0, g1, s0, s1, None, tol).unwrap();
        assert!((root - 0.61).abs() <= tol * 0.01, "{root}");
    }

    #[test]
    fn a_converged_newton_step_ends_the_search_inside_the_bracket() {
        // A root Newton lands on exactly: its next step is 0 and must end the search
        // there, not bisect from an end (the bracket then closes on the root).
        let tol = 1e-8;
        let p = |th: f64| (th - 0.5, 1.0);
        let (root, slope) = bracketed_root(p, -0.5, 0.5, tol).unwrap();
        assert_eq!(root, 0.5);
        assert_eq!(slope, 1.0);
        // No bracket, no root.
        assert!(bracketed_root(p, 0.5, 0.5, tol).is_none());
        assert!(hermite_root(0.1, 0.5, 1.0, 1.0, None, tol).is_none());
    }
}
