//! Newton-Raphson on a group's loop-closure equations (thesis section 3.2): the
//! position solver of the triad, and a second method for every dyad (its tests check
//! the closed forms against it).
//!
//! Bounded by [`NEWTON_MAX_ITER`]; warm-started from
//! `gd.x`, the previous configuration, which keeps the assembly branch as long as the
//! motion does not cross a singular position (checked by the sign of det W). The warm
//! start is first moved along the group's transmission functions (`predict`): from
//! `x(q₀)` to `x(q₀) + C (q - q₀)` plus the second-order term along the rates of that
//! evaluation, whose error is third order in `q - q₀`.

use super::chain::{
    chain_gaps, eval_terms, jacobian, position_from_jacobian, position_from_terms, residual, Arms,
};
use super::{Base, Group, GroupData, GroupKind, Term};
use crate::capacity::Capacity;
use crate::config::{MAX_DOF, MAX_GROUP_VARS, NEWTON_MAX_ITER};
use crate::error::GroupFault;
use crate::model::Model;
use crate::scalar::{Real, Vec2};
use crate::workspace::BodyState;

/// Bit k set when unknown k is an angle (it turns a term), else a slide length.
fn angle_mask<T: Real>(g: &Group<T>) -> u8 {
    // The triad's and a general Assur group's unknowns are all link angles (their
    // builders make arms only, unknown k turning its link's): no scan of the terms.
    if matches!(g.kind, GroupKind::Triad | GroupKind::Assur) {
        return u8::try_from((1u16 << g.n_vars.min(8)) - 1).unwrap_or(u8::MAX);
    }
    let mut m = 0u8;
    for t in g.chains.iter().flat_map(|c| c.terms.iter()) {
        let (Term::Arm { angle, .. } | Term::Slide { angle, .. }) = t;
        if let Base::Var(k) = angle.base {
            m |= 1 << (k & 7);
        }
    }
    m
}

/// Predictor of the warm start, to second order: `x += C dq + ½ s² ẍ_b` with
/// `dq = q - q_C`, `C = ∂x/∂q` as the last evaluation recorded it at `(q_C, x_C)`
/// (`gd.dx_dq_at`), `ẍ_b = ∂²x/∂q² [q̇_C, q̇_C]` its bias accelerations (`gd.xdd_bias`,
/// `ẍ` at `q̈ = 0`) and `q̇_C = qd` its rates, and `s = (dq · q̇_C) / (q̇_C · q̇_C)`: the
/// Taylor series of `x(q)` to second order along `q̇_C`. With one degree of freedom
/// that is the whole second-order term (`½ dq² ∂²x/∂q²`); with more, it is the
/// term along the trajectory, where a step's stages move (`dq = q̇_C h + O(h²)`).
/// The error is then third order, and the one Newton step a predicted start takes
/// converges (from the first-order start, about one solve in seven of S2's A68/crank
/// steps took a second). Without usable rates (zero, not finite, none given) or bias, the predictor is
/// first order (`x += C dq`). After a velocities-only evaluation
/// ([`transmission::evaluate_velocities`](crate::transmission::evaluate_velocities))
/// the bias is that of the last full evaluation, nearby on the same trajectory: an
/// estimate, which costs at most a Newton step.
///
/// It moves the start only when `gd.x` is still that `x_C` (a caller that restored
/// older unknowns, or a fresh assembly, keeps its warm start as it is). Returns
/// whether it moved the start: not at `q = q_C`, where the start is the solution
/// recorded there (so a re-evaluation of a state, as after a refused step, reproduces
/// its bits).
fn predict<T: Real>(gd: &mut GroupData<T>, n: usize, q: &[T], qd: &[T]) -> bool {
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
    // s is the time (s) the rates take to cover dq's part along them; ½ s² ẍ_b is in
    // x's units.
    let (mut along, mut norm2) = (T::zero(), T::zero());
    for (d, r) in dq.iter().zip(qd.iter()) {
        along += *d * *r;
        norm2 += *r * *r;
    }
    let s = along / norm2;
    let mut half_s2 = T::c(0.5) * s * s;
    let bias_ok = gd.xdd_bias.iter().take(n).all(|b| (*b * half_s2).finite());
    if !(norm2 > T::zero() && half_s2.finite() && bias_ok) {
        half_s2 = T::zero();
    }
    for (k, (x, b)) in gd.x.iter_mut().zip(gd.xdd_bias.iter()).enumerate().take(n) {
        for (j, d) in dq.iter().enumerate() {
            *x += gd.dx_dq.get((k, j)).copied().unwrap_or(T::zero()) * *d;
        }
        *x += half_s2 * *b;
    }
    true
}

/// `(cos, sin)` of `x = x₀ - d` from `cs = (cos x₀, sin x₀)`: turned by `-d` with the
/// Taylor series of `cos d` and `sin d` when `|d| ≤ 2⁻⁵` (the first term left out,
/// `d⁸/8!` or `d⁹/9!`, is under 1e-17 of the result there: the turn is exact to
/// rounding, a few ulps), else from `x` by `sin_cos`. A converged solve's last
/// correction is ~1e-8 rad: its sines and cosines cost a few multiplications instead
/// of a `sin_cos` per angle (~70 instructions each in f64).
#[inline]
fn turn<T: Real>(cs: Vec2<T>, x: T, d: T) -> Vec2<T> {
    if !(d.abs() <= T::c(0.03125)) {
        let (s, c) = x.sincos();
        return Vec2::new(c, s);
    }
    let d2 = d * d;
    // cos d = 1 - d²/2 + d⁴/24 - d⁶/720, sin d = d (1 - d²/6 + d⁴/120 - d⁶/5040).
    let cd = T::one() - d2 * (T::c(0.5) - d2 * (T::c(1.0 / 24.0) - d2 * T::c(1.0 / 720.0)));
    let sd = d
        * (T::one() - d2 * (T::c(1.0 / 6.0) - d2 * (T::c(1.0 / 120.0) - d2 * T::c(1.0 / 5040.0))));
    // cos(x₀ - d) = cos x₀ cos d + sin x₀ sin d, sin(x₀ - d) = sin x₀ cos d - cos x₀ sin d.
    Vec2::new(cs.x * cd + cs.y * sd, cs.y * cd - cs.x * sd)
}

/// Solves `f(x) = 0` from `gd.x`, then caches the terms, factors W and places the links.
/// `qd` are the rates of the last evaluation (the predictor's, see `predict`; empty for
/// none). Returns det W.
pub(crate) fn solve<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
    qd: &[T],
) -> Result<T, GroupFault> {
    // n is even (two rows per closing chain): each size with its own fixed matrices.
    match g.n_vars {
        2 => solve_n::<T, 2, C>(g, gd, model, bodies, q, qd),
        4 => solve_n::<T, 4, C>(g, gd, model, bodies, q, qd),
        _ => solve_n::<T, MAX_GROUP_VARS, C>(g, gd, model, bodies, q, qd),
    }
}

/// [`solve`] for `n = N` unknowns (`n = 0` solves nothing and only places).
fn solve_n<T: Real, const N: usize, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
    qd: &[T],
) -> Result<T, GroupFault> {
    let n = (g.n_vars as usize).min(N);
    let tol = model.newton_tol();
    let mut res = T::zero();
    let angles = angle_mask(g);
    // A predicted start within the tolerance still takes one step: the solution keeps
    // the accuracy of a converged Newton step (far below the tolerance), not the
    // predictor's.
    let predicted = predict(gd, n, q, qd);
    // The chains' ends are known points: placed before the group, fixed while it solves.
    let gaps = chain_gaps(g, model, bodies);
    // The cosines and sines of the start: those of the last solve if it is still at
    // its unknowns (`trig_at`; a re-evaluation of a state then reproduces its bits),
    // else taken anew. Each Newton correction turns them (`turn`).
    for (k, ((x, cs), at)) in
        gd.x.iter()
            .zip(gd.trig.iter_mut())
            .zip(gd.trig_at.iter_mut())
            .enumerate()
            .take(n)
    {
        if angles & (1 << k) != 0 && (predicted || *at != *x) {
            let (s, c) = x.sincos();
            *cs = Vec2::new(c, s);
            *at = *x;
        }
    }
    // An all-arm group (the triad, a general Assur group) evaluates its terms, its
    // residual and W in one pass; W at the converged iterate is then the one factored.
    let arms = Arms::of(g);
    let mut w = [[T::zero(); N]; N];
    for it in 0..NEWTON_MAX_ITER {
        let f = match &arms {
            Some(a) => a.eval(gd, &gaps, &mut w),
            None => {
                eval_terms(g, gd, bodies, q);
                residual(g, gd, &gaps)
            }
        };
        res = f.amax();
        if !res.finite() {
            return Err(GroupFault::NonFiniteInput);
        }
        if res <= tol && (it > 0 || !predicted) {
            gd.iterations = it;
            // The terms are cached at this `x` (just evaluated for the residual).
            return match arms {
                Some(_) => position_from_jacobian(g, gd, model, bodies, q, &w),
                None => position_from_terms(g, gd, model, bodies, q),
            };
        }
        // The step solves W dx = f by elimination (`factor` factors W once more, at
        // the solution, for the linear passes).
        if arms.is_none() {
            jacobian(g, gd, &mut w);
        }
        let mut dx = [T::zero(); N];
        for (d, v) in dx.iter_mut().zip(f.iter()) {
            *d = *v;
        }
        let mut piv = [0u8; N];
        if crate::linalg::lu(&mut w, &mut piv).is_none() {
            return Err(GroupFault::Singular { conditioning: 0.0 });
        }
        crate::linalg::lu_solve::<T, N, N>(&w, &piv, &mut dx);
        for (k, (((x, cs), at), d)) in
            gd.x.iter_mut()
                .zip(gd.trig.iter_mut())
                .zip(gd.trig_at.iter_mut())
                .zip(dx.iter())
                .enumerate()
                .take(n)
        {
            *x -= *d;
            if angles & (1 << k) != 0 {
                *cs = turn(*cs, *x, *d);
                *at = *x;
            }
        }
    }
    gd.iterations = NEWTON_MAX_ITER;
    Err(GroupFault::NewtonDidNotConverge {
        iterations: NEWTON_MAX_ITER,
        residual: res.to_f64(),
    })
}
