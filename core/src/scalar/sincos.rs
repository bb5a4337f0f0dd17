//! Sine and cosine in `f32` arithmetic (Cody-Waite reduction by π/2 in four parts,
//! Cephes' minimax polynomials on [-π/4, π/4]).
//!
//! Written by hand, not taken from libm: libm's `sincosf` (musl's) works in `f64`
//! inside, which a single-precision FPU (Cortex-M4F) runs as soft-float calls, about a
//! third of an f32 twin step's instructions there. This one is IEEE `f32` additions
//! and multiplications only up to [`REDUCED_MAX`], no fused operation, no table, no
//! branch on data beyond the quadrant: the same bits on every IEEE-754 target (host
//! and firmware), no panic, bounded work.
//!
//! Accuracy against the `f64` sine and cosine of the same argument (every `f32` of
//! the range, scanned): ≤ 0.67 ulp for |x| < 0.5, ≤ 1.6 ulp for |x| ≤ 256 rad, ≤ 2.4
//! ulp for |x| ≤ [`REDUCED_MAX`]. Past it (an `f32` angle's ulp is 1e-3 rad there and
//! more) the angle is first reduced by whole turns in `f64` (exact to 2e-9 rad while
//! |x| < 2^24; the `f64` operations are a few soft-float calls on a single-precision
//! FPU, on this branch only) and rounded to `f32`: within 1.6e-7 of the sine and
//! cosine (absolute). NaN and infinities give NaN. No libm: its `sinf`/`cosf`/
//! `sincosf` and their `f64` reduction (4 KB of Thumb-2 code) are not linked.

/// π/2 = P1 + P2 + P3 + P4 (to 8e-20): P1 has 8 significant bits, P2 10 and P3 11, so
/// `k·P1`, `k·P2` and `k·P3` are exact for |k| < 2^13, and `x - k·P1` is exact
/// (Sterbenz); near a multiple of π/2 each following subtraction is exact too, so the
/// reduced argument keeps its relative accuracy at the sine's and cosine's zeros.
const P1: f32 = 1.570_312_5;
const P2: f32 = 4.837_513e-4;
const P3: f32 = 7.549_533_6e-8;
const P4: f32 = 2.563_344e-12;

/// The largest |x| reduced here, rad (|k| ≤ 5216 < 2^13).
pub const REDUCED_MAX: f32 = 8192.0;

/// Cephes `sinf`: sin r = r + r³ (S3 + S2 r² + S1 r⁴) on [-π/4, π/4].
const S1: f32 = -1.951_529_6e-4;
const S2: f32 = 8.332_161e-3;
const S3: f32 = -1.666_665_5e-1;
/// Cephes `cosf`: cos r = 1 - r²/2 + r⁴ (C3 + C2 r² + C1 r⁴) on [-π/4, π/4].
const C1: f32 = 2.443_315_7e-5;
const C2: f32 = -1.388_731_6e-3;
const C3: f32 = 4.166_664_6e-2;

/// `(sin x, cos x)` for `f32`.
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if x.abs() <= REDUCED_MAX {
        reduced(x)
    } else {
        far(x)
    }
}

/// [`sin_cos_f32`] for |x| ≤ [`REDUCED_MAX`].
#[inline(always)]
fn reduced(x: f32) -> (f32, f32) {
    // k = x·2/π rounded half away from zero (|k| ≤ 5216: the cast is exact).
    let k = if x.abs() <= core::f32::consts::FRAC_PI_4 {
        0.0
    } else {
        let t = x * core::f32::consts::FRAC_2_PI;
        let a = (t.abs() + 0.5) as i32 as f32;
        if t < 0.0 {
            -a
        } else {
            a
        }
    };
    let r = (((x - k * P1) - k * P2) - k * P3) - k * P4;
    let z = r * r;
    let s = ((S1 * z + S2) * z + S3) * z * r + r;
    let c = ((C1 * z + C2) * z + C3) * z * z - 0.5 * z + 1.0;
    match (k as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// [`sin_cos_f32`] past [`REDUCED_MAX`]: whole turns taken off in `f64`, then
/// [`reduced`]. Each pass takes off `|x|/2π` rounded turns: exact to 2e-9 rad while
/// |x| < 2^24 (one pass); past 2^53 the product keeps up to the angle's `f64` ulp,
/// which the next pass takes off (three passes bring `f32::MAX`, 2^128, under π). An
/// `f32` angle past 2^24 rad holds no fraction of a turn (its ulp is 2 rad or more):
/// its sine and cosine are then those of the reduced `f64` angle, a point of the unit
/// circle. NaN and infinities give NaN. Not inlined: the `f64` operations (soft-float
/// calls on a single-precision FPU) stay off the common path.
#[inline(never)]
fn far(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let mut r = f64::from(x);
    for _ in 0..4 {
        if r.abs() <= core::f64::consts::PI {
            break;
        }
        let turns = r * (0.5 * core::f64::consts::FRAC_1_PI);
        // Rounded half away from zero; from 2^52 on every f64 is a whole number.
        let n = if turns.abs() >= 4_503_599_627_370_496.0 {
            turns
        } else {
            (turns + if turns < 0.0 { -0.5 } else { 0.5 }) as i64 as f64
        };
        r -= n * core::f64::consts::TAU;
    }
    let r = r as f32;
    if r.abs() <= REDUCED_MAX {
        reduced(r)
    } else {
        (f32::NAN, f32::NAN)
    }
}

#[cfg(test)]
mod tests {
    use super::{sin_cos_f32, REDUCED_MAX};

    /// `got`'s error from `exact` in ulps of the `f32` nearest to `exact`.
    fn ulps(got: f32, exact: f64) -> f64 {
        let e = (exact as f32).abs();
        let ulp = if e == 0.0 {
            f64::from(f32::from_bits(1))
        } else {
            f64::from(f32::from_bits(e.to_bits() + 1)) - f64::from(e)
        };
        (f64::from(got) - exact).abs() / ulp
    }

    /// Against the `f64` sine and cosine (the host's libm, an independent code) of
    /// the same argument: every 97th `f32` of ±[1e-6, REDUCED_MAX] (about 4.6
    /// million, every exponent), the quadrant edges, and the bounds of the module docs.
    #[test]
    fn against_f64() {
        extern crate std;
        let (lo, hi) = (1e-6f32.to_bits(), REDUCED_MAX.to_bits());
        let mut worst = [0.0f64; 3];
        let edges = (0..5217).map(|k| k as f32 * core::f32::consts::FRAC_PI_2);
        let sweep = (lo..=hi).step_by(97).map(f32::from_bits);
        for x in sweep.chain(edges).flat_map(|x| [x, -x]) {
            let (s, c) = sin_cos_f32(x);
            let e = ulps(s, f64::from(x).sin()).max(ulps(c, f64::from(x).cos()));
            let band = if x.abs() < 0.5 {
                0
            } else if x.abs() <= 256.0 {
                1
            } else {
                2
            };
            worst[band] = worst[band].max(e);
        }
        assert!(
            worst[0] <= 0.67 && worst[1] <= 1.6 && worst[2] <= 2.4,
            "{worst:?}"
        );
        // Exact at 0, and NaN in, NaN out.
        assert_eq!(sin_cos_f32(0.0), (0.0, 1.0));
        let (s, c) = sin_cos_f32(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
        // Past the reduced range: whole turns off in f64, within 2.4e-7 of the f64
        // sine and cosine (absolute: the reduced angle's rounding to f32) up to 2^24;
        // past it a point of the unit circle; NaN for the infinities.
        let mut worst = 0.0f64;
        let far = (REDUCED_MAX.to_bits() + 1..16_777_216f32.to_bits()).step_by(101);
        for x in far.map(f32::from_bits).flat_map(|x| [x, -x]) {
            let (s, c) = sin_cos_f32(x);
            let x = f64::from(x);
            let e = (f64::from(s) - x.sin())
                .abs()
                .max((f64::from(c) - x.cos()).abs());
            assert!(e <= 2.4e-7, "{x}: {s} {c}: {e:e}");
            worst = worst.max(e);
        }
        assert!(worst > 0.0);
        std::println!("past REDUCED_MAX to 2^24: within {worst:.3e}");
        for x in [16_777_216.0, 3.0e9, 1.0e20, f32::MAX, -f32::MAX] {
            let (s, c) = sin_cos_f32(x);
            let norm = f64::from(s).powi(2) + f64::from(c).powi(2);
            assert!((norm - 1.0).abs() < 1e-6, "{x}: {s} {c}");
        }
        for x in [f32::INFINITY, f32::NEG_INFINITY] {
            let (s, c) = sin_cos_f32(x);
            assert!(s.is_nan() && c.is_nan());
        }
    }
}
