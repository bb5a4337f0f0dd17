//! Dyad RTT (thesis figure 12): link `a` turns on a known pole A and slides in slider
//! `b`, which runs along a guide fixed in a known body.
//!
//! Loop closure: `G + sb·u + R(θb)·(L_b - S_b) + sab·R(θb + δ)·e_x - R(θa)·(S_a - A_a) - A = 0`
//! with `θb = θg + βb` and `θa = θb + βa` fixed by the two prismatic joints; unknowns
//! `x = (sb, sab)`. Linear in `x`: the closed form is one solve (no branch).

use super::{
    chain, guesses, list, Angle, Base, Group, GroupKind, Joint, JointKind, Length, Placement,
    PointRef, Term,
};
use crate::capacity::Capacity;
use crate::error::ModelError;
use crate::model::Model;
use crate::scalar::{unit, Real, Vec2};

/// Dyad RTT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DyadRtt<T: Real> {
    /// The link on pole A that slides in `b` (body index).
    pub a: u8,
    /// The slider on the known guide (body index).
    pub b: u8,
    /// Known pole A.
    pub pole_a: PointRef,
    /// `a`'s point at A.
    pub a_at_pole: u8,
    /// A known point of `b`'s guide line (`sb` is measured from it).
    pub guide: PointRef,
    /// Direction of the guide in its body's frame, rad.
    pub guide_angle: T,
    /// `b`'s point on the guide line.
    pub b_on_guide: u8,
    /// `θb - θguide body`, rad.
    pub b_angle: T,
    /// A point of `b`'s own line along which `a` slides (`sab` is measured from it).
    pub b_line: u8,
    /// Direction of that line in `b`'s frame, rad.
    pub b_line_angle: T,
    /// `a`'s point on `b`'s line.
    pub a_on_line: u8,
    /// `θa - θb`, rad.
    pub a_angle: T,
}

impl<T: Real> DyadRtt<T> {
    /// Builds the group's description.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let aa = model.local(self.a, self.a_at_pole, "dyad RTT: a at pole")?;
        let asl = model.local(self.a, self.a_on_line, "dyad RTT: a on line")?;
        let bg = model.local(self.b, self.b_on_guide, "dyad RTT: b on guide")?;
        let bl = model.local(self.b, self.b_line, "dyad RTT: b line point")?;
        let pole = model.resolve(self.pole_a, "dyad RTT: pole A")?;
        let guide = model.resolve(self.guide, "dyad RTT: guide point")?;
        let g = self.guide.body;
        let ex = Vec2::new(T::one(), T::zero());
        let ang = |off: T| Angle::new(Base::Body(g), off);
        let (tb, ta) = (self.b_angle, self.b_angle + self.a_angle);
        let terms = [
            Term::Slide {
                angle: ang(self.guide_angle),
                dir: ex,
                s: Length::Var(0),
            },
            Term::Arm {
                angle: ang(tb),
                v: bl - bg,
            },
            Term::Slide {
                angle: ang(tb + self.b_line_angle),
                dir: ex,
                s: Length::Var(1),
            },
            Term::Arm {
                angle: ang(ta),
                v: -(asl - aa),
            },
        ];
        Ok(Group {
            kind: GroupKind::Rtt,
            n_vars: 2,
            chains: list(&[chain(self.guide, &terms, Some(self.pole_a))?], "chains")?,
            placements: list(
                &[
                    Placement {
                        link: self.b,
                        angle: ang(tb),
                        chain: 0,
                        prefix: 1,
                        local: bg,
                    },
                    Placement {
                        link: self.a,
                        angle: ang(ta),
                        chain: 0,
                        prefix: 3,
                        local: asl,
                    },
                ],
                "placements",
            )?,
            joints: list(
                &[
                    Joint {
                        i: self.a,
                        pi: aa,
                        j: self.pole_a.body,
                        pj: pole,
                        kind: JointKind::Revolute,
                    },
                    Joint {
                        i: self.a,
                        pi: asl,
                        j: self.b,
                        pj: bl,
                        kind: JointKind::Prismatic {
                            dir: unit(self.b_line_angle),
                        },
                    },
                    Joint {
                        i: self.b,
                        pi: bg,
                        j: g,
                        pj: guide,
                        kind: JointKind::Prismatic {
                            dir: unit(self.guide_angle),
                        },
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
