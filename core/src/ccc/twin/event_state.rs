//! The state at an event, for the energy check before its mode choice: the dense
//! output's, or the end of a DP5 step of its own from the same start
//! ([`Twin::event_state`]), nudged past a speed event's crossing if it ends just short
//! of it ([`Twin::nudge_past`]).

use super::error::TwinStepError;
use super::evaluate::{Stage, Torques};
use super::guards::{EventKind, Guard, Guards};
use super::inputs::Inputs;
use super::settings;
use super::slot::STATE;
use super::{Twin, Work};
use crate::dynamics::finish_accelerations;
use crate::scalar::Real;
use nalgebra::SVector;

/// The longest first-order step [`Twin::nudge_past`] takes past a speed event, as a
/// fraction of the step: 17 times the dense output's largest error in S2's crossing
/// times at h = 1 ms (5.7e-6).
const NUDGE_MAX: f64 = 1e-4;

impl<T: Real> Twin<T> {
    /// The state at event `kind` located `h_e` (s) into the DP5 step just taken (the
    /// event functions `g0` at its start), checked by the energy balance
    /// (`w.audit_at_events`) before the mode choice: the dense output's state there,
    /// or, if that breaks the balance by
    /// [`EVENT_AUDIT_MARGIN`](settings::EVENT_AUDIT_MARGIN) times the tolerance, the
    /// end of a DP5 step of `h_e` from the same start (its first stage kept: 6
    /// evaluations), once an attempt. The dense output is DP5's 4th-order extension,
    /// a step's end its 5th-order solution: in S2 at h = 1 ms in f64 the catch at
    /// 0.1763 s breaks the balance by 70 tolerances at the dense output, where the end
    /// of the step that found it, 0.74 ms later, breaks it by under 2. Without this the
    /// attempt fails there and the step is redone in sub-steps, its event located and
    /// its mode chosen again. The step's end differs from the dense output by the
    /// latter's error, which may put it just before the crossing (a release's clutch
    /// torque still positive): returns `false` then, the step's end evaluated in full
    /// (its event functions the next segment starts from), and the next DP5 step
    /// finds the event at its very start, where its dense output is nearly exact. On
    /// an error (the step's state still breaks the balance, or the step fails) the
    /// attempt fails as it would have. Not while the shaft coasts: its analytic motion
    /// is booked at the choice ([`Twin::coast_to`]). Not inlined: its frame (a DP5
    /// step, a state's copies) would stand under the mode choice's too (the M7's step
    /// stack 14.2 → 15.5 KB inlined).
    #[inline(never)]
    pub(super) fn event_state(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        (g0, kind): (&Guards<T>, EventKind),
        h_e: T,
    ) -> Result<bool, TwinStepError> {
        let margin = T::c(settings::EVENT_AUDIT_MARGIN);
        let links = self.slots.cur().links(&self.params);
        if let Err(e) = self.balance_within(w, &links, margin) {
            let seeded = if w.restepped {
                None
            } else {
                self.dp5.seed_last_start()
            };
            let Some((t0, y0)) = seeded else {
                return Err(e);
            };
            crate::trace::debug!(
                "t = {:.6} s: {} taken at the end of a DP5 step of its own (the dense output's state broke the energy balance by {:?} of its tolerance)",
                w.t.to_f64(),
                kind.name(),
                w.excess
            );
            w.restepped = true;
            w.t = t0;
            w.y = y0;
            self.dp5_step(w, inputs, h_e, false)?;
            if !self.crossed_at_step_end(w, inputs, g0, kind)? {
                return Ok(false);
            }
            let links = self.slots.cur().links(&self.params);
            self.balance_within(w, &links, margin)?;
        }
        w.event_audited = true;
        Ok(true)
    }

    /// Whether event `kind`'s function, at most 0 in `g0`, is past 0 at `w`, the end of
    /// the DP5 step [`Twin::event_state`] took (the slot evaluated there by its last
    /// stage). A speed function is read from the kinematics; a torque function needs
    /// the kinetostatics, and so does a state the segment goes on from (not crossed:
    /// its event functions are the next step's start), which is then evaluated in full.
    fn crossed_at_step_end(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        g0: &Guards<T>,
        kind: EventKind,
    ) -> Result<bool, TwinStepError> {
        let Some(guard) = Guard::ALL.into_iter().find(|g| g.event() == kind) else {
            return Ok(true);
        };
        if guard.is_speed() {
            let links = self.slots.cur().links(&self.params);
            let g = self.guards_of(self.slots.cur(), &links, &self.c, inputs, w.t);
            if g0.fired(&g).contains(guard) || self.nudge_past(w, inputs, (g0, &g), guard)? {
                return Ok(true);
            }
        }
        self.evaluate_from(Stage::Accelerations, w, inputs, Torques::Kinetostatics)?;
        Ok(g0.fired(&self.guards).contains(guard))
    }

    /// A speed function `guard` (`g` its values at `w`, the end of the DP5 step
    /// [`Twin::event_state`] took, not yet past 0) crosses `δ = -g/ġ` later on this
    /// trajectory, `ġ` its rate there: within 1e-5 of the step at S2's events, the
    /// dense output's error in the crossing's time. For `δ` up to
    /// [`NUDGE_MAX`] of the step, `w` moves to `δ (1 + 1e-3)` on by a first-order Taylor
    /// step along the step's last stage `f(t, y)` (its error `δ² ÿ / 2`, about 1e-12 of
    /// the state at S2's, four orders under the DP5 step's own), evaluated in speeds as
    /// the dense output's state is for the mode choice. Returns whether the function
    /// is past 0 there; if not, `w` is as it was, the slot evaluated there again in
    /// speeds (the caller's full evaluation follows). Spares the DP5 step that would
    /// otherwise find the event at its very start (S2 at h = 1 ms in f64, the catch at
    /// 0.1763 s: 340 k -> 280 k Thumb-2 instructions on the Cortex-M7).
    fn nudge_past(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        (g0, g): (&Guards<T>, &Guards<T>),
        guard: Guard,
    ) -> Result<bool, TwinStepError> {
        let slot = self.slots.cur_mut();
        finish_accelerations(&slot.model, &mut slot.ws);
        let links = self.slots.cur().links(&self.params);
        let rate = self.guard_rates_of(self.slots.cur(), &links).get(guard);
        let (Some(v), Some(r)) = (g.get(guard), rate) else {
            return Ok(false);
        };
        let delta = -v / r * T::c(1.0 + 1e-3);
        if !(delta > T::zero() && delta <= self.settings.h * T::c(NUDGE_MAX)) {
            return Ok(false);
        }
        let (t, y) = (w.t, w.y);
        let mut f = SVector::<T, STATE>::zeros();
        self.dp5.dense_derivative(T::one(), &mut f);
        w.t = t + delta;
        w.y = y + f * delta;
        let speeds = |twin: &mut Self, w: &Work<T>| {
            twin.slots
                .cur_mut()
                .eval_speeds(w.t, &w.y)
                .map_err(|e| twin.physical_error(e))
        };
        speeds(self, w)?;
        let links = self.slots.cur().links(&self.params);
        let after = self.guards_of(self.slots.cur(), &links, &self.c, inputs, w.t);
        if g0.fired(&after).contains(guard) {
            return Ok(true);
        }
        w.t = t;
        w.y = y;
        speeds(self, w)?;
        Ok(false)
    }
}
