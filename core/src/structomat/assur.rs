//! A general Assur group of revolute joints, solved by Newton-Raphson on vector loops
//! the caller lays out (thesis section 3.2's method, past the triad).
//!
//! The library's closed-form groups (dyads) and the triad cover the thesis's
//! mechanisms. Some motion-transmission sequences need a larger group: the converter
//! in mode A68 driven by its crank (levers 6 and 8 joined and turning with the shaft)
//! leaves links 2, 3, 4, 5, 7 and the joined lever as one group of 6 links and 9
//! joints (3·6 = 2·9), with no smaller group in it. Its position problem is 3 loop
//! closures in 6 link angles.
//!
//! Each loop starts at a known point, walks through links of the group (a step is a
//! link, from one of its points to another: the term `R(θ_link)(p_to - p_from)`) and
//! closes on a known point. Unknown k is the angle of `links[k]`. Each link is placed
//! from the first step that walks through it. Newton is bounded and warm-started
//! ([`newton`](super::newton)); the branch is kept by the sign of det W as for the
//! triad.

use super::{
    guesses, Angle, Base, Chain, Group, GroupKind, Joint, JointKind, Placement, PointRef, Term,
};
use crate::capacity::Capacity;
use crate::config::MAX_GROUP_LINKS;
use crate::error::ModelError;
use crate::model::{GroupSpec, Model, Points, WriteGroup};
use crate::scalar::Real;

/// One step of a loop: link `links[link]` walked from its point `from` to its point
/// `to`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AssurStep {
    /// Index of the link in the group's `links`.
    pub link: u8,
    /// The link's point where the step enters it.
    pub from: u8,
    /// The link's point where the step leaves it.
    pub to: u8,
}

/// A closing loop: `start + Σ steps = end`, both ends known before the group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssurLoop<'a> {
    /// The known point the loop starts from.
    pub start: PointRef,
    /// The steps through the group's links.
    pub steps: &'a [AssurStep],
    /// The known point it must reach.
    pub end: PointRef,
}

/// A revolute joint of the group: point `at` of the group's body `link` (a body
/// index) pinned to `other` (a point of the ground, of an earlier group, or of the
/// group).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AssurJoint {
    /// The group's link (body index).
    pub link: u8,
    /// Its point at the joint.
    pub at: u8,
    /// The point it is pinned to.
    pub other: PointRef,
}

/// A general Assur group of revolute joints (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssurGroup<'a, T: Real> {
    /// The group's links (body indices); unknown k is the angle of `links[k]`.
    pub links: &'a [u8],
    /// The closing loops, one per two unknowns.
    pub loops: &'a [AssurLoop<'a>],
    /// Every joint of the group (`3 × links = 2 × joints`), for the kinetostatics.
    pub joints: &'a [AssurJoint],
    /// Guesses of the link angles, rad, in the order of `links`: Newton's start, which
    /// picks the assembly branch.
    pub guess: &'a [T],
}

impl<T: Real> AssurGroup<'_, T> {
    /// Builds the group's description.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let mut g = Group::empty();
        self.write(&model.points(), &mut g)?;
        Ok(g)
    }
}

impl<T: Real> WriteGroup<T> for AssurGroup<'_, T> {
    /// [`AssurGroup::build`], in place.
    fn write(&self, model: &Points<'_, T>, g: &mut Group<T>) -> Result<(), ModelError> {
        let n = self.links.len();
        if n == 0 || n > MAX_GROUP_LINKS || 2 * self.loops.len() > MAX_GROUP_LINKS {
            return Err(ModelError::Capacity("links of an Assur group"));
        }
        if 2 * self.loops.len() != n {
            return Err(ModelError::Degenerate(
                "Assur group: it needs one closing loop per two links",
            ));
        }
        if 2 * self.joints.len() != 3 * n {
            return Err(ModelError::Degenerate(
                "Assur group: 3 × links must equal 2 × joints",
            ));
        }
        if self.guess.len() != n {
            return Err(ModelError::Degenerate(
                "Assur group: one guess per link is needed",
            ));
        }
        let mut placements: heapless::Vec<Placement<T>, MAX_GROUP_LINKS> = heapless::Vec::new();
        for (ci, lp) in self.loops.iter().enumerate() {
            model.resolve(lp.start, "Assur group: loop start")?;
            model.resolve(lp.end, "Assur group: loop end")?;
            g.chains
                .push(Chain {
                    start: lp.start,
                    terms: heapless::Vec::new(),
                    end: Some(lp.end),
                })
                .map_err(|_| ModelError::Capacity("loops of an Assur group"))?;
            let terms = match g.chains.last_mut() {
                Some(c) => &mut c.terms,
                None => return Err(ModelError::Capacity("loops of an Assur group")),
            };
            for (si, st) in lp.steps.iter().enumerate() {
                let body = *self
                    .links
                    .get(st.link as usize)
                    .ok_or(ModelError::UnknownReference("Assur group: step link"))?;
                let from = model.local(body, st.from, "Assur group: step point")?;
                let to = model.local(body, st.to, "Assur group: step point")?;
                if !((to - from).norm() > T::zero()) {
                    return Err(ModelError::Degenerate(
                        "Assur group: a step's two points coincide",
                    ));
                }
                let angle = Angle::of(Base::Var(st.link));
                terms
                    .push(Term::Arm {
                        angle,
                        v: to - from,
                    })
                    .map_err(|_| ModelError::Capacity("steps in an Assur loop"))?;
                if !placements.iter().any(|p| p.link == body) {
                    placements
                        .push(Placement {
                            link: body,
                            angle,
                            chain: ci as u8,
                            prefix: si as u8,
                            local: from,
                        })
                        .map_err(|_| ModelError::Capacity("links of an Assur group"))?;
                }
            }
        }
        if placements.len() != n {
            return Err(ModelError::Degenerate(
                "Assur group: a link is walked by no loop",
            ));
        }
        // Placements in the order of `links` (the kinetostatics' row order).
        for body in self.links {
            if let Some(p) = placements.iter().find(|p| p.link == *body) {
                let _ = g.placements.push(*p);
            }
        }
        for jt in self.joints {
            if !self.links.contains(&jt.link) {
                return Err(ModelError::UnknownReference("Assur group: joint link"));
            }
            g.joints
                .push(Joint {
                    i: jt.link,
                    pi: model.local(jt.link, jt.at, "Assur group: joint point")?,
                    j: jt.other.body,
                    pj: model.resolve(jt.other, "Assur group: joint other point")?,
                    kind: JointKind::Revolute,
                })
                .map_err(|_| ModelError::Capacity("joints of an Assur group"))?;
        }
        g.kind = GroupKind::Assur;
        g.n_vars = n as u8;
        g.guess = guesses(self.guess);
        Ok(())
    }
}

impl<T: Real> GroupSpec<T> for AssurGroup<'_, T> {
    fn build(&self, model: &Model<T>) -> Result<Group<T>, ModelError> {
        AssurGroup::build(self, model)
    }
}
