//! Dyad RRR (thesis figure 12): links `a` and `b` on known poles A and B, joined at C.
//!
//! Loop closure: `A + R(θa)·(C_a - A_a) - R(θb)·(C_b - B_b) - B = 0` (2 equations,
//! unknowns `x = (θa, θb)`, the link-frame angles). Closed form: C is an intersection of
//! circle(A, la) and circle(B, lb); branch +1 puts C to the left of A→B.

use super::chain::{link_acceleration, link_velocity, place_link};
use super::{
    extend, guesses, point_acc, point_pos, point_vel, push_chain, Angle, Angles, Base, Group,
    GroupData, GroupKind, Joint, JointKind, Placement, PointRef, Term, TermCache,
};
use crate::capacity::Capacity;
use crate::config::MAX_GROUP_VARS;
use crate::error::{GroupFault, ModelError};
use crate::model::{Model, Points, WriteGroup};
use crate::scalar::{cross, perp, Real, Vec2};
use crate::workspace::BodyState;

/// Dyad RRR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DyadRrr<T: Real> {
    /// First link (body index), on pole A.
    pub a: u8,
    /// Second link, on pole B.
    pub b: u8,
    /// Known pole A.
    pub pole_a: PointRef,
    /// `a`'s point at A.
    pub a_at_pole: u8,
    /// Known pole B.
    pub pole_b: PointRef,
    /// `b`'s point at B.
    pub b_at_pole: u8,
    /// `a`'s point at the joint C.
    pub a_joint: u8,
    /// `b`'s point at the joint C.
    pub b_joint: u8,
    /// Guesses of `(θa, θb)`, rad: they pick the assembly branch.
    pub guess: [T; 2],
}

impl<T: Real> DyadRrr<T> {
    /// Builds the group's description. Closed-form constants:
    /// `[la, lb, cos ∠va, sin ∠va, cos ∠wb, sin ∠wb, ∠va, ∠wb]` with
    /// `va = C_a - A_a`, `wb = C_b - B_b` in the link frames.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let mut g = Group::empty();
        self.write(&model.points(), &mut g)?;
        Ok(g)
    }
}

impl<T: Real> WriteGroup<T> for DyadRrr<T> {
    /// [`DyadRrr::build`], in place.
    fn write(&self, model: &Points<'_, T>, g: &mut Group<T>) -> Result<(), ModelError> {
        let pa = model.local(self.a, self.a_at_pole, "dyad RRR: a at pole")?;
        let ca = model.local(self.a, self.a_joint, "dyad RRR: a at joint")?;
        let pb = model.local(self.b, self.b_at_pole, "dyad RRR: b at pole")?;
        let cb = model.local(self.b, self.b_joint, "dyad RRR: b at joint")?;
        let pole_a = model.resolve(self.pole_a, "dyad RRR: pole A")?;
        let pole_b = model.resolve(self.pole_b, "dyad RRR: pole B")?;
        let (va, wb) = (ca - pa, cb - pb);
        let (la, lb) = (va.norm(), wb.norm());
        if !(la > T::zero() && lb > T::zero()) {
            return Err(ModelError::Degenerate("dyad RRR: a link's joints coincide"));
        }
        let ang = |k: u8| Angle::of(Base::Var(k));
        g.kind = GroupKind::Rrr;
        g.n_vars = 2;
        push_chain(
            g,
            self.pole_a,
            &[
                Term::Arm {
                    angle: ang(0),
                    v: va,
                },
                Term::Arm {
                    angle: ang(1),
                    v: -wb,
                },
            ],
            Some(self.pole_b),
        )?;
        extend(
            &mut g.placements,
            &[
                Placement {
                    link: self.a,
                    angle: ang(0),
                    chain: 0,
                    prefix: 0,
                    local: pa,
                },
                Placement {
                    link: self.b,
                    angle: ang(1),
                    chain: 0,
                    prefix: 1,
                    local: cb,
                },
            ],
            "placements",
        )?;
        extend(
            &mut g.joints,
            &[
                Joint {
                    i: self.a,
                    pi: pa,
                    j: self.pole_a.body,
                    pj: pole_a,
                    kind: JointKind::Revolute,
                },
                Joint {
                    i: self.b,
                    pi: pb,
                    j: self.pole_b.body,
                    pj: pole_b,
                    kind: JointKind::Revolute,
                },
                Joint {
                    i: self.a,
                    pi: ca,
                    j: self.b,
                    pj: cb,
                    kind: JointKind::Revolute,
                },
            ],
            "joints",
        )?;
        g.guess = guesses(&self.guess);
        g.consts = [
            la,
            lb,
            va.x / la,
            va.y / la,
            wb.x / lb,
            wb.y / lb,
            va.y.atan2(va.x),
            wb.y.atan2(wb.x),
        ];
        Ok(())
    }
}

/// Poles A and B, placements of links a and b.
type Parts<'g, T> = (PointRef, PointRef, &'g Placement<T>, &'g Placement<T>);

/// The dyad's poles A and B and the placements of its links a (anchored at A) and b
/// (anchored at C), as [`DyadRrr::build`] lays them out.
#[inline]
fn parts<T: Real>(g: &Group<T>) -> Result<Parts<'_, T>, GroupFault> {
    let (ch, end) = super::chain::closing_chain(g)?;
    let (Some(pa), Some(pb)) = (g.placements.first(), g.placements.get(1)) else {
        return Err(GroupFault::NonFiniteInput);
    };
    Ok((ch.start, end, pa, pb))
}

/// Closed-form position on the branch `gd.branch`, with everything the linear passes
/// and the kinetostatics need: `gd.x`, the links' cosines and sines (`gd.trig`,
/// straight from the constructed vectors: no trigonometry but the two `atan2` that
/// record the angles), the terms (`gd.cache`), `W⁻¹` and the conditioning, and the
/// links' poses. Returns det W.
///
/// With the joint C constructed, the terms are `w_a = R(θa) va = C - A` and
/// `w_b = -R(θb) wb = B - C`, `W = [J w_a, J w_b]`, `det W = w_a × w_b`, and the
/// column norms are the link lengths: the conditioning `|w_a × w_b| / (la lb)` is the
/// sine of the transmission angle at C.
pub(crate) fn solve<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    singular_tol: T,
    angles: Angles,
) -> Result<T, GroupFault> {
    let (start, end, pl_a, pl_b) = parts(g)?;
    let [la, lb, ca, sa, cb, sb, alpha_a, alpha_b] = g.consts;
    let a = point_pos(model, bodies, start);
    let b = point_pos(model, bodies, end);
    let d = b - a;
    let dist = d.norm_squared().root();
    if !dist.finite() {
        return Err(GroupFault::NonFiniteInput);
    }
    // C projects on AB at `along` from A, at `height` off the line (circle intersection).
    let along = (la * la - lb * lb + dist * dist) / (T::c(2.0) * dist);
    let h2 = la * la - along * along;
    if !(dist > T::zero()) || !(h2 >= T::zero()) {
        let gap = if dist > la + lb {
            dist - la - lb
        } else {
            (la - lb).abs() - dist
        };
        return Err(GroupFault::CannotAssemble { gap: gap.to_f64() });
    }
    let e = d / dist;
    let c = a + e * along + perp(&e) * (gd.branch * h2.root());
    let (wa, wb) = (c - a, b - c);
    let (ua, ub) = (wa / la, -wb / lb);
    // θ = ∠u - α: turn u back by α.
    let trig_a = Vec2::new(ua.x * ca + ua.y * sa, ua.y * ca - ua.x * sa);
    let trig_b = Vec2::new(ub.x * cb + ub.y * sb, ub.y * cb - ub.x * sb);
    let (theta_a, theta_b) = match angles {
        Angles::Record => (ua.y.atan2(ua.x) - alpha_a, ub.y.atan2(ub.x) - alpha_b),
        Angles::Stale => (gd.x[0], gd.x[1]),
    };
    gd.x[0] = theta_a;
    gd.x[1] = theta_b;
    gd.trig[0] = trig_a;
    gd.trig[1] = trig_b;
    if let Some(row) = gd.cache.first_mut() {
        row[0] = TermCache {
            w: wa,
            s: T::zero(),
        };
        row[1] = TermCache {
            w: wb,
            s: T::zero(),
        };
    }
    let det = cross(&wa, &wb);
    let cond = det.abs() / (la * lb);
    gd.conditioning = cond;
    if !(cond > singular_tol) {
        return Err(GroupFault::Singular {
            conditioning: cond.to_f64(),
        });
    }
    // W = [[-wa.y, -wb.y], [wa.x, wb.x]]: its inverse in closed form.
    let id = T::one() / det;
    for ((r, k), v) in [
        ((0, 0), wb.x * id),
        ((0, 1), wb.y * id),
        ((1, 0), -wa.x * id),
        ((1, 1), -wa.y * id),
    ] {
        if let Some(m) = gd.w_fact.get_mut(r).and_then(|row| row.get_mut(k)) {
            *m = v;
        }
    }
    if let Some(s) = bodies.get_mut(pl_a.link as usize) {
        place_link(s, theta_a, trig_a, a, &pl_a.local);
    }
    if let Some(s) = bodies.get_mut(pl_b.link as usize) {
        place_link(s, theta_b, trig_b, c, &pl_b.local);
    }
    Ok(det)
}

/// `W⁻¹ r` for the dyad's 2 × 2 block.
#[inline]
fn solve_2<T: Real>(gd: &GroupData<T>, r: Vec2<T>) -> [T; 2] {
    let m = |i: usize, k: usize| {
        gd.w_fact
            .get(i)
            .and_then(|row| row.get(k))
            .copied()
            .unwrap_or(T::zero())
    };
    [m(0, 0) * r.x + m(0, 1) * r.y, m(1, 0) * r.x + m(1, 1) * r.y]
}

/// Velocity pass of the dyad (the linear pass of [`chain`](mod@super::chain) written out
/// for its two arms): `W ẋ = v_B - v_A` (the arms turn only with the unknowns), then
/// link a turns about A at `θ̇a` and link b about C, whose velocity is
/// `v_A + θ̇a J w_a`.
pub(crate) fn velocity<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
) {
    let Ok((start, end, pl_a, pl_b)) = parts(g) else {
        return;
    };
    let va = point_vel(model, bodies, start);
    let vb = point_vel(model, bodies, end);
    let [wd_a, wd_b] = solve_2(gd, vb - va);
    let mut xd = [T::zero(); MAX_GROUP_VARS];
    xd[0] = wd_a;
    xd[1] = wd_b;
    gd.xd = xd;
    let wa = gd.cache[0][0].w;
    if let Some(s) = bodies.get_mut(pl_a.link as usize) {
        link_velocity(s, va, wd_a, &pl_a.local);
    }
    if let Some(s) = bodies.get_mut(pl_b.link as usize) {
        link_velocity(s, va + perp(&wa) * wd_a, wd_b, &pl_b.local);
    }
}

/// Acceleration pass of the dyad (after its velocity pass):
/// `W ẍ = a_B - a_A + θ̇a² w_a + θ̇b² w_b` (the arms' centripetal parts), then link a
/// about A and link b about C, whose acceleration is `a_A + θ̈a J w_a - θ̇a² w_a`.
pub(crate) fn acceleration<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
) {
    let Ok((start, end, pl_a, pl_b)) = parts(g) else {
        return;
    };
    let aa = point_acc(model, bodies, start);
    let ab = point_acc(model, bodies, end);
    let (wa, wb) = (gd.cache[0][0].w, gd.cache[0][1].w);
    let (wd_a, wd_b) = (gd.xd[0], gd.xd[1]);
    let ca = wa * (wd_a * wd_a);
    let [wdd_a, wdd_b] = solve_2(gd, ab - aa + ca + wb * (wd_b * wd_b));
    let mut xdd = [T::zero(); MAX_GROUP_VARS];
    xdd[0] = wdd_a;
    xdd[1] = wdd_b;
    gd.xdd = xdd;
    if let Some(s) = bodies.get_mut(pl_a.link as usize) {
        link_acceleration(s, aa, wdd_a, &pl_a.local);
    }
    if let Some(s) = bodies.get_mut(pl_b.link as usize) {
        link_acceleration(s, aa + perp(&wa) * wdd_a - ca, wdd_b, &pl_b.local);
    }
}
