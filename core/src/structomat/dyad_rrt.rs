//! Dyad RRT (thesis figure 12): a rod on a known pole A, pinned at C to a slider that
//! runs along a guide fixed in a known body (the slider-crank's rod and piston).
//!
//! Loop closure: `G + s·u + R(θs)·(C_s - S_s) - R(θr)·(C_r - A_r) - A = 0` with `G` a
//! point of the guide line, `u` its direction, `θs` the slider's angle (the guide body's
//! plus a constant). Unknowns `x = (θr, s)`. Closed form: C = K + s·u on the line at
//! distance `lr` from A, `s = -u·e ± √((u·e)² - |e|² + lr²)`, `e = K - A`; branch +1
//! takes the root farther along `u`.

use super::chain::angle_cs;
use super::{
    chain, guesses, list, point_pos, Angle, Base, Group, GroupData, GroupKind, Joint, JointKind,
    Length, Placement, PointRef, Term,
};
use crate::capacity::Capacity;
use crate::error::{GroupFault, ModelError};
use crate::model::Model;
use crate::scalar::{rotate_cs, unit, Real, Vec2};
use crate::workspace::BodyState;

/// Dyad RRT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DyadRrt<T: Real> {
    /// The rod (body index).
    pub rod: u8,
    /// The slider (body index).
    pub slider: u8,
    /// Known pole A of the rod.
    pub pole: PointRef,
    /// The rod's point at A.
    pub rod_at_pole: u8,
    /// The rod's point at the pin C.
    pub rod_joint: u8,
    /// The slider's point at the pin C.
    pub slider_joint: u8,
    /// A known point of the guide line (on the guide's body); `s` is measured from it.
    pub guide: PointRef,
    /// Direction of the guide in the guide body's frame, rad.
    pub guide_angle: T,
    /// The slider's point that runs on the guide line.
    pub slider_on_guide: u8,
    /// Slider angle relative to the guide's body, rad.
    pub slider_angle: T,
    /// Guesses of `(θr, s)` (rad, m): they pick the assembly branch.
    pub guess: [T; 2],
}

impl<T: Real> DyadRrt<T> {
    /// Builds the group's description. Closed-form constants:
    /// `[lr, cos α, sin α, α, 0, 0, 0, 0]` with `α = ∠(C_r - A_r)` in the rod's frame.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let ra = model.local(self.rod, self.rod_at_pole, "dyad RRT: rod at pole")?;
        let rc = model.local(self.rod, self.rod_joint, "dyad RRT: rod at pin")?;
        let sc = model.local(self.slider, self.slider_joint, "dyad RRT: slider at pin")?;
        let ss = model.local(
            self.slider,
            self.slider_on_guide,
            "dyad RRT: slider on guide",
        )?;
        let pole = model.resolve(self.pole, "dyad RRT: pole")?;
        let guide = model.resolve(self.guide, "dyad RRT: guide point")?;
        let vr = rc - ra;
        let lr = vr.norm();
        if !(lr > T::zero()) {
            return Err(ModelError::Degenerate(
                "dyad RRT: the rod's joints coincide",
            ));
        }
        let g = self.guide.body;
        let along = Angle::new(Base::Body(g), self.guide_angle);
        let slider_angle = Angle::new(Base::Body(g), self.slider_angle);
        let rod_angle = Angle::new(Base::Var(0), T::zero());
        let terms = [
            Term::Slide {
                angle: along,
                dir: Vec2::new(T::one(), T::zero()),
                s: Length::Var(1),
            },
            Term::Arm {
                angle: slider_angle,
                v: sc - ss,
            },
            Term::Arm {
                angle: rod_angle,
                v: -vr,
            },
        ];
        Ok(Group {
            kind: GroupKind::Rrt,
            n_vars: 2,
            chains: list(&[chain(self.guide, &terms, Some(self.pole))?], "chains")?,
            placements: list(
                &[
                    Placement {
                        link: self.rod,
                        angle: rod_angle,
                        chain: 0,
                        prefix: 2,
                        local: rc,
                    },
                    Placement {
                        link: self.slider,
                        angle: slider_angle,
                        chain: 0,
                        prefix: 1,
                        local: ss,
                    },
                ],
                "placements",
            )?,
            joints: list(
                &[
                    Joint {
                        i: self.rod,
                        pi: ra,
                        j: self.pole.body,
                        pj: pole,
                        kind: JointKind::Revolute,
                    },
                    Joint {
                        i: self.rod,
                        pi: rc,
                        j: self.slider,
                        pj: sc,
                        kind: JointKind::Revolute,
                    },
                    Joint {
                        i: self.slider,
                        pi: ss,
                        j: g,
                        pj: guide,
                        kind: JointKind::Prismatic {
                            dir: unit(self.guide_angle),
                        },
                    },
                ],
                "joints",
            )?,
            guess: guesses(&self.guess),
            consts: [
                lr,
                vr.x / lr,
                vr.y / lr,
                vr.y.atan2(vr.x),
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
    let (Some(Term::Slide { angle: along, .. }), Some(Term::Arm { angle: sa, v: sv })) =
        (ch.terms.first(), ch.terms.get(1))
    else {
        return Err(GroupFault::NonFiniteInput);
    };
    let [lr, cr, sr, alpha_r, ..] = g.consts;
    // Both angles are the guide body's plus constants: no trigonometry.
    let u = angle_cs(along, &gd.trig, &[], bodies);
    let cs = angle_cs(sa, &gd.trig, &[], bodies);
    let a = point_pos(model, bodies, end);
    let k = point_pos(model, bodies, ch.start) + rotate_cs(cs.x, cs.y, sv);
    let e = k - a;
    let ue = u.dot(&e);
    let disc = ue * ue - e.norm_squared() + lr * lr;
    if !disc.finite() {
        return Err(GroupFault::NonFiniteInput);
    }
    if disc < T::zero() {
        let off_line = (e.norm_squared() - ue * ue).max(T::zero()).root();
        return Err(GroupFault::CannotAssemble {
            gap: (off_line - lr).to_f64(),
        });
    }
    let s = -ue + gd.branch * disc.root();
    let c = k + u * s;
    let ur = (c - a) / lr;
    // The rod's angle is ∠(C - A) - α: turn the unit vector back by α.
    gd.trig[0] = Vec2::new(ur.x * cr + ur.y * sr, ur.y * cr - ur.x * sr);
    gd.x[0] = ur.y.atan2(ur.x) - alpha_r;
    gd.x[1] = s;
    Ok(())
}
