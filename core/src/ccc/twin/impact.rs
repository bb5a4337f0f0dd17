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
    let minv = mass.try_inverse()?;
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
    let chol = nalgebra::Cholesky::new(gram)?;
    let l = chol.l();
    for i in 0..n {
        if !(l[(i, i)] * l[(i, i)] > T::c(1e-10) * gram[(i, i)].max(T::EPS)) {
            return None;
        }
    }
    let lambda = chol.solve(&ju);
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
