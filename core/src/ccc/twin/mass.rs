//! The oscillating mass as a parameter that changes between steps: an estimator's
//! (the observer's) estimate of the machine's, taken into every mode's model at the
//! present state with the energy the change puts in booked in the audit, and the
//! crank's acceleration's sensitivity to it.

use super::super::build::{physical_link, CRANK, ROCKER};
use super::error::TwinStepError;
use super::Twin;
use crate::scalar::{perp, rotate_cs, Real, Vec2};

impl<T: Real> Twin<T> {
    /// The oscillating mass the twin's models carry, kg.
    pub fn oscillating_mass(&self) -> T {
        self.params.mass
    }

    /// Sets the oscillating mass to `mass` (kg) at the present state: the rocker of
    /// every slot's model takes it (the mass's own moment of inertia scaled with it:
    /// the same body of another density), the state (positions, speeds) stays, and
    /// the mode is evaluated anew (its accelerations and clutch torques are the new
    /// mass's). The energy the change puts in (`½ δm v_C² - δm g·x_C` and the
    /// rotation's) is booked in the audit's correction term, so its residual stays
    /// where it was; returns it, J. A change that moves an event function past its
    /// crossing is not made (the twin as it was, `Ok(0)`): a mode change is the
    /// dynamics' to take. A mass not finite or not positive is refused
    /// ([`TwinStepError::BadInput`]); an evaluation that fails keeps the last good
    /// state and mass.
    pub fn set_oscillating_mass(&mut self, mass: T) -> Result<T, TwinStepError> {
        if !(mass.finite() && mass > T::zero()) {
            return Err(TwinStepError::BadInput {
                time: self.t.to_f64(),
                field: "oscillating mass",
                value: mass.to_f64(),
            });
        }
        let old = (self.params.mass, self.params.mass_inertia);
        if mass == old.0 {
            return Ok(T::zero());
        }
        self.params.mass_inertia = old.1 * (mass / old.0);
        self.params.mass = mass;
        self.rocker_to_slots();
        let inputs = self.inputs.inputs();
        let saved = self.slots.cur().warm_start();
        self.dp5.invalidate();
        self.last_guards = None;
        self.at_rest = false;
        self.state_evaluated = false;
        let g0 = self.guards;
        let w = self.work_from_state();
        let result = self.restart_at(&w, &inputs);
        if result.is_err() || !g0.fired(&self.guards).is_empty() {
            (self.params.mass, self.params.mass_inertia) = old;
            self.rocker_to_slots();
            self.restore(false, &saved);
            return result.map(|()| T::zero());
        }
        Ok(self.commit_booked(&w))
    }

    /// The rocker of the parameters into each slot's model that has it.
    fn rocker_to_slots(&mut self) {
        let l = physical_link(&self.params, ROCKER);
        for s in self.slots.s.iter_mut() {
            let body = s.body(ROCKER);
            if body != 0 {
                // A slot whose model has no such body (not built yet) is built from
                // the parameters when it is used.
                let _ = s.model.set_mass_properties(body, l.mass, l.inertia, l.cog);
            }
        }
    }

    /// `∂α1/∂m`: the crank's angular acceleration's sensitivity to the oscillating
    /// mass at the last evaluation, rad/s² per kg; 0 with no degree of freedom or a
    /// singular mass matrix. Lagrange's equations are linear in the mass: a mass
    /// `δm` more at the rocker's point C adds `δm J_Cᵀ(a_C - g) + δm k² J_ωᵀ α` to
    /// `M q̈ + …` (`J_C = ∂v_C/∂q̇`, `J_ω = ∂ω/∂q̇` the rocker's, `k²` the mass's own
    /// inertia per kg), so `∂q̈/∂m = -M⁻¹(J_Cᵀ(a_C - g) + k² J_ωᵀ α)` and
    /// `∂α1/∂m = r ∂q̈/∂m` (`r` the crank's row).
    pub fn crank_mass_sensitivity(&self) -> T {
        let slot = self.slots.cur();
        let dof = slot.map.dof.min(2);
        let body = slot.body(ROCKER) as usize;
        if dof == 0 || body == 0 {
            return T::zero();
        }
        let row = 3 * (body - 1);
        let v = |r: usize, c: usize| slot.ws.v.get((r, c)).copied().unwrap_or(T::zero());
        let bias = |r: usize| slot.ws.a_bias.get(r).copied().unwrap_or(T::zero());
        let qdd = |c: usize| slot.ws.qdd.get(c).copied().unwrap_or(T::zero());
        let rocker = self.links[ROCKER];
        let link = physical_link(&self.params, ROCKER);
        let (s, c) = rocker.theta.sincos();
        // C from the rocker's COG (the model's, the oscillating mass included).
        let r_gc = rotate_cs(
            c,
            s,
            &(Vec2::new(self.params.mass_at, T::zero()) - link.cog),
        );
        let turn = perp(&r_gc);
        let mut a_g = Vec2::new(bias(row), bias(row + 1));
        let mut alpha = bias(row + 2);
        for k in 0..dof {
            a_g += Vec2::new(v(row, k), v(row + 1, k)) * qdd(k);
            alpha += v(row + 2, k) * qdd(k);
        }
        let omega = rocker.omega;
        let a_c = a_g + turn * alpha - r_gc * (omega * omega);
        let k2 = self.params.mass_inertia / self.params.mass;
        let mut g = [T::zero(); 2];
        for (k, gk) in g.iter_mut().enumerate().take(dof) {
            let j_c = Vec2::new(v(row, k), v(row + 1, k)) + turn * v(row + 2, k);
            *gk = -(j_c.dot(&(a_c - self.params.gravity)) + k2 * v(row + 2, k) * alpha);
        }
        let r = slot.omega_row(CRANK);
        let (num, det) = match dof {
            1 => (
                r[0] * g[0],
                slot.ws.mass_q.get((0, 0)).copied().unwrap_or(T::zero()),
            ),
            _ => {
                // r M⁻¹ g with M⁻¹ = adj(M)/det.
                let (adj, det) = slot.mass_adjugate_times(g);
                (r[0] * adj[0] + r[1] * adj[1], det)
            }
        };
        if det > T::zero() {
            num / det
        } else {
            T::zero()
        }
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

    /// The sensitivity against central differences of the crank's acceleration over
    /// the mass, in each mode S2 passes through (1- and 2-DOF), at the first step of
    /// each.
    #[test]
    fn the_mass_sensitivity_is_the_acceleration_s_difference_quotient() {
        let (mut twin, inputs) = s2();
        let mut seen: Vec<Mode> = Vec::new();
        for _ in 0..4000 {
            twin.step(&inputs).unwrap();
            let mode = twin.mode();
            if seen.contains(&mode) || mode == Mode::Jam {
                continue;
            }
            seen.push(mode);
            let m = twin.oscillating_mass();
            let sens = twin.crank_mass_sensitivity();
            let eps = 1e-4;
            let at = |dm: f64| {
                let mut t = twin.clone();
                t.set_oscillating_mass(m + dm).unwrap();
                t.link(1).alpha
            };
            let fd = (at(eps) - at(-eps)) / (2.0 * eps);
            assert!(
                (sens - fd).abs() <= 1e-5 * fd.abs().max(1.0),
                "{mode:?}: {sens} vs {fd}"
            );
        }
        assert!(seen.len() >= 4, "{seen:?}");
    }

    /// A mass change books its energy: the audit's residual stays where it was (to
    /// 1e-12 J), and the energy booked is the point mass's `½ δm v_C² - δm g·x_C` plus
    /// its own rotation's `½ δI ω²` (computed here from the rocker's state, an
    /// independent path: the twin computes it from every link's); the twin steps on
    /// with its energy balance checked each step.
    #[test]
    fn a_mass_change_books_its_energy() {
        let (mut twin, inputs) = s2();
        for _ in 0..700 {
            twin.step(&inputs).unwrap();
        }
        let p = twin.params;
        let r = twin.link(3);
        let (c, s) = (r.theta.cos(), r.theta.sin());
        let at = Vec2::new(p.mass_at * c, p.mass_at * s);
        let v_c = r.velocity + Vec2::new(-at.y, at.x) * r.omega;
        let x_c = r.origin + at;
        let (dm, di) = (0.5, p.mass_inertia * 0.5 / p.mass);
        let expected =
            0.5 * dm * v_c.norm_squared() - dm * p.gravity.dot(&x_c) + 0.5 * di * r.omega * r.omega;
        let before = twin.audit();
        let e = twin.set_oscillating_mass(6.5).unwrap();
        let after = twin.audit();
        assert!(
            (after.residual() - before.residual()).abs() < 1e-12,
            "{before:?} {after:?}"
        );
        assert!(
            (e - expected).abs() < 1e-9 * expected.abs().max(1.0),
            "{e} vs {expected}"
        );
        assert!((after.correction - before.correction - e).abs() < 1e-12);
        assert_eq!(twin.oscillating_mass(), 6.5);
        for _ in 0..300 {
            twin.step(&inputs).expect("steps on, balance checked");
        }
        let a = twin.audit();
        assert!(a.residual().abs() < 1e-6 * a.motor_work, "{a:?}");
    }

    /// A mass that is not finite or not positive is a named error and changes nothing
    /// (the twin's state to the bit); the same mass again is no change (no energy, no
    /// evaluation).
    #[test]
    fn a_bad_mass_is_refused_and_the_twin_kept() {
        let (mut twin, inputs) = s2();
        for _ in 0..50 {
            twin.step(&inputs).unwrap();
        }
        let state = |t: &Twin<f64>| std::format!("{:?} {:?} {:?}", t.y, t.links, t.audit);
        let before = state(&twin);
        for m in [f64::NAN, 0.0, -1.0, f64::INFINITY] {
            let e = twin.set_oscillating_mass(m).unwrap_err();
            assert!(std::format!("{e}").contains("oscillating mass"), "{e}");
        }
        assert_eq!(twin.set_oscillating_mass(6.0).unwrap(), 0.0);
        assert_eq!(state(&twin), before);
        assert_eq!(twin.oscillating_mass(), 6.0);
    }

    /// The model's setter: a body that exists takes the values; no such body, a
    /// negative mass or inertia, or a value not finite leave the model as it was.
    #[test]
    fn the_model_takes_mass_properties_it_validates() {
        let (twin, _) = s2();
        let mut m = twin.slots.cur().model.clone();
        let body = twin.slots.cur().body(super::ROCKER);
        let cog = Vec2::new(0.3, 0.0);
        assert_eq!(m.set_mass_properties(body, 7.0, 0.5, cog), Ok(()));
        let l = &m.links()[usize::from(body) - 1];
        assert_eq!((l.mass, l.inertia, l.cog), (7.0, 0.5, cog));
        for (b, mass, inertia, c) in [
            (99, 1.0, 1.0, cog),
            (0, 1.0, 1.0, cog),
            (body, -1.0, 1.0, cog),
            (body, 1.0, -1.0, cog),
            (body, f64::NAN, 1.0, cog),
            (body, 1.0, 1.0, Vec2::new(f64::INFINITY, 0.0)),
        ] {
            assert!(m.set_mass_properties(b, mass, inertia, c).is_err());
        }
        let l = &m.links()[usize::from(body) - 1];
        assert_eq!((l.mass, l.inertia, l.cog), (7.0, 0.5, cog));
    }
}
