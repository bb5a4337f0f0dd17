//! Event location inside a DP5 step: Illinois regula falsi on the dense output, started
//! from the root of an interpolant of the event function.

use super::error::TwinStepError;
use super::evaluate::{Stage, Torques};
use super::guards::{EventKind, Fired, Guard, Guards, CATCH_ULPS};
use super::inputs::Inputs;
use super::settings::*;
use super::slot::STATE;
use super::{Twin, Work};
use crate::scalar::Real;
use nalgebra::SVector;

/// An event is located to this fraction of the step (1e-12 s at h = 1e-4 s; f32: 8 ulps,
/// or the event function's rounding floor, see `Twin::locate`).
pub(super) const THETA_TOL: f64 = 1e-8;

/// Ulps of the torque scale (T_r + 1 N·m plus the clutch torques at the step's start)
/// under which a transmitted torque is rounding: inside that band a torque function's
/// sign is noise. S2 in f32 at h = 1 ms: c8 of A68 driven by its lever (a six-link
/// group by Newton) scatters by ±0.04 N·m (~420 ulps of 800 N·m) around its release at
/// 0.2629 s, and the iteration spent its 16 full evaluations (kinetostatics included)
/// on that noise, 120k x86 instructions. f64: 1.8e-10 N·m, far under anything S2's
/// torque functions resolve.
pub(super) const TORQUE_NOISE_ULPS: f64 = 1024.0;

/// Largest fraction of the step the rounding floor may widen the tolerance to (a
/// function that barely crosses over the step).
pub(super) const NOISE_THETA_MAX: f64 = 1e-3;

/// The fraction of the step `θ` below which the fired event functions' rounding hides
/// their crossing: their rounding floor (`noise`, in their units) over their rise across
/// the step (`chord`, per unit of θ), at most [`NOISE_THETA_MAX`]; 0 if they do not
/// rise.
pub(super) fn noise_theta<T: Real>(noise: T, chord: T) -> T {
    let th = noise / chord;
    if chord > T::zero() && th.finite() {
        th.min(T::c(NOISE_THETA_MAX))
    } else {
        T::zero()
    }
}

/// The root in (0, 1) of the cubic Hermite interpolant of an event function over a
/// step, `p(0) = g0 ≤ 0 < p(1) = g1` with slopes `s0`, `s1` (per unit of the step's
/// fraction θ: h·dg/dt), to `tol`/100 ([`bracketed_root`]); with `before`, the value
/// `gm` at the start of the step before (θ = -r, `r` its length over this one's), of
/// the quartic that also passes there. No evaluation of the mechanism: the first
/// point of [`Twin::locate`]'s iteration, O(h⁴) from the true crossing (the quartic
/// O(h⁵)). In S2 the cubic's roots were off the crossings by up to 15 of
/// [`Twin::locate`]'s tolerances (1e-8 of the step), the quartic's by at most 0.41
/// (most by under 0.05). `None` if the values do not bracket a root.
pub(super) fn hermite_root<T: Real>(
    g0: T,
    g1: T,
    s0: T,
    s1: T,
    before: Option<(T, T)>,
    tol: T,
) -> Option<(T, T)> {
    if !(s0.finite() && s1.finite()) {
        return None;
    }
    let one = T::one();
    let (two, three, six) = (T::c(2.0), T::c(3.0), T::c(6.0));
    // p(θ) = h00 g0 + h10 s0 + h01 g1 + h11 s1 and p'(θ).
    let cubic = |th: T| {
        let u = one - th;
        let value = (one + two * th) * u * u * g0
            + th * u * u * s0
            + th * th * (three - two * th) * g1
            + th * th * (th - one) * s1;
        let slope = six * th * (th - one) * (g0 - g1)
            + (three * th * th - T::c(4.0) * th + one) * s0
            + (three * th * th - two * th) * s1;
        (value, slope)
    };
    // The quartic through the value at the start of the step before too (θ = -r):
    // p + c θ²(θ-1)², which keeps the ends' values and slopes.
    let c = before
        .map(|(gm, r)| {
            let w = r * r * (r + one) * (r + one);
            (gm - cubic(-r).0) / w
        })
        .filter(|c| c.finite())
        .unwrap_or(T::zero());
    bracketed_root(
        |th: T| {
            let (v, d) = cubic(th);
            let u = th - one;
            (
                v + c * th * th * u * u,
                d + c * two * th * u * (two * th - one),
            )
        },
        g0,
        g1,
        tol,
    )
}

/// The root in (0, 1) of the quadratic through an event function's values `g0 ≤ 0`
/// and `g1 > 0` at the step's ends and `g3` at `θ3`, to `tol`/100. For the torque
/// functions, whose rates the evaluation does not give: `θ3 = -r` is the start of the
/// step before (`r` its length over this one's; O(h³) from the true crossing), or,
/// with no step before (the step after an event), `θ3` inside the step is the
/// location's first point. S2's release of lever 6 at 0.2713 s, 0.7 ms after a shaft
/// stop, came within 1.5 % of the step from the regula falsi's first point (the
/// function curves: -37, 4.4 and 28 N·m at 0, 0.57 and 1), within 0.15 % from this
/// quadratic's root. `None` if the values do not bracket a root.
pub(super) fn quadratic_root<T: Real>(t3: T, g3: T, g0: T, g1: T, tol: T) -> Option<(T, T)> {
    // p(θ) = g0 + a θ + b θ², p(1) = g1, p(θ3) = g3.
    let b = (g3 - g0 - (g1 - g0) * t3) / (t3 * (t3 - T::one()));
    let a = g1 - g0 - b;
    if !(a.finite() && b.finite()) {
        return None;
    }
    bracketed_root(
        |th: T| (g0 + th * (a + th * b), a + T::c(2.0) * th * b),
        g0,
        g1,
        tol,
    )
}

/// The root in (0, 1) of an interpolant `p` (value, slope) of an event function with
/// `p(0) = g0 ≤ 0 < p(1) = g1`, to `tol`/100: safeguarded Newton from the linear
/// root (bisection whenever Newton leaves the bracket; at most 40 iterations, usually
/// 3), until a Newton step or the bracket is under `tol`/100. `None` if the values do not bracket a root.
pub(super) fn bracketed_root<T: Real>(
    p: impl Fn(T) -> (T, T),
    g0: T,
    g1: T,
    tol: T,
) -> Option<(T, T)> {
    if !(g0 <= T::zero() && g1 > T::zero()) {
        return None;
    }
    let (mut a, mut b) = (T::zero(), T::one());
    let mut th = g0 / (g0 - g1);
    for _ in 0..40 {
        let (v, dv) = p(th);
        if v > T::zero() {
            b = th;
        } else {
            a = th;
        }
        let newton = th - v / dv;
        // Converged: a last Newton step this small may round onto an end of the
        // bracket, and bisecting from there took 20 more iterations.
        if newton.finite() && (newton - th).abs() <= tol * T::c(0.01) {
            th = newton.max(a).min(b);
            break;
        }
        let next = if newton.finite() && newton > a && newton < b {
            newton
        } else {
            (a + b) * T::c(0.5)
        };
        let moved = (next - th).abs();
        th = next;
        if moved <= tol * T::c(0.01) || b - a <= tol * T::c(0.01) {
            break;
        }
    }
    let (_, slope) = p(th);
    (th.finite() && slope.finite()).then_some((th, slope))
}

impl<T: Real> Twin<T> {
    /// Locates the first crossing among the fired event functions inside the last
    /// DP5 step (`t0`, `h`) by Illinois regula falsi on the dense output; returns the
    /// fraction of the step just past the event, which event it is, and whether `w`
    /// and the slot hold that point, evaluated (the last evaluation was there).
    ///
    /// `(g0, r0)`: the event functions and the speed functions' rates at the step's
    /// start. A single speed function fired starts the iteration from the root of its
    /// Hermite interpolant over the step ([`hermite_root`]: the values and rates at
    /// both ends, and the value at the start of the step before if that step had no
    /// event; no evaluation), 4th- or 5th-order accurate. A single torque function
    /// (a release, a breakaway; each evaluation is a full one, kinetostatics included)
    /// starts from the root of its quadratic through the step's ends and the start of
    /// the step before ([`quadratic_root`]), if that step had no event.
    ///
    /// The iteration ends when the bracket is within the tolerance, or sooner when a
    /// point past the crossing is within the tolerance of the secant's crossing through
    /// it and the point before, both `near` the crossing (the secant's error is then
    /// second order in their distances, ~1e-10 of the tolerance), or, for the first
    /// point, of a Newton step back on the Hermite interpolant's slope. Near the
    /// crossing it aims just past it: the first point half the tolerance past the
    /// Hermite root, the next 0.4 tol past the crossing that Newton step or the
    /// secant places. S2's 18 speed events take 1 evaluation, its torque events 2–3,
    /// instead of 2–5: a bracket closed on both sides needs a point on each, and the
    /// cubic's guess was rarely within the tolerance.
    ///
    /// Not inlined, nor is [`Twin::try_candidate`]: with both inlined the f64 step's
    /// stack high-water was 20.6 KB instead of 16.7 KB (`tests/footprint.rs`).
    #[inline(never)]
    pub(super) fn locate(
        &mut self,
        w: &mut Work<T>,
        t0: T,
        h: T,
        (g0, r0): (&Guards<T>, &Guards<T>),
        fired: Fired,
        inputs: &Inputs<T>,
    ) -> Result<(T, EventKind, bool), TwinStepError> {
        // The caller evaluates the state at the event in full after this.
        let speeds_only = fired.speeds_only();
        let norm = Normalized::new(g0, &self.guards, fired);
        let (glo, _) = norm.largest(g0);
        let (ghi, which) = norm.largest(&self.guards);
        // THETA_TOL, or 8 ulps of the step's fraction if that is larger (f32: 9.5e-7),
        // so that the margin below moves the point by a few ulps at least; or the
        // fraction under which the fired functions are rounding (`noise_theta`):
        // closer than that, their signs are noise and only the evaluation cap ends the
        // iteration. f64 at S2's events: under 1e-11, so THETA_TOL decides.
        let noise = norm.fold(T::zero(), |n, k, chord| {
            n.max(noise_theta(self.guard_noise(k, inputs), chord))
        });
        let tol = T::c(THETA_TOL).max(T::EPS * T::c(8.0)).max(noise);
        // Two points this close to each other bracket... or not, but their secant
        // places the crossing to about near²·|g''/g'| (θ units), 1e-10 in f64 for a
        // curvature |g''/g'| of 1 per step: far below `tol`.
        let near = (tol * T::c(0.01)).sqrt();
        let mut b = Bracket {
            lo: T::zero(),
            hi: T::one(),
            glo,
            ghi,
            side: 0,
            which,
        };
        let guess = self.first_guess((g0, r0), fired, h, tol);
        // A lone torque function with no guess (no step before this one to take a
        // quadratic through: the step after an event): after the first point, the
        // quadratic through it and the step's ends.
        let mut three_point = guess.is_none() && !speeds_only && fired.single().is_some();
        let mut at_hi = false;
        let mut used = 0;
        // The last evaluated point (θ, its event function, not Illinois-scaled), and
        // the interpolant's slope at the guess, for the estimates below.
        let mut last: Option<(T, T)> = None;
        let mut slope = guess.map(|(_, s)| s);
        // The Hermite interpolant's slope where it is trusted to place the crossing
        // from one point past it: positive and within a factor 2 of the slope of the
        // chord over the step (a crossing far from linear is left to the secant).
        let chord = ghi - glo;
        let trusted =
            slope.filter(|s| speeds_only && *s >= chord * T::c(0.5) && *s <= chord * T::c(2.0));
        // The first point aims half the tolerance past the Hermite root, which is off
        // the crossing by under half the tolerance when the step before gives the
        // quartic (all of S2's 18 speed events): it lands past the crossing within the
        // tolerance and is located by the one evaluation (see `trusted` below).
        let mut guess = guess.map(|(th, _)| {
            if trusted.is_some() {
                th + tol * T::c(0.5)
            } else {
                th
            }
        });
        for _ in 0..MAX_LOCATE_ITER {
            if b.hi - b.lo <= tol {
                break;
            }
            used += 1;
            // Near the crossing, a sharper estimate aims just past it (see `near`):
            // from the first evaluated point, a Newton step on the interpolant's slope;
            // from two, their secant.
            let margin = tol * T::c(0.4);
            let aimed = match (guess.take(), last) {
                (Some(th), _) => Some(th),
                (None, Some((tp, gp))) => slope.take().map(|s| tp - gp / s + margin),
                (None, None) => None,
            };
            let th = b.point(aimed, margin);
            self.eval_point(w, t0 + th * h, th, speeds_only, inputs)?;
            let (g, k) = norm.largest(&self.guards);
            at_hi = g > T::zero();
            let crossing = crossing_estimate((th, g), last, trusted, near);
            last = Some((th, g));
            if b.update(th, g, k, crossing, tol) {
                break;
            }
            // Next: aim just past the secant's crossing, or the quadratic's.
            if let Some(r) = crossing {
                guess = Some(r + margin);
            } else if core::mem::take(&mut three_point) {
                guess = quadratic_root(th, g, glo, ghi, tol).map(|(r, _)| r + margin);
            }
        }
        crate::trace::debug!(
            "event functions {:#08b}: located to {:?} of the step in {used} evaluations",
            fired.bits(),
            b.hi - b.lo
        );
        Ok((b.hi, b.which.event(), at_hi))
    }

    /// The rounding floor of event function `k`, in its units: a speed's
    /// [`CATCH_ULPS`] ulps of the largest link speed (the catches' own offset), a
    /// torque's [`TORQUE_NOISE_ULPS`] ulps of the torque scale (T_r + 1 N·m and the
    /// clutch torques of the last full evaluation), or the speed's if that is larger
    /// (the evaluation that gives a torque moves the speeds too).
    fn guard_noise(&self, k: Guard, inputs: &Inputs<T>) -> T {
        let speed = T::EPS * T::c(CATCH_ULPS) * speed_scale(&self.links);
        if k.is_speed() {
            return speed;
        }
        let scale = inputs.load.abs() + T::one() + self.c[0].abs() + self.c[1].abs();
        speed.max(T::EPS * T::c(TORQUE_NOISE_ULPS) * scale)
    }

    /// Where the iteration starts: a single fired function's interpolant's root over
    /// the step and its slope there (see [`Twin::locate`]), if there is one.
    fn first_guess(
        &self,
        (g0, r0): (&Guards<T>, &Guards<T>),
        fired: Fired,
        h: T,
        tol: T,
    ) -> Option<(T, T)> {
        let speeds_only = fired.speeds_only();
        let before = self
            .last_guards
            .zip(fired.first())
            .and_then(|((g, hp), k)| g.get(k).map(|v| (v, hp / h)));
        fired.single().and_then(|k| {
            match (
                g0.get(k),
                self.guards.get(k),
                r0.get(k),
                self.guard_rates.get(k),
            ) {
                (Some(a), Some(b), Some(ra), Some(rb)) if speeds_only => {
                    hermite_root(a, b, ra * h, rb * h, before, tol)
                }
                (Some(a), Some(b), _, _) if !speeds_only => {
                    before.and_then(|(gm, r)| quadratic_root(-r, gm, a, b, tol))
                }
                _ => None,
            }
        })
    }

    /// The event functions at the point `th` of the DP5 step (time `t`) on its dense
    /// output, moved into `w`: speed functions from the speeds alone (`speeds_only`;
    /// the clutch torques are those of the last full evaluation, the torque functions
    /// are not read, none of them fired), else from a full evaluation. A point of the
    /// bracket, not where the step goes on from: no seed.
    fn eval_point(
        &mut self,
        w: &mut Work<T>,
        t: T,
        th: T,
        speeds_only: bool,
        inputs: &Inputs<T>,
    ) -> Result<(), TwinStepError> {
        let mut y = SVector::<T, STATE>::zeros();
        self.dp5.dense(th, &mut y);
        w.t = t;
        w.y = y;
        if speeds_only {
            self.slots
                .cur_mut()
                .eval_speeds(w.t, &w.y)
                .map_err(|e| self.physical_error(e))?;
            let links = self.slots.cur().links(&self.params);
            self.guards = self.guards_of(self.slots.cur(), &links, &self.c, inputs, t);
        } else {
            self.evaluate_from(Stage::Motion, w, inputs, Torques::Kinetostatics)?;
        }
        Ok(())
    }
}

/// The crossing estimated from the point `(th, g)` (θ, its event function) and the
/// point before, `last`: their secant, if they are `near`: the crossing to ~near² (the
/// curvature term), far below the tolerance. The first point, `near` the Hermite root,
/// takes the interpolant's `trusted` slope instead: a Newton step from it places the
/// crossing to ~(g/s)² |g''/g'| plus (g/s) times the slope's relative error (S2's second
/// points landed on the crossing this step predicts to 1e-13 of the step).
fn crossing_estimate<T: Real>(
    (th, g): (T, T),
    last: Option<(T, T)>,
    trusted: Option<T>,
    near: T,
) -> Option<T> {
    match (last, trusted) {
        (Some((tp, gp)), _) => Some((tp, gp))
            .filter(|(tp, _)| (th - *tp).abs() <= near)
            .map(|(tp, gp)| th - g * (th - tp) / (g - gp)),
        (None, Some(s)) => Some(th - g / s),
        (None, None) => None,
    }
    .filter(|r| r.finite())
}

/// The fired event functions of a step as the iteration sees them: their largest. One
/// function alone is taken as it is. Several are each divided by their rise across
/// the step, so that each is about θ less its crossing's θ and the largest crosses 0
/// at the first crossing. As they are, a speed (rad/s) and a torque (N·m) differ in
/// scale by 1e3 to 1e5 near their crossings: regula falsi on the larger placed its
/// points next to the end where the speed was the larger, and Illinois halved the
/// torque's value at the other end one evaluation at a time. With friction at every
/// joint at h = 1 ms such pairs (a catch and a breakaway, a release and a shaft stop)
/// used up the 16 evaluations and were placed to 8 % of the step; divided, they take
/// 2 to 7.
struct Normalized<T> {
    /// The functions that fired.
    fired: Fired,
    /// Each function's factor (index `Guard as usize`): 1 over its rise, or 1.
    factor: [T; 6],
    /// Its rise across the step, in its units.
    chord: [T; 6],
}

impl<T: Real> Normalized<T> {
    /// The fired functions between their values at the step's start `g0` and its
    /// end `g1`.
    fn new(g0: &Guards<T>, g1: &Guards<T>, fired: Fired) -> Self {
        let mut n = Self {
            fired,
            factor: [T::one(); 6],
            chord: [T::zero(); 6],
        };
        let several = fired.single().is_none();
        for k in Guard::ALL {
            if let (true, Some(a), Some(b)) = (fired.contains(k), g0.get(k), g1.get(k)) {
                let chord = b - a;
                let i = k as usize;
                if let Some(c) = n.chord.get_mut(i) {
                    *c = chord;
                }
                // Fired: a ≤ 0 < b, so the rise is positive unless it overflowed.
                let inv = T::one() / chord;
                if let (true, Some(f)) = (
                    several && chord > T::zero() && inv.finite(),
                    n.factor.get_mut(i),
                ) {
                    *f = inv;
                }
            }
        }
        n
    }

    /// The largest of the fired functions in `g` (the first of equals), scaled, and
    /// which it is.
    fn largest(&self, g: &Guards<T>) -> (T, Guard) {
        let mut best = (T::c(f64::NEG_INFINITY), Guard::Catch6);
        for (k, v) in g.watched() {
            let v = v * self.factor.get(k as usize).copied().unwrap_or(T::one());
            if self.fired.contains(k) && v > best.0 {
                best = (v, k);
            }
        }
        best
    }

    /// `f` folded over the fired functions with their rises across the step.
    fn fold(&self, init: T, mut f: impl FnMut(T, Guard, T) -> T) -> T {
        let mut acc = init;
        for k in Guard::ALL {
            if self.fired.contains(k) {
                acc = f(
                    acc,
                    k,
                    self.chord.get(k as usize).copied().unwrap_or(T::zero()),
                );
            }
        }
        acc
    }
}

/// The bracket of an event's crossing in the step's fraction θ, Illinois-scaled.
struct Bracket<T> {
    /// Its ends, θ.
    lo: T,
    hi: T,
    /// The event function at them (scaled by Illinois' halving).
    glo: T,
    ghi: T,
    /// The side the last point fell on (-1: before the crossing, 1: past it).
    side: i8,
    /// The function past the crossing at `hi`.
    which: Guard,
}

impl<T: Real> Bracket<T> {
    /// The next point: `aimed` if there is one, else regula falsi's, kept at least
    /// `margin` (0.4 of the tolerance) inside the bracket: once the crossing is that
    /// close to an end, the next point lands past it and closes the bracket.
    /// (Bisecting whenever the point fell within 1% of the bracket of an end turned
    /// the iteration into bisection near convergence: every event of S2 took the 16
    /// evaluations and was located to about 1e-5 of the step, not to the tolerance.)
    /// A function exactly 0 at `lo` (f32: the shaft's speed rounds to 0.0 over a
    /// stretch of 5e-6 of the step around its stop) puts regula falsi's point on `lo`
    /// for good: the margin crept up 0.4 tol per evaluation, the bracket never closed
    /// and the event was placed at the step's end, past the lever's reversal (S2 in
    /// f32 chose I0 instead of I8 at 0.3073 s). Bisect then.
    fn point(&self, aimed: Option<T>, margin: T) -> T {
        let (lo, hi, glo, ghi) = (self.lo, self.hi, self.glo, self.ghi);
        match aimed {
            Some(th) if th.finite() => th.max(lo + margin).min(hi - margin),
            _ if glo != T::zero() => {
                let rf = (lo * ghi - hi * glo) / (ghi - glo);
                if rf.finite() {
                    rf.max(lo + margin).min(hi - margin)
                } else {
                    (lo + hi) * T::c(0.5)
                }
            }
            _ => (lo + hi) * T::c(0.5),
        }
    }

    /// Takes the point `th` with its event function `g` (the largest fired, `k`) into
    /// the bracket; returns whether the crossing is located: `th` is past it by at most
    /// `tol` of the estimate `crossing`, though no point on the other side is that
    /// close (`lo` becomes the estimate, for the log).
    fn update(&mut self, th: T, g: T, k: Guard, crossing: Option<T>, tol: T) -> bool {
        if g > T::zero() {
            self.hi = th;
            self.ghi = g;
            self.which = k;
            if self.side == 1 {
                self.glo *= T::c(0.5);
            }
            self.side = 1;
            if let Some(r) = crossing.filter(|r| th - *r <= tol && *r >= self.lo) {
                self.lo = r;
                return true;
            }
        } else {
            self.lo = th;
            self.glo = g;
            if self.side == -1 {
                self.ghi *= T::c(0.5);
            }
            self.side = -1;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::{bracketed_root, hermite_root, noise_theta, NOISE_THETA_MAX, THETA_TOL};

    /// An event function over a step (θ in [0, 1]) and its slope.
    fn quartic(th: f64) -> (f64, f64) {
        // (θ - 0.37)(θ² + 2)(θ + 3): one root in (0, 1), at 0.37.
        let (a, b, c) = (th - 0.37, th * th + 2.0, th + 3.0);
        (a * b * c, b * c + a * 2.0 * th * c + a * b)
    }

    #[test]
    fn the_quartic_through_the_step_before_finds_a_quartic_crossing() {
        let tol = 1e-8;
        let (g0, s0) = quartic(0.0);
        let (g1, s1) = quartic(1.0);
        let r = 0.8;
        let gm = quartic(-r).0;
        let (root, slope) = hermite_root(g0, g1, s0, s1, Some((gm, r)), tol).unwrap();
        // A quartic is its own interpolant: the root to the solver's tol/100.
        assert!((root - 0.37).abs() <= tol * 0.01, "{root}");
        assert!((slope - quartic(0.37).1).abs() <= 1e-9 * slope.abs());
        // The cubic alone is off by its interpolation error, far past the tolerance:
        // the step before's value is what brings the root to it.
        let (cubic, _) = hermite_root(g0, g1, s0, s1, None, tol).unwrap();
        assert!((cubic - 0.37).abs() > 100.0 * tol, "{cubic}");
    }

    #[test]
    fn the_cubic_finds_a_cubic_crossing() {
        let tol = 1e-8;
        // (θ - 0.61)(θ² + 1): Hermite's cubic is exact.
        let g = |th: f64| {
            (
                (th - 0.61) * (th * th + 1.0),
                th * th + 1.0 + (th - 0.61) * 2.0 * th,
            )
        };
        let ((g0, s0), (g1, s1)) = (g(0.0), g(1.0));
        let (root, _) = hermite_root(g0, g1, s0, s1, None, tol).unwrap();
        assert!((root - 0.61).abs() <= tol * 0.01, "{root}");
    }

    #[test]
    fn a_converged_newton_step_ends_the_search_inside_the_bracket() {
        // A root Newton lands on exactly: its next step is 0 and must end the search
        // there, not bisect from an end (the bracket then closes on the root).
        let tol = 1e-8;
        let p = |th: f64| (th - 0.5, 1.0);
        let (root, slope) = bracketed_root(p, -0.5, 0.5, tol).unwrap();
        assert_eq!(root, 0.5);
        assert_eq!(slope, 1.0);
        // No bracket, no root.
        assert!(bracketed_root(p, 0.5, 0.5, tol).is_none());
        assert!(hermite_root(0.1, 0.5, 1.0, 1.0, None, tol).is_none());
    }

    /// The rounding floor in θ is the floor over the rise across the step (a line's
    /// crossing moves by noise / slope), capped, and nothing for a function that does
    /// not rise. In f64 at S2's scales (1024 ulps of 801 N·m over a rise of 30 N·m a
    /// step, h = 1e-4 s) it is far under THETA_TOL, which then decides alone.
    #[test]
    fn the_rounding_floor_in_theta_is_noise_over_the_rise() {
        assert_eq!(noise_theta(0.5, 100.0), 0.005_f64.min(NOISE_THETA_MAX));
        assert!((noise_theta(0.01_f64, 100.0) - 1e-4).abs() <= 1e-19);
        assert_eq!(noise_theta(1.0, 0.5), NOISE_THETA_MAX);
        assert_eq!(noise_theta(1.0, 0.0), 0.0);
        assert_eq!(noise_theta(1.0, -2.0), 0.0);
        assert_eq!(noise_theta(1.0, f64::NAN), 0.0);
        let f64_floor = 1024.0 * f64::EPSILON * 801.0;
        assert!(noise_theta(f64_floor, 30.0) < THETA_TOL * 1e-3);
        // f32 at h = 1 ms, S2's release at 0.2629 s (a rise of ~300 N·m a step): the
        // scatter measured there, ±0.04 N·m, is inside the floor.
        let f32_floor = 1024.0 * f32::EPSILON * 801.0;
        assert!(f32_floor > 0.04);
        assert!(noise_theta(f32_floor, 300.0f32) < 1e-3);
    }
}
