//! Small dense linear algebra the core needs beyond nalgebra's fixed-size helpers.

use crate::scalar::Real;
use nalgebra::{SMatrix, SVector};

/// The rows of `a`, copied: the eliminations below work on whole rows, which as arrays
/// they walk with iterators (no index checks in the inner loops).
fn rows<T: Real, const N: usize>(a: &SMatrix<T, N, N>) -> [[T; N]; N] {
    let mut m = [[T::zero(); N]; N];
    for (c, col) in a.column_iter().enumerate() {
        for (row, v) in m.iter_mut().zip(col.iter()) {
            if let Some(e) = row.get_mut(c) {
                *e = *v;
            }
        }
    }
    m
}

/// Swaps entries `i` and `j` of `m` (rows of a matrix, or of a right-hand side);
/// nothing if either is out of range (which makes the swap's bound check dead: no
/// panic is reachable from the eliminations below).
#[inline]
fn swap<X, const N: usize>(m: &mut [X; N], i: usize, j: usize) {
    if i < N && j < N {
        m.swap(i, j);
    }
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting ([`lu`], then
/// [`lu_solve`]). `None` if a pivot vanishes or is not finite. Bounded work: `N³/3`
/// multiply-adds, no iteration.
pub fn solve<T: Real, const N: usize>(
    a: SMatrix<T, N, N>,
    b: SVector<T, N>,
) -> Option<SVector<T, N>> {
    let mut m = rows(&a);
    let mut x = [T::zero(); N];
    for (e, v) in x.iter_mut().zip(b.iter()) {
        *e = *v;
    }
    solve_in_place(&mut m, &mut x).then(|| SVector::from(x))
}

/// Solves `A x = b` (`a` row-major) in place, `x` into `b` (`a` into its LU factors):
/// [`solve`] on plain arrays. `false` if a pivot vanishes or is not finite.
pub fn solve_in_place<T: Real, const N: usize>(a: &mut [[T; N]; N], b: &mut [T; N]) -> bool {
    let mut piv = [0u8; N];
    if factor(a, &mut piv).is_none() {
        return false;
    }
    lu_solve::<T, N, N>(a, &piv, b);
    true
}

/// LU factorisation with partial pivoting (Doolittle) of `a` (row-major), in place:
/// `P A = L U`, with `L` strictly below the diagonal (its unit diagonal implied) and
/// `U` on and above it, the rows in pivot order; `piv[k]` is the row swapped with row
/// `k` at step `k` (`k` itself for none). Rows whose entry in the pivot column is zero
/// are left alone (a group's sparse Jacobian costs little more than its fill-in).
/// Returns the determinant, or `None` if a pivot vanishes or is not finite or the
/// determinant overflows (`a` and `piv` are then partly overwritten). Bounded work: `N³/3` multiply-adds at most, no
/// iteration; the size is a constant, so the loops unroll (a group's `W`, `N` ≤ 6).
/// With [`lu_solve`] (`N²` per right-hand side, as a product by the inverse) it
/// replaces an inverse (`N³`) where a matrix serves a few solves.
pub fn lu<T: Real, const N: usize>(a: &mut [[T; N]; N], piv: &mut [u8; N]) -> Option<T> {
    factor(a, piv).filter(|det| det.finite())
}

/// [`lu`] whatever its determinant: `None` only if a pivot vanishes or is not finite
/// (a solve needs no finite determinant).
fn factor<T: Real, const N: usize>(a: &mut [[T; N]; N], piv: &mut [u8; N]) -> Option<T> {
    let mut det = T::one();
    // The first steps one call each with a constant `k`: inlined, their loops have
    // constant bounds and unroll (a group's W, N ≤ 6, is factored in full so, with no
    // loop overhead); the steps of a larger matrix past them in a loop.
    elimination_step(a, piv, &mut det, 0)?;
    elimination_step(a, piv, &mut det, 1)?;
    elimination_step(a, piv, &mut det, 2)?;
    elimination_step(a, piv, &mut det, 3)?;
    elimination_step(a, piv, &mut det, 4)?;
    elimination_step(a, piv, &mut det, 5)?;
    for k in 6..N {
        elimination_step(a, piv, &mut det, k)?;
    }
    Some(det)
}

/// Step `k` of [`factor`] (nothing if `k ≥ N`): the pivot of column `k` (the largest
/// magnitude on or below the diagonal) swapped into row `k`, `det` multiplied by it
/// (and negated by a swap), and its multiples subtracted from the rows below.
#[inline(always)]
fn elimination_step<T: Real, const N: usize>(
    a: &mut [[T; N]; N],
    piv: &mut [u8; N],
    det: &mut T,
    k: usize,
) -> Option<()> {
    if k >= N {
        return Some(());
    }
    let mut p = k;
    let mut best = T::zero();
    for r in k..N {
        let v = a.get(r)?.get(k)?.abs();
        if v > best {
            best = v;
            p = r;
        }
    }
    if !(best > T::zero() && best.finite()) {
        return None;
    }
    if p != k {
        swap(a, k, p);
        *det = -*det;
    }
    *piv.get_mut(k)? = p as u8;
    let prow = *a.get(k)?;
    let d = *prow.get(k)?;
    *det *= d;
    for r in k + 1..N {
        let row = a.get_mut(r)?;
        let rk = *row.get(k)?;
        if rk == T::zero() {
            continue;
        }
        let f = rk / d;
        *row.get_mut(k)? = f;
        for c in k + 1..N {
            *row.get_mut(c)? -= f * *prow.get(c)?;
        }
    }
    Some(())
}

/// Solves `A x = b`, `x` into `b`, from the factors [`lu`] made of the top-left
/// `N × N` block `A` of `lu` (`piv` its row swaps; `M ≥ N` is the storage's size):
/// `b` permuted by `P`, then `L y = P b` forward and `U x = y` backward. Entries of
/// `b` past `N` are left as they are.
pub fn lu_solve<T: Real, const N: usize, const M: usize>(
    lu: &[[T; M]; M],
    piv: &[u8; M],
    b: &mut [T; M],
) {
    for k in 0..N {
        let p = piv.get(k).map_or(k, |p| *p as usize);
        if p > k && p < N {
            swap(b, k, p);
        }
    }
    lu_substitute::<T, N, M>(lu, b);
}

/// The substitutions of [`lu_solve`] on a right-hand side already permuted by `P`:
/// `L y = b` forward, then `U x = y` backward, `x` into `b`.
pub fn lu_substitute<T: Real, const N: usize, const M: usize>(lu: &[[T; M]; M], b: &mut [T; M]) {
    for r in 1..N {
        let (Some(row), Some(mut s)) = (lu.get(r), b.get(r).copied()) else {
            return;
        };
        for c in 0..r {
            if let (Some(l), Some(y)) = (row.get(c), b.get(c)) {
                s -= *l * *y;
            }
        }
        if let Some(e) = b.get_mut(r) {
            *e = s;
        }
    }
    for r in (0..N).rev() {
        let (Some(row), Some(mut s)) = (lu.get(r), b.get(r).copied()) else {
            return;
        };
        for c in r + 1..N {
            if let (Some(u), Some(x)) = (row.get(c), b.get(c)) {
                s -= *u * *x;
            }
        }
        if let (Some(e), Some(d)) = (b.get_mut(r), row.get(r)) {
            *e = s / *d;
        }
    }
}

/// Cholesky factor of a symmetric positive definite `a`: the lower-triangular `L` with
/// `L Lᵀ = A` and a positive diagonal (its strict upper part zero). Only the lower
/// triangle of `a` is read. `None` if a pivot is zero, negative or NaN (`a` is not
/// positive definite to working precision).
///
/// Column by column (Cholesky-Banachiewicz by columns, Golub & Van Loan alg. 4.2.1):
/// column `j` less `L_jk` times column `k` for every `k < j`, then divided by the square
/// root of its diagonal. The operations and their order are nalgebra's
/// `Cholesky::new`'s, so the factor has the same bits. Bounded work: `N³/6`
/// multiply-adds and `N` square roots, no iteration.
pub fn cholesky<T: Real, const N: usize>(a: &SMatrix<T, N, N>) -> Option<SMatrix<T, N, N>> {
    let mut l = *a;
    for j in 0..N {
        for k in 0..j {
            let f = *l.get((j, k))?;
            for r in j..N {
                let lrk = *l.get((r, k))?;
                let e = l.get_mut((r, j))?;
                *e = -f * lrk + *e;
            }
        }
        let diag = *l.get((j, j))?;
        if diag == T::zero() {
            return None;
        }
        let d = diag.try_sqrt()?;
        *l.get_mut((j, j))? = d;
        for r in j + 1..N {
            let e = l.get_mut((r, j))?;
            *e /= d;
        }
        for c in j + 1..N {
            *l.get_mut((j, c))? = T::zero();
        }
    }
    Some(l)
}

/// Solves `L Lᵀ x = b` for `x` from the factor `l` of [`cholesky`]: `L y = b` forward
/// (column-oriented), then `Lᵀ x = y` backward (row-oriented, by dot products), in
/// nalgebra's `Cholesky::solve`'s order of operations (same bits). `N²` multiply-adds;
/// a zero diagonal (no factor of [`cholesky`] has one) gives infinities, not a panic.
pub fn cholesky_solve<T: Real, const N: usize>(
    l: &SMatrix<T, N, N>,
    b: &SVector<T, N>,
) -> SVector<T, N> {
    let mut x = *b;
    for i in 0..N {
        let (Some(d), Some(xi)) = (l.get((i, i)).copied(), x.get(i).copied()) else {
            break;
        };
        let coeff = xi / d;
        if let Some(e) = x.get_mut(i) {
            *e = coeff;
        }
        for r in i + 1..N {
            if let (Some(lri), Some(e)) = (l.get((r, i)).copied(), x.get_mut(r)) {
                *e = -coeff * lri + *e;
            }
        }
    }
    for i in (0..N).rev() {
        let mut dot = T::zero();
        for k in i + 1..N {
            if let (Some(lki), Some(xk)) = (l.get((k, i)), x.get(k)) {
                dot += *lki * *xk;
            }
        }
        if let (Some(d), Some(e)) = (l.get((i, i)).copied(), x.get_mut(i)) {
            *e = (*e - dot) / d;
        }
    }
    x
}

/// The inverse of a 3 × 3 matrix by its cofactors over its determinant (Cramer's
/// rule), in nalgebra's `try_inverse`'s order of operations (same bits). `None` only
/// if the determinant is exactly zero: a nearly singular or non-finite `m` gives a
/// large or non-finite inverse, which the caller's own tests must catch. 12
/// multiplications for the minors and determinant, 9 divisions, no branch but that.
pub fn inverse3<T: Real>(m: &SMatrix<T, 3, 3>) -> Option<SMatrix<T, 3, 3>> {
    let [[m11, m21, m31], [m12, m22, m32], [m13, m23, m33]] = m.data.0;
    let minor_m12_m23 = m22 * m33 - m32 * m23;
    let minor_m11_m23 = m21 * m33 - m31 * m23;
    let minor_m11_m22 = m21 * m32 - m31 * m22;
    let det = m11 * minor_m12_m23 - m12 * minor_m11_m23 + m13 * minor_m11_m22;
    if det == T::zero() {
        return None;
    }
    Some(SMatrix::<T, 3, 3>::new(
        minor_m12_m23 / det,
        (m13 * m32 - m33 * m12) / det,
        (m12 * m23 - m22 * m13) / det,
        -minor_m11_m23 / det,
        (m11 * m33 - m31 * m13) / det,
        (m13 * m21 - m23 * m11) / det,
        minor_m11_m22 / det,
        (m12 * m31 - m32 * m11) / det,
        (m11 * m22 - m21 * m12) / det,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

    /// A pseudo-random sequence in [-1, 1) (SplitMix64), for test matrices.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// `B Bᵀ + I`: symmetric positive definite.
    fn spd<const N: usize>(rng: &mut Rng) -> SMatrix<f64, N, N> {
        let b = SMatrix::<f64, N, N>::from_fn(|_, _| rng.next());
        b * b.transpose() + SMatrix::<f64, N, N>::identity()
    }

    /// A known factor: `A = L Lᵀ` with `L = [[2, 0, 0], [1, 3, 0], [-1, 2, 4]]` (the
    /// product worked by hand: `A = [[4, 2, -2], [2, 10, 5], [-2, 5, 21]]`).
    #[test]
    fn cholesky_of_a_known_matrix() {
        let a = Matrix3::new(4.0, 2.0, -2.0, 2.0, 10.0, 5.0, -2.0, 5.0, 21.0);
        let l = cholesky(&a).unwrap();
        let want = Matrix3::new(2.0, 0.0, 0.0, 1.0, 3.0, 0.0, -1.0, 2.0, 4.0);
        assert_eq!(l, want);
        // A x = b with x = (1, -2, 3): b = A x = (-6, -3, 51).
        let x = cholesky_solve(&l, &Vector3::new(-6.0, -3.0, 51.0));
        assert!((x - Vector3::new(1.0, -2.0, 3.0)).norm() < 1e-14, "{x}");
    }

    /// `L Lᵀ = A` and the residual `A x - b` to round-off, on random SPD matrices of
    /// every size the core solves; the bits are nalgebra's `Cholesky` (the dynamics'
    /// golden pins were made with it).
    #[test]
    fn cholesky_factors_and_solves() {
        fn check<const N: usize>(rng: &mut Rng) {
            for _ in 0..200 {
                let a = spd::<N>(rng);
                let b = SVector::<f64, N>::from_fn(|_, _| rng.next());
                let l = cholesky(&a).unwrap();
                let scale = a.norm();
                assert!((l * l.transpose() - a).norm() < 1e-14 * scale);
                for i in 0..N {
                    assert!(l[(i, i)] > 0.0);
                    for j in i + 1..N {
                        assert_eq!(l[(i, j)], 0.0);
                    }
                }
                let x = cholesky_solve(&l, &b);
                assert!((a * x - b).norm() < 1e-13 * scale * (x.norm() + 1.0));
                let na = nalgebra::Cholesky::new(a).unwrap();
                assert_eq!(l, na.l());
                assert_eq!(x, na.solve(&b));
            }
        }
        let mut rng = Rng(1);
        check::<1>(&mut rng);
        check::<2>(&mut rng);
        check::<3>(&mut rng);
        check::<6>(&mut rng);
    }

    /// Not positive definite: a zero, a negative or a NaN pivot is refused.
    #[test]
    fn cholesky_refuses_indefinite_matrices() {
        let zero = Matrix3::new(1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(cholesky(&zero).is_none());
        let indefinite = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(cholesky(&indefinite).is_none());
        let nan = Matrix3::new(f64::NAN, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(cholesky(&nan).is_none());
    }

    /// `A A⁻¹ = I` on random matrices, the bits of nalgebra's `try_inverse`, and a
    /// singular matrix refused.
    #[test]
    fn inverse3_inverts() {
        let mut rng = Rng(7);
        for _ in 0..500 {
            let a = Matrix3::from_fn(|_, _| rng.next());
            let inv = inverse3(&a).unwrap();
            let cond = a.norm() * inv.norm();
            assert!((a * inv - Matrix3::identity()).norm() < 1e-14 * cond, "{a}");
            assert_eq!(Some(inv), a.try_inverse());
        }
        // Known: diag(2, 4, -8) and a unit upper triangle.
        let d = Matrix3::from_diagonal(&Vector3::new(2.0, 4.0, -8.0));
        let want = Matrix3::from_diagonal(&Vector3::new(0.5, 0.25, -0.125));
        assert_eq!(inverse3(&d), Some(want));
        let u = Matrix3::new(1.0, 2.0, 3.0, 0.0, 1.0, 4.0, 0.0, 0.0, 1.0);
        let u_inv = Matrix3::new(1.0, -2.0, 5.0, 0.0, 1.0, -4.0, 0.0, 0.0, 1.0);
        assert_eq!(inverse3(&u), Some(u_inv));
        let singular = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert_eq!(inverse3(&singular), None);
    }
}
