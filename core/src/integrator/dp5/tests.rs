//! DP5 against analytic solutions, its order, its dense output and its FSAL reuse.

extern crate std;
use super::*;
use core::convert::Infallible;
use nalgebra::{Vector1, Vector2};
use std::println;

/// The value of a step or an evaluation of a system that cannot fail: its error type
/// has no value, so no panic is needed to take it.
trait NeverFails<R> {
    fn never_fails(self) -> R;
}

impl<R> NeverFails<R> for Result<R, Infallible> {
    fn never_fails(self) -> R {
        match self {
            Ok(v) => v,
            Err(never) => match never {},
        }
    }
}

/// `y' = λ y`, counting evaluations.
struct Lin {
    lambda: f64,
    evals: u32,
}

impl OdeSystem<f64, 1> for Lin {
    type Error = Infallible;
    fn eval(&mut self, _t: f64, y: &Vector1<f64>, dy: &mut Vector1<f64>) -> Result<(), Infallible> {
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
        dp.step(&mut sys, &mut t, &mut y, h).never_fails();
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
            dp.step(&mut sys, &mut t, &mut y, h).never_fails();
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
        dp.step(&mut sys, &mut t, &mut y, 0.01).never_fails();
    }
    let h_last = t_end - t;
    dp.step(&mut sys, &mut t, &mut y, h_last).never_fails();
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
        dp.step(&mut sys, &mut t, &mut y, 0.01).never_fails();
    }
    // The system is autonomous: the state has advanced by exactly n steps of the f32
    // step `0.01f32`; the f32 sum `t` drifts from that by accumulated rounding.
    let elapsed = n as f64 * (0.01f32 as f64);
    let ex = (y[0] as f64 - elapsed.cos()).abs();
    let ev = (y[1] as f64 + elapsed.sin()).abs();
    let drift = (t as f64 - elapsed).abs();
    println!("f32 oscillator, 10 periods at h=0.01: |dx|={ex:e} |dv|={ev:e}, t drift {drift:e} s");
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
        *e = dp.step(&mut sys, &mut t, &mut y, h).never_fails().error;
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
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals, 7);
    for i in 0..5 {
        dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
        assert_eq!(sys.evals, 7 + 6 * (i + 1));
    }
    assert_eq!(dp.evaluations(), sys.evals as u64);
    dp.invalidate();
    let before = sys.evals;
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals - before, 7, "after invalidate()");
    // Another y (bitwise) or another t: k1 re-evaluated, no invalidate() needed.
    let before = sys.evals;
    y[0] = f64::from_bits(y[0].to_bits() + 1);
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals - before, 7, "after changing y");
    let before = sys.evals;
    t += 0.5;
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals - before, 7, "after changing t");
    let before = sys.evals;
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
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
        a.step(&mut sys, &mut ta, &mut ya, 0.01).never_fails();
        b.invalidate();
        b.step(&mut sys, &mut tb, &mut yb, 0.01).never_fails();
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
    fresh.step(&mut sys, &mut tf, &mut yf, 0.1).never_fails();
    assert_eq!(sys.evals, 7);
    // Seeded with f(t0, y0): one evaluation fewer, the same bits.
    let mut dp = Dp5::<f64, 1>::new();
    dp.seed(t0, &y0, &Vector1::new(-2.0 * y0[0]));
    let (mut t, mut y) = (t0, y0);
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
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
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals - before, 7, "seed at another y");
    let before = sys.evals;
    dp.seed(t, &y, &Vector1::new(-2.0 * y[0]));
    dp.invalidate();
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
    assert_eq!(sys.evals - before, 7, "seed forgotten by invalidate()");
}

/// A step redone shorter from the last step's start ([`Dp5::seed_last_start`]): the
/// same bits as a fresh stepper's step of that length from there, in 6 evaluations
/// (the first stage kept), and closer to `exp(λ t)` at its end than the dense output
/// of the longer step there (5th order against the interpolant's 4th).
#[test]
fn a_step_redone_shorter_from_the_last_start_is_a_fresh_step_in_six_evaluations() {
    let lambda = -2.0;
    let mut sys = Lin { lambda, evals: 0 };
    let (t0, y0, h, theta) = (0.25, Vector1::new(0.75), 0.2, 0.6);
    let mut dp = Dp5::<f64, 1>::new();
    assert_eq!(dp.seed_last_start(), None, "no step yet");
    let (mut t, mut y) = (t0, y0);
    dp.step(&mut sys, &mut t, &mut y, h).never_fails();
    let mut dense = Vector1::zeros();
    dp.dense(theta, &mut dense);
    let before = sys.evals;
    let seeded = dp.seed_last_start();
    assert_eq!(
        seeded.map(|(ts, ys)| (ts.to_bits(), ys[0].to_bits())),
        Some((t0.to_bits(), y0[0].to_bits())),
        "a step was taken"
    );
    let (ts, ys) = seeded.unwrap_or((t0, y0));
    let (mut t, mut y) = (ts, ys);
    dp.step(&mut sys, &mut t, &mut y, theta * h).never_fails();
    assert_eq!(sys.evals - before, 6);
    let mut fresh = Dp5::<f64, 1>::new();
    let (mut tf, mut yf) = (t0, y0);
    fresh
        .step(&mut sys, &mut tf, &mut yf, theta * h)
        .never_fails();
    assert_eq!(
        (t.to_bits(), y[0].to_bits()),
        (tf.to_bits(), yf[0].to_bits())
    );
    let exact = y0[0] * (lambda * theta * h).exp();
    let (e_step, e_dense) = ((y[0] - exact).abs(), (dense[0] - exact).abs());
    println!("at θ = {theta}: step's error {e_step:e}, dense output's {e_dense:e}");
    assert!(e_step < e_dense / 10.0, "{e_step:e} vs {e_dense:e}");
    // The redone step is now the last one: its end is the next step's FSAL stage.
    let before = sys.evals;
    dp.step(&mut sys, &mut t, &mut y, h).never_fails();
    assert_eq!(sys.evals - before, 6);
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
    dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
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
    sys.eval(0.3, &y0, &mut f).never_fails();
    assert_eq!(out, f);
    dp.dense_derivative(1.0, &mut out);
    sys.eval(t, &y, &mut f).never_fails();
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
    dp.step(&mut sys, &mut t, &mut y, h).never_fails();
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
        dp.step(&mut sys, &mut t, &mut y, h).never_fails();
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
    assert!(fresh.step(&mut sys, &mut tf, &mut yf, 0.1).is_ok());
    assert!(dp.step(&mut sys, &mut t, &mut y, 0.1).is_ok());
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
    let rf = fresh.step(&mut sys, &mut tf, &mut yf, 0.1);
    sys.evals = 0;
    let r = dp.step(&mut sys, &mut t, &mut y, 0.1);
    assert!(r.is_ok());
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
    let r = dp.step(&mut sys, &mut t, &mut y, 0.0).never_fails();
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

/// `y' = λ y`, recording each evaluation's `(t, y, inner)`, `inner` as
/// [`OdeSystem::inner_stage`] last said.
struct Staged {
    inner: bool,
    seen: std::vec::Vec<(f64, f64, bool)>,
}

impl OdeSystem<f64, 1> for Staged {
    type Error = Infallible;
    fn eval(&mut self, t: f64, y: &Vector1<f64>, dy: &mut Vector1<f64>) -> Result<(), Infallible> {
        self.seen.push((t, y[0], self.inner));
        dy[0] = -2.0 * y[0];
        Ok(())
    }
    fn inner_stage(&mut self, inner: bool) {
        self.inner = inner;
    }
}

/// Every evaluation of a step is an inner stage but the last, `f(t1, y1)`: the one at
/// the state the step ends at (the step's returned `t` and `y`, to the bit), whose
/// evaluation a caller reads after the step (FSAL). The stage before it, at `t1` too,
/// is at another state and is inner. With the first stage reused (FSAL) or evaluated,
/// alike.
#[test]
fn only_the_last_stage_is_the_steps_end() {
    let mut sys = Staged {
        inner: false,
        seen: std::vec::Vec::new(),
    };
    let mut dp = Dp5::<f64, 1>::new();
    let (mut t, mut y) = (0.0, Vector1::new(1.0));
    for evals in [7, 6, 6] {
        sys.seen.clear();
        dp.step(&mut sys, &mut t, &mut y, 0.1).never_fails();
        assert_eq!(sys.seen.len(), evals);
        let (last, inner) = sys
            .seen
            .split_last()
            .map_or((None, &[][..]), |(l, i)| (Some(l), i));
        assert_eq!(last, Some(&(t, y[0], false)));
        assert!(inner.iter().all(|s| s.2), "{inner:?}");
        let (t6, y6, _) = inner[inner.len() - 1];
        assert_eq!(t6, t);
        assert_ne!(y6, y[0]);
    }
}
