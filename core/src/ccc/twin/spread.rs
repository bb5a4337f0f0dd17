//! An event's work spread over the steps after it ([`TwinSettings::spread_events`]), for
//! a real-time loop whose budget is its worst step. Without it a step with an event
//! takes a DP5 step to the event, its location, the mode choice and a second DP5 step
//! to the step's end: on a Cortex-M4F in f32 up to 2.3 plain steps' worth of a 1 kHz
//! loop's budget. With it:
//!
//! 1. the step that finds an event ends at it: the event located, the old mode's state
//!    there evaluated in full, committed and audited (exact: the state the choice
//!    would start from);
//! 2. the next step chooses the new mode there ([`Pending::Choice`]), the time
//!    unchanged;
//! 3. the steps after catch up with the clock, each one DP5 step of at most
//!    [`CATCH_UP`] steps, until a step ends at `(n + 1)·h` again.
//!
//! A return to the mode's preferred coordinates (a build and an evaluation) is left
//! to the next step the same way ([`Pending::Return`]). The event sequence, the
//! events' times and the audit are the unspread twin's to its accuracy (a step's
//! grid differs after an event, not its order).
//!
//! [`TwinSettings::spread_events`]: super::TwinSettings::spread_events

use super::error::TwinStepError;
use super::evaluate::{Stage, Torques};
use super::guards::EventKind;
use super::inputs::Inputs;
use super::settings::CATCH_UP;
use super::{Mode, Twin, Work};
use crate::scalar::Real;

/// Work a step leaves to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Pending {
    /// The step ended at this event, in the old mode: the next chooses the new one.
    Choice(EventKind),
    /// The step ended where the mode's preferred coordinates are predicted conditioned
    /// again ([`Twin::return_predicted`]): the next returns to them.
    Return,
}

impl<T: Real> Work<T> {
    /// Ends the segment at event `kind`, located at this state, for the next step to
    /// choose its mode ([`TwinSettings::spread_events`](super::TwinSettings::spread_events));
    /// `full`: the location's last evaluation was a full one, at that state. Returns
    /// `true` (the event is handled).
    pub(super) fn pend_choice(&mut self, kind: EventKind, full: bool) -> bool {
        self.evaluated_at_event = full;
        self.pending = Some(Pending::Choice(kind));
        true
    }
}

impl<T: Real> Twin<T> {
    /// The time the step ends at: the clock's `(n + 1)·h`, or, behind it after an event,
    /// [`CATCH_UP`] steps on from its start if that is sooner and the last step was a
    /// plain one that passed the energy check undivided, else one step `h` on (not at
    /// rest, in the jam: nothing moves there, the step goes to the clock at once).
    /// DP5's energy error grows as the step's sixth power and the tolerance as its
    /// length: a catching-up step's is 5.4 times harder to pass, and where the motion
    /// needs sub-steps the twin keeps its lag (S2 in f64 at h = 1 ms after the catch
    /// at 0.0666 s: 1.4 h steps redone in sub-steps cost the Cortex-M7 473k Thumb-2
    /// instructions, where a step of h costs 290k).
    pub(super) fn spread_step_end(&self, w: &Work<T>, clock: T) -> T {
        if !self.settings.spread_events || !self.behind || self.slots.cur().mode == Mode::Jam {
            return clock;
        }
        let ahead = if self.may_catch_up {
            T::c(CATCH_UP)
        } else {
            T::one()
        };
        clock.min(w.t + self.settings.h * ahead)
    }

    /// The end of a step at the event it located: the old mode's state there evaluated
    /// in full (kinetostatics included, unless the location's last evaluation was, at
    /// that state: `w.evaluated_at_event`) for the commit, the coasting shaft's motion
    /// booked up to it. The next step chooses the mode ([`Twin::settle_pending`]).
    #[inline(always)]
    pub(super) fn end_at_event(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        let stage = if w.evaluated_at_event {
            Stage::Readout
        } else {
            Stage::Motion
        };
        self.evaluate_from(stage, w, inputs, Torques::Kinetostatics)?;
        self.dp5.invalidate();
        self.coast_to(w, w.t, self.coast.accel);
        Ok(())
    }

    /// Does what the last step left to this one, at the twin's state, the time
    /// unchanged; returns whether that is the step. A mode choice always is (new
    /// inputs, `changed`, hold from the event on: the state is evaluated under them
    /// first). A return to the preferred coordinates is, if they assemble
    /// conditioned; under new inputs the state is evaluated under them first, as any
    /// step's start does (`w.inputs_taken`), and a mode choice they call for takes the
    /// return's place. If the return does not assemble (or the mode changed) the step
    /// goes on as usual, and its end leaves no return to the next. A firmware loop fed
    /// a measured torque has new inputs every period: a return left to a step's end
    /// would join a full step there (on the M4F in the firmware example, 145 k Thumb-2
    /// instructions, the loop's dearest step).
    pub(super) fn settle_pending(
        &mut self,
        w: &mut Work<T>,
        inputs: &Inputs<T>,
        changed: bool,
    ) -> Result<bool, TwinStepError> {
        match self.pending {
            None => Ok(false),
            Some(Pending::Choice(kind)) => {
                w.behind = true;
                if changed {
                    self.restart_under_new_inputs(w, inputs)?;
                }
                self.choose(w, kind, inputs)?;
                self.settle_clutch_torques(w, inputs)?;
                Ok(true)
            }
            Some(Pending::Return) => {
                if changed {
                    self.new_inputs(w, inputs)?;
                    w.inputs_taken = true;
                }
                if !w.chosen && self.return_to_preferred(w, inputs)? {
                    w.behind = true;
                    self.settle_clutch_torques(w, inputs)?;
                    return Ok(true);
                }
                w.return_failed = true;
                Ok(false)
            }
        }
    }
}
