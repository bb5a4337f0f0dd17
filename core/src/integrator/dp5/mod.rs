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
use crate::scalar::{same_bits, Real};
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

/// Counts and performs one evaluation of `sys`, an inner stage (`inner`: every stage
/// but the last, `f(t1, y1)`, whose state is the step's end) or not.
fn eval<T: Real, const N: usize, S: OdeSystem<T, N>>(
    sys: &mut S,
    count: &mut u64,
    inner: bool,
    t: T,
    y: &SVector<T, N>,
    dy: &mut SVector<T, N>,
) -> Result<(), S::Error> {
    *count = count.saturating_add(1);
    sys.inner_stage(inner);
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

    /// Seeds the next step with the last step's first stage and returns that step's
    /// start `(t0, y0)`, `None` before the first step. A step from there (of any
    /// length) then takes 6 evaluations: a step redone shorter, to land exactly on a
    /// time inside the last one (the dense output is an order less accurate than a
    /// step's end).
    pub fn seed_last_start(&mut self) -> Option<(T, SVector<T, N>)> {
        if !self.has_last {
            return None;
        }
        let last = self.last();
        let (t0, y0, k1) = (last.t0, last.y0, last.k[0]);
        self.seed(t0, &y0, &k1);
        Some((t0, y0))
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
            eval(sys, ev, true, t, y, k1)?;
        }
        let yt = stage_input(y, h, [&*k1], &a[1]);
        eval(sys, ev, true, t + T::c(c[1]) * h, &yt, k2)?;
        let yt = stage_input(y, h, [&*k1, &*k2], &a[2]);
        eval(sys, ev, true, t + T::c(c[2]) * h, &yt, k3)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3], &a[3]);
        eval(sys, ev, true, t + T::c(c[3]) * h, &yt, k4)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4], &a[4]);
        eval(sys, ev, true, t + T::c(c[4]) * h, &yt, k5)?;
        let yt = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4, &*k5], &a[5]);
        eval(sys, ev, true, t1, &yt, k6)?;
        tr.y1 = stage_input(y, h, [&*k1, &*k2, &*k3, &*k4, &*k5, &*k6], &Tableau::B5);
        eval(sys, ev, false, t1, &tr.y1, k7)?;
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
mod tests;
