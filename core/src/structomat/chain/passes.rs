//! The linear velocity and acceleration passes of a group without a closed form of its
//! own (SPEC 1: `W ẋ = L`, `W ẍ = L̇ - Ẇ ẋ`): one generic pass over the chains' terms,
//! compiled per derivative level, and its all-arm form.

use super::*;
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
        GroupKind::Rrr => crate::structomat::dyad_rrr::velocity(g, gd, model, bodies),
        GroupKind::MotorR => crate::structomat::motor_r::velocity(g, gd, model, bodies, qd),
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
        GroupKind::Rrr => crate::structomat::dyad_rrr::acceleration(g, gd, model, bodies),
        GroupKind::MotorR => crate::structomat::motor_r::acceleration(g, gd, model, bodies, qdd),
        _ => any_linear_pass(g, gd, model, bodies, &Acc { qd, qdd }),
    }
}
