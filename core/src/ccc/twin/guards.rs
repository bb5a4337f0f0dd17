//! The event functions of the mechanical diode (SPEC 3): a free lever catching the
//! shaft, a held lever releasing it, a breakaway of the held shaft, the shaft stopping;
//! and the events they fire.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use super::settings::*;
use super::slot::{Inputs, LinkState, Slot};
use super::{shaft_accel, shaft_speed, Twin};
use crate::scalar::Real;

/// Ulps of the largest link speed by which a free lever must pass the shaft for a catch
/// to fire (see [`Twin::guards_of`]).
pub(super) const CATCH_ULPS: f64 = 16.0;

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
            EventKind::Catch(8) => "catch8",
            // No other lever has a clutch: a kind built by hand with one is named
            // without a lever, never as another lever's.
            EventKind::Catch(_) => "catch",
            EventKind::Release(6) => "release6",
            EventKind::Release(8) => "release8",
            EventKind::Release(_) => "release",
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

/// Which event functions are watched, their values: `[catch6, catch8, release6,
/// release8, breakaway, shaft stop]`; an event fires when its function goes from ≤ 0 to
/// > 0 over a step.
pub(super) type Guards<T> = [Option<T>; 6];

/// The event functions that are speeds (catches, shaft stop), as bits of [`fired`]:
/// the kinematics up to the velocities evaluate them, with no equations of motion and
/// no kinetostatics.
pub(super) const SPEED_GUARDS: u8 = 0b10_0011;

/// Which of the event functions went from ≤ 0 to > 0 (bit k: function k).
pub(super) fn fired<T: Real>(g0: &Guards<T>, g1: &Guards<T>) -> u8 {
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

impl<T: Real> Twin<T> {
    /// Whether none of the torque functions in `g0` (a release, a breakaway) can cross
    /// 0 over the next `h`: each is below 0 by more than 16 times its change over
    /// the last step without an event (`last_guards`), scaled to `h`. A clutch torque
    /// is a smooth function of the motion (it changes on the time scale of the crank's
    /// turn, ~10 ms in S2): its rate does not grow 16-fold from one step of 1e-4 s to
    /// the next, and a jump (an event, new inputs) clears `last_guards`. A mode
    /// without torque functions (I0) can always wait. Were one to cross anyway, the
    /// mode choice at the speed event still checks every clutch torque.
    pub(super) fn torques_can_wait(&self, g0: &Guards<T>, h: T) -> bool {
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

    /// The time derivatives of [`Twin::guards_of`]'s speed functions at `slot`'s
    /// evaluated state (accelerations included): a catch's `d·(α_lever − α_shaft)`, the
    /// shaft stop's `-d·α_shaft` (the catch's tolerance taken as constant).
    pub(super) fn guard_rates_of(&self, slot: &Slot<T>, links: &[LinkState<T>; 9]) -> Guards<T> {
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
    pub(super) fn guards_of(
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
}

#[cfg(test)]
mod tests {
    use super::EventKind;

    /// Regression (`EventKind::name` called every catch but lever 6's "catch8", every
    /// release but lever 6's "release8"): each kind is named by its own lever, and the
    /// names of different kinds differ.
    #[test]
    fn each_event_kind_is_named_by_its_own_lever() {
        let named = [
            (EventKind::Start, "start"),
            (EventKind::Inputs, "inputs"),
            (EventKind::Catch(6), "catch6"),
            (EventKind::Catch(8), "catch8"),
            (EventKind::Release(6), "release6"),
            (EventKind::Release(8), "release8"),
            (EventKind::Breakaway, "breakaway"),
            (EventKind::ShaftStop, "shaft-stop"),
            (EventKind::Catch(7), "catch"),
            (EventKind::Release(5), "release"),
        ];
        for (k, name) in named {
            assert_eq!(k.name(), name, "{k:?}");
        }
        for (i, (a, _)) in named.iter().enumerate() {
            for (b, _) in named.iter().skip(i + 1) {
                assert_ne!(a.name(), b.name(), "{a:?} and {b:?}");
            }
        }
    }
}
