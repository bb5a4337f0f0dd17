//! Dyad RTR (thesis figure 12): link `b` turns on a known pole B and carries a
//! straight guide; link `a` (a block) turns on a known pole A and slides along `b`'s
//! guide (the inverted slider-crank, Whitworth's quick return).
//!
//! Loop closure: `B + R(θb)·(L_b - B_b) + s·R(θb + γ)·e_x - R(θb + β)·(S_a - A_a) - A = 0`,
//! unknowns `x = (θb, s)`; the prismatic joint keeps `θa = θb + β`. Every term turns
//! with `θb`: `R(θb)(c + s d) = A - B`, so `s = -c·d ± √((c·d)² - |c|² + |AB|²)` and
//! `θb = ∠(A - B) - ∠(c + s d)`; branch +1 takes the larger `s`.

use super::{
    chain, guesses, list, point_pos, Angle, Base, Group, GroupData, GroupKind, Joint, JointKind,
    Length, Placement, PointRef, Term,
};
use crate::capacity::Capacity;
use crate::error::{GroupFault, ModelError};
use crate::model::Model;
use crate::scalar::{rotate_cs, unit, Real, Vec2};
use crate::workspace::BodyState;

/// Dyad RTR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DyadRtr<T: Real> {
    /// The block that slides along `b` (body index), on pole A.
    pub a: u8,
    /// The guide link (body index), on pole B.
    pub b: u8,
    /// Known pole A.
    pub pole_a: PointRef,
    /// `a`'s point at A.
    pub a_at_pole: u8,
    /// Known pole B.
    pub pole_b: PointRef,
    /// `b`'s point at B.
    pub b_at_pole: u8,
    /// A point of `b`'s guide line (`s` is measured from it).
    pub b_line: u8,
    /// Direction of the guide line in `b`'s frame, rad.
    pub b_line_angle: T,
    /// `a`'s point that runs on the line.
    pub a_on_line: u8,
    /// `θa - θb`, rad.
    pub a_angle: T,
    /// Guesses of `(θb, s)` (rad, m).
    pub guess: [T; 2],
}

impl<T: Real> DyadRtr<T> {
    /// Builds the group's description. Closed-form constants: `[c.x, c.y, d.x, d.y]`.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let aa = model.local(self.a, self.a_at_pole, "dyad RTR: a at pole")?;
        let asl = model.local(self.a, self.a_on_line, "dyad RTR: a on line")?;
        let bb = model.local(self.b, self.b_at_pole, "dyad RTR: b at pole")?;
        let bl = model.local(self.b, self.b_line, "dyad RTR: b line point")?;
        let pole_a = model.resolve(self.pole_a, "dyad RTR: pole A")?;
        let pole_b = model.resolve(self.pole_b, "dyad RTR: pole B")?;
        let (sb, cb) = self.a_angle.sincos();
        let d = unit(self.b_line_angle);
        let c = (bl - bb) - rotate_cs(cb, sb, &(asl - aa));
        let var0 = |off: T| Angle::new(Base::Var(0), off);
        let terms = [
            Term::Arm {
                angle: var0(T::zero()),
                v: bl - bb,
            },
            Term::Slide {
                angle: var0(self.b_line_angle),
                dir: Vec2::new(T::one(), T::zero()),
                s: Length::Var(1),
            },
            Term::Arm {
                angle: var0(self.a_angle),
                v: -(asl - aa),
            },
        ];
        Ok(Group {
            kind: GroupKind::Rtr,
            n_vars: 2,
            chains: list(&[chain(self.pole_b, &terms, Some(self.pole_a))?], "chains")?,
            placements: list(
                &[
                    Placement {
                        link: self.b,
                        angle: var0(T::zero()),
                        chain: 0,
                        prefix: 0,
                        local: bb,
                    },
                    Placement {
                        link: self.a,
                        angle: var0(self.a_angle),
                        chain: 0,
                        prefix: 2,
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
                        pj: pole_a,
                        kind: JointKind::Revolute,
                    },
                    Joint {
                        i: self.b,
                        pi: bb,
                        j: self.pole_b.body,
                        pj: pole_b,
                        kind: JointKind::Revolute,
                    },
                    Joint {
                        i: self.a,
                        pi: asl,
                        j: self.b,
                        pj: bl,
                        kind: JointKind::Prismatic { dir: d },
                    },
                ],
                "joints",
            )?,
            guess: guesses(&self.guess),
            consts: [
                c.x,
                c.y,
                d.x,
                d.y,
                T::zero(),
                T::zero(),
                T::zero(),
                T::zero(),
            ],
            coord: None,
        })
    }
}

/// Closed-form position on the branch `gd.branch`: writes `gd.x`.
pub(crate) fn solve<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
) -> Result<(), GroupFault> {
    let (ch, end) = super::chain::closing_chain(g)?;
    let [cx, cy, dx, dy, ..] = g.consts;
    let (c, d) = (Vec2::new(cx, cy), Vec2::new(dx, dy));
    let ab = point_pos(model, bodies, end) - point_pos(model, bodies, ch.start);
    let dist2 = ab.norm_squared();
    let cd = c.dot(&d);
    let disc = cd * cd - c.norm_squared() + dist2;
    if !disc.finite() {
        return Err(GroupFault::NonFiniteInput);
    }
    if disc < T::zero() {
        let off = (c.norm_squared() - cd * cd).max(T::zero()).root();
        return Err(GroupFault::CannotAssemble {
            gap: (off - dist2.root()).to_f64(),
        });
    }
    let s = -cd + gd.branch * disc.root();
    let r = c + d * s;
    // θb = ∠(A - B) - ∠r; |r| = |AB| by construction, so e(θb) = (AB·r, r×AB) / |AB|².
    let (cb, sb) = (ab.dot(&r) / dist2, (r.x * ab.y - r.y * ab.x) / dist2);
    gd.trig[0] = Vec2::new(cb, sb);
    gd.x[0] = sb.atan2(cb);
    gd.x[1] = s;
    Ok(())
}
