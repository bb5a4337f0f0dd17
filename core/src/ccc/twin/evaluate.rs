//! The evaluation of the current slot at a state: equations of motion, accelerations,
//! kinetostatics, clutch torques and event functions.

use super::error::TwinError;
use super::guards::Guards;
use super::slot::{Inputs, LinkState};
use super::{Twin, Work};
use crate::dynamics::finish_accelerations;
use crate::kinetostatics::reactions;
use crate::scalar::Real;

impl<T: Real> Twin<T> {
    /// The kinetostatics of the state the step ends at, if its clutch torques are
    /// still the mode choice's screen's (the choice was the step's last evaluation).
    pub(super) fn settle_clutch_torques(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinError> {
        if self.c_screened {
            self.finish_evaluated(w, inputs)?;
        }
        Ok(())
    }

    /// Evaluates the current slot at `w`'s state: equations of motion, accelerations,
    /// kinetostatics, the event functions.
    pub(super) fn evaluate_at(&mut self, w: &Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        self.slots
            .cur_mut()
            .eval(w.t, &w.y, inputs, self.drive)
            .map_err(|e| self.physical_error(e))?;
        self.finish_evaluated(w, inputs)
    }

    /// [`Twin::evaluate_at`] where the integration goes on from `w`'s state: the next
    /// DP5 step from there takes its first stage from this evaluation.
    pub(super) fn finish(&mut self, w: &mut Work<T>, inputs: &Inputs<T>) -> Result<(), TwinError> {
        self.evaluate_at(w, inputs)?;
        self.seed_first_stage(w, inputs);
        Ok(())
    }

    /// Hands the slot's evaluation at `w`'s state (just made, in full) to the DP5
    /// stepper as the first stage of a step from there: after a mode change or a
    /// coordinate switch the rest of the step then takes 6 evaluations, not 7.
    pub(super) fn seed_first_stage(&mut self, w: &Work<T>, inputs: &Inputs<T>) {
        let k1 = self.slots.cur().rates(&w.y, inputs, self.drive);
        self.dp5.seed(w.t, &w.y, &k1);
    }

    /// [`Twin::finish`] when the slot's workspace already holds the evaluation of `w`'s
    /// state (after an accepted DP5 step, whose last stage is `f(t1, y1)`, FSAL).
    pub(super) fn finish_evaluated(
        &mut self,
        w: &Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinError> {
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
    pub(super) fn finish_step(
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
                g0.fired(&g).any_speed()
            });
        if !deferred {
            let slot = self.slots.cur_mut();
            reactions(&slot.model, &mut slot.ws, w.t.to_f64())
                .map_err(|e| self.physical_error(e))?;
        }
        self.read_links(&links, inputs, deferred.then_some(self.c));
        Ok(())
    }

    /// The clutch torques and the event functions from the slot's workspace, which
    /// holds a full evaluation (accelerations and kinetostatics; or accelerations and
    /// the clutch torques `c`, from the mode choice's screen). Not inlined: inlined
    /// into the mode choice it added 3.7 KB to the f64 step's stack high-water
    /// (`tests/footprint.rs`: 19.1 KB instead of 15.5 KB).
    #[inline(never)]
    pub(super) fn read_evaluation(&mut self, inputs: &Inputs<T>, c: Option<[T; 2]>) {
        let links = self.slots.cur().links(&self.params);
        self.read_links(&links, inputs, c);
    }

    /// [`Twin::read_evaluation`] with the slot's physical `links` at hand.
    pub(super) fn read_links(
        &mut self,
        links: &[LinkState<T>; 9],
        inputs: &Inputs<T>,
        c: Option<[T; 2]>,
    ) {
        self.c_screened = c.is_some();
        self.c = c.unwrap_or_else(|| self.slots.cur().clutch_torques(&self.params, links));
        self.guards = self.guards_of(self.slots.cur(), links, &self.c, inputs);
        self.guard_rates = self.guard_rates_of(self.slots.cur(), links);
    }
}
