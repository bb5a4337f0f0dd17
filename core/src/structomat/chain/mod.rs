//! The kinematics every group shares: evaluating its vector chains, its Jacobian `W`,
//! placing its links, and the linear velocity and acceleration passes (SPEC 1:
//! `W ẋ = L`, `W ẍ = L̇ - Ẇ ẋ`).
//!
//! Term derivatives, with `w = R(θ)v` for an arm and `u = R(θ)d` for a slide:
//! - arm: velocity `θ̇ J w`, acceleration `θ̈ J w - θ̇² w`;
//! - slide: velocity `ṡ u + s θ̇ J u`, acceleration `s̈ u + 2 ṡ θ̇ J u + s θ̈ J u - s θ̇² u`.
//!
//! The right-hand sides are the same derivatives evaluated with the group's unknown
//! rates (or accelerations) set to zero, so no term is written twice.

use super::{Angle, Base, Chain, Group, GroupKind, Length, PointRef, Term};
use crate::capacity::Capacity;
use crate::config::{MAX_CHAINS, MAX_DOF, MAX_GROUP_VARS, MAX_TERMS};
use crate::error::GroupFault;
use crate::model::Model;
use crate::scalar::{perp, rotate_cs, Real, Vec2};
use crate::workspace::BodyState;
use nalgebra::{SMatrix, SVector};

mod matrix;
mod passes;

use matrix::factor_w;
pub(crate) use matrix::{factor, jacobian, Arms};
pub(crate) use passes::{acceleration_pass, velocity_pass};

/// The group's stacked loop-closure residuals (2 rows per closing chain).
pub type GroupVector<T> = SVector<T, MAX_GROUP_VARS>;

const _: () = assert!(
    2 * MAX_CHAINS <= MAX_GROUP_VARS,
    "every closing chain has 2 rows"
);

/// A term evaluated at the current configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TermCache<T: Real> {
    /// `R(θ)v` for an arm (m), `R(θ)d` for a slide (unit).
    pub w: Vec2<T>,
    /// Slide length, m (0 for an arm).
    pub s: T,
}

/// The state and scratch of one group in the workspace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupData<T: Real> {
    /// Unknowns (rad or m). Kept between steps: the warm start of Newton-Raphson.
    pub x: [T; MAX_GROUP_VARS],
    /// Their rates.
    pub xd: [T; MAX_GROUP_VARS],
    /// Their accelerations.
    pub xdd: [T; MAX_GROUP_VARS],
    /// `(cos, sin)` of each angle unknown at `x`: set by the closed forms from the
    /// vectors they construct, or by Newton from `x` or turned along with its
    /// corrections (slides: unused).
    pub trig: [Vec2<T>; MAX_GROUP_VARS],
    /// The unknowns `trig` belongs to (Newton's): Newton starts from `trig` as it is
    /// for an unknown still at exactly this value (a re-evaluation of a state then
    /// reproduces its bits), and takes the sine and cosine anew otherwise (a moved
    /// start, unknowns set from outside).
    pub trig_at: [T; MAX_GROUP_VARS],
    /// Assembly branch of a closed form (+1 or -1), chosen at assembly from the guesses.
    pub branch: T,
    /// Sign of det W at assembly (the branch of a Newton group).
    pub det_sign: T,
    /// `W` factored (top-left `n × n` block, rows): a dyad's (`n = 2`) inverse `W⁻¹`;
    /// for a larger group the LU factors of `P W` ([`linalg::lu`](crate::linalg::lu):
    /// `L` below the diagonal, `U` on and above it), `P` in `w_piv`. The linear passes
    /// solve with it; factoring costs `n³/3`, an inverse `n³`.
    pub w_fact: [[T; MAX_GROUP_VARS]; MAX_GROUP_VARS],
    /// The row swaps of the LU factors in `w_fact`, 4 bits a step (the row
    /// swapped with row `k` at step `k` in bits `4k..4k + 4`);
    /// unused for a dyad. (Packed: 4 bytes where an array would take 8, in each of the
    /// workspace's groups.)
    pub w_piv: u32,
    /// |det W| / product of column norms at the last position solve: the sine of the
    /// transmission angle for a dyad; 0 at a dead point.
    pub conditioning: T,
    /// Newton-Raphson iterations used by the last position solve.
    pub iterations: u32,
    /// Terms evaluated at `x`.
    pub cache: [[TermCache<T>; MAX_TERMS]; MAX_CHAINS],
    /// `∂x/∂q` (the thesis's transmission functions C of this group), column j from
    /// the velocity pass with `q̇ = e_j`.
    pub dx_dq: SMatrix<T, MAX_GROUP_VARS, MAX_DOF>,
    /// `ẍ` with `q̈ = 0`: the bias part of the group's accelerations, `∂²x/∂q² [q̇, q̇]`
    /// at the rates of the last full evaluation (Newton's predictor reads it so).
    pub xdd_bias: [T; MAX_GROUP_VARS],
    /// The coordinates and unknowns at which `dx_dq` was last recorded: Newton-Raphson
    /// starts from the prediction `x + C (q - q_C)` plus its second-order term along the
    /// rates (from `xdd_bias`) when its warm start is still that `x`
    /// ([`newton`](super::newton)). Recorded for the groups Newton
    /// solves only ([`GroupKind::solved_by_newton`]): the others never read it.
    pub dx_dq_at: ([T; MAX_DOF], [T; MAX_GROUP_VARS]),
}

impl<T: Real> Default for GroupData<T> {
    fn default() -> Self {
        GroupData {
            x: [T::zero(); MAX_GROUP_VARS],
            xd: [T::zero(); MAX_GROUP_VARS],
            xdd: [T::zero(); MAX_GROUP_VARS],
            trig: [Vec2::new(T::one(), T::zero()); MAX_GROUP_VARS],
            trig_at: [T::zero(); MAX_GROUP_VARS],
            branch: T::one(),
            det_sign: T::zero(),
            w_fact: core::array::from_fn(|r| {
                core::array::from_fn(|c| if r == c { T::one() } else { T::zero() })
            }),
            w_piv: pack_pivots(&core::array::from_fn::<u8, MAX_GROUP_VARS, _>(|k| k as u8)),
            conditioning: T::one(),
            iterations: 0,
            cache: [[TermCache::default(); MAX_TERMS]; MAX_CHAINS],
            dx_dq: SMatrix::zeros(),
            xdd_bias: [T::zero(); MAX_GROUP_VARS],
            dx_dq_at: ([T::zero(); MAX_DOF], [T::zero(); MAX_GROUP_VARS]),
        }
    }
}

const _: () = assert!(
    MAX_GROUP_VARS <= 8,
    "a group's LU pivots are packed 4 bits each in a u32"
);

/// Packs LU row swaps ([`linalg::lu`](crate::linalg::lu)'s `piv`) 4 bits a step: the
/// row swapped with row `k` at step `k` in bits `4k..4k + 4`.
pub(crate) fn pack_pivots<const N: usize>(piv: &[u8; N]) -> u32 {
    piv.iter().enumerate().fold(0, |acc, (k, p)| {
        acc | (u32::from(*p) & 15).checked_shl(4 * k as u32).unwrap_or(0)
    })
}

/// Applies the row swaps [`pack_pivots`] packed to `b` (the first `n` steps).
#[inline]
fn permute<T: Real>(packed: u32, b: &mut [T; MAX_GROUP_VARS], n: usize) {
    let mut p = packed;
    for k in 0..n.min(MAX_GROUP_VARS) {
        let r = (p & 15) as usize;
        p >>= 4;
        if r > k && r < MAX_GROUP_VARS {
            b.swap(k, r);
        }
    }
}

/// Which derivative level an evaluation reads.
#[derive(Clone, Copy)]
enum Level {
    Pos,
    Vel,
    Acc,
}

#[inline]
fn body_field<T: Real>(bodies: &[BodyState<T>], b: u8, level: Level) -> T {
    bodies.get(b as usize).map_or(T::zero(), |s| match level {
        Level::Pos => s.theta,
        Level::Vel => s.omega,
        Level::Acc => s.alpha,
    })
}

#[inline]
fn get<T: Real>(v: &[T], k: u8) -> T {
    v.get(k as usize).copied().unwrap_or(T::zero())
}

/// Value (or rate, or acceleration) of an angle's variable part plus, for `Pos`, its
/// offset.
#[inline]
fn angle_at<T: Real>(a: &Angle<T>, x: &[T], q: &[T], bodies: &[BodyState<T>], level: Level) -> T {
    let base = match a.base {
        Base::Var(k) => get(x, k),
        Base::Coord(j) => get(q, j),
        Base::Body(b) => body_field(bodies, b, level),
    };
    match level {
        Level::Pos => base + a.offset,
        _ => base,
    }
}

/// `(cos, sin)` of an angle at the current configuration: the base's from the group's
/// trig cache (unknowns), from one `sin_cos` (a coordinate) or from the placed body,
/// then turned by the constant offset.
#[inline]
pub(crate) fn angle_cs<T: Real>(
    a: &Angle<T>,
    trig: &[Vec2<T>],
    q: &[T],
    bodies: &[BodyState<T>],
) -> Vec2<T> {
    let base = match a.base {
        Base::Var(k) => trig
            .get(k as usize)
            .copied()
            .unwrap_or(Vec2::new(T::one(), T::zero())),
        Base::Coord(j) => {
            let (s, c) = get(q, j).sincos();
            Vec2::new(c, s)
        }
        Base::Body(b) => bodies
            .get(b as usize)
            .map_or(Vec2::new(T::one(), T::zero()), |s| Vec2::new(s.c, s.s)),
    };
    rotate_cs(base.x, base.y, &a.offset_cs)
}

#[inline]
fn length_at<T: Real>(s: Length, x: &[T], q: &[T]) -> T {
    match s {
        Length::Var(k) => get(x, k),
        Length::Coord(j) => get(q, j),
    }
}

/// World position of a point of a placed body (ground points are world coordinates).
#[inline]
pub(crate) fn point_pos<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    p: PointRef,
) -> Vec2<T> {
    let local = model.point_local(p);
    if p.body == 0 {
        return local;
    }
    bodies
        .get(p.body as usize)
        .map_or(local, |b| b.o + rotate_cs(b.c, b.s, &local))
}

/// World velocity of a point of a placed body, m/s.
#[inline]
pub(crate) fn point_vel<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    p: PointRef,
) -> Vec2<T> {
    if p.body == 0 {
        return Vec2::zeros();
    }
    let local = model.point_local(p);
    bodies.get(p.body as usize).map_or(Vec2::zeros(), |b| {
        b.v + perp(&rotate_cs(b.c, b.s, &local)) * b.omega
    })
}

/// World acceleration of a point of a placed body, m/s².
#[inline]
pub(crate) fn point_acc<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    p: PointRef,
) -> Vec2<T> {
    if p.body == 0 {
        return Vec2::zeros();
    }
    let local = model.point_local(p);
    bodies.get(p.body as usize).map_or(Vec2::zeros(), |b| {
        let r = rotate_cs(b.c, b.s, &local);
        b.a + perp(&r) * b.alpha - r * (b.omega * b.omega)
    })
}

/// Evaluates every term of the group at `gd.x` (angles through `sin_cos`, once each).
pub(crate) fn eval_terms<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    bodies: &[BodyState<T>],
    q: &[T],
) {
    let GroupData { trig, x, cache, .. } = gd;
    for (ch, row) in g.chains.iter().zip(cache.iter_mut()) {
        for (t, c) in ch.terms.iter().zip(row.iter_mut()) {
            *c = match t {
                Term::Arm { angle, v } => {
                    let cs = angle_cs(angle, trig, q, bodies);
                    TermCache {
                        w: rotate_cs(cs.x, cs.y, v),
                        s: T::zero(),
                    }
                }
                Term::Slide { angle, dir, s } => {
                    let cs = angle_cs(angle, trig, q, bodies);
                    TermCache {
                        w: rotate_cs(cs.x, cs.y, dir),
                        s: length_at(*s, x, q),
                    }
                }
            };
        }
    }
}

/// Position term value from its cache.
#[inline]
fn term_pos<T: Real>(t: &Term<T>, c: &TermCache<T>) -> Vec2<T> {
    match t {
        Term::Arm { .. } => c.w,
        Term::Slide { .. } => c.w * c.s,
    }
}

/// Velocity of a term; `xd` are the group's unknown rates (zeros for the known part).
#[inline]
fn term_vel<T: Real>(
    t: &Term<T>,
    c: &TermCache<T>,
    xd: &[T],
    qd: &[T],
    bodies: &[BodyState<T>],
) -> Vec2<T> {
    match t {
        Term::Arm { angle, .. } => perp(&c.w) * angle_at(angle, xd, qd, bodies, Level::Vel),
        Term::Slide { angle, s, .. } => {
            let th_d = angle_at(angle, xd, qd, bodies, Level::Vel);
            c.w * length_at(*s, xd, qd) + perp(&c.w) * (c.s * th_d)
        }
    }
}

/// Acceleration of a term; `xdd` zero gives the bias part.
#[allow(clippy::too_many_arguments)]
#[inline]
fn term_acc<T: Real>(
    t: &Term<T>,
    c: &TermCache<T>,
    xd: &[T],
    xdd: &[T],
    qd: &[T],
    qdd: &[T],
    bodies: &[BodyState<T>],
) -> Vec2<T> {
    match t {
        Term::Arm { angle, .. } => {
            let w = angle_at(angle, xd, qd, bodies, Level::Vel);
            let a = angle_at(angle, xdd, qdd, bodies, Level::Acc);
            perp(&c.w) * a - c.w * (w * w)
        }
        Term::Slide { angle, s, .. } => {
            let w = angle_at(angle, xd, qd, bodies, Level::Vel);
            let a = angle_at(angle, xdd, qdd, bodies, Level::Acc);
            let sd = length_at(*s, xd, qd);
            let sdd = length_at(*s, xdd, qdd);
            let jw = perp(&c.w);
            c.w * (sdd - c.s * w * w) + jw * (T::c(2.0) * sd * w + c.s * a)
        }
    }
}

/// Calls `col(k, ∂term/∂x_k)` for each unknown `x_k` the term depends on: its columns
/// of `W = ∂f/∂x` (an arm: `J w` for its angle; a slide: `s J u` for its angle, `u` for
/// its length).
#[inline]
fn term_columns<T: Real>(t: &Term<T>, c: &TermCache<T>, mut col: impl FnMut(u8, Vec2<T>)) {
    match t {
        Term::Arm { angle, .. } => {
            if let Base::Var(k) = angle.base {
                col(k, perp(&c.w));
            }
        }
        Term::Slide { angle, s, .. } => {
            if let Base::Var(k) = angle.base {
                col(k, perp(&c.w) * c.s);
            }
            if let Length::Var(k) = s {
                col(*k, c.w);
            }
        }
    }
}

/// The part of a term's derivative that the group's unknown derivatives `u` make: its
/// columns of `W` times `u` (the linear passes' `W u`, term by term).
#[inline]
fn term_unknown<T: Real>(t: &Term<T>, c: &TermCache<T>, u: &[T]) -> Vec2<T> {
    let mut d = Vec2::zeros();
    term_columns(t, c, |k, col| d += col * get(u, k));
    d
}

/// `start - end` of every closing chain (m): the known part of its residual, the same
/// for every Newton-Raphson iterate.
pub(crate) fn chain_gaps<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
) -> [Vec2<T>; MAX_CHAINS] {
    let mut gaps = [Vec2::zeros(); MAX_CHAINS];
    for (ch, gap) in g.chains.iter().zip(gaps.iter_mut()) {
        if let Some(end) = ch.end {
            *gap = point_pos(model, bodies, ch.start) - point_pos(model, bodies, end);
        }
    }
    gaps
}

/// Loop-closure residual `start + Σ terms - end` of every closing chain (m), stacked;
/// `gaps` from [`chain_gaps`].
pub(crate) fn residual<T: Real>(
    g: &Group<T>,
    gd: &GroupData<T>,
    gaps: &[Vec2<T>; MAX_CHAINS],
) -> GroupVector<T> {
    let mut f = GroupVector::zeros();
    for (ci, ((ch, row), gap)) in g
        .chains
        .iter()
        .zip(gd.cache.iter())
        .zip(gaps.iter())
        .enumerate()
    {
        if ch.end.is_none() {
            continue;
        }
        let mut r = *gap;
        for (t, c) in ch.terms.iter().zip(row.iter()) {
            r += term_pos(t, c);
        }
        set2(&mut f, ci, r);
    }
    f
}

#[inline]
fn set2<T: Real>(f: &mut GroupVector<T>, ci: usize, r: Vec2<T>) {
    if let Some(e) = f.get_mut(2 * ci) {
        *e = r.x;
    }
    if let Some(e) = f.get_mut(2 * ci + 1) {
        *e = r.y;
    }
}

/// Sets the pose of every link of the group from the cached terms.
pub(crate) fn place<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) {
    // The chains start at known points (of earlier groups): placed once each.
    let mut starts = [Vec2::zeros(); MAX_CHAINS];
    for (ch, s) in g.chains.iter().zip(starts.iter_mut()) {
        *s = point_pos(model, bodies, ch.start);
    }
    for p in g.placements.iter() {
        // The anchor: its chain's start plus the chain's first `prefix` terms, summed in
        // order (the origin for a placement past its chain or past `MAX_TERMS`).
        let c = p.chain as usize;
        let prefix = p.prefix as usize;
        let anchor = match (g.chains.get(c), gd.cache.get(c), starts.get(c)) {
            (Some(ch), Some(row), Some(start)) if prefix <= MAX_TERMS => {
                let mut a = *start;
                for (t, tc) in ch.terms.iter().zip(row.iter()).take(prefix) {
                    a += term_pos(t, tc);
                }
                a
            }
            _ => Vec2::zeros(),
        };
        let theta = angle_at(&p.angle, &gd.x, q, bodies, Level::Pos);
        let cs = angle_cs(&p.angle, &gd.trig, q, bodies);
        if let Some(b) = bodies.get_mut(p.link as usize) {
            place_link(b, theta, cs, anchor, &p.local);
        }
    }
}

/// Places link `b` at angle `theta` (`cs` its cosine and sine) with its point `local`
/// (link frame) at `anchor`: every group's position pass ends so.
#[inline]
pub(crate) fn place_link<T: Real>(
    b: &mut BodyState<T>,
    theta: T,
    cs: Vec2<T>,
    anchor: Vec2<T>,
    local: &Vec2<T>,
) {
    b.theta = theta;
    (b.c, b.s) = (cs.x, cs.y);
    b.o = anchor - rotate_cs(cs.x, cs.y, local);
}

/// Sets link `b`'s angular speed `omega` and its frame origin's velocity from the
/// velocity `anchor` of its point `local` (placed by [`place_link`]):
/// `v_o = v_anchor - ω J r`, `r = R(θ) local`.
#[inline]
pub(crate) fn link_velocity<T: Real>(
    b: &mut BodyState<T>,
    anchor: Vec2<T>,
    omega: T,
    local: &Vec2<T>,
) {
    let r = rotate_cs(b.c, b.s, local);
    b.omega = omega;
    b.v = anchor - perp(&r) * omega;
}

/// Sets link `b`'s angular acceleration `alpha` and its frame origin's acceleration
/// from the acceleration `anchor` of its point `local` (after [`link_velocity`]):
/// `a_o = a_anchor - α J r + ω² r`.
#[inline]
pub(crate) fn link_acceleration<T: Real>(
    b: &mut BodyState<T>,
    anchor: Vec2<T>,
    alpha: T,
    local: &Vec2<T>,
) {
    let r = rotate_cs(b.c, b.s, local);
    b.alpha = alpha;
    b.a = anchor - perp(&r) * alpha + r * (b.omega * b.omega);
}

/// With `gd.x` solved: caches the terms, factors `W` and places the links.
pub(crate) fn position_from_x<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    eval_terms(g, gd, bodies, q);
    position_from_terms(g, gd, model, bodies, q)
}

/// [`position_from_x`] when the terms are already cached at `gd.x` (Newton-Raphson's
/// converged iterate: its residual check evaluated them there).
pub(crate) fn position_from_terms<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    let det = factor(g, gd, model.singular_tol())?;
    place(g, gd, model, bodies, q);
    Ok(det)
}

/// [`position_from_terms`] with `W` at the cached terms already built (`w`, by
/// [`Arms::eval`]; `N` the size [`factor`] picks for the group's `n`).
pub(crate) fn position_from_jacobian<T: Real, const N: usize, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
    w: &[[T; N]; N],
) -> Result<T, GroupFault> {
    let det = factor_w(w, gd, model.singular_tol())?;
    place(g, gd, model, bodies, q);
    Ok(det)
}

/// The closing chain of a dyad and its end pole (the closed forms' common start).
pub(crate) fn closing_chain<T: Real>(g: &Group<T>) -> Result<(&Chain<T>, PointRef), GroupFault> {
    let ch = g.chains.first().ok_or(GroupFault::NonFiniteInput)?;
    let end = ch.end.ok_or(GroupFault::NonFiniteInput)?;
    Ok((ch, end))
}
