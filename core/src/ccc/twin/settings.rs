//! The twin's settings fixed at start, and the bounds and thresholds of its step.

use super::error::TwinSetupError;
use super::slot::LinkState;
use crate::balance;
use crate::scalar::Real;

/// Events per step at most (see the module docs for what happens past it).
pub const MAX_EVENTS_PER_STEP: usize = 4;

/// Evaluations spent locating one event at most (Illinois regula falsi).
pub const MAX_LOCATE_ITER: usize = 16;

/// Coordinate switches inside a step at most: after a failed sub-step, or at a sub-step's
/// end near a dead point (the step's end may switch once more).
pub const MAX_RETRIES: usize = 2;

/// Sub-steps tried in turn when a step breaks the energy balance (see
/// [`TwinSettings::energy_tol`]): the core's division of a fixed step, at most
/// 1 + 4 + 16 DP5 steps' work. The twin tries 2 and 3 before 4, and 32 and 64 after 16,
/// when the failed attempt's energy jump predicts that they pass.
pub use crate::balance::SUBSTEPS;

/// The twin's rungs: [`SUBSTEPS`], 2 and 3 before 4, and 32 and 64 after 16, each of
/// the twin's own tried only when the last failed attempt's energy jump predicts that it
/// passes (`rung_may_pass` in the twin's step). At most 1 + 2 + 3 + 4 + 16 + 32 + 64 DP5
/// steps' work. S2 in f64 at h = 1 ms: 7 of the 8 steps that 4 sub-steps redid pass in 3
/// (jumps of 19.6 to 70 tolerances undivided), among them the catch I0 -> A8 at
/// 0.1763 s (488k Thumb-2 instructions on the Cortex-M7 in 1 + 4 DP5 steps). The
/// converter at light loads needs the finer ones at h = 1 ms: after a catch into A68
/// the mechanism runs near a dead point of each coordinate choice in turn (at
/// 20/200 N·m, motor / load, 16 sub-steps left the step after the catch at 0.2224 s
/// 3 tolerances over; at h = 1e-4 s the same stretch needs 3 sub-steps a step, 33 µs).
/// S2 never reaches past 4.
pub(super) const RETRY_SUBSTEPS: [u32; 7] = [1, 2, 3, 4, 16, 32, 64];

/// The factor by which a predicted rung's jump must stay under its tolerance
/// (the O(h⁶) estimate of `rung_may_pass` is asymptotic).
pub(super) const RUNG_SAFETY: f64 = 2.0;

/// An attempt that may be redone finer stops at an event whose state breaks the energy
/// balance by this many times the tolerance already: the dense output's state there is
/// where the step goes on from, and its error is the step's end's too unless the rest
/// of the step cancels it. (S2 at h = 1 ms: the same 32 steps redone as checked at
/// their ends only.)
pub(super) const EVENT_AUDIT_MARGIN: f64 = 1.0;

/// An attempt that may be redone finer stops before it locates an event if the end of
/// the DP5 step that found it breaks the energy balance by this many times the
/// tolerance: that end lies past the event, along the old mode's equations (which
/// still hold there as equations, and whose integration error is the event's plus the
/// rest of the step's): the state at the event, a fraction of the step before, then
/// fails [`EVENT_AUDIT_MARGIN`]'s check as a rule, after a location and its
/// evaluations. Twice
/// the tolerance leaves the steps whose event state passes to the event's check: S2
/// at h = 1 ms keeps its bits (the same 32 steps redone in the same sub-steps), and
/// the release at 0.2629 s, whose event breaks the balance by 135 tolerances, is
/// redone without locating it undivided: 386.6k → 332.3k x86 instructions in f64
/// (the Cortex-M7's worst step of S2 477k → 432k Thumb-2 instructions, now the catch
/// at 0.0667 s, whose balance breaks after its event). It costs an audit (about 1.6k
/// x86 instructions in f32) at each step with an event.
pub(super) const EARLY_AUDIT_MARGIN: f64 = 2.0;

/// Below this conditioning of its worst group, a [`TwinStepError::Diverged`](super::TwinStepError::Diverged) step is taken
/// to run into a singularity of the mechanism rather than to be too coarse.
pub const SINGULAR_CONDITIONING: f64 = 1e-2;

/// A diode branch whose rod and lever come in line within this many steps at their
/// present rate counts as in line when a step fails ([`TwinStepError::Diode`](super::TwinStepError::Diode)). In f64 the
/// branch's |sin| is under [`SINGULAR_CONDITIONING`] by then; in f32 rounding breaks
/// the energy balance 8 to 20 steps before (S1 at h = 1e-4 s: 0.3225 s against f64's
/// 0.3239 s, 14 steps before it), at |sin| of 3e-2 to 6e-2.
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
    /// under 4e-11 at h = 1e-4 s; S1's last steps before the diode stretches grow past
    /// 1e-9 each. Reference: [`energy_tolerance`].
    pub energy_tol: T,
    /// Spread an event's work over the steps that follow it, for a real-time loop's
    /// worst step (issue 18's budget): the step that finds an event ends at it (the
    /// event located, the state there in the old mode: exact, committed and audited),
    /// the next step chooses the new mode at that state without moving in time, and
    /// the steps after catch up with the clock, [`CATCH_UP`] steps long at most, until
    /// a step ends at `(n + 1)·h` again. Each step then holds one DP5 step and a
    /// location, or one mode choice, where an event step held two DP5 steps, the
    /// location and the choice. The twin's time ([`Twin::time`](super::Twin::time))
    /// lags the clock after an event ([`Twin::lag`](super::Twin::lag): S2 at h = 1 ms
    /// up to 4 h). `false` (the reference): every step ends at `(n + 1)·h`.
    pub spread_events: bool,
}

/// The longest step a twin with [`TwinSettings::spread_events`] takes to catch up with
/// the clock after an event, in steps `h`: one DP5 step (under the 1.5 `h` past which
/// a step's rest is split), so a catching-up step costs what a plain one does; a lag of
/// 2 `h` is made up in five steps.
pub const CATCH_UP: f64 = 1.4;

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
            energy_tol: energy_tolerance(h),
            spread_events: false,
        }
    }
}

/// The step that [`balance::ENERGY_TOL`] is the per-step tolerance of, s: the f64
/// reference step.
pub const ENERGY_TOL_STEP: f64 = 1e-4;

/// [`TwinSettings::reference`]'s energy tolerance at step `h`: the core's 1e-9
/// ([`balance::ENERGY_TOL`]) per [`ENERGY_TOL_STEP`] of time, so 1e-9 · h / 1e-4 s for
/// steps longer than it (an error per unit time: a second's steps may move the
/// residual by as much at any `h` as the 10 000 steps of 1e-4 s may), or the core's
/// rounding floor ([`balance::tolerance`]: 1000 ulps, f32's 1.2e-4) if that is larger.
///
/// DP5's energy error per step grows as h⁶, so at h = 1e-3 s a fixed 1e-9 redid 59 of
/// S2's 1000 steps (jumps of up to 1.35e-6 undivided) in sub-steps for an audit of
/// 1.1e-8 of the motor work, where h = 1e-4 s keeps 2.4e-11 without redoing any. The
/// jumps are the integrator's own error (the physical energy against the quadrature of
/// the motor's power), largest in smooth stretches of fast motion (I0 before a catch,
/// A68 before a release), not at events. Undivided, S2's audit at 1e-3 s ends at
/// 1.6e-6 of the motor work (past issue 18's 1e-6): the check is needed. With 1e-8 it
/// ends at 1.0e-7, the events the same as at 1e-4 s within 7.4e-9 s; 27 steps take
/// sub-steps (2 to 4), and 4 sub-steps divide a jump by about 4⁵ = 1024, under 1e-8 for
/// the largest. At h ≤ 1e-4 s, and in f32 at any h under 12 s, the tolerance is the core's.
pub fn energy_tolerance<T: Real>(h: T) -> T {
    let per_time = (h / T::c(ENERGY_TOL_STEP)).max(T::one());
    (T::c(balance::ENERGY_TOL) * per_time).max(balance::tolerance())
}

/// The largest angular speed of the links (rad/s), at least 1: the scale of the
/// speed thresholds.
pub(super) fn speed_scale<T: Real>(links: &[LinkState<T>; 9]) -> T {
    links.iter().fold(T::one(), |m, s| m.max(s.omega.abs()))
}

/// A candidate mode whose violation from the reference model ([`Twin::screen`](super::Twin::screen)) is over
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
