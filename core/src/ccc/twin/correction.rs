//! A correction of the twin's state in crank terms, an observer's update
//! ([`Twin::correct_crank`]).
//!
//! The crank's angle θ1 is what the encoder measures, whatever the mode's independent
//! coordinates `q` are (the twin switches them at dead points). A correction
//! `(δθ1, δω1)` is mapped into the current coordinates through the transmission's crank
//! row `r = ∂θ1/∂q` (= `∂ω1/∂q̇`, the crank's row of `V`, SPEC 1) along a direction `u`
//! with `r·u = 1`, `δq = u δθ1`, then `δq̇` along `u` from the row at the moved
//! positions (so the crank's speed is the one asked for). With one degree of freedom
//! `u = 1/r`: exact to first order. In a 2-DOF mode `u = M⁻¹rᵀ / (r M⁻¹ rᵀ)`, the
//! dynamically consistent inverse of `r` (`M` the mode's mass matrix in its
//! coordinates): the change a torque on the crank makes, the other coordinate moving
//! with the crank as the coupling of their inertias moves it. A crank off the machine's
//! is mostly a torque the model lacks at the crank (its friction, its masses' errors
//! seen there), and that torque moves both coordinates so; the least-norm inverse
//! `rᵀ/|r|²` (the other coordinate left still, with the crank a coordinate) measured
//! worse on the known machine's logs (12 of 15 sequences kept against 15, with the
//! identified tuning). The positions are then re-solved
//! and the speeds set by the mode's own kinematics, so the state stays on its
//! constraints; the event functions are evaluated there, and one that the correction
//! would move past its crossing cuts it short of the crossing, so that the twin's next
//! step meets it and takes the event by its own location and mode choice.

use super::super::build::CRANK;
use super::super::mode::Mode;
use super::error::TwinStepError;
use super::slot::{LinkState, QD};
use super::spread::Pending;
use super::Twin;
use crate::scalar::Real;

/// What [`Twin::correct_crank`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correction<T> {
    /// The crank's angle and speed changes made, rad and rad/s (after the positions'
    /// re-solution: second order off the ones asked for).
    pub crank: (T, T),
    /// The energy it put into the state, J (booked in [`Audit::correction`](super::Audit)).
    pub energy: T,
    /// Whether it was applied: not in the jam (no degree of freedom), nor where the
    /// crank does not move with the coordinates (`|∂θ1/∂q|` = 0).
    pub applied: bool,
}

impl<T: Real> Correction<T> {
    /// Nothing done.
    pub fn none() -> Self {
        Correction {
            crank: (T::zero(), T::zero()),
            energy: T::zero(),
            applied: false,
        }
    }
}

/// The largest change of a coordinate one correction makes, rad.
const MAX_DQ: f64 = 0.1;
/// The largest change of a coordinate's rate one correction makes, rad/s.
const MAX_DQD: f64 = 10.0;

/// Cuts of a correction that crosses an event function at most (the first by the
/// crossing's estimate, then halvings).
const CUTS: usize = 4;

/// `|r|²` over the first `dof` entries.
fn norm2<T: Real>(r: &[T; 2], dof: usize) -> T {
    r.iter().take(dof).fold(T::zero(), |s, x| s + *x * *x)
}

impl<T: Real> Twin<T> {
    /// Moves the state `w` (the twin's) by the crank change `(δθ1, δω1)`: the
    /// coordinates by `rᵀ δθ1 / |r|²`, the positions and speeds re-solved there, then
    /// the coordinates' rates by `r'ᵀ (ω1 + δω1 - ω1') / |r'|²` with the transmission
    /// `r'` and the crank speed `ω1'` at the moved positions (so the crank's speed is
    /// the one asked for, not its first-order estimate), and the full evaluation there.
    fn move_crank(
        &mut self,
        w: &mut super::Work<T>,
        dof: usize,
        (d_theta, d_omega): (T, T),
        omega: T,
        inputs: &super::Inputs<T>,
    ) -> Result<(), TwinStepError> {
        let u = self.crank_direction(dof);
        for (k, u) in u.iter().take(dof).enumerate() {
            if let Some(q) = w.y.get_mut(k) {
                *q += *u * d_theta;
            }
        }
        self.slots
            .cur_mut()
            .eval_speeds(w.t, &w.y)
            .map_err(|e| self.physical_error(e))?;
        let row = self.slots.cur().omega_row(CRANK);
        let norm = norm2(&row, dof);
        if norm > T::zero() {
            let now = (0..dof).fold(T::zero(), |s, k| {
                s + row.get(k).copied().unwrap_or(T::zero())
                    * w.y.get(QD + k).copied().unwrap_or(T::zero())
            });
            let miss = omega + d_omega - now;
            let u = self.crank_direction(dof);
            for (k, u) in u.iter().take(dof).enumerate() {
                if let Some(qd) = w.y.get_mut(QD + k) {
                    *qd += *u * miss;
                }
            }
        }
        self.restart_at(w, inputs)
    }

    /// The direction `u` (`r·u = 1`, `r` the crank's row at the last evaluation) along
    /// which a crank change moves the coordinates (the module's doc): `r/|r|²` with one
    /// degree of freedom, or where `M` is not positive definite; `M⁻¹rᵀ / (r M⁻¹ rᵀ)`
    /// with two. Zeros where the crank does not move with the coordinates.
    fn crank_direction(&self, dof: usize) -> [T; 2] {
        let slot = self.slots.cur();
        let r = slot.omega_row(CRANK);
        let norm = norm2(&r, dof);
        if !(norm > T::zero()) {
            return [T::zero(); 2];
        }
        let least = [r[0] / norm, r[1] / norm];
        if dof != 2 {
            return least;
        }
        let m00 = slot.ws.mass_q.get((0, 0)).copied().unwrap_or(T::zero());
        let (adj, det) = slot.mass_adjugate_times(r);
        if !(det > T::zero() && m00 > T::zero()) {
            return least;
        }
        let v = [adj[0] / det, adj[1] / det];
        // r·v = r M⁻¹ rᵀ > 0 for M positive definite and r ≠ 0.
        let rv = r[0] * v[0] + r[1] * v[1];
        if rv > T::zero() {
            [v[0] / rv, v[1] / rv]
        } else {
            least
        }
    }

    /// The current slot's Newton warm starts back to `saved`.
    fn restore_unknowns(&mut self, saved: &crate::workspace::WarmStart<T>) {
        let slot = self.slots.cur_mut();
        slot.ws.restore_warm_start(slot.model.groups(), saved);
    }

    /// Moves the crank's angle by `d_theta` (rad) and its speed by `d_omega` (rad/s) at
    /// the present time, in the present mode and coordinates (the module's doc): the
    /// positions re-solved, the speeds set through the transmission, the energy the
    /// change puts in booked in the audit's own term, the event functions evaluated at
    /// the new state; a correction that would take one past its crossing is cut short
    /// of it (the next step takes the event), one near a dead point of the crank in
    /// the coordinates scaled to 0.1 rad and 10 rad/s of them. On an error (a group
    /// that does not assemble at the corrected state) the twin keeps its state.
    pub fn correct_crank(
        &mut self,
        d_theta: T,
        d_omega: T,
    ) -> Result<Correction<T>, TwinStepError> {
        for (field, v) in [
            ("crank correction", d_theta),
            ("crank speed correction", d_omega),
        ] {
            if !v.finite() {
                return Err(TwinStepError::BadInput {
                    time: self.t.to_f64(),
                    field,
                    value: v.to_f64(),
                });
            }
        }
        if matches!(self.pending, Some(Pending::Choice(_))) {
            // The state is an event's, its mode chosen by the next step: it stays.
            return Ok(Correction::none());
        }
        let dof = self.slots.cur().map.dof.min(2);
        let row = self.slots.cur().omega_row(CRANK);
        let norm = norm2(&row, dof);
        if self.slots.cur().mode == Mode::Jam || dof == 0 || !(norm > T::zero()) {
            return Ok(Correction::none());
        }
        // Near a dead point of the crank in these coordinates (`|r|` → 0) a crank change
        // is a large change of the coordinates: the correction is scaled down to
        // [`MAX_DQ`] and [`MAX_DQD`] in them (the rest is left to the next updates, when
        // the transmission has moved on).
        let len = norm.root();
        let (dq, dqd) = (d_theta.abs() / len, d_omega.abs() / len);
        let scale = T::one()
            .min(T::c(MAX_DQ) / dq.max(T::c(MAX_DQ)))
            .min(T::c(MAX_DQD) / dqd.max(T::c(MAX_DQD)));
        let (d_theta, d_omega) = (d_theta * scale, d_omega * scale);
        let inputs = self.inputs.inputs();
        let saved = self.slots.cur().warm_start();
        let log = (
            self.events.clone(),
            self.switches.clone(),
            self.candidates.clone(),
        );
        let before = self.links[CRANK];
        self.dp5.invalidate();
        self.last_guards = None;
        self.at_rest = false;
        self.state_evaluated = false;
        let g0 = self.guards;
        let mut w = self.work_from_state();
        let mut result = self.move_crank(&mut w, dof, (d_theta, d_omega), before.omega, &inputs);
        if let (Ok(()), Some(g)) = (&result, g0.fired(&self.guards).first()) {
            // An event function the correction would move past its crossing: the
            // correction is cut short of it (by the crossing's linear estimate between
            // the two ends, then halved while still past), so that the twin's own next
            // step meets the crossing and locates and takes the event by its dynamics,
            // as any other; the rest of the correction is left to the next updates.
            let mut cut = match (g0.get(g), self.guards.get(g)) {
                (Some(a), Some(b)) if a < b => T::c(0.999) * a / (a - b),
                _ => T::zero(),
            };
            for _ in 0..CUTS {
                w = self.work_from_state();
                self.restore_unknowns(&saved);
                result = self.move_crank(
                    &mut w,
                    dof,
                    (d_theta * cut, d_omega * cut),
                    before.omega,
                    &inputs,
                );
                if result.is_err() || g0.fired(&self.guards).is_empty() {
                    break;
                }
                cut *= T::c(0.5);
            }
            if result.is_ok() && !g0.fired(&self.guards).is_empty() {
                self.restore(false, &saved);
                return Ok(Correction::none());
            }
        }
        if let Err(e) = result {
            (self.events, self.switches, self.candidates) = log;
            self.restore(w.switched, &saved);
            return Err(e);
        }
        let energy = self.commit_booked(&w);
        Ok(self.made(&before, energy))
    }

    /// Commits `w`'s state, the twin's own moved by an estimator at the present time,
    /// with the energy the move put in booked in the audit's correction term: the term
    /// that keeps the residual where it was (the state's energy change less the impact
    /// losses a mode change booked). Returns that energy, J.
    pub(super) fn commit_booked(&mut self, w: &super::Work<T>) -> T {
        let links = self.slots.cur().links(&self.params);
        let mut audit = self.audit_of(&links, w);
        let energy = self.audit.residual() - audit.residual();
        audit.correction += energy;
        self.y = w.y;
        self.commit(w, audit, &links);
        energy
    }

    /// The correction made from the crank's state `before` to the twin's, with the
    /// `energy` booked (J).
    pub(super) fn made(&self, before: &LinkState<T>, energy: T) -> Correction<T> {
        let after = self.links[CRANK];
        Correction {
            crank: (after.theta - before.theta, after.omega - before.omega),
            energy,
            applied: true,
        }
    }
}
