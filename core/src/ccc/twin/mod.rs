//! The twin: fixed-step DP5 on the current mode's model, with the mechanical diode's
//! events located inside the step from the dense output, the new mode chosen by SPEC 3's
//! consistency conditions, plastic impacts, and coordinate switches at dead points.
//!
//! The rooms, one idea each: the step itself ([`Twin::step`], here); the twin's
//! construction, by value or in place (`construction.rs`), and what its models need of
//! the core's capacities (`capacity.rs`); its settings,
//! bounds and thresholds (`settings.rs`); its inputs (`inputs.rs`) and what it reports
//! (`outputs.rs`); its errors (`error.rs`); the event functions (`guards.rs`) and their
//! location inside a step (`locate.rs`); the mode choice at an event (`choice.rs`),
//! each candidate built and judged (`candidate.rs`) by the consistency conditions
//! (`consistency.rs`) after the plastic impact (`impact.rs`); coordinate choice and
//! switching (`coordinates.rs`); a correction of the state in crank terms, an
//! observer's update (`correction.rs`); one mode's model and workspace (`slot.rs`), the three
//! working slots (`slots.rs`) and their staged evaluation (`evaluate.rs`); the energy
//! audit (`audit.rs`) and the sub-steps a step takes when it breaks the balance
//! (`rungs.rs`); the state at an event checked before its choice (`event_state.rs`);
//! an event's work spread over the steps after it, for a real-time
//! loop's worst step (`spread.rs`).
//!
//! The twin's contract (bounded work, no allocation, size, step sizes, placement in
//! firmware) is on [`Twin`].

mod audit;
mod candidate;
mod capacity;
mod choice;
mod coast;
mod consistency;
mod construction;
mod coordinates;
mod correction;
mod error;
mod evaluate;
mod event_state;
mod guards;
mod held_lever;
mod impact;
pub(crate) mod inputs;
mod locate;
mod mass;
mod outputs;
mod rungs;
mod settings;
mod slot;
mod slots;
mod spread;

pub use audit::Audit;
pub use capacity::Converter;
pub use coordinates::CoordinateSwitch;
use coordinates::Leave;
pub use correction::Correction;
pub use error::{Failure, TwinSetupError, TwinStepError};
pub use guards::{Event, EventKind};
pub use inputs::{Encoder, Inputs, Measurement, MotorInput, MAX_CONVERTER_LOAD};
pub use outputs::EncoderResiduals;
pub use settings::{
    energy_tolerance, TwinSettings, CATCH_UP, DIODE_HORIZON_STEPS, ENERGY_TOL_STEP,
    MAX_EVENTS_PER_STEP, MAX_LOCATE_ITER, MAX_RETRIES, SINGULAR_CONDITIONING, SUBSTEPS,
};
pub use slot::{LinkState, JOINTS, JOINT_NAMES};

use super::mode::{Clutch, Coordinates, Mode};
use super::params::CccParams;
use crate::error::StepError;
use crate::integrator::Dp5;
use crate::scalar::{same_bits, Real, Vec2};
use crate::workspace::WarmStart;
use coast::{lever_driven, Coast};
use evaluate::{Stage, TorqueSource, Torques};
use guards::Guards;
use inputs::{check_inputs, same_inputs, Held};
use nalgebra::SVector;
use rungs::JumpHistory;
use settings::{EARLY_AUDIT_MARGIN, RETRY_SUBSTEPS};
use slot::{unwrap_near, Equations, Slot, QD, STATE};
use slots::Slots;
use spread::Pending;

/// The twin of one converter: its parameters, settings and state, and the working
/// models of its modes.
///
/// # Contract
///
/// **Bounded work per step.** A step is at most 7 attempts (1, 2, 3, 4, 16, 32 and 64
/// DP5 steps between events, 2, 3, 32 and 64 only when the energy check predicts they
/// pass, and the rungs below 3 or finer skipped when the last steps' energy jumps
/// predict that they fail: 122 steps' work in all; [`SUBSTEPS`] are the core's rungs),
/// each with at most [`MAX_EVENTS_PER_STEP`] events, each located in at most
/// [`MAX_LOCATE_ITER`] evaluations and settled by at most 7 candidate modes of at most 3
/// coordinate choices each, and at most [`MAX_RETRIES`] coordinate switches inside the
/// step (after a failed sub-step, or at a sub-step's end where the choice is under half
/// of [`TwinSettings::switch_below`]: a look at the others there, one a sub-step). Every
/// evaluation's groups solve in closed form or by Newton-Raphson in at most
/// [`NEWTON_MAX_ITER`](crate::config::NEWTON_MAX_ITER) iterations (a group that does not
/// converge fails the evaluation); the event root finders stop after 40 iterations. When a step holds more events than the bound, the rest of the step is
/// integrated in the last mode chosen and the pending sign changes are handled at the
/// start of the next step (the event functions are re-checked there): no event is
/// lost, it is late by under one step, and the twin cannot chatter.
///
/// **No allocation, no panic.** All state is inline (`heapless` vectors for the logs of
/// a step); no indexing on the step path can panic, and a failed step returns an error
/// and keeps the last good state.
///
/// **Size.** `size_of::<Twin<f64>>()` is 63 584 B (62.1 KiB), `Twin<f32>` 32 768 B
/// (32.0 KiB) on x86_64: three slots, each a model and a workspace sized for the
/// converter; the mode choice builds its reference model in the one it leaves free
/// (the core asserts the budgets at compile time: 64 KiB and 32 KiB). A step's
/// stack high-water is about 10.7 KiB in f64 and 8.0 KiB in f32 on x86_64 in release
/// (S2, events included), 12.2 and 8.1 KiB painted on the Cortex-M boards.
///
/// **Step sizes.** h = 1e-4 s is the reference in f64 (S2's events within 1e-6 s of
/// h = 5e-5 s); h = 2e-4 s is the recommended f32 step (S2's crank within 7.5e-6 rad of
/// f64's at 0.5 s where 1 ms is 1.9e-4 rad off, half the work of 1e-4 s; f32's error is
/// rounding, and up to h = 1 ms no f32 step of S2 is redone in sub-steps). At h = 1 ms
/// in f64 the twin keeps h = 1e-4 s's events at every operating point of
/// `host-sim/sweeps/loop-step.toml` that runs through; under light loads some of its
/// steps take 16 to 64 sub-steps (11 to 14 times S2's worst step).
///
/// **In firmware** the twin is far too large for a stack: it lives in a `static` and is
/// built there by [`Twin::new_in`], which initialises it in place (construction needs
/// 7.5 KiB of stack on a Cortex-M4F in f32 and 11.3 KiB on a Cortex-M7 in f64, painted
/// under QEMU, where [`Twin::new`], which returns it by value, needs 219 and 445 KiB).
/// Only [`Twin::step`] and the outputs are called after that.
///
/// **The worst step.** A step with an event holds two DP5 steps, the event's location
/// and the mode choice. Where the loop's budget is its worst step,
/// [`TwinSettings::spread_events`] spreads that work over the steps after the event;
/// the twin's time then lags the clock by a few steps ([`Twin::lag`]). S2 at 1 kHz on a
/// Cortex-M4F in f32: 107 k Thumb-2 instructions at worst spread, 228 k without.
///
/// # Example
///
/// ```
/// use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
/// let inputs = Inputs { motor: MotorInput::Torque(20.0), load: 0.0, measured: None };
/// let mut twin = Twin::new(CccParams::<f64>::reference(), TwinSettings::reference(1e-4), inputs)
///     .expect("the reference converter assembles");
/// for _ in 0..10 {
///     twin.step(&inputs).expect("a step of S2's start");
/// }
/// assert_eq!(twin.steps(), 10);
/// ```
///
/// # Firmware
///
/// The core of the repository's `checks/firmware/src/bin/example.rs` (a `no_std` binary
/// that runs it on an emulated Cortex-M4F): the twin in a `static`, built in place, and
/// a 1 kHz loop that reads the crank's encoder and the motor's torque sensor, steps the
/// twin with them and reads its mode and the measurement residual (with a
/// [`TwinObserver`](crate::ccc::TwinObserver) stepping it, the twin is also corrected
/// by the encoder). On the M4F the twin spreads its events to keep its worst step
/// within the period; while it is behind the clock its state is not the machine's at
/// the sample, so there is no residual then, the lag instead. The board's
/// functions are stubs here.
///
/// ```no_run
/// use core::mem::MaybeUninit;
/// use structomat::ccc::{CccParams, Inputs, Measurement, MotorInput, Twin, TwinSettings};
///
/// /// The twin's home: a static in `.bss`, never the stack. (cortex-m-rt's `#[entry]`
/// /// hands `main` its `static mut`s as `&'static mut`: the example does that.)
/// static mut TWIN: MaybeUninit<Twin<f32>> = MaybeUninit::uninit();
///
/// /// The loop's period, s: the twin's step.
/// const PERIOD: f32 = 1e-3;
/// /// Encoder counts per crank revolution.
/// const COUNTS_PER_REV: u32 = 4096;
/// /// The shaft's load, N·m.
/// const LOAD: f32 = 800.0;
/// # fn wait_for_tick() {}
/// # fn read_encoder() -> i64 { 0 }
/// # fn read_torque_sensor() -> f32 { 12.0 }
/// # fn report(_mode: &str, _angle_residual: f32) {}
/// # fn report_lag(_mode: &str, _lag: f32) {}
/// # fn report_refused(_e: &structomat::ccc::TwinStepError) {}
///
/// fn main() {
///     // SAFETY: the one reference to TWIN, taken once by the one context that uses it.
///     let place = unsafe { &mut *core::ptr::addr_of_mut!(TWIN) };
///     let start = Inputs { motor: MotorInput::Torque(12.0), load: LOAD, measured: None };
///     let mut settings = TwinSettings::reference(PERIOD);
///     settings.spread_events = true;
///     let Ok(twin) = Twin::new_in(place, CccParams::reference(), settings, start) else {
///         panic!("the converter does not assemble");
///     };
///     // The encoder's count 0 is the crank's angle at the start.
///     let zero = twin.link(1).theta;
///     loop {
///         wait_for_tick();
///         let inputs = Inputs {
///             motor: MotorInput::Torque(read_torque_sensor()),
///             load: LOAD,
///             measured: Some(Measurement::crank(read_encoder(), COUNTS_PER_REV, zero)),
///         };
///         // A refused step (a bad reading) keeps the twin's last good state.
///         if let Err(e) = twin.step(&inputs) {
///             report_refused(&e);
///         }
///         match twin.measurement_residual().and_then(|r| r.crank) {
///             Some(da) => report(twin.mode().name(), da),
///             None => report_lag(twin.mode().name(), twin.lag()),
///         }
///     }
/// }
/// ```
#[derive(Clone, Debug)]
pub struct Twin<T: Real> {
    params: CccParams<T>,
    settings: TwinSettings<T>,
    drive: T,
    /// The current slot, the backup and the candidate slot ([`Slots`]).
    slots: Slots<T>,
    dp5: Dp5<T, STATE>,
    y: SVector<T, STATE>,
    t: T,
    steps: u64,
    /// The last step's motor, load and encoder angles.
    inputs: Held<T>,
    links: [LinkState<T>; 9],
    shaft_angle: T,
    /// The shaft's motion while it coasts ([`Mode::Coast`]), taken from the step's
    /// start (or the coasting's) on.
    coast: Coast<T>,
    c: [T; 2],
    joints: [Vec2<T>; 11],
    guards: Guards<T>,
    /// Time derivatives of the speed event functions at the last full evaluation
    /// (rad/s²; `None` for the others): the slopes of [`hermite_root`](locate::hermite_root)'s interpolant.
    guard_rates: Guards<T>,
    /// The event functions at the start of the last DP5 step, if it had no event, and
    /// its length (s): a third sample of a torque function for [`quadratic_root`](locate::quadratic_root), a
    /// fifth of a speed function for [`hermite_root`](locate::hermite_root).
    last_guards: Option<(Guards<T>, T)>,
    audit: Audit<T>,
    // The logs' lengths in a byte (their capacities are under 256): 4 B of the f32
    // twin's 32 KiB each.
    events: heapless::Vec<Event<T>, MAX_EVENTS_PER_STEP, u8>,
    switches: heapless::Vec<CoordinateSwitch<T>, { MAX_RETRIES + 1 }, u8>,
    candidates: heapless::Vec<(Mode, T), 8, u8>,
    /// Where `c` came from: a state is committed only with the current slot's own
    /// kinetostatics.
    torque_source: TorqueSource,
    /// The last step ended at rest (jam) through [`Twin::advance`]'s rest branch: the
    /// current slot's workspace, guards and clutch torques are the full evaluation of
    /// the committed state under the last step's inputs ([`Twin::repeats_at_rest`]).
    at_rest: bool,
    /// Any of the losses of `params.friction` is on (`Friction::active`, taken once):
    /// without, the equations skip every friction term.
    lossy: bool,
    /// The last two steps' energy jumps, from which the next step's first rung is
    /// predicted ([`JumpHistory::start_rung`]).
    jumps: JumpHistory,
    /// What the last step left to this one ([`TwinSettings::spread_events`]).
    pending: Option<Pending>,
    /// The last step was a plain one that passed the energy check undivided: the next
    /// may catch up with the clock ([`TwinSettings::spread_events`]).
    may_catch_up: bool,
    /// The twin's time is behind the clock's `n·h` ([`TwinSettings::spread_events`]).
    behind: bool,
    /// The current slot's workspace holds the full evaluation of the committed state
    /// (an accepted step's last DP5 stage, FSAL; `tests.rs` checks it bit for bit after
    /// every step): a step under new inputs takes its kinematics as they are and
    /// evaluates only the loads and `q̈` anew ([`Stage::Loads`]). Taken by the step's
    /// first attempt, set by its commit; a correction of the state between steps
    /// clears it.
    state_evaluated: bool,
    /// The coordinates a step left because its energy balance broke in them on every
    /// rung ([`Twin::redo_in_other_coordinates`]): not taken back for a better
    /// conditioning alone ([`Leave::IfBetter`]) until the mode changes or they are
    /// conditioned at least `switch_below` again ([`Twin::return_to_preferred`]).
    broke_in: Option<Coordinates>,
}

/// The working state of a step, committed only when the whole step succeeds.
struct Work<T: Real> {
    t: T,
    y: SVector<T, STATE>,
    impact: T,
    switched: bool,
    /// The mode choice took a mode in this step, and with it the coordinate choice
    /// [`Twin::try_candidate`] found best at the event.
    chosen: bool,
    /// The shaft's rotation over the step's segments before the present one (between
    /// the step's start and events), rad: the engaged lever's rotation in each segment
    /// whose mode turns the shaft, by the mode of that segment.
    shaft_turn: T,
    /// Levers 6 and 8's angles at the present segment's start, rad (unwrapped against
    /// the last committed ones).
    segment_levers: [T; 2],
    /// Check the energy balance at each event, before its mode choice
    /// ([`Twin::balance_within`]), and fail the attempt there if it already breaks by
    /// [`EVENT_AUDIT_MARGIN`](settings::EVENT_AUDIT_MARGIN) times the tolerance.
    audit_at_events: bool,
    /// The attempt's sub-steps (its rung, for [`TwinStepError::Diverged`]).
    substeps: u32,
    /// The state `w` holds is an event's that passed the check of `audit_at_events`
    /// ([`Twin::event_state`]): the mode choice does not check it again.
    event_audited: bool,
    /// An event's state was taken by a DP5 step of its own in this attempt
    /// ([`Twin::event_state`]; once an attempt, which bounds the steps it adds).
    restepped: bool,
    /// The step ended in the rest branch of [`Twin::advance`] (its last evaluation the
    /// full one of the state at rest, at the step's end).
    at_rest: bool,
    /// The last energy check's jump over its tolerance: the one that failed the
    /// attempt (over 1), from which [`rung_may_pass`](rungs::rung_may_pass) predicts the next rung, or the
    /// step's end's that passed, from which the next step's first rung is predicted
    /// ([`JumpHistory`]).
    excess: Option<T>,
    /// What the step leaves to the next ([`TwinSettings::spread_events`]).
    pending: Option<Pending>,
    /// The location's last evaluation, at the event the step ends at, was a full one
    /// ([`TwinSettings::spread_events`]).
    evaluated_at_event: bool,
    /// The return to the preferred coordinates the last step left to this one failed:
    /// this step's end does not leave it to the next again.
    return_failed: bool,
    /// The step's new inputs were taken before its integration (at a pending return,
    /// [`Twin::settle_pending`]): the state is evaluated under them.
    inputs_taken: bool,
    /// The current slot's workspace holds the kinematics of the state the step starts
    /// from ([`Twin::state_evaluated`], taken by the first attempt), until the step's
    /// first evaluation under its new inputs.
    state_evaluated: bool,
    /// The step ends short of the clock ([`TwinSettings::spread_events`]).
    behind: bool,
}

impl<T: Real> Twin<T> {
    /// One step of `h` under `inputs` (held over the step). On error the twin keeps the
    /// state of the last good step, including what it reports of that step (events,
    /// coordinate switches, the candidates of the last mode choice).
    pub fn step(&mut self, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
        check_inputs(inputs, self.t)?;
        if self.repeats_at_rest(inputs) {
            return self.step_at_rest(inputs);
        }
        // Set again by a step committed at rest.
        self.at_rest = false;
        let changed = !same_inputs(&self.inputs, inputs);
        let mut saved = WarmStart::new();
        self.slots.cur().save_warm_start(&mut saved);
        // The last good step's log: an attempt rewrites it. Its events and switches
        // are copied only if there are any (after most steps there are none: the
        // copies of their full buffers, 416 B in f64, cost the M7 ~200 instructions a
        // step); the last mode choice's candidates stand until the next choice.
        let log = (
            (!self.events.is_empty()).then(|| self.events.clone()),
            (!self.switches.is_empty()).then(|| self.switches.clone()),
            self.candidates.clone(),
        );
        let start = self.jumps.start_rung();
        if start > 1 {
            crate::trace::debug!(
                "t = {:.6} s: the step starts in {start} sub-steps (the last steps' energy jumps)",
                self.t.to_f64()
            );
        }
        // How far the attempt's energy balance broke (see `Work::excess`).
        let mut excess = None;
        let mut result = self.attempt(inputs, changed, changed, start, &saved, &mut excess);
        let first_jump = excess;
        let mut progress = (start, excess);
        if matches!(&result, Err(e) if e.retry_finer()) {
            let floor = self.tolerance_at_rounding_floor();
            result = self.climb(inputs, changed, result, &mut progress, &saved, floor);
        }
        // A step that fails near the diode's limit is the mechanism's singularity, also
        // when rounding (f32) breaks the energy balance some steps before the groups'
        // conditioning falls under SINGULAR_CONDITIONING. Elsewhere a balance broken on
        // every rung may pass in other coordinates; no choice drives past the diode.
        let diode = match &result {
            Err(e) if e.retry_finer() => self.diode_in_line(),
            _ => None,
        };
        if matches!(&result, Err(TwinStepError::Diverged { .. })) {
            if diode.is_none() && self.redo_in_other_coordinates(inputs, changed, &saved) {
                result = Ok(());
            } else if matches!(&result, Err(TwinStepError::Diverged { stalled: true, .. })) {
                // The climb stopped where the jump stalled: its finer rungs in these
                // coordinates, before the step is refused.
                result = self.climb(inputs, changed, result, &mut progress, &saved, false);
            }
        }
        let Err(failure) = result else {
            let eventful = !(self.events.is_empty() && self.switches.is_empty());
            self.jumps = self.jumps.after(start, first_jump, eventful);
            self.may_catch_up = !eventful
                && self.pending.is_none()
                && start == 1
                && first_jump.is_some_and(|j| j < T::one());
            return Ok(());
        };
        let (events, switches, candidates) = log;
        match events {
            Some(e) => self.events = e,
            None => self.events.clear(),
        }
        match switches {
            Some(s) => self.switches = s,
            None => self.switches.clear(),
        }
        self.candidates = candidates;
        Err(diode.unwrap_or(failure))
    }

    /// Whether a step under `inputs` can only repeat the last one at rest: that step
    /// ended in the jam through [`Twin::advance`]'s rest branch, and the inputs are the
    /// same and give the crank the same motor torque, bit for bit, at any time (no user
    /// law of time). The rest branch's evaluation at the new step's end is then a
    /// function of the same state and torques (the jam's model is dyads in closed form
    /// with no degree of freedom: no time, no Newton warm start enters it), so it
    /// reproduces the workspace, guards, clutch torques, links, reactions and audit the
    /// twin holds. S2 rests from its jam at 0.8185 s to its end: 18 % of its steps.
    fn repeats_at_rest(&self, inputs: &Inputs<T>) -> bool {
        if !self.at_rest || self.slots.cur().mode != Mode::Jam || !same_inputs(&self.inputs, inputs)
        {
            return false;
        }
        if self.inputs.motor.is_user_law() || inputs.motor.is_user_law() {
            return false;
        }
        // Without a user law the torque is a function of the crank's speed alone.
        let omega = self.links[1].omega;
        let zero = T::zero();
        same_bits(
            self.inputs.motor.torque(zero, zero, omega),
            inputs.motor.torque(zero, zero, omega),
        )
    }

    /// The step [`Twin::repeats_at_rest`] allows: what a full step at rest commits
    /// (the time `(n + 1)·h`, the step count, no event or switch, the inputs; the
    /// state, outputs and audit as they are), without its evaluation.
    fn step_at_rest(&mut self, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
        let t_end = self.step_end()?;
        self.events.clear();
        self.switches.clear();
        self.t = t_end;
        self.steps += 1;
        // The full step adds the rest's shaft turns, 0 + 0, and no impact loss to the
        // audit's (the same bits, a -0 included).
        self.shaft_angle += T::zero() + T::zero();
        self.audit.impact_loss += T::zero();
        self.inputs = Held::of(inputs);
        Ok(())
    }

    /// One attempt at the step in at most `substeps` DP5 steps between events,
    /// committed if it succeeds; on an error the twin is back at its last good state
    /// (the current slot's warm starts `saved`). `changed`: the inputs differ from the
    /// last step's; `fresh`: the integrator's last stage is not the first of this
    /// attempt (the inputs changed). A failed attempt's restore evaluates the step's
    /// start anew and seeds DP5 with it under the last step's inputs
    /// ([`Twin::restore`]): with the same inputs, the retry's first stage.
    fn attempt(
        &mut self,
        inputs: &Inputs<T>,
        changed: bool,
        fresh: bool,
        substeps: u32,
        saved: &WarmStart<T>,
        excess: &mut Option<T>,
    ) -> Result<(), TwinStepError> {
        self.events.clear();
        self.switches.clear();
        if fresh {
            self.dp5.invalidate();
        }
        let coast = self.coast;
        self.coast_from_state(inputs.load);
        let mut w = self.work_from_state();
        w.state_evaluated = core::mem::take(&mut self.state_evaluated);
        // Every rung but the finest may stop at an event whose state already breaks the
        // energy balance: a finer one redoes the step, its event and mode choice anyway.
        w.audit_at_events = RETRY_SUBSTEPS.last().is_some_and(|n| substeps < *n);
        w.substeps = substeps;
        let advanced = self.advance(&mut w, inputs, changed, substeps);
        // The physical links the check and the commit read, made where they stay (as
        // a result's part they were moved twice: 504 B in f64).
        let links = self.slots.cur().links(&self.params);
        let result = advanced.and_then(|()| self.check_energy(&mut w, &links));
        *excess = w.excess;
        match result {
            Ok(audit) => {
                self.y = w.y;
                self.steps += 1;
                self.commit(&w, audit, &links);
                self.inputs = Held::of(inputs);
                self.at_rest = w.at_rest;
                self.pending = w.pending;
                self.behind = w.behind;
                self.state_evaluated = true;
                Ok(())
            }
            Err(e) => {
                self.restore(w.switched, saved);
                self.coast = coast;
                Err(e)
            }
        }
    }

    /// A step's working state, starting from the twin's last good state.
    fn work_from_state(&self) -> Work<T> {
        Work {
            t: self.t,
            y: self.y,
            impact: T::zero(),
            switched: false,
            chosen: false,
            shaft_turn: T::zero(),
            segment_levers: [self.links[6].theta, self.links[8].theta],
            audit_at_events: false,
            substeps: 1,
            event_audited: false,
            restepped: false,
            at_rest: false,
            excess: None,
            pending: None,
            evaluated_at_event: false,
            return_failed: false,
            inputs_taken: false,
            state_evaluated: false,
            behind: false,
        }
    }

    /// Integrates from `w` to the end of the step in at most `substeps` DP5 steps
    /// between events, handling the events and coordinate switches on the way.
    fn advance(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        changed: bool,
        substeps: u32,
    ) -> Result<(), TwinStepError> {
        if self.settle_pending(w, inputs, changed)? {
            return Ok(());
        }
        // A step redone because its balance broke in these coordinates
        // ([`Twin::redo_in_other_coordinates`]) starts in the best other choice, or
        // not at all if none assembles. The switch counts among the step's
        // `MAX_RETRIES`.
        let left = self.broke_in == Some(self.slots.cur().coords);
        if left && !self.switch_coordinates(w, inputs, Leave::BalanceBroke)? {
            return Err(TwinStepError::Mechanism {
                time: w.t.to_f64(),
                mode: self.slots.cur().mode,
                failures: heapless::Vec::new(),
            });
        }
        let clock = self.step_end()?;
        let t_end = self.spread_step_end(w, clock);
        // Undivided without a conversion of `substeps` (f64's, a library's on the M4F).
        let h_max = match substeps {
            1 => self.settings.h,
            n => self.settings.h / T::c(f64::from(n)),
        };
        if changed && !w.inputs_taken {
            self.new_inputs(w, inputs)?;
        }
        let mut retries = usize::from(left);
        let mut events = 0;
        while w.t < t_end {
            if self.slots.cur().mode == Mode::Jam {
                // At rest: nothing moves until the inputs make another mode consistent.
                w.t = t_end;
                self.restart_at(w, inputs)?;
                w.at_rest = true;
                break;
            }
            let t0 = w.t;
            // The last sub-step takes what is left (no sliver of a step from rounding).
            let h = if t_end - t0 > h_max * T::c(1.5) {
                h_max
            } else {
                t_end - t0
            };
            if !self.dp5_step(w, inputs, h, retries < MAX_RETRIES)? {
                retries += 1;
                continue;
            }
            if self.sub_step_end(w, inputs, t0, h, events < MAX_EVENTS_PER_STEP)? {
                events += 1;
            } else if w.t < t_end
                && retries < MAX_RETRIES
                && self.slots.cur().conditioning() < self.settings.switch_below * T::c(0.5)
            {
                // A step redone in sub-steps may run into a dead point of its
                // coordinates that steps of the sub-step's length would have switched
                // away from at an end: the converter at light loads at h = 1 ms, where
                // after a catch into A68 the lever's conditioning fell to 0.033 (10/100
                // N·m, motor / load) and 2e-4 (22/200) inside a step, which then broke
                // the energy balance on every rung. Under half of `switch_below` only
                // (the step's end looks at `switch_below`): a choice near it still
                // drives a sub-step well, and switching there moved bench1's observed
                // release at 0.2866 s into the crank's Newton group (+160k Thumb-2
                // instructions on the Cortex-M7) for nothing. A switch made counts
                // among the step's `MAX_RETRIES`: the step's log holds them all.
                if self.switch_coordinates(w, inputs, Leave::IfBetter)? {
                    retries += 1;
                }
            }
            if let Some(Pending::Choice(_)) = w.pending {
                w.behind = true;
                return self.end_at_event(w, inputs);
            }
        }
        w.behind = t_end < clock;
        self.step_end_at(w, inputs, t_end)
    }

    /// The time `(n + 1)·h` the next step ends at, s.
    fn step_end(&self) -> Result<T, TwinStepError> {
        let h = self.settings.h;
        let t_end = T::c((self.steps + 1) as f64) * h;
        // The scalar must resolve the step: where its spacing u near t reaches h/2 a
        // step would be rounded to 0 or 2h and the twin's clock leave the machine's
        // (f32 at h = 1 ms from 8192 s on, at 2e-4 s from 1024 s). t + h/4 rounds
        // back to t where u/2 > h/4 (one add: the step count's conversion to
        // a float is a library call on the Cortex-M).
        if !(t_end.finite() && t_end + h * T::c(0.25) > t_end) {
            return Err(TwinStepError::TimeOverflow {
                steps: self.steps,
                h: self.settings.h.to_f64(),
            });
        }
        Ok(t_end)
    }

    /// Inputs changed: re-evaluates at `w` and sees whether the mode still holds.
    fn new_inputs(&mut self, w: &mut Work<T>, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
        self.restart_under_new_inputs(w, inputs)?;
        if self.settings.clutch && self.guards.any_past() {
            self.choose(w, EventKind::Inputs, inputs)?;
        }
        Ok(())
    }

    /// One DP5 step of `h` from `w` in the current slot; returns whether it was taken.
    /// If a group fails, `w` is back at the sub-step's start and, with `may_switch`,
    /// the coordinates are switched there (the sub-step is then to be redone);
    /// without, or for another error, the step fails.
    fn dp5_step(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        h: T,
        may_switch: bool,
    ) -> Result<bool, TwinStepError> {
        let (t0, y0) = (w.t, w.y);
        let saved = self.slots.cur().ws.unknowns();
        let mut sys = Equations {
            slot: self.slots.cur_mut(),
            inputs,
            drive: self.drive,
            friction: self.lossy.then_some(&self.params.friction),
            coast: self.coast,
            inner: false,
        };
        let Err(e) = self.dp5.step(&mut sys, &mut w.t, &mut w.y, h) else {
            return Ok(true);
        };
        // Warm starts only: the step goes on from here (the cosines and sines are
        // taken anew from these unknowns).
        self.slots.cur_mut().ws.restore_unknowns(&saved);
        w.t = t0;
        w.y = y0;
        if !may_switch || !matches!(e, StepError::Group { .. }) {
            return Err(self.physical_error(e));
        }
        self.restart_at(w, inputs)?;
        self.switch_coordinates(w, inputs, Leave::Failed(e))?;
        Ok(false)
    }

    /// Evaluates the end of the DP5 step just taken from `t0` (length `h`) and, with
    /// `may_handle` (the step's events are not at their bound), handles the first event
    /// inside it: located, the state moved there, the new mode chosen. Returns whether
    /// it handled one.
    fn sub_step_end(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        t0: T,
        h: T,
        may_handle: bool,
    ) -> Result<bool, TwinStepError> {
        let (g0, r0) = (self.guards, self.guard_rates);
        // Deferring the kinetostatics costs an extra look at the event functions:
        // only worth it when a speed function is near its crossing (within 4 steps
        // at its rate at the start).
        let may_defer = self.settings.clutch
            && may_handle
            && g0.speed_guards().any(|(k, g)| {
                r0.get(k)
                    .is_some_and(|r| g + T::c(4.0) * h * r.abs() > T::zero())
            });
        let torques = if may_defer {
            Torques::DeferAtSpeedEvent(&g0, h)
        } else {
            Torques::Kinetostatics
        };
        self.evaluate_from(Stage::Accelerations, w, inputs, torques)?;
        let fired = g0.fired(&self.guards);
        if fired.is_empty() || !may_handle || !self.settings.clutch {
            self.last_guards = fired.is_empty().then_some((g0, h));
            return Ok(false);
        }
        if w.audit_at_events && self.slots.cur().mode != Mode::Coast {
            // A finer rung would redo this step: stop before the location if its end
            // already breaks the energy balance (see `EARLY_AUDIT_MARGIN`). Not in
            // coast: the coasting shaft's turn and the brake's work are booked at the
            // segment's end (`Twin::coast_to`), so the audit here would miss them (a
            // braked shaft's stop at 0.1553 s "broke" it by 1,480 tolerances on every
            // rung, and the step ended with `Diverged` once 16 sub-steps were no
            // longer the finest).
            let links = self.slots.cur().links(&self.params);
            self.balance_within(w, &links, T::c(EARLY_AUDIT_MARGIN))?;
        }
        let (theta, kind, evaluated) = self.locate(w, t0, h, (&g0, &r0), fired, inputs)?;
        self.last_guards = None;
        // f64 only (decided at compile time): f32's energy tolerance is its rounding
        // floor, 1.2e-4 of the scale, four orders over the dense output's error at S2's
        // events (70 f64 tolerances of 1e-8 at most), and no f32 step of S2 is redone
        // at h = 1 ms; the f32 twin's code stays within issue 18's 128 KB (2 KB more
        // with it).
        let audit_event = w.audit_at_events
            && core::mem::size_of::<T>() == 8
            && self.slots.cur().mode != Mode::Coast;
        if !evaluated {
            let mut ye = SVector::<T, STATE>::zeros();
            self.dp5.dense(theta, &mut ye);
            w.t = t0 + theta * h;
            w.y = ye;
            if self.settings.spread_events && !audit_event {
                // The step ends here, evaluated in full by `Twin::end_at_event`.
                return Ok(w.pend_choice(kind, false));
            }
            // The mode choice reads the old mode's positions and speeds only (the
            // new mode is evaluated in full): no accelerations or kinetostatics.
            self.slots
                .cur_mut()
                .eval_speeds(w.t, &w.y)
                .map_err(|e| self.physical_error(e))?;
        }
        if audit_event && !self.event_state(w, inputs, (&g0, kind), theta * h)? {
            // Stepped to just before the event: the segment goes on from there.
            return Ok(false);
        }
        if self.settings.spread_events {
            // A torque function is located on full evaluations; a speed function on
            // the speeds alone.
            let full = evaluated && matches!(kind, EventKind::Release(_) | EventKind::Breakaway);
            return Ok(w.pend_choice(kind, full));
        }
        self.choose(w, kind, inputs)?;
        Ok(true)
    }

    /// The step's end at `t_end`: back to the mode's preferred coordinates if they are
    /// conditioned again, else a coordinate switch if the current choice nears its
    /// dead point; the time exactly `t_end`, the clutch torques of the kinetostatics.
    fn step_end_at(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        t_end: T,
    ) -> Result<(), TwinStepError> {
        // Coordinates chosen at an event in this step stand until its end: the mode
        // choice took them by the same rule (the first conditioned at least
        // `switch_below`, else the best by 1.5) a fraction of the step ago. Scanning
        // again cost 24k instructions at S2's catches into A68, whose lever choice is
        // then at its dead point (the lever stops as it catches) and fails to assemble
        // each time. The next step's end scans as usual.
        if self.slots.cur().mode != Mode::Jam && !w.chosen {
            if self.settings.spread_events && !w.return_failed && self.return_predicted().is_some()
            {
                // The return is the next step's (`Twin::settle_pending`).
                w.pending = Some(Pending::Return);
            } else if !self.return_to_preferred(w, inputs)?
                && self.slots.cur().conditioning() < self.settings.switch_below
            {
                self.switch_coordinates(w, inputs, Leave::IfBetter)?;
            }
        }
        if !same_bits(w.t, t_end) {
            w.t = t_end;
            self.dp5.invalidate();
        }
        self.coast_to(w, t_end, self.coast.accel);
        self.settle_clutch_torques(w, inputs)
    }

    /// Physical angles of the slot's links, unwrapped against the last committed ones.
    fn slot_links_unwrapped(&self) -> [T; 9] {
        self.unwrapped(&self.slots.cur().links(&self.params))
    }

    /// The angles of the physical `links`, unwrapped against the last committed ones.
    fn unwrapped(&self, links: &[LinkState<T>; 9]) -> [T; 9] {
        let mut out = [T::zero(); 9];
        for ((o, now), last) in out.iter_mut().zip(links).zip(&self.links).skip(1) {
            *o = unwrap_near(now.theta, last.theta);
        }
        out
    }

    /// Makes the state after a successful step the twin's: physical links (angles
    /// unwrapped), shaft, clutch torques, reactions, the energy audit.
    fn commit(&mut self, w: &Work<T>, audit: Audit<T>, links: &[LinkState<T>; 9]) {
        self.t = w.t;
        // Link by link, each angle unwrapped against the last: the whole array moved
        // in was a `memcpy` call (504 B in f64), ~170 instructions a step dearer on
        // either board.
        for (last, l) in self.links.iter_mut().zip(links.iter()).skip(1) {
            *last = LinkState {
                theta: unwrap_near(l.theta, last.theta),
                ..*l
            };
        }
        let end = shaft_turn(self.slots.cur().mode, &self.links, &w.segment_levers);
        self.shaft_angle += w.shaft_turn + end;
        self.joints = self.slots.cur().joint_reactions(&self.params, &self.links);
        self.audit = audit;
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

/// The shaft's rotation since a segment's start (levers 6 and 8 at `start`, rad) to
/// the physical state `links`, in `mode`: the engaged lever's rotation if a lever
/// carries the shaft (it turns with it), else 0 (a coasting shaft's turn is booked by
/// [`Twin::coast_to`]), rad.
fn shaft_turn<T: Real>(mode: Mode, links: &[LinkState<T>; 9], start: &[T; 2]) -> T {
    if !lever_driven(mode) {
        return T::zero();
    }
    let (k, lever) = if mode.clutches()[0] == Clutch::Engaged {
        (0, 6)
    } else {
        (1, 8)
    };
    unwrap_near(links[lever].theta, start[k]) - start[k]
}

/// Shaft speed, rad/s CCW: the engaged lever's in an A mode, 0 otherwise (the coasting
/// shaft's is [`Twin::shaft_at`]).
fn shaft_speed<T: Real>(mode: Mode, links: &[LinkState<T>; 9]) -> T {
    match mode.clutches() {
        _ if !lever_driven(mode) => T::zero(),
        [Clutch::Engaged, _] => links[6].omega,
        _ => links[8].omega,
    }
}

/// Shaft acceleration, rad/s², as [`shaft_speed`].
fn shaft_accel<T: Real>(mode: Mode, links: &[LinkState<T>; 9]) -> T {
    match mode.clutches() {
        _ if !lever_driven(mode) => T::zero(),
        [Clutch::Engaged, _] => links[6].alpha,
        _ => links[8].alpha,
    }
}

#[cfg(test)]
mod tests;
