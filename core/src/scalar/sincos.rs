//! Sine and cosine in `f32` arithmetic only (Cody-Waite reduction by π/2 in four parts,
//! Cephes' minimax polynomials on [-π/4, π/4]).
//!
//! Written by hand, not taken from libm: libm's `sincosf` (musl's) works in `f64`
//! inside, which a single-precision FPU (Cortex-M4F) runs as soft-float calls, about a
//! third of an f32 twin step's instructions there. This one is IEEE `f32` additions
//! and multiplications only, no fused operation, no table, no branch on data beyond the
//! quadrant: the same bits on every IEEE-754 target (host and firmware), no `f64`
//! anywhere, no panic, bounded work.
//!
//! Accuracy against the `f64` sine and cosine of the same argument (every `f32` of
//! the range, scanned): ≤ 0.67 ulp for |x| < 0.5, ≤ 1.6 ulp for |x| ≤ 256 rad, ≤ 2.4
//! ulp for |x| ≤ [`REDUCED_MAX`]. Past it (an `f32` angle's ulp is 1e-3 rad there),
//! and for NaN and infinities, libm's `sincosf`.

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
    if !(x.abs() <= REDUCED_MAX) {
        return nalgebra::ComplexField::sin_cos(x);
    }
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
        // Past the reduced range: libm's sincosf, close to the f64 values too.
        let x = 1.0e5f32;
        let (s, c) = sin_cos_f32(x);
        assert!(ulps(s, f64::from(x).sin()) <= 1.0 && ulps(c, f64::from(x).cos()) <= 1.0);
    }
}
