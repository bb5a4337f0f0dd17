//! The scalar type the core is generic over: `f64` on PCs and double-precision MCUs,
//! `f32` on MCUs with a single-precision FPU (Cortex-M4F).
//!
//! Every transcendental function goes through nalgebra/simba built with `libm-force`,
//! so host and target evaluate the same `libm` code and produce the same bits.

use nalgebra::RealField;

mod sincos;

/// A real scalar usable by the core (`f64` or `f32`).
pub trait Real: RealField + Copy + core::fmt::Debug + core::fmt::Display + Default {
    /// Converts an `f64` constant (rounded to nearest for `f32`).
    fn c(x: f64) -> Self;
    /// Widens to `f64` (exact for both implementations).
    fn to_f64(self) -> f64;
    /// The IEEE 754 bit pattern, widened to 64 bits: two values have the same only if
    /// they are the same bits (a -0 and a NaN's payload included). f32's own, not
    /// through `to_f64`, which is a library's conversion on a single-precision FPU.
    fn bits(self) -> u64;
    /// Machine epsilon of the type.
    const EPS: Self;
    /// `true` when the value is neither NaN nor infinite.
    fn finite(self) -> bool;
    /// The square root, correctly rounded (IEEE 754): libm's, or with the feature
    /// `arm-vsqrt-f64` on ARM the FPU's `VSQRT.F64` (f64). Both are the correctly
    /// rounded root, so the bits are the same; the FPU's costs one instruction (14
    /// cycles on a Cortex-M7) where libm's software root on a core without an SSE-like
    /// path costs ~100 instructions.
    fn root(self) -> Self;
    /// `(sin x, cos x)`: f64, libm's `sincos` (as `RealField::sin_cos`); f32, in `f32`
    /// arithmetic only (Cody-Waite and Cephes polynomials: libm's `sincosf` works in f64 inside, soft-float on
    /// a single-precision FPU), within 1.6 ulp for |x| ≤ 256 rad.
    fn sincos(self) -> (Self, Self);
}

impl Real for f64 {
    #[inline(always)]
    fn c(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn bits(self) -> u64 {
        self.to_bits()
    }
    const EPS: Self = f64::EPSILON;
    #[inline(always)]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline(always)]
    fn root(self) -> Self {
        #[cfg(all(feature = "arm-vsqrt-f64", target_arch = "arm"))]
        {
            let r: f64;
            // SAFETY: one FPU instruction on registers (a D register in, one out): no
            // memory, no stack, no condition flags. The feature promises a
            // double-precision FPU (FPv5-D16, Cortex-M7); without one it does not build.
            unsafe {
                core::arch::asm!(
                    "vsqrt.f64 {r}, {x}",
                    r = lateout(dreg_low16) r,
                    x = in(dreg_low16) self,
                    options(pure, nomem, nostack, preserves_flags)
                );
            }
            r
        }
        #[cfg(not(all(feature = "arm-vsqrt-f64", target_arch = "arm")))]
        {
            nalgebra::ComplexField::sqrt(self)
        }
    }
    #[inline(always)]
    fn sincos(self) -> (Self, Self) {
        nalgebra::ComplexField::sin_cos(self)
    }
}

impl Real for f32 {
    #[inline(always)]
    fn c(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn bits(self) -> u64 {
        u64::from(self.to_bits())
    }
    const EPS: Self = f32::EPSILON;
    #[inline(always)]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline(always)]
    fn root(self) -> Self {
        #[cfg(all(feature = "arm-vsqrt-f32", target_arch = "arm"))]
        {
            let bits: u32;
            // SAFETY: FPU instructions on registers only: no memory, no stack, no
            // condition flags. S0 is borrowed and given back within the block (Rust's
            // S-register operands need the `vfp2` target feature, which names a
            // double-precision FPU the M4F lacks: its single-precision FPv4-SP does
            // `VSQRT.F32` all the same). The feature promises an FPU; without one the
            // assembler refuses the instructions.
            unsafe {
                core::arch::asm!(
                    "vmov {keep}, s0",
                    "vmov s0, {x}",
                    "vsqrt.f32 s0, s0",
                    "vmov {r}, s0",
                    "vmov s0, {keep}",
                    x = in(reg) self.to_bits(),
                    r = lateout(reg) bits,
                    keep = out(reg) _,
                    options(pure, nomem, nostack, preserves_flags)
                );
            }
            f32::from_bits(bits)
        }
        #[cfg(not(all(feature = "arm-vsqrt-f32", target_arch = "arm")))]
        {
            nalgebra::ComplexField::sqrt(self)
        }
    }
    #[inline]
    fn sincos(self) -> (Self, Self) {
        sincos::sin_cos_f32(self)
    }
}

/// A plane vector `(x, y)`, m (or m/s, m/s²).
pub type Vec2<T> = nalgebra::Vector2<T>;

/// `e(a) = (cos a, sin a)`: the unit vector at angle `a` (SPEC 2).
#[inline(always)]
pub fn unit<T: Real>(a: T) -> Vec2<T> {
    let (s, c) = a.sincos();
    Vec2::new(c, s)
}

/// Rotates `v` by the angle whose cosine and sine are `(c, s)`.
#[inline(always)]
pub fn rotate_cs<T: Real>(c: T, s: T, v: &Vec2<T>) -> Vec2<T> {
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// `J v`: `v` turned by +90° (the planar `ω ×`).
#[inline(always)]
pub fn perp<T: Real>(v: &Vec2<T>) -> Vec2<T> {
    Vec2::new(-v.y, v.x)
}

/// The planar cross product `a × b = a.x b.y - a.y b.x` (a moment, N·m, for `r × F`).
#[inline(always)]
pub fn cross<T: Real>(a: &Vec2<T>, b: &Vec2<T>) -> T {
    a.x * b.y - a.y * b.x
}

/// Whether `a` and `b` are the same bits (see [`Real::bits`]): the test of a state or
/// an input met again, where `==` would take -0 for 0 and never a NaN for itself.
#[inline]
pub fn same_bits<T: Real>(a: T, b: T) -> bool {
    a.bits() == b.bits()
}
#[cfg(test)]
mod tests {
    use super::Real;

    /// A deterministic spread of f64 bit patterns: every exponent (subnormals included),
    /// pseudo-random mantissas (xorshift), and the edges.
    fn samples() -> impl Iterator<Item = f64> {
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let edges = [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            f64::MAX,
            1.0,
            2.0,
            4.0,
            f64::INFINITY,
        ];
        edges.into_iter().chain((0..200_000).map(move |_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // Positive, any exponent up to the largest finite.
            f64::from_bits(x & 0x7fef_ffff_ffff_ffff)
        }))
    }

    /// `Real::root` is the correctly rounded square root: against Rust's own `sqrt`
    /// (IEEE 754's, correctly rounded) and, independently, by its residual: `r` is the
    /// root rounded to nearest iff `x` lies between the squares of the midpoints to
    /// `r`'s neighbours, checked in exact integer arithmetic for normal `r`.
    #[test]
    fn root_is_correctly_rounded() {
        extern crate std;
        for x in samples() {
            let r = x.root();
            assert_eq!(
                r.to_bits(),
                std::primitive::f64::sqrt(x).to_bits(),
                "root({x:e})"
            );
            if r.is_normal() && x.is_normal() {
                // r = m·2^e with a 53-bit m; midpoints (2m ± 1)·2^(e-1); squares
                // (2m ± 1)²·2^(2e-2) against x = mx·2^ex.
                let (m, e) = (
                    ((r.to_bits() & ((1 << 52) - 1)) | (1 << 52)) as u128,
                    ((r.to_bits() >> 52) as i32) - 1075,
                );
                let (mx, ex) = (
                    ((x.to_bits() & ((1 << 52) - 1)) | (1 << 52)) as u128,
                    ((x.to_bits() >> 52) as i32) - 1075,
                );
                let shift = ex - (2 * e - 2);
                assert!((50..=60).contains(&shift), "exponents {x:e}: {shift}");
                let xs = mx << shift;
                let (lo, hi) = ((2 * m - 1) * (2 * m - 1), (2 * m + 1) * (2 * m + 1));
                assert!(
                    lo <= xs && xs <= hi,
                    "root({x:e}) = {r:e} is not rounded to nearest"
                );
            }
        }
        // f32: against the f64 root rounded once more (exact: 53 ≥ 2·24 + 2 bits).
        for x in samples().map(|x| x as f32).filter(|x| x.is_finite()) {
            assert_eq!(
                x.root().to_bits(),
                ((x as f64).root() as f32).to_bits(),
                "root({x:e})"
            );
        }
    }
}
