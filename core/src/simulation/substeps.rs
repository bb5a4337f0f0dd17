//! Why and how a fixed step is redone in sub-steps (issue 17, items 1-2). Every fixed
//! step of a [`Simulation`](super::Simulation) is checked twice:
//!
//! - its **energy balance** ([`crate::balance`]): work in against Δ(K + V), to
//!   [`tolerance`](crate::balance::tolerance) of the energy scale;
//! - its **local error**: the max-norm of DP5's embedded 5(4) estimate
//!   `‖y5 - y4‖∞ = ‖h Σ E_i k_i‖∞` (over `q` and `q̇` alike, rad, m, rad/s, m/s), which
//!   the fixed-step integrator computes with every step anyway, against
//!   [`local_tolerance`] for the whole step; a step in `n` sub-steps gives each
//!   sub-step the share `1/n` of it. The tolerance is an error per unit time
//!   ([`per_step`]): [`LOCAL_ATOL`] and [`LOCAL_RTOL`] per [`TOLERANCE_STEP`] (1 ms) of
//!   step, so a step of `h` may make `h / 1 ms` of it and the sum of the estimates over
//!   a run, the bound on its global error below, does not depend on `h`.
//!
//! A step that breaks either is redone in [`SUBSTEPS`] (4, then 16 DP5 steps landing on
//! the same `(n+1)·h`): the firmware's step stays fixed and its work bounded (1 + 4 + 16
//! DP5 steps at most). The finest division keeps the energy rule (a step that breaks it
//! even in 16 fails with [`StepError::EnergyBalance`]) but is accepted over the local
//! tolerance and counted ([`Balance::inexact`]): the estimate is a measure of accuracy,
//! not of a broken physics.
//!
//! The local tolerance and the global error: the estimate is the 4th-order solution's
//! local error, `O(h⁵)`; the propagated 5th-order solution's is `O(h⁶)`, smaller by a
//! factor of order `h / T` (`T` the motion's time scale). Keeping every step's estimate
//! under `rate·h` keeps the global error of the 5th-order solution well under the sum of
//! the estimates, `rate·t` after a time `t`, times the motion's growth of errors. A
//! tolerance per step instead would ask a coarse step for the accuracy of a fine one
//! (the slider-crank at h = 10 ms redid 991 of its 1000 steps, its q1 within 2e-12 rad
//! of an adaptive run; per unit time it redoes 722, within 1.5e-11 rad). [`LOCAL_ATOL`]
//! and [`LOCAL_RTOL`] are chosen on the README's main job (the five-bar at h = 1 ms, its
//! q1(0.5 s) and q1(1 s) within 1e-8 rad of an adaptive rtol 1e-12 run, with margin:
//! see `host-sim/tests/main_job.rs`), where the per-unit-time rule gives the same
//! tolerance as before.

use crate::balance::Balance;
pub use crate::balance::SUBSTEPS;
use crate::error::StepError;
use crate::scalar::Real;

/// The step length the local tolerance is given for, s: a step of `h` is allowed
/// `h / TOLERANCE_STEP` of it ([`per_step`]).
pub const TOLERANCE_STEP: f64 = 1e-3;

/// The absolute part of the local error allowed per [`TOLERANCE_STEP`] of step, in the
/// state's units (rad, m, rad/s, m/s): the max-norm of DP5's embedded estimate, summed
/// over a step's sub-steps (3e-7 per second).
pub const LOCAL_ATOL: f64 = 3e-10;

/// The relative part: of the state's max-norm `‖(q, q̇)‖∞` (a run that spins ever
/// faster keeps its relative accuracy, where an absolute bound would ask ever more),
/// per [`TOLERANCE_STEP`] of step.
pub const LOCAL_RTOL: f64 = 1e-12;

/// The relative part in ulps, when that is larger (`f32`: an estimate made of rounded
/// stages is no smaller than ~1e-7 of the state).
pub const LOCAL_ULPS: f64 = 1e3;

/// The tolerance `(atol, rtol)` given per [`TOLERANCE_STEP`] scaled to a step of
/// `length` s: `length / TOLERANCE_STEP` of each (exactly them at 1 ms).
pub fn per_step<T: Real>((atol, rtol): (T, T), length: T) -> (T, T) {
    let s = length / T::c(TOLERANCE_STEP);
    (atol * s, rtol * s)
}

/// The local error allowed for one fixed step whose state has max-norm `size`
/// (`(atol, rtol)` already [`per_step`]):
/// `atol + max(rtol, LOCAL_ULPS ulps)·size`.
pub fn local_tolerance<T: Real>((atol, rtol): (T, T), size: T) -> T {
    atol + rtol.max(T::EPS * T::c(LOCAL_ULPS)) * size
}

/// What one attempt at a step reports besides its balance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Audited<T> {
    /// The balance at the step's end.
    pub balance: Balance<T>,
    /// The largest of its sub-steps' error estimates relative to their share of the
    /// local tolerance (at most 1 when the step is accurate enough).
    pub error: T,
}

/// Why an attempt at a step was refused.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Refused<T> {
    /// A failure of the step itself (an evaluation's, the energy balance's, a
    /// non-finite output).
    Step(StepError),
    /// Its error estimate exceeded the local tolerance (relative size given).
    Inaccurate(T),
}

impl<T> From<StepError> for Refused<T> {
    fn from(e: StepError) -> Self {
        Refused::Step(e)
    }
}

/// Takes one fixed step by `attempt(n, enforce)` (the step in `n` sub-steps; `enforce`:
/// whether an error estimate over the local tolerance refuses it): undivided first; if
/// that breaks the energy balance or the local tolerance, in each finer division of
/// [`SUBSTEPS`] in turn until one passes; the finest is accepted over the local
/// tolerance. A refused attempt must leave the state as it was. A division may fail
/// otherwise (a group's fault, a non-finite value: a coarse step's stages can land far
/// off); the next one is tried all the same. When none passes, the error is the energy
/// balance's, with the residual of the finest division that reached the step's end, or
/// the finest division's own. An undivided step that fails otherwise fails with its own
/// error. The balance returned counts the step's sub-steps and their reasons.
pub(crate) fn redo_in_substeps<T: Real>(
    mut attempt: impl FnMut(u32, bool) -> Result<Audited<T>, Refused<T>>,
) -> Result<Balance<T>, StepError> {
    let (mut energy, mut error) = (false, false);
    let mut broken: Option<StepError> = None;
    let mut other: Option<StepError> = None;
    let last = SUBSTEPS.len() - 1;
    for (i, n) in SUBSTEPS.into_iter().enumerate() {
        match attempt(n, i < last) {
            Ok(a) => return Ok(count(a, n, energy, error)),
            Err(Refused::Inaccurate(_)) => error = true,
            Err(Refused::Step(e @ StepError::EnergyBalance { .. })) => {
                energy = true;
                broken = Some(e);
            }
            Err(Refused::Step(e)) if i == 0 => return Err(e),
            Err(Refused::Step(e)) => other = Some(e),
        }
    }
    // The finest division is never refused as inaccurate: it broke the balance or
    // failed otherwise.
    Err(broken.or(other).unwrap_or(StepError::NonFinite {
        time: f64::NAN,
        what: "a step that no division of the step could take",
    }))
}

/// The balance of a step accepted in `n` sub-steps, with its counts: whether a coarser
/// division broke the energy balance (`energy`) or the local tolerance (`error`).
fn count<T: Real>(a: Audited<T>, n: u32, energy: bool, error: bool) -> Balance<T> {
    let mut b = a.balance;
    b.worst_error = b.worst_error.max(a.error);
    if a.error > T::one() {
        b.inexact = b.inexact.saturating_add(1);
    }
    if n > 1 {
        b.redone = b.redone.saturating_add(1);
        b.substeps = b.substeps.saturating_add(u64::from(n));
        if energy {
            b.redone_energy = b.redone_energy.saturating_add(1);
        }
        if error {
            b.redone_error = b.redone_error.saturating_add(1);
        }
    }
    b
}
