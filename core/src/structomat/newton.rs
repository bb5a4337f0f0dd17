//! Newton-Raphson on a group's loop-closure equations (thesis section 3.2): the
//! position solver of the triad, and a second method for every dyad (its tests check
//! the closed forms against it).
//!
//! Bounded by [`NEWTON_MAX_ITER`]; warm-started from
//! `gd.x`, the previous configuration, which keeps the assembly branch as long as the
//! motion does not cross a singular position (checked by the sign of det W). The warm
//! start is first moved along the group's transmission functions (`predict`): from
//! `x(q₀)` to `x(q₀) + C (q - q₀)`, whose error is second order in `q - q₀`.

use super::chain::{chain_gaps, eval_terms, jacobian, position_from_terms, residual};
use super::{Base, Group, GroupData, Term};
use crate::config::{MAX_DOF, MAX_GROUP_VARS, NEWTON_MAX_ITER};
use crate::error::GroupFault;
use crate::model::Model;
use crate::scalar::Real;
use crate::workspace::BodyState;
use nalgebra::SVector;

/// Bit k set when unknown k is an angle (it turns a term), else a slide length.
fn angle_mask<T: Real>(g: &Group<T>) -> u8 {
    let mut m = 0u8;
    for t in g.chains.iter().flat_map(|c| c.terms.iter()) {
        let (Term::Arm { angle, .. } | Term::Slide { angle, .. }) = t;
        if let Base::Var(k) = angle.base {
            m |= 1 << (k & 7);
        }
    }
    m
}

/// First-order predictor of the warm start: `x += C (q - q_C)` with `C = ∂x/∂q` as the
/// last evaluation recorded it at `(q_C, x_C)` (`gd.dx_dq_at`), when `gd.x` is still
/// that `x_C` (a caller that restored older unknowns, or a fresh assembly, keeps its
/// warm start as it is). Returns whether it moved the start: not at `q = q_C`, where
/// the start is the solution recorded there (so a re-evaluation of a state, as after a
/// refused step, reproduces its bits).
fn predict<T: Real>(gd: &mut GroupData<T>, n: usize, q: &[T]) -> bool {
    let (q_c, x_c) = &gd.dx_dq_at;
    if gd.x != *x_c {
        return false;
    }
    let mut dq = [T::zero(); MAX_DOF];
    for (d, (qc, qj)) in dq.iter_mut().zip(q_c.iter().zip(q.iter())) {
        *d = *qj - *qc;
    }
    if dq.iter().all(|d| *d == T::zero()) {
        return false;
    }
    for (k, x) in gd.x.iter_mut().enumerate().take(n) {
        for (j, d) in dq.iter().enumerate() {
            *x += gd.dx_dq.get((k, j)).copied().unwrap_or(T::zero()) * *d;
        }
    }
    true
}

/// Solves `f(x) = 0` from `gd.x`, then caches the terms, factors W and places the links.
/// Returns det W.
pub(crate) fn solve<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    // n is even (two rows per closing chain): each size with its own fixed matrices.
    match g.n_vars {
        2 => solve_n::<T, 2>(g, gd, model, bodies, q),
        4 => solve_n::<T, 4>(g, gd, model, bodies, q),
        _ => solve_n::<T, MAX_GROUP_VARS>(g, gd, model, bodies, q),
    }
}

/// [`solve`] for `n = N` unknowns (`n = 0` solves nothing and only places).
fn solve_n<T: Real, const N: usize>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    let n = (g.n_vars as usize).min(N);
    let tol = model.newton_tol();
    let mut res = T::zero();
    let angles = angle_mask(g);
    // A predicted start within the tolerance still takes one step: the solution keeps
    // the accuracy of a converged Newton step (far below the tolerance), not the
    // predictor's.
    let predicted = predict(gd, n, q);
    // The chains' ends are known points: placed before the group, fixed while it solves.
    let gaps = chain_gaps(g, model, bodies);
    for it in 0..NEWTON_MAX_ITER {
        for (k, (x, cs)) in gd.x.iter().zip(gd.trig.iter_mut()).enumerate().take(n) {
            if angles & (1 << k) != 0 {
                let (s, c) = x.sin_cos();
                *cs = nalgebra::Vector2::new(c, s);
            }
        }
        eval_terms(g, gd, bodies, q);
        let f = residual(g, gd, &gaps);
        res = f.amax();
        if !res.finite() {
            return Err(GroupFault::NonFiniteInput);
        }
        if res <= tol && (it > 0 || !predicted) {
            gd.iterations = it;
            // The terms are cached at this `x` (just evaluated for the residual).
            return position_from_terms(g, gd, model, bodies, q);
        }
        // The step solves W dx = f (no inverse: `factor` inverts W once, at the
        // solution).
        let w = jacobian::<T, N>(g, gd);
        let f_n = SVector::<T, N>::from_fn(|r, _| f.get(r).copied().unwrap_or(T::zero()));
        let Some(dx) = crate::linalg::solve(w, f_n) else {
            return Err(GroupFault::Singular { conditioning: 0.0 });
        };
        for (x, d) in gd.x.iter_mut().zip(dx.iter()).take(n) {
            *x -= *d;
        }
    }
    gd.iterations = NEWTON_MAX_ITER;
    Err(GroupFault::NewtonDidNotConverge {
        iterations: NEWTON_MAX_ITER,
        residual: res.to_f64(),
    })
}
