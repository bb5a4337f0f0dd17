//! The twin's settings fixed at start, and the bounds and thresholds of its step.

use super::error::TwinSetupError;
use super::slot::LinkState;
use crate::balance;
use crate::scalar::Real;

/// Events per step at most (see the module docs for what happens past it).
pub const MAX_EVENTS_PER_STEP: usize = 4;

/// Evaluations spent locating one event at most (Illinois regula falsi).
pub const MAX_LOCATE_ITER: usize = 16;

/// Coordinate switches after a failed sub-step at most.
pub const MAX_RETRIES: usize = 2;

/// Sub-steps tried in turn when a step breaks the energy balance (see
/// [`TwinSettings::energy_tol`]): the core's division of a fixed step, at most
/// 1 + 4 + 16 DP5 steps' work.
pub use crate::balance::SUBSTEPS;

/// Below this conditioning of its worst group, a [`TwinStepError::Diverged`](super::TwinStepError::Diverged) step is taken
/// to run into a singularity of the mechanism rather than to be too coarse.
pub const SINGULAR_CONDITIONING: f64 = 1e-2;

/// A diode branch whose rod and lever come in line within this many steps at their
/// present rate counts as in line when a step fails ([`TwinStepError::Diode`](super::TwinStepError::Diode)). In f64 the
/// branch's |sin| is under [`SINGULAR_CONDITIONING`] by then; in f32 rounding breaks
/// the energy balance 8 to 16 steps before (S1 at h = 1e-4 s: 0.3227 s against f64's
/// 0.3238 s), at |sin| of 3e-2 to 6e-2.
pub const DIODE_HORIZON_STEPS: f64 = 32.0;

/// Settings fixed at start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinSettings<T> {
    /// The fixed step, s.
    pub h: T,
    /// `false`: no clutch at all (SPEC 3's free mode, thesis 7.1), the levers swing freely.
    pub clutch: bool,
    /// Initial crank angle q1, rad.
    pub crank: T,
    /// Initial swing-link angle q2, rad.
    pub swing: T,
    /// Initial crank speed, rad/s.
    pub crank_speed: T,
    /// Initial swing-link speed, rad/s.
    pub swing_speed: T,
    /// Under this normalized determinant of a group, other coordinate choices are tried
    /// (a dead point of the coordinates is coming); one is taken if it is at least 1.5
    /// times better.
    pub switch_below: T,
    /// Largest change of the audit residual over one step, relative to 1 J plus the
    /// motor work and the kinetic and potential energies. A step past it is redone in
    /// [`SUBSTEPS`]; if even the finest fails, the step fails with
    /// [`TwinStepError::Diverged`](super::TwinStepError::Diverged) and the twin keeps its last good state. S2's steps stay
    /// under 4e-11; S1's last steps before the diode stretches grow past 1e-9 each.
    /// Reference: the core's energy balance tolerance ([`balance::tolerance`]: 1e-9,
    /// or 1000 ulps of the scalar if that is larger, f32).
    pub energy_tol: T,
}

impl<T: Real> TwinSettings<T> {
    /// SPEC 3's initial state (q1 = 105°, q2 = 90°, at rest) with the diode, at step `h`.
    pub fn reference(h: T) -> Self {
        TwinSettings {
            h,
            clutch: true,
            crank: T::c(105f64.to_radians()),
            swing: T::c(90f64.to_radians()),
            crank_speed: T::zero(),
            swing_speed: T::zero(),
            switch_below: T::c(0.2),
            energy_tol: balance::tolerance(),
        }
    }
}

/// The largest angular speed of the links (rad/s), at least 1: the scale of the
/// speed thresholds.
pub(super) fn speed_scale<T: Real>(links: &[LinkState<T>; 9]) -> T {
    links.iter().fold(T::one(), |m, s| m.max(s.omega.abs()))
}

/// A candidate mode whose violation from the reference model ([`Twin::screen`]) is over
/// this is not built: its own model would find it violating too (the two differ by
/// rounding, ~1e-12 of the scales in f64). Near 0 the built model decides.
pub(super) fn screen_margin<T: Real>() -> T {
    T::c(1e-6).max(T::EPS * T::c(1e4))
}

/// Relative threshold on angular speeds (of the largest): whether a lever touches the
/// shaft, and whether a coordinate choice carries the speeds it is given. 1e-6, or 1000
/// ulps if that is larger (f32, 1.2e-4). A choice at its dead point is off by O(1); a
/// good one by rounding, amplified near a dead point: 2.3e-15 in f64 and 2.5e-6 (20
/// ulps) in f32 at S2's events, over f32's 1e-6, so that f32 refused every mode at the
/// first breakaway (0.0666 s) and went on in I0.
pub(super) fn speed_tol<T: Real>() -> T {
    T::c(1e-6).max(T::EPS * T::c(1e3))
}

/// The threshold on transmitted torques for a torque scale `s` (T_r + 1 N·m, plus the
/// levers' torques in the consistency conditions): 1e-9 s, or if that is larger (f32)
/// 10 ulps of `s` plus 1e4 ulps of 1 N·m. A lever that carries nothing computes c as a
/// sum of the mechanism's own torques (up to hundreds of N·m) that cancel: S2 without
/// load rounds it to 6e-13 N·m at most in f64 and 2.4e-4 N·m in f32 (~2700 ulps of
/// 1 N·m in both), far over f32's 1e-9 (T_r + 1 N·m): it fired a release every few
/// steps. The f32 threshold is 1.2e-3 N·m at T_r = 0 and 2.1e-3 N·m at T_r = 800 N·m,
/// which moves a release by ~1e-5 s in S2.
pub(super) fn torque_tol<T: Real>(s: T) -> T {
    (T::c(1e-9) * s).max(T::EPS * (T::c(10.0) * s + T::c(1e4)))
}

/// The settings are in range, or the error that names the first that is not.
pub(super) fn check_settings<T: Real>(s: &TwinSettings<T>) -> Result<(), TwinSetupError> {
    let positive = |x: T| x.finite() && x > T::zero();
    let checks = [
        ("h", s.h, positive(s.h)),
        (
            "switch_below",
            s.switch_below,
            positive(s.switch_below) && s.switch_below < T::one(),
        ),
        ("energy_tol", s.energy_tol, positive(s.energy_tol)),
        ("crank", s.crank, s.crank.finite()),
        ("swing", s.swing, s.swing.finite()),
        ("crank_speed", s.crank_speed, s.crank_speed.finite()),
        ("swing_speed", s.swing_speed, s.swing_speed.finite()),
    ];
    match checks.iter().find(|(_, _, ok)| !ok) {
        Some((field, value, _)) => Err(TwinSetupError::Setting {
            field,
            value: value.to_f64(),
        }),
        None => Ok(()),
    }
}
