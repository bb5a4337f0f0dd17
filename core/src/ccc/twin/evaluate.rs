//! One staged evaluation of the current slot at a state, in the spirit of MuJoCo's
//! `mj_forwardSkip`: the equations of motion ([`Stage::Motion`]: kinematics, inputs,
//! `q̈`; [`Stage::Loads`]: inputs and `q̈` at the kinematics held), the bodies' accelerations ([`Stage::Accelerations`]), the kinetostatics
//! ([`Stage::Reactions`]) and the readout ([`Stage::Readout`]: clutch torques and event
//! functions), each a function; [`Twin::evaluate_from`] runs them from a given stage on,
//! for a workspace that already holds the stages before it.

use super::error::TwinStepError;
use super::guards::Guards;
use super::inputs::Inputs;
use super::slot::LinkState;
use super::{Twin, Work};
use crate::dynamics::finish_accelerations;
use crate::kinetostatics::reactions;
use crate::scalar::Real;
use crate::structomat::Angles;

/// A stage of the evaluation of a slot, in order: each runs after those before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Stage {
    /// Kinematics (positions, velocities), the motor and load torques, `q̈`.
    Motion,
    /// The motor and load torques and `q̈` at the kinematics the workspace holds (the
    /// same state under new inputs).
    Loads,
    /// The bodies' accelerations from `q̈` (after an accepted DP5 step the workspace
    /// holds the motion of its last stage, `f(t1, y1)`: FSAL).
    Accelerations,
    /// The kinetostatics: the joint reactions, from which the clutch torques follow.
    Reactions,
    /// Only the readout of what the workspace holds: clutch torques, event functions.
    Readout,
}

/// Where the readout's clutch torques come from.
#[derive(Clone, Copy, Debug)]
pub(super) enum Torques<'a, T> {
    /// From the slot's kinetostatics.
    Kinetostatics,
    /// From the mode choice's screen (N·m), which stood for the kinetostatics.
    Screened([T; 2]),
    /// From the kinetostatics, unless it can wait: a speed function fired since the
    /// event functions `g0` at the start of the DP5 step of length `h` (s) this state
    /// ends, and the torque functions cannot have crossed (`torques_can_wait`). The
    /// step then goes on from the event inside it, and this state, with the clutch
    /// torques of the step's start, is dropped. It spared 7-8k instructions of the
    /// 12-16k kinetostatics of a Newton-group model at S2's slowest event steps.
    DeferAtSpeedEvent(&'a Guards<T>, T),
}

/// What the clutch torques the twin holds come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TorqueSource {
    /// The current slot's kinetostatics at the state.
    Kinetostatics,
    /// The mode choice's screen, or the last ones kept while the kinetostatics waited
    /// at a speed event: a state is committed only with the kinetostatics' own, which
    /// a re-evaluation of it (after a failed step) reproduces.
    Kept,
}

impl<T: Real> Twin<T> {
    /// Evaluates the current slot at `w`'s state from `stage` on (the workspace holds
    /// the stages before it at that state), the clutch torques from `torques`; returns
    /// where they came from (also kept in the twin, for [`Twin::settle_clutch_torques`]).
    /// Not inlined: inlined into `advance` it raised the f32 step's stack high-water
    /// from 9.0 to 11.7 KB, into the mode choice the f64 step's by 3.7 KB
    /// (`tests/footprint.rs`).
    #[inline(never)]
    pub(super) fn evaluate_from(
        &mut self,
        stage: Stage,
        w: &Work<T>,
        inputs: &Inputs<T>,
        torques: Torques<'_, T>,
    ) -> Result<TorqueSource, TwinStepError> {
        if stage <= Stage::Loads {
            self.stage_motion(w, inputs, stage == Stage::Motion)?;
        }
        if stage <= Stage::Accelerations {
            let slot = self.slots.cur_mut();
            finish_accelerations(&slot.model, &mut slot.ws);
        }
        let links = self.slots.cur().links(&self.params);
        let kept = match torques {
            Torques::Kinetostatics => None,
            Torques::Screened(c) => Some(c),
            // The torque functions from the start's clutch torques: as at the start.
            Torques::DeferAtSpeedEvent(g0, h) => (self.torques_can_wait(g0, h) && {
                let g = self.guards_of(self.slots.cur(), &links, &self.c, inputs, w.t);
                g0.fired(&g).any_speed()
            })
            .then_some(self.c),
        };
        if stage <= Stage::Reactions && kept.is_none() {
            self.stage_reactions(w)?;
        }
        Ok(self.readout(&links, inputs, kept, w.t))
    }

    /// [`Stage::Motion`]: the slot's equations of motion at `w`'s state, its
    /// `kinematics` solved, or ([`Stage::Loads`]) as the workspace holds them.
    fn stage_motion(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
        kinematics: bool,
    ) -> Result<(), TwinStepError> {
        let friction = self.lossy.then_some(&self.params.friction);
        let loads = (self.drive, friction, self.coast.omega_at(w.t));
        let angles = kinematics.then_some(Angles::Record);
        self.slots
            .cur_mut()
            .eval_with(w.t, &w.y, inputs, loads, angles)
            .map_err(|e| self.physical_error(e))
    }

    /// [`Stage::Reactions`]: the slot's kinetostatics.
    fn stage_reactions(&mut self, w: &Work<T>) -> Result<(), TwinStepError> {
        let slot = self.slots.cur_mut();
        reactions(&slot.model, &mut slot.ws, w.t.to_f64()).map_err(|e| self.physical_error(e))
    }

    /// [`Stage::Readout`]: the clutch torques (`kept`, or the slot's from its
    /// kinetostatics) and the event functions and their rates at the slot's physical
    /// `links` (at time `t`).
    fn readout(
        &mut self,
        links: &[LinkState<T>; 9],
        inputs: &Inputs<T>,
        kept: Option<[T; 2]>,
        t: T,
    ) -> TorqueSource {
        self.torque_source = if kept.is_some() {
            TorqueSource::Kept
        } else {
            TorqueSource::Kinetostatics
        };
        self.c = kept.unwrap_or_else(|| self.slots.cur().clutch_torques(&self.params, links));
        self.guards = self.guards_of(self.slots.cur(), links, &self.c, inputs, t);
        self.guard_rates = self.guard_rates_of(self.slots.cur(), links);
        self.torque_source
    }

    /// The full evaluation at `w`'s state where the integration goes on from it: the
    /// next DP5 step from there takes its first stage from this evaluation (after a
    /// mode change or a coordinate switch the rest of the step then takes 6
    /// evaluations, not 7).
    pub(super) fn restart_at(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        self.evaluate_from(Stage::Motion, w, inputs, Torques::Kinetostatics)?;
        self.seed_first_stage(w, inputs);
        Ok(())
    }

    /// [`Twin::restart_at`] under new inputs at the state the step starts from: the
    /// kinematics as the workspace holds them if it holds the state's
    /// (`w.state_evaluated`, the last step's end), only the loads and `q̈` anew. The
    /// torque functions jump with the inputs: no earlier sample of them fits. The
    /// same bits as a full evaluation (the kinematics are a function of the state);
    /// S2 in f64 at h = 1 ms under a torque that changes every step: 11.8k x86_64
    /// instructions a step more than under a constant one, of which this spares
    /// the kinematics.
    pub(super) fn restart_under_new_inputs(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        self.last_guards = None;
        let stage = if core::mem::take(&mut w.state_evaluated) {
            Stage::Loads
        } else {
            Stage::Motion
        };
        self.evaluate_from(stage, w, inputs, Torques::Kinetostatics)?;
        self.seed_first_stage(w, inputs);
        Ok(())
    }

    /// Hands the slot's evaluation at `w`'s state (made in full) to the DP5 stepper as
    /// the first stage of a step from there.
    pub(super) fn seed_first_stage(&mut self, w: &Work<T>, inputs: &Inputs<T>) {
        let k1 = self.slots.cur().rates(
            &w.y,
            inputs,
            self.drive,
            self.lossy.then_some(&self.params.friction),
            self.coast.omega_at(w.t),
        );
        self.dp5.seed(w.t, &w.y, &k1);
    }

    /// The kinetostatics of the state the step ends at, if its clutch torques are
    /// still kept from the screen (the choice was the step's last evaluation).
    pub(super) fn settle_clutch_torques(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        if self.torque_source == TorqueSource::Kept {
            self.evaluate_from(Stage::Accelerations, w, inputs, Torques::Kinetostatics)?;
        }
        Ok(())
    }
}
