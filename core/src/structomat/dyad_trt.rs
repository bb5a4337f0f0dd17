//! Dyad TRT (thesis figure 12): two sliders on known guides, pinned together at C.
//!
//! Loop closure: `Ga + sa·ua + R(θa)·(C_a - S_a) - R(θb)·(C_b - S_b) - sb·ub - Gb = 0`,
//! unknowns `x = (sa, sb)`; both angles are fixed by the guides. The equations are
//! linear in `x`: the closed form is one solve with `W = [ua, -ub]` (no branch).

use super::{
    chain, guesses, list, Angle, Base, Group, GroupKind, Joint, JointKind, Length, Placement,
    PointRef, Term,
};
use crate::capacity::Capacity;
use crate::error::ModelError;
use crate::model::Model;
use crate::scalar::{unit, Real, Vec2};

/// Dyad TRT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DyadTrt<T: Real> {
    /// First slider (body index).
    pub a: u8,
    /// Second slider (body index).
    pub b: u8,
    /// A known point of `a`'s guide line (`sa` is measured from it).
    pub guide_a: PointRef,
    /// Direction of `a`'s guide in its body's frame, rad.
    pub guide_a_angle: T,
    /// `a`'s point on its guide line.
    pub a_on_guide: u8,
    /// `a`'s angle relative to its guide's body, rad.
    pub a_angle: T,
    /// A known point of `b`'s guide line.
    pub guide_b: PointRef,
    /// Direction of `b`'s guide in its body's frame, rad.
    pub guide_b_angle: T,
    /// `b`'s point on its guide line.
    pub b_on_guide: u8,
    /// `b`'s angle relative to its guide's body, rad.
    pub b_angle: T,
    /// `a`'s point at the pin C.
    pub a_joint: u8,
    /// `b`'s point at the pin C.
    pub b_joint: u8,
}

impl<T: Real> DyadTrt<T> {
    /// Builds the group's description.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let asg = model.local(self.a, self.a_on_guide, "dyad TRT: a on guide")?;
        let ac = model.local(self.a, self.a_joint, "dyad TRT: a at pin")?;
        let bsg = model.local(self.b, self.b_on_guide, "dyad TRT: b on guide")?;
        let bc = model.local(self.b, self.b_joint, "dyad TRT: b at pin")?;
        let ga = model.resolve(self.guide_a, "dyad TRT: guide a")?;
        let gb = model.resolve(self.guide_b, "dyad TRT: guide b")?;
        let (ba, bb) = (self.guide_a.body, self.guide_b.body);
        let ex = Vec2::new(T::one(), T::zero());
        let ang = |b: u8, off: T| Angle::new(Base::Body(b), off);
        let terms = [
            Term::Slide {
                angle: ang(ba, self.guide_a_angle),
                dir: ex,
                s: Length::Var(0),
            },
            Term::Arm {
                angle: ang(ba, self.a_angle),
                v: ac - asg,
            },
            Term::Arm {
                angle: ang(bb, self.b_angle),
                v: -(bc - bsg),
            },
            Term::Slide {
                angle: ang(bb, self.guide_b_angle),
                dir: -ex,
                s: Length::Var(1),
            },
        ];
        Ok(Group {
            kind: GroupKind::Trt,
            n_vars: 2,
            chains: list(
                &[chain(self.guide_a, &terms, Some(self.guide_b))?],
                "chains",
            )?,
            placements: list(
                &[
                    Placement {
                        link: self.a,
                        angle: ang(ba, self.a_angle),
                        chain: 0,
                        prefix: 1,
                        local: asg,
                    },
                    Placement {
                        link: self.b,
                        angle: ang(bb, self.b_angle),
                        chain: 0,
                        prefix: 3,
                        local: bsg,
                    },
                ],
                "placements",
            )?,
            joints: list(
                &[
                    Joint {
                        i: self.a,
                        pi: asg,
                        j: ba,
                        pj: ga,
                        kind: JointKind::Prismatic {
                            dir: unit(self.guide_a_angle),
                        },
                    },
                    Joint {
                        i: self.b,
                        pi: bsg,
                        j: bb,
                        pj: gb,
                        kind: JointKind::Prismatic {
                            dir: unit(self.guide_b_angle),
                        },
                    },
                    Joint {
                        i: self.a,
                        pi: ac,
                        j: self.b,
                        pj: bc,
                        kind: JointKind::Revolute,
                    },
                ],
                "joints",
            )?,
            guess: guesses(&[]),
            consts: [T::zero(); 8],
            coord: None,
        })
    }
}
