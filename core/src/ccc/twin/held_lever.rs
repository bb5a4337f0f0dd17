//! The locked lever's angle as a quantity an estimator corrects (the observer's).
//!
//! In I6 and I8 the locked lever stands where it stopped, and its pin is a ground point
//! of the mode's model ([`build`](super::super::build)): a constant of the mode, not a
//! state. The twin's lever stopped where the twin put it, which the crank's encoder
//! alone does not pin down (the 2-DOF phases before leave one coordinate unobserved),
//! and the crank's motion in these modes depends on it: near a reversal of the crank
//! in I6 (a dead point of the crank in the mode's coordinates), the crank's extreme
//! angle is set by the pin. On the known machine's logs at 600 N·m the twin's lever 6
//! stood 0.0021 rad off the machine's and its crank reversed 17 counts beyond the
//! machine's. [`Twin::move_held_lever`] moves the pin at the present state, the
//! mode's coordinates and their rates kept (so the crank moves), with the energy the
//! move puts in booked in the audit; [`Twin::held_lever_sensitivity`] is the crank's
//! angle's derivative with respect to the pin's angle there.

use super::super::build::{BRANCHES, CRANK};
use super::super::mode::{Clutch, Mode};
use super::coordinates::Rates;
use super::correction::Correction;
use super::error::TwinStepError;
use super::spread::Pending;
use super::Twin;
use crate::error::StepError;
use crate::scalar::Real;

/// The physical number of the mode's one locked lever (I6: 6, I8: 8), if it has one.
fn held_lever(mode: Mode) -> Option<usize> {
    let c = mode.clutches();
    match (c[0] == Clutch::Locked, c[1] == Clutch::Locked) {
        (true, false) => Some(BRANCHES[0].1),
        (false, true) => Some(BRANCHES[1].1),
        _ => None,
    }
}

impl<T: Real> Twin<T> {
    /// The angle the mode's locked lever stands at (I6: lever 6, I8: lever 8), rad;
    /// `None` in a mode without exactly one locked lever.
    pub fn held_lever_angle(&self) -> Option<T> {
        held_lever(self.slots.cur().mode).and_then(|l| self.links.get(l).map(|s| s.theta))
    }

    /// `∂θ1/∂ψ`: how the crank's angle moves with the locked lever's angle `ψ` at the
    /// present state, the mode's coordinates kept (rad/rad): the mode assembled in the
    /// scratch slot with the lever `ε` further on (`ε = √ε_machine` rad, a forward
    /// difference; the state untouched). 0 in a mode without one locked lever, with
    /// the crank a coordinate, or where the moved mode does not assemble.
    pub fn held_lever_sensitivity(&mut self) -> T {
        let (mode, coords) = (self.slots.cur().mode, self.slots.cur().coords);
        let Some(lever) = held_lever(mode) else {
            return T::zero();
        };
        let mut pose = self.slot_links_unwrapped();
        let crank = pose[CRANK];
        let eps = T::EPS.root();
        if let Some(a) = pose.get_mut(lever) {
            *a += eps;
        }
        let time = self.t.to_f64();
        let (scratch, params) = self.scratch(false);
        if scratch
            .reposition(params, mode, coords, &pose, time)
            .is_err()
        {
            return T::zero();
        }
        let moved = super::slot::unwrap_near(scratch.links(params)[CRANK].theta, crank);
        (moved - crank) / eps
    }

    /// Moves the locked lever (I6: lever 6, I8: lever 8) by `d` (rad) at the present
    /// time: its pin moves with it, the mode's coordinates and their rates stay, the
    /// other links are re-solved there (the crank moves, unless it is a coordinate),
    /// the mode is evaluated anew and the energy the move puts in is booked in the
    /// audit's correction term (its residual stays where it was). A move that would
    /// take an event function past its crossing, or after which the mode does not
    /// assemble, is not made (the twin as it was; `applied` false). Nothing is done in
    /// a mode without one locked lever. A `d` that is no number is refused (a named
    /// error, the twin as it was).
    pub fn move_held_lever(&mut self, d: T) -> Result<Correction<T>, TwinStepError> {
        if !d.finite() {
            return Err(TwinStepError::BadInput {
                time: self.t.to_f64(),
                field: "held lever correction",
                value: d.to_f64(),
            });
        }
        if matches!(self.pending, Some(Pending::Choice(_))) {
            // The state is an event's, its mode chosen by the next step: it stays.
            return Ok(Correction::none());
        }
        let (mode, coords) = (self.slots.cur().mode, self.slots.cur().coords);
        let Some(lever) = held_lever(mode) else {
            return Ok(Correction::none());
        };
        if d == T::zero() {
            return Ok(Correction::none());
        }
        let inputs = self.inputs.inputs();
        let saved = self.slots.cur().warm_start();
        let before = self.links[CRANK];
        let links = self.slots.cur().links(&self.params);
        let mut pose = self.unwrapped(&links);
        if let Some(a) = pose.get_mut(lever) {
            *a += d;
        }
        let time = self.t.to_f64();
        let (scratch, params) = self.scratch(false);
        let q = match scratch.reposition(params, mode, coords, &pose, time) {
            Ok(q) => q,
            Err(TwinStepError::Step(StepError::Group { .. })) => return Ok(Correction::none()),
            Err(e) => return Err(e),
        };
        self.last_guards = None;
        self.at_rest = false;
        self.state_evaluated = false;
        let g0 = self.guards;
        let mut w = self.work_from_state();
        let result = self.adopt_scratch(&mut w, &inputs, &q, &links, Rates::OfTheirLinks);
        if result.is_err() || !g0.fired(&self.guards).is_empty() {
            self.restore(w.switched, &saved);
            return result.map(|()| Correction::none());
        }
        let energy = self.commit_booked(&w);
        Ok(self.made(&before, energy))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Inputs, Twin};
    use crate::ccc::Mode;
    use crate::scalar::Vec2;
    extern crate std;
    use std::boxed::Box;
    use std::vec::Vec;

    fn s2() -> (Box<Twin<f64>>, Inputs<f64>) {
        super::super::tests::s2(1e-4)
    }

    /// S2 stepped to 5 ms into each phase of a mode with one locked lever (I6, I8),
    /// at most `n` of them.
    fn held_states(n: usize) -> Vec<(Box<Twin<f64>>, Inputs<f64>)> {
        let (mut twin, inputs) = s2();
        let (mut out, mut since) = (Vec::new(), 0);
        for _ in 0..8000 {
            twin.step(&inputs).unwrap();
            since = if twin.events().is_empty() {
                since + 1
            } else {
                0
            };
            if since == 50 && matches!(twin.mode(), Mode::I6 | Mode::I8) {
                out.push((twin.clone(), inputs));
                if out.len() == n {
                    break;
                }
            }
        }
        out
    }

    /// The largest gap between the two ends of each of SPEC 3's revolute joints, from
    /// the links' angles and the bars' lengths alone (the oracle: not the solver's
    /// groups), m.
    fn joint_gap(t: &Twin<f64>) -> f64 {
        let p = t.params;
        let at = |link: usize, point: usize| t.joint_position(link, point);
        let pairs: [(Vec2<f64>, Vec2<f64>); 11] = [
            (at(1, 0), p.a),
            (at(1, 1), at(2, 0)),
            (at(2, 1), at(3, 1)),
            (at(3, 0), at(4, 1)),
            (at(4, 0), p.f),
            (at(3, 2), at(5, 0)),
            (at(3, 2), at(7, 0)),
            (at(5, 1), at(6, 1)),
            (at(7, 1), at(8, 1)),
            (at(6, 0), p.h),
            (at(8, 0), p.h),
        ];
        pairs
            .iter()
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max)
    }

    /// A move of the locked lever by 2 mrad, in each I6 and I8 phase of S2: the lever
    /// stands 2 mrad on (to rounding), the mode's coordinate link keeps its angle and
    /// speed, every joint of the linkage closes at the new pose (from the links'
    /// angles and lengths, to 1e-12 m), the crank moved, and the energy the move put
    /// in is booked: the audit's residual stays (to 1e-12 J) while the state's
    /// energy changed by the booked amount. The twin then steps on, its balance
    /// checked each step, the audit within 1e-6 of the motor work.
    #[test]
    fn a_held_lever_move_keeps_the_coordinate_closes_every_joint_and_books_its_energy() {
        let states = held_states(6);
        assert!(states.len() >= 4, "{}", states.len());
        let mut modes = Vec::new();
        for (mut twin, inputs) in states {
            let mode = twin.mode();
            modes.push(mode);
            let lever = if mode == Mode::I6 { 6 } else { 8 };
            let coord = twin.slots.cur().map.coord_link[0] as usize;
            let (psi, q) = (twin.held_lever_angle().unwrap(), twin.link(coord));
            let (crank, before) = (twin.link(1), twin.audit());
            assert!(
                joint_gap(&twin) < 1e-12,
                "{mode:?} before: {}",
                joint_gap(&twin)
            );
            let c = twin.move_held_lever(2e-3).unwrap();
            assert!(c.applied, "{mode:?} at {}", twin.time());
            assert!((twin.held_lever_angle().unwrap() - psi - 2e-3).abs() < 1e-14);
            assert!((twin.link(lever).theta - psi - 2e-3).abs() < 1e-14);
            assert!((twin.link(coord).theta - q.theta).abs() < 1e-13, "{mode:?}");
            assert!((twin.link(coord).omega - q.omega).abs() < 1e-12, "{mode:?}");
            assert!(joint_gap(&twin) < 1e-12, "{mode:?}: {}", joint_gap(&twin));
            assert!(c.crank.0.abs() > 1e-5, "{mode:?}: {c:?}");
            assert_eq!(c.crank.0, twin.link(1).theta - crank.theta);
            let after = twin.audit();
            assert!(
                (after.residual() - before.residual()).abs() < 1e-12,
                "{before:?} {after:?}"
            );
            let d_energy = after.kinetic + after.potential - before.kinetic - before.potential;
            assert!((c.energy - d_energy).abs() < 1e-12, "{c:?} {d_energy}");
            assert!((after.correction - before.correction - c.energy).abs() < 1e-12);
            for _ in 0..300 {
                twin.step(&inputs).expect("steps on, balance checked");
            }
            let a = twin.audit();
            assert!(a.residual().abs() < 1e-6 * a.motor_work, "{a:?}");
        }
        assert!(
            modes.contains(&Mode::I6) && modes.contains(&Mode::I8),
            "{modes:?}"
        );
    }

    /// `∂θ1/∂ψ` against the central difference of two moves of ±1e-6 rad (each from the
    /// same state, on copies), in each I6 and I8 phase of S2, to 1e-6 of it.
    #[test]
    fn the_held_lever_sensitivity_is_the_crank_s_difference_quotient() {
        for (mut twin, _) in held_states(6) {
            let mode = twin.mode();
            let sens = twin.held_lever_sensitivity();
            let moved = |d: f64| {
                let mut t = twin.clone();
                let c = t.move_held_lever(d).unwrap();
                assert!(c.applied);
                c.crank.0
            };
            let fd = (moved(1e-6) - moved(-1e-6)) / 2e-6;
            assert!(
                (sens - fd).abs() <= 1e-6 * fd.abs().max(1.0),
                "{mode:?}: {sens} vs {fd}"
            );
        }
    }

    /// Where no lever is locked alone (I0, A68, the jam) there is nothing to move: no
    /// move, a sensitivity of 0, the twin's state to the bit; a move that is no number
    /// is a named error with the twin kept.
    #[test]
    fn no_locked_lever_no_move_and_a_bad_move_is_refused() {
        let (mut twin, inputs) = s2();
        let state = |t: &Twin<f64>| std::format!("{:?} {:?} {:?}", t.y, t.links, t.audit);
        let mut seen = Vec::new();
        for _ in 0..9000 {
            twin.step(&inputs).unwrap();
            let mode = twin.mode();
            if matches!(mode, Mode::I6 | Mode::I8) || seen.contains(&mode) {
                continue;
            }
            seen.push(mode);
            let before = state(&twin);
            assert_eq!(twin.held_lever_angle(), None);
            assert_eq!(twin.held_lever_sensitivity(), 0.0);
            let c = twin.move_held_lever(1e-3).unwrap();
            assert!(!c.applied && c.crank == (0.0, 0.0) && c.energy == 0.0);
            assert_eq!(state(&twin), before, "{mode:?}");
        }
        assert!(
            seen.contains(&Mode::I0) && seen.contains(&Mode::A68),
            "{seen:?}"
        );
        let (mut twin, _) = held_states(1).pop().unwrap();
        let before = state(&twin);
        for d in [f64::NAN, f64::INFINITY] {
            let e = twin.move_held_lever(d).unwrap_err();
            assert!(std::format!("{e}").contains("held lever correction"), "{e}");
        }
        assert_eq!(state(&twin), before);
    }
}
