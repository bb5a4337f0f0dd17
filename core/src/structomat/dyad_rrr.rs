//! Dyad RRR (thesis figure 12): links `a` and `b` on known poles A and B, joined at C.
//!
//! Loop closure: `A + R(θa)·(C_a - A_a) - R(θb)·(C_b - B_b) - B = 0` (2 equations,
//! unknowns `x = (θa, θb)`, the link-frame angles). Closed form: C is an intersection of
//! circle(A, la) and circle(B, lb); branch +1 puts C to the left of A→B.

use super::{
    chain, guesses, list, point_pos, Angle, Base, Group, GroupData, GroupKind, Joint, JointKind,
    Placement, PointRef, Term,
};
use crate::error::{GroupFault, ModelError};
use crate::model::Model;
use crate::scalar::{perp, Real, Vec2};
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
    pub fn build(&self, model: &Model<T>) -> Result<Group<T>, ModelError> {
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
        let ang = |k: u8| Angle::new(Base::Var(k), T::zero());
        let terms = [
            Term::Arm {
                angle: ang(0),
                v: va,
            },
            Term::Arm {
                angle: ang(1),
                v: -wb,
            },
        ];
        Ok(Group {
            kind: GroupKind::Rrr,
            n_vars: 2,
            chains: list(&[chain(self.pole_a, &terms, Some(self.pole_b))?], "chains")?,
            placements: list(
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
            )?,
            joints: list(
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
            )?,
            guess: guesses(&self.guess),
            consts: [
                la,
                lb,
                va.x / la,
                va.y / la,
                wb.x / lb,
                wb.y / lb,
                va.y.atan2(va.x),
                wb.y.atan2(wb.x),
            ],
            coord: None,
        })
    }
}

/// Closed-form position on the branch `gd.branch`: writes `gd.x` and the links' cosines
/// and sines (`gd.trig`, straight from the constructed vectors: no trigonometry but the
/// two `atan2` that record the angles).
pub(crate) fn solve<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T>,
    bodies: &[BodyState<T>],
) -> Result<(), GroupFault> {
    let (ch, end) = super::chain::closing_chain(g)?;
    let [la, lb, ca, sa, cb, sb, alpha_a, alpha_b] = g.consts;
    let a = point_pos(model, bodies, ch.start);
    let b = point_pos(model, bodies, end);
    let d = b - a;
    let dist = d.norm();
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
    let c = a + e * along + perp(&e) * (gd.branch * h2.sqrt());
    let (ua, ub) = ((c - a) / la, (c - b) / lb);
    // θ = ∠u - α: turn u back by α.
    gd.trig[0] = Vec2::new(ua.x * ca + ua.y * sa, ua.y * ca - ua.x * sa);
    gd.trig[1] = Vec2::new(ub.x * cb + ub.y * sb, ub.y * cb - ub.x * sb);
    gd.x[0] = ua.y.atan2(ua.x) - alpha_a;
    gd.x[1] = ub.y.atan2(ub.x) - alpha_b;
    Ok(())
}
