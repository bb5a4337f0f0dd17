//! What serde reads of a run file: raw structures that reject unknown keys (the
//! message lists the allowed ones) and wrong types; [`super::validate`] checks their
//! values.

use super::*;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFile {
    pub(super) name: Option<String>,
    pub(super) description: Option<String>,
    pub(super) gravity: Option<[f64; 2]>,
    #[serde(default)]
    pub(super) ground: Vec<RawGround>,
    #[serde(default)]
    pub(super) link: Vec<RawLink>,
    #[serde(default)]
    pub(super) joint: Vec<RawJoint>,
    #[serde(default)]
    pub(super) driver: Vec<RawDriver>,
    #[serde(default)]
    pub(super) load: Vec<RawLoad>,
    pub(super) converter: Option<RawConverter>,
    pub(super) run: RawRun,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGround {
    pub(super) name: String,
    pub(super) at: [f64; 2],
}

#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "a distance along the bar from its start, m, or a point [x, y] in the link frame, m"
)]
pub(super) enum RawCog {
    Along(f64),
    At([f64; 2]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLink {
    pub(super) name: String,
    pub(super) length: Option<f64>,
    #[serde(default)]
    pub(super) points: BTreeMap<String, [f64; 2]>,
    pub(super) mass: f64,
    pub(super) inertia: f64,
    pub(super) cog: Option<RawCog>,
    pub(super) angle_deg: Option<f64>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawJointType {
    Revolute,
    Prismatic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawJoint {
    pub(super) name: Option<String>,
    #[serde(rename = "type")]
    pub(super) kind: RawJointType,
    pub(super) points: Option<[String; 2]>,
    pub(super) slider: Option<String>,
    pub(super) guide: Option<String>,
    pub(super) guide_angle_deg: Option<f64>,
    pub(super) slider_angle_deg: Option<f64>,
    pub(super) offset: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDriver {
    pub(super) link: String,
    pub(super) joint: String,
    pub(super) q0_deg: Option<f64>,
    pub(super) q0: Option<f64>,
    pub(super) qd0: Option<f64>,
    pub(super) offset_deg: Option<f64>,
    pub(super) motor: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLoad {
    pub(super) link: String,
    pub(super) at: Option<[f64; 2]>,
    pub(super) force: Option<[f64; 2]>,
    pub(super) moment: Option<f64>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawDrive {
    Cw,
    Ccw,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawSide {
    Left,
    Right,
}

impl From<RawSide> for Side {
    fn from(s: RawSide) -> Side {
        match s {
            RawSide::Left => Side::Left,
            RawSide::Right => Side::Right,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBar {
    pub(super) length: f64,
    pub(super) mass: f64,
    pub(super) inertia: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawConverter {
    pub(super) a: [f64; 2],
    pub(super) f: [f64; 2],
    pub(super) h: [f64; 2],
    pub(super) link: Vec<RawBar>,
    pub(super) rocker_d: f64,
    pub(super) mass: f64,
    pub(super) mass_inertia: f64,
    pub(super) mass_at: f64,
    pub(super) shaft_inertia: f64,
    pub(super) friction: Option<RawFriction>,
    pub(super) drive: RawDrive,
    pub(super) gravity: [f64; 2],
    pub(super) branch_c: RawSide,
    pub(super) branch_g: RawSide,
    pub(super) branch_i: RawSide,
    pub(super) crank_deg: Option<f64>,
    pub(super) swing_deg: Option<f64>,
    pub(super) crank_speed: Option<f64>,
    pub(super) swing_speed: Option<f64>,
    pub(super) motor_offset: Option<f64>,
}

/// `[converter.friction]`: the losses of a real machine (SPEC 5), each 0 when absent.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFriction {
    pub(super) viscous: Option<RawJoints>,
    pub(super) coulomb: Option<RawJoints>,
    pub(super) coulomb_eps: Option<f64>,
    pub(super) clutch_drag: Option<f64>,
}

/// A coefficient per revolute joint of the converter, by SPEC's letter
/// ([`FRICTION_JOINT_NAMES`]); the levers' joints at H are the clutches.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub(super) struct RawJoints {
    pub(super) A: Option<f64>,
    pub(super) B: Option<f64>,
    pub(super) C: Option<f64>,
    pub(super) E: Option<f64>,
    pub(super) F: Option<f64>,
    pub(super) D5: Option<f64>,
    pub(super) D7: Option<f64>,
    pub(super) G: Option<f64>,
    pub(super) I: Option<f64>,
}

impl RawJoints {
    /// In [`FRICTION_JOINT_NAMES`]' order, absent ones `None`.
    pub(super) fn values(&self) -> [Option<f64>; 9] {
        [
            self.A, self.B, self.C, self.E, self.F, self.D5, self.D7, self.G, self.I,
        ]
    }
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawMode {
    Clutch,
    Free,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawIntegrator {
    Dp5,
    Adaptive,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRun {
    pub(super) h: f64,
    pub(super) t_end: f64,
    pub(super) every: Option<u64>,
    pub(super) f32: Option<bool>,
    pub(super) integrator: Option<RawIntegrator>,
    pub(super) rtol: Option<f64>,
    pub(super) atol: Option<f64>,
    pub(super) h_max: Option<f64>,
    pub(super) mode: Option<RawMode>,
    pub(super) motor: Option<toml::Value>,
    pub(super) load: Option<f64>,
    pub(super) spread_events: Option<bool>,
}
