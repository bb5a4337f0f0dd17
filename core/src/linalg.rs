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

/// Inverts the top-left `n × n` block of `a` by Gauss-Jordan elimination with partial
/// pivoting; the rest of the result is the identity. Returns the inverse and the
/// block's determinant, or `None` if a pivot vanishes or is not finite. Bounded work:
/// `n³` multiply-adds, no iteration (a group's Jacobian `W`, `n` ≤ 6).
pub fn invert<T: Real, const N: usize>(
    a: SMatrix<T, N, N>,
    n: usize,
) -> Option<(SMatrix<T, N, N>, T)> {
    let n = n.min(N);
    let mut m = rows(&a);
    let mut inv = [[T::zero(); N]; N];
    for (k, row) in inv.iter_mut().enumerate() {
        if let Some(e) = row.get_mut(k) {
            *e = T::one();
        }
    }
    let mut det = T::one();
    for k in 0..n {
        let p = pivot(&m, k, n)?;
        if p != k {
            swap(&mut m, k, p);
            swap(&mut inv, k, p);
            det = -det;
        }
        let (mk, ik) = (m.get_mut(k)?, inv.get_mut(k)?);
        let piv = *mk.get(k)?;
        det *= piv;
        let ip = T::one() / piv;
        for (e, i) in mk.get_mut(..n)?.iter_mut().zip(ik.get_mut(..n)?) {
            *e *= ip;
            *i *= ip;
        }
        let (mk, ik) = (*mk, *ik);
        let (mk, ik) = (mk.get(..n)?, ik.get(..n)?);
        for (r, (row, irow)) in m
            .get_mut(..n)?
            .iter_mut()
            .zip(inv.get_mut(..n)?)
            .enumerate()
        {
            if r == k {
                continue;
            }
            let f = *row.get(k)?;
            if f == T::zero() {
                continue;
            }
            for (e, pe) in row.get_mut(..n)?.iter_mut().zip(mk) {
                *e -= f * *pe;
            }
            for (i, pi) in irow.get_mut(..n)?.iter_mut().zip(ik) {
                *i -= f * *pi;
            }
        }
    }
    if !det.finite() {
        return None;
    }
    let at = |r: usize, c: usize| inv.get(r).and_then(|row| row.get(c)).copied();
    Some((SMatrix::from_fn(|r, c| at(r, c).unwrap_or(T::zero())), det))
}
