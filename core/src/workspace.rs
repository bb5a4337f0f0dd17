//! The workspace: every buffer a step needs, preallocated (MuJoCo's `mjData`). One
//! workspace per simulation (and per thread); algorithms are functions over
//! `(&Model, &mut Workspace)`.

use crate::capacity::{ArrayStorage, Capacity, Generic};
use crate::config::{
    MAX_BODIES, MAX_DOF, MAX_DRIVES, MAX_GROUPS, MAX_GROUP_JOINTS, MAX_GROUP_VARS, POSE_ROWS,
};
use crate::in_place::{elements, uninit};
use crate::scalar::{Real, Vec2};
use crate::structomat::{Group, GroupData, GroupKind};
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use nalgebra::{SMatrix, SVector};

/// Pose and motion of one body: `P = o + R(θ)p` for its point `p`. The default is a
/// body at rest at θ = 0 (`cos θ = 1`), as the ground always is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState<T: Real> {
    /// Angle of the link frame, rad.
    pub theta: T,
    /// `cos θ`.
    pub c: T,
    /// `sin θ`.
    pub s: T,
    /// World position of the frame origin, m.
    pub o: Vec2<T>,
    /// Angular speed, rad/s.
    pub omega: T,
    /// Velocity of the frame origin, m/s.
    pub v: Vec2<T>,
    /// Angular acceleration, rad/s².
    pub alpha: T,
    /// Acceleration of the frame origin, m/s².
    pub a: Vec2<T>,
}

impl<T: Real> Default for BodyState<T> {
    fn default() -> Self {
        BodyState {
            theta: T::zero(),
            c: T::one(),
            s: T::zero(),
            o: Vec2::zeros(),
            omega: T::zero(),
            v: Vec2::zeros(),
            alpha: T::zero(),
            a: Vec2::zeros(),
        }
    }
}

/// A joint reaction from the kinetostatics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reaction<T: Real> {
    /// Force on the group's link `i` from body `j`, world frame, N (for a driver of a
    /// motor element T: the driving force along the guide).
    pub force: Vec2<T>,
    /// Moment on `i` from `j`, N·m: the reaction moment of a prismatic joint, or the
    /// driving torque of a motor element R.
    pub moment: T,
}

/// Each group's unknowns (rad or m), in sequence order: the warm start of its
/// Newton-Raphson. As many as the workspace has groups, with no padding: a step saves
/// them before each DP5 step, and a zeroed array of the core's limits (8 groups) cost
/// its copies and clears.
pub type GroupUnknowns<T> = heapless::Vec<[T; MAX_GROUP_VARS], MAX_GROUPS>;

/// One group's warm start: its unknowns and their cosines and sines.
pub type GroupWarmStart<T> = ([T; MAX_GROUP_VARS], [Vec2<T>; MAX_GROUP_VARS]);

/// The groups' warm starts as an evaluation left them: each group's unknowns and their
/// cosines and sines ([`GroupData::trig`]), of the groups that keep one
/// ([`keeps_warm_start`]), in order. Restored together, a re-evaluation of the state
/// they were saved at reproduces its bits; a step taken back restores them. As many
/// as the workspace has such groups (a step saves them before each attempt: the
/// zeroed arrays of the core's limits, 1.2 KB in f64, cost the Cortex-M7 about 2k
/// instructions a step in clears and copies).
#[derive(Clone, Debug, PartialEq)]
pub struct WarmStart<T: Real> {
    /// Each group's.
    pub groups: heapless::Vec<GroupWarmStart<T>, MAX_GROUPS>,
}

impl<T: Real> WarmStart<T> {
    /// No group's. A function, not a constant: a constant's value is materialised
    /// whole, its 1,152 B of unused capacity zeroed (a 1160 B clear a step on the
    /// Cortex-M7 in f64, where a runtime `Vec::new` writes only the length).
    pub fn new() -> Self {
        WarmStart {
            groups: heapless::Vec::new(),
        }
    }
}

impl<T: Real> Default for WarmStart<T> {
    fn default() -> Self {
        Self::new()
    }
}

/// Whether [`Workspace::warm_start`] saves a group of `kind`: all but an RRR dyad. Its
/// solve reads nothing of its last unknowns where it records its links' angles
/// (`Angles::Record`: the joint it constructs gives the angles, their cosines and
/// sines), and an evaluation after a restore records them (DP5's inner stages alone
/// leave them stale, and take them from the evaluation before). The twin's models are
/// mostly RRR dyads: their saves before each attempt were ~1.3 k Thumb-2 instructions
/// a step on the Cortex-M7 in f64, in copies.
pub fn keeps_warm_start(kind: GroupKind) -> bool {
    kind != GroupKind::Rrr
}

/// One group's Newton predictor: `∂x/∂q`, the bias accelerations and where they were
/// recorded (`(q, x)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Predictor<T: Real> {
    /// `∂x/∂q` ([`GroupData::dx_dq`]).
    pub dx_dq: SMatrix<T, MAX_GROUP_VARS, MAX_DOF>,
    /// `ẍ` at `q̈ = 0` ([`GroupData::xdd_bias`]).
    pub xdd_bias: [T; MAX_GROUP_VARS],
    /// Where they were recorded ([`GroupData::dx_dq_at`]).
    pub at: ([T; MAX_DOF], [T; MAX_GROUP_VARS]),
}

impl<T: Real> Default for Predictor<T> {
    fn default() -> Self {
        Predictor {
            dx_dq: SMatrix::zeros(),
            xdd_bias: [T::zero(); MAX_GROUP_VARS],
            at: ([T::zero(); MAX_DOF], [T::zero(); MAX_GROUP_VARS]),
        }
    }
}

/// Every group's [`Predictor`].
pub type Predictors<T> = [Predictor<T>; MAX_GROUPS];

/// Preallocated buffers of a mechanism's evaluation; its per-group arrays sized by the
/// capacity `C` (that of the model it evaluates).
#[derive(Debug, PartialEq)]
pub struct Workspace<T: Real, C: Capacity<T> = Generic> {
    /// Body states (index 0: the ground, at rest).
    pub body: [BodyState<T>; MAX_BODIES],
    /// Group states and scratch, in sequence order.
    pub group: C::GroupData,
    /// Coordinates of the last evaluation.
    pub q: [T; MAX_DOF],
    /// Their rates.
    pub qd: [T; MAX_DOF],
    /// Their accelerations (from the equations of motion).
    pub qdd: [T; MAX_DOF],
    /// Velocity transmission matrix `V = ∂P/∂q` (3 rows `x_G, y_G, θ` per moving link).
    pub v: SMatrix<T, POSE_ROWS, MAX_DOF>,
    /// Bias accelerations `a_b = V̇ q̇` of the COGs (`q̈ = 0`).
    pub a_bias: SVector<T, POSE_ROWS>,
    /// Applied loads `F` at the COGs (force, moment about the COG): gravity, motors,
    /// external loads.
    pub force: SVector<T, POSE_ROWS>,
    /// Reduced mass matrix `VᵀMV` (identity padding past the degrees of freedom).
    pub mass_q: SMatrix<T, MAX_DOF, MAX_DOF>,
    /// Generalized forces `Vᵀ(F - M a_b)`.
    pub gen_force: SVector<T, MAX_DOF>,
    /// Torque (N·m) or force (N) of each drive at the last evaluation.
    pub motor: [T; MAX_DRIVES],
    /// External moments set by the caller (N·m, CCW, by body index; index 0, the
    /// ground, is ignored), like MuJoCo's `xfrc_applied`: inputs that change at run time
    /// (a measured motor torque, a load torque) without rebuilding the model. Added to
    /// the applied loads of the equations of motion and of the kinetostatics; each
    /// acts between its link and the ground.
    pub applied_moment: [T; MAX_BODIES],
    /// Joint reactions of each group (kinetostatics), in the order of its joints.
    pub reactions: C::Reactions,
    /// Evaluations of the equations of motion so far.
    pub evaluations: u64,
}

impl<T: Real, C: Capacity<T>> Clone for Workspace<T, C> {
    fn clone(&self) -> Self {
        let mut w = Self::new();
        w.clone_from(self);
        w
    }

    /// Field by field, in place: no temporary workspace (13 KB in f64) on the stack.
    fn clone_from(&mut self, source: &Self) {
        let Workspace {
            body,
            group,
            q,
            qd,
            qdd,
            v,
            a_bias,
            force,
            mass_q,
            gen_force,
            motor,
            applied_moment,
            reactions,
            evaluations,
        } = self;
        *body = source.body;
        *group = source.group;
        *q = source.q;
        *qd = source.qd;
        *qdd = source.qdd;
        *v = source.v;
        *a_bias = source.a_bias;
        *force = source.force;
        *mass_q = source.mass_q;
        *gen_force = source.gen_force;
        *motor = source.motor;
        *applied_moment = source.applied_moment;
        *reactions = source.reactions;
        *evaluations = source.evaluations;
    }
}

/// The fields [`Workspace::init`] writes: a field added to [`Workspace`] and not there
/// fails to compile here.
#[allow(dead_code)]
fn fields_of<T: Real, C: Capacity<T>>(w: &Workspace<T, C>) {
    let Workspace {
        body: _,
        group: _,
        q: _,
        qd: _,
        qdd: _,
        v: _,
        a_bias: _,
        force: _,
        mass_q: _,
        gen_force: _,
        motor: _,
        applied_moment: _,
        reactions: _,
        evaluations: _,
    } = w;
}

impl<T: Real, C: Capacity<T>> Default for Workspace<T, C> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, C: Capacity<T>> Workspace<T, C> {
    /// A zeroed workspace.
    pub fn new() -> Self {
        Workspace {
            body: [BodyState::default(); MAX_BODIES],
            group: ArrayStorage::filled(GroupData::default()),
            q: [T::zero(); MAX_DOF],
            qd: [T::zero(); MAX_DOF],
            qdd: [T::zero(); MAX_DOF],
            v: SMatrix::zeros(),
            a_bias: SVector::zeros(),
            force: SVector::zeros(),
            mass_q: SMatrix::identity(),
            gen_force: SVector::zeros(),
            motor: [T::zero(); MAX_DRIVES],
            applied_moment: [T::zero(); MAX_BODIES],
            reactions: ArrayStorage::filled([Reaction::default(); MAX_GROUP_JOINTS]),
            evaluations: 0,
        }
    }

    /// Initialises `place` in place as [`Workspace::new`]'s zeroed workspace: nothing
    /// larger than one group's data (1.2 KB in f64) on the stack, where `new` builds the
    /// whole workspace (13.6 KB in f64) and moves it. For a workspace in a `static` or
    /// inside a larger value built in place (the twin's slots).
    pub fn init(place: &mut MaybeUninit<Self>) -> &mut Self {
        let p = place.as_mut_ptr();
        // SAFETY: every field of `*p` is written once through a raw pointer to it (no
        // reference to an uninitialised field is made; `fields_of` below fails to
        // compile if a field is added and not listed there), the arrays element by
        // element, so `*p` is initialised before `assume_init_mut`.
        unsafe {
            for b in elements(uninit(addr_of_mut!((*p).body))) {
                b.write(BodyState::default());
            }
            for g in C::GroupData::elements(uninit(addr_of_mut!((*p).group))) {
                g.write(GroupData::default());
            }
            addr_of_mut!((*p).q).write([T::zero(); MAX_DOF]);
            addr_of_mut!((*p).qd).write([T::zero(); MAX_DOF]);
            addr_of_mut!((*p).qdd).write([T::zero(); MAX_DOF]);
            addr_of_mut!((*p).v).write(SMatrix::zeros());
            addr_of_mut!((*p).a_bias).write(SVector::zeros());
            addr_of_mut!((*p).force).write(SVector::zeros());
            addr_of_mut!((*p).mass_q).write(SMatrix::identity());
            addr_of_mut!((*p).gen_force).write(SVector::zeros());
            addr_of_mut!((*p).motor).write([T::zero(); MAX_DRIVES]);
            addr_of_mut!((*p).applied_moment).write([T::zero(); MAX_BODIES]);
            for r in C::Reactions::elements(uninit(addr_of_mut!((*p).reactions))) {
                r.write([Reaction::default(); MAX_GROUP_JOINTS]);
            }
            addr_of_mut!((*p).evaluations).write(0);
            place.assume_init_mut()
        }
    }

    /// Back to the state of [`Workspace::new`], in place (a 13 KB workspace in f64 is
    /// not rebuilt on the stack).
    pub fn reset(&mut self) {
        self.reset_but_groups(0);
    }

    /// [`Workspace::reset`] but for the data of the first `n` groups, left as they are:
    /// for [`assemble`](crate::kinematics::assemble) of a model of `n` groups, which
    /// sets each group's data to its default before it solves it (once it succeeds,
    /// the workspace is the one a full reset would have given; most of the 13 KB are
    /// the 8 groups' data).
    pub fn reset_but_groups(&mut self, n: usize) {
        let Workspace {
            body,
            group,
            q,
            qd,
            qdd,
            v,
            a_bias,
            force,
            mass_q,
            gen_force,
            motor,
            applied_moment,
            reactions,
            evaluations,
        } = self;
        body.fill(BodyState::default());
        if let Some(rest) = group.get_mut(n..) {
            rest.fill(GroupData::default());
        }
        q.fill(T::zero());
        qd.fill(T::zero());
        qdd.fill(T::zero());
        // Whole-matrix stores (a memset), not nalgebra's element-by-element `fill`.
        *v = SMatrix::zeros();
        *a_bias = SVector::zeros();
        *force = SVector::zeros();
        *mass_q = SMatrix::identity();
        *gen_force = SVector::zeros();
        motor.fill(T::zero());
        applied_moment.fill(T::zero());
        reactions.fill([Reaction::default(); MAX_GROUP_JOINTS]);
        *evaluations = 0;
    }

    /// World position of link `body`'s centre of gravity, m.
    pub fn cog(&self, model: &crate::model::Model<T, C>, body: u8) -> Vec2<T> {
        match (self.body.get(body as usize), model.link(body)) {
            (Some(b), Some(l)) => b.o + crate::scalar::rotate_cs(b.c, b.s, &l.cog),
            _ => Vec2::zeros(),
        }
    }

    /// The warm starts of `groups` (the model's, this workspace's), to restore with
    /// [`Workspace::restore_warm_start`]: every group's but an RRR dyad's (see
    /// [`keeps_warm_start`]).
    pub fn warm_start(&self, groups: &[Group<T>]) -> WarmStart<T> {
        let mut saved = WarmStart::new();
        self.save_warm_start(groups, &mut saved);
        saved
    }

    /// [`Workspace::warm_start`] into `saved`, where it lives: a step's hot path saves
    /// its warm starts so (returned by value, the 1.2 KB in f64 were built in a local
    /// and moved: a 1160 B memcpy a step on the Cortex-M7).
    pub fn save_warm_start(&self, groups: &[Group<T>], saved: &mut WarmStart<T>) {
        saved.groups.clear();
        for (g, gd) in groups.iter().zip(self.group.iter()) {
            if keeps_warm_start(g.kind) {
                // Never full: the workspace holds at most MAX_GROUPS groups.
                let _ = saved.groups.push((gd.x, gd.trig));
            }
        }
    }

    /// Sets the unknowns of `groups` (those [`Workspace::warm_start`] saved) and their
    /// cosines and sines to `saved` (those of the saved unknowns: Newton starts from
    /// them as they are).
    pub fn restore_warm_start(&mut self, groups: &[Group<T>], saved: &WarmStart<T>) {
        let mut saved = saved.groups.iter();
        for (g, gd) in groups.iter().zip(self.group.iter_mut()) {
            if !keeps_warm_start(g.kind) {
                continue;
            }
            let Some((x, trig)) = saved.next() else {
                break;
            };
            gd.x = *x;
            gd.trig = *trig;
            gd.trig_at = *x;
        }
    }

    /// The groups' Newton predictors ([`GroupData::dx_dq`], `xdd_bias`, `dx_dq_at`):
    /// with the warm start, what the next position solve starts from. A step taken back
    /// restores them too, or its retry would start from the failed attempt's prediction.
    pub fn predictors(&self) -> Predictors<T> {
        core::array::from_fn(|i| {
            self.group
                .get(i)
                .map_or_else(Predictor::default, |g| Predictor {
                    dx_dq: g.dx_dq,
                    xdd_bias: g.xdd_bias,
                    at: g.dx_dq_at,
                })
        })
    }

    /// Restores predictors saved by [`Workspace::predictors`].
    pub fn restore_predictors(&mut self, saved: &Predictors<T>) {
        for (g, p) in self.group.iter_mut().zip(saved.iter()) {
            g.dx_dq = p.dx_dq;
            g.xdd_bias = p.xdd_bias;
            g.dx_dq_at = p.at;
        }
    }

    /// The groups' unknowns alone.
    pub fn unknowns(&self) -> GroupUnknowns<T> {
        let mut x = heapless::Vec::new();
        for g in self.group.iter() {
            // Never full (see `warm_start`).
            let _ = x.push(g.x);
        }
        x
    }

    /// Sets the groups' unknowns to `x`, leaving their cosines and sines: Newton takes
    /// them anew from an unknown that moved.
    pub fn restore_unknowns(&mut self, x: &GroupUnknowns<T>) {
        for (g, x) in self.group.iter_mut().zip(x.iter()) {
            g.x = *x;
        }
    }
}
