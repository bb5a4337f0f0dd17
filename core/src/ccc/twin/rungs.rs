//! The sub-step ladder: which rungs ([`RETRY_SUBSTEPS`]: a step's DP5 steps) a step
//! tries when its energy balance breaks, and which one it starts from.
//!
//! DP5's energy error per step is O(h⁶): an attempt in `n` sub-steps breaks the balance
//! by about `(1/n)⁵` of an undivided one, its rung-1 equivalent `jump · n⁵` (the jump
//! in tolerances). Two predictions follow. After a failed attempt, a finer rung is
//! tried only if its jump is predicted to pass ([`rung_may_pass`]). And where the
//! balance breaks by more step after step, as the motion quickens towards an event,
//! the next step's rung-1 jump is extrapolated from the last two steps'
//! ([`JumpHistory::start_rung`]): a step predicted to fail rung 1 and rung 2 starts
//! at the rung predicted to pass, and the attempts below it, each a DP5 step's work
//! only to fail, are not made. S2 in f64 at h = 1 ms: the release of lever 8 at
//! 0.2629 s broke the balance by 2.97, 20.7 and 242 tolerances in three steps; the
//! third now starts at 4 sub-steps, 1 attempt instead of 2 (on the Cortex-M7 in f64,
//! 371k → 318k Thumb-2 instructions, within the 320k budget).

use super::error::TwinStepError;
use super::inputs::Inputs;
use super::settings::{RETRY_SUBSTEPS, RUNG_SAFETY, SUBSTEPS};
use super::Twin;
use crate::balance;
use crate::scalar::Real;
use crate::workspace::WarmStart;

/// The rung a step may start from at least: a start at rung 2 would save one DP5
/// step where the prediction holds and cost one where it does not (an undivided step
/// that would have passed), and the trend is rough (S2's jumps change by factors of 0.2
/// to 11 from step to step); a start at 3 or finer is predicted to skip two rungs that
/// fail by `RUNG_SAFETY` at least.
const START_RUNG_MIN: u32 = 3;

/// `n⁵`, the factor by which `n` sub-steps divide an undivided step's energy jump.
fn fifth(n: u32) -> f64 {
    let n = f64::from(n);
    n * n * n * n * n
}

/// Whether a retry in `n` sub-steps is worth trying after an attempt in `done` failed,
/// its energy jump `excess` times its tolerance (`None`: it failed otherwise): `n`
/// sub-steps where there were `done` divide the jump by about `(n/done)⁵`. The rungs
/// of the core's [`SUBSTEPS`] are always tried (a mechanism failure, or a prediction
/// that fails, goes on to them); the twin's extra rungs (2, 3, 32 and 64) only when
/// predicted to pass by a factor [`RUNG_SAFETY`]. S2 at h = 1 ms: the catch I6 -> A68 at 0.0666 s
/// broke the balance by 9.9 undivided, where 4 sub-steps had redone it (706k Thumb-2
/// instructions on the Cortex-M7 in f64).
pub(super) fn rung_may_pass<T: Real>(n: u32, done: u32, excess: Option<T>) -> bool {
    if SUBSTEPS.contains(&n) {
        return true;
    }
    let r = f64::from(n) / f64::from(done.max(1));
    excess.is_some_and(|e| e.to_f64() * RUNG_SAFETY <= r * r * r * r * r)
}

/// The rung-1 energy jumps (tolerances) of the last two steps, oldest first, each a
/// bfloat16 (the high half of an `f32`'s bits; 0: none). A step records its first
/// attempt's jump times that attempt's `n⁵` if it is at least 1 (the undivided step
/// would have failed), and none if it had an event or a coordinate switch (the motion
/// after it is another's: S2's release at 0.2629 s broke by 242 and the step after it by
/// 3.8). Two bytes each: with them the f32 twin fills its 32 KiB (32,768 B on
/// x86_64), and a trend needs no more than 3 digits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct JumpHistory([u16; 2]);

impl JumpHistory {
    /// No history: the next step starts at rung 1.
    pub const NONE: Self = JumpHistory([0; 2]);

    /// The history after a step whose first attempt, in `start` sub-steps, broke the
    /// balance by `jump` tolerances (`None`: not measured); `eventful`: the step had an
    /// event or a coordinate switch.
    pub fn after<T: Real>(self, start: u32, jump: Option<T>, eventful: bool) -> Self {
        if eventful {
            return Self::NONE;
        }
        let code = match jump {
            // Compared in `T` where the attempt was undivided (most steps pass it: f64
            // arithmetic is a library's on the M4F).
            Some(j) if start == 1 && !(j >= T::one()) => 0,
            Some(j) => bfloat16_at_least_1(j.to_f64() * fifth(start)),
            None => 0,
        };
        let [_, last] = self.0;
        JumpHistory([last, code])
    }

    /// The rung the next step starts from: the coarsest of [`RETRY_SUBSTEPS`] at which
    /// the last two jumps' geometric trend, `j₁ · (j₁ / j₀)`, is predicted to pass by
    /// [`RUNG_SAFETY`] (the finest if none), if it is [`START_RUNG_MIN`] or finer; else
    /// rung 1.
    pub fn start_rung(self) -> u32 {
        let [first, ..] = RETRY_SUBSTEPS;
        if self.0.contains(&0) {
            return first;
        }
        let decode = |c: u16| f64::from(f32::from_bits(u32::from(c) << 16));
        let [j0, j1] = self.0.map(decode);
        let predicted = j1 * (j1 / j0);
        let fine = RETRY_SUBSTEPS.last().copied().unwrap_or(first);
        let n = RETRY_SUBSTEPS
            .iter()
            .copied()
            .find(|n| predicted * RUNG_SAFETY <= fifth(*n))
            .unwrap_or(fine);
        if n >= START_RUNG_MIN {
            n
        } else {
            first
        }
    }
}

impl<T: Real> Twin<T> {
    /// The step redone on the finer rungs after its attempt in `progress.0` sub-steps
    /// failed (`failed`), its energy jump `progress.1` (see [`rung_may_pass`]), until
    /// one passes or fails otherwise, or, with `until_stalled`, until two attempts in a
    /// row show a jump that does not fall with the sub-steps ([`jump_stalled`]: finer
    /// rungs would not mend it, other coordinates may,
    /// [`Twin::redo_in_other_coordinates`]): that attempt's result (`failed` if no rung
    /// is left), `progress` the last attempt's sub-steps and jump. Not inlined: the
    /// rungs' arithmetic (f64's, a library's on the M4F) stays off the path of a step
    /// that passes.
    #[inline(never)]
    pub(super) fn climb(
        &mut self,
        inputs: &Inputs<T>,
        changed: bool,
        failed: Result<(), TwinStepError>,
        progress: &mut (u32, Option<T>),
        saved: &WarmStart<T>,
        until_stalled: bool,
    ) -> Result<(), TwinStepError> {
        let mut result = failed;
        let mut stalled = matches!(&result, Err(TwinStepError::Diverged { stalled: true, .. }));
        let (mut done, mut excess) = *progress;
        for substeps in RETRY_SUBSTEPS {
            if substeps <= done || !rung_may_pass(substeps, done, excess) {
                continue;
            }
            crate::trace::debug!(
                "t = {:.6} s: the step redone in {substeps} sub-steps (energy jump {excess:?} of its tolerance)",
                self.t.to_f64()
            );
            // The failed attempt's restore seeded the first stage (see `attempt`): a
            // retry takes 1 evaluation fewer (8k Thumb-2 instructions on the M7 in A68).
            let before = (done, excess);
            result = self.attempt(inputs, changed, changed, substeps, saved, &mut excess);
            stalled = jump_stalled(before, (substeps, excess));
            done = substeps;
            match &result {
                Err(e) if e.retry_finer() && !(until_stalled && stalled) => {}
                _ => break,
            }
        }
        *progress = (done, excess);
        if let Err(TwinStepError::Diverged { stalled: s, .. }) = &mut result {
            *s = stalled;
        }
        result
    }

    /// Whether the energy tolerance is the scalar's rounding floor
    /// ([`balance::tolerance`]: f32's, at any step under 12 s). There a jump that does
    /// not fall with the sub-steps is that floor's, and the climb stops at it for other
    /// coordinates ([`Twin::climb`]'s `until_stalled`): at 22/200 N·m (motor / load) in
    /// f32 at h = 1 ms the levers' angle breaks the balance by 6.7, 7.5, 4.7, 5.3 and 5.2
    /// tolerances in 1, 2, 4, 16 and 32 sub-steps: climbed to 64 before the redo in the
    /// crank's angle the step takes 802 µs on x86_64, stopped at the stall 35 µs (S2's
    /// worst, 31 µs). In f64 a jump that falls slowly is more often DP5 short of its
    /// asymptotic rate, which the finer rungs still mend (stopped at it, light loads of
    /// the f64 grid at 1 ms moved in their last digits).
    pub(super) fn tolerance_at_rounding_floor(&self) -> bool {
        !(self.settings.energy_tol > balance::tolerance::<T>())
    }

    /// A step whose energy balance broke on every rung it tried, redone from its start
    /// in the mode's best conditioned other choice of coordinates, on the rungs again:
    /// whether that passed (the twin then goes on in that choice, and does not take the
    /// one it left back for a better conditioning alone: [`Twin::broke_in`]). `false`
    /// if the mode has no other choice, none assembles, or the balance breaks there
    /// too: the step is then refused with the first failure, in the mode's own
    /// coordinates. Not inlined, as [`Twin::climb`].
    ///
    /// Near a dead point of the coordinates the balance breaks on two counts, each a
    /// property of the choice, not of the step's size:
    /// - rounding (f32): a coordinate that drives the fastest link many times faster
    ///   than itself carries the links' speeds with that much of its rounding. At
    ///   22/200 N·m (motor / load) at h = 1 ms, 1.3 ms after the catch into A68, the
    ///   lever's angle drives the crank 43 times faster than itself and the links'
    ///   kinetic energy evaluated from it scatters by 0.2 J (3e-3 of it) from one
    ///   sub-step to the next, against a tolerance of 0.023 J: the balance broke by 5
    ///   to 7.5 tolerances in 1 to 64 sub-steps (stalled). The crank's angle,
    ///   conditioned 0.017 there (the lever 0.063), passes undivided.
    /// - truncation: the mode's equations in that choice are stiff where its
    ///   transmission blows up. f64, the drive counter-clockwise with friction at
    ///   12/100 N·m: at 0.640 s in A68 the step broke the balance by 6.6e-4 J in 16
    ///   sub-steps in the levers' coordinates, and passes in the crank's.
    #[inline(never)]
    pub(super) fn redo_in_other_coordinates(
        &mut self,
        inputs: &Inputs<T>,
        changed: bool,
        saved: &WarmStart<T>,
    ) -> bool {
        let slot = self.slots.cur();
        if slot.mode.coordinate_choices().len() < 2 {
            return false;
        }
        let bar = self.broke_in;
        self.broke_in = Some(slot.coords);
        crate::trace::debug!(
            "t = {:.6} s: the step redone in the mode's other coordinates (the energy balance broke in {} on every rung)",
            self.t.to_f64(),
            slot.coords
        );
        let mut excess = None;
        let mut result = self.attempt(inputs, changed, changed, 1, saved, &mut excess);
        if matches!(&result, Err(e) if e.retry_finer()) {
            result = self.climb(inputs, changed, result, &mut (1, excess), saved, false);
        }
        if result.is_err() {
            self.broke_in = bar;
        }
        result.is_ok()
    }
}

/// Whether the energy jump (tolerances) of an attempt in `n2` sub-steps, `e2`, fell by
/// less than `(n2/n1)²` from `e1` in `n1`, where DP5's truncation error falls by
/// `(n2/n1)⁵` ([`TwinStepError::Diverged`]'s `stalled`). `false` unless both were
/// measured.
fn jump_stalled<T: Real>((n1, e1): (u32, Option<T>), (n2, e2): (u32, Option<T>)) -> bool {
    match (e1, e2) {
        (Some(a), Some(b)) if n2 > n1 => {
            let r = f64::from(n2) / f64::from(n1.max(1));
            b.to_f64() * r * r > a.to_f64()
        }
        _ => false,
    }
}

/// `x` as a bfloat16 (rounded to nearest, ties away) if it is at least 1, else 0.
fn bfloat16_at_least_1(x: f64) -> u16 {
    if x >= 1.0 {
        ((x as f32).to_bits().saturating_add(0x8000) >> 16) as u16
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::{fifth, jump_stalled, rung_may_pass, JumpHistory, RETRY_SUBSTEPS, RUNG_SAFETY};

    /// Measured pairs of failed attempts (sub-steps, jump in tolerances). f32 at h = 1 ms
    /// near A68's dead points: 20/200 N·m at 0.241 s, 4.39 in 32 and 2.00 in 64 sub-steps
    /// (DP5's truncation would give 0.14); with J_s = 0.5 kg·m² at 12/100 N·m, 1.50 in 32
    /// and 4.75 in 64. Truncation at its order: a jump that falls by `(n2/n1)⁵` (and by a
    /// little more than the square) is not stalled.
    #[test]
    fn a_jump_that_does_not_fall_with_the_sub_steps_is_stalled() {
        let at = |n: u32, e: f64| (n, Some(e));
        assert!(jump_stalled(at(32, 4.39), at(64, 2.00)));
        assert!(jump_stalled(at(32, 1.50), at(64, 4.75)));
        assert!(!jump_stalled(at(4, 242.0), at(16, 242.0 / fifth(4))));
        assert!(!jump_stalled(at(16, 4.1), at(32, 1.0)));
        // No trend without two measured jumps, nor from a coarser rung.
        assert!(!jump_stalled(at(32, 4.39), (64, None)));
        assert!(!jump_stalled((16, None::<f64>), at(32, 4.39)));
        assert!(!jump_stalled(at(64, 2.0), at(32, 4.39)));
    }

    /// The history after the steps whose undivided jumps are `jumps`.
    fn after(jumps: &[f64]) -> JumpHistory {
        jumps
            .iter()
            .fold(JumpHistory::NONE, |h, j| h.after(1, Some(*j), false))
    }

    #[test]
    fn a_quickening_jump_starts_the_next_step_where_it_is_predicted_to_pass() {
        // S2 in f64 at h = 1 ms before the release at 0.2629 s: 2.97 then 20.7; the
        // trend predicts 144, which passes in 4 sub-steps by 1024/144 = 7.1 (3: 243/144
        // = 1.7, under RUNG_SAFETY). The step broke by 242 undivided: 4 sub-steps was
        // its rung.
        assert_eq!(after(&[2.97, 20.7]).start_rung(), 4);
        // Past 4 sub-steps' reach: 16 (predicted 80 000, 16⁵/2 = 524 288), 32 (2e6,
        // 32⁵/2 = 1.7e7), and past every rung's the finest.
        assert_eq!(after(&[2.0, 400.0]).start_rung(), 16);
        assert_eq!(after(&[2.0, 2000.0]).start_rung(), 32);
        assert_eq!(after(&[1.0, 1e5]).start_rung(), 64);
        // 7.1 → 25.2 predicts 89, under 243/2: 3 sub-steps.
        assert_eq!(after(&[7.1, 25.2]).start_rung(), 3);
    }

    #[test]
    fn a_rung_under_three_or_no_trend_starts_at_one() {
        // Predicted 12.9: rung 2 passes (32/12.9 = 2.5), a start at 2 is not made.
        assert_eq!(after(&[2.0, 5.08]).start_rung(), 1);
        // A falling trend: 33.6 → 5.65 predicts 0.95.
        assert_eq!(after(&[33.6, 5.65]).start_rung(), 1);
        // One step's jump alone is no trend.
        assert_eq!(after(&[300.0]).start_rung(), 1);
        // A step that passed undivided (under 1) breaks the trend.
        assert_eq!(after(&[20.0, 300.0, 0.5]).start_rung(), 1);
        assert_eq!(after(&[20.0, 0.5, 300.0]).start_rung(), 1);
        // An event or a coordinate switch clears it.
        let h = after(&[20.0, 300.0]).after(1, Some(500.0), true);
        assert_eq!(h, JumpHistory::NONE);
        assert_eq!(h.start_rung(), 1);
        assert_eq!(JumpHistory::NONE.start_rung(), 1);
    }

    #[test]
    fn a_divided_first_attempt_counts_as_its_undivided_jump() {
        // A step started at 4 sub-steps that broke by 0.1 of its tolerance is a rung-1
        // jump of 102.4: after 20, the trend predicts 524 (4 sub-steps pass by 1.95,
        // under RUNG_SAFETY: 16).
        let h = after(&[20.0]).after(4, Some(0.1f64), false);
        assert_eq!(h.start_rung(), 16);
        // Under 1 undivided: none.
        let h = after(&[20.0]).after(2, Some(0.02f64), false);
        assert_eq!(h.start_rung(), 1);
        // Not measured: none.
        let h = after(&[20.0, 300.0]).after::<f64>(1, None, false);
        assert_eq!(h.start_rung(), 1);
    }

    #[test]
    fn the_code_keeps_three_digits() {
        for j in [1.0, 2.97, 20.7, 241.75, 8185.2, 1e30] {
            let h = after(&[1.0, j]);
            let got = f64::from(f32::from_bits(u32::from(h.0[1]) << 16));
            assert!((got - j).abs() <= j * 2f64.powi(-8), "{j} coded as {got}");
        }
        // The start rung from coded values agrees with the exact trend's wherever the
        // exact prediction is not within the code's error of a rung's threshold.
        for (a, b) in [(1.5, 9.0), (3.0, 40.0), (10.0, 100.0), (50.0, 60.0)] {
            let exact = b * b / a;
            let n = RETRY_SUBSTEPS
                .iter()
                .copied()
                .find(|n| exact * RUNG_SAFETY <= fifth(*n))
                .unwrap_or(64);
            let n = if n >= 3 { n } else { 1 };
            assert_eq!(after(&[a, b]).start_rung(), n, "{a} -> {b}");
        }
    }

    /// The rungs after a failed attempt: the core's (4 and 16) always; 2 and 3 only where
    /// DP5's O(h⁶) energy error per step, divided into `n` where there were `done`, brings
    /// the jump under the tolerance by the safety factor 2: a jump of `e` tolerances
    /// becomes e·(done/n)⁵, so 3 after 1 passes for e ≤ 3⁵/2 = 121.5 and 2 after 1 for
    /// e ≤ 2⁵/2 = 16 (S2 in f64 at h = 1 ms: 70.2 at its catch I0 -> A8 at 0.1763 s, which
    /// 3 sub-steps then passed; 135 at the release at 0.2629 s, which goes to 4).
    #[test]
    fn the_rungs_are_tried_where_the_h6_law_predicts_they_pass() {
        use super::SUBSTEPS;
        assert_eq!(RUNG_SAFETY, 2.0);
        // The core's rungs are all the twin's, in the same order, with 2 and 3 before 4
        // and 32 and 64 after 16.
        assert_eq!(RETRY_SUBSTEPS, [1, 2, 3, 4, 16, 32, 64]);
        assert!(SUBSTEPS.iter().all(|n| RETRY_SUBSTEPS.contains(n)));
        for n in SUBSTEPS {
            assert!(rung_may_pass::<f64>(n, 1, None), "{n}");
            assert!(rung_may_pass::<f64>(n, 3, Some(1e6)), "{n}");
        }
        // 3 after 1: 243 / 2 = 121.5 tolerances.
        assert!(rung_may_pass(3, 1, Some(70.2f64)));
        assert!(rung_may_pass(3, 1, Some(121.5f64)));
        assert!(!rung_may_pass(3, 1, Some(121.6f64)));
        assert!(!rung_may_pass(3, 1, Some(135.0f64)));
        // 2 after 1: 32 / 2 = 16.
        assert!(rung_may_pass(2, 1, Some(16.0f64)));
        assert!(!rung_may_pass(2, 1, Some(16.1f64)));
        // 3 after 2: 1.5⁵ / 2 = 3.796875.
        assert!(rung_may_pass(3, 2, Some(3.796875f64)));
        assert!(!rung_may_pass(3, 2, Some(3.8f64)));
        // 32 after 16: 2⁵ / 2 = 16; 64 after 16: 4⁵ / 2 = 512; 64 after 32: 16.
        assert!(rung_may_pass(32, 16, Some(16.0f64)) && !rung_may_pass(32, 16, Some(16.1f64)));
        assert!(rung_may_pass(64, 16, Some(512.0f64)) && !rung_may_pass(64, 16, Some(513.0f64)));
        assert!(rung_may_pass(64, 32, Some(16.0f64)) && !rung_may_pass(64, 32, Some(16.1f64)));
        // A failure without an energy jump (a mechanism failure) goes to the core's rungs.
        assert!(!rung_may_pass::<f64>(2, 1, None) && !rung_may_pass::<f64>(3, 1, None));
        assert!(!rung_may_pass::<f64>(32, 16, None) && !rung_may_pass::<f64>(64, 16, None));
        // In f32 the same law.
        assert!(rung_may_pass(3, 1, Some(121.5f32)) && !rung_may_pass(3, 1, Some(122.0f32)));
    }
}
