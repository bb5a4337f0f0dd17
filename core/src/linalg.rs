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

/// Swaps entries `k < p` of `s` (rows of a row-major matrix, or of a vector); nothing
/// if either is out of range (no panic path: slice `swap` asserts its indices).
fn swap_entries<X>(s: &mut [X], k: usize, p: usize) {
    if let Some((lo, hi)) = s.split_at_mut_checked(p) {
        if let (Some(x), Some(y)) = (lo.get_mut(k), hi.first_mut()) {
            core::mem::swap(x, y);
        }
    }
}

/// Solves the top-left `n × n` block of `A x = b` (`a` row-major, `n ≤ N`) in place,
/// `x` into `b`, by Gaussian elimination with partial pivoting: the same elimination as
/// [`solve`], on plain arrays walked by iterators (no per-entry index checks), and
/// rows whose entry in the pivot column is zero are left alone, so a sparse system
/// (a group's reduced equilibrium: each row sees one or two joints) costs little more
/// than its fill-in. `false` if a pivot vanishes or is not finite. Bounded work:
/// `n³/3` multiply-adds at most, no iteration.
pub fn solve_rows<T: Real, const N: usize>(a: &mut [[T; N]; N], b: &mut [T; N], n: usize) -> bool {
    let n = n.min(N);
    for k in 0..n {
        let mut p = k;
        let mut best = T::zero();
        for (r, row) in (k..).zip(a.get(k..n).unwrap_or(&[])) {
            let v = row.get(k).map_or(T::zero(), |v| v.abs());
            if v > best {
                best = v;
                p = r;
            }
        }
        if !(best > T::zero() && best.finite()) {
            return false;
        }
        if p != k {
            swap_entries(a, k, p);
            swap_entries(b, k, p);
        }
        let (Some((head, tail)), Some((bh, bt))) =
            (a.split_at_mut_checked(k + 1), b.split_at_mut_checked(k + 1))
        else {
            return false;
        };
        let (Some(prow), Some(bk)) = (head.last(), bh.last()) else {
            return false;
        };
        let (Some(piv), Some(right)) = (prow.get(k).copied(), prow.get(k + 1..n)) else {
            return false;
        };
        let rows = tail.get_mut(..n - k - 1).unwrap_or(&mut []);
        for (row, br) in rows.iter_mut().zip(bt.iter_mut()) {
            let Some(rk) = row.get(k).copied().filter(|v| *v != T::zero()) else {
                continue;
            };
            let f = rk / piv;
            // Column k itself is not read again: only the columns right of it.
            for (x, y) in row
                .get_mut(k + 1..n)
                .unwrap_or(&mut [])
                .iter_mut()
                .zip(right)
            {
                *x -= f * *y;
            }
            *br -= f * *bk;
        }
    }
    for k in (0..n).rev() {
        let (Some(row), Some((bh, bt))) = (a.get(k), b.split_at_mut_checked(k + 1)) else {
            return false;
        };
        let (Some(bk), Some(d), Some(right)) = (bh.last_mut(), row.get(k), row.get(k + 1..n))
        else {
            return false;
        };
        let mut s = *bk;
        for (x, v) in right.iter().zip(bt.iter()) {
            s -= *x * *v;
        }
        *bk = s / *d;
    }
    true
}
