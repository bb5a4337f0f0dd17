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
    Base, DyadRrr, DyadRrt, DyadRtr, DyadRtt, DyadTrt, Group, GroupKind, JointKind, Length, MotorR,
    MotorT, PointRef, Term, TriadRrRrRr,
};
use core::fmt;
use core::marker::PhantomData;
use core::mem::MaybeUninit;
use core::ops::{Deref, DerefMut};
use core::ptr::addr_of_mut;

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

/// Builds and validates a [`Model`]: its own ([`ModelBuilder::new`], then
/// [`ModelBuilder::build`]) or one rebuilt in place ([`ModelBuilder::in_place`], then
/// [`ModelBuilder::finish`]), which keeps the model (16 KB in f64) off the stack.
#[derive(Clone, Debug)]
pub struct ModelBuilder<T: Real, M = OwnedModel<T>> {
    m: M,
    scalar: PhantomData<T>,
}

/// The model a [`ModelBuilder::new`] owns.
#[derive(Clone, Debug)]
pub struct OwnedModel<T: Real>(Model<T>);

impl<T: Real> Deref for OwnedModel<T> {
    type Target = Model<T>;
    fn deref(&self) -> &Model<T> {
        &self.0
    }
}

impl<T: Real> DerefMut for OwnedModel<T> {
    fn deref_mut(&mut self) -> &mut Model<T> {
        &mut self.0
    }
}

impl<T: Real> Default for ModelBuilder<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// Gravity of a new model, m/s² (SPEC: g along -y).
fn default_gravity<T: Real>() -> Vec2<T> {
    Vec2::new(T::zero(), T::c(-9.81))
}

/// sqrt(eps)/10: 1.5e-9 for f64, 3.5e-5 for f32 (the sine of the transmission angle of
/// a dyad at which W counts as singular).
fn default_singular_tol<T: Real>() -> T {
    T::EPS.sqrt() * T::c(0.1)
}

impl<T: Real> ModelBuilder<T> {
    /// An empty mechanism with gravity `(0, -9.81)` m/s² (SPEC: g along -y).
    pub fn new() -> Self {
        ModelBuilder {
            m: OwnedModel(Model::empty()),
            scalar: PhantomData,
        }
    }

    /// Validates the description and returns the model.
    pub fn build(mut self) -> Result<Model<T>, ModelError> {
        validate(&mut self.m)?;
        Ok(self.m.0)
    }
}

impl<'a, T: Real, C: Capacity<T>> ModelBuilder<T, &'a mut Model<T, C>> {
    /// Rebuilds `model` in place: empties it to the state of [`ModelBuilder::new`]'s
    /// model, then declares into it. Until [`ModelBuilder::finish`] succeeds, `model`
    /// is not a valid model.
    pub fn in_place(model: &'a mut Model<T, C>) -> Self {
        model.ground.clear();
        model.links.clear();
        model.groups.clear();
        model.drives.clear();
        model.loads.clear();
        model.gravity = default_gravity();
        model.dof = 0;
        model.singular_tol = default_singular_tol();
        model.newton_tol = T::zero();
        ModelBuilder {
            m: model,
            scalar: PhantomData,
        }
    }

    /// Validates the model built in place.
    pub fn finish(self) -> Result<(), ModelError> {
        validate(self.m)
    }

    /// [`ModelBuilder::finish`] for a model whose sequence of `dof` coordinates is
    /// known to be valid and whose groups were written by the crate's constructors of
    /// the motor element R, the dyad RRR, the triad and the Assur group from points
    /// only (their angle offsets zero): the converter's modes, rebuilt at each event,
    /// whose every declaration the full validation passes in the tests. It skips what
    /// only a wrong declaration could fail (see `validate_rebuilt`).
    pub(crate) fn finish_rebuilt(self, dof: u8) -> Result<(), ModelError> {
        validate_rebuilt(self.m, dof)
    }
}

impl<T: Real, M: DerefMut<Target = Model<T>>> ModelBuilder<T, M> {
    /// Appends a group to the motion-transmission sequence. [`ModelBuilder::build`]
    /// checks that every value the group holds is finite: its angle offsets and guesses
    /// as given, and what its constructor derives from the links' points (lengths,
    /// directions: a point at 1e200 m is finite but its squared length is not).
    pub fn group(&mut self, spec: &impl GroupSpec<T>) -> Result<u8, ModelError> {
        let g = spec.build(&self.m)?;
        self.m
            .groups
            .push(g)
            .map_err(|_| ModelError::Capacity("groups"))?;
        Ok((self.m.groups.len() - 1) as u8)
    }
}

impl<T: Real, C: Capacity<T>, M: DerefMut<Target = Model<T, C>>> ModelBuilder<T, M> {
    /// The model as declared so far (group constructors resolve points in it).
    pub fn model(&self) -> &Model<T, C> {
        &self.m
    }

    /// Sets gravity, m/s².
    pub fn gravity(&mut self, g: Vec2<T>) -> &mut Self {
        self.m.gravity = g;
        self
    }

    /// Sets the singularity threshold on a group's normalized determinant.
    pub fn singular_tol(&mut self, tol: T) -> &mut Self {
        self.m.singular_tol = tol;
        self
    }

    /// Adds a ground point (world, m).
    pub fn ground_point(&mut self, x: T, y: T) -> Result<PointRef, ModelError> {
        self.m
            .ground
            .push(Vec2::new(x, y))
            .map_err(|_| ModelError::Capacity("ground points"))?;
        Ok(PointRef {
            body: 0,
            point: (self.m.ground.len() - 1) as u8,
        })
    }

    /// Adds a moving link; returns its body index (1, 2, ...).
    pub fn link(&mut self, link: Link<T>) -> Result<u8, ModelError> {
        self.m
            .links
            .push(link)
            .map_err(|_| ModelError::Capacity("links"))?;
        Ok(self.m.links.len() as u8)
    }

    /// [`ModelBuilder::group`] for the constructors that write their group in place:
    /// the same group and errors (but a full sequence's, which comes first), the group
    /// written into the sequence, not built apart and moved there.
    pub(crate) fn group_in_place(&mut self, spec: &impl WriteGroup<T>) -> Result<u8, ModelError> {
        let Model {
            ground,
            links,
            groups,
            ..
        } = &mut *self.m;
        let points = Points { ground, links };
        if groups.is_full() {
            // Unlike `group`, before the constructor's own errors: its group would have
            // to be written apart (2 KB in f64 on the stack, and code of its own).
            return Err(ModelError::Capacity("groups"));
        }
        let _ = groups.push(Group::empty());
        let written = match groups.last_mut() {
            Some(g) => spec.write(&points, g),
            None => Err(ModelError::Capacity("groups")),
        };
        if let Err(e) = written {
            groups.pop();
            return Err(e);
        }
        Ok((groups.len() - 1) as u8)
    }

    /// Puts a motor on coordinate `coord` (applied by its first motor element).
    pub fn drive(&mut self, coord: u8, motor: Motor<T>) -> Result<&mut Self, ModelError> {
        self.m
            .drives
            .push(Drive {
                coord,
                group: u8::MAX,
                motor,
                joint: None,
            })
            .map_err(|_| ModelError::Capacity("drives"))?;
        Ok(self)
    }

    /// Puts a motor across the joint between link `body` and body `on` (a revolute or
    /// prismatic joint of the group that places `body`, `body` its moving side): its
    /// torque acts on `body` (reaction on `on`), or its force along the guide of `on`.
    /// The joint is found at validation.
    pub fn drive_across(
        &mut self,
        body: u8,
        on: u8,
        motor: Motor<T>,
    ) -> Result<&mut Self, ModelError> {
        self.m
            .drives
            .push(Drive {
                coord: Drive::<T>::ACROSS,
                // Resolved by validation: the bodies until then.
                group: body,
                motor,
                joint: Some(on),
            })
            .map_err(|_| ModelError::Capacity("drives"))?;
        Ok(self)
    }

    /// Adds a constant external load.
    pub fn load(&mut self, load: Load<T>) -> Result<&mut Self, ModelError> {
        self.m
            .loads
            .push(load)
            .map_err(|_| ModelError::Capacity("loads"))?;
        Ok(self)
    }
}

/// Validates a declared model and completes its derived data (Newton tolerance, the
/// drives' motor elements): the end of [`ModelBuilder::build`] and
/// [`ModelBuilder::finish`].
fn validate<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<(), ModelError> {
    let size = validate_bodies(m)?;
    // After the points: a group's values derive from them, and a non-finite point
    // is named as such above.
    for (k, g) in m.groups.iter().enumerate() {
        if let Err(what) = group_values_finite(g) {
            return Err(ModelError::GroupNonFinite {
                group: k as u8,
                kind: g.kind,
                what,
            });
        }
    }
    check_sequence(m)?;
    validate_drives_and_loads(m, size)
}

/// [`validate`] for a model rebuilt in place whose sequence is known to be valid and
/// whose group constructors are known to derive their values from its points only,
/// apart from the guesses (the converter's modes, [`ModelBuilder::finish_rebuilt`]):
/// the same checks of the links, ground points, guesses, drives and loads, the same
/// Newton tolerance, but no walk of the sequence and of the groups' derived values,
/// which a finite mechanism of finite size squared keeps finite (differences of its
/// points, their lengths, directions and angles). `dof` is the number of coordinates
/// the sequence drives.
fn validate_rebuilt<T: Real, C: Capacity<T>>(
    m: &mut Model<T, C>,
    dof: u8,
) -> Result<(), ModelError> {
    let size = validate_bodies(m)?;
    for (k, g) in m.groups.iter().enumerate() {
        if !g.guess.iter().all(|x| x.finite()) {
            return Err(ModelError::GroupNonFinite {
                group: k as u8,
                kind: g.kind,
                what: "a guess",
            });
        }
    }
    m.dof = dof;
    validate_drives_and_loads(m, size)
}

/// The first part of [`validate`]: gravity, the singularity threshold, the ground
/// points and the links, and the Newton tolerance from the mechanism's scale; returns
/// the mechanism's size (twice its largest coordinate, m).
fn validate_bodies<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<T, ModelError> {
    if !(m.gravity.x.finite() && m.gravity.y.finite()) {
        return Err(ModelError::NonFinite("gravity"));
    }
    if !(m.singular_tol.finite() && m.singular_tol > T::zero()) {
        return Err(ModelError::NotPositive("singularity threshold"));
    }
    let mut scale = T::one();
    for p in m.ground.iter() {
        finite2(p, "ground point")?;
        scale = scale.max(p.x.abs()).max(p.y.abs());
    }
    for l in m.links.iter() {
        finite(l.mass, "link mass")?;
        finite(l.inertia, "link inertia")?;
        finite2(&l.cog, "link COG")?;
        if l.mass < T::zero() {
            return Err(ModelError::Negative("link mass"));
        }
        if l.inertia < T::zero() {
            return Err(ModelError::Negative("link inertia"));
        }
        for p in l.points.iter() {
            finite2(p, "link point")?;
            scale = scale.max(p.x.abs()).max(p.y.abs());
        }
    }
    // The step squares distances (closed forms, Newton's residual, speeds) and
    // multiplies masses by gravity and heights (weights, potential energy): a
    // description finite in itself can still overflow there (a point at 1e200 m; in
    // f32 past 1.8e19 m). Twice the largest coordinate bounds every distance.
    let cogs = m
        .links
        .iter()
        .fold(T::zero(), |a, l| a.max(l.cog.x.abs()).max(l.cog.y.abs()));
    let size = T::c(2.0) * scale.max(cogs);
    if !(size * size).finite() {
        return Err(ModelError::Overflow("the mechanism's size squared"));
    }
    let g = m.gravity.x.abs().max(m.gravity.y.abs());
    for l in m.links.iter() {
        if !(l.mass * size * size + l.inertia).finite() {
            return Err(ModelError::Overflow(
                "a link's moment of inertia about a point of the mechanism",
            ));
        }
        if !(l.mass * g * size).finite() {
            return Err(ModelError::Overflow(
                "a link's weight times the mechanism's size (its potential energy)",
            ));
        }
    }
    // Newton stops at 64 ulps of the mechanism's size in f64 (1.4e-14 m per metre)
    // and at 8 ulps in f32 (9.5e-7 m per metre). f32's 64 ulps, 7.6e-6 m per metre,
    // left the joints of a triad or of A68's six-link group that far apart, and that
    // broke the twin's energy balance at S2's dead points (0.1789 s, in 16 sub-steps
    // too). f32's residual gets under 1 ulp; 8 still takes at most one iteration a
    // solve in S2, as 64 did.
    m.newton_tol = T::c(64.0 * f64::EPSILON).max(T::c(8.0) * T::EPS) * scale;
    Ok(size)
}

/// The last part of [`validate`], after the sequence: each drive's motor element and
/// motor law, each load's body and values (`size`: the mechanism's, m).
fn validate_drives_and_loads<T: Real, C: Capacity<T>>(
    m: &mut Model<T, C>,
    size: T,
) -> Result<(), ModelError> {
    let Model {
        drives,
        groups,
        dof,
        loads,
        links,
        ..
    } = m;
    for d in drives.iter_mut() {
        if let Some(on) = d.joint {
            let (body, on) = (d.group, on);
            let (g, j) = joint_between(groups, body, on).ok_or(ModelError::Coordinates(
                "a drive across a joint names bodies that no revolute or prismatic joint of the group placing the first joins",
            ))?;
            (d.group, d.joint) = (g, Some(j));
            d.motor.validate()?;
            continue;
        }
        if d.coord >= *dof {
            return Err(ModelError::Coordinates(
                "a drive names a coordinate no motor element has",
            ));
        }
        d.group = groups
            .iter()
            .position(|g| g.coord == Some(d.coord))
            .map(|k| k as u8)
            .ok_or(ModelError::Coordinates(
                "a drive names a coordinate no motor element has",
            ))?;
        d.motor.validate()?;
    }
    for l in loads.iter() {
        if l.body == 0 || l.body as usize > links.len() {
            return Err(ModelError::UnknownReference("load: body"));
        }
        finite2(&l.point, "load point")?;
        finite2(&l.force, "load force")?;
        finite(l.moment, "load moment")?;
        let size = size.max(T::c(2.0) * l.point.x.abs().max(l.point.y.abs()));
        if !((l.force.x.abs() + l.force.y.abs()) * size + l.moment.abs()).finite() {
            return Err(ModelError::Overflow(
                "a load's moment about a point of the mechanism",
            ));
        }
    }
    Ok(())
}

/// The group that places link `body` and the index of its revolute or prismatic joint
/// from `body` to `on`.
fn joint_between<T: Real>(groups: &[Group<T>], body: u8, on: u8) -> Option<(u8, u8)> {
    let (g, grp) = groups
        .iter()
        .enumerate()
        .find(|(_, g)| g.links().any(|l| l == body))?;
    let j = grp.joints.iter().position(|jt| {
        jt.i == body
            && jt.j == on
            && matches!(jt.kind, JointKind::Revolute | JointKind::Prismatic { .. })
    })?;
    Some((g as u8, j as u8))
}

/// Every value of a built group is finite, or the name of the first that is not.
fn group_values_finite<T: Real>(g: &Group<T>) -> Result<(), &'static str> {
    let ok = |x: T, what| if x.finite() { Ok(()) } else { Err(what) };
    let ok2 = |v: &Vec2<T>, what| ok(v.x, what).and_then(|()| ok(v.y, what));
    for x in g.guess.iter() {
        ok(*x, "a guess")?;
    }
    for x in g.consts.iter() {
        ok(*x, "a length or angle of its closed form")?;
    }
    for c in g.chains.iter() {
        for t in c.terms.iter() {
            match t {
                Term::Arm { angle, v } => {
                    ok(angle.offset, "an angle offset")?;
                    ok2(v, "an arm (a link's joint-to-joint vector)")?;
                }
                Term::Slide { angle, dir, .. } => {
                    ok(angle.offset, "a guide angle")?;
                    ok2(dir, "a guide direction")?;
                }
            }
        }
    }
    for p in g.placements.iter() {
        ok(p.angle.offset, "an angle offset")?;
        ok2(&p.local, "a link point")?;
    }
    for j in g.joints.iter() {
        ok2(&j.pi, "a joint point")?;
        ok2(&j.pj, "a joint point")?;
        if let JointKind::Prismatic { dir } | JointKind::DriveForce { dir } = j.kind {
            ok2(&dir, "a guide direction")?;
        }
    }
    Ok(())
}

fn finite<T: Real>(x: T, what: &'static str) -> Result<(), ModelError> {
    if x.finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite(what))
    }
}

fn finite2<T: Real>(v: &Vec2<T>, what: &'static str) -> Result<(), ModelError> {
    finite(v.x, what)?;
    finite(v.y, what)
}

/// Checks that the sequence places every link once, each group using only what earlier
/// groups placed, and that the coordinates are `0..dof`, each driven.
fn check_sequence<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<(), ModelError> {
    let mut placed = [false; MAX_LINKS + 1];
    placed[0] = true;
    let mut coord_used = [false; MAX_DOF];
    let n_links = m.links.len();
    let known = |placed: &[bool], b: u8| placed.get(b as usize).copied().unwrap_or(false);
    for (gi, g) in m.groups.iter().enumerate() {
        let gi = gi as u8;
        let err = |why| ModelError::Sequence { group: gi, why };
        for ch in g.chains.iter() {
            if !known(&placed, ch.start.body) || ch.end.is_some_and(|e| !known(&placed, e.body)) {
                return Err(err("an input pole is on a link no earlier group places"));
            }
            for t in ch.terms.iter() {
                let (angle, len) = match t {
                    Term::Arm { angle, .. } => (angle, None),
                    Term::Slide { angle, s, .. } => (angle, Some(*s)),
                };
                match angle.base {
                    Base::Body(b) if !known(&placed, b) => {
                        return Err(err("a guide is on a link no earlier group places"))
                    }
                    Base::Var(k) if k >= g.n_vars => return Err(err("unknown index out of range")),
                    Base::Coord(j) if j as usize >= MAX_DOF => {
                        return Err(ModelError::Capacity("coordinates"))
                    }
                    _ => {}
                }
                match len {
                    Some(Length::Var(k)) if k >= g.n_vars => {
                        return Err(err("unknown index out of range"))
                    }
                    Some(Length::Coord(j)) if j as usize >= MAX_DOF => {
                        return Err(ModelError::Capacity("coordinates"))
                    }
                    _ => {}
                }
            }
        }
        if g.chains.iter().filter(|c| c.end.is_some()).count() * 2 != g.n_vars as usize {
            return Err(err("unknowns and loop-closure equations differ in number"));
        }
        for p in g.placements.iter() {
            if p.link == 0 || p.link as usize > n_links {
                return Err(ModelError::UnknownReference("group: link"));
            }
            if known(&placed, p.link) {
                return Err(err("places a link an earlier group placed"));
            }
            if p.chain as usize >= g.chains.len() {
                return Err(err("placement on a missing chain"));
            }
        }
        for p in g.placements.iter() {
            if let Some(s) = placed.get_mut(p.link as usize) {
                *s = true;
            }
        }
        for j in g.joints.iter() {
            if !known(&placed, j.j) || !known(&placed, j.i) {
                return Err(err("a joint names a link that is not placed"));
            }
        }
        if let Some(c) = g.coord {
            let slot = coord_used
                .get_mut(c as usize)
                .ok_or(ModelError::Capacity("coordinates"))?;
            *slot = true;
            if !matches!(g.kind, GroupKind::MotorR | GroupKind::MotorT) {
                return Err(err("only motor elements drive coordinates"));
            }
        }
    }
    if let Some(k) = placed.iter().take(n_links + 1).position(|p| !p) {
        return Err(ModelError::Unplaced { link: k as u8 });
    }
    let dof = coord_used.iter().rposition(|u| *u).map_or(0, |k| k + 1);
    if coord_used.iter().take(dof).any(|u| !u) {
        return Err(ModelError::Coordinates(
            "a coordinate below the highest one is driven by no motor element",
        ));
    }
    m.dof = dof as u8;
    Ok(())
}
