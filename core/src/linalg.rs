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

/// Partial pivoting: the row (from `k` up to `n`) of the largest entry of column `k`;
/// `None` if that entry is zero or not finite.
fn pivot<T: Real, const N: usize>(m: &[[T; N]; N], k: usize, n: usize) -> Option<usize> {
    let mut p = k;
    let mut best = T::zero();
    for (r, row) in m.get(k..n)?.iter().enumerate() {
        let v = row.get(k)?.abs();
        if v > best {
            best = v;
            p = k + r;
        }
    }
    (best > T::zero() && best.finite()).then_some(p)
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting (`N` ≤ 12 here: a
/// group's equilibrium). `None` if a pivot vanishes or is not finite. Bounded work:
/// `N³/3` multiply-adds, no iteration.
pub fn solve<T: Real, const N: usize>(
    a: SMatrix<T, N, N>,
    b: SVector<T, N>,
) -> Option<SVector<T, N>> {
    let mut m = rows(&a);
    let mut x = [T::zero(); N];
    for (e, v) in x.iter_mut().zip(b.iter()) {
        *e = *v;
    }
    for k in 0..N {
        let p = pivot(&m, k, N)?;
        if p != k {
            swap(&mut m, k, p);
            swap(&mut x, k, p);
        }
        let (top, rest) = m.split_at_mut_checked(k + 1)?;
        let (xtop, xrest) = x.split_at_mut_checked(k + 1)?;
        let (prow, xk) = (top.last()?, *xtop.last()?);
        let piv = *prow.get(k)?;
        for (row, xr) in rest.iter_mut().zip(xrest.iter_mut()) {
            let f = *row.get(k)? / piv;
            if f == T::zero() {
                continue;
            }
            for (e, pk) in row.get_mut(k..)?.iter_mut().zip(prow.get(k..)?) {
                *e -= f * *pk;
            }
            *xr -= f * xk;
        }
    }
    for k in (0..N).rev() {
        let row = m.get(k)?;
        let mut s = *x.get(k)?;
        for (e, xc) in row.get(k + 1..)?.iter().zip(x.get(k + 1..)?) {
            s -= *e * *xc;
        }
        *x.get_mut(k)? = s / *row.get(k)?;
    }
    Some(SVector::from(x))
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

/// LU factorisation with partial pivoting (Doolittle) of `a` (row-major), in place:
/// `P A = L U`, with `L` strictly below the diagonal (its unit diagonal implied) and
/// `U` on and above it, the rows in pivot order; `piv[k]` is the row swapped with row
/// `k` at step `k` (`k` itself for none). Rows whose entry in the pivot column is zero
/// are left alone (a group's sparse Jacobian costs little more than its fill-in).
/// Returns the determinant, or `None` if a pivot vanishes or is not finite (`a` and
/// `piv` are then partly overwritten). Bounded work: `N³/3` multiply-adds at most, no
/// iteration; the size is a constant, so the loops unroll (a group's `W`, `N` ≤ 6).
/// With [`lu_solve`] (`N²` per right-hand side, as a product by the inverse) it
/// replaces an inverse (`N³`) where a matrix serves a few solves.
pub fn lu<T: Real, const N: usize>(a: &mut [[T; N]; N], piv: &mut [u8; N]) -> Option<T> {
    let mut det = T::one();
    for k in 0..N {
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
            det = -det;
        }
        *piv.get_mut(k)? = p as u8;
        let prow = *a.get(k)?;
        let d = *prow.get(k)?;
        det *= d;
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
    }
    det.finite().then_some(det)
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
