//! SPEC 3's consistency conditions: how far a mode violates them, from its own model
//! or screened from the reference model.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use super::impact::constraint_rows;
use super::inputs::Inputs;
use super::settings::*;
use super::slot::{LinkState, QD, STATE};
use super::{shaft_accel, shaft_speed, Twin};
use crate::scalar::Real;
use nalgebra::{SMatrix, SVector};

/// Whether mode `m`'s clutch torques `c` (N·m, from [`Twin::screen`]) are clear of
/// [`Twin::violation`]'s torque conditions by [`screen_margin`] of its torque scale:
/// each locked or engaged lever's `c_k` over its threshold, and a held shaft's locked
/// torques under `T_r`, by that much. Its own model's kinetostatics, which differ by
/// rounding, would then decide those conditions alike.
pub(super) fn torques_clear<T: Real>(m: Mode, c: &[T; 2], inputs: &Inputs<T>) -> bool {
    let scale = inputs.load + T::one() + c[0].abs() + c[1].abs();
    let clear = torque_tol(scale) + screen_margin::<T>() * scale;
    let mut locked = T::zero();
    for (ck, clutch) in c.iter().zip(m.clutches()) {
        match clutch {
            Clutch::Free => {}
            Clutch::Locked | Clutch::Engaged => {
                if !(*ck > clear) {
                    return false;
                }
                if clutch == Clutch::Locked {
                    locked += *ck;
                }
            }
        }
    }
    m.shaft_turning() || locked < inputs.load - clear
}

/// Which free levers a mode choice's consistency conditions take as touching the
/// shaft, whose acceleration then may not pass the shaft's in the drive direction.
#[derive(Clone, Copy, Debug)]
pub(super) struct Touch<T> {
    /// A lever whose speed is within this of the shaft's touches it, rad/s.
    pub tol_w: T,
    /// The levers (6, 8) that held the shaft as it stopped: they touch it whatever
    /// their speed. The state of a shaft stop lies a little past the stop (on the
    /// dense output, or the end of a step taken just past it), where the levers still
    /// move with the shaft's residual speed and the other links with what it
    /// transmits to them; a candidate that holds the shaft sees that speed as the
    /// levers' speed relative to it, which is the stop's location error, not a motion
    /// away. Without this, a lever moving 4e-5 rad/s "away" was let go and caught
    /// again 3 µs later (friction at every joint, 8/1000 at h = 1 ms).
    pub held_at_stop: [bool; 2],
}

impl<T: Real> Twin<T> {
    /// How far mode `m` (entered from `from`) with the clutch torques `c` and the
    /// physical links' speeds and accelerations `links` violates SPEC 3's consistency
    /// conditions, each relative to its scale (0: consistent): c_k ≥ 0 for a locked or
    /// engaged lever, Σc_k ≤ T_r over the locked ones, a free lever does not move past
    /// the shaft in the drive direction (by more than `touch.tol_w`, relative to the
    /// largest link speed) and, touching it (as `touch` says), does not accelerate
    /// past it, a shaft starting from rest accelerates in the drive direction.
    /// `coast`: the shaft's speed (rad/s) and acceleration (rad/s²) if `m` is
    /// [`Mode::Coast`] (no lever carries it).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn violation(
        &self,
        m: Mode,
        from: Mode,
        c: &[T; 2],
        links: &[LinkState<T>; 9],
        inputs: &Inputs<T>,
        touch: Touch<T>,
        coast: [T; 2],
    ) -> T {
        let d = self.drive;
        let torque_scale = inputs.load + T::c(1.0) + c[0].abs() + c[1].abs();
        let tol_c = torque_tol(torque_scale);
        let alpha_scale = links.iter().fold(T::one(), |a, s| a.max(s.alpha.abs()));
        let omega_scale = links.iter().fold(T::one(), |a, s| a.max(s.omega.abs()));
        let tol_a = T::c(1e-9) * alpha_scale;
        let coasting = m == Mode::Coast;
        let shaft_alpha = if coasting {
            coast[1]
        } else {
            shaft_accel(m, links)
        };
        let shaft_w = if coasting {
            coast[0]
        } else {
            shaft_speed(m, links)
        };
        let mut v = T::zero();
        let mut locked = T::zero();
        for (k, ((_, lever), clutch)) in BRANCHES.iter().zip(m.clutches()).enumerate() {
            match clutch {
                Clutch::Locked | Clutch::Engaged => {
                    v += (-c[k] - tol_c).max(T::zero()) / torque_scale;
                    if clutch == Clutch::Locked {
                        locked += c[k];
                    }
                }
                Clutch::Free => {
                    // A free lever touching the shaft must not pass it in the drive
                    // direction.
                    let l = links.get(*lever).copied().unwrap_or_default();
                    let drag = self.params.friction.clutch_drag;
                    if drag != T::zero() && !m.shaft_turning() && m != Mode::Free {
                        // Its drag on the held shaft, which the brake holds as well.
                        locked += d * drag * l.omega;
                    }
                    let rel_w = l.omega - shaft_w;
                    // Nor may it move past it (that is a catch): a lever that held
                    // the shaft before the event and is let go can leave the impact's
                    // projection a little faster than the shaft, and its catch
                    // function, past 0 from the start, would never cross it (with
                    // friction and J_s = 0.5 kg·m², counter-clockwise at 22/200 N·m at
                    // h = 1 ms, lever 6 ran 15 ms through its clutch in I8).
                    if m != Mode::Free {
                        v += (d * rel_w - touch.tol_w).max(T::zero()) / omega_scale;
                    }
                    if rel_w.abs() <= touch.tol_w || touch.held_at_stop.get(k) == Some(&true) {
                        let rel = d * (l.alpha - shaft_alpha);
                        v += (rel - tol_a).max(T::zero()) / alpha_scale;
                    }
                }
            }
        }
        if !m.shaft_turning() {
            v += (locked - inputs.load - tol_c).max(T::zero()) / torque_scale;
        } else if !from.shaft_turning() {
            // A shaft starting from rest turns in the drive direction.
            v += (-d * shaft_alpha - tol_a).max(T::zero()) / alpha_scale;
        }
        v
    }

    /// Turns the clutch drag in the reference's generalized forces `rhs` (both levers
    /// overrunning a held shaft, at the reference's evaluated speeds) into mode `m`'s at
    /// the speeds `u_plus`: none on a locked or engaged lever, `-drag·(ω_k − ω_s)` on an
    /// overrunning one and the opposite on a turning shaft (`ω_s` the engaged lever's
    /// speed; a held shaft's brake takes it).
    fn drag_as_in(&self, m: Mode, u_plus: &SVector<T, 3>, drag: T, rhs: &mut SVector<T, 6>) {
        let r = self.slots.reference();
        let speed = |lever: usize| {
            let v = r.omega_row(lever);
            v[0] * u_plus[0] + v[1] * u_plus[1]
        };
        let clutches = m.clutches();
        let ws = if m == Mode::Coast {
            u_plus[2]
        } else if m.shaft_turning() {
            BRANCHES
                .iter()
                .zip(clutches.iter())
                .find(|(_, c)| **c == Clutch::Engaged)
                .map_or(T::zero(), |((_, lever), _)| speed(*lever))
        } else {
            T::zero()
        };
        for ((_, lever), clutch) in BRANCHES.iter().zip(clutches.iter()) {
            let v = r.omega_row(*lever);
            // Take out the reference's drag on this lever, put in the mode's.
            let mut on_lever = drag * r.omega_of(*lever);
            if *clutch == Clutch::Free {
                let slip = drag * (speed(*lever) - ws);
                on_lever -= slip;
                if m.shaft_turning() {
                    rhs[2] += slip;
                }
            }
            rhs[0] += v[0] * on_lever;
            rhs[1] += v[1] * on_lever;
        }
    }

    /// Mode `m`'s violation of SPEC 3's consistency conditions (as
    /// [`Twin::violation`]) from the reference model (I0, both levers free), without
    /// building `m`'s model, with its clutch torques (N·m): `None` if it cannot tell.
    /// At the state `yr` with the
    /// speeds `u_plus` after the impact projection, the reference's equations of motion
    /// `M q̈ = Q` with the shaft as a third coordinate (inertia J_s, possibly 0; the load
    /// -d·T_r on it while it turns) and `m`'s clutches as constraints on the
    /// accelerations, `J q̈ = -β` (a locked lever's `α_k = 0`, an engaged one's
    /// `α_k = α_s`, a held shaft's `α_s = 0`; `β`: the levers' bias accelerations), give
    /// `q̈` and the multipliers λ of the KKT system `[M Jᵀ; J 0] [q̈; -λ] = [Q; -β]`:
    /// λ_k is the torque lever k's clutch applies to it, so `c_k = -d·λ_k` (SPEC 3: the
    /// moment of everything else on the lever minus `I_H α_k`). The same motion as
    /// `m`'s own model, up to rounding.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn screen(
        &mut self,
        m: Mode,
        from: Mode,
        yr: &mut SVector<T, STATE>,
        u_plus: &SVector<T, 3>,
        t: T,
        inputs: &Inputs<T>,
        touch: Touch<T>,
    ) -> Option<(T, [T; 2])> {
        let d = self.drive;
        // The reference evaluated at the candidate's speeds, unless the speeds `yr` its
        // workspace holds differ from them by under 1e-3 of the screen's margin
        // (relative to the largest speed): the bias accelerations, quadratic in the
        // speeds, then differ by 2e-3 of the margin at most. Without an impact (a
        // release, a catch located in time) the projection moves the speeds by rounding.
        // For the reference's own mode (I0) exactly at them: the reference is then the
        // candidate itself (see `Twin::reference_is_candidate`).
        let scale = u_plus.iter().fold(T::one(), |a, v| a.max(v.abs()));
        let moved = (0..2).fold(T::zero(), |a, k| a.max((yr[QD + k] - u_plus[k]).abs()));
        let exact = m == self.slots.reference().mode;
        if !(moved <= screen_margin::<T>() * T::c(1e-3) * scale) || (exact && moved != T::zero()) {
            yr[QD] = u_plus[0];
            yr[QD + 1] = u_plus[1];
            if self
                .slots
                .reference_mut()
                .eval(
                    t,
                    yr,
                    inputs,
                    d,
                    self.lossy.then_some(&self.params.friction),
                    T::zero(),
                )
                .is_err()
            {
                // The workspace holds no evaluation: the next screen evaluates again.
                yr[QD] = T::c(f64::NAN);
                return None;
            }
        }
        let x = self.reference_kkt(m, inputs, u_plus)?;
        let r = self.slots.reference();
        let row = |lever: usize| r.lever_row(lever);
        // The multipliers in the order of `constraint_rows`: one per locked or engaged
        // lever, in branch order.
        let mut c = [T::zero(); 2];
        let mut i = 3;
        for (ck, clutch) in c.iter_mut().zip(m.clutches()) {
            if clutch != Clutch::Free {
                *ck = d * x.get(i).copied().unwrap_or(T::zero());
                i += 1;
            }
        }
        let mut links = [LinkState::default(); 9];
        for (p, l) in links.iter_mut().enumerate().skip(1) {
            let v = row(p);
            l.omega = v[0] * u_plus[0] + v[1] * u_plus[1];
            l.alpha = v[0] * x[0] + v[1] * x[1] + r.alpha_bias(p);
        }
        let coast = [u_plus[2], x[2]];
        Some((self.violation(m, from, &c, &links, inputs, touch, coast), c))
    }

    /// The reference's KKT system with mode `m`'s clutches as constraints on the
    /// accelerations (see [`Twin::screen`]), solved: `q̈` (with the shaft's) and the
    /// multipliers, in the order of `constraint_rows`; `None` if it is singular or its
    /// solution not finite.
    fn reference_kkt(
        &self,
        m: Mode,
        inputs: &Inputs<T>,
        u_plus: &SVector<T, 3>,
    ) -> Option<SVector<T, 6>> {
        let d = self.drive;
        let r = self.slots.reference();
        let row = |lever: usize| r.lever_row(lever);
        let rows = constraint_rows(m, true, row);
        // The constraints' bias terms: the same combinations of the levers' bias
        // accelerations (first component; the shaft's bias is 0).
        let bias = constraint_rows(m, true, |lever| {
            SVector::<T, 3>::new(r.alpha_bias(lever), T::zero(), T::zero())
        });
        let mut kkt = SMatrix::<T, 6, 6>::identity();
        let mut rhs = SVector::<T, 6>::zeros();
        for i in 0..2 {
            for j in 0..2 {
                kkt[(i, j)] = r.ws.mass_q[(i, j)];
            }
            rhs[i] = r.ws.gen_force[i];
        }
        kkt[(2, 2)] = self.params.shaft_inertia;
        if m.shaft_turning() {
            rhs[2] = -d * inputs.load;
        }
        let drag = self.params.friction.clutch_drag;
        if drag != T::zero() {
            self.drag_as_in(m, u_plus, drag, &mut rhs);
        }
        // At most the three coordinates' worth of constraints (3 rows per mode).
        for (i, (a, b)) in rows.iter().zip(bias.iter()).take(3).enumerate() {
            let k = 3 + i;
            for (j, aj) in a.iter().enumerate() {
                for at in [(k, j), (j, k)] {
                    if let Some(e) = kkt.get_mut(at) {
                        *e = *aj;
                    }
                }
            }
            if let Some(e) = kkt.get_mut((k, k)) {
                *e = T::zero();
            }
            if let Some(e) = rhs.get_mut(k) {
                *e = -b[0];
            }
        }
        let x = crate::linalg::solve(kkt, rhs)?;
        x.iter().all(|v| v.finite()).then_some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::mode::Mode;
    use super::super::super::params::CccParams;
    use super::super::inputs::{Inputs, MotorInput};
    use super::super::slot::LinkState;
    use super::super::{Twin, TwinSettings};
    use super::{torques_clear, Touch};

    fn inputs(load: f64) -> Inputs<f64> {
        Inputs {
            motor: MotorInput::Torque(0.0),
            load,
            measured: None,
        }
    }

    /// The reference twin (drive clockwise: d = -1); only its drive direction is read.
    fn twin() -> Twin<f64> {
        Twin::new(
            CccParams::reference(),
            TwinSettings::reference(1e-4),
            inputs(100.0),
        )
        .unwrap()
    }

    /// Links at rest, lever `lever` with angular speed `w` and acceleration `a`.
    fn links(lever: usize, w: f64, a: f64) -> [LinkState<f64>; 9] {
        let mut l = [LinkState::default(); 9];
        l[lever].omega = w;
        l[lever].alpha = a;
        l
    }

    /// SPEC 3's conditions on hand-built states with known answers: a locked lever's
    /// clutch pushes in the drive direction (c ≥ 0), the held shaft's locked torque
    /// stays under T_r, a free lever touching the shaft does not accelerate past it in
    /// the drive direction, a shaft starting from rest turns in the drive direction.
    /// Each violation is its excess over the scale (T_r + 1 + |c6| + |c8| for torques,
    /// the largest |α| for accelerations), up to the thresholds (1e-9 of the scale).
    #[test]
    fn the_consistency_conditions_on_hand_built_states() {
        let tw = twin();
        let d = -1.0; // clockwise
        let tol_w = 1e-6;
        let at_rest = [LinkState::default(); 9];
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-8 * (1.0 + b.abs());
        let by_speed = Touch {
            tol_w,
            held_at_stop: [false; 2],
        };
        let v = |m, from, c: [f64; 2], l: &[LinkState<f64>; 9], load| {
            tw.violation(m, from, &c, l, &inputs(load), by_speed, [0.0; 2])
        };
        // A locked lever (I6): c6 = +5 N·m holds, c6 = -5 N·m pulls: violates by 5/106.
        assert_eq!(v(Mode::I6, Mode::I0, [5.0, 0.0], &at_rest, 100.0), 0.0);
        assert!(close(
            v(Mode::I6, Mode::I0, [-5.0, 0.0], &at_rest, 100.0),
            5.0 / 106.0
        ));
        // The held shaft: c6 = 150 N·m against T_r = 100 N·m breaks away: 50/251.
        assert!(close(
            v(Mode::I6, Mode::I0, [150.0, 0.0], &at_rest, 100.0),
            50.0 / 251.0
        ));
        assert_eq!(v(Mode::I6, Mode::I0, [99.0, 0.0], &at_rest, 100.0), 0.0);
        // An engaged lever (A6) with the shaft turning carries any c ≥ 0 (no T_r bound).
        assert_eq!(v(Mode::A6, Mode::A6, [500.0, 0.0], &at_rest, 100.0), 0.0);
        // A free lever touching the held shaft (I0, ω6 = 0): accelerating in the drive
        // direction (d·α6 = 2 > 0) overruns it: 2/2 of the α scale; the other way is fine.
        assert!(close(
            v(Mode::I0, Mode::I0, [0.0; 2], &links(6, 0.0, 2.0 * d), 0.0),
            1.0
        ));
        assert_eq!(
            v(Mode::I0, Mode::I0, [0.0; 2], &links(6, 0.0, -2.0 * d), 0.0),
            0.0
        );
        // Not touching (ω6 off the shaft's by 1 rad/s against the drive direction): no
        // condition on its α.
        assert_eq!(
            v(Mode::I0, Mode::I0, [0.0; 2], &links(6, 1.0, 2.0 * d), 0.0),
            0.0
        );
        // Moving past the held shaft in the drive direction (d·ω6 = 1e-4 rad/s, over
        // `tol_w`) is a catch, not a free lever: (1e-4 - 1e-6) of the speed scale (1).
        assert!(close(
            v(
                Mode::I0,
                Mode::I0,
                [0.0; 2],
                &links(6, 1e-4 * d, -2.0 * d),
                0.0
            ),
            1e-4 - 1e-6
        ));
        // Past it by 2 rad/s while the fastest link turns at 4: 2/4 more.
        let mut fast = links(6, 2.0 * d, -2.0 * d);
        fast[3].omega = 4.0;
        assert!(close(
            v(Mode::I0, Mode::I0, [0.0; 2], &fast, 0.0),
            (2.0 - 1e-6) / 4.0
        ));
        // The shaft starting from rest with lever 6 (I6 -> A6): α_s = α6 must be in the
        // drive direction; against it (d·α6 = -3) violates by 3/3. Lever 8, free and at
        // rest, touches the shaft there too and then passes it (d·(α8 - α_s) = 3): 3/3
        // more; moving off the shaft (ω8 = 1 rad/s) it is free of the condition.
        assert_eq!(
            v(Mode::A6, Mode::I6, [1.0, 0.0], &links(6, 0.0, 3.0 * d), 0.0),
            0.0
        );
        assert!(close(
            v(
                Mode::A6,
                Mode::I6,
                [1.0, 0.0],
                &links(6, 0.0, -3.0 * d),
                0.0
            ),
            2.0
        ));
        let mut off = links(6, 0.0, -3.0 * d);
        off[8].omega = 1.0;
        assert!(close(v(Mode::A6, Mode::I6, [1.0, 0.0], &off, 0.0), 1.0));

        // A shaft stop (A68 -> I0) located a little past the stop: lever 8 still moves
        // with the shaft's residual speed, 4e-5 rad/s against the drive direction (over
        // `tol_w`), and accelerates in it (d·α8 = 2). By speed alone it is off the shaft
        // and free to go; having held the shaft as it stopped, it touches it, and
        // passing it violates by 2/2.
        let stopping = links(8, -4e-5 * d, 2.0 * d);
        assert_eq!(v(Mode::I0, Mode::A68, [0.0; 2], &stopping, 800.0), 0.0);
        let at_stop = Touch {
            tol_w,
            held_at_stop: [true; 2],
        };
        let load = inputs(800.0);
        let c = [0.0; 2];
        let held = tw.violation(Mode::I0, Mode::A68, &c, &stopping, &load, at_stop, [0.0; 2]);
        assert!(close(held, 1.0), "{held}");
        // Accelerating against the drive direction, it lets go.
        let leaving = links(8, -4e-5 * d, -2.0 * d);
        let free = tw.violation(Mode::I0, Mode::A68, &c, &leaving, &load, at_stop, [0.0; 2]);
        assert_eq!(free, 0.0);
    }

    /// The screen's torques stand for the kinetostatics' only when clear of the
    /// thresholds by the screen's margin (1e-6 of the scale): a lever just above 0, or
    /// a held shaft just under T_r, is left to its own model.
    #[test]
    fn screened_torques_are_clear_only_away_from_the_thresholds() {
        let i = inputs(100.0);
        assert!(torques_clear(Mode::I6, &[5.0, 0.0], &i));
        assert!(!torques_clear(Mode::I6, &[1e-7, 0.0], &i));
        assert!(!torques_clear(Mode::I6, &[100.0 - 1e-6, 0.0], &i));
        assert!(torques_clear(Mode::A6, &[500.0, 0.0], &i));
        assert!(!torques_clear(Mode::A68, &[5.0, -1.0], &i));
        assert!(torques_clear(Mode::I0, &[0.0, 0.0], &i));
    }
}
