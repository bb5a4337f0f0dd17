//! Small dense linear algebra the core needs beyond nalgebra's fixed-size helpers.

use crate::scalar::Real;
use nalgebra::{SMatrix, SVector};

/// Swaps rows `i` and `j` of `m`; `None` (and nothing swapped) if either is out of
/// range. nalgebra's `swap_rows` asserts its indices; this bound makes that assertion
/// provably dead, so no panic is reachable from the eliminations below.
fn swap_rows<T: Real, const R: usize, const C: usize>(
    m: &mut SMatrix<T, R, C>,
    i: usize,
    j: usize,
) -> Option<()> {
    if i < R && j < R {
        m.swap_rows(i, j);
        Some(())
    } else {
        None
    }
}

/// Partial pivoting: the row (from `k` up to `n`) of the largest entry of column `k`;
/// `None` if that entry is zero or not finite.
fn pivot<T: Real, const N: usize>(a: &SMatrix<T, N, N>, k: usize, n: usize) -> Option<usize> {
    let mut p = k;
    let mut best = T::zero();
    for r in k..n {
        let v = a.get((r, k))?.abs();
        if v > best {
            best = v;
            p = r;
        }
    }
    (best > T::zero() && best.finite()).then_some(p)
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting (`N` ≤ 12 here: a
/// group's equilibrium). `None` if a pivot vanishes or is not finite. Bounded work:
/// `N³/3` multiply-adds, no iteration.
pub fn solve<T: Real, const N: usize>(
    mut a: SMatrix<T, N, N>,
    mut b: SVector<T, N>,
) -> Option<SVector<T, N>> {
    for k in 0..N {
        let p = pivot(&a, k, N)?;
        if p != k {
            swap_rows(&mut a, k, p)?;
            swap_rows(&mut b, k, p)?;
        }
        let piv = *a.get((k, k))?;
        for r in (k + 1)..N {
            let f = *a.get((r, k))? / piv;
            if f == T::zero() {
                continue;
            }
            for c in k..N {
                let akc = *a.get((k, c))?;
                *a.get_mut((r, c))? -= f * akc;
            }
            let bk = *b.get(k)?;
            *b.get_mut(r)? -= f * bk;
        }
    }
    for k in (0..N).rev() {
        let mut s = *b.get(k)?;
        for c in (k + 1)..N {
            s -= *a.get((k, c))? * *b.get(c)?;
        }
        *b.get_mut(k)? = s / *a.get((k, k))?;
    }
    Some(b)
}

/// Inverts the top-left `n × n` block of `a` by Gauss-Jordan elimination with partial
/// pivoting; the rest of the result is the identity. Returns the inverse and the
/// block's determinant, or `None` if a pivot vanishes or is not finite. Bounded work:
/// `n³` multiply-adds, no iteration (a group's Jacobian `W`, `n` ≤ 6).
pub fn invert<T: Real, const N: usize>(
    mut a: SMatrix<T, N, N>,
    n: usize,
) -> Option<(SMatrix<T, N, N>, T)> {
    let n = n.min(N);
    let mut inv = SMatrix::<T, N, N>::identity();
    let mut det = T::one();
    for k in 0..n {
        let p = pivot(&a, k, n)?;
        if p != k {
            swap_rows(&mut a, k, p)?;
            swap_rows(&mut inv, k, p)?;
            det = -det;
        }
        let piv = *a.get((k, k))?;
        det *= piv;
        let ip = T::one() / piv;
        for c in 0..n {
            *a.get_mut((k, c))? *= ip;
            *inv.get_mut((k, c))? *= ip;
        }
        for r in 0..n {
            if r == k {
                continue;
            }
            let f = *a.get((r, k))?;
            if f == T::zero() {
                continue;
            }
            for c in 0..n {
                let akc = *a.get((k, c))?;
                let ikc = *inv.get((k, c))?;
                *a.get_mut((r, c))? -= f * akc;
                *inv.get_mut((r, c))? -= f * ikc;
            }
        }
    }
    if !det.finite() {
        return None;
    }
    Some((inv, det))
}
