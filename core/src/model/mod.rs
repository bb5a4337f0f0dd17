//! The model: an immutable, validated description of a mechanism (links, ground
//! points, the motion-transmission sequence of groups, motors, loads, gravity).
//!
//! Bodies are numbered as in the thesis: 0 is the ground (its points form the
//! zero-pole), moving links are `1..=n`. A model is built once by [`ModelBuilder`],
//! which checks everything a step relies on, so that the step path never meets a bad
//! reference.

use crate::capacity::{Capacity, Generic, List};
use crate::config::{MAX_DOF, MAX_DRIVES, MAX_GROUPS, MAX_LINKS, MAX_LINK_POINTS};
use crate::error::ModelError;
use crate::motor::Motor;
use crate::scalar::{Real, Vec2};
use crate::structomat::{
    DyadRrr, DyadRrt, DyadRtr, DyadRtt, DyadTrt, Group, MotorR, MotorT, PointRef, TriadRrRrRr,
};
use core::fmt;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;

mod builder;
mod validate;

pub use builder::{ModelBuilder, OwnedModel};

/// A rigid link: mass properties and the points where joints sit, in its own frame.
///
/// For a bar, the frame's origin is its first joint and its x axis points to the
/// second joint (SPEC: "COG position in the link frame").
#[derive(Clone, Debug, PartialEq)]
pub struct Link<T: Real> {
    /// Mass, kg.
    pub mass: T,
    /// Moment of inertia about the centre of gravity, kg·m².
    pub inertia: T,
    /// Centre of gravity in the link frame, m.
    pub cog: Vec2<T>,
    /// Points (joint locations, extra points) in the link frame, m.
    pub points: heapless::Vec<Vec2<T>, MAX_LINK_POINTS>,
}

impl<T: Real> Link<T> {
    /// A bar of length `length` (m): point 0 at its start, point 1 at its end, COG on
    /// the bar at `cog_from_start` (m) from the start.
    pub fn bar(length: T, mass: T, inertia: T, cog_from_start: T) -> Self {
        let mut points = heapless::Vec::new();
        // Capacity is at least 2 (checked at compile time below): these pushes succeed.
        let _ = points.push(Vec2::zeros());
        let _ = points.push(Vec2::new(length, T::zero()));
        Link {
            mass,
            inertia,
            cog: Vec2::new(cog_from_start, T::zero()),
            points,
        }
    }

    /// A block (a slider): point 0 at its frame origin, COG there.
    pub fn block(mass: T, inertia: T) -> Self {
        let mut points = heapless::Vec::new();
        let _ = points.push(Vec2::zeros());
        Link {
            mass,
            inertia,
            cog: Vec2::zeros(),
            points,
        }
    }

    /// Adds a point (link frame, m) and returns its index.
    pub fn add_point(&mut self, p: Vec2<T>) -> Result<u8, ModelError> {
        self.points
            .push(p)
            .map_err(|_| ModelError::Capacity("points on a link"))?;
        Ok((self.points.len() - 1) as u8)
    }

    /// Attaches a point mass `mass` (kg) with its own inertia `inertia` (kg·m²) at `at`
    /// (link frame): the link's COG and its inertia about the new COG follow (parallel
    /// axis theorem).
    pub fn add_mass(&mut self, mass: T, inertia: T, at: Vec2<T>) {
        let total = self.mass + mass;
        if !(total > T::zero()) {
            return;
        }
        let cog = (self.cog * self.mass + at * mass) / total;
        self.inertia = self.inertia
            + self.mass * (self.cog - cog).norm_squared()
            + inertia
            + mass * (at - cog).norm_squared();
        self.cog = cog;
        self.mass = total;
    }
}

const _: () = assert!(MAX_LINK_POINTS >= 2, "a bar needs two points");
const _: () = assert!(MAX_DOF <= 4 && MAX_GROUPS <= 255 && MAX_LINKS <= 254);

/// A motor model acting on a generalized coordinate, through the motor element that
/// drives it: a torque on its link (element R) or a force along its guide (element T),
/// the reaction on the body it is mounted on.
///
/// A drive *across a joint* ([`ModelBuilder::drive_across`]) acts on a joint that is
/// no coordinate's: a motor whose link the sequence places by another group (an
/// alternative choice of coordinates, [`crate::simulation::switch`]). Its law reads
/// the joint's relative motion (a revolute joint: `θ_i - θ_j` and `ω_i - ω_j`; a
/// prismatic one: the offset along the guide and its rate), and its torque or force
/// maps onto the coordinates through the transmission, as any load does.
#[derive(Clone, Copy, Debug)]
pub struct Drive<T: Real> {
    /// The coordinate ([`Drive::ACROSS`] for a drive across a joint).
    pub coord: u8,
    /// Index in the sequence of the motor element that applies it, or of the group
    /// whose joint `joint` it acts across.
    pub group: u8,
    /// The torque (N·m) or force (N) law.
    pub motor: Motor<T>,
    /// For a drive across a joint: the joint's index in its group's joints.
    pub joint: Option<u8>,
}

impl<T: Real> Drive<T> {
    /// The `coord` of a drive across a joint: it drives no coordinate.
    pub const ACROSS: u8 = u8::MAX;
}

/// A constant external load on a link: a force at a point and a moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Load<T: Real> {
    /// The loaded link (body index).
    pub body: u8,
    /// Point of application, link frame, m.
    pub point: Vec2<T>,
    /// Force, world frame, N.
    pub force: Vec2<T>,
    /// Moment, N·m, CCW positive.
    pub moment: T,
}

/// A validated mechanism description. Built by [`ModelBuilder`]; read-only afterwards.
/// Its lists are sized by the capacity `C` ([`Generic`]: the `config` limits).
#[derive(Debug)]
pub struct Model<T: Real, C: Capacity<T> = Generic> {
    ground: C::GroundPoints,
    links: C::Links,
    groups: C::Groups,
    drives: heapless::Vec<Drive<T>, MAX_DRIVES>,
    loads: C::Loads,
    gravity: Vec2<T>,
    dof: u8,
    singular_tol: T,
    newton_tol: T,
}

impl<T: Real, C: Capacity<T>> Clone for Model<T, C> {
    fn clone(&self) -> Self {
        Model {
            ground: self.ground.clone(),
            links: self.links.clone(),
            groups: self.groups.clone(),
            drives: self.drives.clone(),
            loads: self.loads.clone(),
            gravity: self.gravity,
            dof: self.dof,
            singular_tol: self.singular_tol,
            newton_tol: self.newton_tol,
        }
    }

    /// Field by field, in place: no temporary model (16 KB in f64) on the stack.
    fn clone_from(&mut self, source: &Self) {
        copy_vec(&mut self.ground, &source.ground);
        copy_vec(&mut self.links, &source.links);
        copy_vec(&mut self.groups, &source.groups);
        copy_vec(&mut self.drives, &source.drives);
        copy_vec(&mut self.loads, &source.loads);
        self.gravity = source.gravity;
        self.dof = source.dof;
        self.singular_tol = source.singular_tol;
        self.newton_tol = source.newton_tol;
    }
}

impl<T: Real, C: Capacity<T>> Model<T, C> {
    /// The empty model [`ModelBuilder::new`] starts from (no links, gravity `(0, -9.81)`
    /// m/s²), by value. Not a valid model to evaluate until rebuilt
    /// ([`ModelBuilder::in_place`]).
    pub(crate) fn empty() -> Self {
        Model {
            ground: List::new(),
            links: List::new(),
            groups: List::new(),
            drives: heapless::Vec::new(),
            loads: List::new(),
            gravity: default_gravity(),
            dof: 0,
            singular_tol: default_singular_tol(),
            newton_tol: T::zero(),
        }
    }

    /// Initialises `place` in place as an empty model, the one [`ModelBuilder::new`]
    /// starts from (no links, gravity `(0, -9.81)` m/s²): nothing on the stack but the
    /// small fields (a model is 16 KB in f64). Not a valid model to evaluate until
    /// rebuilt ([`ModelBuilder::in_place`]).
    pub(crate) fn init_empty(place: &mut MaybeUninit<Self>) -> &mut Self {
        let p = place.as_mut_ptr();
        // SAFETY: every field of `*p` is written once through a raw pointer to it (no
        // reference to an uninitialised field is made; `fields_of` below fails to
        // compile if a field is added and not listed there), so `*p` is initialised
        // before `assume_init_mut`. A heapless vector's `new` leaves its buffer
        // uninitialised: only its length is stored.
        unsafe {
            addr_of_mut!((*p).ground).write(List::new());
            addr_of_mut!((*p).links).write(List::new());
            addr_of_mut!((*p).groups).write(List::new());
            addr_of_mut!((*p).drives).write(heapless::Vec::new());
            addr_of_mut!((*p).loads).write(List::new());
            addr_of_mut!((*p).gravity).write(default_gravity());
            addr_of_mut!((*p).dof).write(0);
            addr_of_mut!((*p).singular_tol).write(default_singular_tol());
            addr_of_mut!((*p).newton_tol).write(T::zero());
            place.assume_init_mut()
        }
    }
}

/// The fields [`Model::init_empty`] writes: a field added to [`Model`] and not there
/// fails to compile here.
#[allow(dead_code)]
fn fields_of<T: Real, C: Capacity<T>>(m: &Model<T, C>) {
    let Model {
        ground: _,
        links: _,
        groups: _,
        drives: _,
        loads: _,
        gravity: _,
        dof: _,
        singular_tol: _,
        newton_tol: _,
    } = m;
}

/// `dst` becomes a copy of `src`, element by element (the same capacity: every push fits).
fn copy_vec<E: Clone, L: List<E>>(dst: &mut L, src: &L) {
    dst.clear();
    for e in src.iter() {
        let _ = dst.push(e.clone());
    }
}

impl<T: Real, C: Capacity<T>> Model<T, C> {
    /// Number of moving links.
    pub fn n_links(&self) -> usize {
        self.links.len()
    }
    /// Degrees of freedom (number of generalized coordinates).
    pub fn dof(&self) -> usize {
        self.dof as usize
    }
    /// Link `body` (1-based), if it exists.
    pub fn link(&self, body: u8) -> Option<&Link<T>> {
        (body as usize)
            .checked_sub(1)
            .and_then(|k| self.links.get(k))
    }
    /// The moving links, body 1 first.
    pub fn links(&self) -> &[Link<T>] {
        &self.links
    }
    /// Sets body `body`'s (1-based) mass (kg), moment of inertia about its COG (kg·m²)
    /// and COG (in its frame, m): a parameter changed between steps, e.g. by an
    /// estimator (the next evaluation takes it). A value the model's validation refuses
    /// (not finite, a negative mass or inertia) or no such body is its error, and the
    /// model stays as it is.
    pub fn set_mass_properties(
        &mut self,
        body: u8,
        mass: T,
        inertia: T,
        cog: Vec2<T>,
    ) -> Result<(), ModelError> {
        validate::mass_properties(mass, inertia, &cog)?;
        let l = (body as usize)
            .checked_sub(1)
            .and_then(|k| self.links.get_mut(k))
            .ok_or(ModelError::UnknownReference("link"))?;
        l.mass = mass;
        l.inertia = inertia;
        l.cog = cog;
        Ok(())
    }
    /// The ground points (world, m).
    pub fn ground_points(&self) -> &[Vec2<T>] {
        &self.ground
    }
    /// The motion-transmission sequence.
    pub fn groups(&self) -> &[Group<T>] {
        &self.groups
    }
    /// The motors.
    pub fn drives(&self) -> &[Drive<T>] {
        &self.drives
    }
    /// The constant external loads.
    pub fn loads(&self) -> &[Load<T>] {
        &self.loads
    }
    /// Gravity, m/s².
    pub fn gravity(&self) -> Vec2<T> {
        self.gravity
    }
    /// Normalized determinant below which a group's Jacobian counts as singular.
    pub fn singular_tol(&self) -> T {
        self.singular_tol
    }
    /// Loop-closure residual (m) at which Newton-Raphson stops.
    pub fn newton_tol(&self) -> T {
        self.newton_tol
    }

    /// Local coordinates of `p` (world coordinates for a ground point); zero for a
    /// reference the builder would have rejected.
    #[inline]
    pub fn point_local(&self, p: PointRef) -> Vec2<T> {
        if p.body == 0 {
            self.ground
                .get(p.point as usize)
                .copied()
                .unwrap_or_else(Vec2::zeros)
        } else {
            self.link(p.body)
                .and_then(|l| l.points.get(p.point as usize))
                .copied()
                .unwrap_or_else(Vec2::zeros)
        }
    }

    /// Local coordinates of `p`, or an error naming `what`.
    pub fn resolve(&self, p: PointRef, what: &'static str) -> Result<Vec2<T>, ModelError> {
        self.points().resolve(p, what)
    }

    /// Point `point` of link `body` in its frame, or an error naming `what`.
    pub fn local(&self, body: u8, point: u8, what: &'static str) -> Result<Vec2<T>, ModelError> {
        self.points().local(body, point, what)
    }

    /// The ground's and the links' points, which group constructors resolve.
    #[inline]
    pub(crate) fn points(&self) -> Points<'_, T> {
        Points {
            ground: &self.ground,
            links: &self.links,
        }
    }

    /// The structomatic formula of the sequence, e.g.
    /// `Z(0) + R(1) + R(2) + RRR(3,4)` (thesis eq. 3.1-3.3).
    pub fn formula(&self) -> Formula<'_, T, C> {
        Formula(self)
    }
}

/// The points of a model's ground and links, borrowed apart from its groups: what a
/// group constructor resolves while it writes its group into the model
/// ([`ModelBuilder::group_in_place`]).
#[derive(Clone, Copy)]
pub(crate) struct Points<'a, T: Real> {
    ground: &'a [Vec2<T>],
    links: &'a [Link<T>],
}

impl<T: Real> Points<'_, T> {
    /// See [`Model::resolve`].
    pub(crate) fn resolve(&self, p: PointRef, what: &'static str) -> Result<Vec2<T>, ModelError> {
        let point = if p.body == 0 {
            self.ground.get(p.point as usize)
        } else {
            self.link(p.body)
                .and_then(|l| l.points.get(p.point as usize))
        };
        point.copied().ok_or(ModelError::UnknownReference(what))
    }

    /// See [`Model::local`].
    pub(crate) fn local(
        &self,
        body: u8,
        point: u8,
        what: &'static str,
    ) -> Result<Vec2<T>, ModelError> {
        if body == 0 {
            return Err(ModelError::UnknownReference(what));
        }
        self.resolve(PointRef { body, point }, what)
    }

    #[inline]
    fn link(&self, body: u8) -> Option<&Link<T>> {
        (body as usize)
            .checked_sub(1)
            .and_then(|k| self.links.get(k))
    }
}

/// Displays a model's structomatic formula ([`Model::formula`]).
pub struct Formula<'a, T: Real, C: Capacity<T> = Generic>(&'a Model<T, C>);

impl<T: Real, C: Capacity<T>> fmt::Display for Formula<'_, T, C> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Z(0)")?;
        for (i, g) in self.0.groups.iter().enumerate() {
            write!(f, " + {}", crate::kinematics::group_id(g, i))?;
        }
        Ok(())
    }
}

/// A group description that can be built against the links declared so far.
pub trait GroupSpec<T: Real> {
    /// Builds the group, resolving its points in `model`.
    fn build(&self, model: &Model<T>) -> Result<Group<T>, ModelError>;
}

/// A group constructor that writes its group in place, into an empty group of the
/// model's sequence ([`ModelBuilder::group_in_place`]): no group value (2 KB in f64) is
/// built apart and moved. Its [`GroupSpec::build`] writes into a new group the same way.
pub(crate) trait WriteGroup<T: Real>: GroupSpec<T> {
    /// Fills `g`, an empty group ([`Group::empty`]), resolving points in `points`; on
    /// an error `g` is partly written.
    fn write(&self, points: &Points<'_, T>, g: &mut Group<T>) -> Result<(), ModelError>;
}

macro_rules! group_spec {
    ($($t:ident),*) => {$(
        impl<T: Real> GroupSpec<T> for $t<T> {
            fn build(&self, model: &Model<T>) -> Result<Group<T>, ModelError> {
                $t::build(self, model)
            }
        }
    )*};
}
group_spec!(
    MotorR,
    MotorT,
    DyadRrr,
    DyadRrt,
    DyadRtr,
    DyadTrt,
    DyadRtt,
    TriadRrRrRr
);

/// Gravity of a new model, m/s² (SPEC: g along -y).
fn default_gravity<T: Real>() -> Vec2<T> {
    Vec2::new(T::zero(), T::c(-9.81))
}

/// sqrt(eps)/10: 1.5e-9 for f64, 3.5e-5 for f32 (the sine of the transmission angle of
/// a dyad at which W counts as singular).
fn default_singular_tol<T: Real>() -> T {
    T::EPS.sqrt() * T::c(0.1)
}
