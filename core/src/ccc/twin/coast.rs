//! The coasting shaft (SPEC 5, shaft inertia J_s > 0): the state [`Mode::Coast`] in
//! which no lever drives the turning shaft.
//!
//! **Why a mode, and the shaft's motion beside the model.** While it coasts the shaft
//! is decoupled from the linkage: the linkage moves as in I0 (both levers overrunning,
//! 2 DOF, I0's model and coordinates), and the shaft turns on its own,
//!
//! `J_s·ω̇_s = −d·T_r + Σ_free drag·(ω_k − ω_s)`
//!
//! (d the drive direction: a turning shaft turns that way, and the brake T_r opposes
//! it; the clutch drag of each overrunning lever, SPEC 5). A [`Mode`] of its own makes
//! the clutch and shaft states one value, as SPEC 3's modes are, and every part of the
//! step (events, mode choice, impact, audit, logs) sees it there. The shaft's speed and
//! angle are not the model's coordinates: under a torque held constant the speed is
//! linear in time and the angle quadratic, so the twin keeps the shaft's motion as
//! [`Coast`] (its speed at a time and its acceleration) and reads it exactly at any
//! time, rather than adding a seventh component to the DP5 state (its stages, dense
//! output and copies would cost 7·4 B per component and more in f32, where the twin has
//! 16 B to spare).
//!
//! **The torque on the shaft is held over each step.** Without clutch drag it is the
//! brake's, constant while the inputs are: the motion is exact. With drag it depends
//! on the levers' speeds: it is taken at the start of each step (or of the coasting,
//! at an event) and held to the step's end, first order in the step for the shaft's
//! speed (the levers feel the drag of the shaft's exact speed at every stage). The
//! energy audit books each body's share with the motion it has: the drag on the
//! levers is integrated with their motion by DP5 (its power `τ_k·ω_k`, `τ_k` the drag
//! on lever k), and the shaft's brake and drag with the shaft's exact motion: over a
//! stretch where it turns by `Δθ_s` they take `−J_s·a·Δθ_s`, the shaft's kinetic energy
//! change, out of it (booked in the load's work, with the losses). The balance holds
//! to DP5's accuracy whatever the step.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use super::slot::{LinkState, W_LOAD};
use super::{shaft_accel, shaft_speed, Twin, Work};
use crate::scalar::Real;

/// The coasting shaft's motion: speed `omega` (rad/s, CCW) at time `t0` (s), constant
/// acceleration `accel` (rad/s²) since.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Coast<T> {
    /// The time the motion is taken from, s.
    pub t0: T,
    /// Speed at `t0`, rad/s, CCW.
    pub omega: T,
    /// Acceleration, rad/s².
    pub accel: T,
}

impl<T: Real> Coast<T> {
    /// Speed at `t`, rad/s.
    pub fn omega_at(&self, t: T) -> T {
        self.omega + self.accel * (t - self.t0)
    }

    /// Angle turned from `t0` to `t`, rad.
    pub fn turn_to(&self, t: T) -> T {
        let s = t - self.t0;
        s * (self.omega + T::c(0.5) * self.accel * s)
    }
}

impl<T: Real> Twin<T> {
    /// The shaft's speed in `mode` at time `t` (the physical `links` there), rad/s:
    /// the coasting shaft's own in [`Mode::Coast`], else the engaged lever's (0 held).
    pub(super) fn shaft_at(&self, mode: Mode, links: &[LinkState<T>; 9], t: T) -> T {
        if mode == Mode::Coast {
            self.coast.omega_at(t)
        } else {
            shaft_speed(mode, links)
        }
    }

    /// The shaft's acceleration in `mode` (as [`Twin::shaft_at`]), rad/s².
    pub(super) fn shaft_alpha(&self, mode: Mode, links: &[LinkState<T>; 9]) -> T {
        if mode == Mode::Coast {
            self.coast.accel
        } else {
            shaft_accel(mode, links)
        }
    }

    /// The coasting shaft's acceleration at its speed `shaft` with the levers at
    /// `links` under the load `load` (N·m), rad/s²: `(−d·T_r + Σ drag·(ω_k − ω_s))/J_s`
    /// (both levers overrun).
    pub(super) fn coast_accel(&self, links: &[LinkState<T>; 9], shaft: T, load: T) -> T {
        let drag = self.params.friction.clutch_drag;
        let mut torque = -self.drive * load;
        if drag != T::zero() {
            for (_, lever) in BRANCHES {
                torque += drag * (links.get(lever).map_or(T::zero(), |l| l.omega) - shaft);
            }
        }
        torque / self.params.shaft_inertia
    }

    /// Books the coasting shaft's motion up to `t` into `w` (its turn into the step's
    /// shaft rotation; the kinetic energy the brake and the drag took from it,
    /// `−J_s·a·Δθ_s`, into the load's work) and takes its motion from `t` on, with
    /// acceleration `accel`. Nothing unless the current mode coasts.
    pub(super) fn coast_to(&mut self, w: &mut Work<T>, t: T, accel: T) {
        if self.slots.cur().mode != Mode::Coast {
            return;
        }
        let turn = self.coast.turn_to(t);
        w.shaft_turn += turn;
        w.y[W_LOAD] -= self.params.shaft_inertia * self.coast.accel * turn;
        self.coast = Coast {
            t0: t,
            omega: self.coast.omega_at(t),
            accel,
        };
    }

    /// Starts a step's attempt in [`Mode::Coast`]: the shaft's acceleration under the
    /// step's load `load` and the levers' speeds at its start (the committed state).
    pub(super) fn coast_from_state(&mut self, load: T) {
        if self.slots.cur().mode == Mode::Coast {
            self.coast.accel = self.coast_accel(&self.links, self.coast.omega, load);
        }
    }
}

/// Whether `m` is a mode with a lever carrying the shaft (the A modes).
pub(super) fn lever_driven(m: Mode) -> bool {
    m.clutches().contains(&Clutch::Engaged)
}

#[cfg(test)]
mod tests {
    use super::super::guards::EventKind;
    use super::super::{Inputs, MotorInput, Twin, TwinSettings};
    use crate::ccc::{CccParams, Mode};
    extern crate std;
    use std::boxed::Box;

    /// S2 with shaft inertia `js` (kg·m²) to 0.07 s (the shaft turning with both
    /// levers), then with no load until the shaft coasts; the no-load inputs.
    fn coasting(js: f64) -> (Box<Twin<f64>>, Inputs<f64>) {
        let mut p = CccParams::<f64>::reference();
        p.shaft_inertia = js;
        let s2 = Inputs {
            motor: MotorInput::Torque(12.0),
            load: 800.0,
            measured: None,
        };
        let free = Inputs { load: 0.0, ..s2 };
        let mut twin = Box::new(Twin::new(p, TwinSettings::reference(1e-4), s2).unwrap());
        while twin.t < 0.07 - 5e-5 {
            twin.step(&s2).unwrap();
        }
        while twin.slots.cur().mode != Mode::Coast && twin.t < 0.5 {
            twin.step(&free).unwrap();
        }
        assert_eq!(twin.slots.cur().mode, Mode::Coast, "t = {}", twin.t);
        (twin, free)
    }

    /// `½ q̇ᵀ M q̇` of the current slot's model at its evaluated state, J (an A mode's
    /// model carries the shaft's J_s on its engaged lever).
    fn model_kinetic(twin: &Twin<f64>) -> f64 {
        let s = twin.slots.cur();
        let n = s.map.dof;
        let mut k = 0.0;
        for i in 0..n {
            for j in 0..n {
                k += 0.5 * s.ws.qd[i] * s.ws.mass_q[(i, j)] * s.ws.qd[j];
            }
        }
        k
    }

    /// SPEC 3 and 5: a catch of the coasting shaft found late, at a speed mismatch (the
    /// shaft set 0.5 rad/s behind the faster lever in the drive direction, as a fixed
    /// step that missed the crossing leaves it), is a plastic impact: the loss booked
    /// (from the projection in the momentum space of I0 plus the shaft) equals the
    /// kinetic energy lost, `½ q̇ᵀMq̇` of the coasting model plus `½ J_s ω_s²` before,
    /// minus `½ q̇ᵀMq̇` of the engaged mode's own model (the shaft in its lever) after.
    #[test]
    fn a_late_catch_of_the_coasting_shaft_books_the_kinetic_energy_lost() {
        let (mut twin, free) = coasting(0.05);
        let d = twin.drive;
        let (k, lever) = if d * twin.links[6].omega > d * twin.links[8].omega {
            (0, 6)
        } else {
            (1, 8)
        };
        let wk = twin.links[lever].omega;
        let slip = 0.5;
        assert!(d * wk > 2.0 * slip, "lever {lever} at {wk} rad/s");
        twin.coast.omega = wk - d * slip;
        let mut w = twin.work_from_state();
        twin.restart_at(&w, &free).unwrap();
        let js = twin.params.shaft_inertia;
        let before = model_kinetic(&twin) + 0.5 * js * twin.coast.omega * twin.coast.omega;
        twin.choose(&mut w, EventKind::Catch(lever as u8), &free)
            .unwrap();
        let to = twin.slots.cur().mode;
        assert_ne!(to.clutches()[k], crate::ccc::Clutch::Free, "{to}");
        assert!(to.shaft_turning(), "{to}");
        let after = model_kinetic(&twin);
        let e = twin.events.last().unwrap();
        let lost = before - after;
        std::println!(
            "late catch{lever} at t = {:.6} s: coast -> {to}, slip {slip} rad/s, booked {:.9e} J, lost {:.9e} J",
            e.time,
            e.impact_loss,
            lost
        );
        assert!(lost > 1e-3, "{lost}");
        assert!(
            (e.impact_loss - lost).abs() <= 1e-9 * before,
            "booked {} vs lost {lost}",
            e.impact_loss
        );
        assert!((e.mismatch - slip).abs() <= 1e-9, "{}", e.mismatch);
    }
}
