//! The converter's parameters (SPEC 3): the reference geometry by default, every value
//! changeable, validated once by [`CccParams::validate`].

use crate::error::ModelError;
use crate::scalar::{Real, Vec2};

/// Which way the output shaft turns (SPEC 3: the reference converter turns clockwise).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveDirection {
    /// Clockwise: lever 8 drives while D moves away from H, lever 6 while it comes
    /// closer.
    Cw,
    /// Counter-clockwise: the mirror roles.
    Ccw,
}

impl DriveDirection {
    /// `+1` for CCW, `-1` for CW: multiplies a CCW-positive angular quantity into "in the
    /// drive direction".
    pub fn sign<T: Real>(self) -> T {
        match self {
            DriveDirection::Cw => -T::one(),
            DriveDirection::Ccw => T::one(),
        }
    }
}

/// An assembly branch: on which side of the directed line from a group's first pole to
/// its second the joint sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Left of the line (CCW side).
    Left,
    /// Right of the line.
    Right,
}

/// Length (m), mass (kg) and moment of inertia about the COG (kg·m²) of a bar whose COG
/// is at its midpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar<T> {
    /// Joint-to-joint length, m.
    pub length: T,
    /// Mass, kg.
    pub mass: T,
    /// Moment of inertia about the COG, kg·m².
    pub inertia: T,
}

/// The converter (SPEC 3, thesis tables 8-9). Physical links, numbered as in SPEC:
/// 1 crank A→B, 2 coupler B→C, 3 rocker E→C (D on it), 4 swing link F→E, 5 and 7 the
/// diode rods D→G and D→I, 6 and 8 the diode levers H→G and H→I (H: the output shaft).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CccParams<T> {
    /// Crank pivot A, m.
    pub a: Vec2<T>,
    /// Swing-link pivot F, m.
    pub f: Vec2<T>,
    /// Output shaft H, m.
    pub h: Vec2<T>,
    /// Links 1..8 (index 0 is link 1). Each bar's own COG is at its midpoint.
    pub links: [Bar<T>; 8],
    /// Distance from E to D along the rocker, m (SPEC: its midpoint).
    pub rocker_d: T,
    /// The oscillating mass, kg.
    pub mass: T,
    /// Its own moment of inertia, kg·m².
    pub mass_inertia: T,
    /// Its distance from E along the rocker, m (SPEC: at C, the rocker's end).
    pub mass_at: T,
    /// Output shaft inertia J_s, kg·m² (SPEC: 0, the thesis has none).
    pub shaft_inertia: T,
    /// The losses of a real machine (SPEC 5): joint friction and clutch drag, all 0 by
    /// default (SPEC's ideal machine).
    pub friction: Friction<T>,
    /// The direction the shaft turns.
    pub drive: DriveDirection,
    /// Gravity, m/s².
    pub gravity: Vec2<T>,
    /// Branch of C: side of B→E (reference: right, C with the larger x).
    pub branch_c: Side,
    /// Branch of G: side of D→H (reference: left, G above line DH).
    pub branch_g: Side,
    /// Branch of I: side of D→H (reference: right, I below line DH).
    pub branch_i: Side,
}

impl<T: Real> CccParams<T> {
    /// SPEC 3's reference converter, shaft turning clockwise.
    pub fn reference() -> Self {
        let c = T::c;
        let bar = |length: f64, mass: f64, inertia: f64| Bar {
            length: c(length),
            mass: c(mass),
            inertia: c(inertia),
        };
        CccParams {
            a: Vec2::new(c(0.0), c(0.0)),
            f: Vec2::new(c(0.20), c(0.50)),
            h: Vec2::new(c(1.10), c(0.0)),
            links: [
                bar(0.075, 0.688, 0.0010),
                bar(0.350, 2.888, 0.0330),
                bar(0.700, 5.462, 0.2390),
                bar(0.100, 0.888, 0.0010),
                bar(0.650, 5.288, 0.1960),
                bar(0.300, 2.488, 0.0220),
                bar(0.650, 5.288, 0.1960),
                bar(0.300, 2.488, 0.0220),
            ],
            rocker_d: c(0.350),
            mass: c(6.0),
            mass_inertia: c(0.0400),
            mass_at: c(0.700),
            shaft_inertia: c(0.0),
            friction: Friction::none(),
            drive: DriveDirection::Cw,
            gravity: Vec2::new(c(0.0), c(-9.81)),
            branch_c: Side::Right,
            branch_g: Side::Left,
            branch_i: Side::Right,
        }
    }

    /// Link `p` (1..=8).
    pub fn link(&self, p: usize) -> Bar<T> {
        self.links.get(p.wrapping_sub(1)).copied().unwrap_or(Bar {
            length: T::one(),
            mass: T::zero(),
            inertia: T::zero(),
        })
    }

    /// Moment of inertia of lever `p` (6 or 8) about the shaft H, kg·m² (bar with its
    /// COG at its midpoint).
    pub fn lever_inertia_about_h(&self, p: usize) -> T {
        let b = self.link(p);
        let r = b.length * T::c(0.5);
        b.inertia + b.mass * r * r
    }

    /// Checks every value: finite, lengths and masses positive, inertias non-negative,
    /// D and the mass on the rocker; and that the converter's size, squared, and its
    /// weights times its size do not overflow the scalar (the assembly squares lengths,
    /// the audit multiplies weights by heights). Errors name the link (SPEC numbering).
    pub fn validate(&self) -> Result<(), ModelError> {
        let fin = |x: T, what| {
            if x.finite() {
                Ok(())
            } else {
                Err(ModelError::NonFinite(what))
            }
        };
        for (p, what) in [
            (self.a, "crank pivot A"),
            (self.f, "swing-link pivot F"),
            (self.h, "output shaft H"),
            (self.gravity, "gravity"),
        ] {
            fin(p.x, what)?;
            fin(p.y, what)?;
        }
        for (b, [length, mass, inertia]) in self.links.iter().zip(LINK_FIELDS.iter()) {
            fin(b.length, length)?;
            fin(b.mass, mass)?;
            fin(b.inertia, inertia)?;
            if !(b.length > T::zero()) {
                return Err(ModelError::NotPositive(length));
            }
            if !(b.mass > T::zero()) {
                return Err(ModelError::NotPositive(mass));
            }
            if b.inertia < T::zero() {
                return Err(ModelError::Negative(inertia));
            }
        }
        for (x, what) in [
            (self.rocker_d, "D on the rocker"),
            (self.mass, "oscillating mass"),
            (self.mass_inertia, "oscillating mass inertia"),
            (self.mass_at, "oscillating mass position"),
            (self.shaft_inertia, "shaft inertia"),
        ] {
            fin(x, what)?;
            if x < T::zero() {
                return Err(ModelError::Negative(what));
            }
        }
        self.friction.validate()?;
        if !(self.rocker_d > T::zero()) {
            return Err(ModelError::NotPositive("D on the rocker"));
        }
        // Every joint lies within the pivots' spread plus the sum of the lengths.
        let mut size = self.rocker_d + self.mass_at;
        for p in [self.a, self.f, self.h] {
            size += p.x.abs() + p.y.abs();
        }
        for b in self.links.iter() {
            size += b.length;
        }
        let size = T::c(2.0) * size;
        if !(size * size).finite() {
            return Err(ModelError::Overflow("its size squared"));
        }
        let g = self.gravity.x.abs() + self.gravity.y.abs();
        let total_mass = self.links.iter().fold(self.mass, |m, b| m + b.mass);
        if !(total_mass * g * size + total_mass * size * size).finite() {
            return Err(ModelError::Overflow("its masses times its size (energies)"));
        }
        let inertias = self
            .links
            .iter()
            .fold(self.mass_inertia + self.shaft_inertia, |i, b| i + b.inertia);
        if !inertias.finite() {
            return Err(ModelError::Overflow("the sum of its inertias"));
        }
        Ok(())
    }
}

/// The converter's revolute joints that carry joint friction, as `(i, j)`: link `i`
/// turns on link `j` (0: the ground), its relative speed `ω_i − ω_j`. SPEC's letters
/// ([`FRICTION_JOINT_NAMES`]): A, B, C, E, F, D (rod 5), D (rod 7), G, I. The levers'
/// joints at H are the one-way clutches: their loss is the clutch drag.
pub const FRICTION_JOINTS: [(u8, u8); 9] = [
    (1, 0),
    (2, 1),
    (3, 2),
    (3, 4),
    (4, 0),
    (5, 3),
    (7, 3),
    (6, 5),
    (8, 7),
];

/// SPEC's letters for [`FRICTION_JOINTS`] (as the joint reactions' names).
pub const FRICTION_JOINT_NAMES: [&str; 9] = ["A", "B", "C", "E", "F", "D5", "D7", "G", "I"];

/// The losses of a real machine (SPEC 5), 0 by default. At each revolute joint of
/// [`FRICTION_JOINTS`], of relative speed `w` (rad/s), the torque on its link `i` is
/// `-(viscous·w + coulomb·w/√(w² + ε²))` and the opposite on link `j` (none on the
/// ground); an overrunning (free) lever `k` feels `-clutch_drag·(ω_k − ω_shaft)` and
/// the shaft the opposite (a held shaft: the brake takes it). An engaged or locked
/// clutch has no slip and no drag.
///
/// The dry friction is regularized: `w/√(w² + ε²)` stands for `sgn(w)`, with
/// `ε = coulomb_eps` (rad/s) the relative speed under which the joint behaves as a
/// viscous one of coefficient `coulomb/ε`. Its errors: a joint that should stick under a
/// torque `T` below `coulomb` creeps at `w = ε·T/√(coulomb² − T²)`; one sliding at `w`
/// gets `coulomb·(1 − |w|/√(w² + ε²)) ≤ coulomb·ε²/(2w²)` less than `coulomb`. The
/// regularization's stiffness `coulomb/ε` must stay within the explicit integrator's
/// reach: `h·coulomb/(ε·J) ≲ 3` with `J` the smallest inertia the joint's speed sees
/// (a smaller `ε` makes the twin redo its steps in sub-steps, then fail).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction<T> {
    /// Viscous coefficient of each joint of [`FRICTION_JOINTS`], N·m·s/rad.
    pub viscous: [T; 9],
    /// Dry (Coulomb) friction torque of each joint of [`FRICTION_JOINTS`], N·m.
    pub coulomb: [T; 9],
    /// The dry friction's regularization speed ε, rad/s (> 0).
    pub coulomb_eps: T,
    /// The overrunning clutches' drag coefficient, N·m·s/rad.
    pub clutch_drag: T,
}

impl<T: Real> Friction<T> {
    /// No losses: SPEC's ideal machine (ε at its default, 0.01 rad/s).
    pub fn none() -> Self {
        Friction {
            viscous: [T::zero(); 9],
            coulomb: [T::zero(); 9],
            coulomb_eps: T::c(0.01),
            clutch_drag: T::zero(),
        }
    }

    /// Whether any loss is on: with none the twin skips every friction term (the same
    /// bits as a machine without the field).
    pub fn active(&self) -> bool {
        let on = |x: &T| *x != T::zero();
        self.clutch_drag != T::zero() || self.viscous.iter().any(on) || self.coulomb.iter().any(on)
    }

    /// The torque a joint of viscous coefficient `c` and dry friction `mu` applies
    /// against its relative speed `w` (the torque on its link `i` is minus this), N·m.
    pub fn joint_torque(&self, c: T, mu: T, w: T) -> T {
        let mut tau = c * w;
        if mu != T::zero() {
            tau += mu * w / (w * w + self.coulomb_eps * self.coulomb_eps).sqrt();
        }
        tau
    }

    /// Every coefficient finite and non-negative, ε positive; errors name the
    /// coefficient by its run-file key.
    pub fn validate(&self) -> Result<(), ModelError> {
        let check = |x: T, what: &'static str| {
            if !x.finite() {
                Err(ModelError::NonFinite(what))
            } else if x < T::zero() {
                Err(ModelError::Negative(what))
            } else {
                Ok(())
            }
        };
        for (k, (c, mu)) in self.viscous.iter().zip(self.coulomb.iter()).enumerate() {
            let names = FRICTION_KEYS
                .get(k)
                .copied()
                .unwrap_or(["friction", "friction"]);
            check(*c, names[0])?;
            check(*mu, names[1])?;
        }
        check(self.clutch_drag, "converter.friction.clutch_drag")?;
        check(self.coulomb_eps, "converter.friction.coulomb_eps")?;
        if !(self.coulomb_eps > T::zero()) {
            return Err(ModelError::NotPositive("converter.friction.coulomb_eps"));
        }
        Ok(())
    }
}

/// The run-file keys of each joint's viscous and dry coefficients, for errors.
const FRICTION_KEYS: [[&str; 2]; 9] = [
    [
        "converter.friction.viscous.A",
        "converter.friction.coulomb.A",
    ],
    [
        "converter.friction.viscous.B",
        "converter.friction.coulomb.B",
    ],
    [
        "converter.friction.viscous.C",
        "converter.friction.coulomb.C",
    ],
    [
        "converter.friction.viscous.E",
        "converter.friction.coulomb.E",
    ],
    [
        "converter.friction.viscous.F",
        "converter.friction.coulomb.F",
    ],
    [
        "converter.friction.viscous.D5",
        "converter.friction.coulomb.D5",
    ],
    [
        "converter.friction.viscous.D7",
        "converter.friction.coulomb.D7",
    ],
    [
        "converter.friction.viscous.G",
        "converter.friction.coulomb.G",
    ],
    [
        "converter.friction.viscous.I",
        "converter.friction.coulomb.I",
    ],
];

/// The names of each link's length, mass and inertia in errors (SPEC 3's numbering).
const LINK_FIELDS: [[&str; 3]; 8] = [
    [
        "link 1 (crank) length",
        "link 1 (crank) mass",
        "link 1 (crank) inertia",
    ],
    [
        "link 2 (coupler) length",
        "link 2 (coupler) mass",
        "link 2 (coupler) inertia",
    ],
    [
        "link 3 (rocker) length",
        "link 3 (rocker) mass",
        "link 3 (rocker) inertia",
    ],
    [
        "link 4 (swing link) length",
        "link 4 (swing link) mass",
        "link 4 (swing link) inertia",
    ],
    [
        "link 5 (rod to G) length",
        "link 5 (rod to G) mass",
        "link 5 (rod to G) inertia",
    ],
    [
        "link 6 (lever 6) length",
        "link 6 (lever 6) mass",
        "link 6 (lever 6) inertia",
    ],
    [
        "link 7 (rod to I) length",
        "link 7 (rod to I) mass",
        "link 7 (rod to I) inertia",
    ],
    [
        "link 8 (lever 8) length",
        "link 8 (lever 8) mass",
        "link 8 (lever 8) inertia",
    ],
];

/// The intersection of circle(`p`, `rp`) and circle(`q`, `rq`) on side `side` of p→q;
/// `None` if they do not meet.
pub(crate) fn circle_meet<T: Real>(
    p: Vec2<T>,
    rp: T,
    q: Vec2<T>,
    rq: T,
    side: Side,
) -> Option<Vec2<T>> {
    let d = q - p;
    let dd = d.norm_squared();
    if !(dd > T::zero()) {
        return None;
    }
    let a = (rp * rp - rq * rq + dd) / (T::c(2.0) * dd);
    let h2 = rp * rp / dd - a * a;
    if !(h2 >= T::zero()) {
        return None;
    }
    let n = Vec2::new(-d.y, d.x) * h2.sqrt();
    let s = match side {
        Side::Left => T::one(),
        Side::Right => -T::one(),
    };
    Some(p + d * a + n * s)
}
