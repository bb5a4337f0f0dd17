//! Mechanisms and runs from TOML files (issue 5): the file format, its parsing and its
//! validation. Every key is described in `host-sim/scenarios/README.md` and in
//! `host-sim help run`.
//!
//! Two kinds of file:
//! - a **general mechanism**: top-level `name`, `description`, `gravity`, arrays of
//!   tables `[[ground]]`, `[[link]]`, `[[joint]]`, `[[driver]]`, `[[load]]`, and `[run]`.
//!   The host finds the motion-transmission sequence itself ([`super::analysis`]).
//! - the **converter**: `[converter]` (every field of [`CccParams`], with its eight bars
//!   as `[[converter.link]]`) and `[run]` (mode, motor, load, steps).
//!
//! Parsing is in two stages, so that a parameter sweep can edit a file's values before
//! they are checked: the text (or a [`toml::Value`] tree a sweep has edited, e.g.
//! `converter.mass = 40`, `run.load = 600`) is deserialized into private raw structs
//! that reject unknown keys (`deny_unknown_fields`: the message lists the allowed
//! names) and wrong types; then a validation pass checks every value and every reference
//! (units, signs, names, capacities) before anything runs. No input makes it panic.
//!
//! Units: SI (m, kg, kg·m², s, N, N·m, rad/s, m/s); angles that a person writes are in
//! degrees, in keys ending in `_deg`; motor speeds in keys ending in `_rpm`.

use crate::error::Sci;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use structomat::ccc::{Bar, CccParams, DriveDirection, Friction, Side, FRICTION_JOINT_NAMES};
use structomat::config::{MAX_DOF, MAX_GROUND_POINTS, MAX_LINKS, MAX_LINK_POINTS, MAX_LOADS};
use structomat::motor::{rpm, Asynchronous, Motor};
use structomat::scalar::Vec2;
use structomat::{ModelError, Real};

/// Loads (N·m, N) from which on a run is refused: the step's energy tolerance (1e-9 of
/// an energy scale that such a load's work dominates) and the clutch's tolerances are
/// then far coarser than the mechanism's own energies and torques.
pub const MAX_LOAD: f64 = 1e12;

/// The converter's load torque T_r (N·m) from which on a run is refused: the twin
/// releases a locked lever when its clutch torque falls below -1e-9 (T_r + 1 N·m)
/// (`structomat::ccc`'s torque tolerance), so from 1e6 N·m on an accepted state may
/// hold a clutch torque below -1e-3 N·m and a release comes late by that tolerance
/// over the torque's rate (S2 at T_r = 1e7: c8 = -7.4e-3 N·m, the release 5e-5 s
/// late; at 1e11, -98 N·m), far coarser than the converter's own torques.
pub const MAX_CONVERTER_LOAD: f64 = 1e6;

/// A bad run file: which file, where (when the toml parser knows), which field, what is
/// wrong. Displayed as `FILE[:LINE:COLUMN]: FIELD: MESSAGE`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileError {
    /// The file's path, or the name the caller gave its text (`ccc-s2.toml`, a sweep's
    /// job name).
    pub origin: String,
    /// Line and column, from 1, when the toml parser gave a position.
    pub position: Option<(usize, usize)>,
    /// The field path, e.g. `link "coupler".mass`, `run.h`; empty when the message
    /// names it (the toml parser's own messages).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.origin)?;
        if let Some((line, col)) = self.position {
            write!(f, ":{line}:{col}")?;
        }
        if !self.field.is_empty() {
            write!(f, ": {}", self.field)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for FileError {}

/// A parsed and validated run file.
#[derive(Clone, Debug, PartialEq)]
pub struct RunFile {
    /// The mechanism's name (`name = ...`), if given.
    pub name: Option<String>,
    /// A one-line description (`description = ...`), if given.
    pub description: Option<String>,
    /// What is simulated.
    pub body: Body,
    /// The run settings (`[run]`).
    pub run: RunSettings,
}

/// What a run file simulates.
#[derive(Clone, Debug, PartialEq)]
pub enum Body {
    /// A general mechanism (links, joints, drivers).
    Mechanism(Mechanism),
    /// The Constantinesco converter (boxed: its parameters are most of the file).
    Converter(Box<Converter>),
}

/// `[run]`: the integration and output settings common to both kinds of file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSettings {
    /// Fixed step, s (> 0).
    pub h: f64,
    /// Simulated time, s (> 0).
    pub t_end: f64,
    /// Write every N-th step (≥ 1).
    pub every: u64,
    /// Run the core in single precision.
    pub f32: bool,
    /// How the mechanism is integrated between output times.
    pub integrator: Integrator,
}

/// `[run] integrator`: how a mechanism file is integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// `"dp5"`: the fixed-step Dormand-Prince 5 of `Simulation::step`, step `h`.
    Dp5,
    /// `"adaptive"`: the adaptive DP5(4) of `Simulation::step_adaptive` (error control
    /// by `rtol` and `atol`, steps of its own size up to `h_max`); `h` is then the
    /// output interval.
    Adaptive {
        /// Relative tolerance (> 0).
        rtol: f64,
        /// Absolute tolerance, rad or m (> 0).
        atol: f64,
        /// Largest step, s (> 0).
        h_max: f64,
    },
}

/// A point of a body: body 0 is the ground (point = index of a `[[ground]]` point),
/// bodies `1..` are the links in file order (point = index in the link's point list).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct PointId {
    /// Body, 0 = ground.
    pub body: usize,
    /// Point index in that body.
    pub point: usize,
}

/// A ground point (`[[ground]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct GroundPoint {
    /// Its name, used in point references.
    pub name: String,
    /// Position, world frame, m.
    pub at: [f64; 2],
}

/// A link (`[[link]]`), body `index + 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkSpec {
    /// Its name.
    pub name: String,
    /// Points in the link frame, m: `start` (0) and `end` (1) of a bar, then the named
    /// points in name order; a link without `length` starts with its origin (`origin`).
    pub points: Vec<[f64; 2]>,
    /// The names of `points`, same order.
    pub point_names: Vec<String>,
    /// Mass, kg (≥ 0).
    pub mass: f64,
    /// Moment of inertia about the COG, kg·m² (≥ 0).
    pub inertia: f64,
    /// Centre of gravity, link frame, m.
    pub cog: [f64; 2],
    /// Initial guess of the link angle (its frame's x axis), degrees: it picks the
    /// assembly branch of the group that places the link.
    pub angle_deg: f64,
}

/// A joint (`[[joint]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct JointSpec {
    /// Its name (default `J<k>`, k from 1 in file order).
    pub name: String,
    /// Its kind and points.
    pub kind: JointKind,
}

/// The two kinds of lower pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// A pin joining two points of two bodies.
    Revolute {
        /// The two points (different bodies).
        points: [PointId; 2],
    },
    /// A slider: `slider`'s point runs on a straight line of the guide body through
    /// `guide`.
    Prismatic {
        /// The sliding body's point on the line.
        slider: PointId,
        /// A point of the line, on the guide body; offsets are measured from it.
        guide: PointId,
        /// Direction of the line in the guide body's frame, degrees.
        guide_angle_deg: f64,
        /// Angle of the slider relative to the guide body, degrees.
        slider_angle_deg: f64,
        /// Initial guess of the offset along the line, m.
        offset: f64,
    },
}

impl JointKind {
    /// The two bodies the joint joins.
    pub fn bodies(&self) -> [usize; 2] {
        match self {
            JointKind::Revolute { points } => [points[0].body, points[1].body],
            JointKind::Prismatic { slider, guide, .. } => [slider.body, guide.body],
        }
    }

    /// The point of the joint on `body`, if it joins it.
    pub fn point_on(&self, body: usize) -> Option<PointId> {
        match self {
            JointKind::Revolute { points } => points.iter().copied().find(|p| p.body == body),
            JointKind::Prismatic { slider, guide, .. } => {
                [*slider, *guide].into_iter().find(|p| p.body == body)
            }
        }
    }

    /// Whether it is a revolute joint.
    pub fn is_revolute(&self) -> bool {
        matches!(self, JointKind::Revolute { .. })
    }
}

/// A driver (`[[driver]]`): the motor element that makes a generalized coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct DriverSpec {
    /// The driven link (body index, ≥ 1).
    pub link: usize,
    /// The joint it is driven about (revolute: element R) or along (prismatic:
    /// element T), index in the joint list.
    pub joint: usize,
    /// Initial value of the coordinate: rad (element R, from `q0_deg`) or m (element T).
    pub q0: f64,
    /// `q0` as written: degrees for element R, m for element T (kept so that the
    /// conversion to radians is done in one place, bit for bit as the core's `deg`).
    pub q0_written: f64,
    /// Initial rate, rad/s or m/s.
    pub qd0: f64,
    /// Element R: link angle minus the coordinate, degrees.
    pub offset_deg: f64,
    /// Its motor model, if any.
    pub motor: Option<MotorSpec>,
}

/// A constant external load (`[[load]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadSpec {
    /// The loaded link (body index).
    pub link: usize,
    /// Point of application, link frame, m.
    pub at: [f64; 2],
    /// Force, world frame, N.
    pub force: [f64; 2],
    /// Moment, N·m, CCW positive.
    pub moment: f64,
}

/// A general mechanism.
#[derive(Clone, Debug, PartialEq)]
pub struct Mechanism {
    /// Gravity, m/s² (default `[0, -9.81]`).
    pub gravity: [f64; 2],
    /// Ground points.
    pub ground: Vec<GroundPoint>,
    /// Links (body `k + 1`).
    pub links: Vec<LinkSpec>,
    /// Joints.
    pub joints: Vec<JointSpec>,
    /// Drivers, in coordinate order (`q1`, `q2`, ...).
    pub drivers: Vec<DriverSpec>,
    /// External loads.
    pub loads: Vec<LoadSpec>,
}

impl Mechanism {
    /// A body's name for messages: `ground` or the link's name.
    pub fn body_name(&self, body: usize) -> String {
        match body {
            0 => "ground".to_string(),
            b => self
                .links
                .get(b - 1)
                .map_or_else(|| format!("#{b}"), |l| format!("\"{}\"", l.name)),
        }
    }

    /// A point's reference as a file writes it (`A`, `crank.end`).
    pub fn point_name(&self, p: PointId) -> String {
        if p.body == 0 {
            return self
                .ground
                .get(p.point)
                .map_or_else(|| format!("ground.{}", p.point), |g| g.name.clone());
        }
        match self.links.get(p.body - 1) {
            Some(l) => format!(
                "{}.{}",
                l.name,
                l.point_names
                    .get(p.point)
                    .cloned()
                    .unwrap_or_else(|| p.point.to_string())
            ),
            None => format!("#{}.{}", p.body, p.point),
        }
    }
}

/// A motor model (the core's [`Motor`] variants that a file can describe).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MotorSpec {
    /// Constant torque, N·m (force, N, on a motor element T).
    Constant(f64),
    /// The asynchronous motor's parabola through (breakdown speed, breakdown torque),
    /// (rated speed, rated torque), (synchronous speed, 0) (thesis eq. 5.24-5.27).
    Asynchronous {
        /// ω_min, rpm.
        breakdown_rpm: f64,
        /// T_max, N·m.
        breakdown_torque: f64,
        /// ω_n, rpm.
        rated_rpm: f64,
        /// T_n, N·m.
        rated_torque: f64,
        /// ω_s, rpm.
        synchronous_rpm: f64,
    },
    /// `T(ω) = a + b ω + c ω²` with ω in rad/s.
    Polynomial {
        /// N·m.
        a: f64,
        /// N·m·s/rad.
        b: f64,
        /// N·m·s²/rad².
        c: f64,
    },
}

impl MotorSpec {
    /// The core's motor law in scalar `T`. The asynchronous motor is built exactly as
    /// the core's slider-crank builds it (`Asynchronous::through(rpm(..), ..)` in `T`),
    /// so that a file describes it bit for bit.
    pub fn motor<T: Real>(&self) -> Result<Motor<T>, ModelError> {
        let c = T::c;
        Ok(match *self {
            MotorSpec::Constant(t) => Motor::Constant(c(t)),
            MotorSpec::Asynchronous {
                breakdown_rpm,
                breakdown_torque,
                rated_rpm,
                rated_torque,
                synchronous_rpm,
            } => Motor::Asynchronous(Asynchronous::through(
                rpm(c(breakdown_rpm)),
                c(breakdown_torque),
                rpm(c(rated_rpm)),
                c(rated_torque),
                rpm(c(synchronous_rpm)),
            )?),
            MotorSpec::Polynomial { a, b, c: cc } => Motor::Asynchronous(Asynchronous {
                a: c(a),
                b: c(b),
                c: c(cc),
            }),
        })
    }
}

impl MotorSpec {
    /// The coefficients `(a, b, c)` of a quadratic characteristic `T(ω) = a + bω + cω²`
    /// (ω in rad/s, computed in `f64`); `None` for a constant torque.
    pub fn quadratic(&self) -> Option<(f64, f64, f64)> {
        match self.motor::<f64>() {
            Ok(Motor::Asynchronous(q)) => Some((q.a, q.b, q.c)),
            _ => None,
        }
    }

    /// The speeds the characteristic is meant for, `[0, ω_r]` rad/s: from standstill up
    /// to the speed `ω_r = -b / 2c` past which a parabola with `c > 0` rises again
    /// (unbounded when `c <= 0`). Between an asynchronous motor's `ω_s` and `ω_r` the
    /// parabola brakes, as the motor does as a generator; past `ω_r` the torque grows
    /// with speed and the motor runs away. `None` for a constant torque.
    pub fn working_zone(&self) -> Option<(f64, f64)> {
        let (_, b, c) = self.quadratic()?;
        let rising = if c > 0.0 {
            -b / (2.0 * c)
        } else {
            f64::INFINITY
        };
        Some((0.0, rising.max(0.0)))
    }

    /// The set-up warning of a characteristic that turns up again past a speed (`c > 0`):
    /// a motor driven past it gets more torque the faster it turns and runs away.
    pub fn warning(&self) -> Option<String> {
        let (_, b, c) = self.quadratic()?;
        (c > 0.0).then(|| {
            let w = -b / (2.0 * c);
            format!(
                "the characteristic {} rises again past ω = {} rad/s ({} rpm): driven past \
                 it, the motor gets more torque the faster it turns and runs away",
                characteristic(self.quadratic().map_or(0.0, |q| q.0), b, c),
                Sci(w),
                Sci(w * 60.0 / std::f64::consts::TAU)
            )
        })
    }
}

impl fmt::Display for MotorSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MotorSpec::Constant(t) => write!(f, "{t} N·m"),
            MotorSpec::Asynchronous {
                breakdown_rpm,
                breakdown_torque,
                rated_rpm,
                rated_torque,
                synchronous_rpm,
            } => write!(
                f,
                "asynchronous ({breakdown_torque} N·m at {breakdown_rpm} rpm, {rated_torque} N·m at {rated_rpm} rpm, synchronous {synchronous_rpm} rpm)"
            ),
            MotorSpec::Polynomial { a, b, c } => {
                write!(f, "T(ω) = {a} + {b} ω + {c} ω² N·m")
            }
        }
    }
}

/// The converter (`[converter]` and the converter keys of `[run]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Converter {
    /// Every parameter of the twin (SPEC 3).
    pub params: CccParams<f64>,
    /// Initial crank angle q1, degrees (default 105, SPEC 3).
    pub crank_deg: f64,
    /// Initial swing-link angle q2, degrees (default 90).
    pub swing_deg: f64,
    /// Initial crank speed, rad/s (default 0).
    pub crank_speed: f64,
    /// Initial swing-link speed, rad/s (default 0).
    pub swing_speed: f64,
    /// `converter.motor_offset`: added to a measured motor torque (a bench log's,
    /// `host-sim replay`), N·m, CCW positive (default 0): a current sensor's offset.
    pub motor_offset: f64,
    /// `run.mode`: `true` with the diode's clutches, `false` in free mode.
    pub clutch: bool,
    /// `run.motor`: the motor on the crank.
    pub motor: MotorSpec,
    /// `run.load`: load torque T_r on the shaft, N·m (≥ 0; 0 in free mode).
    pub load: f64,
}

impl Converter {
    /// The parameters in scalar `T` (each value converted once, as the core's
    /// `CccParams::reference` does).
    pub fn params<T: Real>(&self) -> CccParams<T> {
        let p = &self.params;
        let v = |v: Vec2<f64>| Vec2::new(T::c(v.x), T::c(v.y));
        let c = T::c;
        CccParams {
            a: v(p.a),
            f: v(p.f),
            h: v(p.h),
            links: p.links.map(|b| Bar {
                length: c(b.length),
                mass: c(b.mass),
                inertia: c(b.inertia),
            }),
            rocker_d: c(p.rocker_d),
            mass: c(p.mass),
            mass_inertia: c(p.mass_inertia),
            mass_at: c(p.mass_at),
            shaft_inertia: c(p.shaft_inertia),
            friction: Friction {
                viscous: p.friction.viscous.map(c),
                coulomb: p.friction.coulomb.map(c),
                coulomb_eps: c(p.friction.coulomb_eps),
                clutch_drag: c(p.friction.clutch_drag),
            },
            drive: p.drive,
            gravity: v(p.gravity),
            branch_c: p.branch_c,
            branch_g: p.branch_g,
            branch_i: p.branch_i,
        }
    }
}

// ---------------------------------------------------------------------------------
// Raw structures: what serde reads. Unknown keys are errors that list the allowed ones.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    name: Option<String>,
    description: Option<String>,
    gravity: Option<[f64; 2]>,
    #[serde(default)]
    ground: Vec<RawGround>,
    #[serde(default)]
    link: Vec<RawLink>,
    #[serde(default)]
    joint: Vec<RawJoint>,
    #[serde(default)]
    driver: Vec<RawDriver>,
    #[serde(default)]
    load: Vec<RawLoad>,
    converter: Option<RawConverter>,
    run: RawRun,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGround {
    name: String,
    at: [f64; 2],
}

#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "a distance along the bar from its start, m, or a point [x, y] in the link frame, m"
)]
enum RawCog {
    Along(f64),
    At([f64; 2]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLink {
    name: String,
    length: Option<f64>,
    #[serde(default)]
    points: BTreeMap<String, [f64; 2]>,
    mass: f64,
    inertia: f64,
    cog: Option<RawCog>,
    angle_deg: Option<f64>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum RawJointType {
    Revolute,
    Prismatic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawJoint {
    name: Option<String>,
    #[serde(rename = "type")]
    kind: RawJointType,
    points: Option<[String; 2]>,
    slider: Option<String>,
    guide: Option<String>,
    guide_angle_deg: Option<f64>,
    slider_angle_deg: Option<f64>,
    offset: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDriver {
    link: String,
    joint: String,
    q0_deg: Option<f64>,
    q0: Option<f64>,
    qd0: Option<f64>,
    offset_deg: Option<f64>,
    motor: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    link: String,
    at: Option<[f64; 2]>,
    force: Option<[f64; 2]>,
    moment: Option<f64>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawDrive {
    Cw,
    Ccw,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawSide {
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
struct RawBar {
    length: f64,
    mass: f64,
    inertia: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConverter {
    a: [f64; 2],
    f: [f64; 2],
    h: [f64; 2],
    link: Vec<RawBar>,
    rocker_d: f64,
    mass: f64,
    mass_inertia: f64,
    mass_at: f64,
    shaft_inertia: f64,
    friction: Option<RawFriction>,
    drive: RawDrive,
    gravity: [f64; 2],
    branch_c: RawSide,
    branch_g: RawSide,
    branch_i: RawSide,
    crank_deg: Option<f64>,
    swing_deg: Option<f64>,
    crank_speed: Option<f64>,
    swing_speed: Option<f64>,
    motor_offset: Option<f64>,
}

/// `[converter.friction]`: the losses of a real machine (SPEC 5), each 0 when absent.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFriction {
    viscous: Option<RawJoints>,
    coulomb: Option<RawJoints>,
    coulomb_eps: Option<f64>,
    clutch_drag: Option<f64>,
}

/// A coefficient per revolute joint of the converter, by SPEC's letter
/// ([`FRICTION_JOINT_NAMES`]); the levers' joints at H are the clutches.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawJoints {
    A: Option<f64>,
    B: Option<f64>,
    C: Option<f64>,
    E: Option<f64>,
    F: Option<f64>,
    D5: Option<f64>,
    D7: Option<f64>,
    G: Option<f64>,
    I: Option<f64>,
}

impl RawJoints {
    /// In [`FRICTION_JOINT_NAMES`]' order, absent ones `None`.
    fn values(&self) -> [Option<f64>; 9] {
        [
            self.A, self.B, self.C, self.E, self.F, self.D5, self.D7, self.G, self.I,
        ]
    }
}

/// The friction of `[converter.friction]`, validated: every coefficient finite and
/// non-negative, ε positive; errors name the key (`converter.friction.viscous.A`).
fn friction_of(ck: &Check<'_>, raw: Option<&RawFriction>) -> Result<Friction<f64>, FileError> {
    let mut f = Friction::<f64>::none();
    let Some(raw) = raw else {
        return Ok(f);
    };
    for (table, kind, out) in [
        (&raw.viscous, "viscous", &mut f.viscous),
        (&raw.coulomb, "coulomb", &mut f.coulomb),
    ] {
        let Some(joints) = table else {
            continue;
        };
        for ((slot, value), name) in out
            .iter_mut()
            .zip(joints.values())
            .zip(FRICTION_JOINT_NAMES)
        {
            if let Some(v) = value {
                *slot = ck.non_negative(&format!("converter.friction.{kind}.{name}"), v)?;
            }
        }
    }
    if let Some(v) = raw.clutch_drag {
        f.clutch_drag = ck.non_negative("converter.friction.clutch_drag", v)?;
    }
    if let Some(v) = raw.coulomb_eps {
        f.coulomb_eps = ck.positive("converter.friction.coulomb_eps", v)?;
    }
    Ok(f)
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum RawMode {
    Clutch,
    Free,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum RawIntegrator {
    Dp5,
    Adaptive,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRun {
    h: f64,
    t_end: f64,
    every: Option<u64>,
    f32: Option<bool>,
    integrator: Option<RawIntegrator>,
    rtol: Option<f64>,
    atol: Option<f64>,
    h_max: Option<f64>,
    mode: Option<RawMode>,
    motor: Option<toml::Value>,
    load: Option<f64>,
}

// ---------------------------------------------------------------------------------
// Entry points.

/// Parses and validates a run file's text; `origin` names it in errors (a path, or
/// `ccc-s2.toml` for a built-in). Errors of the toml syntax and of the keys' types carry
/// the line and column.
pub fn parse_run_file(text: &str, origin: &str) -> Result<RunFile, FileError> {
    let raw: RawFile = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
    validate(raw, origin)
}

/// Validates a run file given as a [`toml::Value`] tree: what a parameter sweep calls
/// after setting dotted keys (`converter.mass = 40`, `run.motor = 10`) in the tree of
/// [`parse_value`]. Errors name the key path (no line numbers: a tree has none).
pub fn run_file_from_value(value: toml::Value, origin: &str) -> Result<RunFile, FileError> {
    let raw: RawFile = value
        .try_into()
        .map_err(|e: toml::de::Error| toml_error(&e, "", origin))?;
    validate(raw, origin)
}

/// The toml tree of a file's text (syntax checked, values not yet): a sweep edits it
/// and hands it to [`run_file_from_value`].
pub fn parse_value(text: &str, origin: &str) -> Result<toml::Value, FileError> {
    text.parse::<toml::Table>()
        .map(toml::Value::Table)
        .map_err(|e| toml_error(&e, text, origin))
}

/// Writes `value` at the dotted `key` of a run file's tree (from [`parse_value`]),
/// creating the tables on its way: `converter.mass` is `tree[converter][mass]`; a segment that is a number selects that element (from 0) of an
/// array. Errors name the key and the segment.
pub fn set_dotted(tree: &mut toml::Value, key: &str, value: toml::Value) -> Result<(), String> {
    match tree {
        toml::Value::Table(root) => set_dotted_in(root, key, value),
        other => Err(format!(
            "key '{key}': the file is a {}, not a table",
            other.type_str()
        )),
    }
}

/// [`set_dotted`] in a tree's root table.
pub fn set_dotted_in(root: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let segments: Vec<&str> = key.split('.').collect();
    if segments.iter().any(|s| s.trim().is_empty()) {
        return Err(format!("key '{key}': an empty segment"));
    }
    let Some((last, path)) = segments.split_last() else {
        return Err(format!("key '{key}': empty"));
    };
    let mut here = Node::Table(root);
    for (k, seg) in path.iter().enumerate() {
        let so_far = segments[..=k].join(".");
        here = match here {
            Node::Table(t) => {
                let next = t
                    .entry(seg.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                Node::of(next, &so_far, key)?
            }
            Node::Array(a) => {
                let n = a.len();
                let next = index(seg, n).and_then(|i| a.get_mut(i)).ok_or_else(|| {
                    format!("key '{key}': '{so_far}' is out of the array of {n} elements")
                })?;
                Node::of(next, &so_far, key)?
            }
        };
    }
    match here {
        Node::Table(t) => {
            t.insert(last.to_string(), value);
        }
        Node::Array(a) => {
            let n = a.len();
            let slot = index(last, n).and_then(|i| a.get_mut(i)).ok_or_else(|| {
                format!("key '{key}': '{last}' is out of the array of {n} elements")
            })?;
            *slot = value;
        }
    }
    Ok(())
}

enum Node<'a> {
    Table(&'a mut toml::Table),
    Array(&'a mut Vec<toml::Value>),
}

impl<'a> Node<'a> {
    fn of(v: &'a mut toml::Value, so_far: &str, key: &str) -> Result<Node<'a>, String> {
        match v {
            toml::Value::Table(t) => Ok(Node::Table(t)),
            toml::Value::Array(a) => Ok(Node::Array(a)),
            other => Err(format!(
                "key '{key}': '{so_far}' is a {}, not a table",
                other.type_str()
            )),
        }
    }
}

fn index(seg: &str, len: usize) -> Option<usize> {
    seg.parse::<usize>().ok().filter(|i| *i < len)
}

fn one_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// A toml error with its line and column (from its byte span into `text`; none for a
/// tree's error) and its key path.
pub(crate) fn toml_error(e: &toml::de::Error, text: &str, origin: &str) -> FileError {
    let position = e.span().filter(|_| !text.is_empty()).map(|s| {
        let before = text.get(..s.start.min(text.len())).unwrap_or("");
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        (line, col)
    });
    // The key path: the error's Display gives it ("in `link.mass`") when it has no
    // input text to quote (the toml crate keeps the keys private).
    let mut bare = e.clone();
    bare.set_input(None);
    let shown = bare.to_string();
    let field = shown
        .lines()
        .find_map(|l| l.trim().strip_prefix("in `")?.strip_suffix('`'))
        .unwrap_or("")
        .to_string();
    FileError {
        origin: origin.to_string(),
        position,
        field,
        message: one_line(e.message()),
    }
}

// ---------------------------------------------------------------------------------
// Validation.

/// The message for a link name that is not one of `links`.
fn unknown_link(name: &str, links: &[LinkSpec]) -> String {
    format!(
        "unknown link \"{name}\" (links: {})",
        list(links.iter().map(|l| l.name.as_str()))
    )
}

struct Check<'a> {
    origin: &'a str,
}

impl Check<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> FileError {
        FileError {
            origin: self.origin.to_string(),
            position: None,
            field: field.into(),
            message: message.into(),
        }
    }

    fn finite(&self, field: &str, x: f64) -> Result<f64, FileError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, format!("must be finite, got {x}")))
        }
    }

    fn positive(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, format!("must be > 0, got {x}")))
        }
    }

    fn non_negative(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x >= 0.0 {
            // -0 is 0.
            Ok(x + 0.0)
        } else {
            Err(self.err(field, format!("must be >= 0, got {x}")))
        }
    }

    /// A load (N·m or N): finite and below [`MAX_LOAD`] in magnitude.
    fn load(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.below(
            field,
            x,
            MAX_LOAD,
            "",
            "the energy and clutch tolerances lose their meaning",
        )
    }

    /// The converter's load torque T_r (N·m): finite and below [`MAX_CONVERTER_LOAD`].
    fn converter_load(&self, field: &str, x: f64) -> Result<f64, FileError> {
        self.below(
            field,
            x,
            MAX_CONVERTER_LOAD,
            " N·m",
            "the clutch tolerance 1e-9 (T_r + 1 N·m) lets a locked lever hold a negative torque past 1e-3 N·m and releases it late",
        )
    }

    /// `x` finite and below `bound` in magnitude, else an error saying `why` (`unit`
    /// follows the numbers).
    fn below(
        &self,
        field: &str,
        x: f64,
        bound: f64,
        unit: &str,
        why: &str,
    ) -> Result<f64, FileError> {
        self.finite(field, x)?;
        if x.abs() < bound {
            Ok(x)
        } else {
            Err(self.err(
                field,
                format!(
                    "{}{unit} is too large: from {}{unit} on {why}",
                    Sci(x),
                    Sci(bound)
                ),
            ))
        }
    }

    fn vec2(&self, field: &str, v: [f64; 2]) -> Result<[f64; 2], FileError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(self.err(field, format!("must be finite, got [{}, {}]", v[0], v[1])))
        }
    }
}

/// `[run] integrator` and its tolerances: `rtol`, `atol`, `h_max` only with
/// `"adaptive"` (defaults 1e-9, 1e-9 and 10·h).
fn integrator(ck: &Check<'_>, r: &RawRun) -> Result<Integrator, FileError> {
    let tolerances = [("rtol", r.rtol), ("atol", r.atol), ("h_max", r.h_max)];
    match r.integrator.unwrap_or(RawIntegrator::Dp5) {
        RawIntegrator::Dp5 => match tolerances.iter().find(|t| t.1.is_some()) {
            Some((key, _)) => Err(ck.err(
                format!("run.{key}"),
                "only with integrator = \"adaptive\" (the fixed-step dp5 steps by h)",
            )),
            None => Ok(Integrator::Dp5),
        },
        RawIntegrator::Adaptive => Ok(Integrator::Adaptive {
            rtol: ck.positive("run.rtol", r.rtol.unwrap_or(1e-9))?,
            atol: ck.positive("run.atol", r.atol.unwrap_or(1e-9))?,
            h_max: ck.positive("run.h_max", r.h_max.unwrap_or(10.0 * r.h))?,
        }),
    }
}

fn validate(raw: RawFile, origin: &str) -> Result<RunFile, FileError> {
    let ck = Check { origin };
    let r = &raw.run;
    let run = RunSettings {
        h: ck.positive("run.h", r.h)?,
        t_end: ck.positive("run.t_end", r.t_end)?,
        every: match r.every {
            Some(0) => return Err(ck.err("run.every", "must be at least 1, got 0")),
            Some(n) => n,
            None => 1,
        },
        f32: r.f32.unwrap_or(false),
        integrator: integrator(&ck, r)?,
    };
    let mechanism_keys = [
        ("gravity", raw.gravity.is_some()),
        ("ground", !raw.ground.is_empty()),
        ("link", !raw.link.is_empty()),
        ("joint", !raw.joint.is_empty()),
        ("driver", !raw.driver.is_empty()),
        ("load", !raw.load.is_empty()),
    ];
    let body = match raw.converter {
        Some(c) => {
            if let Some((key, _)) = mechanism_keys.iter().find(|(_, given)| *given) {
                return Err(ck.err(
                    *key,
                    "not in a converter file ([converter] describes the whole mechanism)",
                ));
            }
            if run.integrator != Integrator::Dp5 {
                return Err(ck.err(
                    "run.integrator",
                    "the converter's twin steps with a fixed h, as in firmware: only \"dp5\"",
                ));
            }
            Body::Converter(Box::new(converter(&ck, c, &raw.run)?))
        }
        None => {
            for (key, given) in [
                ("run.mode", r.mode.is_some()),
                ("run.motor", r.motor.is_some()),
                ("run.load", r.load.is_some()),
            ] {
                if given {
                    return Err(ck.err(
                        key,
                        "only in a converter file (a mechanism's motors are in [[driver]])",
                    ));
                }
            }
            Body::Mechanism(mechanism(
                &ck,
                raw.gravity,
                raw.ground,
                raw.link,
                raw.joint,
                raw.driver,
                raw.load,
            )?)
        }
    };
    Ok(RunFile {
        name: raw.name,
        description: raw.description,
        body,
        run,
    })
}

fn converter(ck: &Check<'_>, c: RawConverter, run: &RawRun) -> Result<Converter, FileError> {
    if c.link.len() != 8 {
        return Err(ck.err(
            "converter.link",
            format!(
                "needs the 8 bars of SPEC 3 in order (crank, coupler, rocker, swing link, rod 5, lever 6, rod 7, lever 8), got {}",
                c.link.len()
            ),
        ));
    }
    let mut links = [Bar {
        length: 1.0,
        mass: 0.0,
        inertia: 0.0,
    }; 8];
    for (k, (slot, b)) in links.iter_mut().zip(&c.link).enumerate() {
        let f = |key: &str| format!("converter.link[{}] (link {}).{key}", k, k + 1);
        *slot = Bar {
            length: ck.positive(&f("length"), b.length)?,
            mass: ck.positive(&f("mass"), b.mass)?,
            inertia: ck.non_negative(&f("inertia"), b.inertia)?,
        };
    }
    let v = |field: &str, p: [f64; 2]| ck.vec2(field, p).map(|p| Vec2::new(p[0], p[1]));
    let params = CccParams {
        a: v("converter.a", c.a)?,
        f: v("converter.f", c.f)?,
        h: v("converter.h", c.h)?,
        links,
        rocker_d: ck.positive("converter.rocker_d", c.rocker_d)?,
        mass: ck.non_negative("converter.mass", c.mass)?,
        mass_inertia: ck.non_negative("converter.mass_inertia", c.mass_inertia)?,
        mass_at: ck.non_negative("converter.mass_at", c.mass_at)?,
        shaft_inertia: ck.non_negative("converter.shaft_inertia", c.shaft_inertia)?,
        friction: friction_of(ck, c.friction.as_ref())?,
        drive: match c.drive {
            RawDrive::Cw => DriveDirection::Cw,
            RawDrive::Ccw => DriveDirection::Ccw,
        },
        gravity: v("converter.gravity", c.gravity)?,
        branch_c: c.branch_c.into(),
        branch_g: c.branch_g.into(),
        branch_i: c.branch_i.into(),
    };
    // What the core checks beyond these (overflow of the size squared): its message.
    params
        .validate()
        .map_err(|e| ck.err("converter", e.to_string()))?;
    let clutch = run.mode.unwrap_or(RawMode::Clutch) == RawMode::Clutch;
    let load = match run.load {
        Some(l) if !clutch && l != 0.0 => {
            return Err(ck.err(
                "run.load",
                "free mode has no clutch, so no shaft load (use mode = \"clutch\")",
            ))
        }
        Some(l) => ck.converter_load("run.load", ck.non_negative("run.load", l)?)?,
        None => 0.0,
    };
    let motor = match &run.motor {
        Some(m) => motor(ck, "run.motor", m)?,
        None => {
            return Err(ck.err(
                "run.motor",
                "missing (the motor on the crank: a torque in N·m, or a motor table)",
            ))
        }
    };
    Ok(Converter {
        params,
        crank_deg: ck.finite("converter.crank_deg", c.crank_deg.unwrap_or(105.0))?,
        swing_deg: ck.finite("converter.swing_deg", c.swing_deg.unwrap_or(90.0))?,
        crank_speed: ck.finite("converter.crank_speed", c.crank_speed.unwrap_or(0.0))?,
        swing_speed: ck.finite("converter.swing_speed", c.swing_speed.unwrap_or(0.0))?,
        motor_offset: ck.finite("converter.motor_offset", c.motor_offset.unwrap_or(0.0))?,
        clutch,
        motor,
        load,
    })
}

/// The motor keys by type, for messages.
const MOTOR_KEYS: [(&str, &[&str]); 3] = [
    ("constant", &["type", "torque"]),
    (
        "asynchronous",
        &[
            "type",
            "breakdown_rpm",
            "breakdown_torque",
            "rated_rpm",
            "rated_torque",
            "synchronous_rpm",
        ],
    ),
    ("polynomial", &["type", "a", "b", "c"]),
];

/// A motor: a number (constant torque, N·m) or a table with `type`.
fn motor(ck: &Check<'_>, field: &str, v: &toml::Value) -> Result<MotorSpec, FileError> {
    let num = |key: &str, v: Option<&toml::Value>| -> Result<f64, FileError> {
        let f = format!("{field}.{key}");
        match v {
            Some(toml::Value::Float(x)) => ck.finite(&f, *x),
            Some(toml::Value::Integer(i)) => Ok(*i as f64),
            Some(other) => Err(ck.err(f, format!("must be a number, got {}", other.type_str()))),
            None => Err(ck.err(f, "missing")),
        }
    };
    let t = match v {
        toml::Value::Float(_) | toml::Value::Integer(_) => {
            return Ok(MotorSpec::Constant(num("torque", Some(v)).map_err(|mut e| {
                e.field = field.to_string();
                e
            })?))
        }
        toml::Value::Table(t) => t,
        other => {
            return Err(ck.err(
                field,
                format!(
                    "must be a torque in N·m or a table with type = \"constant\" | \"asynchronous\" | \"polynomial\", got {}",
                    other.type_str()
                ),
            ))
        }
    };
    let kind = match t.get("type") {
        Some(toml::Value::String(s)) => s.as_str(),
        Some(other) => {
            return Err(ck.err(
                format!("{field}.type"),
                format!("must be a string, got {}", other.type_str()),
            ))
        }
        None => {
            return Err(ck.err(
                format!("{field}.type"),
                "missing (constant, asynchronous or polynomial)",
            ))
        }
    };
    let Some((_, keys)) = MOTOR_KEYS.iter().find(|(k, _)| *k == kind) else {
        return Err(ck.err(
            format!("{field}.type"),
            format!("unknown motor type \"{kind}\" (known: constant, asynchronous, polynomial)"),
        ));
    };
    if let Some(k) = t.keys().find(|k| !keys.contains(&k.as_str())) {
        return Err(ck.err(
            format!("{field}.{k}"),
            format!(
                "unknown key for a {kind} motor (allowed: {})",
                keys.join(", ")
            ),
        ));
    }
    let g = |key: &str| num(key, t.get(key));
    Ok(match kind {
        "constant" => MotorSpec::Constant(g("torque")?),
        "asynchronous" => {
            let m = MotorSpec::Asynchronous {
                breakdown_rpm: g("breakdown_rpm")?,
                breakdown_torque: g("breakdown_torque")?,
                rated_rpm: g("rated_rpm")?,
                rated_torque: g("rated_torque")?,
                synchronous_rpm: g("synchronous_rpm")?,
            };
            if let MotorSpec::Asynchronous {
                breakdown_rpm: a,
                rated_rpm: b,
                synchronous_rpm: c,
                ..
            } = m
            {
                if !(0.0 <= a && a < b && b < c) {
                    return Err(ck.err(
                        field,
                        format!("needs 0 <= breakdown_rpm < rated_rpm < synchronous_rpm, got {a}, {b}, {c}"),
                    ));
                }
            }
            m.motor::<f64>().map_err(|e| ck.err(field, e.to_string()))?;
            starts(ck, field, m)?
        }
        _ => starts(
            ck,
            field,
            MotorSpec::Polynomial {
                a: g("a")?,
                b: g("b")?,
                c: g("c")?,
            },
        )?,
    })
}

/// `T(ω) = a + bω + cω²` for messages: `T(ω) = 12.6 - 2.61014 ω + 0.121585 ω² N·m`.
fn characteristic(a: f64, b: f64, c: f64) -> String {
    let term = |x: f64| format!("{} {}", if x < 0.0 { '-' } else { '+' }, Sci(x.abs()));
    format!("T(ω) = {} {} ω {} ω² N·m", Sci(a), term(b), term(c))
}

/// A quadratic characteristic must give a torque `T(0) ≥ 0` at standstill: with
/// `T(0) < 0` the motor cannot start; it turns backward, down the parabola's other
/// branch, until its torque is no longer finite.
fn starts(ck: &Check<'_>, field: &str, m: MotorSpec) -> Result<MotorSpec, FileError> {
    match m.quadratic() {
        Some((a, b, c)) if a < 0.0 => Err(ck.err(
            field,
            format!(
                "the characteristic {} gives T(0) = {} N·m < 0 at standstill: the motor \
                 cannot start; check its speeds and torques",
                characteristic(a, b, c),
                Sci(a)
            ),
        )),
        _ => Ok(m),
    }
}

/// Names: not empty, no `.` (it separates a link from its point in references).
fn check_name(ck: &Check<'_>, field: &str, name: &str) -> Result<(), FileError> {
    if name.is_empty() {
        return Err(ck.err(field, "must not be empty"));
    }
    if name.contains('.') {
        return Err(ck.err(
            field,
            format!("\"{name}\": a name must not contain '.' (it separates a link from its point)"),
        ));
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn mechanism(
    ck: &Check<'_>,
    gravity: Option<[f64; 2]>,
    raw_ground: Vec<RawGround>,
    raw_links: Vec<RawLink>,
    raw_joints: Vec<RawJoint>,
    raw_drivers: Vec<RawDriver>,
    raw_loads: Vec<RawLoad>,
) -> Result<Mechanism, FileError> {
    let gravity = ck.vec2("gravity", gravity.unwrap_or([0.0, -9.81]))?;
    if raw_links.is_empty() {
        return Err(ck.err("link", "missing: a mechanism needs at least one [[link]]"));
    }
    if raw_links.len() > MAX_LINKS {
        return Err(ck.err(
            "link",
            format!(
                "{} links, the core holds at most {MAX_LINKS}",
                raw_links.len()
            ),
        ));
    }
    if raw_ground.len() > MAX_GROUND_POINTS {
        return Err(ck.err(
            "ground",
            format!(
                "{} ground points, the core holds at most {MAX_GROUND_POINTS}",
                raw_ground.len()
            ),
        ));
    }
    // Names: one namespace for ground points and links (a reference `X` is a ground
    // point, `X.p` a link's point).
    let mut names: BTreeMap<String, String> = BTreeMap::new();
    let mut declare = |field: String, name: &str| -> Result<(), FileError> {
        check_name(ck, &field, name)?;
        if let Some(first) = names.get(name) {
            return Err(ck.err(
                field,
                format!("duplicate name \"{name}\" (already used by {first})"),
            ));
        }
        names.insert(name.to_string(), field);
        Ok(())
    };
    let mut ground = Vec::new();
    for (k, g) in raw_ground.into_iter().enumerate() {
        declare(format!("ground[{k}].name"), &g.name)?;
        let at = ck.vec2(&format!("ground \"{}\".at", g.name), g.at)?;
        ground.push(GroundPoint { name: g.name, at });
    }
    let mut links = Vec::new();
    for (k, l) in raw_links.into_iter().enumerate() {
        declare(format!("link[{k}].name"), &l.name)?;
        let f = |key: &str| format!("link \"{}\".{key}", l.name);
        let mass = ck.non_negative(&f("mass"), l.mass)?;
        let inertia = ck.non_negative(&f("inertia"), l.inertia)?;
        let (mut points, mut point_names) = match l.length {
            Some(len) => {
                let len = ck.positive(&f("length"), len)?;
                (
                    vec![[0.0, 0.0], [len, 0.0]],
                    vec!["start".to_string(), "end".to_string()],
                )
            }
            None => (vec![[0.0, 0.0]], vec!["origin".to_string()]),
        };
        for (name, p) in &l.points {
            let pf = f(&format!("points.{name}"));
            check_name(ck, &pf, name)?;
            if point_names.iter().any(|n| n == name) || name.parse::<usize>().is_ok() {
                return Err(ck.err(
                    pf,
                    format!("\"{name}\" is reserved (start, end, origin and numbers name the built-in points and indices)"),
                ));
            }
            points.push(ck.vec2(&pf, *p)?);
            point_names.push(name.clone());
        }
        if points.len() > MAX_LINK_POINTS {
            return Err(ck.err(
                f("points"),
                format!(
                    "{} points on the link, the core holds at most {MAX_LINK_POINTS}",
                    points.len()
                ),
            ));
        }
        let cog = match (l.cog, l.length) {
            (Some(RawCog::Along(d)), Some(_)) => [ck.finite(&f("cog"), d)?, 0.0],
            (Some(RawCog::Along(_)), None) => return Err(ck.err(
                f("cog"),
                "a distance along the bar needs `length`; give [x, y] for a link without length",
            )),
            (Some(RawCog::At(p)), _) => ck.vec2(&f("cog"), p)?,
            // The midpoint of a bar (SPEC: bars have their COG at the midpoint), the
            // origin of a block.
            (None, Some(len)) => [0.5 * len, 0.0],
            (None, None) => [0.0, 0.0],
        };
        let angle_deg = ck.finite(&f("angle_deg"), l.angle_deg.unwrap_or(0.0))?;
        links.push(LinkSpec {
            name: l.name,
            points,
            point_names,
            mass,
            inertia,
            cog,
            angle_deg,
        });
    }
    let body_of = |name: &str| links.iter().position(|l| l.name == name).map(|k| k + 1);
    // A point reference: `G` (ground point G) or `link.point` (`start`, `end`,
    // `origin`, a named point, or an index).
    let point = |field: &str, r: &str| -> Result<PointId, FileError> {
        match r.split_once('.') {
            None => match ground.iter().position(|g| g.name == r) {
                Some(point) => Ok(PointId { body: 0, point }),
                None if body_of(r).is_some() => Err(ck.err(
                    field,
                    format!("\"{r}\" is a link: name one of its points, e.g. \"{r}.start\""),
                )),
                None => Err(ck.err(
                    field,
                    format!(
                        "unknown point \"{r}\" (ground points: {}; a link's point is written link.point)",
                        list(ground.iter().map(|g| g.name.as_str()))
                    ),
                )),
            },
            Some((link, p)) => {
                let Some(body) = body_of(link) else {
                    return Err(ck.err(
                        field,
                        format!(
                            "unknown link \"{link}\" in \"{r}\" (links: {})",
                            list(links.iter().map(|l| l.name.as_str()))
                        ),
                    ));
                };
                let l = &links[body - 1];
                let point = l
                    .point_names
                    .iter()
                    .position(|n| n == p)
                    .or_else(|| p.parse::<usize>().ok().filter(|&i| i < l.points.len()));
                match point {
                    Some(point) => Ok(PointId { body, point }),
                    None => Err(ck.err(
                        field,
                        format!(
                            "link \"{link}\" has no point \"{p}\" (its points: {}, or 0..{})",
                            list(l.point_names.iter().map(String::as_str)),
                            l.points.len() - 1
                        ),
                    )),
                }
            }
        }
    };
    let mut joints: Vec<JointSpec> = Vec::new();
    for (k, j) in raw_joints.into_iter().enumerate() {
        let name = j.name.clone().unwrap_or_else(|| format!("J{}", k + 1));
        let jf = format!("joint \"{name}\"");
        check_name(ck, &format!("{jf}.name"), &name)?;
        if joints.iter().any(|o| o.name == name) {
            return Err(ck.err(
                format!("{jf}.name"),
                format!("duplicate joint name \"{name}\""),
            ));
        }
        let f = |key: &str| format!("{jf}.{key}");
        let kind = match j.kind {
            RawJointType::Revolute => {
                for (key, given) in [
                    ("slider", j.slider.is_some()),
                    ("guide", j.guide.is_some()),
                    ("guide_angle_deg", j.guide_angle_deg.is_some()),
                    ("slider_angle_deg", j.slider_angle_deg.is_some()),
                    ("offset", j.offset.is_some()),
                ] {
                    if given {
                        return Err(ck.err(f(key), "only for a prismatic joint"));
                    }
                }
                let Some([p, q]) = &j.points else {
                    return Err(ck.err(
                        f("points"),
                        "missing: a revolute joint joins two points, points = [\"A\", \"crank.start\"]",
                    ));
                };
                let points = [point(&f("points"), p)?, point(&f("points"), q)?];
                if points[0].body == points[1].body {
                    return Err(ck.err(f("points"), "both points are on the same body"));
                }
                JointKind::Revolute { points }
            }
            RawJointType::Prismatic => {
                if j.points.is_some() {
                    return Err(ck.err(
                        f("points"),
                        "only for a revolute joint (a prismatic joint has slider and guide)",
                    ));
                }
                let (Some(s), Some(g)) = (&j.slider, &j.guide) else {
                    let missing = if j.slider.is_none() {
                        "slider"
                    } else {
                        "guide"
                    };
                    return Err(ck.err(
                        f(missing),
                        "missing: a prismatic joint needs slider and guide",
                    ));
                };
                let slider = point(&f("slider"), s)?;
                let guide = point(&f("guide"), g)?;
                if slider.body == guide.body {
                    return Err(ck.err(f("guide"), "slider and guide are on the same body"));
                }
                if slider.body == 0 {
                    return Err(ck.err(
                        f("slider"),
                        "the slider must be a link (the guide may be on the ground)",
                    ));
                }
                JointKind::Prismatic {
                    slider,
                    guide,
                    guide_angle_deg: ck
                        .finite(&f("guide_angle_deg"), j.guide_angle_deg.unwrap_or(0.0))?,
                    slider_angle_deg: ck
                        .finite(&f("slider_angle_deg"), j.slider_angle_deg.unwrap_or(0.0))?,
                    offset: ck.finite(&f("offset"), j.offset.unwrap_or(0.0))?,
                }
            }
        };
        joints.push(JointSpec { name, kind });
    }
    if raw_drivers.len() > MAX_DOF {
        return Err(ck.err(
            "driver",
            format!(
                "{} drivers, the core integrates at most {MAX_DOF} coordinates",
                raw_drivers.len()
            ),
        ));
    }
    let mut drivers: Vec<DriverSpec> = Vec::new();
    for (k, d) in raw_drivers.into_iter().enumerate() {
        let df = format!("driver[{k}]");
        let f = |key: &str| format!("{df}.{key}");
        let Some(link) = body_of(&d.link) else {
            return Err(ck.err(f("link"), unknown_link(&d.link, &links)));
        };
        let Some(joint) = joints.iter().position(|j| j.name == d.joint) else {
            return Err(ck.err(
                f("joint"),
                format!(
                    "unknown joint \"{}\" (joints: {})",
                    d.joint,
                    list(joints.iter().map(|j| j.name.as_str()))
                ),
            ));
        };
        let kind = joints[joint].kind;
        if !kind.bodies().contains(&link) {
            return Err(ck.err(
                f("joint"),
                format!("joint \"{}\" does not join link \"{}\"", d.joint, d.link),
            ));
        }
        if let JointKind::Prismatic { slider, .. } = kind {
            if slider.body != link {
                return Err(ck.err(
                    f("link"),
                    format!(
                        "a prismatic driver moves the joint's slider; \"{}\" is its guide",
                        d.link
                    ),
                ));
            }
        }
        if let Some(first) = drivers.iter().position(|o| o.link == link) {
            return Err(ck.err(
                f("link"),
                format!("link \"{}\" is already driven by driver[{first}]", d.link),
            ));
        }
        let (q0_written, q0) = if kind.is_revolute() {
            if d.q0.is_some() {
                return Err(ck.err(
                    f("q0"),
                    "a revolute driver's initial angle is q0_deg, degrees",
                ));
            }
            let Some(q) = d.q0_deg else {
                return Err(ck.err(f("q0_deg"), "missing (the initial angle, degrees)"));
            };
            let q = ck.finite(&f("q0_deg"), q)?;
            (q, q.to_radians())
        } else {
            if d.q0_deg.is_some() || d.offset_deg.is_some() {
                let key = if d.q0_deg.is_some() {
                    "q0_deg"
                } else {
                    "offset_deg"
                };
                return Err(ck.err(
                    f(key),
                    "only for a revolute driver (a prismatic driver's q0 is in m)",
                ));
            }
            let Some(q) = d.q0 else {
                return Err(ck.err(f("q0"), "missing (the initial offset along the guide, m)"));
            };
            let q = ck.finite(&f("q0"), q)?;
            (q, q)
        };
        let motor = match &d.motor {
            Some(m) => Some(motor(ck, &f("motor"), m)?),
            None => None,
        };
        drivers.push(DriverSpec {
            link,
            joint,
            q0,
            q0_written,
            qd0: ck.finite(&f("qd0"), d.qd0.unwrap_or(0.0))?,
            offset_deg: ck.finite(&f("offset_deg"), d.offset_deg.unwrap_or(0.0))?,
            motor,
        });
    }
    if raw_loads.len() > MAX_LOADS {
        return Err(ck.err(
            "load",
            format!(
                "{} loads, the core holds at most {MAX_LOADS}",
                raw_loads.len()
            ),
        ));
    }
    let mut loads = Vec::new();
    for (k, l) in raw_loads.into_iter().enumerate() {
        let f = |key: &str| format!("load[{k}].{key}");
        let Some(link) = body_of(&l.link) else {
            return Err(ck.err(f("link"), unknown_link(&l.link, &links)));
        };
        loads.push(LoadSpec {
            link,
            at: ck.vec2(&f("at"), l.at.unwrap_or([0.0, 0.0]))?,
            force: {
                let v = ck.vec2(&f("force"), l.force.unwrap_or([0.0, 0.0]))?;
                [ck.load(&f("force"), v[0])?, ck.load(&f("force"), v[1])?]
            },
            moment: ck.load(&f("moment"), l.moment.unwrap_or(0.0))?,
        });
    }
    Ok(Mechanism {
        gravity,
        ground,
        links,
        joints,
        drivers,
        loads,
    })
}

fn list<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}
