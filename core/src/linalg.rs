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
