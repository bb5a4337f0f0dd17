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

/// The converter's load torque T_r (N·m) from which on a run is refused: the core's
/// limit (a twin's step refuses it too; see its docs for why).
pub use structomat::ccc::MAX_CONVERTER_LOAD;

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
    /// `run.spread_events`: each event's work spread over the steps after it, as a
    /// firmware twin that must keep its worst step within the loop's period does
    /// (`TwinSettings::spread_events`; default false).
    pub spread_events: bool,
}

/// Why `command` (`replay`, `identify`) refuses the converter `name` whose run file sets
/// `run.spread_events`: it pairs the twin's state with the log's sample of the same
/// time, and a twin that spreads its events lags the log's clock after each.
pub fn spreading_refused(name: &str, command: &str) -> String {
    format!(
        "{name}: run.spread_events = true: {command} pairs the twin with the log sample by \
         sample, and a twin that spreads its events lags the log's clock after each \
         (remove the key to {command})"
    )
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

mod raw;
mod validate;

use raw::RawFile;

// ---------------------------------------------------------------------------------
// Entry points.

/// Parses and validates a run file's text; `origin` names it in errors (a path, or
/// `ccc-s2.toml` for a built-in). Errors of the toml syntax and of the keys' types carry
/// the line and column.
pub fn parse_run_file(text: &str, origin: &str) -> Result<RunFile, FileError> {
    let raw: RawFile = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
    validate::validate(raw, origin)
}

/// Validates a run file given as a [`toml::Value`] tree: what a parameter sweep calls
/// after setting dotted keys (`converter.mass = 40`, `run.motor = 10`) in the tree of
/// [`parse_value`]. Errors name the key path (no line numbers: a tree has none).
pub fn run_file_from_value(value: toml::Value, origin: &str) -> Result<RunFile, FileError> {
    let raw: RawFile = value
        .try_into()
        .map_err(|e: toml::de::Error| toml_error(&e, "", origin))?;
    validate::validate(raw, origin)
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

/// `T(ω) = a + bω + cω²` for messages: `T(ω) = 12.6 - 2.61014 ω + 0.121585 ω² N·m`.
fn characteristic(a: f64, b: f64, c: f64) -> String {
    let term = |x: f64| format!("{} {}", if x < 0.0 { '-' } else { '+' }, Sci(x.abs()));
    format!("T(ω) = {} {} ω {} ω² N·m", Sci(a), term(b), term(c))
}
