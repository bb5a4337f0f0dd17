//! Motor element R (thesis figure 11a): a link turning about a known point; its
//! absolute angle is a generalized coordinate, `θ = q_j + offset`.

use super::chain::{angle_cs, link_acceleration, link_velocity, place_link};
use super::{
    extend, point_acc, point_pos, point_vel, push_chain, Angle, Base, Group, GroupData, GroupKind,
    Joint, JointKind, Placement, PointRef,
};
use crate::capacity::Capacity;
use crate::config::MAX_GROUP_VARS;
use crate::error::{GroupFault, ModelError};
use crate::model::{Model, Points, WriteGroup};
use crate::scalar::{same_bits, Real};
use crate::workspace::BodyState;

/// Motor element R.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorR<T: Real> {
    /// The driven link (body index).
    pub link: u8,
    /// The known point it turns about (usually a ground point).
    pub pivot: PointRef,
    /// The link's own point at the pivot (index in its point list).
    pub link_point: u8,
    /// The generalized coordinate `q_j` that gives its angle.
    pub coord: u8,
    /// `θ_link - q_j`, rad (0 when the coordinate is the link angle itself).
    pub offset: T,
}

impl<T: Real> MotorR<T> {
    /// Builds the group's description against the links declared so far.
    pub fn build<C: Capacity<T>>(&self, model: &Model<T, C>) -> Result<Group<T>, ModelError> {
        let mut g = Group::empty();
        self.write(&model.points(), &mut g)?;
        Ok(g)
    }
}

impl<T: Real> WriteGroup<T> for MotorR<T> {
    /// [`MotorR::build`], in place.
    fn write(&self, model: &Points<'_, T>, g: &mut Group<T>) -> Result<(), ModelError> {
        let local = model.local(self.link, self.link_point, "motor element R: link point")?;
        let pivot = model.resolve(self.pivot, "motor element R: pivot")?;
        let angle = Angle::new(Base::Coord(self.coord), self.offset);
        g.kind = GroupKind::MotorR;
        g.n_vars = 0;
        push_chain(g, self.pivot, &[], None)?;
        extend(
            &mut g.placements,
            &[Placement {
                link: self.link,
                angle,
                chain: 0,
                prefix: 0,
                local,
            }],
            "placements",
        )?;
        extend(
            &mut g.joints,
            &[
                Joint {
                    i: self.link,
                    pi: local,
                    j: self.pivot.body,
                    pj: pivot,
                    kind: JointKind::Revolute,
                },
                Joint {
                    i: self.link,
                    pi: local,
                    j: self.pivot.body,
                    pj: pivot,
                    kind: JointKind::DriveTorque,
                },
            ],
            "joints",
        )?;
        g.coord = Some(self.coord);
        Ok(())
    }
}

/// The element's pivot, its placement, and the coordinate its angle is (see
/// [`MotorR::build`]); `None` for a group of another shape.
#[inline]
fn parts<T: Real>(g: &Group<T>) -> Option<(PointRef, &Placement<T>, usize)> {
    let p = g.placements.first()?;
    let Base::Coord(j) = p.angle.base else {
        return None;
    };
    Some((g.chains.first()?.start, p, j as usize))
}

/// Sets the group's rates (a motor element has no unknowns: they are +0) to +0. In f64
/// only if they are not already (they are from the assembly on): the clear of 48 B is
/// a library call on the Cortex-M7 at each evaluation, the test a few compares. f32's
/// 24 B are a few stores, cheaper than the test (decided at compile time). Per element,
/// or for the 13 bodies' applied moments, the tests cost more than the clear.
#[inline]
fn clear<T: Real>(x: &mut [T; MAX_GROUP_VARS]) {
    let zero = T::zero();
    if core::mem::size_of::<T>() <= 4 || x.iter().any(|v| !same_bits(*v, zero)) {
        *x = [zero; MAX_GROUP_VARS];
    }
}

#[inline]
fn get<T: Real>(v: &[T], j: usize) -> T {
    v.get(j).copied().unwrap_or(T::zero())
}

/// Position: the link at `θ = q_j + offset` about its pivot (no unknowns: W is empty,
/// its conditioning 1). Returns det W = 1.
pub(crate) fn position<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
) -> Result<T, GroupFault> {
    let (pivot, p, j) = parts(g).ok_or(GroupFault::NonFiniteInput)?;
    gd.conditioning = T::one();
    let anchor = point_pos(model, bodies, pivot);
    let cs = angle_cs(&p.angle, &gd.trig, q, bodies);
    if let Some(b) = bodies.get_mut(p.link as usize) {
        place_link(b, get(q, j) + p.angle.offset, cs, anchor, &p.local);
    }
    Ok(T::one())
}

/// Velocity pass: `ω = q̇_j`, the link turning about its pivot.
pub(crate) fn velocity<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    qd: &[T],
) {
    let Some((pivot, p, j)) = parts(g) else {
        return;
    };
    clear(&mut gd.xd);
    let anchor = point_vel(model, bodies, pivot);
    let rate = get(qd, j);
    if let Some(b) = bodies.get_mut(p.link as usize) {
        link_velocity(b, anchor, rate, &p.local);
    }
}

/// Acceleration pass (after the velocity pass): `α = q̈_j`.
pub(crate) fn acceleration<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    qdd: &[T],
) {
    let Some((pivot, p, j)) = parts(g) else {
        return;
    };
    clear(&mut gd.xdd);
    let anchor = point_acc(model, bodies, pivot);
    let rate = get(qdd, j);
    if let Some(b) = bodies.get_mut(p.link as usize) {
        link_acceleration(b, anchor, rate, &p.local);
    }
}
