//! A standard error-controlled Dormand-Prince 5(4) integrator for accurate reference runs
//! (SPEC 1 "Integration"; Hairer, Nørsett & Wanner, *Solving ODEs I*, II.4 and code
//! `dopri5`).
//!
//! Each attempted step of size `h` from `(t, y)` gives the 5th-order `y1` and the embedded
//! error `e = h Σ E_i k_i`. With `sc_i = atol + rtol·max(|y_i|, |y1_i|)`,
//!
//! `err = sqrt(mean_i (e_i / sc_i)²)`;
//!
//! the step is accepted when `err <= 1`, and the next step is
//! `h_new = h · min(fac_max, max(fac_min, 0.9 · err^(-1/5)))` with `fac_min = 0.2`,
//! `fac_max = 10`; right after a rejection the step does not grow. A rejected step leaves
//! `t` and `y` untouched (and the FSAL stage valid).

use super::thesis::{check_positive, check_steps};
use super::{Dp5, OdeSystem, ThesisSettingsError};
use crate::scalar::Real;
use core::fmt;
use nalgebra::SVector;

/// Smallest step factor after a rejection (Hairer's `fac1 = 0.2`).
const FAC_MIN: f64 = 0.2;
/// Largest step growth factor (Hairer's `fac2 = 10`).
const FAC_MAX: f64 = 10.0;
/// Safety factor of the controller (Hairer's `safe = 0.9`).
const SAFETY: f64 = 0.9;
/// A remaining interval up to this multiple of the step is covered in one step
/// (Hairer's `x + 1.01 h` test), so no sliver of a last step is left.
const STRETCH: f64 = 1.01;

/// Settings of [`Adaptive`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings<T> {
    /// Relative tolerance (dimensionless), > 0.
    pub rtol: T,
    /// Absolute tolerance, state units, > 0.
    pub atol: T,
    /// Initial step, s.
    pub h0: T,
    /// Smallest step the controller may propose, s; needing less is
    /// [`AdaptiveError::StepTooSmall`].
    pub h_min: T,
    /// Largest step, s.
    pub h_max: T,
    /// Most step attempts (accepted + rejected) in one [`Adaptive::integrate_to`], >= 1.
    pub max_steps: u32,
    /// Most consecutive rejections of one step.
    pub max_rejections: u32,
}

impl<T: Real> Default for AdaptiveSettings<T> {
    /// `rtol 1e-10`, `atol 1e-12`, `h0 1e-4 s`, `h_min 1e-12 s`, `h_max 1e-2 s`,
    /// `max_steps 10_000_000`, `max_rejections 50`.
    fn default() -> Self {
        Self {
            rtol: T::c(1e-10),
            atol: T::c(1e-12),
            h0: T::c(1e-4),
            h_min: T::c(1e-12),
            h_max: T::c(1e-2),
            max_steps: 10_000_000,
            max_rejections: 50,
        }
    }
}

impl<T: Real> AdaptiveSettings<T> {
    /// Checks `rtol`, `atol`, `h0`, `h_min`, `h_max` finite and positive,
    /// `h_min <= h0 <= h_max` and `max_steps >= 1`.
    pub fn validate(&self) -> Result<(), ThesisSettingsError> {
        check_positive(self.rtol, "rtol")?;
        check_positive(self.atol, "atol")?;
        check_positive(self.h0, "h0")?;
        check_positive(self.h_min, "h_min")?;
        check_positive(self.h_max, "h_max")?;
        check_steps(self.h0, self.h_min, self.h_max)?;
        if self.max_steps == 0 {
            return Err(ThesisSettingsError::NotPositive("max_steps"));
        }
        Ok(())
    }
}

/// Why [`Adaptive`] stopped. Times are in s; on every error `t` and `y` hold the last
/// accepted state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AdaptiveError<E> {
    /// The system failed to evaluate.
    System(E),
    /// The controller needed a step below `h_min` (or below the resolution of `t`) at `t`.
    StepTooSmall {
        /// Time of the last accepted state, s.
        t: f64,
    },
    /// `max_steps` attempts in one [`Adaptive::integrate_to`] did not reach `t_end`.
    TooManySteps {
        /// Time of the last accepted state, s.
        t: f64,
    },
    /// More than `max_rejections` consecutive rejections at `t` (the count restarts after
    /// this error is returned).
    TooManyRejections {
        /// Time of the last accepted state, s.
        t: f64,
    },
    /// An invalid argument (non-finite `t` or `t_end`, `t_end < t`): nothing was done.
    Settings(ThesisSettingsError),
}

impl<E: fmt::Display> fmt::Display for AdaptiveError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::System(e) => write!(f, "system evaluation failed: {e}"),
            Self::StepTooSmall { t } => write!(f, "step size below h_min at t = {t} s"),
            Self::TooManySteps { t } => write!(f, "too many steps, stopped at t = {t} s"),
            Self::TooManyRejections { t } => {
                write!(f, "too many consecutive rejected steps at t = {t} s")
            }
            Self::Settings(e) => write!(f, "{e}"),
        }
    }
}

impl<E: fmt::Display + fmt::Debug> core::error::Error for AdaptiveError<E> {}

/// What one [`Adaptive::integrate_to`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptiveStats {
    /// Accepted steps.
    pub accepted: u32,
    /// Rejected step attempts.
    pub rejected: u32,
    /// Calls to the system's `eval`.
    pub evaluations: u64,
}

/// Error-controlled DP5(4) (Hairer's controller, see the module docs), for accurate
/// reference runs. Bounded work: one attempt per [`Adaptive::step`], at most
/// `max_steps` attempts per [`Adaptive::integrate_to`].
#[derive(Clone, Debug)]
pub struct Adaptive<T: Real, const N: usize> {
    /// The stepper (attempts, commits, dense output).
    dp5: Dp5<T, N>,
    /// Validated settings.
    settings: AdaptiveSettings<T>,
    /// Size of the next attempt, s.
    h: T,
    /// The last attempt was rejected (no growth on the next acceptance).
    after_rejection: bool,
    /// Consecutive rejections so far.
    rejections: u32,
}

impl<T: Real, const N: usize> Adaptive<T, N> {
    /// An integrator whose first attempt has size `settings.h0`, after
    /// [`AdaptiveSettings::validate`].
    pub fn new(settings: AdaptiveSettings<T>) -> Result<Self, ThesisSettingsError> {
        settings.validate()?;
        Ok(Self {
            dp5: Dp5::new(),
            settings,
            h: settings.h0,
            after_rejection: false,
            rejections: 0,
        })
    }

    /// Size of the next attempt, s.
    pub fn h(&self) -> T {
        self.h
    }

    /// The settings in use.
    pub fn settings(&self) -> &AdaptiveSettings<T> {
        &self.settings
    }

    /// The inner stepper: dense output of the last accepted step, evaluation count.
    pub fn dp5(&self) -> &Dp5<T, N> {
        &self.dp5
    }

    /// Forgets the FSAL stage (see [`Dp5::invalidate`]).
    pub fn invalidate(&mut self) {
        self.dp5.invalidate();
    }

    /// Integrates from `(t, y)` to exactly `t_end` (the last step is shortened so that
    /// `t == t_end` bitwise at the end), with at most `max_steps` attempts.
    ///
    /// `t_end == t` does nothing. On error, `t` and `y` hold the last accepted state.
    pub fn integrate_to<S: OdeSystem<T, N>>(
        &mut self,
        sys: &mut S,
        t: &mut T,
        y: &mut SVector<T, N>,
        t_end: T,
    ) -> Result<AdaptiveStats, AdaptiveError<S::Error>> {
        self.integrate_to_with(sys, t, y, t_end, |_, _, _| {})
    }

    /// [`Adaptive::integrate_to`], telling `attempted(sys, h, accepted)` after each
    /// attempt: its step `h` (s, the time advanced when accepted) and whether it was
    /// accepted. A quadrature carried with the state (a work `∫ P dt` from the power at
    /// the stages) is summed there.
    pub fn integrate_to_with<S: OdeSystem<T, N>>(
        &mut self,
        sys: &mut S,
        t: &mut T,
        y: &mut SVector<T, N>,
        t_end: T,
        mut attempted: impl FnMut(&mut S, T, bool),
    ) -> Result<AdaptiveStats, AdaptiveError<S::Error>> {
        if !t_end.finite() {
            return Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite(
                "t_end",
            )));
        }
        if !t.finite() {
            return Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite("t")));
        }
        if t_end < *t {
            return Err(AdaptiveError::Settings(ThesisSettingsError::Inconsistent(
                "t_end before t",
            )));
        }
        let evaluations0 = self.dp5.evaluations();
        let mut stats = AdaptiveStats::default();
        while *t < t_end {
            if stats.accepted.saturating_add(stats.rejected) >= self.settings.max_steps {
                return Err(AdaptiveError::TooManySteps { t: t.to_f64() });
            }
            let t0 = *t;
            let accepted = self.step(sys, t, y, t_end)?;
            attempted(sys, *t - t0, accepted);
            if accepted {
                stats.accepted += 1;
            } else {
                stats.rejected += 1;
            }
        }
        stats.evaluations = self.dp5.evaluations() - evaluations0;
        Ok(stats)
    }

    /// One attempt from `(t, y)` towards `t_limit`, for callers that want to see each
    /// accepted step (e.g. to write output, with [`Dp5::dense`] through [`Adaptive::dp5`]).
    ///
    /// The attempt has the current step size, or exactly `t_limit - t` (landing on
    /// `t_limit` bitwise) when that is at most 1.01 times it. Returns `Ok(true)` when the
    /// step was accepted (`t`, `y` advanced), `Ok(false)` when it was rejected (`t`, `y`
    /// untouched, smaller step next time) or when `t_limit <= t` (nothing done).
    /// `t_limit` may be `+∞`.
    pub fn step<S: OdeSystem<T, N>>(
        &mut self,
        sys: &mut S,
        t: &mut T,
        y: &mut SVector<T, N>,
        t_limit: T,
    ) -> Result<bool, AdaptiveError<S::Error>> {
        if !t.finite() {
            return Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite("t")));
        }
        if !(t_limit.finite() || t_limit > *t) {
            // NaN or -∞ (+∞ is allowed).
            return Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite(
                "t_limit",
            )));
        }
        if t_limit <= *t {
            return Ok(false);
        }
        let remaining = t_limit - *t;
        let (h, t1, landing) = if remaining <= self.h * T::c(STRETCH) {
            (remaining, t_limit, true)
        } else {
            (self.h, *t + self.h, false)
        };
        if t1 == *t {
            return Err(AdaptiveError::StepTooSmall { t: t.to_f64() });
        }
        self.dp5
            .attempt(sys, *t, y, h, t1)
            .map_err(AdaptiveError::System)?;
        let err = self.error_norm(y, sys.live());
        let s = &self.settings;
        if err <= T::c(1.0) {
            let mut fac = if err == T::c(0.0) {
                T::c(FAC_MAX)
            } else {
                (T::c(SAFETY) * err.powf(T::c(-0.2)))
                    .max(T::c(FAC_MIN))
                    .min(T::c(FAC_MAX))
            };
            if self.after_rejection {
                fac = fac.min(T::c(1.0));
            }
            let mut h_new = h * fac;
            if landing {
                // A step shortened to land says little about the step the problem allows.
                h_new = h_new.max(self.h);
            }
            self.h = h_new.max(s.h_min).min(s.h_max);
            self.after_rejection = false;
            self.rejections = 0;
            self.dp5.commit(t, y);
            Ok(true)
        } else {
            // err > 1, or NaN/∞ (a diverging attempt): reject.
            let fac = if err.finite() {
                (T::c(SAFETY) * err.powf(T::c(-0.2))).max(T::c(FAC_MIN))
            } else {
                T::c(FAC_MIN)
            };
            self.after_rejection = true;
            self.rejections = self.rejections.saturating_add(1);
            if h <= s.h_min {
                return Err(AdaptiveError::StepTooSmall { t: t.to_f64() });
            }
            self.h = (h * fac).max(s.h_min);
            if self.rejections > s.max_rejections {
                // Reported once; a later call starts a fresh count.
                self.rejections = 0;
                return Err(AdaptiveError::TooManyRejections { t: t.to_f64() });
            }
            Ok(false)
        }
    }

    /// `sqrt(mean_i (e_i / (atol + rtol·max(|y_i|, |y1_i|)))²)` of the attempted step
    /// (Hairer's norm), the mean over the system's `live` scalars
    /// ([`OdeSystem::live`]; its padding's errors are 0); 0 for `N = 0`; NaN when the
    /// attempt produced NaN.
    fn error_norm(&self, y: &SVector<T, N>, live: usize) -> T {
        if N == 0 {
            return T::c(0.0);
        }
        let live = live.clamp(1, N);
        let s = &self.settings;
        let mut sum = T::c(0.0);
        for ((e, y0), y1) in self
            .dp5
            .trial_err()
            .iter()
            .zip(y.iter())
            .zip(self.dp5.trial_y1().iter())
        {
            let sc = s.atol + s.rtol * y0.abs().max(y1.abs());
            let r = *e / sc;
            sum += r * r;
        }
        (sum / T::c(live as f64)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use core::convert::Infallible;
    use nalgebra::{Vector1, Vector2};
    use std::{format, println, string::String};

    struct Lin {
        lambda: f64,
    }

    impl OdeSystem<f64, 1> for Lin {
        type Error = Infallible;
        fn eval(
            &mut self,
            _t: f64,
            y: &Vector1<f64>,
            dy: &mut Vector1<f64>,
        ) -> Result<(), Infallible> {
            dy[0] = self.lambda * y[0];
            Ok(())
        }
    }

    /// `y' = -k (y - cos t)`: fast relaxation onto a slow forcing.
    struct Relax {
        k: f64,
    }

    impl Relax {
        /// Exact solution with `y(0) = 0`.
        fn exact(&self, t: f64) -> f64 {
            let k = self.k;
            let d = k * k + 1.0;
            (k * k * t.cos() + k * t.sin()) / d - (k * k / d) * (-k * t).exp()
        }
    }

    impl OdeSystem<f64, 1> for Relax {
        type Error = Infallible;
        fn eval(
            &mut self,
            t: f64,
            y: &Vector1<f64>,
            dy: &mut Vector1<f64>,
        ) -> Result<(), Infallible> {
            dy[0] = -self.k * (y[0] - t.cos());
            Ok(())
        }
    }

    /// `y' = y` for its first `ok_evals` evaluations, NaN afterwards (a model that
    /// breaks down: every later attempt diverges).
    struct Breaks {
        evals: u32,
        ok_evals: u32,
    }

    impl OdeSystem<f64, 1> for Breaks {
        type Error = Infallible;
        fn eval(
            &mut self,
            _t: f64,
            y: &Vector1<f64>,
            dy: &mut Vector1<f64>,
        ) -> Result<(), Infallible> {
            self.evals += 1;
            dy[0] = if self.evals > self.ok_evals {
                f64::NAN
            } else {
                y[0]
            };
            Ok(())
        }
    }

    #[derive(Debug, PartialEq)]
    struct Boom;

    impl fmt::Display for Boom {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("boom")
        }
    }

    struct FailAfter {
        t_fail: f64,
    }

    impl OdeSystem<f64, 2> for FailAfter {
        type Error = Boom;
        fn eval(&mut self, t: f64, y: &Vector2<f64>, dy: &mut Vector2<f64>) -> Result<(), Boom> {
            if t > self.t_fail {
                return Err(Boom);
            }
            dy[0] = y[1];
            dy[1] = -y[0];
            Ok(())
        }
    }

    #[test]
    fn exp_to_one_matches_e_and_lands_exactly() {
        let mut ad = Adaptive::<f64, 1>::new(AdaptiveSettings::default()).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        let stats = ad
            .integrate_to(&mut Lin { lambda: 1.0 }, &mut t, &mut y, 1.0)
            .unwrap();
        let err = (y[0] - core::f64::consts::E).abs();
        println!("y'=y to 1, rtol 1e-10: |y-e| = {err:e}, {stats:?}");
        assert_eq!(t.to_bits(), 1.0f64.to_bits());
        assert!(err < 1e-8);
        assert_eq!(ad.dp5().last_step().map(|(t0, h)| t0 + h), Some(1.0));
        // FSAL: 7 evaluations for the first attempt, 6 for each later one.
        assert_eq!(
            stats.evaluations,
            1 + 6 * (stats.accepted + stats.rejected) as u64
        );
        // Going on from there continues exactly, with the same controller state.
        let stats2 = ad
            .integrate_to(&mut Lin { lambda: 1.0 }, &mut t, &mut y, 2.0)
            .unwrap();
        assert_eq!(t, 2.0);
        assert!((y[0] - 2.0f64.exp()).abs() < 1e-8 * 2.0f64.exp());
        assert_eq!(
            stats2.evaluations,
            6 * (stats2.accepted + stats2.rejected) as u64
        );
        // t_end == t: nothing.
        let s3 = ad
            .integrate_to(&mut Lin { lambda: 1.0 }, &mut t, &mut y, 2.0)
            .unwrap();
        assert_eq!(s3, AdaptiveStats::default());
    }

    #[test]
    fn error_follows_the_tolerance() {
        let mut errs = [0.0; 3];
        for (e, rtol) in errs.iter_mut().zip([1e-6, 1e-8, 1e-10]) {
            let s = AdaptiveSettings {
                rtol,
                atol: rtol * 1e-2,
                h_max: 1.0,
                ..Default::default()
            };
            let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
            let (mut t, mut y) = (0.0, Vector1::new(1.0));
            ad.integrate_to(&mut Lin { lambda: -2.0 }, &mut t, &mut y, 3.0)
                .unwrap();
            *e = (y[0] - (-6.0f64).exp()).abs() / (-6.0f64).exp();
        }
        println!("y'=-2y to 3: relative errors for rtol 1e-6, 1e-8, 1e-10: {errs:?}");
        for (e, rtol) in errs.iter().zip([1e-6, 1e-8, 1e-10]) {
            assert!(*e < 10.0 * rtol, "error {e} at rtol {rtol}");
        }
        assert!(errs[0] > errs[1] && errs[1] > errs[2]);
    }

    #[test]
    fn fast_problem_rejects_but_converges() {
        let mut sys = Relax { k: 1000.0 };
        let s = AdaptiveSettings {
            h0: 1e-2,
            ..Default::default()
        };
        let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(0.0));
        let stats = ad.integrate_to(&mut sys, &mut t, &mut y, 1.0).unwrap();
        let err = (y[0] - sys.exact(1.0)).abs();
        println!("y'=-1000(y-cos t) to 1: |err| = {err:e}, {stats:?}");
        assert!(stats.rejected > 0);
        assert_eq!(t, 1.0);
        assert!(err < 1e-8, "{err}");
    }

    #[test]
    fn rejected_step_leaves_state_untouched() {
        let mut sys = Relax { k: 1000.0 };
        let s = AdaptiveSettings {
            h0: 1e-2,
            ..Default::default()
        };
        let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(0.0));
        let accepted = ad.step(&mut sys, &mut t, &mut y, 1.0).unwrap();
        assert!(!accepted);
        assert_eq!((t, y[0]), (0.0, 0.0));
        assert!(ad.h() < 1e-2 && ad.h() >= 2e-3);
        assert_eq!(ad.dp5().last_step(), None);
        // Step by step until accepted, then on to t_limit: every accepted step visible.
        let mut accepted_steps = 0;
        while t < 0.01 {
            if ad.step(&mut sys, &mut t, &mut y, 0.01).unwrap() {
                accepted_steps += 1;
                let mut d = Vector1::zeros();
                ad.dp5().dense(1.0, &mut d);
                assert_eq!(d, y);
            }
        }
        assert_eq!(t, 0.01);
        assert!(accepted_steps > 1);
        assert!((y[0] - sys.exact(0.01)).abs() < 1e-9);
        // Nothing to do once there.
        assert_eq!(ad.step(&mut sys, &mut t, &mut y, 0.01), Ok(false));
        assert_eq!(t, 0.01);
    }

    #[test]
    fn max_steps_bound() {
        let s = AdaptiveSettings {
            max_steps: 10,
            ..Default::default()
        };
        let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        let r = ad.integrate_to(&mut Lin { lambda: 1.0 }, &mut t, &mut y, 1.0);
        match r {
            Err(AdaptiveError::TooManySteps { t: ts }) => {
                assert_eq!(ts, t);
                assert!(t > 0.0 && t < 1.0);
            }
            other => panic!("expected TooManySteps, got {other:?}"),
        }
        assert_eq!(ad.dp5().evaluations(), 7 + 6 * 9);
        assert!((y[0] - t.exp()).abs() < 1e-10);
    }

    #[test]
    fn breakdown_gives_too_many_rejections_or_step_too_small() {
        // One good step (7 evaluations), then every attempt is NaN and rejected.
        let s = AdaptiveSettings {
            max_rejections: 5,
            ..Default::default()
        };
        let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        let mut sys = Breaks {
            evals: 0,
            ok_evals: 7,
        };
        let r = ad.integrate_to(&mut sys, &mut t, &mut y, 1.0);
        println!(
            "breakdown, max_rejections 5: {r:?}, {} evaluations",
            sys.evals
        );
        assert_eq!(r, Err(AdaptiveError::TooManyRejections { t: 1e-4 }));
        assert_eq!(t, 1e-4);
        assert!((y[0] - t.exp()).abs() < 1e-15);
        // 6 rejected attempts of 6 evaluations each (FSAL stage reused).
        assert_eq!(sys.evals, 7 + 6 * 6);

        // With many rejections allowed, the step shrinks by 0.2 per rejection to h_min.
        let s = AdaptiveSettings {
            max_rejections: 1000,
            ..Default::default()
        };
        let mut ad = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        let mut sys = Breaks {
            evals: 0,
            ok_evals: 7,
        };
        let r = ad.integrate_to(&mut sys, &mut t, &mut y, 1.0);
        println!("breakdown, max_rejections 1000: {r:?}, h = {:e}", ad.h());
        assert_eq!(r, Err(AdaptiveError::StepTooSmall { t: 1e-4 }));
        assert_eq!(ad.h(), 1e-12);
    }

    #[test]
    fn system_error_is_returned_with_state_untouched() {
        let mut ad = Adaptive::<f64, 2>::new(AdaptiveSettings::default()).unwrap();
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
        let r = ad.integrate_to(&mut FailAfter { t_fail: 0.05 }, &mut t, &mut y, 1.0);
        assert_eq!(r, Err(AdaptiveError::System(Boom)));
        assert!(t <= 0.05 && t > 0.0);
        assert!((y[0] - t.cos()).abs() < 1e-12 && (y[1] + t.sin()).abs() < 1e-12);
        let (t_before, y_before) = (t, y);
        assert_eq!(
            ad.step(&mut FailAfter { t_fail: 0.05 }, &mut t, &mut y, 1.0),
            Err(AdaptiveError::System(Boom))
        );
        assert_eq!((t, y), (t_before, y_before));
        assert_eq!(
            format!("{}", AdaptiveError::System(Boom)),
            "system evaluation failed: boom"
        );
    }

    #[test]
    fn bad_arguments_and_settings() {
        let ok = AdaptiveSettings::<f64>::default();
        assert_eq!(ok.validate(), Ok(()));
        let cases = [
            (
                AdaptiveSettings {
                    rtol: f64::NAN,
                    ..ok
                },
                ThesisSettingsError::NonFinite("rtol"),
            ),
            (
                AdaptiveSettings { atol: 0.0, ..ok },
                ThesisSettingsError::NotPositive("atol"),
            ),
            (
                AdaptiveSettings { h_max: -1.0, ..ok },
                ThesisSettingsError::NotPositive("h_max"),
            ),
            (
                AdaptiveSettings {
                    h_min: 1.0,
                    h0: 1.0,
                    h_max: 0.5,
                    ..ok
                },
                ThesisSettingsError::Inconsistent("h_min > h_max"),
            ),
            (
                AdaptiveSettings { h0: 1.0, ..ok },
                ThesisSettingsError::Inconsistent("h0 outside [h_min, h_max]"),
            ),
            (
                AdaptiveSettings { max_steps: 0, ..ok },
                ThesisSettingsError::NotPositive("max_steps"),
            ),
        ];
        for (s, e) in cases {
            assert_eq!(s.validate(), Err(e));
            assert_eq!(Adaptive::<f64, 1>::new(s).err(), Some(e));
        }
        let mut ad = Adaptive::<f64, 1>::new(ok).unwrap();
        let mut sys = Lin { lambda: 1.0 };
        let (mut t, mut y) = (1.0, Vector1::new(1.0));
        let r = ad.integrate_to(&mut sys, &mut t, &mut y, 0.5);
        assert_eq!(
            r,
            Err(AdaptiveError::Settings(ThesisSettingsError::Inconsistent(
                "t_end before t"
            )))
        );
        let r = ad.integrate_to(&mut sys, &mut t, &mut y, f64::NAN);
        assert_eq!(
            r,
            Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite(
                "t_end"
            )))
        );
        let r = ad.step(&mut sys, &mut t, &mut y, f64::NAN);
        assert_eq!(
            r,
            Err(AdaptiveError::Settings(ThesisSettingsError::NonFinite(
                "t_limit"
            )))
        );
        assert_eq!((t, y[0]), (1.0, 1.0));
        assert_eq!(ad.dp5().evaluations(), 0);
        let msg: String = format!("{}", AdaptiveError::<Infallible>::StepTooSmall { t: 0.5 });
        assert_eq!(msg, "step size below h_min at t = 0.5 s");
    }

    #[test]
    fn error_norm_is_hairers_rms() {
        // One step of y' = y with a 2-component copy: the norm equals the 1-component one.
        struct Two;
        impl OdeSystem<f64, 2> for Two {
            type Error = Infallible;
            fn eval(
                &mut self,
                _t: f64,
                y: &Vector2<f64>,
                dy: &mut Vector2<f64>,
            ) -> Result<(), Infallible> {
                *dy = *y;
                Ok(())
            }
        }
        let s = AdaptiveSettings {
            h0: 1e-2,
            ..Default::default()
        };
        let mut a1 = Adaptive::<f64, 1>::new(s).unwrap();
        let mut a2 = Adaptive::<f64, 2>::new(s).unwrap();
        let y1 = Vector1::new(1.0);
        let y2 = Vector2::new(1.0, 1.0);
        a1.dp5
            .attempt(&mut Lin { lambda: 1.0 }, 0.0, &y1, 1e-2, 1e-2)
            .unwrap();
        a2.dp5.attempt(&mut Two, 0.0, &y2, 1e-2, 1e-2).unwrap();
        let (n1, n2) = (a1.error_norm(&y1, 1), a2.error_norm(&y2, 2));
        // Hand computation for one component.
        let e = a1.dp5.trial_err()[0];
        let sc = s.atol + s.rtol * 1.0f64.max(a1.dp5.trial_y1()[0].abs());
        assert!((n1 - (e / sc).abs()).abs() <= 1e-15 * n1);
        assert!((n1 - n2).abs() <= 1e-15 * n1);
    }

    /// A system padded with scalars it keeps at 0 (a 1-DOF mechanism in a larger
    /// state) and saying so (`live`) is integrated as the unpadded one, step for step
    /// and bit for bit: its zeros no longer dilute the error norm (they made the
    /// tolerance √(N/live) times the one asked, and the steps longer).
    #[test]
    fn padding_does_not_loosen_the_tolerance() {
        struct Padded {
            live: usize,
        }
        impl OdeSystem<f64, 4> for Padded {
            type Error = Infallible;
            fn eval(
                &mut self,
                t: f64,
                y: &nalgebra::Vector4<f64>,
                dy: &mut nalgebra::Vector4<f64>,
            ) -> Result<(), Infallible> {
                *dy = nalgebra::Vector4::new(-50.0 * (y[0] - t.cos()), 0.0, 0.0, 0.0);
                Ok(())
            }
            fn live(&self) -> usize {
                self.live
            }
        }
        let s = AdaptiveSettings {
            rtol: 1e-8,
            atol: 1e-10,
            ..Default::default()
        };
        let mut one = Adaptive::<f64, 1>::new(s).unwrap();
        let (mut t1, mut y1) = (0.0, Vector1::new(0.0));
        let st1 = one
            .integrate_to(&mut Relax { k: 50.0 }, &mut t1, &mut y1, 2.0)
            .unwrap();
        let run = |live: usize| {
            let mut a = Adaptive::<f64, 4>::new(s).unwrap();
            let (mut t, mut y) = (0.0, nalgebra::Vector4::zeros());
            let st = a
                .integrate_to(&mut Padded { live }, &mut t, &mut y, 2.0)
                .unwrap();
            (st, y[0])
        };
        let (said, y_said) = run(1);
        assert_eq!(said.accepted, st1.accepted);
        assert_eq!(y_said.to_bits(), y1[0].to_bits());
        // Unsaid, the padding takes the tolerance √4 = 2 times looser: fewer steps.
        let (unsaid, _) = run(4);
        assert!(
            unsaid.accepted < st1.accepted,
            "{} vs {}",
            unsaid.accepted,
            st1.accepted
        );
    }
}
