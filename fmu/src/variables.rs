//! The FMU's variables: one table ([`VARIABLES`]) that both the modelDescription.xml
//! ([`crate::description`]) and the C functions' value references
//! ([`crate::instance`]) are made from, and the start values ([`Start`]): SPEC 3's
//! reference converter under S2's inputs by default, or those `host-sim fmu` wrote
//! into the FMU's `resources/start.txt`.
//!
//! Value references: each type has its own, counted from 0 in table order (Real,
//! Integer and Boolean are separate spaces in FMI 2.0); a Real's reference is its
//! index in [`Start::reals`] and in the instance's store.

use core::fmt::Write as _;
use structomat::ccc::{CccParams, DriveDirection, Side};

/// The FMI 2.0 type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `fmi2Real` (f64).
    Real,
    /// `fmi2Integer` (i32).
    Integer,
    /// `fmi2Boolean` (i32: 0 or 1).
    Boolean,
}

/// What a variable is to the importer (its `causality`, and so its `variability`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A parameter fixed at initialization (`causality="parameter"
    /// variability="fixed"`): settable after `fmi2Instantiate` and in initialization
    /// mode, read by the twin when it is built.
    Parameter,
    /// An input held over each communication step (`causality="input"`).
    Input,
    /// An output of the twin's state (`causality="output"`, `initial="calculated"`).
    Output,
}

/// One variable of the FMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variable {
    /// Its name (FMI's structured naming: `link3.mass`, `audit.residual`).
    pub name: &'static str,
    /// Its type.
    pub kind: Kind,
    /// Parameter, input or output.
    pub role: Role,
    /// Its unit's name in the modelDescription's `UnitDefinitions` ("" for none).
    pub unit: &'static str,
    /// What it is.
    pub description: &'static str,
}

const fn var(
    name: &'static str,
    kind: Kind,
    role: Role,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        kind,
        role,
        unit,
        description,
    }
}

const fn par(name: &'static str, unit: &'static str, description: &'static str) -> Variable {
    var(name, Kind::Real, Role::Parameter, unit, description)
}

const fn out(name: &'static str, unit: &'static str, description: &'static str) -> Variable {
    var(name, Kind::Real, Role::Output, unit, description)
}

/// A link's three parameters (SPEC 3's numbering and names).
macro_rules! bar {
    ($p:literal, $what:literal) => {
        [
            par(
                concat!("link", $p, ".length"),
                "m",
                concat!("link ", $p, " (", $what, ") joint-to-joint length"),
            ),
            par(
                concat!("link", $p, ".mass"),
                "kg",
                concat!("link ", $p, " (", $what, ") mass (COG at its midpoint)"),
            ),
            par(
                concat!("link", $p, ".inertia"),
                "kg.m2",
                concat!(
                    "link ",
                    $p,
                    " (",
                    $what,
                    ") moment of inertia about its COG"
                ),
            ),
        ]
    };
}

/// The description of the `mode` output: its codes ([`structomat::ccc::Mode::code`])
/// and names.
pub const MODE_DESCRIPTION: &str = "the converter's mode (SPEC 3): 0 free (no clutch), \
1 I0 (shaft held, both levers overrunning), 2 I6 (shaft held, lever 6 locked), 3 I8 \
(shaft held, lever 8 locked), 4 jam (both levers locked), 5 A6 (shaft turning with lever \
6), 6 A8 (shaft turning with lever 8), 7 A68 (shaft turning with both levers), 8 coast \
(shaft turning with no lever: only with shaft inertia)";

const LINKS: [[Variable; 3]; 8] = [
    bar!(1, "crank A-B"),
    bar!(2, "coupler B-C"),
    bar!(3, "rocker E-C"),
    bar!(4, "swing link F-E"),
    bar!(5, "rod D-G"),
    bar!(6, "lever H-G"),
    bar!(7, "rod D-I"),
    bar!(8, "lever H-I"),
];

/// The Real variables before the links: the step and the pivots.
const HEAD: [Variable; 7] = [
    par(
        "h",
        "s",
        "the twin's fixed step; every communication step must be a whole multiple of it",
    ),
    par("A.x", "m", "crank pivot A, x"),
    par("A.y", "m", "crank pivot A, y"),
    par("F.x", "m", "swing-link pivot F, x"),
    par("F.y", "m", "swing-link pivot F, y"),
    par("H.x", "m", "output shaft H, x"),
    par("H.y", "m", "output shaft H, y"),
];

/// The losses of a real machine (SPEC 5; `CccParams::friction`, 0 by default): each
/// joint's viscous and dry coefficients, in `FRICTION_JOINTS`' order, then the dry
/// friction's regularization speed and the overrunning clutches' drag.
macro_rules! joint_friction {
    ($j:literal) => {
        [
            par(
                concat!("friction.viscous.", $j),
                "N.m.s/rad",
                concat!(
                    "viscous friction of joint ",
                    $j,
                    " on its relative angular speed"
                ),
            ),
            par(
                concat!("friction.coulomb.", $j),
                "N.m",
                concat!("dry (Coulomb) friction torque of joint ", $j),
            ),
        ]
    };
}

const JOINT_FRICTION: [[Variable; 2]; 9] = [
    joint_friction!("A"),
    joint_friction!("B"),
    joint_friction!("C"),
    joint_friction!("E"),
    joint_friction!("F"),
    joint_friction!("D5"),
    joint_friction!("D7"),
    joint_friction!("G"),
    joint_friction!("I"),
];

const FRICTION_TAIL: [Variable; 2] = [
    par(
        "friction.coulomb_eps",
        "rad/s",
        "the dry friction's regularization speed: under it a joint acts as a viscous one of coefficient coulomb/eps (> 0)",
    ),
    par(
        "friction.clutch_drag",
        "N.m.s/rad",
        "drag of an overrunning clutch on the lever's speed relative to the shaft",
    ),
];

/// The Real variables after the links: the rest of the converter, its initial
/// state, the inputs and the outputs.
const TAIL: [Variable; 25] = [
    par("rocker_d", "m", "D on the rocker, distance from E"),
    par("mass", "kg", "the oscillating mass on the rocker"),
    par(
        "mass_inertia",
        "kg.m2",
        "the oscillating mass's own moment of inertia",
    ),
    par(
        "mass_at",
        "m",
        "the oscillating mass's distance from E along the rocker",
    ),
    par("shaft_inertia", "kg.m2", "output shaft inertia J_s"),
    par("gravity.x", "m/s2", "gravity, x"),
    par("gravity.y", "m/s2", "gravity, y"),
    par("initial.crank_deg", "deg", "initial crank angle q1"),
    par("initial.swing_deg", "deg", "initial swing-link angle q2"),
    par("initial.crank_speed", "rad/s", "initial crank speed"),
    par("initial.swing_speed", "rad/s", "initial swing-link speed"),
    var(
        "motor_torque",
        Kind::Real,
        Role::Input,
        "N.m",
        "motor torque on the crank, CCW positive, held over the communication step",
    ),
    var(
        "load_torque",
        Kind::Real,
        Role::Input,
        "N.m",
        "load torque T_r >= 0 resisting the output shaft, held over the communication step",
    ),
    out("crank_angle", "rad", "crank angle theta1, CCW from x"),
    out("crank_speed", "rad/s", "crank speed omega1, CCW positive"),
    out(
        "shaft_angle",
        "rad",
        "output shaft angle turned since the start, CCW positive",
    ),
    out(
        "shaft_speed",
        "rad/s",
        "output shaft speed, CCW positive (0 while held)",
    ),
    out(
        "c6",
        "N.m",
        "torque transmitted by lever 6's clutch, positive in the drive direction",
    ),
    out(
        "c8",
        "N.m",
        "torque transmitted by lever 8's clutch, positive in the drive direction",
    ),
    out(
        "audit.kinetic",
        "J",
        "kinetic energy of the links and the shaft",
    ),
    out("audit.potential", "J", "potential energy (gravity)"),
    out(
        "audit.motor_work",
        "J",
        "work of the motor on the crank since the start",
    ),
    out(
        "audit.load_work",
        "J",
        "work done against the load on the shaft since the start",
    ),
    out(
        "audit.impact_loss",
        "J",
        "kinetic energy lost in plastic impacts since the start",
    ),
    out(
        "audit.residual",
        "J",
        "energy audit: motor work - (kinetic + potential - initial) - load work - impact losses",
    ),
];

/// The Integer and Boolean variables.
const DISCRETE: [Variable; 6] = [
    var("mode", Kind::Integer, Role::Output, "", MODE_DESCRIPTION),
    var(
        "clutch",
        Kind::Boolean,
        Role::Parameter,
        "",
        "with the diode's one-way clutches (false: SPEC 3's free mode, the levers swing freely)",
    ),
    var(
        "ccw",
        Kind::Boolean,
        Role::Parameter,
        "",
        "the output shaft turns counter-clockwise (false: clockwise, SPEC 3's reference)",
    ),
    var(
        "branch_c_left",
        Kind::Boolean,
        Role::Parameter,
        "",
        "assembly branch of C: left of B->E (false: right, the reference)",
    ),
    var(
        "branch_g_left",
        Kind::Boolean,
        Role::Parameter,
        "",
        "assembly branch of G: left of D->H (true: the reference)",
    ),
    var(
        "branch_i_left",
        Kind::Boolean,
        Role::Parameter,
        "",
        "assembly branch of I: left of D->H (false: right, the reference)",
    ),
];

/// Number of Real variables.
pub const N_REAL: usize =
    HEAD.len() + 3 * LINKS.len() + 2 * JOINT_FRICTION.len() + FRICTION_TAIL.len() + TAIL.len();
/// Number of Boolean variables.
pub const N_BOOL: usize = 5;

/// Every variable, in the modelDescription's order (Reals, then the mode, then the
/// Booleans).
pub const VARIABLES: [Variable; N_REAL + 1 + N_BOOL] = {
    let mut all = [HEAD[0]; N_REAL + 1 + N_BOOL];
    let mut k = 0;
    let mut i = 0;
    while i < HEAD.len() {
        all[k] = HEAD[i];
        k += 1;
        i += 1;
    }
    let mut p = 0;
    while p < LINKS.len() {
        let mut j = 0;
        while j < 3 {
            all[k] = LINKS[p][j];
            k += 1;
            j += 1;
        }
        p += 1;
    }
    p = 0;
    while p < JOINT_FRICTION.len() {
        all[k] = JOINT_FRICTION[p][0];
        k += 1;
        p += 1;
    }
    p = 0;
    while p < JOINT_FRICTION.len() {
        all[k] = JOINT_FRICTION[p][1];
        k += 1;
        p += 1;
    }
    i = 0;
    while i < FRICTION_TAIL.len() {
        all[k] = FRICTION_TAIL[i];
        k += 1;
        i += 1;
    }
    i = 0;
    while i < TAIL.len() {
        all[k] = TAIL[i];
        k += 1;
        i += 1;
    }
    i = 0;
    while i < DISCRETE.len() {
        all[k] = DISCRETE[i];
        k += 1;
        i += 1;
    }
    all
};

/// The Real value references by meaning.
pub mod vr {
    /// The step h.
    pub const H: u32 = 0;
    /// A.x (A.y, F.x, F.y, H.x, H.y follow).
    pub const A_X: u32 = 1;
    /// link1.length; link p's (length, mass, inertia) are at `LINK + 3 (p - 1) + 0..3`.
    pub const LINK: u32 = 7;
    /// friction.viscous.A: joint k's viscous coefficient (`FRICTION_JOINTS`' order) at
    /// `FRICTION + k`, its dry one at `FRICTION + 9 + k`; coulomb_eps at `FRICTION + 18`,
    /// clutch_drag at `FRICTION + 19`.
    pub const FRICTION: u32 = LINK + 24;
    /// rocker_d.
    pub const ROCKER_D: u32 = FRICTION + 20;
    /// mass.
    pub const MASS: u32 = ROCKER_D + 1;
    /// mass_inertia.
    pub const MASS_INERTIA: u32 = ROCKER_D + 2;
    /// mass_at.
    pub const MASS_AT: u32 = ROCKER_D + 3;
    /// shaft_inertia.
    pub const SHAFT_INERTIA: u32 = ROCKER_D + 4;
    /// gravity.x (gravity.y follows).
    pub const GRAVITY_X: u32 = ROCKER_D + 5;
    /// initial.crank_deg.
    pub const CRANK_DEG: u32 = ROCKER_D + 7;
    /// initial.swing_deg.
    pub const SWING_DEG: u32 = ROCKER_D + 8;
    /// initial.crank_speed.
    pub const CRANK_SPEED0: u32 = ROCKER_D + 9;
    /// initial.swing_speed.
    pub const SWING_SPEED0: u32 = ROCKER_D + 10;
    /// The input motor_torque.
    pub const MOTOR: u32 = ROCKER_D + 11;
    /// The input load_torque.
    pub const LOAD: u32 = ROCKER_D + 12;
    /// The first output (crank_angle); the outputs run to the last Real.
    pub const FIRST_OUTPUT: u32 = ROCKER_D + 13;
    /// The Integer output mode.
    pub const MODE: u32 = 0;
    /// The Booleans: clutch, ccw, branch_c_left, branch_g_left, branch_i_left.
    pub const CLUTCH: u32 = 0;
    /// ccw.
    pub const CCW: u32 = 1;
    /// branch_c_left (branch_g_left, branch_i_left follow).
    pub const BRANCH_C: u32 = 2;
}

/// The value reference of `VARIABLES[index]` (its index among the variables of its
/// type).
pub fn value_reference(index: usize) -> u32 {
    let Some(v) = VARIABLES.get(index) else {
        return u32::MAX;
    };
    VARIABLES[..index]
        .iter()
        .filter(|w| w.kind == v.kind)
        .count() as u32
}

/// The variable of type `kind` with value reference `r`, and its index in
/// [`VARIABLES`].
pub fn lookup(kind: Kind, r: u32) -> Option<(usize, &'static Variable)> {
    VARIABLES
        .iter()
        .enumerate()
        .filter(|(_, v)| v.kind == kind)
        .nth(r as usize)
}

/// The variable named `name`, and its index in [`VARIABLES`].
pub fn by_name(name: &str) -> Option<(usize, &'static Variable)> {
    VARIABLES.iter().enumerate().find(|(_, v)| v.name == name)
}

/// The start values of the parameters and inputs (the outputs' slots unused): what
/// `fmi2Instantiate` and `fmi2Reset` set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    /// The Reals by value reference.
    pub reals: [f64; N_REAL],
    /// The Booleans by value reference.
    pub bools: [bool; N_BOOL],
}

impl Default for Start {
    /// SPEC 3's reference converter from its initial state (q1 = 105°, q2 = 90°, at
    /// rest) with the clutches, h = 1e-4 s, under S2's inputs (12 N·m on the crank,
    /// T_r = 800 N·m).
    fn default() -> Self {
        let mut s = Start {
            reals: [0.0; N_REAL],
            bools: [true, false, false, true, false],
        };
        s.set_params(&CccParams::reference());
        s.reals[vr::H as usize] = 1e-4;
        s.reals[vr::CRANK_DEG as usize] = 105.0;
        s.reals[vr::SWING_DEG as usize] = 90.0;
        s.reals[vr::MOTOR as usize] = 12.0;
        s.reals[vr::LOAD as usize] = 800.0;
        s
    }
}

impl Start {
    /// Sets the converter's parameters (the drive and the branches too) from `p`.
    pub fn set_params(&mut self, p: &CccParams<f64>) {
        let r = &mut self.reals;
        let a = vr::A_X as usize;
        r[a..a + 6].copy_from_slice(&[p.a.x, p.a.y, p.f.x, p.f.y, p.h.x, p.h.y]);
        for (k, b) in p.links.iter().enumerate() {
            let i = vr::LINK as usize + 3 * k;
            r[i..i + 3].copy_from_slice(&[b.length, b.mass, b.inertia]);
        }
        let f = vr::FRICTION as usize;
        r[f..f + 9].copy_from_slice(&p.friction.viscous);
        r[f + 9..f + 18].copy_from_slice(&p.friction.coulomb);
        r[f + 18] = p.friction.coulomb_eps;
        r[f + 19] = p.friction.clutch_drag;
        r[vr::ROCKER_D as usize] = p.rocker_d;
        r[vr::MASS as usize] = p.mass;
        r[vr::MASS_INERTIA as usize] = p.mass_inertia;
        r[vr::MASS_AT as usize] = p.mass_at;
        r[vr::SHAFT_INERTIA as usize] = p.shaft_inertia;
        r[vr::GRAVITY_X as usize] = p.gravity.x;
        r[vr::GRAVITY_X as usize + 1] = p.gravity.y;
        let b = vr::BRANCH_C as usize;
        self.bools[vr::CCW as usize] = p.drive == DriveDirection::Ccw;
        self.bools[b] = p.branch_c == Side::Left;
        self.bools[b + 1] = p.branch_g == Side::Left;
        self.bools[b + 2] = p.branch_i == Side::Left;
    }

    /// The converter's parameters of these values.
    pub fn params(&self) -> CccParams<f64> {
        let r = &self.reals;
        let at = |v: u32| r[v as usize];
        let v2 = |v: u32| structomat::scalar::Vec2::new(at(v), at(v + 1));
        let side = |left: bool| if left { Side::Left } else { Side::Right };
        let mut p = CccParams::<f64>::reference();
        p.a = v2(vr::A_X);
        p.f = v2(vr::A_X + 2);
        p.h = v2(vr::A_X + 4);
        for (k, b) in p.links.iter_mut().enumerate() {
            let i = vr::LINK + 3 * k as u32;
            b.length = at(i);
            b.mass = at(i + 1);
            b.inertia = at(i + 2);
        }
        let f = vr::FRICTION as usize;
        p.friction.viscous.copy_from_slice(&r[f..f + 9]);
        p.friction.coulomb.copy_from_slice(&r[f + 9..f + 18]);
        p.friction.coulomb_eps = at(vr::FRICTION + 18);
        p.friction.clutch_drag = at(vr::FRICTION + 19);
        p.rocker_d = at(vr::ROCKER_D);
        p.mass = at(vr::MASS);
        p.mass_inertia = at(vr::MASS_INERTIA);
        p.mass_at = at(vr::MASS_AT);
        p.shaft_inertia = at(vr::SHAFT_INERTIA);
        p.gravity = v2(vr::GRAVITY_X);
        p.drive = if self.bools[vr::CCW as usize] {
            DriveDirection::Ccw
        } else {
            DriveDirection::Cw
        };
        let b = vr::BRANCH_C as usize;
        p.branch_c = side(self.bools[b]);
        p.branch_g = side(self.bools[b + 1]);
        p.branch_i = side(self.bools[b + 2]);
        p
    }

    /// The start value of variable `index` of [`VARIABLES`] as the modelDescription
    /// writes it (`None` for an output: it has none). Reals in Rust's shortest
    /// round-trip form, so the XML and `start.txt` give back the same bits.
    pub fn text(&self, index: usize) -> Option<String> {
        let v = VARIABLES.get(index)?;
        let r = value_reference(index) as usize;
        match (v.role, v.kind) {
            (Role::Output, _) => None,
            (_, Kind::Real) => Some(real_text(self.reals[r])),
            (_, Kind::Boolean) => Some(self.bools[r].to_string()),
            (_, Kind::Integer) => None,
        }
    }

    /// The `resources/start.txt` of these values for the FMU of GUID `guid`: a line
    /// `name = value` for each parameter and input.
    pub fn file_text(&self, guid: &str) -> String {
        let mut s = String::from(
            "# The start values of this FMU's parameters and inputs (as in its\n\
             # modelDescription.xml), read by fmi2Instantiate and fmi2Reset.\n",
        );
        let _ = writeln!(s, "guid = {guid}");
        for (k, v) in VARIABLES.iter().enumerate() {
            if let Some(t) = self.text(k) {
                let _ = writeln!(s, "{} = {t}", v.name);
            }
        }
        s
    }

    /// The values of a `start.txt` over the defaults, and its GUID. Errors name the
    /// line and the variable.
    pub fn parse(text: &str) -> Result<(Start, Option<String>), String> {
        let mut s = Start::default();
        let mut guid = None;
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let at = |what: String| format!("start.txt line {}: {what}", n + 1);
            let Some((name, value)) = line.split_once('=') else {
                return Err(at(format!("'{line}' is not 'name = value'")));
            };
            let (name, value) = (name.trim(), value.trim());
            if name == "guid" {
                guid = Some(value.to_string());
                continue;
            }
            let Some((k, v)) = by_name(name).filter(|(_, v)| v.role != Role::Output) else {
                return Err(at(format!("'{name}' is no parameter or input of this FMU")));
            };
            let r = value_reference(k) as usize;
            match v.kind {
                Kind::Real => {
                    let x: f64 = value
                        .parse()
                        .map_err(|_| at(format!("{name} = '{value}' is not a number")))?;
                    if !x.is_finite() {
                        return Err(at(format!("{name} = {value} is not finite")));
                    }
                    s.reals[r] = x;
                }
                Kind::Boolean => {
                    s.bools[r] = match value {
                        "true" => true,
                        "false" => false,
                        _ => return Err(at(format!("{name} = '{value}' is not true or false"))),
                    }
                }
                Kind::Integer => return Err(at(format!("'{name}' has no start value"))),
            }
        }
        Ok((s, guid))
    }
}

/// A Real in Rust's shortest round-trip form (`1e-4` as `0.0001`, `-9.81`).
pub fn real_text(x: f64) -> String {
    format!("{x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    // The named references point at the variables they name.
    #[test]
    fn references_match_the_table() {
        let real = |r: u32| lookup(Kind::Real, r).map(|(_, v)| v.name);
        assert_eq!(real(vr::H), Some("h"));
        assert_eq!(real(vr::A_X), Some("A.x"));
        assert_eq!(real(vr::LINK), Some("link1.length"));
        assert_eq!(real(vr::LINK + 3 * 7 + 2), Some("link8.inertia"));
        // The joints' friction in the core's joint order, named by SPEC's letters.
        for (k, j) in structomat::ccc::FRICTION_JOINT_NAMES.iter().enumerate() {
            let viscous = format!("friction.viscous.{j}");
            let coulomb = format!("friction.coulomb.{j}");
            assert_eq!(real(vr::FRICTION + k as u32), Some(viscous.as_str()));
            assert_eq!(real(vr::FRICTION + 9 + k as u32), Some(coulomb.as_str()));
        }
        assert_eq!(real(vr::FRICTION + 18), Some("friction.coulomb_eps"));
        assert_eq!(real(vr::FRICTION + 19), Some("friction.clutch_drag"));
        assert_eq!(real(vr::ROCKER_D), Some("rocker_d"));
        assert_eq!(real(vr::GRAVITY_X + 1), Some("gravity.y"));
        assert_eq!(real(vr::SWING_SPEED0), Some("initial.swing_speed"));
        assert_eq!(real(vr::MOTOR), Some("motor_torque"));
        assert_eq!(real(vr::LOAD), Some("load_torque"));
        assert_eq!(real(vr::FIRST_OUTPUT), Some("crank_angle"));
        assert_eq!(real(N_REAL as u32 - 1), Some("audit.residual"));
        assert_eq!(real(N_REAL as u32), None);
        assert_eq!(
            lookup(Kind::Integer, vr::MODE).map(|v| v.1.name),
            Some("mode")
        );
        assert_eq!(
            lookup(Kind::Boolean, vr::BRANCH_C + 2).map(|v| v.1.name),
            Some("branch_i_left")
        );
        let outputs = VARIABLES.iter().filter(|v| v.kind == Kind::Real);
        for (k, v) in outputs.enumerate() {
            assert_eq!(
                v.role == Role::Output,
                k >= vr::FIRST_OUTPUT as usize,
                "{}",
                v.name
            );
        }
        let mut names: Vec<_> = VARIABLES.iter().map(|v| v.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), VARIABLES.len(), "names are unique");
    }

    // The defaults are the core's reference converter, and start.txt gives back the
    // same bits.
    #[test]
    fn start_values_round_trip() {
        let s = Start::default();
        assert_eq!(s.params(), CccParams::reference());
        let text = s.file_text("{x}");
        let (back, guid) = Start::parse(&text).unwrap();
        assert_eq!(back, s);
        assert_eq!(guid.as_deref(), Some("{x}"));
        // A machine's losses, every coefficient its own value, go there and back.
        let mut p = CccParams::<f64>::reference();
        for k in 0..9 {
            p.friction.viscous[k] = 0.01 * (k + 1) as f64;
            p.friction.coulomb[k] = 0.1 + 0.01 * k as f64;
        }
        p.friction.coulomb_eps = 0.02;
        p.friction.clutch_drag = 0.05;
        let mut f = Start::default();
        f.set_params(&p);
        assert_eq!(f.params(), p);
        let (back, _) = Start::parse(&f.file_text("{y}")).unwrap();
        assert_eq!(back.params(), p);
        let e = Start::parse("mass = NaN").unwrap_err();
        assert!(e.contains("line 1") && e.contains("mass"), "{e}");
        let e = Start::parse("\ncrank_angle = 1").unwrap_err();
        assert!(e.contains("line 2") && e.contains("crank_angle"), "{e}");
        let e = Start::parse("clutch = yes").unwrap_err();
        assert!(e.contains("clutch"), "{e}");
    }
}
