//! A group's Jacobian `W = ∂f/∂x` from its cached terms (the general path, and the
//! all-arm path of the triad and the general Assur group in one pass), and its factors:
//! a dyad's closed-form inverse, a larger group's LU with its conditioning.

use super::*;
/// Sets `w` to `N × N` zeros with the identity past the top-left `n × n` block: the
/// padding of a group's `W` (whose live block the caller then fills).
#[inline]
pub(super) fn zero_padded<T: Real, const N: usize>(w: &mut [[T; N]; N], n: usize) {
    for (k, row) in w.iter_mut().enumerate() {
        for (c, e) in row.iter_mut().enumerate() {
            *e = if k >= n && c == k {
                T::one()
            } else {
                T::zero()
            };
        }
    }
}

/// The Jacobian `W = ∂f/∂x` from the cached terms into `w`, as `N × N` rows: the
/// top-left `n × n` block, identity padding past it (`N = 2` for a dyad, 4 for the
/// triad, [`MAX_GROUP_VARS`] for the larger groups).
#[inline]
pub(crate) fn jacobian<T: Real, const N: usize>(
    g: &Group<T>,
    gd: &GroupData<T>,
    w: &mut [[T; N]; N],
) {
    zero_padded(w, g.n_vars as usize);
    for (ci, (ch, row)) in g.chains.iter().zip(gd.cache.iter()).enumerate() {
        if ch.end.is_none() {
            continue;
        }
        let Some([wx, wy]) = w.get_mut(2 * ci..2 * ci + 2) else {
            continue;
        };
        for (t, c) in ch.terms.iter().zip(row.iter()) {
            term_columns(t, c, |k, col| {
                if let Some(e) = wx.get_mut(k as usize) {
                    *e += col.x;
                }
                if let Some(e) = wy.get_mut(k as usize) {
                    *e += col.y;
                }
            });
        }
    }
}

/// The terms of a group whose chains all close and whose terms are all arms turned
/// by one unknown each, without offset (the triad's and a general Assur group's, as
/// their builders make them): each term's unknown `k` and link vector `v`, read from
/// the group once per solve. Its evaluation ([`Arms::eval`]) is [`eval_terms`],
/// [`residual`] and [`jacobian`] in one pass without their per-term matches, to the
/// same bits (an arm's value is `R(θ_k) v`, its column of `W` is `J R(θ_k) v`).
pub(crate) struct Arms<T: Real> {
    /// Unknown `n` of the group (2 per chain).
    n: usize,
    /// Per chain: how many terms.
    len: [u8; MAX_CHAINS],
    /// Per chain and term: the unknown that turns it.
    var: [[u8; MAX_TERMS]; MAX_CHAINS],
    /// Per chain and term: the vector it turns (link frame, m).
    v: [[Vec2<T>; MAX_TERMS]; MAX_CHAINS],
}

impl<T: Real> Arms<T> {
    /// The group's arms, or `None` if a chain is open, a term is a slide, or an angle
    /// is not an unknown alone (the general path then serves it).
    pub(crate) fn of(g: &Group<T>) -> Option<Self> {
        let n = g.n_vars as usize;
        if n == 0 || 2 * g.chains.len() != n {
            return None;
        }
        let mut a = Arms {
            n,
            len: [0; MAX_CHAINS],
            var: [[0; MAX_TERMS]; MAX_CHAINS],
            v: [[Vec2::zeros(); MAX_TERMS]; MAX_CHAINS],
        };
        let unturned = Vec2::new(T::one(), T::zero());
        for (ch, ((len, var), v)) in g
            .chains
            .iter()
            .zip(a.len.iter_mut().zip(a.var.iter_mut()).zip(a.v.iter_mut()))
        {
            ch.end?;
            for (t, (ak, av)) in ch.terms.iter().zip(var.iter_mut().zip(v.iter_mut())) {
                let Term::Arm {
                    angle:
                        Angle {
                            base: Base::Var(k),
                            offset_cs,
                            ..
                        },
                    v: tv,
                } = t
                else {
                    return None;
                };
                if *offset_cs != unturned || *k as usize >= n {
                    return None;
                }
                (*ak, *av) = (*k, *tv);
            }
            *len = ch.terms.len() as u8;
        }
        Some(a)
    }

    /// Evaluates the terms at the unknowns' cosines and sines `gd.trig` into
    /// `gd.cache`, writes `W` into `w` (as [`jacobian`]) and returns the residual (as
    /// [`residual`], `gaps` from [`chain_gaps`]).
    pub(crate) fn eval<const N: usize>(
        &self,
        gd: &mut GroupData<T>,
        gaps: &[Vec2<T>; MAX_CHAINS],
        w: &mut [[T; N]; N],
    ) -> GroupVector<T> {
        zero_padded(w, self.n);
        let mut f = GroupVector::zeros();
        let GroupData { trig, cache, .. } = gd;
        for (ci, ((((len, var), v), gap), row)) in self
            .len
            .iter()
            .zip(self.var.iter())
            .zip(self.v.iter())
            .zip(gaps.iter())
            .zip(cache.iter_mut())
            .enumerate()
            .take(self.n / 2)
        {
            let Some([wx, wy]) = w.get_mut(2 * ci..2 * ci + 2) else {
                continue;
            };
            let mut r = *gap;
            for ((k, v), c) in var
                .iter()
                .zip(v.iter())
                .zip(row.iter_mut())
                .take(*len as usize)
            {
                let k = *k as usize;
                let cs = trig
                    .get(k)
                    .copied()
                    .unwrap_or(Vec2::new(T::one(), T::zero()));
                let t = rotate_cs(cs.x, cs.y, v);
                *c = TermCache { w: t, s: T::zero() };
                r += t;
                let col = perp(&t);
                if let Some(e) = wx.get_mut(k) {
                    *e += col.x;
                }
                if let Some(e) = wy.get_mut(k) {
                    *e += col.y;
                }
            }
            set2(&mut f, ci, r);
        }
        f
    }
}

/// Factors `W` into `gd.w_fact` (a dyad's inverse, a larger group's LU factors) and
/// measures its conditioning; a dead point is an error (and leaves `gd.w_fact` as it
/// was).
pub(crate) fn factor<T: Real>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    // n is even (two rows per closing chain): each size with its own fixed matrices.
    match g.n_vars {
        0 => {
            gd.conditioning = T::one();
            Ok(T::one())
        }
        2 => factor_n::<T, 2>(g, gd, singular_tol),
        4 => factor_n::<T, 4>(g, gd, singular_tol),
        _ => factor_n::<T, MAX_GROUP_VARS>(g, gd, singular_tol),
    }
}

/// [`factor`] for `n = N` unknowns.
fn factor_n<T: Real, const N: usize>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    let mut w = [[T::zero(); N]; N];
    jacobian(g, gd, &mut w);
    factor_w(&w, gd, singular_tol)
}

/// [`factor`] of a `W` already built (`N` rows, the size [`factor`] picks for the
/// group's `n`).
pub(super) fn factor_w<T: Real, const N: usize>(
    w: &[[T; N]; N],
    gd: &mut GroupData<T>,
    singular_tol: T,
) -> Result<T, GroupFault> {
    // The product of W's column norms (identity padding: 1 each), for the conditioning.
    let mut norms = T::one();
    for c in 0..N {
        let mut sq = T::zero();
        for row in w.iter() {
            let v = row.get(c).copied().unwrap_or(T::zero());
            sq += v * v;
        }
        norms *= sq.root();
    }
    // A dyad's 2×2 inverse in closed form; larger groups by LU (n³/3, where an
    // inverse costs n³: W is used for the 2 or 3 solves of the linear passes only).
    let mut fact = *w;
    let mut piv = [0u8; N];
    let det = match (N, w.first(), w.get(1)) {
        (2, Some(r0), Some(r1)) => {
            let e = |r: &[T; N], c: usize| r.get(c).copied().unwrap_or(T::zero());
            let (a, b, c, d) = (e(r0, 0), e(r0, 1), e(r1, 0), e(r1, 1));
            let det = a * d - b * c;
            let id = T::one() / det;
            for (k, v) in [d * id, -b * id, -c * id, a * id].into_iter().enumerate() {
                if let Some(x) = fact.get_mut(k / 2).and_then(|r| r.get_mut(k % 2)) {
                    *x = v;
                }
            }
            det
        }
        // A failed factorisation (a vanishing pivot) is a dead point: det 0.
        // (On the whole N × N matrix: its padding is the identity.)
        _ => crate::linalg::lu(&mut fact, &mut piv).unwrap_or(T::zero()),
    };
    let cond = if norms > T::zero() {
        det.abs() / norms
    } else {
        T::zero()
    };
    gd.conditioning = cond;
    if !(cond > singular_tol) {
        return Err(GroupFault::Singular {
            conditioning: cond.to_f64(),
        });
    }
    for (dst, src) in gd.w_fact.iter_mut().zip(fact.iter()) {
        for (e, v) in dst.iter_mut().zip(src.iter()) {
            *e = *v;
        }
    }
    gd.w_piv = pack_pivots(&piv);
    Ok(det)
}
