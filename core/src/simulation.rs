//! A simulation: a model, its workspace, the state `(t, q, q̇)` and the fixed-step
//! Dormand-Prince integrator (SPEC 1, thesis 5.2). Each [`Simulation::step`] either
//! advances the state or returns an error and keeps the last good state.

use crate::balance::{audited_step, metered_adaptive, Balance, LoadPoses};
use crate::config::{MAX_DOF, STATE_DIM};
use crate::dynamics::{energy, finish_accelerations, forward, generalized_accelerations, Energy};
use crate::error::{ModelError, StepError};
use crate::integrator::{Adaptive, AdaptiveError, AdaptiveStats, Dp5, OdeSystem};
use crate::kinematics::assemble;
use crate::kinetostatics::reactions;
use crate::model::Model;
use crate::scalar::Real;
use crate::workspace::Workspace;
use core::fmt;
use nalgebra::SVector;

pub mod singular;
pub mod substeps;
pub mod switch;

#[cfg(doc)]
use substeps::TOLERANCE_STEP;
use substeps::{redo_in_substeps, LOCAL_ATOL, LOCAL_RTOL};

/// Why a simulation could not be set up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SetupError {
    /// The model was rejected.
    Model(ModelError),
    /// The mechanism does not assemble at the initial state (or its dynamics fail there).
    Initial(StepError),
    /// A setting is out of range.
    Setting(&'static str),
}

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetupError::Model(e) => write!(f, "model: {e}"),
            SetupError::Initial(e) => write!(f, "initial state: {e}"),
            SetupError::Setting(w) => write!(f, "setting: {w}"),
        }
    }
}

impl core::error::Error for SetupError {}

impl From<ModelError> for SetupError {
    fn from(e: ModelError) -> Self {
        SetupError::Model(e)
    }
}

/// The equations of motion as an ODE on `y = [q (MAX_DOF slots), q̇ (MAX_DOF slots)]`
/// (slots past the degrees of freedom stay zero).
pub struct Equations<'a, T: Real> {
    /// The mechanism.
    pub model: &'a Model<T>,
    /// Its workspace.
    pub ws: &'a mut Workspace<T>,
}

impl<T: Real> OdeSystem<T, STATE_DIM> for Equations<'_, T> {
    type Error = StepError;
    /// The coordinates and their rates of the model's degrees of freedom: the rest of
    /// the state is padding (0).
    fn live(&self) -> usize {
        2 * self.model.dof().min(MAX_DOF)
    }
    fn eval(
        &mut self,
        t: T,
        y: &SVector<T, STATE_DIM>,
        dy: &mut SVector<T, STATE_DIM>,
    ) -> Result<(), StepError> {
        let m = self.model.dof();
        let (q, qd) = y.as_slice().split_at(MAX_DOF);
        generalized_accelerations(
            self.model,
            self.ws,
            t,
            q.get(..m).unwrap_or(q),
            qd.get(..m).unwrap_or(qd),
        )?;
        dy.fill(T::zero());
        let (dq, dqd) = dy.as_mut_slice().split_at_mut(MAX_DOF);
        for (d, v) in dq.iter_mut().zip(&self.ws.qd).take(m) {
            *d = *v;
        }
        for (d, a) in dqd.iter_mut().zip(&self.ws.qdd).take(m) {
            *d = *a;
        }
        Ok(())
    }
}

/// A running simulation of one mechanism with fixed-step DP5.
#[derive(Clone)]
pub struct Simulation<T: Real> {
    model: Model<T>,
    ws: Workspace<T>,
    dp5: Dp5<T, STATE_DIM>,
    t: T,
    y: SVector<T, STATE_DIM>,
    h: T,
    steps: u64,
    balance: Balance<T>,
    /// The end time set by [`Simulation::end_at`]: the step that would pass it lands on
    /// it.
    end: Option<T>,
    /// The local error allowed per [`substeps::TOLERANCE_STEP`] of step: absolute
    /// (state units) and relative to the state's max-norm.
    local_tol: (T, T),
}

impl<T: Real> Simulation<T> {
    /// Assembles `model` at `q0` (rad or m) with speeds `qd0`, to be stepped by `h` (s).
    pub fn new(model: Model<T>, q0: &[T], qd0: &[T], h: T) -> Result<Self, SetupError> {
        let m = model.dof();
        if q0.len() != m || qd0.len() != m {
            return Err(SetupError::Setting(
                "initial state: one value per generalized coordinate",
            ));
        }
        if !(h.finite() && h > T::zero()) {
            return Err(SetupError::Setting("step h must be positive and finite"));
        }
        let mut y = SVector::<T, STATE_DIM>::zeros();
        for k in 0..m {
            y[k] = q0[k];
            y[MAX_DOF + k] = qd0[k];
        }
        if y.iter().any(|v| !v.finite()) {
            return Err(SetupError::Setting("initial state is not finite"));
        }
        let mut ws = Workspace::new();
        assemble(&model, &mut ws, q0).map_err(SetupError::Initial)?;
        forward(&model, &mut ws, T::zero(), q0, qd0).map_err(SetupError::Initial)?;
        check_outputs(&model, &ws, 0.0).map_err(SetupError::Initial)?;
        let balance = Balance::start(&model, &ws);
        Ok(Simulation {
            model,
            ws,
            dp5: Dp5::new(),
            t: T::zero(),
            y,
            h,
            steps: 0,
            balance,
            end: None,
            local_tol: (T::c(LOCAL_ATOL), T::c(LOCAL_RTOL)),
        })
    }

    /// One DP5 step of size `h`. On error the state, the workspace's configuration and
    /// the integrator are those of the last good step. A step whose end state has a
    /// non-finite output (a link's state, an energy: a finite speed whose `½Iω²` does
    /// not fit the scalar) is refused too: such a state has run away.
    ///
    /// Time is `n·h` after `n` steps, not a running sum (which drifts by a few ulps a
    /// step: 1.3e-4 s over 1000 steps in `f32`): the step taken is `(n+1)h - t`, exact
    /// by Sterbenz's lemma once `t > 0`, so `t + step` lands on `(n+1)h` and the FSAL
    /// stage stays valid.
    ///
    /// The step's energy balance ([`balance`](crate::balance)) and its local error
    /// ([`substeps`]) are checked: a step that breaks either is redone in 4, then 16
    /// sub-steps (still landing on `(n+1)h`); one that breaks the balance even so fails
    /// with [`StepError::EnergyBalance`], one over the local tolerance even so is
    /// accepted and counted ([`Balance::inexact`]).
    pub fn step(&mut self) -> Result<(), StepError> {
        let start = self.balance;
        let tol = substeps::per_step(self.local_tol, self.step_length());
        self.balance = redo_in_substeps(|n, enforce| {
            self.advance(
                |sys, dp5, t, y, h| audited_step(sys, dp5, t, y, h, n, &start, (tol, enforce)),
                substeps::Refused::Step,
            )
        })?;
        Ok(())
    }

    /// Sets the local error allowed per [`TOLERANCE_STEP`] (1 ms) of step
    /// ([`substeps`]; defaults [`LOCAL_ATOL`], [`LOCAL_RTOL`]; a step of `h` is allowed
    /// `h / 1 ms` of it): `atol` in the state's units (rad, m, rad/s, m/s) plus `rtol`
    /// of the state's max-norm. `atol = ∞` checks the energy balance only. Errors: `atol` is NaN or not
    /// positive, `rtol` NaN or negative.
    pub fn set_local_tolerance(&mut self, atol: T, rtol: T) -> Result<(), SetupError> {
        if !(atol > T::zero() && rtol >= T::zero()) {
            return Err(SetupError::Setting(
                "local tolerance: atol must be positive, rtol not negative",
            ));
        }
        self.local_tol = (atol, rtol);
        Ok(())
    }

    /// The local error allowed per [`TOLERANCE_STEP`] of step: `(atol, rtol)`.
    pub fn local_tolerance(&self) -> (T, T) {
        self.local_tol
    }

    /// Advances to the next output time `(n+1)·h` with the adaptive DP5(4) `adaptive`
    /// (error control by `rtol`/`atol`, as many steps of its own size as that needs, the
    /// last one landing on `(n+1)·h` exactly): `h` is then the output interval, not the
    /// integration step. The same guarantees as [`Simulation::step`]: on error the
    /// state, the workspace and the step count are those of the last output time, and
    /// `adaptive` forgets its FSAL stage. Returns the interval's step statistics.
    ///
    /// The simulation's own fixed-step integrator forgets its FSAL stage too: mixing
    /// `step` and `step_adaptive` is allowed, each starts from the state.
    ///
    /// The interval's energy balance is not checked (the error control keeps it):
    /// [`Balance::unaudited`] counts such intervals. Its work is metered as a fixed
    /// step's is (the motors' with the state at the accepted steps' stages).
    pub fn step_adaptive(
        &mut self,
        adaptive: &mut Adaptive<T, STATE_DIM>,
    ) -> Result<AdaptiveStats, AdaptiveError<StepError>> {
        self.dp5.invalidate();
        let poses = LoadPoses::at(&self.model, &self.ws);
        let first = self.balance.power();
        let r = self.advance(
            |sys, _, t, y, h| {
                let t_end = *t + h;
                metered_adaptive(sys, adaptive, t, y, t_end, first)
            },
            AdaptiveError::System,
        );
        match r {
            Ok((stats, motor)) => {
                self.balance
                    .skip(&self.model, &self.ws, &poses, self.h, motor);
                Ok(stats)
            }
            Err(e) => {
                adaptive.invalidate();
                Err(e)
            }
        }
    }

    /// Takes the state from `t` to the next output time `(n+1)·h` by `integrate(system,
    /// the fixed-step integrator, t, y, the interval)`, then checks the outputs there
    /// (their errors wrapped by `wrap` into the integrator's error type `E`); on any
    /// error restores the last good state (`t`, `y`, the groups' warm starts, the
    /// workspace) and forgets the FSAL stage if the state had moved.
    fn advance<R, E>(
        &mut self,
        integrate: impl FnOnce(
            &mut Equations<'_, T>,
            &mut Dp5<T, STATE_DIM>,
            &mut T,
            &mut SVector<T, STATE_DIM>,
            T,
        ) -> Result<R, E>,
        wrap: fn(StepError) -> E,
    ) -> Result<R, E> {
        // The groups' unknowns with their cosines and sines (`GroupData::trig`): a
        // step taken back restores both, so its re-evaluation reproduces the state.
        let saved = self.ws.warm_start(self.model.groups());
        // The evaluated outputs too: at a state singular within rounding (a q̈ that a
        // position one ulp off multiplies by 1e30) re-evaluating from the warm start
        // need not reproduce them, and a failed step must leave them as they were.
        let outputs = (self.ws.body, self.ws.qdd, self.ws.motor);
        let predictors = self.ws.predictors();
        let t_next = self.clamp_to_end(T::c((self.steps + 1) as f64) * self.h);
        if !t_next.finite() {
            return Err(wrap(StepError::NonFinite {
                time: self.t.to_f64(),
                what: "the time n·h of the next step",
            }));
        }
        let h = t_next - self.t;
        let (t0, y0) = (self.t, self.y);
        let mut sys = Equations {
            model: &self.model,
            ws: &mut self.ws,
        };
        let result =
            integrate(&mut sys, &mut self.dp5, &mut self.t, &mut self.y, h).and_then(|r| {
                // The last stage was evaluated at the new state (FSAL): finish it.
                finish_accelerations(&self.model, &mut self.ws);
                check_outputs(&self.model, &self.ws, t_next.to_f64())
                    .map(|()| r)
                    .map_err(wrap)
            });
        match result {
            Ok(r) => {
                self.steps += 1;
                Ok(r)
            }
            Err(e) => {
                if self.t != t0 {
                    // The integrator had taken the step (its FSAL stage is the new
                    // state's): take it back.
                    self.t = t0;
                    self.y = y0;
                    self.dp5.invalidate();
                }
                self.ws.restore_warm_start(self.model.groups(), &saved);
                self.ws.restore_predictors(&predictors);
                // Re-evaluate at the last good state (it evaluated before, from the same
                // warm start): the workspace describes the state again.
                let m = self.model.dof();
                let (q, qd) = self.y.as_slice().split_at(MAX_DOF);
                let (q, qd) = (q.get(..m).unwrap_or(q), qd.get(..m).unwrap_or(qd));
                let _ = forward(&self.model, &mut self.ws, self.t, q, qd);
                // Where that re-evaluation does not reproduce the last good state (it
                // failed, or its Newton iterations moved the unknowns by rounding), the
                // state shown is still the last good one, bit for bit.
                self.ws.restore_warm_start(self.model.groups(), &saved);
                self.ws.restore_predictors(&predictors);
                (self.ws.body, self.ws.qdd, self.ws.motor) = outputs;
                Err(e)
            }
        }
    }

    /// Sets the run's end time `t_end` (s, in `(t, ∞)`): the step that would pass it is
    /// shortened to land on it exactly (a run whose `t_end` is not a multiple of `h`
    /// ends at `t_end`, not past it); the steps before keep `h`. Past `t_end` the steps
    /// are `h` again. Errors: `t_end` is not finite or not after the current time.
    pub fn end_at(&mut self, t_end: T) -> Result<(), SetupError> {
        if !(t_end.finite() && t_end > self.t) {
            return Err(SetupError::Setting(
                "end time t_end must be finite and after the current time",
            ));
        }
        self.end = Some(t_end);
        Ok(())
    }

    /// The length of the next step, s: `h`, or less for the step shortened to land on
    /// the end time of [`Simulation::end_at`]. (The steps of `n·h` are `h` to rounding:
    /// their tolerance is `h`'s, the same bits every step.)
    fn step_length(&self) -> T {
        let t_next = T::c((self.steps + 1) as f64) * self.h;
        let clamped = self.clamp_to_end(t_next);
        if clamped < t_next {
            clamped - self.t
        } else {
            self.h
        }
    }

    /// The next step's end time `t_next`, or the end time of [`Simulation::end_at`] if
    /// the step would pass it (and the state is still before it).
    fn clamp_to_end(&self, t_next: T) -> T {
        match self.end {
            Some(e) if e < t_next && self.t < e => e,
            _ => t_next,
        }
    }

    /// Time, s.
    pub fn time(&self) -> T {
        self.t
    }
    /// Step size, s.
    pub fn h(&self) -> T {
        self.h
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// Generalized coordinates.
    pub fn q(&self) -> &[T] {
        self.y.as_slice().get(..self.model.dof()).unwrap_or(&[])
    }
    /// Generalized speeds.
    pub fn qd(&self) -> &[T] {
        self.y
            .as_slice()
            .get(MAX_DOF..MAX_DOF + self.model.dof())
            .unwrap_or(&[])
    }
    /// Generalized accelerations at the current state.
    pub fn qdd(&self) -> &[T] {
        self.ws.qdd.get(..self.model.dof()).unwrap_or(&[])
    }
    /// The model.
    pub fn model(&self) -> &Model<T> {
        &self.model
    }
    /// The workspace, evaluated at the current state.
    pub fn workspace(&self) -> &Workspace<T> {
        &self.ws
    }
    /// The integrator (its dense output covers the last step, or its last sub-step).
    pub fn integrator(&self) -> &Dp5<T, STATE_DIM> {
        &self.dp5
    }
    /// Kinetic and potential energy at the current state, J.
    pub fn energy(&self) -> Energy<T> {
        energy(&self.model, &self.ws)
    }
    /// The energy balance since the start: the motors' and loads' work, the energies,
    /// the worst step's relative residual and the sub-steps taken.
    pub fn balance(&self) -> &Balance<T> {
        &self.balance
    }
    /// Joint reactions and driving torques at the current state (kinetostatics), into
    /// the workspace's `reactions`; an error if one is not finite (the state has run
    /// away: forces that overflow the scalar).
    pub fn kinetostatics(&mut self) -> Result<&Workspace<T>, StepError> {
        let time = self.t.to_f64();
        reactions(&self.model, &mut self.ws, time)?;
        check_reactions(&self.model, &self.ws, time)?;
        Ok(&self.ws)
    }
}

/// The outputs at the workspace's state (every link's angle, position, speeds and
/// accelerations, the energies) are finite, or the error that names the first that is
/// not (at time `time`, s). The evaluation checks `q`, `q̇`, `q̈` and the mass matrix;
/// finite values can still overflow past them: an angle offset of -1e300 rad plus
/// q = -f64::MAX, accelerations `V q̈` of a q̈ near f64::MAX, `½Iω²` of a huge inertia.
fn check_outputs<T: Real>(model: &Model<T>, ws: &Workspace<T>, time: f64) -> Result<(), StepError> {
    let fail = |what| Err(StepError::NonFinite { time, what });
    for b in ws.body.iter().skip(1).take(model.n_links()) {
        if !(b.theta.finite() && b.o.x.finite() && b.o.y.finite()) {
            return fail("a link's angle or position");
        }
        if !(b.omega.finite() && b.v.x.finite() && b.v.y.finite()) {
            return fail("a link's speed");
        }
        if !(b.alpha.finite() && b.a.x.finite() && b.a.y.finite()) {
            return fail("a link's acceleration (the applied forces overflow it)");
        }
    }
    let e = energy(model, ws);
    if !(e.kinetic.finite() && e.potential.finite()) {
        return fail("the kinetic or potential energy (the state overflows it)");
    }
    Ok(())
}

/// Every joint reaction and driving torque of the kinetostatics is finite, or the error
/// that says not (at time `time`, s).
fn check_reactions<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    time: f64,
) -> Result<(), StepError> {
    for (g, r) in model.groups().iter().zip(ws.reactions.iter()) {
        for x in r.iter().take(g.joints.len()) {
            if !(x.force.x.finite() && x.force.y.finite() && x.moment.finite()) {
                return Err(StepError::NonFinite {
                    time,
                    what: "a joint reaction or driving torque (the forces overflow the scalar)",
                });
            }
        }
    }
    Ok(())
}
