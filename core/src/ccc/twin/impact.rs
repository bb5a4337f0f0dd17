//! The plastic impact (SPEC 3): the velocity constraints of a mode in the reference
//! space and the projection of the speeds onto them.

use super::super::build::BRANCHES;
use super::super::mode::{Clutch, Mode};
use crate::scalar::Real;
use nalgebra::{SMatrix, SVector};

/// The velocity constraints of mode `m` in the reference space `(q̇1, q̇2, ω_s)`: a
/// locked lever stands still, an engaged one turns with the shaft (without shaft
/// inertia: with the other engaged lever), a held shaft stands still.
pub(super) fn constraint_rows<T: Real>(
    m: Mode,
    with_shaft: bool,
    row: impl Fn(usize) -> SVector<T, 3>,
) -> heapless::Vec<SVector<T, 3>, 3> {
    let mut rows = heapless::Vec::new();
    let shaft = SVector::<T, 3>::new(T::zero(), T::zero(), T::one());
    let c = m.clutches();
    for (k, (_, lever)) in BRANCHES.iter().enumerate() {
        match c[k] {
            Clutch::Locked => {
                let _ = rows.push(row(*lever));
            }
            Clutch::Engaged if with_shaft => {
                let _ = rows.push(row(*lever) - shaft);
            }
            _ => {}
        }
    }
    if !with_shaft && c == [Clutch::Engaged, Clutch::Engaged] {
        let _ = rows.push(row(6) - row(8));
    }
    if with_shaft && !m.shaft_turning() && m != Mode::Free {
        let _ = rows.push(shaft);
    }
    rows
}

/// Plastic impact (SPEC 3): `u⁺ = u - M⁻¹Jᵀ(J M⁻¹ Jᵀ)⁻¹ J u`, and the kinetic energy
/// lost. `None` if the constraints are rank-deficient. Without shaft inertia the third
/// coordinate is unused (`M` has 1 there and `J`'s third column is 0).
pub(super) fn project<T: Real>(
    mass: &SMatrix<T, 3, 3>,
    u: &SVector<T, 3>,
    rows: &[SVector<T, 3>],
) -> Option<(SVector<T, 3>, T)> {
    let minv = crate::linalg::inverse3(mass)?;
    let n = rows.len();
    // At most the three coordinates' worth of independent constraints.
    if n > 3 {
        return None;
    }
    if n == 0 {
        return Some((*u, T::zero()));
    }
    let mut gram = SMatrix::<T, 3, 3>::identity();
    let mut ju = SVector::<T, 3>::zeros();
    for (i, ri) in rows.iter().enumerate() {
        ju[i] = ri.dot(u);
        for (j, rj) in rows.iter().enumerate() {
            gram[(i, j)] = (ri.transpose() * minv * rj)[(0, 0)];
        }
    }
    // Rank: each pivot relative to its row's own weight.
    let l = crate::linalg::cholesky(&gram)?;
    for i in 0..n {
        if !(l[(i, i)] * l[(i, i)] > T::c(1e-10) * gram[(i, i)].max(T::EPS)) {
            return None;
        }
    }
    let lambda = crate::linalg::cholesky_solve(&l, &ju);
    let mut jt_l = SVector::<T, 3>::zeros();
    for (i, ri) in rows.iter().enumerate() {
        jt_l += ri * lambda[i];
    }
    let u_plus = u - minv * jt_l;
    let half = T::c(0.5);
    let loss = half * (u.transpose() * mass * u)[(0, 0)]
        - half * (u_plus.transpose() * mass * u_plus)[(0, 0)];
    Some((u_plus, loss.max(T::zero())))
}

pub(super) fn rows_mismatch<T: Real>(rows: &[SVector<T, 3>], u: &SVector<T, 3>) -> T {
    rows.iter().fold(T::zero(), |m, r| m.max(r.dot(u).abs()))
}

#[cfg(test)]
mod tests {
    use super::super::super::mode::Mode;
    use super::{constraint_rows, project, rows_mismatch};
    use nalgebra::{SMatrix, SVector};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
    }

    /// Two bodies on a line (masses m1, m2, speeds va, vb; the third coordinate unused:
    /// mass 1, no constraint on it) made to move together: the common speed conserves
    /// momentum and the loss is ½·m1·m2/(m1+m2)·Δv² (the textbook plastic impact).
    #[test]
    fn a_plastic_impact_of_two_bodies_loses_the_reduced_mass_energy() {
        for (m1, m2, va, vb) in [
            (1.0, 1.0, 2.0, -1.0),
            (3.0, 0.5, 0.2, 4.0),
            (10.0, 0.01, -7.0, 3.0),
        ] {
            let mass = SMatrix::<f64, 3, 3>::from_diagonal(&SVector::<f64, 3>::new(m1, m2, 1.0));
            let u = SVector::<f64, 3>::new(va, vb, 0.0);
            let rows = [SVector::<f64, 3>::new(1.0, -1.0, 0.0)];
            let (up, loss) = project(&mass, &u, &rows).unwrap();
            let common = (m1 * va + m2 * vb) / (m1 + m2);
            assert!(
                close(up[0], common, 1e-14) && close(up[1], common, 1e-14),
                "{up}"
            );
            assert!(close(m1 * up[0] + m2 * up[1], m1 * va + m2 * vb, 1e-14));
            let want = 0.5 * m1 * m2 / (m1 + m2) * (va - vb) * (va - vb);
            assert!(close(loss, want, 1e-13), "{loss} vs {want}");
            assert!(rows_mismatch(&rows, &up) <= 1e-14 * va.abs().max(vb.abs()));
            assert!(close(rows_mismatch(&rows, &u), (va - vb).abs(), 1e-15));
        }
    }

    /// The rotational analogue on a coupled mass matrix: a shaft of inertia J_s
    /// engaging a lever whose speed is `r·q̇` on a 2-DOF mechanism with mass matrix M.
    /// The impact conserves the generalized momentum but along the constraint
    /// (M(u⁺ - u) = λ·row), meets it (row·u⁺ = 0) and loses
    /// ½·(row·u)²/(rowᵀ M⁻¹ row), the energy of the relative speed on the reduced
    /// inertia.
    #[test]
    fn an_engagement_with_the_shaft_conserves_momentum_off_the_constraint() {
        let (a, b, js) = (0.7, -1.3, 0.25);
        let mass = SMatrix::<f64, 3, 3>::new(2.0, 0.3, 0.0, 0.3, 0.8, 0.0, 0.0, 0.0, js);
        let u = SVector::<f64, 3>::new(1.5, -0.4, 3.0);
        let lever = SVector::<f64, 3>::new(a, b, 0.0);
        let rows = constraint_rows(Mode::A6, true, |_| lever);
        assert_eq!(rows.len(), 1);
        let row = rows[0];
        let (up, loss) = project(&mass, &u, &rows).unwrap();
        assert!(
            row.dot(&up).abs() <= 1e-14,
            "the lever turns with the shaft"
        );
        // The impulse is along the constraint: M(u⁺ - u) ∥ row.
        let imp = mass * (up - u);
        let lambda = imp.dot(&row) / row.dot(&row);
        assert!(
            (imp - row * lambda).norm() <= 1e-14 * imp.norm(),
            "{imp} vs {row}"
        );
        let minv = mass.try_inverse().unwrap();
        let want = 0.5 * row.dot(&u).powi(2) / (row.transpose() * minv * row)[(0, 0)];
        assert!(close(loss, want, 1e-13), "{loss} vs {want}");
        // And the kinetic energies before and after agree with the loss.
        let ke = |v: &SVector<f64, 3>| 0.5 * (v.transpose() * mass * v)[(0, 0)];
        assert!(close(ke(&u) - ke(&up), loss, 1e-13));
    }

    /// No constraint: nothing moves, nothing is lost; two copies of one constraint
    /// (rank 1 of 2) are refused.
    #[test]
    fn no_constraint_changes_nothing_and_dependent_ones_are_refused() {
        let mass = SMatrix::<f64, 3, 3>::identity();
        let u = SVector::<f64, 3>::new(1.0, 2.0, 3.0);
        assert_eq!(project(&mass, &u, &[]), Some((u, 0.0)));
        let r = SVector::<f64, 3>::new(1.0, -2.0, 0.0);
        assert!(project(&mass, &u, &[r, r]).is_none());
        assert!(project(&mass, &u, &[r, r * 3.0]).is_none());
    }

    /// Each mode's rows, by hand from SPEC 3: a locked lever stands still (its row), an
    /// engaged one turns with the shaft (its row minus the shaft's unit row; without
    /// shaft inertia the two engaged levers turn together), a held shaft stands still.
    #[test]
    fn the_constraint_rows_of_each_mode() {
        let r6 = SVector::<f64, 3>::new(0.3, -0.9, 0.0);
        let r8 = SVector::<f64, 3>::new(-1.1, 0.4, 0.0);
        let e3 = SVector::<f64, 3>::new(0.0, 0.0, 1.0);
        let row = |lever: usize| if lever == 6 { r6 } else { r8 };
        let rows = |m: Mode, shaft: bool| constraint_rows(m, shaft, row).to_vec();
        for shaft in [false, true] {
            assert!(rows(Mode::Free, shaft).is_empty());
        }
        assert!(rows(Mode::I0, false).is_empty());
        assert_eq!(rows(Mode::I0, true), [e3]);
        assert_eq!(rows(Mode::I6, false), [r6]);
        assert_eq!(rows(Mode::I6, true), [r6, e3]);
        assert_eq!(rows(Mode::I8, true), [r8, e3]);
        assert_eq!(rows(Mode::Jam, false), [r6, r8]);
        assert_eq!(rows(Mode::Jam, true), [r6, r8, e3]);
        assert!(rows(Mode::A6, false).is_empty());
        assert_eq!(rows(Mode::A6, true), [r6 - e3]);
        assert_eq!(rows(Mode::A8, true), [r8 - e3]);
        assert_eq!(rows(Mode::A68, false), [r6 - r8]);
        assert_eq!(rows(Mode::A68, true), [r6 - e3, r8 - e3]);
    }
}
