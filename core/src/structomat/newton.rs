//! Newton-Raphson on a group's loop-closure equations (thesis section 3.2): the
//! position solver of the triad, and a second method for every dyad (its tests check
//! the closed forms against it).
//!
//! Bounded by [`NEWTON_MAX_ITER`]; warm-started from
//! `gd.x`, the previous configuration, which keeps the assembly branch as long as the
//! motion does not cross a singular position (checked by the sign of det W).

use super::chain::{eval_terms, jacobian, position_from_terms, residual};
use super::{Base, Group, GroupData, Term};
use crate::config::NEWTON_MAX_ITER;
use crate::error::GroupFault;
use crate::model::Model;
use crate::scalar::Real;
use crate::workspace::BodyState;

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

/// Solves `f(x) = 0` from `gd.x`, then caches the terms, factors W and places the links.
/// Returns det W.
pub(crate) fn solve<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    let n = g.n_vars as usize;
    let tol = model.newton_tol();
    let mut res = T::zero();
    let angles = angle_mask(g);
    for it in 0..NEWTON_MAX_ITER {
        for (k, (x, cs)) in gd.x.iter().zip(gd.trig.iter_mut()).enumerate().take(n) {
            if angles & (1 << k) != 0 {
                let (s, c) = x.sin_cos();
                *cs = nalgebra::Vector2::new(c, s);
            }
        }
        eval_terms(g, gd, bodies, q);
        let f = residual(g, gd, model, bodies);
        res = f.amax();
        if !res.finite() {
            return Err(GroupFault::NonFiniteInput);
        }
        if res <= tol {
            gd.iterations = it;
            // The terms are cached at this `x` (just evaluated for the residual).
            return position_from_terms(g, gd, model, bodies, q);
        }
        let w = jacobian(g, gd);
        let Some((inv, _)) = crate::linalg::invert(w, n) else {
            return Err(GroupFault::Singular { conditioning: 0.0 });
        };
        let dx = inv * f;
        for (k, x) in gd.x.iter_mut().enumerate().take(n) {
            *x -= dx[k];
        }
    }
    gd.iterations = NEWTON_MAX_ITER;
    Err(GroupFault::NewtonDidNotConverge {
        iterations: NEWTON_MAX_ITER,
        residual: res.to_f64(),
    })
}
