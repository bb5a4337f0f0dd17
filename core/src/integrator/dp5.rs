//! The fixed-step Dormand-Prince 5(4) stepper with FSAL and dense output (SPEC 1
//! "Integration", thesis 5.4, eq. 5.31-5.33 with the weight rows the right way round).
//!
//! One step from `(t, y)` with size `h` evaluates the seven stages of [`Tableau`],
//! propagates the 5th-order solution `y1 = y + h Σ B5_i k_i`, and keeps:
//! - `k_7 = f(t + h, y1)`, reused as the next step's `k_1` (FSAL: 6 evaluations a step);
//! - the stages and `y0`, `y1` of the last successful step, for the dense output.
//!
//! Stages are written into a scratch copy and swapped in only when every evaluation
//! succeeded, so a failing [`OdeSystem::eval`] leaves the caller's `(t, y)`, the FSAL
//! stage and the dense output of the previous step as they were.

use super::{OdeSystem, Tableau};
use crate::scalar::Real;
use nalgebra::SVector;

/// What one DP5 step reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport<T> {
    /// Max-norm `‖h Σ_i E_i k_i‖_∞ = max_j |y1_j - y1*_j|` of the embedded error estimate
    /// (difference between the propagated 5th-order and the embedded 4th-order solution,
    /// thesis eq. 5.33), in the units of the state components; absolute, not scaled.
    /// NaN or infinite when a component of the estimate is.
    pub error: T,
}

/// One step's data: stages, end points and embedded error vector.
#[derive(Clone, Copy, Debug)]
struct StepData<T: Real, const N: usize> {
    /// `k_1 .. k_7`, slopes (state units per second).
    k: [SVector<T, N>; 7],
    /// State at the start of the step.
    y0: SVector<T, N>,
    /// Propagated 5th-order state at the end of the step.
    y1: SVector<T, N>,
    /// Embedded error estimate `h Σ E_i k_i`.
    err: SVector<T, N>,
    /// Start time, s.
    t0: T,
    /// Step size, s.
    h: T,
    /// End time, s (`t0 + h`, or the exact landing time given by the caller).
    t1: T,
}

impl<T: Real, const N: usize> StepData<T, N> {
    /// All zeros (no step yet).
    fn zeros() -> Self {
        let z = SVector::<T, N>::zeros();
        Self {
            k: [z; 7],
            y0: z,
            y1: z,
            err: z,
            t0: T::c(0.0),
            h: T::c(0.0),
            t1: T::c(0.0),
        }
    }
}

/// `δ_i1 - B5_i`: Hairer's `bspl` coefficients of the dense output (see
/// [`Tableau::DENSE_D`]).
const DENSE_C: [f64; 7] = {
    let b = Tableau::B5;
    [1.0 - b[0], -b[1], -b[2], -b[3], -b[4], -b[5], -b[6]]
};
/// `2 B5_i - δ_i1 - δ_i7`: Hairer's `rcont4` coefficients of the dense output (see
/// [`Tableau::DENSE_D`]).
const DENSE_E: [f64; 7] = {
    let b = Tableau::B5;
    [
        2.0 * b[0] - 1.0,
        2.0 * b[1],
        2.0 * b[2],
        2.0 * b[3],
        2.0 * b[4],
        2.0 * b[5],
        2.0 * b[6] - 1.0,
    ]
};

/// `Σ_i w_i k_i` over as many terms as the shorter of `ks` and `w` (zero weights skipped).
fn lin<'a, T: Real, const N: usize>(
    ks: impl IntoIterator<Item = &'a SVector<T, N>>,
    w: impl IntoIterator<Item = T>,
) -> SVector<T, N> {
    let mut acc = SVector::<T, N>::zeros();
    let zero = T::c(0.0);
    let one = T::c(1.0);
    for (k, wi) in ks.into_iter().zip(w) {
        if wi != zero {
            acc.axpy(wi, k, one);
        }
    }
    acc
}

/// The `f64` weights of a tableau row, converted to `T`.
fn row<T: Real>(w: &[f64]) -> impl Iterator<Item = T> + '_ {
    w.iter().map(|&x| T::c(x))
}

/// `y + h Σ_j a_j k_j` over the given stages.
fn stage_input<'a, T: Real, const N: usize>(
    y: &SVector<T, N>,
    h: T,
    ks: impl IntoIterator<Item = &'a SVector<T, N>>,
    a: &[f64],
) -> SVector<T, N> {
    y + lin(ks, row::<T>(a)) * h
}

/// `‖v‖_∞`; returns the first non-finite component's magnitude if there is one.
pub(super) fn max_norm<T: Real, const N: usize>(v: &SVector<T, N>) -> T {
    let mut m = T::c(0.0);
    for x in v.iter() {
        let a = x.abs();
        if !a.finite() {
            return a;
        }
        if a > m {
            m = a;
        }
    }
    m
}

/// Bitwise equality of two scalars (widening to `f64` is exact and injective).
fn same_bits<T: Real>(a: T, b: T) -> bool {
    a.to_f64().to_bits() == b.to_f64().to_bits()
}

/// Counts and performs one evaluation of `sys`.
fn eval<T: Real, const N: usize, S: OdeSystem<T, N>>(
    sys: &mut S,
    count: &mut u64,
    t: T,
    y: &SVector<T, N>,
    dy: &mut SVector<T, N>,
) -> Result<(), S::Error> {
    *count = count.saturating_add(1);
    sys.eval(t, y, dy)
}

/// The fixed-step Dormand-Prince 5(4) integrator with FSAL and dense output
/// (SPEC 1, thesis 5.4, eq. 5.31-5.33; the 5th-order row is propagated, see
/// [`Tableau::B5`]).
///
/// Holds no reference to the system: each [`Dp5::step`] is given the [`OdeSystem`], the
/// time `t` (s) and the state `y`. Work per step is bounded (7 evaluations at most), no
/// allocation, no panic.
#[derive(Clone, Debug)]
pub struct Dp5<T: Real, const N: usize> {
    /// The last successful step (FSAL stage, dense output) and the scratch for the step
    /// being computed; which is which is `flip` (a commit flips it instead of copying).
    data: [StepData<T, N>; 2],
    /// `data[1]` is the last step, `data[0]` the scratch (else the other way round).
    flip: bool,
    /// `true` once a step has succeeded (`last` holds it).
    has_last: bool,
    /// `true` while `last.k[6]` may be reused as `f(last.t1, last.y1)`.
    fsal: bool,
    /// `true` while the scratch's `k[0]` is a caller's `f(t0, y0)` for the scratch's
    /// `t0`, `y0` ([`Dp5::seed`]).
    seeded: bool,
    /// Number of calls to [`OdeSystem::eval`] made so far, failing ones included.
    evaluations: u64,
}

impl<T: Real, const N: usize> Default for Dp5<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize> Dp5<T, N> {
    /// The last successful step.
    fn last(&self) -> &StepData<T, N> {
        let [a, b] = &self.data;
        if self.flip {
            b
        } else {
            a
        }
    }

    /// The step being computed.
    fn trial(&self) -> &StepData<T, N> {
        let [a, b] = &self.data;
        if self.flip {
            a
        } else {
            b
        }
    }

    /// A stepper with no stored stage (the first step evaluates 7 stages).
    pub fn new() -> Self {
        Self {
            data: [StepData::zeros(); 2],
            flip: false,
            has_last: false,
            fsal: false,
            seeded: false,
            evaluations: 0,
        }
    }

    /// Forgets the FSAL stage: call after the state or the system's inputs (parameters,
    /// external loads, motor torque) changed outside the integrator, so the next step
    /// re-evaluates `k_1 = f(t, y)`. The dense output of the last step stays available.
    ///
    /// A changed `t` or `y` (bitwise) is detected without it; a changed system is not.
    pub fn invalidate(&mut self) {
        self.fsal = false;
        self.seeded = false;
    }

    /// Gives the next step its first stage: `k1 = f(t, y)`, which the caller has just
    /// evaluated itself (after a mode change, say, whose model it evaluated at the new
    /// state to check it). A step from this very `(t, y)` (bitwise) then takes 6
    /// evaluations instead of 7. Call after [`Dp5::invalidate`], which forgets it; the
    /// dense output of the last step stays available.
    pub fn seed(&mut self, t: T, y: &SVector<T, N>, k1: &SVector<T, N>) {
        let [a, b] = &mut self.data;
        let tr = if self.flip { a } else { b };
        tr.t0 = t;
        tr.y0 = *y;
        if let Some(k) = tr.k.first_mut() {
            *k = *k1;
        }
        self.seeded = true;
    }

    /// Number of calls to [`OdeSystem::eval`] so far, failing calls included:
    /// 7 for a step without a valid FSAL stage, 6 with one.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// `(t0, h)` of the last successful step, s; `None` before the first one.
    pub fn last_step(&self) -> Option<(T, T)> {
        if self.has_last {
            Some((self.last().t0, self.last().h))
        } else {
            None
        }
    }

    /// One DP5 step of size `h` (s) from `(t, y)` (SPEC 1, thesis eq. 5.31-5.33).
    ///
    /// `k_1` is the stored `k_7` of the previous step when the FSAL stage is valid and
    /// `t`, `y` are bitwise the end point of that step; otherwise it is evaluated. The
    /// last stage `k_7 = f(t + h, y1)` is kept for the next step.
    ///
    /// On success, `t += h`, `y` = the 5th-order solution, and the report holds the
    /// max-norm of the embedded error estimate. On `Err` from any evaluation, `t`, `y`,
    /// the FSAL stage and the dense output of the previous step are untouched.
    ///
    /// `h` is not checked: `h = 0` is a no-op step, a negative `h` steps backwards, a
    /// non-finite `h` yields a non-finite state.
    pub fn step<S: OdeSystem<T, N>>(
        &mut self,
        sys: &mut S,
        t: &mut T,
        y: &mut SVector<T, N>,
        h: T,
    ) -> Result<StepReport<T>, S::Error> {
        let t1 = *t + h;
        self.attempt(sys, *t, y, h, t1)?;
        let error = max_norm(&self.trial().err);
        self.commit(t, y);
        Ok(StepReport { error })
    }

    /// Computes a step into the scratch buffers without committing it: stages, `y1`,
    /// error vector. `t1` is the end time used for the stages with `c = 1` and stored as
    /// the step's end (`t + h`, or an exact landing time).
    pub(super) fn attempt<S: OdeSystem<T, N>>(
        &mut self,
        sys: &mut S,
        t: T,
        y: &SVector<T, N>,
        h: T,
        t1: T,
    ) -> Result<(), S::Error> {
        let reuse = self.fsal_matches(t, y);
        let seeded = !reuse && self.seed_matches(t, y);
        let ev = &mut self.evaluations;
        // The last step (for its FSAL stage) and the scratch to fill (see `flip`).
        let [a, b] = &mut self.data;
        let (last, tr) = if self.flip { (&*b, a) } else { (&*a, b) };
        tr.t0 = t;
        tr.h = h;
        tr.t1 = t1;
        tr.y0 = *y;
        let a = &Tableau::A;
        let c = &Tableau::C;
        let [k1, k2, k3, k4, k5, k6, k7] = &mut tr.k;

        if reuse {
            *k1 = last.k[6];
        } else if !seeded {
            // (Seeded: `k1` already holds f(t, y).)
            eval(sys, ev, t, y, k1)?;
        }
        let yt = stage_input(y, h, [&*k1], &a[1]);
        eval(sys, ev, t + T::c(c[1]) * h, &yt, k2)?;
        let yt = stage_input(y, h, [&*k1, &*k2], &a[2]);
        eval(sys, ev, t + T::c(c[2]) * h, &yt, k3)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3], &a[3]);
        eval(sys, ev, t + T::c(c[3]) * h, &yt, k4)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4], &a[4]);
        eval(sys, ev, t + T::c(c[4]) * h, &yt, k5)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4, &*k5], &a[5]);
        eval(sys, ev, t1, &yt, k6)?;
        tr.y1 = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4, &*k5, &*k6], &Tableau::B5);
        eval(sys, ev, t1, &tr.y1, k7)?;
        tr.err = lin(
            [&*k1, &*k2, &*k3, &*k4, &*k5, &*k6, &*k7],
            row::<T>(&Tableau::E),
        ) * h;
        Ok(())
    }

    /// The propagated state of the attempted (uncommitted) step.
    pub(super) fn trial_y1(&self) -> &SVector<T, N> {
        &self.trial().y1
    }

    /// The embedded error vector `h Σ E_i k_i` of the attempted step.
    pub(super) fn trial_err(&self) -> &SVector<T, N> {
        &self.trial().err
    }

    /// Makes the attempted step the last step: writes its end `(t1, y1)` to `t`, `y`,
    /// and validates its `k_7` as the FSAL stage.
    pub(super) fn commit(&mut self, t: &mut T, y: &mut SVector<T, N>) {
        self.flip = !self.flip;
        self.has_last = true;
        self.fsal = true;
        self.seeded = false;
        *t = self.last().t1;
        *y = self.last().y1;
    }

    /// `true` when the stored `k_7` is `f(t, y)` for this very `(t, y)`.
    fn fsal_matches(&self, t: T, y: &SVector<T, N>) -> bool {
        self.fsal
            && same_bits(t, self.last().t1)
            && y.iter()
                .zip(self.last().y1.iter())
                .all(|(a, b)| same_bits(*a, *b))
    }

    /// `true` when the scratch's `k[0]` is a seeded `f(t, y)` for this very `(t, y)`.
    fn seed_matches(&self, t: T, y: &SVector<T, N>) -> bool {
        let tr = self.trial();
        self.seeded
            && same_bits(t, tr.t0)
            && y.iter().zip(tr.y0.iter()).all(|(a, b)| same_bits(*a, *b))
    }

    /// Dense output of the last successful step: the 4th-order continuous extension
    /// `y(t0 + θh) = y0 + h Σ_i w_i(θ) k_i` (Hairer's DOPRI5 `CONTD5`, see
    /// [`Tableau::DENSE_D`]), written to `out`.
    ///
    /// `θ` is clamped to `[0, 1]` (NaN counts as 0); `θ = 0` and `θ = 1` give `y0` and
    /// `y1` bitwise. Before the first successful step, writes zeros.
    pub fn dense(&self, theta: T, out: &mut SVector<T, N>) {
        let d = self.last();
        match clamp_theta(theta) {
            Theta::Start => *out = d.y0,
            Theta::End => *out = d.y1,
            Theta::Inner(th) => {
                let u = T::c(1.0) - th;
                let w = Tableau::B5
                    .iter()
                    .zip(DENSE_C.iter())
                    .zip(DENSE_E.iter())
                    .zip(Tableau::DENSE_D.iter())
                    .map(|(((&b, &c), &e), &dd)| {
                        th * (T::c(b) + u * (T::c(c) + th * (T::c(e) + u * T::c(dd))))
                    });
                *out = d.y0 + lin(d.k.iter(), w) * d.h;
            }
        }
    }

    /// Time derivative of [`Dp5::dense`], `d/dt y(t0 + θh) = Σ_i w_i'(θ) k_i` (state units
    /// per second), with the same clamping; `θ = 0` and `θ = 1` give `k_1 = f(t0, y0)` and
    /// `k_7 = f(t1, y1)` bitwise. For locating events between `t0` and `t0 + h`.
    pub fn dense_derivative(&self, theta: T, out: &mut SVector<T, N>) {
        let d = self.last();
        let [k1, .., k7] = &d.k;
        match clamp_theta(theta) {
            Theta::Start => *out = *k1,
            Theta::End => *out = *k7,
            Theta::Inner(th) => {
                let one = T::c(1.0);
                let two = T::c(2.0);
                let u = one - th;
                let g1 = one - two * th;
                let g2 = th * (two - T::c(3.0) * th);
                let g3 = two * th * u * g1;
                let w = Tableau::B5
                    .iter()
                    .zip(DENSE_C.iter())
                    .zip(DENSE_E.iter())
                    .zip(Tableau::DENSE_D.iter())
                    .map(|(((&b, &c), &e), &dd)| {
                        T::c(b) + g1 * T::c(c) + g2 * T::c(e) + g3 * T::c(dd)
                    });
                *out = lin(d.k.iter(), w);
            }
        }
    }
}

/// Where a clamped `θ` lies.
enum Theta<T> {
    /// `θ <= 0` or NaN.
    Start,
    /// `θ >= 1`.
    End,
    /// `0 < θ < 1`.
    Inner(T),
}

/// Clamps `θ` to `[0, 1]` (NaN to 0).
fn clamp_theta<T: Real>(theta: T) -> Theta<T> {
    if theta >= T::c(1.0) {
        Theta::End
    } else if theta > T::c(0.0) {
        Theta::Inner(theta)
    } else {
        Theta::Start
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use core::convert::Infallible;
    use nalgebra::{Vector1, Vector2};
    use std::println;

    /// `y' = λ y`, counting evaluations.
    struct Lin {
        lambda: f64,
        evals: u32,
    }

    impl OdeSystem<f64, 1> for Lin {
        type Error = Infallible;
        fn eval(
            &mut self,
            _t: f64,
            y: &Vector1<f64>,
            dy: &mut Vector1<f64>,
        ) -> Result<(), Infallible> {
            self.evals += 1;
            dy[0] = self.lambda * y[0];
            Ok(())
        }
    }

    /// `x'' = -ω² x` as `(x, v)`.
    struct Osc<T> {
        w2: T,
    }

    impl<T: Real> OdeSystem<T, 2> for Osc<T> {
        type Error = Infallible;
        fn eval(&mut self, _t: T, y: &Vector2<T>, dy: &mut Vector2<T>) -> Result<(), Infallible> {
            dy[0] = y[1];
            dy[1] = -self.w2 * y[0];
            Ok(())
        }
    }

    #[derive(Debug, PartialEq)]
    struct Boom;

    /// The oscillator, failing on its `fail_on`-th evaluation (1-based) while `armed`.
    struct Flaky {
        evals: u32,
        fail_on: u32,
        armed: bool,
    }

    impl OdeSystem<f64, 2> for Flaky {
        type Error = Boom;
        fn eval(&mut self, _t: f64, y: &Vector2<f64>, dy: &mut Vector2<f64>) -> Result<(), Boom> {
            self.evals += 1;
            if self.armed && self.evals == self.fail_on {
                dy[0] = f64::NAN; // garbage must never leak out
                dy[1] = f64::NAN;
                return Err(Boom);
            }
            dy[0] = y[1];
            dy[1] = -y[0];
            Ok(())
        }
    }

    /// Integrates `y' = λy` over `[0, 1]` with `n` steps; returns `|y(1) - e^λ|`.
    fn global_error(lambda: f64, n: u32) -> f64 {
        let mut sys = Lin { lambda, evals: 0 };
        let mut dp = Dp5::<f64, 1>::new();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        let h = 1.0 / n as f64;
        for _ in 0..n {
            dp.step(&mut sys, &mut t, &mut y, h).unwrap();
        }
        assert!((t - 1.0).abs() < 1e-14);
        (y[0] - (lambda * t).exp()).abs()
    }

    /// DP5's stability function: one step of `y' = λy` from 1 gives
    /// `R(z) = Σ_{j≤5} z^j/j! + z^6/600`, `z = λh`; so the local error is
    /// `e^z - R(z) = -z^6/3600 + z^7/5040 + O(z^8)`.
    fn stability(z: f64) -> f64 {
        1.0 + z
            + z * z / 2.0
            + z.powi(3) / 6.0
            + z.powi(4) / 24.0
            + z.powi(5) / 120.0
            + z.powi(6) / 600.0
    }

    #[test]
    fn one_step_matches_exp_with_local_order_six() {
        for lambda in [1.0, -2.0] {
            let mut errs = [0.0; 3];
            for (e, h) in errs.iter_mut().zip([0.1, 0.05, 0.025]) {
                let mut sys = Lin { lambda, evals: 0 };
                let mut dp = Dp5::<f64, 1>::new();
                let (mut t, mut y) = (0.0, Vector1::new(1.0));
                dp.step(&mut sys, &mut t, &mut y, h).unwrap();
                assert_eq!(t, h);
                let z = lambda * h;
                // The stepper is exactly the stability polynomial (up to rounding) ...
                assert!((y[0] - stability(z)).abs() < 4e-16, "R({z})");
                // ... and its error against exp is the analytic local error.
                *e = (y[0] - z.exp()).abs();
                let predicted = (z.powi(6) / 3600.0 - z.powi(7) / 5040.0).abs();
                assert!(
                    (*e - predicted).abs() < 0.1 * predicted + 1e-15,
                    "error {e} vs {predicted}"
                );
            }
            println!(
                "λ={lambda}: one-step errors {errs:?}, ratios {} {}",
                errs[0] / errs[1],
                errs[1] / errs[2]
            );
            // Local error of a 5th-order method is O(h^6): halving h divides it by ~64.
            for r in [errs[0] / errs[1], errs[1] / errs[2]] {
                assert!((50.0..80.0).contains(&r), "local ratio {r}");
            }
        }
    }

    #[test]
    fn global_error_is_fifth_order() {
        for lambda in [1.0, -2.0] {
            let e = [
                global_error(lambda, 10),
                global_error(lambda, 20),
                global_error(lambda, 40),
            ];
            let (r1, r2) = (e[0] / e[1], e[1] / e[2]);
            println!("λ={lambda}: global errors {e:?}, ratios {r1} {r2}");
            assert!((25.0..40.0).contains(&r1), "ratio h/h2 {r1}");
            assert!((25.0..40.0).contains(&r2), "ratio h2/h4 {r2}");
        }
    }

    #[test]
    fn harmonic_oscillator_ten_periods() {
        let mut sys = Osc { w2: 1.0 };
        let mut dp = Dp5::<f64, 2>::new();
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
        let t_end = 20.0 * core::f64::consts::PI;
        let n = (t_end / 0.01) as u32; // 6283 steps of 0.01, then the remainder
        for _ in 0..n {
            dp.step(&mut sys, &mut t, &mut y, 0.01).unwrap();
        }
        let h_last = t_end - t;
        dp.step(&mut sys, &mut t, &mut y, h_last).unwrap();
        let ex = (y[0] - t.cos()).abs();
        let ev = (y[1] + t.sin()).abs();
        let energy = (y[0] * y[0] + y[1] * y[1] - 1.0).abs();
        println!("oscillator, 10 periods at h=0.01: |dx|={ex:e} |dv|={ev:e} |dE|={energy:e}");
        assert!(ex < 1e-9 && ev < 1e-9 && energy < 1e-9);
        assert_eq!(dp.evaluations(), 7 + 6 * n as u64);
    }

    #[test]
    fn harmonic_oscillator_f32() {
        let mut sys = Osc { w2: 1.0f32 };
        let mut dp = Dp5::<f32, 2>::new();
        let (mut t, mut y) = (0.0f32, Vector2::new(1.0f32, 0.0));
        let t_end = 20.0 * core::f64::consts::PI;
        let n = (t_end / 0.01) as u32;
        for _ in 0..n {
            dp.step(&mut sys, &mut t, &mut y, 0.01).unwrap();
        }
        // The system is autonomous: the state has advanced by exactly n steps of the f32
        // step `0.01f32`; the f32 sum `t` drifts from that by accumulated rounding.
        let elapsed = n as f64 * (0.01f32 as f64);
        let ex = (y[0] as f64 - elapsed.cos()).abs();
        let ev = (y[1] as f64 + elapsed.sin()).abs();
        let drift = (t as f64 - elapsed).abs();
        println!(
            "f32 oscillator, 10 periods at h=0.01: |dx|={ex:e} |dv|={ev:e}, t drift {drift:e} s"
        );
        assert!(ex < 1e-4 && ev < 1e-4);
    }

    #[test]
    fn error_estimate_scales_like_h5() {
        let mut est = [0.0; 3];
        for (e, h) in est.iter_mut().zip([0.1, 0.05, 0.025]) {
            let mut sys = Lin {
                lambda: 1.0,
                evals: 0,
            };
            let mut dp = Dp5::<f64, 1>::new();
            let (mut t, mut y) = (0.0, Vector1::new(1.0));
            *e = dp.step(&mut sys, &mut t, &mut y, h).unwrap().error;
        }
        let (r1, r2) = (est[0] / est[1], est[1] / est[2]);
        println!("error estimates {est:?}, ratios {r1} {r2}");
        assert!((20.0..45.0).contains(&r1) && (20.0..45.0).contains(&r2));
        // The estimate measures the 4th-order solution's local error: compare with the
        // true error of y1* = y1 - estimate (same sign conventions up to |.|).
        assert!(est[0] > 0.0);
    }

    #[test]
    fn fsal_six_evaluations_per_step() {
        let mut sys = Lin {
            lambda: -2.0,
            evals: 0,
        };
        let mut dp = Dp5::<f64, 1>::new();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals, 7);
        for i in 0..5 {
            dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
            assert_eq!(sys.evals, 7 + 6 * (i + 1));
        }
        assert_eq!(dp.evaluations(), sys.evals as u64);
        dp.invalidate();
        let before = sys.evals;
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 7, "after invalidate()");
        // Another y (bitwise) or another t: k1 re-evaluated, no invalidate() needed.
        let before = sys.evals;
        y[0] = f64::from_bits(y[0].to_bits() + 1);
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 7, "after changing y");
        let before = sys.evals;
        t += 0.5;
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 7, "after changing t");
        let before = sys.evals;
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 6);
    }

    #[test]
    fn fsal_reuse_gives_the_same_bits_as_re_evaluation() {
        let mut sys = Osc { w2: 4.0 };
        let (mut ta, mut ya) = (0.0, Vector2::new(1.0, 0.5));
        let (mut tb, mut yb) = (ta, ya);
        let mut a = Dp5::<f64, 2>::new();
        let mut b = Dp5::<f64, 2>::new();
        for _ in 0..50 {
            a.step(&mut sys, &mut ta, &mut ya, 0.01).unwrap();
            b.invalidate();
            b.step(&mut sys, &mut tb, &mut yb, 0.01).unwrap();
            assert_eq!(ta.to_bits(), tb.to_bits());
            assert_eq!(ya[0].to_bits(), yb[0].to_bits());
            assert_eq!(ya[1].to_bits(), yb[1].to_bits());
        }
        assert_eq!(a.evaluations(), 7 + 6 * 49);
        assert_eq!(b.evaluations(), 7 * 50);
    }

    #[test]
    fn seeded_step_takes_six_evaluations_and_the_same_bits() {
        let mut sys = Lin {
            lambda: -2.0,
            evals: 0,
        };
        let (t0, y0) = (0.25, Vector1::new(0.75));
        // Reference: a fresh stepper evaluates k1 itself.
        let mut fresh = Dp5::<f64, 1>::new();
        let (mut tf, mut yf) = (t0, y0);
        fresh.step(&mut sys, &mut tf, &mut yf, 0.1).unwrap();
        assert_eq!(sys.evals, 7);
        // Seeded with f(t0, y0): one evaluation fewer, the same bits.
        let mut dp = Dp5::<f64, 1>::new();
        dp.seed(t0, &y0, &Vector1::new(-2.0 * y0[0]));
        let (mut t, mut y) = (t0, y0);
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals, 7 + 6);
        assert_eq!(
            (t.to_bits(), y[0].to_bits()),
            (tf.to_bits(), yf[0].to_bits())
        );
        // The seed is used once, and only at its own (t, y): a seed at another y, or
        // one forgotten by invalidate(), is evaluated again.
        let before = sys.evals;
        dp.invalidate();
        dp.seed(t, &Vector1::new(y[0] + 1.0), &Vector1::new(123.0));
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 7, "seed at another y");
        let before = sys.evals;
        dp.seed(t, &y, &Vector1::new(-2.0 * y[0]));
        dp.invalidate();
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals - before, 7, "seed forgotten by invalidate()");
    }

    #[test]
    fn dense_endpoints_are_exact() {
        let mut sys = Osc { w2: 3.0 };
        let mut dp = Dp5::<f64, 2>::new();
        let mut out = Vector2::zeros();
        dp.dense(0.5, &mut out);
        assert_eq!(out, Vector2::zeros());
        assert_eq!(dp.last_step(), None);
        let (mut t, mut y) = (0.3, Vector2::new(0.7, -0.2));
        let y0 = y;
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(dp.last_step(), Some((0.3, 0.1)));
        for (th, want) in [(0.0, y0), (1.0, y), (-0.5, y0), (1.5, y), (f64::NAN, y0)] {
            dp.dense(th, &mut out);
            assert_eq!(out[0].to_bits(), want[0].to_bits(), "θ={th}");
            assert_eq!(out[1].to_bits(), want[1].to_bits(), "θ={th}");
        }
        // The polynomial itself joins the end points (the shortcuts are continuous).
        dp.dense(1.0 - 1e-12, &mut out);
        assert!((out - y).amax() < 1e-12);
        dp.dense(1e-12, &mut out);
        assert!((out - y0).amax() < 1e-12);
        // Slopes at the ends are f(t0, y0) and f(t1, y1).
        let mut f = Vector2::zeros();
        dp.dense_derivative(0.0, &mut out);
        sys.eval(0.3, &y0, &mut f).unwrap();
        assert_eq!(out, f);
        dp.dense_derivative(1.0, &mut out);
        sys.eval(t, &y, &mut f).unwrap();
        assert_eq!(out, f);
        dp.dense_derivative(1.0 - 1e-9, &mut out);
        assert!((out - f).amax() < 1e-8);
    }

    /// Max over θ of the interpolation error of one step of `y' = y` from `y(0) = 1`,
    /// and the error at θ = 0.5.
    fn dense_errors(h: f64) -> (f64, f64) {
        let mut sys = Lin {
            lambda: 1.0,
            evals: 0,
        };
        let mut dp = Dp5::<f64, 1>::new();
        let (mut t, mut y) = (0.0, Vector1::new(1.0));
        dp.step(&mut sys, &mut t, &mut y, h).unwrap();
        let mut out = Vector1::zeros();
        dp.dense(0.5, &mut out);
        let mid = (out[0] - (0.5 * h).exp()).abs();
        let mut worst = 0.0f64;
        for i in 0..=100 {
            let th = i as f64 / 100.0;
            dp.dense(th, &mut out);
            worst = worst.max((out[0] - (th * h).exp()).abs());
        }
        (mid, worst)
    }

    #[test]
    fn dense_midpoint_is_fourth_order() {
        let (m1, w1) = dense_errors(0.1);
        let (m2, w2) = dense_errors(0.05);
        let (m3, _) = dense_errors(0.025);
        println!(
            "dense θ=0.5 errors h=0.1: {m1:e}, h=0.05: {m2:e}, h=0.025: {m3:e}; ratios {} {}; max over θ {w1:e} {w2:e}",
            m1 / m2,
            m2 / m3
        );
        // A 4th-order interpolant has a local error O(h^5): halving h divides it by ~32.
        assert!(m1 < 1e-7, "midpoint error {m1}");
        assert!(m1 / m2 > 16.0 && m2 / m3 > 16.0);
        assert!(w1 < 1e-7 && w1 / w2 > 16.0);
    }

    #[test]
    fn dense_derivative_matches_finite_differences() {
        let mut sys = Osc { w2: 5.0 };
        let mut dp = Dp5::<f64, 2>::new();
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.3));
        let h = 0.05;
        for _ in 0..3 {
            dp.step(&mut sys, &mut t, &mut y, h).unwrap();
        }
        let (mut yp, mut ym, mut d) = (Vector2::zeros(), Vector2::zeros(), Vector2::zeros());
        let dth = 1e-5;
        let mut worst = 0.0f64;
        for i in 1..10 {
            let th = i as f64 / 10.0;
            dp.dense(th + dth, &mut yp);
            dp.dense(th - dth, &mut ym);
            dp.dense_derivative(th, &mut d);
            let fd = (yp - ym) / (2.0 * dth * h);
            worst = worst.max((fd - d).amax());
        }
        println!("dense_derivative vs central differences: max |diff| = {worst:e}");
        // Central differences: truncation ~ (dθ)²·|y'''|·h² and rounding ~ eps/(dθ h).
        assert!(worst < 1e-8, "{worst}");
    }

    #[test]
    fn failed_step_leaves_everything_untouched() {
        // A first step fails on the 3rd evaluation of the system.
        let mut sys = Flaky {
            evals: 0,
            fail_on: 3,
            armed: true,
        };
        let mut dp = Dp5::<f64, 2>::new();
        let (mut t, mut y) = (0.0, Vector2::new(1.0, 0.0));
        assert_eq!(dp.step(&mut sys, &mut t, &mut y, 0.1), Err(Boom));
        assert_eq!((t, y), (0.0, Vector2::new(1.0, 0.0)));
        assert_eq!(dp.last_step(), None);
        assert_eq!(dp.evaluations(), 3);

        // Healthy again: the same step as a fresh integrator would take.
        sys.armed = false;
        let mut fresh = Dp5::<f64, 2>::new();
        let (mut tf, mut yf) = (t, y);
        fresh.step(&mut sys, &mut tf, &mut yf, 0.1).unwrap();
        dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(
            (t.to_bits(), y[0].to_bits(), y[1].to_bits()),
            (tf.to_bits(), yf[0].to_bits(), yf[1].to_bits())
        );

        // Now a step with a valid FSAL stage fails on the 3rd evaluation of that step.
        let (t_before, y_before) = (t, y);
        let mut dense_before = Vector2::zeros();
        dp.dense(0.4, &mut dense_before);
        sys.evals = 0;
        sys.fail_on = 3;
        sys.armed = true;
        assert_eq!(dp.step(&mut sys, &mut t, &mut y, 0.1), Err(Boom));
        assert_eq!(t.to_bits(), t_before.to_bits());
        assert_eq!(
            (y[0].to_bits(), y[1].to_bits()),
            (y_before[0].to_bits(), y_before[1].to_bits())
        );
        assert_eq!(dp.last_step(), Some((0.0, 0.1)));
        let mut dense_after = Vector2::zeros();
        dp.dense(0.4, &mut dense_after);
        assert_eq!(dense_before, dense_after);

        // Healthy again: FSAL still valid (6 evaluations) and bitwise the fresh result.
        sys.armed = false;
        sys.evals = 0;
        let mut fresh = Dp5::<f64, 2>::new();
        let (mut tf, mut yf) = (t, y);
        let rf = fresh.step(&mut sys, &mut tf, &mut yf, 0.1).unwrap();
        sys.evals = 0;
        let r = dp.step(&mut sys, &mut t, &mut y, 0.1).unwrap();
        assert_eq!(sys.evals, 6);
        assert_eq!(
            (t.to_bits(), y[0].to_bits(), y[1].to_bits()),
            (tf.to_bits(), yf[0].to_bits(), yf[1].to_bits())
        );
        assert_eq!(r, rf);
        assert!(y[0].is_finite() && y[1].is_finite());
    }

    #[test]
    fn zero_step_is_a_no_op() {
        let mut sys = Osc { w2: 1.0 };
        let mut dp = Dp5::<f64, 2>::new();
        let (mut t, mut y) = (1.0, Vector2::new(0.5, 0.25));
        let r = dp.step(&mut sys, &mut t, &mut y, 0.0).unwrap();
        assert_eq!((t, y, r.error), (1.0, Vector2::new(0.5, 0.25), 0.0));
    }

    #[test]
    fn max_norm_propagates_non_finite() {
        assert_eq!(max_norm(&Vector2::new(-3.0, 2.0)), 3.0);
        assert!(max_norm(&Vector2::new(1.0, f64::NAN)).is_nan());
        assert_eq!(
            max_norm(&Vector2::new(f64::NEG_INFINITY, 1.0)),
            f64::INFINITY
        );
    }
}
