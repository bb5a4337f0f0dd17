//! Output poles (thesis section 3.2): points carried by a placed link. Once a group has
//! placed its links, every point of those links is known, with its velocity and
//! acceleration, and serves as an input pole of later groups.
//!
//! `P = o + R(θ) p`, `Ṗ = ȯ + ω J R(θ) p`, `P̈ = ö + α J R(θ) p - ω² R(θ) p`.

use super::{point_acc, point_pos, point_vel, PointRef};
use crate::capacity::Capacity;
use crate::model::Model;
use crate::scalar::{Real, Vec2};
use crate::workspace::Workspace;

/// Position (m), velocity (m/s) and acceleration (m/s²) of a point of a placed body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoleKinematics<T> {
    /// World position, m.
    pub pos: Vec2<T>,
    /// World velocity, m/s.
    pub vel: Vec2<T>,
    /// World acceleration, m/s².
    pub acc: Vec2<T>,
}

/// Kinematics of the point `p` from the workspace's last evaluation.
pub fn output_pole<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &Workspace<T, C>,
    p: PointRef,
) -> PoleKinematics<T> {
    PoleKinematics {
        pos: point_pos(model, &ws.body, p),
        vel: point_vel(model, &ws.body, p),
        acc: point_acc(model, &ws.body, p),
    }
}
