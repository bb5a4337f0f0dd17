//! Structomats: the kinematic groups a planar mechanism is split into (SPEC 1,
//! thesis chapter 3 and figure 12).
//!
//! Each group is described the same way, so that one piece of code serves the
//! kinematics of all of them:
//!
//! - its **unknowns** `x` (link angles, rad, and slider offsets, m): none for a motor
//!   element, 2 for a dyad, 4 for the triad, up to 6 for a general Assur group;
//! - its **vector chains**: a chain starts at a known point and adds rotating arms
//!   `R(θ)·v` and slides `s·R(θ)·d`; a *closing* chain ends at another known point and
//!   gives two loop-closure equations `f(x) = start + Σ terms - end = 0` (SPEC 1: "solve
//!   its loop-closure equations f(x) = 0");
//! - its **placements**: each of its links has an angle source and a local point that
//!   sits at the end of a prefix of a chain, which fixes the link's pose once `x` is known;
//! - its **joints** (revolute, prismatic, and the driver of a motor element), used by
//!   the kinetostatics, where the joint reactions are the multipliers of the group's
//!   equilibrium (thesis 3.3).
//!
//! Position: each dyad has a closed form (in its own file, with an assembly branch);
//! the triad and the general Assur group ([`assur`], up to 6 links) use Newton-Raphson with a bounded iteration count, warm-started from the
//! last configuration ([`newton`]). Velocity and acceleration are linear in the same
//! Jacobian `W = ∂f/∂x`: `W ẋ = -(known part of ḟ)`, `W ẍ = -(f̈ with ẍ = 0)`.

pub mod assur;
mod chain;
pub mod dyad_rrr;
pub mod dyad_rrt;
pub mod dyad_rtr;
pub mod dyad_rtt;
pub mod dyad_trt;
pub mod motor_r;
pub mod motor_t;
pub mod newton;
pub mod pole;
pub mod triad;

pub use assur::{AssurGroup, AssurJoint, AssurLoop, AssurStep};
pub use chain::{GroupData, GroupVector, TermCache};
pub use dyad_rrr::DyadRrr;
pub use dyad_rrt::DyadRrt;
pub use dyad_rtr::DyadRtr;
pub use dyad_rtt::DyadRtt;
pub use dyad_trt::DyadTrt;
pub use motor_r::MotorR;
pub use motor_t::MotorT;
pub use triad::TriadRrRrRr;

pub(crate) use chain::{
    acceleration_pass, point_acc, point_pos, point_vel, position_from_x, velocity_pass,
};

use crate::config::{MAX_CHAINS, MAX_GROUP_JOINTS, MAX_GROUP_LINKS, MAX_GROUP_VARS, MAX_TERMS};
use crate::scalar::{Real, Vec2};

/// Whether a position pass records the angles of the links an RRR dyad places.
///
/// The dyad constructs its links' directions and takes their cosines and sines from
/// them; their angles, two `atan2` a dyad (about 5 % of a Cortex-M7's twin step in f64),
/// are an output: no pass reads an angle (positions, speeds, accelerations, the mass
/// matrix and the kinetostatics use the cosines and sines), only what reads the
/// state's own links does (outputs, event functions' readers, a motor law of the
/// angle, a drive across a joint).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Angles {
    /// Every link's angle (rad) is the state's.
    Record,
    /// The dyads' links keep the angles of their last recorded pass (and so do their
    /// groups' unknowns); the motion is the same to the bit. For an evaluation whose
    /// state only its rates leave: an integrator's inner stage.
    Stale,
}

/// The kind of a structomat (thesis figure 12).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GroupKind {
    /// Motor element R: a link turning about a known point; its angle is a coordinate.
    MotorR,
    /// Motor element T: a link sliding along a known guide; its offset is a coordinate.
    MotorT,
    /// Dyad RRR: two links, three revolute joints.
    Rrr,
    /// Dyad RRT: a rod (revolute at a known point) and a slider on a known guide.
    Rrt,
    /// Dyad RTR: two links on known pivots, one sliding along the other.
    Rtr,
    /// Dyad TRT: two sliders on known guides, pinned together.
    Trt,
    /// Dyad RTT: a link on a known pivot sliding in a slider that runs on a known guide.
    Rtt,
    /// Triad RR-RR-RR: three binary links and one ternary link.
    Triad,
    /// A general Assur group of revolute joints laid out as vector loops
    /// ([`AssurGroup`]), e.g. the converter's crank-driven A68 group.
    Assur,
}

impl GroupKind {
    /// Whether its position is solved by Newton-Raphson ([`newton`]): the triad, the
    /// general Assur group, and the dyads with linear loop closures (TRT, RTT: one
    /// step from anywhere is exact). Only these read the transmission functions
    /// recorded at the last evaluation (`GroupData::dx_dq_at`, Newton's predictor).
    pub fn solved_by_newton(self) -> bool {
        matches!(
            self,
            GroupKind::Trt | GroupKind::Rtt | GroupKind::Triad | GroupKind::Assur
        )
    }

    /// The thesis's symbol, as used in structomatic formulas (`RRR(2,3)`).
    pub fn symbol(self) -> &'static str {
        match self {
            GroupKind::MotorR => "R",
            GroupKind::MotorT => "T",
            GroupKind::Rrr => "RRR",
            GroupKind::Rrt => "RRT",
            GroupKind::Rtr => "RTR",
            GroupKind::Trt => "TRT",
            GroupKind::Rtt => "RTT",
            GroupKind::Triad => "RR-RR-RR",
            GroupKind::Assur => "ASSUR",
        }
    }
}

/// A point of a body: body 0 is the ground (its points are the zero-pole, in world
/// coordinates), bodies `1..` are the moving links (points in the link frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointRef {
    /// Body index (0 = ground).
    pub body: u8,
    /// Index in that body's point list.
    pub point: u8,
}

/// What an angle is made of: a group unknown, a generalized coordinate, or the angle of
/// an already placed body; plus a constant offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Base {
    /// Unknown `x[k]` of the group being solved.
    Var(u8),
    /// Generalized coordinate `q[j]`.
    Coord(u8),
    /// Angle of a body placed by an earlier group (the ground's is 0).
    Body(u8),
}

/// An absolute angle `base + offset`, rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angle<T: Real> {
    /// Where the variable part comes from.
    pub base: Base,
    /// Constant offset, rad.
    pub offset: T,
    /// `(cos offset, sin offset)`, computed once: turning the base's cosine and sine by
    /// it needs no trigonometry on the step path.
    pub offset_cs: Vec2<T>,
}

impl<T: Real> Angle<T> {
    /// The angle `base + offset`.
    pub fn new(base: Base, offset: T) -> Self {
        let (s, c) = offset.sincos();
        Angle {
            base,
            offset,
            offset_cs: Vec2::new(c, s),
        }
    }
}

impl<T: Real> Angle<T> {
    /// The angle `base` itself: [`Angle::new`] with a zero offset, whose cosine and
    /// sine are exactly 1 and 0 (no trigonometry).
    pub fn of(base: Base) -> Self {
        Angle {
            base,
            offset: T::zero(),
            offset_cs: Vec2::new(T::one(), T::zero()),
        }
    }
}

/// Where a slide length comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    /// Unknown `x[k]` of the group.
    Var(u8),
    /// Generalized coordinate `q[j]` (motor element T).
    Coord(u8),
}

/// A term of a vector chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Term<T: Real> {
    /// `R(θ)·v`: a vector fixed in a link (m) turning with the angle.
    Arm {
        /// The angle that turns it.
        angle: Angle<T>,
        /// The vector in the link frame, m.
        v: Vec2<T>,
    },
    /// `s·R(θ)·d`: a slide of length `s` (m) along the unit direction `d`.
    Slide {
        /// The angle that turns the direction.
        angle: Angle<T>,
        /// Unit direction in the turning frame.
        dir: Vec2<T>,
        /// The slide length.
        s: Length,
    },
}

/// A vector chain: `start + Σ terms`, closing on `end` when it is given.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain<T: Real> {
    /// A point known before the group is solved.
    pub start: PointRef,
    /// The terms, in order.
    pub terms: heapless::Vec<Term<T>, MAX_TERMS>,
    /// The known point the chain must reach (a loop-closure equation), or `None` for an
    /// open chain that only places links.
    pub end: Option<PointRef>,
}

/// How a group places one of its links once its unknowns are known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement<T: Real> {
    /// The link (body index).
    pub link: u8,
    /// Its angle.
    pub angle: Angle<T>,
    /// The chain whose prefix gives the anchor point.
    pub chain: u8,
    /// Number of terms of that chain added to its start.
    pub prefix: u8,
    /// The link's own point (link frame, m) that sits at the anchor.
    pub local: Vec2<T>,
}

/// A joint of a group, for the kinetostatics: body `i` is a link of the group, body
/// `j` any body (of the group, placed earlier, or the ground).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint<T: Real> {
    /// The group's link.
    pub i: u8,
    /// The joint point on `i` (link frame of `i`, m).
    pub pi: Vec2<T>,
    /// The other body.
    pub j: u8,
    /// The joint point on `j` (frame of `j`, m; world for the ground).
    pub pj: Vec2<T>,
    /// What the joint transmits.
    pub kind: JointKind<T>,
}

/// The kind of a joint, which fixes its reaction's unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind<T: Real> {
    /// Revolute: a force (2 unknowns), N, acting on `i` from `j` at the joint.
    Revolute,
    /// Prismatic: a force normal to the guide and a moment (2 unknowns), N and N·m;
    /// the guide direction is `dir` in the frame of `j`.
    Prismatic {
        /// Unit direction of the guide, frame of `j`.
        dir: Vec2<T>,
    },
    /// Driver of a motor element R: the torque on `i` (1 unknown), N·m.
    DriveTorque,
    /// Driver of a motor element T: the force on `i` along `dir` (frame of `j`) at the
    /// joint (1 unknown), N.
    DriveForce {
        /// Unit direction of the guide, frame of `j`.
        dir: Vec2<T>,
    },
}

impl<T: Real> JointKind<T> {
    /// Number of reaction unknowns of this joint.
    pub fn unknowns(&self) -> usize {
        match self {
            JointKind::Revolute | JointKind::Prismatic { .. } => 2,
            JointKind::DriveTorque | JointKind::DriveForce { .. } => 1,
        }
    }
}

/// One structomat of a motion-transmission sequence: the description shared by all
/// kinds (see the module docs), built by the kind's constructor (e.g.
/// [`DyadRrr::build`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Group<T: Real> {
    /// The kind.
    pub kind: GroupKind,
    /// Number of unknowns (0, 2, 4, or up to 6 for a general Assur group).
    pub n_vars: u8,
    /// The chains, closing ones first (`n_vars / 2` of them).
    pub chains: heapless::Vec<Chain<T>, MAX_CHAINS>,
    /// One placement per link of the group.
    pub placements: heapless::Vec<Placement<T>, MAX_GROUP_LINKS>,
    /// The joints whose reactions the group's equilibrium determines.
    pub joints: heapless::Vec<Joint<T>, MAX_GROUP_JOINTS>,
    /// Initial guesses of the unknowns (thesis tables: "conditions initiales"); they
    /// choose the assembly branch.
    pub guess: [T; MAX_GROUP_VARS],
    /// Constants of the kind's closed form, computed once when built (documented in the
    /// kind's file).
    pub consts: [T; 8],
    /// The generalized coordinate a motor element drives.
    pub coord: Option<u8>,
}

impl<T: Real> Group<T> {
    /// A group with nothing in it, for a constructor to write in place
    /// ([`WriteGroup`](crate::model::WriteGroup)).
    pub(crate) fn empty() -> Self {
        Group {
            kind: GroupKind::MotorR,
            n_vars: 0,
            chains: heapless::Vec::new(),
            placements: heapless::Vec::new(),
            joints: heapless::Vec::new(),
            guess: [T::zero(); MAX_GROUP_VARS],
            consts: [T::zero(); 8],
            coord: None,
        }
    }

    /// The links of the group in thesis numbering.
    pub fn links(&self) -> impl Iterator<Item = u8> + '_ {
        self.placements.iter().map(|p| p.link)
    }

    /// Whether the position problem has a closed form (dyads, motor elements) or needs
    /// Newton-Raphson (the triad).
    pub fn has_closed_form(&self) -> bool {
        !matches!(self.kind, GroupKind::Triad | GroupKind::Assur)
    }
}

/// Helper for the group constructors: a chain from its parts.
pub(crate) fn chain<T: Real>(
    start: PointRef,
    terms: &[Term<T>],
    end: Option<PointRef>,
) -> Result<Chain<T>, crate::error::ModelError> {
    let mut v = heapless::Vec::new();
    for t in terms {
        v.push(*t)
            .map_err(|_| crate::error::ModelError::Capacity("terms in a chain"))?;
    }
    Ok(Chain {
        start,
        terms: v,
        end,
    })
}

/// Helper for the group constructors that write in place: appends the chain
/// `start + Σ terms`, closing on `end` when given, to `g`.
pub(crate) fn push_chain<T: Real>(
    g: &mut Group<T>,
    start: PointRef,
    terms: &[Term<T>],
    end: Option<PointRef>,
) -> Result<(), crate::error::ModelError> {
    g.chains
        .push(Chain {
            start,
            terms: heapless::Vec::new(),
            end,
        })
        .map_err(|_| crate::error::ModelError::Capacity("chains"))?;
    match g.chains.last_mut() {
        Some(c) => extend(&mut c.terms, terms, "terms in a chain"),
        None => Err(crate::error::ModelError::Capacity("chains")),
    }
}

/// Helper for the group constructors that write in place: appends `items` to `v`.
pub(crate) fn extend<X: Copy, const N: usize>(
    v: &mut heapless::Vec<X, N>,
    items: &[X],
    what: &'static str,
) -> Result<(), crate::error::ModelError> {
    for x in items {
        v.push(*x)
            .map_err(|_| crate::error::ModelError::Capacity(what))?;
    }
    Ok(())
}

/// Helper for the group constructors: a kind's guesses padded to the group capacity.
pub(crate) fn guesses<T: Real>(g: &[T]) -> [T; MAX_GROUP_VARS] {
    let mut out = [T::zero(); MAX_GROUP_VARS];
    for (o, v) in out.iter_mut().zip(g.iter()) {
        *o = *v;
    }
    out
}

/// Helper for the group constructors: a fixed-capacity list from a slice.
pub(crate) fn list<X: Clone, const N: usize>(
    items: &[X],
    what: &'static str,
) -> Result<heapless::Vec<X, N>, crate::error::ModelError> {
    let mut v = heapless::Vec::new();
    for x in items {
        v.push(x.clone())
            .map_err(|_| crate::error::ModelError::Capacity(what))?;
    }
    Ok(v)
}
