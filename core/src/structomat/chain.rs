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

use super::{Angle, Base, Chain, Group, Length, PointRef, Term};
use crate::config::{MAX_CHAINS, MAX_DOF, MAX_GROUP_VARS, MAX_TERMS};
use crate::error::GroupFault;
use crate::model::Model;
use crate::scalar::{perp, rotate_cs, Real, Vec2};
use crate::workspace::BodyState;
use nalgebra::{SMatrix, SVector};

/// A group's Jacobian `W` (top-left `n × n`, identity padding) and its inverse.
pub type GroupMatrix<T> = SMatrix<T, MAX_GROUP_VARS, MAX_GROUP_VARS>;
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
    /// vectors they construct, or by Newton from `x` (slides: unused).
    pub trig: [Vec2<T>; MAX_GROUP_VARS],
    /// Assembly branch of a closed form (+1 or -1), chosen at assembly from the guesses.
    pub branch: T,
    /// Sign of det W at assembly (the branch of a Newton group).
    pub det_sign: T,
    /// `W⁻¹` (top-left `n × n` block).
    pub w_inv: GroupMatrix<T>,
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
    /// `ẍ` with `q̈ = 0`: the bias part of the group's accelerations.
    pub xdd_bias: [T; MAX_GROUP_VARS],
}

impl<T: Real> Default for GroupData<T> {
    fn default() -> Self {
        GroupData {
            x: [T::zero(); MAX_GROUP_VARS],
            xd: [T::zero(); MAX_GROUP_VARS],
            xdd: [T::zero(); MAX_GROUP_VARS],
            trig: [Vec2::new(T::one(), T::zero()); MAX_GROUP_VARS],
            branch: T::one(),
            det_sign: T::zero(),
            w_inv: GroupMatrix::identity(),
            conditioning: T::one(),
            iterations: 0,
            cache: [[TermCache::default(); MAX_TERMS]; MAX_CHAINS],
            dx_dq: SMatrix::zeros(),
            xdd_bias: [T::zero(); MAX_GROUP_VARS],
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
            let (s, c) = get(q, j).sin_cos();
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
pub(crate) fn point_pos<T: Real>(
    model: &Model<T>,
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
pub(crate) fn point_vel<T: Real>(
    model: &Model<T>,
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
pub(crate) fn point_acc<T: Real>(
    model: &Model<T>,
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
    let (trig, x) = (gd.trig, gd.x);
    for (ch, row) in g.chains.iter().zip(gd.cache.iter_mut()) {
        for (t, c) in ch.terms.iter().zip(row.iter_mut()) {
            *c = match t {
                Term::Arm { angle, v } => {
                    let cs = angle_cs(angle, &trig, q, bodies);
                    TermCache {
                        w: rotate_cs(cs.x, cs.y, v),
                        s: T::zero(),
                    }
                }
                Term::Slide { angle, dir, s } => {
                    let cs = angle_cs(angle, &trig, q, bodies);
                    TermCache {
                        w: rotate_cs(cs.x, cs.y, dir),
                        s: length_at(*s, &x, q),
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

/// Loop-closure residual `start + Σ terms - end` of every closing chain (m), stacked.
pub(crate) fn residual<T: Real>(
    g: &Group<T>,
    gd: &GroupData<T>,
    model: &Model<T>,
    bodies: &[BodyState<T>],
) -> GroupVector<T> {
    let mut f = GroupVector::zeros();
    for (ci, (ch, row)) in g.chains.iter().zip(gd.cache.iter()).enumerate() {
        let Some(end) = ch.end else { continue };
        let mut r = point_pos(model, bodies, ch.start) - point_pos(model, bodies, end);
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

#[inline]
fn add_col<T: Real>(w: &mut GroupMatrix<T>, ci: usize, k: u8, v: Vec2<T>) {
    if let Some(e) = w.get_mut((2 * ci, k as usize)) {
        *e += v.x;
    }
    if let Some(e) = w.get_mut((2 * ci + 1, k as usize)) {
        *e += v.y;
    }
}

/// The Jacobian `W = ∂f/∂x` from the cached terms (top-left `n × n`, identity padding).
pub(crate) fn jacobian<T: Real>(g: &Group<T>, gd: &GroupData<T>) -> GroupMatrix<T> {
    let n = g.n_vars as usize;
    let mut w = GroupMatrix::zeros();
    for k in n..MAX_GROUP_VARS {
        if let Some(e) = w.get_mut((k, k)) {
            *e = T::one();
        }
    }
    for (ci, (ch, row)) in g.chains.iter().zip(gd.cache.iter()).enumerate() {
        if ch.end.is_none() {
            continue;
        }
        for (t, c) in ch.terms.iter().zip(row.iter()) {
            match t {
                Term::Arm { angle, .. } => {
                    if let Base::Var(k) = angle.base {
                        add_col(&mut w, ci, k, perp(&c.w));
                    }
                }
                Term::Slide { angle, s, .. } => {
                    if let Base::Var(k) = angle.base {
                        add_col(&mut w, ci, k, perp(&c.w) * c.s);
                    }
                    if let Length::Var(k) = s {
                        add_col(&mut w, ci, *k, c.w);
                    }
                }
            }
        }
    }
    w
}

/// Inverts `W` and measures its conditioning; a dead point is an error.
pub(crate) fn factor<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    let n = g.n_vars as usize;
    if n == 0 {
        gd.conditioning = T::one();
        return Ok(T::one());
    }
    let w = jacobian(g, gd);
    let mut norms = T::one();
    for col in w.column_iter().take(n) {
        norms *= col.norm();
    }
    // A dyad's 2×2 inverse in closed form; larger groups by Gauss-Jordan.
    let (inv, det) = if n == 2 {
        let (a, b, c, d) = (w[(0, 0)], w[(0, 1)], w[(1, 0)], w[(1, 1)]);
        let det = a * d - b * c;
        let id = T::one() / det;
        let mut m = GroupMatrix::identity();
        m[(0, 0)] = d * id;
        m[(0, 1)] = -b * id;
        m[(1, 0)] = -c * id;
        m[(1, 1)] = a * id;
        (m, det)
    } else {
        crate::linalg::invert(w, n).unwrap_or((GroupMatrix::identity(), T::zero()))
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
    gd.w_inv = inv;
    Ok(det)
}

/// Sets the pose of every link of the group from the cached terms.
pub(crate) fn place<T: Real>(
    g: &Group<T>,
    gd: &GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) {
    for p in g.placements.iter() {
        let Some(ch) = g.chains.get(p.chain as usize) else {
            continue;
        };
        let Some(row) = gd.cache.get(p.chain as usize) else {
            continue;
        };
        let mut anchor = point_pos(model, bodies, ch.start);
        for (t, c) in ch.terms.iter().zip(row.iter()).take(p.prefix as usize) {
            anchor += term_pos(t, c);
        }
        let theta = angle_at(&p.angle, &gd.x, q, bodies, Level::Pos);
        let cs = angle_cs(&p.angle, &gd.trig, q, bodies);
        if let Some(b) = bodies.get_mut(p.link as usize) {
            b.theta = theta;
            b.c = cs.x;
            b.s = cs.y;
            b.o = anchor - rotate_cs(cs.x, cs.y, &p.local);
        }
    }
}

/// With `gd.x` solved: caches the terms, factors `W` and places the links.
pub(crate) fn position_from_x<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    eval_terms(g, gd, bodies, q);
    position_from_terms(g, gd, model, bodies, q)
}

/// [`position_from_x`] when the terms are already cached at `gd.x` (Newton-Raphson's
/// converged iterate: its residual check evaluated them there).
pub(crate) fn position_from_terms<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    let det = factor(g, gd, model.singular_tol())?;
    place(g, gd, model, bodies, q);
    Ok(det)
}

/// The derivative level of a linear pass, with the coordinates' derivatives.
#[derive(Clone, Copy)]
enum Pass<'a, T> {
    /// Velocities at the rates `qd`.
    Vel { qd: &'a [T] },
    /// Accelerations at the rates `qd` and accelerations `qdd`.
    Acc { qd: &'a [T], qdd: &'a [T] },
}

impl<T: Real> Pass<'_, T> {
    fn point(self, model: &Model<T>, bodies: &[BodyState<T>], p: PointRef) -> Vec2<T> {
        match self {
            Pass::Vel { .. } => point_vel(model, bodies, p),
            Pass::Acc { .. } => point_acc(model, bodies, p),
        }
    }

    /// A term's derivative with the group's unknown derivatives `u` (zeros: the known
    /// part); `xd` are the unknowns' rates (used by the acceleration level).
    fn term(
        self,
        t: &Term<T>,
        c: &TermCache<T>,
        xd: &[T],
        u: &[T],
        bodies: &[BodyState<T>],
    ) -> Vec2<T> {
        match self {
            Pass::Vel { qd } => term_vel(t, c, u, qd, bodies),
            Pass::Acc { qd, qdd } => term_acc(t, c, xd, u, qd, qdd, bodies),
        }
    }

    fn angle(self, a: &Angle<T>, u: &[T], bodies: &[BodyState<T>]) -> T {
        match self {
            Pass::Vel { qd } => angle_at(a, u, qd, bodies, Level::Vel),
            Pass::Acc { qdd, .. } => angle_at(a, u, qdd, bodies, Level::Acc),
        }
    }
}

/// One linear pass: solves `W u = -(the level's derivative of f with u = 0)` for the
/// unknowns' rates (or accelerations) `u` and sets the links' velocities (or
/// accelerations) from the chains' prefix sums.
fn linear_pass<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    pass: Pass<'_, T>,
) {
    let zero = [T::zero(); MAX_GROUP_VARS];
    let n = g.n_vars as usize;
    let mut u = zero;
    if n > 0 {
        let mut rhs = GroupVector::zeros();
        for (ci, (ch, row)) in g.chains.iter().zip(gd.cache.iter()).enumerate() {
            let Some(end) = ch.end else { continue };
            let mut r = pass.point(model, bodies, ch.start) - pass.point(model, bodies, end);
            for (t, c) in ch.terms.iter().zip(row.iter()) {
                r += pass.term(t, c, &gd.xd, &zero, bodies);
            }
            set2(&mut rhs, ci, -r);
        }
        // Only the top-left n × n block of W⁻¹ is live.
        for (r, ur) in u.iter_mut().enumerate().take(n) {
            let mut acc = T::zero();
            for (c, rc) in rhs.iter().enumerate().take(n) {
                acc += gd.w_inv.get((r, c)).copied().unwrap_or(T::zero()) * *rc;
            }
            *ur = acc;
        }
    }
    match pass {
        Pass::Vel { .. } => gd.xd = u,
        Pass::Acc { .. } => gd.xdd = u,
    }
    for p in g.placements.iter() {
        let (Some(ch), Some(row)) = (
            g.chains.get(p.chain as usize),
            gd.cache.get(p.chain as usize),
        ) else {
            continue;
        };
        let mut anchor = pass.point(model, bodies, ch.start);
        for (t, c) in ch.terms.iter().zip(row.iter()).take(p.prefix as usize) {
            anchor += pass.term(t, c, &gd.xd, &u, bodies);
        }
        let rate = pass.angle(&p.angle, &u, bodies);
        let Some(b) = bodies.get_mut(p.link as usize) else {
            continue;
        };
        let r = rotate_cs(b.c, b.s, &p.local);
        match pass {
            Pass::Vel { .. } => {
                b.omega = rate;
                b.v = anchor - perp(&r) * rate;
            }
            Pass::Acc { .. } => {
                b.alpha = rate;
                b.a = anchor - perp(&r) * rate + r * (b.omega * b.omega);
            }
        }
    }
}

/// Solves `W ẋ = -(known part of ḟ)` and sets the links' velocities.
pub(crate) fn velocity_pass<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    qd: &[T],
) {
    linear_pass(g, gd, model, bodies, Pass::Vel { qd });
}

/// Solves `W ẍ = -(f̈ with ẍ = 0)` and sets the links' accelerations (needs the
/// velocity pass with the actual speeds first).
pub(crate) fn acceleration_pass<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &mut [BodyState<T>],
    qd: &[T],
    qdd: &[T],
) {
    linear_pass(g, gd, model, bodies, Pass::Acc { qd, qdd });
}

/// The closing chain of a dyad and its end pole (the closed forms' common start).
pub(crate) fn closing_chain<T: Real>(g: &Group<T>) -> Result<(&Chain<T>, PointRef), GroupFault> {
    let ch = g.chains.first().ok_or(GroupFault::NonFiniteInput)?;
    let end = ch.end.ok_or(GroupFault::NonFiniteInput)?;
    Ok((ch, end))
}
