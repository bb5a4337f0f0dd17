//! The event functions of the mechanical diode (SPEC 3): a free lever catching the
//! shaft, a held lever releasing it, a breakaway of the held shaft, the shaft stopping;
//! and the events they fire.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use super::inputs::Inputs;
use super::settings::*;
use super::slot::{LinkState, Slot};
use super::Twin;
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

/// One event function of the diode (SPEC 3). Each fires its event when it goes from
/// ≤ 0 to > 0 over a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Guard {
    /// Free lever 6 passes the shaft in the drive direction (a speed).
    Catch6,
    /// Free lever 8 passes the shaft in the drive direction (a speed).
    Catch8,
    /// Locked or engaged lever 6's transmitted torque falls under 0 (a torque).
    Release6,
    /// Locked or engaged lever 8's transmitted torque falls under 0 (a torque).
    Release8,
    /// The locked levers' torques rise past the load T_r (a torque).
    Breakaway,
    /// The turning shaft's speed falls to 0 (a speed).
    ShaftStop,
}

impl Guard {
    /// Every event function, in the order ties between them are broken (the first
    /// wins).
    pub(super) const ALL: [Guard; 6] = [
        Guard::Catch6,
        Guard::Catch8,
        Guard::Release6,
        Guard::Release8,
        Guard::Breakaway,
        Guard::ShaftStop,
    ];

    /// The catch of branch `k` (0: lever 6, 1: lever 8; see `BRANCHES`).
    pub(super) fn catch(k: usize) -> Guard {
        if k == 0 {
            Guard::Catch6
        } else {
            Guard::Catch8
        }
    }

    /// The release of branch `k` (0: lever 6, 1: lever 8).
    pub(super) fn release(k: usize) -> Guard {
        if k == 0 {
            Guard::Release6
        } else {
            Guard::Release8
        }
    }

    /// Whether the function is a speed (the catches, the shaft stop): the kinematics
    /// up to the velocities evaluate it, with no equations of motion and no
    /// kinetostatics; the others are clutch torques, which need the kinetostatics.
    pub(super) fn is_speed(self) -> bool {
        matches!(self, Guard::Catch6 | Guard::Catch8 | Guard::ShaftStop)
    }

    /// The event it fires.
    pub(super) fn event(self) -> EventKind {
        match self {
            Guard::Catch6 => EventKind::Catch(6),
            Guard::Catch8 => EventKind::Catch(8),
            Guard::Release6 => EventKind::Release(6),
            Guard::Release8 => EventKind::Release(8),
            Guard::Breakaway => EventKind::Breakaway,
            Guard::ShaftStop => EventKind::ShaftStop,
        }
    }
}

/// The event functions of a mode at a state (or their time derivatives): `None` for
/// one the mode does not watch (a catch of a held lever, a release of a free one).
/// Speeds in rad/s, torques in N·m (rates per second).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Guards<T> {
    /// [`Guard::Catch6`].
    pub catch6: Option<T>,
    /// [`Guard::Catch8`].
    pub catch8: Option<T>,
    /// [`Guard::Release6`].
    pub release6: Option<T>,
    /// [`Guard::Release8`].
    pub release8: Option<T>,
    /// [`Guard::Breakaway`].
    pub breakaway: Option<T>,
    /// [`Guard::ShaftStop`].
    pub shaft_stop: Option<T>,
}

impl<T: Real> Guards<T> {
    /// None watched (a twin without the diode).
    pub(super) const NONE: Self = Guards {
        catch6: None,
        catch8: None,
        release6: None,
        release8: None,
        breakaway: None,
        shaft_stop: None,
    };

    /// Function `g`'s value, if watched.
    pub(super) fn get(&self, g: Guard) -> Option<T> {
        match g {
            Guard::Catch6 => self.catch6,
            Guard::Catch8 => self.catch8,
            Guard::Release6 => self.release6,
            Guard::Release8 => self.release8,
            Guard::Breakaway => self.breakaway,
            Guard::ShaftStop => self.shaft_stop,
        }
    }

    /// Function `g`'s place.
    pub(super) fn get_mut(&mut self, g: Guard) -> &mut Option<T> {
        match g {
            Guard::Catch6 => &mut self.catch6,
            Guard::Catch8 => &mut self.catch8,
            Guard::Release6 => &mut self.release6,
            Guard::Release8 => &mut self.release8,
            Guard::Breakaway => &mut self.breakaway,
            Guard::ShaftStop => &mut self.shaft_stop,
        }
    }

    /// The watched functions and their values, in [`Guard::ALL`]'s order.
    pub(super) fn watched(&self) -> impl Iterator<Item = (Guard, T)> + '_ {
        Guard::ALL
            .into_iter()
            .filter_map(|g| self.get(g).map(|v| (g, v)))
    }

    /// The watched speed functions (catches, shaft stop) and their values.
    pub(super) fn speed_guards(&self) -> impl Iterator<Item = (Guard, T)> + '_ {
        self.watched().filter(|(g, _)| g.is_speed())
    }

    /// Whether a watched function is past its crossing (> 0) here: the mode is no longer
    /// consistent.
    pub(super) fn any_past(&self) -> bool {
        self.watched().any(|(_, v)| v > T::zero())
    }

    /// Which functions went from ≤ 0 here to > 0 in `after` (the same mode, later).
    pub(super) fn fired(&self, after: &Guards<T>) -> Fired {
        let mut fired = Fired::default();
        for g in Guard::ALL {
            if let (Some(a), Some(b)) = (self.get(g), after.get(g)) {
                if a <= T::zero() && b > T::zero() {
                    fired.insert(g);
                }
            }
        }
        fired
    }
}

/// A set of event functions: those that fired over a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Fired {
    /// Bit `g as u8` for each [`Guard`] `g` in the set.
    bits: u8,
}

impl Fired {
    fn insert(&mut self, g: Guard) {
        self.bits |= 1 << g as u8;
    }

    /// Whether `g` is in the set.
    pub(super) fn contains(self, g: Guard) -> bool {
        self.bits & (1 << g as u8) != 0
    }

    /// Whether none fired.
    pub(super) fn is_empty(self) -> bool {
        self.bits == 0
    }

    /// Whether a speed function fired.
    pub(super) fn any_speed(self) -> bool {
        Guard::ALL.iter().any(|g| g.is_speed() && self.contains(*g))
    }

    /// Whether only speed functions fired (none that needs the kinetostatics).
    pub(super) fn speeds_only(self) -> bool {
        Guard::ALL
            .iter()
            .all(|g| g.is_speed() || !self.contains(*g))
    }

    /// The first that fired, in [`Guard::ALL`]'s order.
    pub(super) fn first(self) -> Option<Guard> {
        Guard::ALL.into_iter().find(|g| self.contains(*g))
    }

    /// The one that fired, if exactly one did.
    pub(super) fn single(self) -> Option<Guard> {
        (self.bits.count_ones() == 1)
            .then(|| self.first())
            .flatten()
    }

    /// The set as bits, bit `k` for the `k`-th of [`Guard::ALL`] (for logs).
    pub(super) fn bits(self) -> u8 {
        self.bits
    }
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
        g0.watched().filter(|(g, _)| !g.is_speed()).all(|(g, a)| {
            let Some(b) = self
                .last_guards
                .and_then(|(gl, hp)| gl.get(g).map(|b| (b, hp)))
                .map(|(b, hp)| (a - b).abs() * (h / hp))
            else {
                return false;
            };
            a + k * b < T::zero()
        })
    }

    /// The time derivatives of [`Twin::guards_of`]'s speed functions at `slot`'s
    /// evaluated state (accelerations included): a catch's `d·(α_lever − α_shaft)`, the
    /// shaft stop's `-d·α_shaft` (the catch's tolerance taken as constant).
    pub(super) fn guard_rates_of(&self, slot: &Slot<T>, links: &[LinkState<T>; 9]) -> Guards<T> {
        let mut r = Guards::NONE;
        if !self.settings.clutch {
            return r;
        }
        let d = self.drive;
        let mode = slot.mode;
        let shaft = self.shaft_alpha(mode, links);
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(mode.clutches()).enumerate() {
            if clutch == Clutch::Free {
                *r.get_mut(Guard::catch(k)) =
                    Some(d * (links.get(*lever).map_or(T::zero(), |s| s.alpha) - shaft));
            }
        }
        if mode.shaft_turning() {
            r.shaft_stop = Some(-d * shaft);
        }
        r
    }

    /// The event functions of `slot`'s mode at its evaluated state (time `t`).
    pub(super) fn guards_of(
        &self,
        slot: &Slot<T>,
        links: &[LinkState<T>; 9],
        c: &[T; 2],
        inputs: &Inputs<T>,
        t: T,
    ) -> Guards<T> {
        let mut g = Guards::NONE;
        if !self.settings.clutch {
            return g;
        }
        let d = self.drive;
        let mode = slot.mode;
        let shaft = self.shaft_at(mode, links, t);
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
                Clutch::Free => {
                    *g.get_mut(Guard::catch(k)) = Some(d * (w - shaft) - w_tol);
                    let drag = self.params.friction.clutch_drag;
                    if drag != T::zero() && !mode.shaft_turning() {
                        // Its drag on the held shaft, which the brake holds as well.
                        locked += d * drag * w;
                    }
                }
                Clutch::Locked => {
                    *g.get_mut(Guard::release(k)) = Some(-(c[k] + c_tol));
                    locked += c[k];
                    any_locked = true;
                }
                Clutch::Engaged => *g.get_mut(Guard::release(k)) = Some(-(c[k] + c_tol)),
            }
        }
        if any_locked {
            g.breakaway = Some(locked - inputs.load);
        }
        if mode.shaft_turning() {
            g.shaft_stop = Some(-d * shaft);
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
