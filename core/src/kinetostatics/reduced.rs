//! The equilibrium of a group whose links each have at most one outer joint (the triad,
//! the six-link Assur group) by block elimination, the dyad's closed form generalized
//! ([`Equilibrium::reduced`]). One function serves both shapes: the system is assembled
//! at the largest size and solved at the shape's own ([`solve_at`]).

use super::{cramer, Equilibrium, GROUP_ROWS};
use crate::config::MAX_GROUP_JOINTS;
use crate::config::MAX_GROUP_LINKS;
use crate::scalar::{cross, Real};
use crate::structomat::Group;
use nalgebra::Vector3;

impl<T: Real> Equilibrium<T> {
    /// A group each of whose links has at most one outer joint (to an earlier body),
    /// of 2 unknowns (the triad, the six-link Assur group), by block elimination, the
    /// dyad's method generalized. Each link `p` may eliminate one joint `e` of 2
    /// unknowns from its equilibrium `W_e λ_e + Σ_k W_k λ_k = -L`: its outer joint,
    /// or, for a link without one that has exactly two joints (a rod), one of them.
    /// It keeps only the row `n = w_e1 × w_e2`, which does not see `e` (the moment
    /// about a revolute joint), and its other rows give `λ_e` by Cramer with `n`
    /// completing `W_e`'s columns (`n`'s coefficient comes out zero to rounding): for a
    /// rod, `λ_e = β + K λ_a` in its other joint `a`'s unknowns, substituted into the
    /// equilibrium of `e`'s other link. A link that eliminates nothing keeps its 3
    /// rows. The kept rows (3 × links - 2 × eliminated joints) determine the other
    /// inner joints' unknowns as a small sparse system: 6 for the triad instead of 12,
    /// 8 for the six-link group instead of 18. A link's one kept row that sees one
    /// inner joint only (the moment about a binary link's outer joint, or about a
    /// rod's eliminated end) leaves that joint one unknown `μ` (see [`Param`]): 3 of
    /// the triad's 6 rows, 4 of the six-link group's 8 are of this kind, and the
    /// system left is 3 × 3 and 4 × 4 (`≤ small`; else none is taken out and the system
    /// is solved whole, at `whole`). Then the rods' joints, then the outer joints,
    /// `W_o λ_o = -L - Σ (the inner reactions' wrenches)`. `None` if the group is not
    /// of this shape (the dense system then solves it), `Some(false)` if it is
    /// singular (a one-joint row of zeros leaves non-finite values instead, which
    /// [`reactions`](super::reactions) reports alike).
    #[inline(never)]
    pub(super) fn reduced(&mut self, g: &Group<T>, size: Sizes) -> Option<bool> {
        // One copy of this function for both shapes (its structural part is the bulk of
        // the code): the system is assembled at the largest size and solved at the
        // shape's own (`solve_at`), the same sizes, hence the same bits, as before.
        let Sizes { whole, small } = size;
        let links = g.placements.len();
        let nj = g.joints.len();
        // Per joint: its link `i`'s index, its other body's (`None`: an earlier body),
        // its first unknown's index in `λ`. Per link: its outer joint, and the inner
        // joints on it (how many, the first two).
        let mut on = [(0, None); MAX_GROUP_JOINTS];
        let mut first = [0; MAX_GROUP_JOINTS];
        let mut outer = [None; MAX_GROUP_LINKS];
        let mut touch = [(0, [0; 2]); MAX_GROUP_LINKS];
        let mut full = 0;
        for (k, ((jt, u), (o, f))) in g
            .joints
            .iter()
            .zip(&self.joints)
            .zip(on.iter_mut().zip(&mut first))
            .enumerate()
        {
            let i = self.link_of(jt.i)?;
            let j = self.link_of(jt.j);
            *o = (i, j);
            *f = full;
            full += u.n;
            match j {
                Some(j) if j == i => return None,
                Some(j) => {
                    for l in [i, j] {
                        let (count, ks) = touch.get_mut(l)?;
                        if let Some(slot) = ks.get_mut(*count) {
                            *slot = k;
                        }
                        *count += 1;
                    }
                }
                None if u.n == 2 => {
                    if outer.get_mut(i)?.replace(k).is_some() {
                        return None;
                    }
                }
                None => return None,
            }
        }
        let two = |k: usize| self.joints.get(k).is_some_and(|u| u.n == 2);
        let other = |k: usize, p: usize| {
            on.get(k)
                .and_then(|(i, j)| if *i == p { *j } else { Some(*i) })
        };
        // The rods' choices: `rod[k] = Some((p, a))` if joint `k` is eliminated by rod
        // `p` whose other joint is `a` (kept: never eliminated itself). Eliminating the
        // joint whose other link keeps one row makes the substitution one row.
        let mut rod = [None; MAX_GROUP_JOINTS];
        let mut kept = [false; MAX_GROUP_JOINTS];
        let mut elim = outer;
        for (p, (e, (count, [k1, k2]))) in elim.iter_mut().zip(&touch).enumerate().take(links) {
            if e.is_some() || *count != 2 || !two(*k1) || !two(*k2) {
                continue;
            }
            let free = |e: usize, a: usize| {
                let (Some(re), Some(ra), Some(ke)) = (rod.get(e), rod.get(a), kept.get(e)) else {
                    return false;
                };
                re.is_none() && ra.is_none() && !ke
            };
            let one_row =
                |e: usize| other(e, p).is_some_and(|q| outer.get(q).is_some_and(|o| o.is_some()));
            let choice = [(*k2, *k1), (*k1, *k2)]
                .into_iter()
                .filter(|(e, a)| free(*e, *a))
                .max_by_key(|(e, _)| one_row(*e));
            if let Some((ke, ka)) = choice {
                if let (Some(r), Some(kp)) = (rod.get_mut(ke), kept.get_mut(ka)) {
                    *r = Some((p, ka));
                    *kp = true;
                }
                *e = Some(ke);
            }
        }
        // The links whose one kept row sees one kept joint only (of 2 unknowns) and
        // no rod's substitution: `par[k] = Some(p)` if link `p`'s row parametrizes
        // joint `k` (see `Param`). Per link: the kept joints it sees (how many, the
        // last), a rod's substitution counting as more than one.
        let mut seen = [(0, 0); MAX_GROUP_LINKS];
        for (k, (r, (i, j))) in rod.iter().zip(&on).enumerate().take(nj) {
            let Some(j) = j else {
                continue;
            };
            let (links, add) = match r {
                None => ([*i, *j], 1),
                Some((p, _)) => ([if i == p { *j } else { *i }, MAX_GROUP_LINKS], 2),
            };
            for l in links {
                if let Some((count, last)) = seen.get_mut(l) {
                    *count += add;
                    *last = k;
                }
            }
        }
        let mut par = [None; MAX_GROUP_JOINTS];
        let mut single = [false; MAX_GROUP_LINKS];
        for (p, ((e, s), sn)) in elim
            .iter()
            .zip(&mut single)
            .zip(&seen)
            .enumerate()
            .take(links)
        {
            if let (Some(_), (1, k)) = (e, sn) {
                if let (true, Some(slot @ None)) = (two(*k), par.get_mut(*k)) {
                    *slot = Some(p);
                    *s = true;
                }
            }
        }
        // Columns: the kept inner joints' unknowns (one, `μ`, for a parametrized
        // joint). The parametrization pays when it leaves a system of at most `small`
        // unknowns; otherwise none is made.
        let mut col = [0; MAX_GROUP_JOINTS];
        let mut m = 0;
        for pass in 0..2 {
            m = 0;
            for ((c, k), (u, pk)) in col
                .iter_mut()
                .zip(0..)
                .zip(self.joints.iter().zip(&par))
                .take(nj)
            {
                *c = m;
                if on.get(k).is_some_and(|(_, j)| j.is_some())
                    && rod.get(k).is_some_and(|r| r.is_none())
                {
                    m += if pk.is_some() { 1 } else { u.n };
                }
            }
            if m <= small || pass == 1 {
                break;
            }
            par = [None; MAX_GROUP_JOINTS];
            single = [false; MAX_GROUP_LINKS];
        }
        // Per link: its first kept row and, if it eliminates a joint, that joint's
        // wrench columns on it (as acting on it) and `n`.
        let mut proj = [(0, None); MAX_GROUP_LINKS];
        let mut rows = 0;
        for (p, ((pr, e), cog)) in proj
            .iter_mut()
            .zip(&elim)
            .zip(&self.cog)
            .enumerate()
            .take(links)
        {
            let w = e.and_then(|e| {
                let u = self.joints.get(e)?;
                let sign = if on.get(e)?.0 == p {
                    T::one()
                } else {
                    -T::one()
                };
                let w = u.wrenches(*cog).map(|w| w * sign);
                Some((w, w[0].cross(&w[1])))
            });
            *pr = (rows, w);
            rows += match (w.is_some(), single.get(p)) {
                (_, Some(true)) => 0,
                (true, _) => 1,
                (false, _) => 3,
            };
        }
        if rows != m || m > whole {
            return None;
        }
        // The parametrized joints: `λ_k = t + μ d` from their link's row.
        let mut param = [Param::default(); MAX_GROUP_JOINTS];
        for (k, (pk, pm)) in par.iter().zip(&mut param).enumerate().take(nj) {
            let Some(p) = pk else {
                continue;
            };
            let (Some(u), Some((i, _)), Some((_, Some((_, n)))), Some(cog), Some(load)) = (
                self.joints.get(k),
                on.get(k),
                proj.get(*p),
                self.cog.get(*p),
                self.load.get(*p),
            ) else {
                return None;
            };
            // The row `n · (±W_k λ_k) = -n · L_p` (`+` on the joint's link `i`).
            let sign = if i == p { T::one() } else { -T::one() };
            let [w0, w1] = u.wrenches(*cog);
            *pm = Param::of(n.dot(&w0) * sign, n.dot(&w1) * sign, -n.dot(load));
        }
        // A rod's eliminated joint: `λ_e = β + K λ_a` (columns of `K`: per unknown of `a`).
        let mut aff = [(Vector3::zeros(), [Vector3::zeros(); 2]); MAX_GROUP_JOINTS];
        for (r, af) in rod.iter().zip(&mut aff).take(nj) {
            let Some((p, a)) = r else {
                continue;
            };
            let (Some((_, Some((w, n)))), Some(cog), Some(load), Some(ua), Some((ia, _))) = (
                proj.get(*p),
                self.cog.get(*p),
                self.load.get(*p),
                self.joints.get(*a),
                on.get(*a),
            ) else {
                return None;
            };
            let sign = if ia == p { -T::one() } else { T::one() };
            let wa = ua.wrenches(*cog);
            let c = [w[0], w[1], *n];
            let beta = Vector3::from(cramer(&c, &-*load));
            *af = (
                beta,
                // (No index into `wa`: at opt-level "s" the map over [0, 1] kept its
                // bounds check, a panic path the firmware check refuses.)
                wa.map(|w| Vector3::from(cramer(&c, &(w * sign)))),
            );
        }
        // `A x = b`: per link's kept rows, `-L` and the kept inner joints' wrench
        // columns (`+W` on the joint's link `i`, `-W` on the other), and each rod's
        // eliminated joint substituted into its other link.
        let mut a = [[T::zero(); REDUCED_MAX]; REDUCED_MAX];
        let mut b = [T::zero(); REDUCED_MAX];
        // A wrench's entries in a link's kept rows (from its first): `n · v`, or `v`.
        let project = |n: Option<&Vector3<T>>, v: &Vector3<T>| match n {
            Some(n) => ([n.dot(v), T::zero(), T::zero()], 1),
            None => ([v.x, v.y, v.z], 3),
        };
        for (((r0, w), load), s) in proj.iter().zip(&self.load).zip(&single).take(links) {
            if *s {
                continue;
            }
            let (e, rows) = project(w.as_ref().map(|(_, n)| n), &-*load);
            for (x, e) in b.iter_mut().skip(*r0).take(rows).zip(e) {
                *x = e;
            }
        }
        // Where kept joint `k`'s unknown `c` goes (see `put`).
        let target = |k: usize, c: usize| {
            let c0 = col.get(k).copied().unwrap_or(REDUCED_MAX);
            match param.get(k) {
                Some(pm) if pm.on => (c0, Some(pm.at(c))),
                _ => (c0 + c, None),
            }
        };
        for (k, ((u, (i, j)), (r, af))) in self
            .joints
            .iter()
            .zip(&on)
            .zip(rod.iter().zip(aff.iter()))
            .enumerate()
            .take(nj)
        {
            let Some(j) = j else {
                continue;
            };
            for (link, neg) in [(*i, false), (*j, true)] {
                let (Some((r0, w)), Some(cog), Some(false)) =
                    (proj.get(link), self.cog.get(link), single.get(link))
                else {
                    continue;
                };
                let n = w.as_ref().map(|(_, n)| n);
                let mut wk = u.wrenches(*cog);
                if neg {
                    wk = wk.map(|v| -v);
                }
                match r {
                    None => {
                        for (c, v) in wk.iter().take(u.n).enumerate() {
                            let (e, rows) = project(n, v);
                            put(&mut a, &mut b, (*r0, rows), e, target(k, c));
                        }
                    }
                    Some((p, _)) if *p == link => {}
                    Some((_, ka)) => {
                        let (beta, kk) = af;
                        let rhs = wk[0] * beta.x + wk[1] * beta.y;
                        let (e, rows) = project(n, &rhs);
                        for (x, e) in b.iter_mut().skip(*r0).take(rows).zip(e) {
                            *x -= e;
                        }
                        for (c, kc) in kk.iter().enumerate() {
                            let v = wk[0] * kc.x + wk[1] * kc.y;
                            let (e, rows) = project(n, &v);
                            put(&mut a, &mut b, (*r0, rows), e, target(*ka, c));
                        }
                    }
                }
            }
        }
        // Solved at a constant size (`small` if it fits, else `whole`): see `solve_at`.
        let size = if m <= small { small } else { whole };
        let solved = match size {
            0..=3 => solve_at::<T, 3>(&a, &mut b, m),
            4 => solve_at::<T, 4>(&a, &mut b, m),
            5..=6 => solve_at::<T, 6>(&a, &mut b, m),
            _ => solve_at::<T, REDUCED_MAX>(&a, &mut b, m),
        };
        if !solved {
            return Some(false);
        }
        // The kept inner joints' unknowns, then the rods' eliminated ones.
        for ((u, ((_, j), r)), ((f0, c0), pm)) in self
            .joints
            .iter()
            .zip(on.iter().zip(&rod))
            .zip(first.iter().zip(&col).zip(&param))
            .take(nj)
        {
            if j.is_none() || r.is_some() {
                continue;
            }
            if pm.on {
                let mu = b.get(*c0).copied().unwrap_or(T::zero());
                for (o, c) in self.lam.iter_mut().skip(*f0).zip(0..2) {
                    let (t, d) = pm.at(c);
                    *o = t + mu * d;
                }
                continue;
            }
            for (o, v) in self
                .lam
                .iter_mut()
                .skip(*f0)
                .zip(b.iter().skip(*c0))
                .take(u.n)
            {
                *o = *v;
            }
        }
        for ((r, (beta, kk)), f0) in rod.iter().zip(&aff).zip(&first).take(nj) {
            let Some((_, ka)) = r else {
                continue;
            };
            let fa = first.get(*ka).copied().unwrap_or(GROUP_ROWS);
            let (Some(x0), Some(x1)) = (self.lam.get(fa), self.lam.get(fa + 1)) else {
                return None;
            };
            let l = *beta + kk[0] * *x0 + kk[1] * *x1;
            for (o, v) in self.lam.iter_mut().skip(*f0).zip([l.x, l.y]) {
                *o = v;
            }
        }
        // Each inner reaction's wrench on a link with an outer joint into that link's
        // right-hand side `-L - Σ ±W λ`; then the outer joints.
        let mut rhs = [Vector3::zeros(); MAX_GROUP_LINKS];
        for (r, l) in rhs.iter_mut().zip(&self.load) {
            *r = -*l;
        }
        for ((u, (i, j)), f0) in self.joints.iter().zip(&on).zip(&first).take(nj) {
            let Some(j) = j else {
                continue;
            };
            let r = u.reaction(self.lam.get(*f0..).unwrap_or(&[]));
            for (link, sign) in [(*i, T::one()), (*j, -T::one())] {
                let (Some(Some(_)), Some(cog), Some(rl)) =
                    (outer.get(link), self.cog.get(link), rhs.get_mut(link))
                else {
                    continue;
                };
                let f = r.force * sign;
                let mom = (r.moment + cross(&(u.at - *cog), &r.force)) * sign;
                *rl -= Vector3::new(f.x, f.y, mom);
            }
        }
        for ((o, (_, w)), rl) in outer.iter().zip(&proj).zip(&rhs).take(links) {
            let (Some(k), Some((wo, n))) = (o, w) else {
                continue;
            };
            let Some(f0) = first.get(*k) else {
                continue;
            };
            let [x, y, _] = cramer(&[wo[0], wo[1], *n], rl);
            for (o, v) in self.lam.iter_mut().skip(*f0).zip([x, y]) {
                *o = v;
            }
        }
        Some(true)
    }
}

/// The largest reduced system (the six-link group's 8 inner unknowns).
const REDUCED_MAX: usize = 8;

/// The sizes a group's reduced system is solved at: `whole` (≤ [`REDUCED_MAX`]) when
/// the one-joint rows cannot be taken out, `small` when they are.
#[derive(Clone, Copy)]
pub(super) struct Sizes {
    pub(super) whole: usize,
    pub(super) small: usize,
}

/// Solves the leading `m × m` block of `A x = b` at the constant size `S ≥ m`, `x`
/// into `b`; `false` if it is singular. Rows and columns past `m` are identity: the
/// elimination then unrolls and bounds-checks once (half the instructions of a
/// run-time size); the padding neither pivots (zero in the live columns) nor changes a
/// live entry (`x - f · 0`).
#[inline(never)]
fn solve_at<T: Real, const S: usize>(
    a: &[[T; REDUCED_MAX]; REDUCED_MAX],
    b: &mut [T; REDUCED_MAX],
    m: usize,
) -> bool {
    let mut sa = [[T::zero(); S]; S];
    let mut sb = [T::zero(); S];
    for (((r, srow), sx), (row, x)) in sa
        .iter_mut()
        .enumerate()
        .zip(&mut sb)
        .zip(a.iter().zip(b.iter()))
    {
        for (y, v) in srow.iter_mut().zip(row) {
            *y = *v;
        }
        *sx = *x;
        if let (true, Some(e)) = (r >= m, srow.get_mut(r)) {
            *e = T::one();
        }
    }
    if !crate::linalg::solve_in_place(&mut sa, &mut sb) {
        return false;
    }
    for (x, v) in b.iter_mut().zip(sb) {
        *x = v;
    }
    true
}

/// A kept joint of 2 unknowns whose link's one kept row `a_0 λ_0 + a_1 λ_1 = β` sees
/// no other unknown: that row leaves it one degree of freedom, `λ = t + μ d` with
/// `t = β a / |a|²` (the row's solution nearest zero) and `d = a^⊥ = (-a_1, a_0)`, so
/// that it takes one column (`μ`) and its row none in the reduced system.
#[derive(Clone, Copy)]
struct Param<T: Real> {
    /// Whether the joint is parametrized.
    on: bool,
    /// Per unknown, `(t_c, d_c)`.
    td: [(T, T); 2],
}

impl<T: Real> Default for Param<T> {
    fn default() -> Self {
        Self {
            on: false,
            td: [(T::zero(), T::zero()); 2],
        }
    }
}

impl<T: Real> Param<T> {
    /// From the row `a_0 λ_0 + a_1 λ_1 = β`.
    fn of(a0: T, a1: T, beta: T) -> Self {
        let s = a0 * a0 + a1 * a1;
        Self {
            on: true,
            td: [(a0 * beta / s, -a1), (a1 * beta / s, a0)],
        }
    }

    /// `(t_c, d_c)` of unknown `c` (0 or 1).
    fn at(&self, c: usize) -> (T, T) {
        self.td.get(c).copied().unwrap_or((T::zero(), T::zero()))
    }
}

/// A kept joint's unknown with entries `e` in the rows `r0..r0 + rows` of the reduced
/// system: into its column `cc`, or, parametrized (`f = (t_c, d_c)`), `d_c` times
/// them into its `μ` column `cc` and `t_c` times them out of the right-hand side.
#[inline(always)]
fn put<T: Real, const N: usize>(
    a: &mut [[T; N]; N],
    b: &mut [T; N],
    (r0, rows): (usize, usize),
    e: [T; 3],
    (cc, f): (usize, Option<(T, T)>),
) {
    for (r, e) in (r0..r0 + rows).zip(e) {
        let (Some(y), Some(x)) = (a.get_mut(r).and_then(|row| row.get_mut(cc)), b.get_mut(r))
        else {
            continue;
        };
        match f {
            Some((t, d)) => {
                *y += e * d;
                *x -= e * t;
            }
            None => *y += e,
        }
    }
}
