//! One mode's model, its body map and its workspace, and what the twin reads from them:
//! the equations of motion with the twin's inputs, the physical state of every link,
//! the transmitted torques c6, c8 and the joint reactions.

use super::super::build::{build_into, BodyMap, BRANCHES, CRANK};
use super::super::mode::{Clutch, Coordinates, Mode};
use super::super::params::{CccParams, Friction, FRICTION_JOINTS};
use super::capacity::Converter;
use super::coast::Coast;
use super::error::TwinStepError;
use super::inputs::Inputs;
use crate::dynamics::solve_accelerations;
use crate::error::{GroupId, StepError};
use crate::in_place::uninit;
use crate::integrator::OdeSystem;
use crate::kinematics::assemble;
use crate::kinematics::{group_id, position};
use crate::model::Model;
use crate::scalar::{cross, perp, rotate_cs, Real, Vec2};
use crate::structomat::JointKind;
use crate::structomat::{Angles, GroupKind};
use crate::transmission::{evaluate_velocities, evaluate_with};
use crate::workspace::{WarmStart, Workspace};
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use nalgebra::SVector;

/// Length of the integrated state: `[q (2 slots), q̇ (2 slots), W_motor, W_load]`. The
/// two works (J) are integrated with the motion, at the integrator's order, for the
/// energy audit.
pub(crate) const STATE: usize = 6;
/// Offset of `q̇` in the state.
pub(crate) const QD: usize = 2;
/// Index of the motor's work.
pub(crate) const W_MOTOR: usize = 4;
/// Index of the work done against the load.
pub(crate) const W_LOAD: usize = 5;

/// A link's physical state (SPEC 3's numbering), whatever the mode's model.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LinkState<T: Real> {
    /// Angle of the link frame (first joint to second), rad, CCW, unwrapped.
    pub theta: T,
    /// Angular speed, rad/s.
    pub omega: T,
    /// Angular acceleration, rad/s².
    pub alpha: T,
    /// Frame origin (the link's first joint), m.
    pub origin: Vec2<T>,
    /// Its velocity, m/s.
    pub velocity: Vec2<T>,
}

impl<T: Real> LinkState<T> {
    /// A point `cog` of the link (in its frame, m) seen from the frame's origin in the
    /// common frame, and its velocity (m/s), the frame's direction `frame` (cos, sin):
    /// the audit's and the momentum mapping's centre of mass.
    pub(crate) fn point_motion(&self, frame: &Vec2<T>, cog: &Vec2<T>) -> (Vec2<T>, Vec2<T>) {
        let r = rotate_cs(frame.x, frame.y, cog);
        (r, self.velocity + perp(&r) * self.omega)
    }
}

/// A mode's model and workspace, sized for the converter ([`Converter`]).
#[derive(Debug)]
pub(crate) struct Slot<T: Real> {
    pub model: Model<T, Converter>,
    pub map: BodyMap<T>,
    pub ws: Workspace<T, Converter>,
    pub mode: Mode,
    pub coords: Coordinates,
    /// Whether `model` is the built model of `mode` and `coords` and `ws` holds an
    /// assembly of it (its groups' branches), which [`Slot::reposition`] can move.
    pub built: bool,
}

impl<T: Real> Clone for Slot<T> {
    fn clone(&self) -> Self {
        Slot {
            model: self.model.clone(),
            map: self.map,
            ws: self.ws.clone(),
            mode: self.mode,
            coords: self.coords,
            built: self.built,
        }
    }

    /// In place: no temporary slot on the stack.
    fn clone_from(&mut self, source: &Self) {
        self.model.clone_from(&source.model);
        self.map = source.map;
        self.ws.clone_from(&source.ws);
        self.mode = source.mode;
        self.coords = source.coords;
        self.built = source.built;
    }
}

/// The fields [`Slot::init_empty`] writes: a field added to [`Slot`] and not there fails
/// to compile here.
#[allow(dead_code)]
fn fields_of<T: Real>(s: &Slot<T>) {
    let Slot {
        model: _,
        map: _,
        ws: _,
        mode: _,
        coords: _,
        built: _,
    } = s;
}

impl<T: Real> Slot<T> {
    /// A slot to build into: an empty model (no links), not assembled.
    pub fn empty() -> Self {
        Slot {
            model: Model::empty(),
            map: BodyMap::default(),
            ws: Workspace::new(),
            mode: Mode::Free,
            coords: Coordinates::CrankSwing,
            built: false,
        }
    }

    /// [`Slot::empty`] initialised in place (a slot is 30 KB in f64): the model and the
    /// workspace by their own in-place constructors.
    pub fn init_empty(place: &mut MaybeUninit<Self>) -> &mut Self {
        let p = place.as_mut_ptr();
        // SAFETY: every field of `*p` is written once through a raw pointer to it (no
        // reference to an uninitialised field is made; `fields_of` below fails to
        // compile if a field is added and not listed there), so `*p` is initialised
        // before `assume_init_mut`. `uninit` hands each in-place constructor its field
        // alone.
        unsafe {
            Model::init_empty(uninit(addr_of_mut!((*p).model)));
            addr_of_mut!((*p).map).write(BodyMap::default());
            Workspace::init(uninit(addr_of_mut!((*p).ws)));
            addr_of_mut!((*p).mode).write(Mode::Free);
            addr_of_mut!((*p).coords).write(Coordinates::CrankSwing);
            addr_of_mut!((*p).built).write(false);
            place.assume_init_mut()
        }
    }

    /// Builds, in this slot, the model of `mode` driven by `coords` at the physical
    /// angles `pose` (index 1..=8) and assembles it there; returns its coordinates. In
    /// place, so that no slot (30 KB in f64) is ever a temporary on the stack. On an
    /// error (the model builder's, or a group's that fails to assemble, in physical
    /// link numbers) the slot holds a half-built mode and must be rebuilt before use.
    pub fn rebuild(
        &mut self,
        params: &CccParams<T>,
        mode: Mode,
        coords: Coordinates,
        pose: &[T; 9],
        time: f64,
    ) -> Result<[T; 2], TwinStepError> {
        self.built = false;
        self.map = build_into(params, mode, coords, pose, &mut self.model)
            .map_err(|error| TwinStepError::Model { time, mode, error })?;
        self.mode = mode;
        self.coords = coords;
        // `assemble` resets the data of the model's groups itself.
        self.ws.reset_but_groups(self.model.groups().len());
        let q = self.assemble_at(pose, time)?;
        self.built = true;
        Ok(q)
    }

    /// [`Slot::rebuild`] without building the model again when the slot holds the
    /// model of `mode` and `coords`, assembled, and it is the model a rebuild at `pose`
    /// would give, up to rounding: a position pass at `pose`'s coordinates from the
    /// groups' present branches then places every physical link at its angle in
    /// `pose` (the same branches, the same locked pins and A68 lever offset; only the
    /// assembly guesses, the angles at the last build, differ). Otherwise (or if the
    /// pass fails) it rebuilds. Dyads give the same bits as a rebuild; a Newton group
    /// (triad, six-link group) converges from its last unknowns instead of the guesses.
    pub fn reposition(
        &mut self,
        params: &CccParams<T>,
        mode: Mode,
        coords: Coordinates,
        pose: &[T; 9],
        time: f64,
    ) -> Result<[T; 2], TwinStepError> {
        // The declared parts first: they need no position pass.
        if self.built && self.mode == mode && self.coords == coords && self.declares(pose) {
            let q = self.map.coordinates_at(pose);
            let placed = position(
                &self.model,
                &mut self.ws,
                q.get(..self.map.dof).unwrap_or(&[]),
                time,
            )
            .is_ok();
            if placed && self.placed_at(params, pose) {
                return Ok(q);
            }
        }
        self.rebuild(params, mode, coords, pose, time)
    }

    /// Whether the slot's model is the one a rebuild at `pose` would declare, up to
    /// rounding (its mode and coordinates being the same). The state-dependent parts
    /// are checked to rounding: a locked lever's pin was placed at exactly its angle in
    /// `pose` (a lever locked again near where it locked before is a new pin), and
    /// A68's lever offset is `pose`'s angle between the levers to 16 ulps.
    fn declares(&self, pose: &[T; 9]) -> bool {
        let th = |p: usize| pose.get(p).copied().unwrap_or(T::zero());
        BRANCHES.iter().all(|(_, lever)| {
            let off = self.map.offset(*lever);
            if self.body(*lever) == 0 {
                return off == th(*lever);
            }
            if off == T::zero() {
                return true;
            }
            // Lever 8 in A68, in lever 6's body.
            let (_, l6) = BRANCHES[0];
            let between = th(*lever) - th(l6);
            let ulps = T::EPS * T::c(16.0) * (th(*lever).abs() + th(l6).abs() + T::one());
            (off - between).abs() <= ulps
        })
    }

    /// Whether the slot's last position pass placed every physical link at its angle in
    /// `pose` (modulo 2π) to 1e-6 rad (1000 ulps in f32): a wrong branch is off by a
    /// sizeable angle, rounding by ~1e-13 rad.
    fn placed_at(&self, params: &CccParams<T>, pose: &[T; 9]) -> bool {
        let tol = T::c(1e-6).max(T::EPS * T::c(1e3));
        self.links(params)
            .iter()
            .zip(pose.iter())
            .skip(1)
            .all(|(l, p)| (l.theta - unwrap_near(*p, l.theta)).abs() <= tol)
    }

    /// Assembles the slot's model at the physical angles `pose` from a fresh workspace;
    /// returns the coordinates there.
    fn assemble_at(&mut self, pose: &[T; 9], time: f64) -> Result<[T; 2], TwinStepError> {
        let q = self.map.coordinates_at(pose);
        assemble(
            &self.model,
            &mut self.ws,
            q.get(..self.map.dof).unwrap_or(&[]),
        )
        .map_err(|e| TwinStepError::Step(physical(&self.map, retime(e, time))))?;
        Ok(q)
    }

    /// The warm starts of the slot's groups ([`Workspace::warm_start`]).
    pub fn warm_start(&self) -> WarmStart<T> {
        self.ws.warm_start(self.model.groups())
    }

    /// [`Slot::warm_start`] into `saved` ([`Workspace::save_warm_start`]).
    pub fn save_warm_start(&self, saved: &mut WarmStart<T>) {
        self.ws.save_warm_start(self.model.groups(), saved);
    }

    /// Model body of physical link `p` (0: held still).
    pub fn body(&self, p: usize) -> u8 {
        self.map.body.get(p).copied().unwrap_or(0)
    }

    /// The row of the transmission matrix `V` that gives physical link `p`'s angular
    /// speed from the coordinates' rates: `ω_p = r[0] q̇₁ + r[1] q̇₂` (rows `3(b-1)+2` of
    /// `V` are the bodies' rotations, SPEC 1). Zeros for a link the mode has no body for.
    pub fn omega_row(&self, p: usize) -> [T; 2] {
        let b = self.body(p) as usize;
        if b == 0 {
            return [T::zero(); 2];
        }
        let r = 3 * (b - 1) + 2;
        let v = &self.ws.v;
        // V has three rows per body of the validated model, so `r` is in range; the
        // checked reads keep the step path free of a reachable panic.
        let at = |c: usize| v.get((r, c)).copied().unwrap_or_else(T::zero);
        [at(0), at(1)]
    }

    /// `adj(M) x` and `det M` of the 2×2 mass matrix of a 2-DOF mode at the last
    /// evaluation (`M⁻¹ x = adj(M) x / det M` where `det M > 0`): the solves of the
    /// crank's correction direction and of its mass sensitivity.
    pub(super) fn mass_adjugate_times(&self, x: [T; 2]) -> ([T; 2], T) {
        let m = |i: usize, j: usize| self.ws.mass_q.get((i, j)).copied().unwrap_or(T::zero());
        (
            [
                m(1, 1) * x[0] - m(0, 1) * x[1],
                m(0, 0) * x[1] - m(1, 0) * x[0],
            ],
            m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
        )
    }

    /// Physical link `p`'s angular acceleration at `q̈ = 0` (the bias `a_b` of the last
    /// evaluation, SPEC 1): `α_p = omega_row(p)·q̈ + alpha_bias(p)`. Zero for a link the
    /// mode has no body for.
    pub fn alpha_bias(&self, p: usize) -> T {
        match self.body(p) as usize {
            0 => T::zero(),
            b => self
                .ws
                .a_bias
                .get(3 * (b - 1) + 2)
                .copied()
                .unwrap_or(T::zero()),
        }
    }

    /// [`Slot::omega_row`] as a row over `(q̇₁, q̇₂, ω_shaft)`: lever `p`'s speed from the
    /// coordinates' rates, the shaft's column zero (the rows of the mode choice's
    /// constraints).
    pub fn lever_row(&self, p: usize) -> SVector<T, 3> {
        let [v0, v1] = self.omega_row(p);
        SVector::<T, 3>::new(v0, v1, T::zero())
    }

    /// The body the shaft and the load act on (A modes), if any.
    pub fn shaft_body(&self) -> Option<u8> {
        let c = self.mode.clutches();
        BRANCHES
            .iter()
            .zip(c.iter())
            .find(|(_, c)| **c == Clutch::Engaged)
            .map(|((_, lever), _)| self.body(*lever))
    }

    /// Evaluates the equations of motion at `(t, y)` with the inputs: kinematics, then
    /// the motor torque on the crank (from its evaluated speed), the load on the
    /// engaged lever and, when any is on, the losses `friction` (joint friction, clutch
    /// drag; `shaft`: the coasting shaft's speed at `t` in [`Mode::Coast`], rad/s, which
    /// the overrunning levers drag against) as applied moments, then `q̈`.
    pub fn eval(
        &mut self,
        t: T,
        y: &SVector<T, STATE>,
        inputs: &Inputs<T>,
        drive: T,
        friction: Option<&Friction<T>>,
        shaft: T,
    ) -> Result<(), StepError> {
        self.eval_with(t, y, inputs, (drive, friction, shaft), Some(Angles::Record))
    }

    /// [`Slot::eval`], the dyads' link angles recorded or left stale (`angles`: stale
    /// only where the motor law does not read the crank's angle, see [`Angles`]), or
    /// at the kinematics the workspace holds (`None`: the motor's and the load's
    /// torques, the losses and `q̈` only; the kinematics are a function of the state
    /// alone, so a state evaluated before under other inputs needs only these).
    pub(super) fn eval_with(
        &mut self,
        t: T,
        y: &SVector<T, STATE>,
        inputs: &Inputs<T>,
        (drive, friction, shaft): (T, Option<&Friction<T>>, T),
        angles: Option<Angles>,
    ) -> Result<(), StepError> {
        if let Some(angles) = angles {
            let n = self.map.dof.min(2);
            let s = y.as_slice();
            let q = s.get(..n).unwrap_or(&[]);
            let qd = s.get(QD..QD + n).unwrap_or(&[]);
            let angles = if inputs.motor.is_user_law() {
                Angles::Record
            } else {
                angles
            };
            evaluate_with(&self.model, &mut self.ws, q, qd, t.to_f64(), angles)?;
        }
        let crank = self
            .ws
            .body
            .get(self.body(CRANK) as usize)
            .copied()
            .unwrap_or_default();
        let tm = inputs.motor.torque(t, crank.theta, crank.omega);
        if !(tm.finite() && inputs.load.finite()) {
            return Err(StepError::NonFinite {
                time: t.to_f64(),
                what: "motor or load torque",
            });
        }
        self.ws.applied_moment.fill(T::zero());
        let crank_body = self.body(CRANK) as usize;
        if let Some(m) = self.ws.applied_moment.get_mut(crank_body) {
            *m = tm;
        }
        if let Some(b) = self.shaft_body() {
            // The load opposes the shaft's rotation, which is in the drive direction.
            if let Some(m) = self.ws.applied_moment.get_mut(b as usize) {
                *m -= drive * inputs.load;
            }
        }
        if let Some(friction) = friction {
            let mut moments = self.ws.applied_moment;
            self.losses(friction, shaft, |body, tau, _| {
                if body != 0 {
                    if let Some(m) = moments.get_mut(body as usize) {
                        *m += tau;
                    }
                }
            });
            self.ws.applied_moment = moments;
        }
        solve_accelerations(&self.model, &mut self.ws, t)
    }

    /// Physical link `p`'s angular speed at the last evaluation (0 for the ground and
    /// a locked lever), rad/s.
    pub fn omega_of(&self, p: usize) -> T {
        match self.body(p) {
            0 => T::zero(),
            b => self.ws.body.get(b as usize).map_or(T::zero(), |s| s.omega),
        }
    }

    /// The losses (SPEC 5) at the last evaluation's speeds: `visit(body, torque, w)`
    /// for each torque (N·m) a loss applies to a model body (0: the ground, or a held
    /// shaft), `w` (rad/s) the speed of that body relative to the other one the loss
    /// acts between. Each loss visits its two bodies with opposite torques and speeds,
    /// so `-Σ torque·w / 2` over the visits is the power it dissipates. Joint friction
    /// at every joint of [`FRICTION_JOINTS`] with a coefficient; the drag of each
    /// overrunning clutch against the shaft (the engaged lever's body in an A mode, the
    /// held shaft in an I mode, the coasting shaft [`COASTING_SHAFT`] at its speed
    /// `shaft` in [`Mode::Coast`]; none in the free mode, which has no diode).
    fn losses(&self, f: &Friction<T>, shaft_w: T, mut visit: impl FnMut(u8, T, T)) {
        for (k, (i, j)) in FRICTION_JOINTS.iter().enumerate() {
            let c = f.viscous.get(k).copied().unwrap_or(T::zero());
            let mu = f.coulomb.get(k).copied().unwrap_or(T::zero());
            if c == T::zero() && mu == T::zero() {
                continue;
            }
            let (i, j) = (*i as usize, *j as usize);
            let w = self.omega_of(i) - self.omega_of(j);
            let tau = f.joint_torque(c, mu, w);
            visit(self.body(i), -tau, w);
            visit(self.body(j), tau, -w);
        }
        if f.clutch_drag == T::zero() || self.mode == Mode::Free {
            return;
        }
        let coasting = self.mode == Mode::Coast;
        let shaft = if coasting {
            COASTING_SHAFT
        } else {
            self.shaft_body().unwrap_or(0)
        };
        let ws = self
            .ws
            .body
            .get(shaft as usize)
            .map_or(T::zero(), |s| s.omega);
        let ws = match shaft {
            COASTING_SHAFT => shaft_w,
            0 => T::zero(),
            _ => ws,
        };
        for ((_, lever), clutch) in BRANCHES.iter().zip(self.mode.clutches()) {
            if clutch != Clutch::Free {
                continue;
            }
            let w = self.omega_of(*lever) - ws;
            let tau = f.clutch_drag * w;
            visit(self.body(*lever), -tau, w);
            visit(shaft, tau, -w);
        }
    }

    /// The kinematics at `y` up to the velocities only (see [`evaluate_velocities`]):
    /// the links' positions and speeds, not their accelerations.
    pub fn eval_speeds(&mut self, t: T, y: &SVector<T, STATE>) -> Result<(), StepError> {
        let n = self.map.dof.min(2);
        let s = y.as_slice();
        let q = s.get(..n).unwrap_or(&[]);
        let qd = s.get(QD..QD + n).unwrap_or(&[]);
        evaluate_velocities(&self.model, &mut self.ws, q, qd, t.to_f64(), Angles::Record)
    }

    /// `dy` of the state after [`Slot::eval`]: `q̇`, `q̈`, motor power, load power (with
    /// the power the losses `friction` dissipate, when any is on; `shaft` as there).
    pub fn rates(
        &self,
        y: &SVector<T, STATE>,
        inputs: &Inputs<T>,
        drive: T,
        friction: Option<&Friction<T>>,
        shaft: T,
    ) -> SVector<T, STATE> {
        let mut dy = SVector::<T, STATE>::zeros();
        let n = self.map.dof.min(2);
        for k in 0..n {
            dy[k] = y[QD + k];
            dy[QD + k] = self.ws.qdd.get(k).copied().unwrap_or(T::zero());
        }
        let crank = self.body(CRANK) as usize;
        let w1 = self.ws.body.get(crank).map_or(T::zero(), |b| b.omega);
        let mut on_crank = self
            .ws
            .applied_moment
            .get(crank)
            .copied()
            .unwrap_or(T::zero());
        let mut loss = T::zero();
        if let Some(friction) = friction {
            // The crank's applied moment holds its joints' friction as well: the
            // motor's alone is its power.
            self.losses(friction, shaft, |body, tau, w| {
                if body as usize == crank {
                    on_crank -= tau;
                }
                loss -= tau * w;
                if body == COASTING_SHAFT {
                    // The coasting shaft's share (the drag's work on it) is booked with
                    // its own motion (`Twin::coast_to`): the two visits here count the
                    // drag's work on the lever alone, `τ·ω_k` each (`w = ω_s − ω_k`).
                    loss += T::c(2.0) * tau * shaft;
                }
            });
        }
        dy[W_MOTOR] = on_crank * w1;
        if let Some(b) = self.shaft_body() {
            let ws = self.ws.body.get(b as usize).map_or(T::zero(), |b| b.omega);
            dy[W_LOAD] = inputs.load * drive * ws;
        }
        if friction.is_some() {
            // Each loss visits its two bodies: half the sum is its power.
            dy[W_LOAD] += loss * T::c(0.5);
        }
        dy
    }

    /// Physical state of links 1..=8 (index 0 unused) at the workspace's evaluation;
    /// angles as the model holds them (the twin unwraps them). Not inlined: inlined
    /// into its callers it raised the M7 step's painted stack from 14.4 to 15.0 KB for
    /// 80 instructions a step.
    #[inline(never)]
    pub fn links(&self, params: &CccParams<T>) -> [LinkState<T>; 9] {
        // Each link's fields are written from its body read through a reference: a
        // body copied out to be read and a link built from defaults cost the M7 about
        // 0.5 k instructions a step in memory copies and clears.
        let mut out = [LinkState::default(); 9];
        for (p, o) in out.iter_mut().enumerate().skip(1) {
            let off = self.map.offset(p);
            match self.body(p) {
                // A locked lever: at rest about H.
                0 => {
                    o.theta = off;
                    o.origin = params.h;
                }
                b => match self.ws.body.get(b as usize) {
                    Some(s) => {
                        o.theta = s.theta + off;
                        o.omega = s.omega;
                        o.alpha = s.alpha;
                        o.origin = s.o;
                        o.velocity = s.v;
                    }
                    // No such body (a model not built): a body at its default.
                    None => o.theta = T::zero() + off,
                },
            }
        }
        out
    }

    /// Physical link `p`'s frame direction `(cos θ_p, sin θ_p)` at the last evaluation,
    /// from its model body's evaluated frame: a sine and cosine are computed only for a
    /// link with an angle offset (a locked lever, lever 8 in A68).
    pub fn frame(&self, p: usize) -> Vec2<T> {
        let off = self.map.offset(p);
        // `Real::sincos`: in f32 in f32 arithmetic (libm's `sinf` and `cosf` work in
        // f64 inside, soft-float calls on the M4F: 2.5 k instructions a step of S2
        // for the locked levers' frames).
        let turn = |a: T| {
            let (sin, cos) = a.sincos();
            Vec2::new(cos, sin)
        };
        let b = self.body(p);
        if b == 0 {
            return turn(off);
        }
        match self.ws.body.get(b as usize) {
            Some(s) if off == T::zero() => Vec2::new(s.c, s.s),
            Some(s) => rotate_cs(s.c, s.s, &turn(off)),
            // No such body (a model not built): a body at its default, `(1, 0)`.
            None if off == T::zero() => Vec2::new(T::one(), T::zero()),
            None => rotate_cs(T::one(), T::zero(), &turn(off)),
        }
    }

    /// [`Slot::frame`] of every physical link (index 0 unused).
    pub fn frames(&self) -> [Vec2<T>; 9] {
        core::array::from_fn(|p| self.frame(p))
    }

    /// The force on lever `lever` (6 or 8) from its rod at its pin (G or I), N, from
    /// the last kinetostatics; zero if the model has no such joint.
    fn rod_force_on_lever(&self, rod: usize, lever: usize) -> Vec2<T> {
        let (br, bl) = (self.body(rod), self.body(lever));
        for (g, r) in self.model.groups().iter().zip(self.ws.reactions.iter()) {
            for (jt, re) in g.joints.iter().zip(r.iter()) {
                if jt.kind != JointKind::Revolute {
                    continue;
                }
                if jt.i == br && jt.j == bl {
                    return -re.force;
                }
                if jt.i == bl && jt.j == br {
                    return re.force;
                }
            }
        }
        Vec2::zeros()
    }

    /// The transmitted torques `[c6, c8]` (SPEC 3), N·m, positive in the drive
    /// direction, after the kinetostatics: for a locked or engaged lever, the moment
    /// about H of its rod's force and its weight, minus `I_H α` when it turns; 0 for a
    /// free lever.
    pub fn clutch_torques(&self, params: &CccParams<T>, links: &[LinkState<T>; 9]) -> [T; 2] {
        let d = params.drive.sign::<T>();
        let mut c = [T::zero(); 2];
        let branches = c.iter_mut().zip(BRANCHES).zip(self.mode.clutches());
        for (k, ((ck, (rod, lever)), clutch)) in branches.enumerate() {
            if clutch == Clutch::Free {
                continue;
            }
            let s = links.get(lever).copied().unwrap_or_default();
            let len = params.link(lever).length;
            let u = self.frame(lever);
            let tip = u * len;
            let cog = u * (len * T::c(0.5));
            let weight = params.gravity * params.link(lever).mass;
            let mut m = cross(&tip, &self.rod_force_on_lever(rod, lever)) + cross(&cog, &weight);
            if let Some((cv, mu)) = pin_friction(&params.friction, k) {
                // The friction at the lever's pin (G, I) acts on it beside the rod's
                // force: the torque on the lever, its speed relative to the rod's.
                let rod_w = links.get(rod).map_or(T::zero(), |r| r.omega);
                m -= params.friction.joint_torque(cv, mu, s.omega - rod_w);
            }
            *ck = d * (m - params.lever_inertia_about_h(lever) * s.alpha);
        }
        c
    }

    /// Physical joint reactions (see [`JOINTS`]) from the last kinetostatics: force on
    /// the first link of each pair from the second, N. The shaft's forces on the levers
    /// come from each lever's own equation of motion about the fixed H.
    pub fn joint_reactions(
        &self,
        params: &CccParams<T>,
        links: &[LinkState<T>; 9],
    ) -> [Vec2<T>; 11] {
        let mut out = [Vec2::zeros(); 11];
        let phys = |b: u8| self.map.phys.get(b as usize).copied().unwrap_or(0);
        for (g, r) in self.model.groups().iter().zip(self.ws.reactions.iter()) {
            for (jt, re) in g.joints.iter().zip(r.iter()) {
                if jt.kind != JointKind::Revolute {
                    continue;
                }
                // A rod pinned to the ground is pinned to its locked lever.
                let locked_lever = |rod: u8| {
                    BRANCHES
                        .iter()
                        .find(|(r, _)| *r as u8 == rod)
                        .map_or(0, |(_, l)| *l as u8)
                };
                let (mut pi, mut pj) = (phys(jt.i), phys(jt.j));
                if pj == 0 {
                    pj = locked_lever(pi);
                } else if pi == 0 {
                    pi = locked_lever(pj);
                }
                // In A68 lever 8 is part of lever 6's body: rod 7 pins to lever 8.
                let (r7, l8) = BRANCHES[1];
                let (_, l6) = BRANCHES[0];
                if (pi, pj) == (l6 as u8, r7 as u8) {
                    pi = l8 as u8;
                } else if (pi, pj) == (r7 as u8, l6 as u8) {
                    pj = l8 as u8;
                }
                let at = JOINT_AT
                    .get(pi as usize)
                    .and_then(|row| row.get(pj as usize))
                    .copied()
                    .unwrap_or(0);
                let k = at.unsigned_abs() as usize;
                if let Some(o) = k.checked_sub(1).and_then(|k| out.get_mut(k)) {
                    *o = if at > 0 { re.force } else { -re.force };
                }
            }
        }
        // Lever k about the fixed H: m a_G = R_rod + R_H + m g.
        for (slot, (tip_joint, lever)) in [(9usize, (7usize, 6usize)), (10, (8, 8))] {
            let s = links.get(lever).copied().unwrap_or_default();
            let b = params.link(lever);
            let r = self.frame(lever) * (b.length * T::c(0.5));
            let a_g = perp(&r) * s.alpha - r * (s.omega * s.omega);
            let on_lever_from_rod = out.get(tip_joint).copied().unwrap_or_default();
            if let Some(o) = out.get_mut(slot) {
                *o = a_g * b.mass - on_lever_from_rod - params.gravity * b.mass;
            }
        }
        out
    }

    /// Smallest normalized determinant over the sequence's groups at the last
    /// evaluation (1 for a well-conditioned sequence, 0 at a dead point).
    pub fn conditioning(&self) -> T {
        self.worst_group().1
    }

    /// The worst-conditioned group of the sequence (physical link numbers) and its
    /// normalized determinant at the last evaluation.
    pub fn worst_group(&self) -> (GroupId, T) {
        let mut worst = (0, T::one());
        for (k, g) in self
            .ws
            .group
            .iter()
            .take(self.model.groups().len())
            .enumerate()
        {
            if g.conditioning < worst.1 {
                worst = (k, g.conditioning);
            }
        }
        let id = self.model.groups().get(worst.0).map_or(
            GroupId {
                index: 0,
                kind: GroupKind::MotorR,
                links: [0; crate::config::MAX_GROUP_LINKS],
                count: 0,
            },
            |g| physical_group(&self.map, group_id(g, worst.0)),
        );
        (id, worst.1)
    }
}

/// The physical joints, as `(i, j)`: the reaction reported is the force on link `i`
/// from link `j` (0: the ground or the shaft). A, B, C, E, F, D (rod 5), D (rod 7), G,
/// I, H (lever 6), H (lever 8).
pub const JOINTS: [(u8, u8); 11] = {
    // The revolute joints with friction (A … I), then the two clutches at H.
    let mut all = [(0, 0); 11];
    let mut k = 0;
    while k < FRICTION_JOINTS.len() {
        all[k] = FRICTION_JOINTS[k];
        k += 1;
    }
    all[9] = (6, 0);
    all[10] = (8, 0);
    all
};

/// [`JOINTS`] by the pair of physical links: `k + 1` at `[i][j]` for the pair
/// `JOINTS[k] = (i, j)`, `-(k + 1)` at `[j][i]` (the force on `j` from `i` is the
/// reaction's opposite), 0 for links that share no joint. A model joint finds its
/// physical one in one look-up, not by a scan of the eleven (the twin commits the
/// reactions at every step).
const JOINT_AT: [[i8; 9]; 9] = {
    let mut at = [[0i8; 9]; 9];
    let mut k = 0;
    while k < JOINTS.len() {
        let (i, j) = JOINTS[k];
        at[i as usize][j as usize] = k as i8 + 1;
        at[j as usize][i as usize] = -(k as i8 + 1);
        k += 1;
    }
    at
};

/// The index in [`FRICTION_JOINTS`] of each lever's pin (G of lever 6, I of lever 8:
/// `(lever, rod)`, in `BRANCHES` order).
const PIN_JOINTS: [usize; 2] = [7, 8];
const _: () = {
    let [(r5, l6), (r7, l8)] = BRANCHES;
    let [g, i] = PIN_JOINTS;
    assert!(
        FRICTION_JOINTS[g].0 as usize == l6 && FRICTION_JOINTS[g].1 as usize == r5,
        "G is lever 6 on rod 5"
    );
    assert!(
        FRICTION_JOINTS[i].0 as usize == l8 && FRICTION_JOINTS[i].1 as usize == r7,
        "I is lever 8 on rod 7"
    );
};

/// The viscous and dry coefficients at branch `k`'s lever pin, if it has any friction.
fn pin_friction<T: Real>(f: &Friction<T>, k: usize) -> Option<(T, T)> {
    let j = PIN_JOINTS.get(k).copied().unwrap_or(0);
    let c = f.viscous.get(j).copied().unwrap_or(T::zero());
    let mu = f.coulomb.get(j).copied().unwrap_or(T::zero());
    (c != T::zero() || mu != T::zero()).then_some((c, mu))
}

/// Names of [`JOINTS`], for CSV headers.
pub const JOINT_NAMES: [&str; 11] = ["A", "B", "C", "E", "F", "D5", "D7", "G", "I", "H6", "H8"];

/// The model body [`Slot::losses`] names the coasting shaft by: none of the model's
/// (it is no body of the linkage), so no moment is applied to it there.
pub(crate) const COASTING_SHAFT: u8 = u8::MAX;

/// The ODE of a slot with its inputs, for the integrator.
pub(crate) struct Equations<'a, T: Real> {
    pub slot: &'a mut Slot<T>,
    pub inputs: &'a Inputs<T>,
    pub drive: T,
    pub friction: Option<&'a Friction<T>>,
    /// The coasting shaft's motion ([`Mode::Coast`]).
    pub coast: Coast<T>,
    /// Whether the next evaluation is an inner stage of the integrator's step: its
    /// links' angles are left stale ([`Angles::Stale`]; only a step's end is a state
    /// the twin reads its links at). False until the integrator says.
    pub inner: bool,
}

impl<T: Real> OdeSystem<T, STATE> for Equations<'_, T> {
    type Error = StepError;
    fn eval(
        &mut self,
        t: T,
        y: &SVector<T, STATE>,
        dy: &mut SVector<T, STATE>,
    ) -> Result<(), StepError> {
        let shaft = self.coast.omega_at(t);
        let angles = if self.inner {
            Angles::Stale
        } else {
            Angles::Record
        };
        self.slot.eval_with(
            t,
            y,
            self.inputs,
            (self.drive, self.friction, shaft),
            Some(angles),
        )?;
        *dy = self
            .slot
            .rates(y, self.inputs, self.drive, self.friction, shaft);
        Ok(())
    }

    fn inner_stage(&mut self, inner: bool) {
        self.inner = inner;
    }
}

fn retime(e: StepError, time: f64) -> StepError {
    match e {
        StepError::Group { group, fault, .. } => StepError::Group { time, group, fault },
        StepError::SingularMassMatrix { .. } => StepError::SingularMassMatrix { time },
        StepError::NonFinite { what, .. } => StepError::NonFinite { time, what },
        e @ StepError::EnergyBalance { .. } => e,
    }
}

/// `e` with its group named in physical link numbers (SPEC 3's), ascending.
pub(crate) fn physical<T: Real>(map: &BodyMap<T>, e: StepError) -> StepError {
    match e {
        StepError::Group { time, group, fault } => StepError::Group {
            time,
            group: physical_group(map, group),
            fault,
        },
        e => e,
    }
}

/// `group` named in physical link numbers, ascending.
fn physical_group<T: Real>(map: &BodyMap<T>, mut group: GroupId) -> GroupId {
    let n = (group.count as usize).min(group.links.len());
    for l in group.links.iter_mut().take(n) {
        *l = map.phys.get(*l as usize).copied().unwrap_or(*l);
    }
    if let Some(s) = group.links.get_mut(..n) {
        s.sort_unstable();
    }
    group
}

/// `a` plus the multiple of 2π that brings it nearest `reference`.
pub(crate) fn unwrap_near<T: Real>(a: T, reference: T) -> T {
    let tau = T::two_pi();
    a + tau * ((reference - a) / tau).round()
}

mod momentum;
#[cfg(test)]
mod tests;
