//! The energy balance of every fixed step (SPEC 3's audit, for any mechanism): the work
//! done on the mechanism by its motors and its constant loads must equal the change of
//! its kinetic plus potential energy (gravity is in the potential),
//!
//! `W_motors + W_loads = Δ(K + V)`.
//!
//! - The motors' work is `∫ Σ_d τ_d(t, q, q̇) q̇_d dt`, integrated with the state: the
//!   power at each DP5 stage, combined with the 5th-order weights (the quadrature DP5
//!   would make of an extra state component `w' = P`, without changing a bit of `q`,
//!   `q̇`). The first stage's power is the last stage's of the step before (FSAL).
//! - A constant load (force `F` at a link point `P`, moment `M` on the link) does the
//!   work `F·Δr_P + M·Δθ` over a step, exactly.
//!
//! A step whose residual (work in minus energy gained) exceeds [`tolerance`] times the
//! energy scale `1 J + |W_motors| + |W_loads| + |K| + |V|` is redone in [`SUBSTEPS`]
//! DP5 steps (4, then 16; the caller's step stays `h`, its time still `(n+1)·h`); if the
//! finest division breaks it too, the step fails with [`StepError::EnergyBalance`].
//! The same sub-steps keep each step's local error
//! ([`crate::simulation::substeps`]). The
//! converter's twin checks its steps by the same rule
//! ([`TwinSettings::energy_tol`](crate::ccc::TwinSettings::energy_tol)), with the
//! tolerance per 1e-4 s of step ([`energy_tolerance`](crate::ccc::energy_tolerance)).
//!
//! The caller-set moments of [`Workspace::applied_moment`] are not metered: a
//! [`Simulation`](crate::Simulation) has no way to set them (the twin, which does, keeps
//! its own audit).

use crate::config::{MAX_LOADS, STATE_DIM};
use crate::dynamics::energy;
use crate::error::StepError;
use crate::integrator::{Adaptive, AdaptiveError, AdaptiveStats, Dp5, OdeSystem, Tableau};
use crate::model::Model;
use crate::scalar::{rotate_cs, Real, Vec2};
use crate::simulation::substeps::{local_tolerance, Audited, Refused};
use crate::simulation::Equations;
use crate::workspace::Workspace;
use nalgebra::SVector;

/// Sub-steps tried in turn for one fixed step whose energy balance breaks: at most
/// 1 + 4 + 16 DP5 steps' work.
pub const SUBSTEPS: [u32; 3] = [1, 4, 16];

/// Relative tolerance of one step's residual, of the energy scale (see the module docs).
pub const ENERGY_TOL: f64 = 1e-9;

/// The tolerance in ulps of the scalar, when that is larger (`f32`: its energies are
/// rounded to ~1e-7 of their size).
pub const ENERGY_ULPS: f64 = 1e3;

/// The relative tolerance of one step's residual in `T`: [`ENERGY_TOL`], or
/// [`ENERGY_ULPS`] ulps if that is larger (`f32`: 1.2e-4).
pub fn tolerance<T: Real>() -> T {
    T::c(ENERGY_TOL).max(T::EPS * T::c(ENERGY_ULPS))
}

/// The energy balance of a simulation since its start, J, and what its audit did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Balance<T> {
    /// Work of the motors on the mechanism, J (N·m·rad or N·m).
    pub motor_work: T,
    /// Work of the model's constant loads on the mechanism, J.
    pub load_work: T,
    /// Kinetic energy now, J.
    pub kinetic: T,
    /// Potential energy now (gravity), J.
    pub potential: T,
    /// Kinetic plus potential energy at the start, J.
    pub initial: T,
    /// The largest residual of one step relative to its energy scale (dimensionless;
    /// the steps pass while it is at most [`tolerance`]).
    pub worst: T,
    /// Steps redone in sub-steps ([`crate::simulation::substeps`]), for either reason.
    pub redone: u64,
    /// DP5 sub-steps of the redone steps, in all.
    pub substeps: u64,
    /// Steps redone because a coarser division broke the energy balance.
    pub redone_energy: u64,
    /// Steps redone because a coarser division's error estimate exceeded the local
    /// tolerance ([`local_tolerance`]).
    pub redone_error: u64,
    /// Steps accepted in the finest division with an error estimate still over the
    /// local tolerance.
    pub inexact: u64,
    /// The largest error estimate of an accepted step relative to its local tolerance
    /// (fixed steps; at most 1 while `inexact` is 0).
    pub worst_error: T,
    /// Intervals of [`Simulation::step_adaptive`](crate::Simulation::step_adaptive),
    /// whose balance is not checked (the error control keeps it; their work is metered
    /// all the same, and `worst` covers the fixed steps only).
    pub unaudited: u64,
    /// The motors' power at the current state, W (the next step's first stage).
    power: T,
}

impl<T: Real> Balance<T> {
    /// The balance at the start: the workspace evaluated at the initial state.
    pub(crate) fn start(model: &Model<T>, ws: &Workspace<T>) -> Self {
        let e = energy(model, ws);
        Balance {
            motor_work: T::zero(),
            load_work: T::zero(),
            kinetic: e.kinetic,
            potential: e.potential,
            initial: e.kinetic + e.potential,
            worst: T::zero(),
            redone: 0,
            substeps: 0,
            redone_energy: 0,
            redone_error: 0,
            inexact: 0,
            worst_error: T::zero(),
            unaudited: 0,
            power: motor_power(model, ws),
        }
    }

    /// The motors' power at the current state, W.
    pub(crate) fn power(&self) -> T {
        self.power
    }

    /// Work in minus energy gained since the start,
    /// The energies and the motors' power at the workspace's state, the works kept:
    /// after the same state is described by other coordinates
    /// ([`crate::simulation::switch`]), whose energies differ from the old ones by the
    /// rounding of the assembly only (which the residual then shows).
    pub(crate) fn rebase(&mut self, model: &Model<T>, ws: &Workspace<T>) {
        let e = energy(model, ws);
        self.kinetic = e.kinetic;
        self.potential = e.potential;
        self.power = motor_power(model, ws);
    }

    /// `motor_work + load_work - (kinetic + potential - initial)`, J.
    pub fn residual(&self) -> T {
        self.motor_work + self.load_work - (self.kinetic + self.potential - self.initial)
    }

    /// The energy scale of a step's tolerance,
    /// `1 J + |motor_work| + |load_work| + |kinetic| + |potential|`, J.
    pub fn scale(&self) -> T {
        T::one()
            + self.motor_work.abs()
            + self.load_work.abs()
            + self.kinetic.abs()
            + self.potential.abs()
    }

    /// After an unaudited interval that ended at the workspace's state: the motors'
    /// work `motor` (J, metered by [`metered_adaptive`]), the loads' work (exact, from
    /// `before`), the energies and the power at the new state.
    pub(crate) fn skip(
        &mut self,
        model: &Model<T>,
        ws: &Workspace<T>,
        before: &LoadPoses<T>,
        h: T,
        motor: T,
    ) {
        let e = energy(model, ws);
        self.motor_work += motor;
        self.load_work += before.work_to(model, ws, h);
        self.kinetic = e.kinetic;
        self.potential = e.potential;
        self.power = motor_power(model, ws);
        self.unaudited = self.unaudited.saturating_add(1);
    }
}

/// `Σ_d τ_d q̇_d`, W: the motors' power at the workspace's last evaluation.
fn motor_power<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> T {
    let mut p = T::zero();
    for (d, tau) in model.drives().iter().zip(ws.motor.iter()) {
        p += *tau * crate::dynamics::drive_motion(model, ws, d).1;
    }
    p
}

/// Where each constant load acts at one state: its point (world, m), its link's angle
/// (rad) and angular speed (rad/s).
#[derive(Clone, Copy)]
pub(crate) struct LoadPoses<T: Real>([(Vec2<T>, T, T); MAX_LOADS]);

impl<T: Real> LoadPoses<T> {
    /// The loads' poses at the workspace's state.
    pub(crate) fn at(model: &Model<T>, ws: &Workspace<T>) -> Self {
        let mut p = [(Vec2::zeros(), T::zero(), T::zero()); MAX_LOADS];
        for (slot, ld) in p.iter_mut().zip(model.loads()) {
            let b = ws.body.get(ld.body as usize).copied().unwrap_or_default();
            *slot = (b.o + rotate_cs(b.c, b.s, &ld.point), b.theta, b.omega);
        }
        LoadPoses(p)
    }

    /// The loads' work from these poses to the workspace's state, `h` (s) later:
    /// `Σ F·Δr_P + M·Δθ`, J. A link angle may be recorded modulo 2π (a dyad's closed
    /// form): `Δθ` is the difference taken to the turn nearest `h (ω0 + ω1)/2`.
    pub(crate) fn work_to(&self, model: &Model<T>, ws: &Workspace<T>, h: T) -> T {
        let end = LoadPoses::at(model, ws);
        let (half, turn) = (T::c(0.5), T::two_pi());
        let mut w = T::zero();
        for ((ld, (r0, th0, om0)), (r1, th1, om1)) in
            model.loads().iter().zip(self.0.iter()).zip(end.0.iter())
        {
            w += ld.force.dot(&(*r1 - *r0));
            if ld.moment != T::zero() {
                let raw = *th1 - *th0;
                let rotation = h * half * (*om0 + *om1);
                w += ld.moment * (raw - turn * ((raw - rotation) / turn).round());
            }
        }
        w
    }
}

/// The equations of motion, metering the motors' power at every evaluation.
struct Metered<'s, 'a, T: Real> {
    /// The equations.
    eq: &'s mut Equations<'a, T>,
    /// The power (W) at each evaluation of the DP5 step under way, in order: a step
    /// evaluates 7 stages, or 6 when it reuses the last one of the step before (FSAL);
    /// the last six are stages 2 to 7.
    power: [T; Tableau::STAGES],
    /// Evaluations of the step under way.
    evals: usize,
}

impl<T: Real> OdeSystem<T, STATE_DIM> for Metered<'_, '_, T> {
    type Error = StepError;
    fn eval(
        &mut self,
        t: T,
        y: &SVector<T, STATE_DIM>,
        dy: &mut SVector<T, STATE_DIM>,
    ) -> Result<(), StepError> {
        self.eq.eval(t, y, dy)?;
        if let Some(p) = self.power.get_mut(self.evals) {
            *p = motor_power(self.eq.model, self.eq.ws);
        }
        self.evals += 1;
        Ok(())
    }
}

impl<'s, 'a, T: Real> Metered<'s, 'a, T> {
    /// The equations `eq`, metered from no evaluation.
    fn new(eq: &'s mut Equations<'a, T>) -> Self {
        Metered {
            eq,
            power: [T::zero(); Tableau::STAGES],
            evals: 0,
        }
    }

    /// The motors' work over the DP5 step of size `h` just taken, whose first stage's
    /// power is `first` (W): `h Σ B5_i P_i`, J; and the power at its last stage (its end
    /// state).
    fn work(&self, h: T, first: T) -> (T, T) {
        let stages = self.power.get(..self.evals).unwrap_or(&[]);
        let later = stages.get(stages.len().saturating_sub(6)..).unwrap_or(&[]);
        let mut sum = T::c(Tableau::B5[0]) * first;
        for (b, p) in Tableau::B5.iter().skip(1).zip(later) {
            sum += T::c(*b) * *p;
        }
        (h * sum, later.last().copied().unwrap_or(first))
    }
}

/// The adaptive DP5(4) `adaptive` from `(t, y)` to `t_end`
/// ([`Adaptive::integrate_to`]), metering the motors' work of its accepted steps as
/// [`audited_step`] does (the 5th-order weights on the stages' power; `first` is the
/// power at `(t, y)`, W; a rejected attempt's stages are dropped). Returns the step
/// statistics and the work, J. The trajectory is that of `integrate_to`, bit for bit.
pub(crate) fn metered_adaptive<T: Real>(
    sys: &mut Equations<'_, T>,
    adaptive: &mut Adaptive<T, STATE_DIM>,
    t: &mut T,
    y: &mut SVector<T, STATE_DIM>,
    t_end: T,
    first: T,
) -> Result<(AdaptiveStats, T), AdaptiveError<StepError>> {
    let mut meter = Metered::new(sys);
    let (mut motor, mut power) = (T::zero(), first);
    let stats = adaptive.integrate_to_with(&mut meter, t, y, t_end, |m, h, accepted| {
        if accepted {
            let (w, p) = m.work(h, power);
            motor += w;
            power = p;
        }
        m.evals = 0;
    })?;
    Ok((stats, motor))
}

/// One fixed step of `h` from `(t, y)` in `substeps` DP5 steps of `h / substeps` (the
/// last landing on `t + h` bitwise), with its energy balance checked against `start`,
/// the balance at `(t, y)`, and each sub-step's error estimate against its share
/// `1/substeps` of the local tolerance `tol` ([`local_tolerance`]). Returns the balance
/// at the end with the largest relative estimate, or why not (the caller restores the
/// last good state): an evaluation's error, [`StepError::EnergyBalance`], a non-finite
/// work, or (when `enforce`) an estimate over the tolerance. Energies that are not
/// finite are left to the caller's check of the outputs, which names them.
#[allow(clippy::too_many_arguments)]
pub(crate) fn audited_step<T: Real>(
    sys: &mut Equations<'_, T>,
    dp5: &mut Dp5<T, STATE_DIM>,
    t: &mut T,
    y: &mut SVector<T, STATE_DIM>,
    h: T,
    substeps: u32,
    start: &Balance<T>,
    (tol, enforce): ((T, T), bool),
) -> Result<Audited<T>, Refused<T>> {
    let (t0, t_end) = (*t, *t + h);
    let n = substeps.max(1);
    let mut meter = Metered::new(sys);
    let (mut motor, mut load, mut power) = (T::zero(), T::zero(), start.power);
    let share = T::one() / T::c(f64::from(n));
    let mut error = T::zero();
    for k in 1..=n {
        // `t0 + h·k/n` (k/n exact: n is a power of 2); the step `t_k - t` is exact
        // (Sterbenz), so each sub-step lands on its `t_k` and the last on `t + h`.
        let t_k = if k == n {
            t_end
        } else {
            t0 + h * T::c(f64::from(k) / f64::from(n))
        };
        let h_k = t_k - *t;
        let poses = LoadPoses::at(meter.eq.model, meter.eq.ws);
        meter.evals = 0;
        let report = dp5.step(&mut meter, t, y, h_k)?;
        let size = y.iter().fold(T::zero(), |m, v| m.max(v.abs()));
        // A NaN estimate counts as over (the outputs' check names a NaN state).
        let ratio = report.error / (local_tolerance(tol, size) * share);
        error = if ratio <= error { error } else { ratio };
        let (w, p) = meter.work(h_k, power);
        motor += w;
        power = p;
        // The last evaluation is at the sub-step's end state.
        load += poses.work_to(meter.eq.model, meter.eq.ws, h_k);
    }
    let (model, ws) = (meter.eq.model, &*meter.eq.ws);
    let e = energy(model, ws);
    let mut end = Balance {
        motor_work: start.motor_work + motor,
        load_work: start.load_work + load,
        kinetic: e.kinetic,
        potential: e.potential,
        power,
        ..*start
    };
    if !(e.kinetic.finite() && e.potential.finite()) {
        return Ok(Audited {
            balance: end,
            error,
        });
    }
    if !(end.motor_work.finite() && end.load_work.finite() && power.finite()) {
        return Err(Refused::Step(StepError::NonFinite {
            time: t_end.to_f64(),
            what: "the work of the motors or loads (their power overflows)",
        }));
    }
    // Work in minus energy gained over the step.
    let residual = motor + load - ((e.kinetic - start.kinetic) + (e.potential - start.potential));
    let scale = end.scale();
    if !(residual.abs() <= tolerance::<T>() * scale) {
        return Err(Refused::Step(StepError::EnergyBalance {
            time: t0.to_f64(),
            residual: residual.to_f64(),
            scale: scale.to_f64(),
            substeps: n,
        }));
    }
    if enforce && !(error <= T::one()) {
        return Err(Refused::Inaccurate(error));
    }
    end.worst = end.worst.max(residual.abs() / scale);
    Ok(Audited {
        balance: end,
        error,
    })
}
