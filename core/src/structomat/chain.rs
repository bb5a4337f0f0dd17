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

/// Sets `w` to `N × N` zeros with the identity past the top-left `n × n` block: the
/// padding of a group's `W` (whose live block the caller then fills).
#[inline]
fn zero_padded<T: Real, const N: usize>(w: &mut [[T; N]; N], n: usize) {
    for (k, row) in w.iter_mut().enumerate() {
        for (c, e) in row.iter_mut().enumerate() {
            *e = if k >= n && c == k {
                T::one()
            } else {
                T::zero()
            };
        }
    }
}

/// The Jacobian `W = ∂f/∂x` from the cached terms into `w`, as `N × N` rows: the
/// top-left `n × n` block, identity padding past it (`N = 2` for a dyad, 4 for the
/// triad, [`MAX_GROUP_VARS`] for the larger groups).
#[inline]
pub(crate) fn jacobian<T: Real, const N: usize>(
    g: &Group<T>,
    gd: &GroupData<T>,
    w: &mut [[T; N]; N],
) {
    zero_padded(w, g.n_vars as usize);
    for (ci, (ch, row)) in g.chains.iter().zip(gd.cache.iter()).enumerate() {
        if ch.end.is_none() {
            continue;
        }
        let Some([wx, wy]) = w.get_mut(2 * ci..2 * ci + 2) else {
            continue;
        };
        for (t, c) in ch.terms.iter().zip(row.iter()) {
            term_columns(t, c, |k, col| {
                if let Some(e) = wx.get_mut(k as usize) {
                    *e += col.x;
                }
                if let Some(e) = wy.get_mut(k as usize) {
                    *e += col.y;
                }
            });
        }
    }
}

/// The terms of a group whose chains all close and whose terms are all arms turned
/// by one unknown each, without offset (the triad's and a general Assur group's, as
/// their builders make them): each term's unknown `k` and link vector `v`, read from
/// the group once per solve. Its evaluation ([`Arms::eval`]) is [`eval_terms`],
/// [`residual`] and [`jacobian`] in one pass without their per-term matches, to the
/// same bits (an arm's value is `R(θ_k) v`, its column of `W` is `J R(θ_k) v`).
pub(crate) struct Arms<T: Real> {
    /// Unknown `n` of the group (2 per chain).
    n: usize,
    /// Per chain: how many terms.
    len: [u8; MAX_CHAINS],
    /// Per chain and term: the unknown that turns it.
    var: [[u8; MAX_TERMS]; MAX_CHAINS],
    /// Per chain and term: the vector it turns (link frame, m).
    v: [[Vec2<T>; MAX_TERMS]; MAX_CHAINS],
}

impl<T: Real> Arms<T> {
    /// The group's arms, or `None` if a chain is open, a term is a slide, or an angle
    /// is not an unknown alone (the general path then serves it).
    pub(crate) fn of(g: &Group<T>) -> Option<Self> {
        let n = g.n_vars as usize;
        if n == 0 || 2 * g.chains.len() != n {
            return None;
        }
        let mut a = Arms {
            n,
            len: [0; MAX_CHAINS],
            var: [[0; MAX_TERMS]; MAX_CHAINS],
            v: [[Vec2::zeros(); MAX_TERMS]; MAX_CHAINS],
        };
        let unturned = Vec2::new(T::one(), T::zero());
        for (ch, ((len, var), v)) in g
            .chains
            .iter()
            .zip(a.len.iter_mut().zip(a.var.iter_mut()).zip(a.v.iter_mut()))
        {
            ch.end?;
            for (t, (ak, av)) in ch.terms.iter().zip(var.iter_mut().zip(v.iter_mut())) {
                let Term::Arm {
                    angle:
                        Angle {
                            base: Base::Var(k),
                            offset_cs,
                            ..
                        },
                    v: tv,
                } = t
                else {
                    return None;
                };
                if *offset_cs != unturned || *k as usize >= n {
                    return None;
                }
                (*ak, *av) = (*k, *tv);
            }
            *len = ch.terms.len() as u8;
        }
        Some(a)
    }

    /// Evaluates the terms at the unknowns' cosines and sines `gd.trig` into
    /// `gd.cache`, writes `W` into `w` (as [`jacobian`]) and returns the residual (as
    /// [`residual`], `gaps` from [`chain_gaps`]).
    pub(crate) fn eval<const N: usize>(
        &self,
        gd: &mut GroupData<T>,
        gaps: &[Vec2<T>; MAX_CHAINS],
        w: &mut [[T; N]; N],
    ) -> GroupVector<T> {
        zero_padded(w, self.n);
        let mut f = GroupVector::zeros();
        let GroupData { trig, cache, .. } = gd;
        for (ci, ((((len, var), v), gap), row)) in self
            .len
            .iter()
            .zip(self.var.iter())
            .zip(self.v.iter())
            .zip(gaps.iter())
            .zip(cache.iter_mut())
            .enumerate()
            .take(self.n / 2)
        {
            let Some([wx, wy]) = w.get_mut(2 * ci..2 * ci + 2) else {
                continue;
            };
            let mut r = *gap;
            for ((k, v), c) in var
                .iter()
                .zip(v.iter())
                .zip(row.iter_mut())
                .take(*len as usize)
            {
                let k = *k as usize;
                let cs = trig
                    .get(k)
                    .copied()
                    .unwrap_or(Vec2::new(T::one(), T::zero()));
                let t = rotate_cs(cs.x, cs.y, v);
                *c = TermCache { w: t, s: T::zero() };
                r += t;
                let col = perp(&t);
                if let Some(e) = wx.get_mut(k) {
                    *e += col.x;
                }
                if let Some(e) = wy.get_mut(k) {
                    *e += col.y;
                }
            }
            set2(&mut f, ci, r);
        }
        f
    }
}

/// Factors `W` into `gd.w_fact` (a dyad's inverse, a larger group's LU factors) and
/// measures its conditioning; a dead point is an error (and leaves `gd.w_fact` as it
/// was).
pub(crate) fn factor<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    // n is even (two rows per closing chain): each size with its own fixed matrices.
    match g.n_vars {
        0 => {
            gd.conditioning = T::one();
            Ok(T::one())
        }
        2 => factor_n::<T, 2>(g, gd, singular_tol),
        4 => factor_n::<T, 4>(g, gd, singular_tol),
        _ => factor_n::<T, MAX_GROUP_VARS>(g, gd, singular_tol),
    }
}

/// [`factor`] for `n = N` unknowns.
fn factor_n<T: Real, const N: usize>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    let mut w = [[T::zero(); N]; N];
    jacobian(g, gd, &mut w);
    factor_w(&w, gd, singular_tol)
}

/// [`factor`] of a `W` already built (`N` rows, the size [`factor`] picks for the
/// group's `n`).
fn factor_w<T: Real, const N: usize>(
    w: &[[T; N]; N],
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    // The product of W's column norms (identity padding: 1 each), for the conditioning.
    let mut norms = T::one();
    for c in 0..N {
        let mut sq = T::zero();
        for row in w.iter() {
            let v = row.get(c).copied().unwrap_or(T::zero());
            sq += v * v;
        }
        norms *= sq.root();
    }
    // A dyad's 2×2 inverse in closed form; larger groups by LU (n³/3, where an
    // inverse costs n³: W is used for the 2 or 3 solves of the linear passes only).
    let mut fact = *w;
    let mut piv = [0u8; N];
    let det = match (N, w.first(), w.get(1)) {
        (2, Some(r0), Some(r1)) => {
            let e = |r: &[T; N], c: usize| r.get(c).copied().unwrap_or(T::zero());
            let (a, b, c, d) = (e(r0, 0), e(r0, 1), e(r1, 0), e(r1, 1));
            let det = a * d - b * c;
            let id = T::one() / det;
            for (k, v) in [d * id, -b * id, -c * id, a * id].into_iter().enumerate() {
                if let Some(x) = fact.get_mut(k / 2).and_then(|r| r.get_mut(k % 2)) {
                    *x = v;
                }
            }
            det
        }
        // A failed factorisation (a vanishing pivot) is a dead point: det 0.
        // (On the whole N × N matrix: its padding is the identity.)
        _ => crate::linalg::lu(&mut fact, &mut piv).unwrap_or(T::zero()),
    };
    let cond = if norms > T::zero() {
        det.abs() / norms
    } else {
        T::zero()
    };
    gd.conditioning = cond;
    if !(cond > singular_tol) {
        return Err(GroupFault::Singular {
            conditioning: cond.to_f64(),
        });
    }
    for (dst, src) in gd.w_fact.iter_mut().zip(fact.iter()) {
        for (e, v) in dst.iter_mut().zip(src.iter()) {
            *e = *v;
        }
    }
    gd.w_piv = pack_pivots(&piv);
    Ok(det)
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

/// The derivative level of a linear pass (velocity or acceleration), with the
/// coordinates' derivatives: what it reads of the known points, terms and angles, and
/// what it sets on a link. One implementation per level, so the passes are compiled
/// for each without a match per term.
trait PassLevel<T: Real> {
    /// The level's derivative of a known point.
    fn point<C: Capacity<T>>(
        &self,
        model: &Model<T, C>,
        bodies: &[BodyState<T>],
        p: PointRef,
    ) -> Vec2<T>;
    /// A term's derivative with the group's unknown derivatives zero (its known part);
    /// `xd` are the unknowns' rates (used by the acceleration level).
    fn known_term(
        &self,
        t: &Term<T>,
        c: &TermCache<T>,
        xd: &[T],
        bodies: &[BodyState<T>],
    ) -> Vec2<T>;
    /// [`known_term`](PassLevel::known_term) of an arm turned by unknown `k` alone (an
    /// all-arm group's, [`arm_pass`]), `w` its cached `R(θ)v`: the same operations
    /// without the matches.
    fn known_arm(&self, w: &Vec2<T>, k: usize, xd: &[T]) -> Vec2<T>;
    /// A placement angle's derivative, the unknowns' being `u`.
    fn angle(&self, a: &Angle<T>, u: &[T], bodies: &[BodyState<T>]) -> T;
    /// Sets a link's rate (or acceleration) from its anchor point's and its angle's;
    /// `local` is the anchor point in the link's frame.
    fn set_link(&self, b: &mut BodyState<T>, anchor: Vec2<T>, rate: T, local: &Vec2<T>);
    /// Where the unknowns' derivatives go in the group's data.
    fn unknowns<'g>(&self, gd: &'g mut GroupData<T>) -> &'g mut [T; MAX_GROUP_VARS];
}

/// The velocity level at the rates `qd`.
struct Vel<'a, T> {
    qd: &'a [T],
}

impl<T: Real> PassLevel<T> for Vel<'_, T> {
    #[inline]
    fn point<C: Capacity<T>>(
        &self,
        model: &Model<T, C>,
        bodies: &[BodyState<T>],
        p: PointRef,
    ) -> Vec2<T> {
        point_vel(model, bodies, p)
    }
    #[inline]
    fn known_term(
        &self,
        t: &Term<T>,
        c: &TermCache<T>,
        _: &[T],
        bodies: &[BodyState<T>],
    ) -> Vec2<T> {
        term_vel(t, c, &[], self.qd, bodies)
    }
    #[inline]
    fn known_arm(&self, w: &Vec2<T>, _: usize, _: &[T]) -> Vec2<T> {
        // term_vel's arm with the unknown's rate zero.
        perp(w) * T::zero()
    }
    #[inline]
    fn angle(&self, a: &Angle<T>, u: &[T], bodies: &[BodyState<T>]) -> T {
        angle_at(a, u, self.qd, bodies, Level::Vel)
    }
    #[inline]
    fn set_link(&self, b: &mut BodyState<T>, anchor: Vec2<T>, rate: T, local: &Vec2<T>) {
        link_velocity(b, anchor, rate, local);
    }
    #[inline]
    fn unknowns<'g>(&self, gd: &'g mut GroupData<T>) -> &'g mut [T; MAX_GROUP_VARS] {
        &mut gd.xd
    }
}

/// The acceleration level at the rates `qd` and accelerations `qdd`.
struct Acc<'a, T> {
    qd: &'a [T],
    qdd: &'a [T],
}

impl<T: Real> PassLevel<T> for Acc<'_, T> {
    #[inline]
    fn point<C: Capacity<T>>(
        &self,
        model: &Model<T, C>,
        bodies: &[BodyState<T>],
        p: PointRef,
    ) -> Vec2<T> {
        point_acc(model, bodies, p)
    }
    #[inline]
    fn known_term(
        &self,
        t: &Term<T>,
        c: &TermCache<T>,
        xd: &[T],
        bodies: &[BodyState<T>],
    ) -> Vec2<T> {
        term_acc(t, c, xd, &[], self.qd, self.qdd, bodies)
    }
    #[inline]
    fn known_arm(&self, w: &Vec2<T>, k: usize, xd: &[T]) -> Vec2<T> {
        // term_acc's arm with the unknown's acceleration zero.
        let wk = get(xd, k as u8);
        perp(w) * T::zero() - *w * (wk * wk)
    }
    #[inline]
    fn angle(&self, a: &Angle<T>, u: &[T], bodies: &[BodyState<T>]) -> T {
        angle_at(a, u, self.qdd, bodies, Level::Acc)
    }
    #[inline]
    fn set_link(&self, b: &mut BodyState<T>, anchor: Vec2<T>, rate: T, local: &Vec2<T>) {
        link_acceleration(b, anchor, rate, local);
    }
    #[inline]
    fn unknowns<'g>(&self, gd: &'g mut GroupData<T>) -> &'g mut [T; MAX_GROUP_VARS] {
        &mut gd.xdd
    }
}

/// One linear pass: solves `W u = -(the level's derivative of f with u = 0)` for the
/// unknowns' rates (or accelerations) `u` and sets the links' velocities (or
/// accelerations) from the chains' prefix sums. Each term's known part is evaluated
/// once: it makes the right-hand side, and with the term's `W` columns times `u` its
/// whole derivative in the prefix sums.
fn linear_pass<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    level: &impl PassLevel<T>,
) {
    let n = (g.n_vars as usize).min(MAX_GROUP_VARS);
    let mut starts = [Vec2::zeros(); MAX_CHAINS];
    let mut known = [[Vec2::zeros(); MAX_TERMS]; MAX_CHAINS];
    let mut rhs = [T::zero(); MAX_GROUP_VARS];
    for (((ch, row), (start, kn)), f) in g
        .chains
        .iter()
        .zip(gd.cache.iter())
        .zip(starts.iter_mut().zip(known.iter_mut()))
        .zip(rhs.chunks_exact_mut(2))
    {
        *start = level.point(model, bodies, ch.start);
        for ((t, c), k) in ch.terms.iter().zip(row.iter()).zip(kn.iter_mut()) {
            *k = level.known_term(t, c, &gd.xd, bodies);
        }
        let Some(end) = ch.end else { continue };
        let mut r = *start - level.point(model, bodies, end);
        for k in kn.iter().take(ch.terms.len()) {
            r += *k;
        }
        if let [fx, fy] = f {
            *fx = -r.x;
            *fy = -r.y;
        }
    }
    let u = solve_factored(gd, n, &rhs);
    *level.unknowns(gd) = u;
    // Each placement's anchor: its chain's start plus its prefix of whole term
    // derivatives (a dyad's links need 0 and 1 terms: no table of sums).
    for p in g.placements.iter() {
        let c = p.chain as usize;
        let (Some(ch), Some(row), Some(start), Some(kn)) = (
            g.chains.get(c),
            gd.cache.get(c),
            starts.get(c),
            known.get(c),
        ) else {
            continue;
        };
        let mut anchor = *start;
        for ((t, c), k) in ch
            .terms
            .iter()
            .zip(row.iter())
            .zip(kn.iter())
            .take(p.prefix as usize)
        {
            anchor += *k + term_unknown(t, c, &u);
        }
        let rate = level.angle(&p.angle, &u, bodies);
        if let Some(b) = bodies.get_mut(p.link as usize) {
            level.set_link(b, anchor, rate, &p.local);
        }
    }
}

/// `W u = rhs` with W as [`factor`] left it in `gd`, size by size (`n` unknowns): a
/// dyad's inverse times `rhs`, a larger group's LU substitutions (only the top-left
/// `n × n` block is live).
#[inline(always)]
fn solve_factored<T: Real>(
    gd: &GroupData<T>,
    n: usize,
    rhs: &[T; MAX_GROUP_VARS],
) -> [T; MAX_GROUP_VARS] {
    let mut u = [T::zero(); MAX_GROUP_VARS];
    match n {
        0 => {}
        2 => {
            for (ur, row) in u.iter_mut().zip(gd.w_fact.iter()).take(2) {
                let mut acc = T::zero();
                for (m, rc) in row.iter().zip(rhs.iter()).take(2) {
                    acc += *m * *rc;
                }
                *ur = acc;
            }
        }
        4 => {
            u = *rhs;
            permute(gd.w_piv, &mut u, 4);
            crate::linalg::lu_substitute::<T, 4, MAX_GROUP_VARS>(&gd.w_fact, &mut u);
        }
        _ => {
            u = *rhs;
            permute(gd.w_piv, &mut u, MAX_GROUP_VARS);
            crate::linalg::lu_substitute::<T, MAX_GROUP_VARS, MAX_GROUP_VARS>(&gd.w_fact, &mut u);
        }
    }
    u
}

/// [`linear_pass`] of an all-arm group (the triad, a general Assur group: every chain
/// closes, every term is an arm turned by an unknown), to the same bits: each term's
/// known part (`J w θ̇` with the unknown's rate zero, `J w θ̈ - w θ̇²` with its
/// acceleration zero) and unknown part (`J w u_k`) written out, the term and its angle
/// matched once per pass instead of in every loop. Returns `false`, having changed
/// nothing, for a group that is not all arms (the general pass then serves it).
#[inline]
fn arm_pass<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    level: &impl PassLevel<T>,
) -> bool {
    let n = g.n_vars as usize;
    if 2 * g.chains.len() != n {
        return false;
    }
    let mut starts = [Vec2::zeros(); MAX_CHAINS];
    let mut known = [[Vec2::zeros(); MAX_TERMS]; MAX_CHAINS];
    let mut vars = [[0u8; MAX_TERMS]; MAX_CHAINS];
    let mut rhs = [T::zero(); MAX_GROUP_VARS];
    for ((ch, row), (((start, kn), vs), f)) in g.chains.iter().zip(gd.cache.iter()).zip(
        starts
            .iter_mut()
            .zip(known.iter_mut())
            .zip(vars.iter_mut())
            .zip(rhs.chunks_exact_mut(2)),
    ) {
        let Some(end) = ch.end else { return false };
        *start = level.point(model, bodies, ch.start);
        let mut r = *start - level.point(model, bodies, end);
        for (((t, c), kv), v) in ch
            .terms
            .iter()
            .zip(row.iter())
            .zip(kn.iter_mut())
            .zip(vs.iter_mut())
        {
            let Term::Arm {
                angle: Angle {
                    base: Base::Var(k), ..
                },
                ..
            } = t
            else {
                return false;
            };
            *v = *k;
            *kv = level.known_arm(&c.w, *k as usize, &gd.xd);
            r += *kv;
        }
        if let [fx, fy] = f {
            *fx = -r.x;
            *fy = -r.y;
        }
    }
    let u = solve_factored(gd, n, &rhs);
    *level.unknowns(gd) = u;
    for p in g.placements.iter() {
        let ci = p.chain as usize;
        let (Some(ch), Some(row), Some(start), Some(kn), Some(vs)) = (
            g.chains.get(ci),
            gd.cache.get(ci),
            starts.get(ci),
            known.get(ci),
            vars.get(ci),
        ) else {
            continue;
        };
        let mut anchor = *start;
        for ((c, kv), k) in row
            .iter()
            .zip(kn.iter())
            .zip(vs.iter())
            .take((p.prefix as usize).min(ch.terms.len()))
        {
            anchor += *kv + (Vec2::zeros() + perp(&c.w) * get(&u, *k));
        }
        let rate = level.angle(&p.angle, &u, bodies);
        if let Some(b) = bodies.get_mut(p.link as usize) {
            level.set_link(b, anchor, rate, &p.local);
        }
    }
    true
}

/// One linear pass of a group without a closed form of its own: [`arm_pass`] for the
/// triad and a general Assur group (all arms, as their builders make them), else (or
/// if it refuses the group) the general [`linear_pass`].
#[inline]
fn any_linear_pass<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    level: &impl PassLevel<T>,
) {
    if matches!(g.kind, GroupKind::Triad | GroupKind::Assur)
        && arm_pass(g, gd, model, bodies, level)
    {
        return;
    }
    linear_pass(g, gd, model, bodies, level);
}

/// Solves `W ẋ = -(known part of ḟ)` and sets the links' velocities.
pub(crate) fn velocity_pass<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    qd: &[T],
) {
    match g.kind {
        GroupKind::Rrr => super::dyad_rrr::velocity(g, gd, model, bodies),
        GroupKind::MotorR => super::motor_r::velocity(g, gd, model, bodies, qd),
        _ => any_linear_pass(g, gd, model, bodies, &Vel { qd }),
    }
}

/// Solves `W ẍ = -(f̈ with ẍ = 0)` and sets the links' accelerations (needs the
/// velocity pass with the actual speeds first).
pub(crate) fn acceleration_pass<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    qd: &[T],
    qdd: &[T],
) {
    match g.kind {
        GroupKind::Rrr => super::dyad_rrr::acceleration(g, gd, model, bodies),
        GroupKind::MotorR => super::motor_r::acceleration(g, gd, model, bodies, qdd),
        _ => any_linear_pass(g, gd, model, bodies, &Acc { qd, qdd }),
    }
}

/// The closing chain of a dyad and its end pole (the closed forms' common start).
pub(crate) fn closing_chain<T: Real>(g: &Group<T>) -> Result<(&Chain<T>, PointRef), GroupFault> {
    let ch = g.chains.first().ok_or(GroupFault::NonFiniteInput)?;
    let end = ch.end.ok_or(GroupFault::NonFiniteInput)?;
    Ok((ch, end))
}
