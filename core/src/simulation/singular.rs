//! Where inside a step a run meets a singularity of the mechanism (issue 17, item 4):
//! the constraints lose rank (a group cannot assemble past a limit position, its
//! Jacobian is singular, the mass matrix is) somewhere inside the step that failed, not
//! at its start. [`Simulation::locate_failure`] finds that time by bisection on the
//! size of a trial step from the last good state, as the twin locates its events: the
//! longest step that still succeeds ends where the mechanism stops.

use super::{Equations, Simulation};
use crate::config::STATE_DIM;
use crate::error::{GroupFault, StepError};
use crate::integrator::Dp5;
use crate::model::Model;
use crate::scalar::Real;
use crate::workspace::Workspace;
use nalgebra::SVector;

/// Halvings of the step by [`Simulation::locate_failure`]: 2⁻⁴⁰ of the step (1e-15 s
/// at h = 1 ms), finer than any time a run reports.
pub const LOCATE_HALVINGS: u32 = 40;

/// Whether a step failed as at a singularity of the mechanism (or of its coordinates):
/// a group singular, unable to assemble, off its branch, unsolved or at a dead point,
/// or the mass matrix singular. Non-finite inputs and broken energy balances are not.
pub fn at_singularity(e: &StepError) -> bool {
    match e {
        StepError::Group { fault, .. } => !matches!(fault, GroupFault::NonFiniteInput),
        StepError::SingularMassMatrix { .. } => true,
        _ => false,
    }
}

impl<T: Real> Simulation<T> {
    /// The time inside the next step (from the current, last good state) at which a
    /// step fails: the end of the longest trial DP5 step from the state that still
    /// succeeds, found by [`LOCATE_HALVINGS`] bisections of the step size (the bracket's
    /// failing end is returned, s). `None` if the whole step succeeds, or the state's
    /// own evaluation fails. `scratch` is overwritten; the simulation is untouched.
    pub fn locate_failure(&self, scratch: &mut Workspace<T>) -> Option<T> {
        self.locate(scratch, 1).map(|(t, _)| t)
    }

    /// Where the motion from the current state meets a singularity of the mechanism
    /// within `steps` step lengths (1: inside the next step): the time of
    /// [`Simulation::locate_failure`] over that span with the failing trial's error
    /// there (its time set to the located one), if that error is one
    /// [`at_singularity`]. A step that failed otherwise (its energy balance broken by
    /// the speeds' run-up to a singular pose just past its end, say) ends at the
    /// singularity all the same when a trial over 2 step lengths meets it. `None` if no
    /// trial fails, or fails otherwise.
    pub fn locate_singularity(
        &self,
        scratch: &mut Workspace<T>,
        steps: u32,
    ) -> Option<(T, StepError)> {
        self.locate(scratch, steps)
            .filter(|(_, e)| at_singularity(e))
            .map(|(t, e)| (t, e.at_time(t.to_f64())))
    }

    /// The located time within `steps` step lengths and the error of the failing trial
    /// at the bracket's end.
    fn locate(&self, scratch: &mut Workspace<T>, steps: u32) -> Option<(T, StepError)> {
        let t_next = self.span_end(steps);
        locate_from(&self.model, &self.ws, self.t, &self.y, t_next, scratch)
    }

    /// The end of the span of `steps` step lengths (at least 1) from the state: the
    /// time `(n + steps)·h`, s.
    pub(crate) fn span_end(&self, steps: u32) -> T {
        T::c(self.steps.saturating_add(u64::from(steps.max(1))) as f64) * self.h
    }
}

/// The time in `(t, t_end]` at which a single trial DP5 step of `model` from the state
/// `(t, y)` (`ws` evaluated there) fails: the failing end of the bracket after
/// [`LOCATE_HALVINGS`] bisections of the trial's size, with that trial's error. `None`
/// if the whole trial to `t_end` succeeds. `scratch` is overwritten.
pub(crate) fn locate_from<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    t: T,
    y: &SVector<T, STATE_DIM>,
    t_end: T,
    scratch: &mut Workspace<T>,
) -> Option<(T, StepError)> {
    let h = t_end - t;
    let trial = |size: T, scratch: &mut Workspace<T>| -> Result<(), StepError> {
        scratch.clone_from(ws);
        let mut dp5 = Dp5::<T, STATE_DIM>::new();
        let (mut t, mut y) = (t, *y);
        let mut sys = Equations { model, ws: scratch };
        dp5.step(&mut sys, &mut t, &mut y, size).map(|_| ())
    };
    let mut failure = trial(h, scratch).err()?;
    let (mut lo, mut hi) = (T::zero(), h);
    let half = T::c(0.5);
    for _ in 0..LOCATE_HALVINGS {
        let mid = (lo + hi) * half;
        match trial(mid, scratch) {
            Ok(()) => lo = mid,
            Err(e) => {
                hi = mid;
                failure = e;
            }
        }
    }
    Some((t + hi, failure))
}
