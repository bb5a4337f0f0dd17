//! The energy audit (SPEC 3).

use super::super::build::physical_link;
use super::super::params::CccParams;
use super::error::{Failure, TwinStepError};
use super::slot::{LinkState, W_LOAD, W_MOTOR};
use super::{Twin, Work};
use crate::error::{GroupFault, StepError};
use crate::scalar::{Real, Vec2};

/// The energy audit (SPEC 3): `motor work + corrections = Δ(kinetic + potential) + load
/// work + impact losses`, each term in J since the start (`corrections`: the energy an
/// observer's corrections of the state put in, 0 without one).
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
    /// The energy the state's corrections ([`Twin::correct_crank`]) put into it, net of
    /// the impact losses of the mode changes they made.
    pub correction: T,
}

impl<T: Real> Audit<T> {
    /// `motor work + corrections - Δ(kinetic + potential) - load work - impact losses`,
    /// J.
    pub fn residual(&self) -> T {
        let r = self.motor_work
            - (self.kinetic + self.potential - self.initial)
            - self.load_work
            - self.impact_loss;
        // Without corrections the residual's bits are the uncorrected twin's (a -0 too).
        if self.correction == T::zero() {
            r
        } else {
            r + self.correction
        }
    }
}

/// A physical link's mass, its moment of inertia about its COG and the COG in its
/// frame (the rocker carries the oscillating mass).
fn mass_properties<T: Real>(params: &CccParams<T>, p: usize) -> (T, T, Vec2<T>) {
    let l = physical_link(params, p);
    (l.mass, l.inertia, l.cog)
}

/// Kinetic and potential energy of the physical links (and of the shaft turning at
/// `shaft_speed`), J: computed from the physical state (the links and their frame
/// directions, [`Slot::frames`](super::slot::Slot::frames)), independently of the mode's model.
fn physical_energy<T: Real>(
    params: &CccParams<T>,
    links: &[LinkState<T>; 9],
    frames: &[Vec2<T>; 9],
    shaft_speed: T,
) -> (T, T) {
    let half = T::c(0.5);
    let (mut k, mut u) = (
        half * params.shaft_inertia * shaft_speed * shaft_speed,
        T::zero(),
    );
    for (p, (s, f)) in links.iter().zip(frames.iter()).enumerate().skip(1) {
        let (m, i, c) = mass_properties(params, p);
        let (r, v) = s.point_motion(f, &c);
        k += half * (m * v.norm_squared() + i * s.omega * s.omega);
        u -= m * params.gravity.dot(&(s.origin + r));
    }
    (k, u)
}

/// The audit's terms are finite, or the error that says they are not. The works are
/// integrated with the motion but not checked by its evaluations, and an energy can
/// overflow at finite speeds (`½ J_s ω²` with a huge J_s): past the scalar's range the
/// balance test would compare infinities and pass.
pub(super) fn audit_finite<T: Real>(a: &Audit<T>, t: T) -> Result<(), TwinStepError> {
    let terms = [
        a.motor_work,
        a.load_work,
        a.impact_loss,
        a.kinetic,
        a.potential,
        a.initial,
        a.correction,
        a.residual(),
    ];
    if terms.iter().all(|x| x.finite()) {
        Ok(())
    } else {
        Err(TwinStepError::Step(StepError::NonFinite {
            time: t.to_f64(),
            what: "the energy audit (a work or an energy overflows the scalar)",
        }))
    }
}

impl<T: Real> Twin<T> {
    /// The audit at the end of a step in `w` (the slot holds its evaluation).
    pub(super) fn audit_of(&self, links: &[LinkState<T>; 9], w: &Work<T>) -> Audit<T> {
        let shaft = self.shaft_at(self.slots.cur().mode, links, w.t);
        let frames = self.slots.cur().frames();
        let (kinetic, potential) = physical_energy(&self.params, links, &frames, shaft);
        Audit {
            motor_work: w.y[W_MOTOR],
            load_work: w.y[W_LOAD],
            impact_loss: self.audit.impact_loss + w.impact,
            kinetic,
            potential,
            initial: self.audit.initial,
            correction: self.audit.correction,
        }
    }

    /// The audit at the end of the step in `w` from the slot's physical `links` there
    /// (the state [`Twin::commit`] takes), or an error if its residual moved past the
    /// tolerance over the step; `w.excess` is its jump over the tolerance either way.
    pub(super) fn check_energy(
        &self,
        w: &mut Work<T>,
        links: &[LinkState<T>; 9],
    ) -> Result<Audit<T>, TwinStepError> {
        let a = self.balance_within(w, links, T::one())?;
        // Passed: the jump under its tolerance, for the step's rung prediction.
        let (jump, tol) = self.jump_of(&a, w.t);
        w.excess = Some(jump.abs() / tol);
        Ok(a)
    }

    /// The audit `a`'s residual's jump since the last committed state's (J) and the
    /// energy tolerance at its scale (J), for a state at time `t`: a step's, or a
    /// catching-up step's ([`TwinSettings::spread_events`](super::TwinSettings::spread_events))
    /// scaled by its length over `h` (the tolerance is one per unit time,
    /// [`energy_tolerance`](super::energy_tolerance)).
    fn jump_of(&self, a: &Audit<T>, t: T) -> (T, T) {
        let jump = a.residual() - self.audit.residual();
        let scale = T::one() + a.motor_work.abs() + a.kinetic.abs() + a.potential.abs();
        let h = self.settings.h;
        let span = if self.settings.spread_events && t - self.t > h {
            (t - self.t) / h
        } else {
            T::one()
        };
        (jump, self.settings.energy_tol * scale * span)
    }

    /// The audit at `w`'s state (the end of the step, or an event inside it) from the
    /// slot's physical `links` there, or the error [`Twin::check_energy`] gives if its
    /// residual moved past `margin` times the tolerance over the step so far; on
    /// failure `w.excess` is the jump over the tolerance.
    pub(super) fn balance_within(
        &self,
        w: &mut Work<T>,
        links: &[LinkState<T>; 9],
        margin: T,
    ) -> Result<Audit<T>, TwinStepError> {
        let a = self.audit_of(links, w);
        audit_finite(&a, w.t)?;
        let (jump, tol) = self.jump_of(&a, w.t);
        if jump.abs() <= tol * margin {
            return Ok(a);
        }
        w.excess = Some(jump.abs() / tol);
        let (group, conditioning) = self.slots.cur().worst_group();
        Err(TwinStepError::Diverged {
            time: self.t.to_f64(),
            mode: self.slots.cur().mode,
            jump: jump.to_f64(),
            substeps: w.substeps,
            worst: Failure {
                coords: self.slots.cur().coords,
                group,
                fault: GroupFault::Singular {
                    conditioning: conditioning.to_f64(),
                },
            },
            // One attempt alone shows no trend: the rungs set it ([`Twin::climb`]).
            stalled: false,
        })
    }
}
