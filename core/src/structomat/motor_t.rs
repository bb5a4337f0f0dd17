//! Motor element T (thesis figure 11a): a link sliding along a known guide; its offset
//! along the guide is a generalized coordinate.

use super::{
    chain, list, Angle, Base, Group, GroupKind, Joint, JointKind, Length, Placement, PointRef, Term,
};
use crate::capacity::Capacity;
use crate::config::MAX_GROUP_VARS;
use crate::error::ModelError;
use crate::model::Model;
use crate::scalar::{unit, Real, Vec2};

/// Motor element T.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorT<T: Real> {
    /// The driven slider (body index).
    pub link: u8,
    /// A known point of the guide line, where `q_j = 0`.
    pub guide: PointRef,
    /// Direction of the guide in the frame of the guide's body, rad.
    pub guide_angle: T,
    /// The slider's point that runs on the guide line.
    pub link_point: u8,
    /// Slider angle relative to the guide's body, rad.
    pub link_angle: T,
    /// The generalized coordinate `q_j`: the offset along the guide, m.
    pub coord: u8,
}

impl<T: Real> MotorT<T> {
    /// Builds the group's description against the links declared so far.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let local = model.local(self.link, self.link_point, "motor element T: link point")?;
        let guide = model.resolve(self.guide, "motor element T: guide point")?;
        let g = self.guide.body;
        let slide = Term::Slide {
            angle: Angle::new(Base::Body(g), self.guide_angle),
            dir: Vec2::new(T::one(), T::zero()),
            s: Length::Coord(self.coord),
        };
        let angle = Angle::new(Base::Body(g), self.link_angle);
        let dir = unit(self.guide_angle);
        Ok(Group {
            kind: GroupKind::MotorT,
            n_vars: 0,
            chains: list(&[chain(self.guide, &[slide], None)?], "chains")?,
            placements: list(
                &[Placement {
                    link: self.link,
                    angle,
                    chain: 0,
                    prefix: 1,
                    local,
                }],
                "placements",
            )?,
            joints: list(
                &[
                    Joint {
                        i: self.link,
                        pi: local,
                        j: g,
                        pj: guide,
                        kind: JointKind::Prismatic { dir },
                    },
                    Joint {
                        i: self.link,
                        pi: local,
                        j: g,
                        pj: guide,
                        kind: JointKind::DriveForce { dir },
                    },
                ],
                "joints",
            )?,
            guess: [T::zero(); MAX_GROUP_VARS],
            consts: [T::zero(); 8],
            coord: Some(self.coord),
        })
    }
}
