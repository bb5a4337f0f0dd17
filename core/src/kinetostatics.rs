//! Kinetostatics (SPEC 1, thesis 3.3): with `q, q̇, q̈` known, the d'Alembert inertia
//! loads `(-m a_G, -I_G α)` are added to the applied loads and each group's equilibrium
//! (3 equations per link) is solved for its joint reactions, walking the sequence
//! backwards (last group first). A group's reactions on the bodies of earlier groups
//! are loads of those groups. A motor element's driver joint yields the driving torque
//! (or force) that the motion requires.
//!
//! Applied motor torques are *not* among the loads: the driving torques are unknowns,
//! so that in a forward-dynamics run they must come out equal to the applied ones.
//!
//! The equilibrium of a group is solved by its structure:
//! - a motor element (one link, 3 unknowns) by Cramer's rule;
//! - a dyad (two links, each with one outer joint, and the middle joint between them,
//!   2 unknowns each) in closed form: each link's moment equation about its outer joint
//!   gives the middle joint's reaction (a 2 × 2 system), then each link's remaining
//!   equations its outer joint's;
//! - a group whose links each have at most one outer joint (the triad, the six-link
//!   Assur group) by block elimination, the dyad's method generalized (see
//!   `Equilibrium::reduced`): a small sparse system in the inner joints' unknowns
//!   (6 for the triad, 8 for the six-link group), of which the rows that see one
//!   joint only are taken out first (leaving 3 and 4), then back-substitution;
//! - any other group as one dense system.

use crate::capacity::Capacity;
use crate::config::{MAX_BODIES, MAX_GROUP_JOINTS, MAX_GROUP_LINKS, POSE_ROWS};
use crate::dynamics::{add_load, link_acceleration, loads_without_motors};
use crate::error::{GroupFault, StepError};
use crate::kinematics::group_id;
use crate::model::Model;
use crate::scalar::{cross, perp, rotate_cs, Real, Vec2};
use crate::structomat::{Group, Joint, JointKind};
use crate::workspace::{Reaction, Workspace};
use nalgebra::{SMatrix, SVector, Vector3};

/// Loads on each body without the motors: gravity, constant and caller-set loads, and
/// inertia (`F - M a_G`, live rows only).
fn free_body_loads<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &Workspace<T, C>,
) -> SVector<T, POSE_ROWS> {
    let mut f = SVector::<T, POSE_ROWS>::zeros();
    loads_without_motors(model, &ws.body, &ws.applied_moment, &mut f);
    for (i, (l, rows)) in model
        .links()
        .iter()
        .zip(f.as_mut_slice().chunks_exact_mut(3))
        .enumerate()
    {
        let acc = link_acceleration(ws, model.dof(), i as u8 + 1);
        for ((e, m), a) in rows.iter_mut().zip([l.mass, l.mass, l.inertia]).zip(acc) {
            *e -= m * a;
        }
    }
    f
}

/// A joint's reaction unknowns at the workspace's pose: where it acts and, per unknown,
/// the unit force (world) and moment it stands for. The reaction on `i` (from `j`) is
/// `Σ_k λ_k units_k`, the one on `j` its opposite.
#[derive(Clone, Copy)]
struct Unknowns<T: Real> {
    /// The joint point, world.
    at: Vec2<T>,
    /// Unit force and moment of each unknown (the first `n` are used).
    units: [(Vec2<T>, T); 2],
    /// Number of unknowns (1 or 2).
    n: usize,
}

impl<T: Real> Unknowns<T> {
    /// The unknowns of joint `jt`: a revolute's force `(F_x, F_y)`; a prismatic's force
    /// normal to the guide and moment; a driver's torque, or force along its guide.
    fn of<C: Capacity<T>>(ws: &Workspace<T, C>, jt: &Joint<T>) -> Self {
        let bi = ws.body.get(jt.i as usize).copied().unwrap_or_default();
        let bj = ws.body.get(jt.j as usize).copied().unwrap_or_default();
        let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
        let x = Vec2::new(T::one(), T::zero());
        let y = Vec2::new(T::zero(), T::one());
        let z = Vec2::zeros();
        let (units, n) = match jt.kind {
            JointKind::Revolute => ([(x, T::zero()), (y, T::zero())], 2),
            JointKind::Prismatic { dir } => {
                let u = rotate_cs(bj.c, bj.s, &dir);
                ([(perp(&u), T::zero()), (z, T::one())], 2)
            }
            JointKind::DriveTorque => ([(z, T::one()), (z, T::zero())], 1),
            JointKind::DriveForce { dir } => {
                let u = rotate_cs(bj.c, bj.s, &dir);
                ([(u, T::zero()), (z, T::zero())], 1)
            }
        };
        Self { at, units, n }
    }

    /// The wrench `(F_x, F_y, M_G)` of each unit on a body whose COG is at `cog` (the
    /// force at the joint reduced to the COG): the columns of its equilibrium.
    fn wrenches(&self, cog: Vec2<T>) -> [Vector3<T>; 2] {
        self.units
            .map(|(f, m)| Vector3::new(f.x, f.y, m + cross(&(self.at - cog), &f)))
    }

    /// The reaction of unknowns `lam` (on `i`, from `j`).
    fn reaction(&self, lam: &[T]) -> Reaction<T> {
        let mut r = Reaction::default();
        for ((f, m), l) in self.units.iter().take(self.n).zip(lam) {
            r.force += *f * *l;
            r.moment += *m * *l;
        }
        r
    }
}

/// One group's equilibrium: per link (by placement) its COG and loads, per joint (in
/// the group's order) its unknowns, and the solution `λ` (a joint's unknowns
/// consecutive). One is set up and solved per group, reusing the buffers.
struct Equilibrium<T: Real> {
    /// Per body, its placement index in the group ([`NOT_IN_GROUP`] for the others).
    link: [u8; MAX_BODIES],
    cog: [Vec2<T>; MAX_GROUP_LINKS],
    load: [Vector3<T>; MAX_GROUP_LINKS],
    joints: [Unknowns<T>; MAX_GROUP_JOINTS],
    lam: [T; GROUP_ROWS],
}

impl<T: Real> Equilibrium<T> {
    fn new() -> Self {
        let none = Unknowns {
            at: Vec2::zeros(),
            units: [(Vec2::zeros(), T::zero()); 2],
            n: 0,
        };
        Self {
            link: [NOT_IN_GROUP; MAX_BODIES],
            cog: [Vec2::zeros(); MAX_GROUP_LINKS],
            load: [Vector3::zeros(); MAX_GROUP_LINKS],
            joints: [none; MAX_GROUP_JOINTS],
            lam: [T::zero(); GROUP_ROWS],
        }
    }

    /// The placement index of `body` in the group, if it is one of its links.
    fn link_of(&self, body: u8) -> Option<usize> {
        self.link
            .get(body as usize)
            .filter(|k| **k != NOT_IN_GROUP)
            .map(|k| *k as usize)
    }

    /// Sets up group `g`'s equilibrium at the workspace's pose under `loads`.
    fn set<C: Capacity<T>>(
        &mut self,
        model: &Model<T, C>,
        ws: &Workspace<T, C>,
        g: &Group<T>,
        loads: &SVector<T, POSE_ROWS>,
    ) {
        self.link = [NOT_IN_GROUP; MAX_BODIES];
        for (k, ((p, c), l)) in g
            .placements
            .iter()
            .zip(&mut self.cog)
            .zip(&mut self.load)
            .enumerate()
        {
            if let Some(e) = self.link.get_mut(p.link as usize) {
                *e = k as u8;
            }
            *c = ws.cog(model, p.link);
            let r = 3 * (p.link as usize).saturating_sub(1);
            if let Some([fx, fy, m]) = loads.as_slice().get(r..r + 3) {
                *l = Vector3::new(*fx, *fy, *m);
            }
        }
        for (k, u) in self.joints.iter_mut().enumerate() {
            match g.joints.get(k) {
                Some(jt) => *u = Unknowns::of(ws, jt),
                None => u.n = 0,
            }
        }
        self.lam = [T::zero(); GROUP_ROWS];
    }

    /// Solves for `λ` by the group's structure (see the module docs); `false` when the
    /// dense system is singular (the closed forms leave non-finite values instead).
    fn solve(&mut self, g: &Group<T>) -> bool {
        let links = g.placements.len();
        let unknowns: usize = self.joints.iter().map(|u| u.n).sum();
        let closed = match (links, unknowns) {
            (1, 3) => self.single_link(g),
            (2, 6) => self.dyad(g),
            _ => false,
        };
        if closed {
            return true;
        }
        // Reduced sizes: 6 covers the triad (4 links, 3 outer joints), 8 the six-link
        // group (3 outer joints, 2 rods); 3 and 4 once their one-joint rows are taken
        // out (each solved at that size: no padding to unroll); a group whose reduced
        // system is larger is solved dense.
        let reduced = match links {
            0..=4 => self.reduced(g, Sizes { whole: 6, small: 3 }),
            _ => self.reduced(g, Sizes { whole: 8, small: 4 }),
        };
        reduced.unwrap_or_else(|| match links {
            0..=2 => self.dense::<6>(g),
            3..=4 => self.dense::<12>(g),
            _ => self.dense::<GROUP_ROWS>(g),
        })
    }

    /// A one-link group with 3 unknowns (a motor element R or T): its 3 equations
    /// `Σ_k λ_k w_k = -L` by Cramer's rule. `false` if a joint does not join the link
    /// to an earlier body.
    fn single_link(&mut self, g: &Group<T>) -> bool {
        let Some(link) = g.placements.first().map(|p| p.link) else {
            return false;
        };
        let mut cols = [Vector3::zeros(); 3];
        let mut slots = cols.iter_mut();
        for (jt, u) in g.joints.iter().zip(&self.joints) {
            if jt.i != link || jt.j == link {
                return false;
            }
            for (w, slot) in u.wrenches(self.cog[0]).iter().take(u.n).zip(&mut slots) {
                *slot = *w;
            }
        }
        let x = cramer(&cols, &-self.load[0]);
        for (o, v) in self.lam.iter_mut().zip(x) {
            *o = v;
        }
        true
    }

    /// A dyad: links `a`, `b`, an outer joint on each (to earlier bodies) and the
    /// middle joint between them, 2 unknowns each. With `W_a` the outer joint's two
    /// wrench columns on `a` and `n_a = w_a1 × w_a2` (the equilibrium row that does not
    /// see them: for a revolute, the moment about the joint; for a prismatic, the
    /// force along the guide), `n_aᵀ (M_a λ_m) = -n_aᵀ L_a` and the same for `b` give
    /// the middle joint's `λ_m` (2 × 2); then `W_a λ_a = -L_a - M_a λ_m`. `false` if
    /// the joints are not of this shape.
    fn dyad(&mut self, g: &Group<T>) -> bool {
        let (Some(a), Some(b)) = (g.placements.first(), g.placements.get(1)) else {
            return false;
        };
        let (a, b) = (a.link, b.link);
        // Joint index of the outer joint on a, on b, and of the middle joint.
        let (mut outer_a, mut outer_b, mut middle) = (None, None, None);
        for (k, jt) in g.joints.iter().enumerate() {
            let slot = match (jt.i, jt.j) {
                (i, j) if (i, j) == (a, b) || (i, j) == (b, a) => &mut middle,
                (i, j) if i == a && j != a => &mut outer_a,
                (i, j) if i == b && j != b => &mut outer_b,
                _ => return false,
            };
            if slot.replace(k).is_some() {
                return false;
            }
        }
        let (Some(oa), Some(ob), Some(m)) = (outer_a, outer_b, middle) else {
            return false;
        };
        let (Some(ua), Some(ub), Some(um), Some(jm)) = (
            self.joints.get(oa),
            self.joints.get(ob),
            self.joints.get(m),
            g.joints.get(m),
        ) else {
            return false;
        };
        // The middle joint's reaction acts on its `i` and, opposite, on the other link.
        let sign_a = if jm.i == a { T::one() } else { -T::one() };
        let [ca, cb] = [self.cog[0], self.cog[1]];
        let [la, lb] = [self.load[0], self.load[1]];
        let wa = ua.wrenches(ca);
        let wb = ub.wrenches(cb);
        let ma = um.wrenches(ca).map(|w| w * sign_a);
        let mb = um.wrenches(cb).map(|w| -w * sign_a);
        let na = wa[0].cross(&wa[1]);
        let nb = wb[0].cross(&wb[1]);
        let lm = solve2(
            [
                [na.dot(&ma[0]), na.dot(&ma[1])],
                [nb.dot(&mb[0]), nb.dot(&mb[1])],
            ],
            [-na.dot(&la), -nb.dot(&lb)],
        );
        // The outer joints: `W λ = r` is consistent, `n` completes `W`'s columns to a
        // basis (its coefficient comes out zero to rounding).
        let outer = |w: &[Vector3<T>; 2], n: Vector3<T>, mm: &[Vector3<T>; 2], l: Vector3<T>| {
            let r = -l - mm[0] * lm[0] - mm[1] * lm[1];
            let [x, y, _] = cramer(&[w[0], w[1], n], &r);
            [x, y]
        };
        for (k, x) in [
            (oa, outer(&wa, na, &ma, la)),
            (ob, outer(&wb, nb, &mb, lb)),
            (m, lm),
        ] {
            for (o, v) in self.lam.iter_mut().skip(2 * k).zip(x) {
                *o = v;
            }
        }
        true
    }

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
    /// [`reactions`] reports alike).
    #[inline(never)]
    fn reduced(&mut self, g: &Group<T>, size: Sizes) -> Option<bool> {
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

    /// Any group: its equilibrium `A λ = b` as one dense system (size `N = 3 × links`,
    /// padded with identity), by Gaussian elimination with partial pivoting; `false`
    /// if it is singular.
    #[inline(never)]
    fn dense<const N: usize>(&mut self, g: &Group<T>) -> bool {
        let mut a = SMatrix::<T, N, N>::identity();
        let mut b = SVector::<T, N>::zeros();
        for (k, l) in self.load.iter().take(g.placements.len()).enumerate() {
            for (c, lc) in l.iter().enumerate() {
                if let (Some(bc), Some(ac)) =
                    (b.get_mut(3 * k + c), a.get_mut((3 * k + c, 3 * k + c)))
                {
                    *bc = -*lc;
                    *ac = T::zero();
                }
            }
        }
        let mut col = 0;
        for (jt, u) in g.joints.iter().zip(&self.joints) {
            for (body, sign) in [(jt.i, T::one()), (jt.j, -T::one())] {
                let Some((k, cog)) = self
                    .link_of(body)
                    .and_then(|k| Some((k, *self.cog.get(k)?)))
                else {
                    continue;
                };
                // Column `col + c` of the link's three equations (rows 3k..3k+3).
                for (c, w) in u.wrenches(cog).iter().take(u.n).enumerate() {
                    for (r, v) in w.iter().enumerate() {
                        if let Some(e) = a.get_mut((3 * k + r, col + c)) {
                            *e += sign * *v;
                        }
                    }
                }
            }
            col += u.n;
        }
        let Some(x) = crate::linalg::solve(a, b) else {
            return false;
        };
        for (o, v) in self.lam.iter_mut().zip(x.iter()) {
            *o = *v;
        }
        true
    }
}

/// The largest reduced system (the six-link group's 8 inner unknowns).
const REDUCED_MAX: usize = 8;

/// The sizes a group's reduced system is solved at: `whole` (≤ [`REDUCED_MAX`]) when
/// the one-joint rows cannot be taken out, `small` when they are.
#[derive(Clone, Copy)]
struct Sizes {
    whole: usize,
    small: usize,
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

/// [`Equilibrium::link`] of a body that is not a link of the group.
const NOT_IN_GROUP: u8 = u8::MAX;

/// `x` with `Σ_k x_k c_k = r` by Cramer's rule (`det = c_0 · (c_1 × c_2)`); non-finite
/// when the columns are dependent.
fn cramer<T: Real>(c: &[Vector3<T>; 3], r: &Vector3<T>) -> [T; 3] {
    let [c0, c1, c2] = c;
    let c12 = c1.cross(c2);
    let det = c0.dot(&c12);
    [
        r.dot(&c12) / det,
        c0.dot(&r.cross(c2)) / det,
        c0.dot(&c1.cross(r)) / det,
    ]
}

/// `x` with `A x = r` for a 2 × 2 `A` (rows) by Cramer's rule; non-finite when `A` is
/// singular.
fn solve2<T: Real>(a: [[T; 2]; 2], r: [T; 2]) -> [T; 2] {
    let [[a00, a01], [a10, a11]] = a;
    let det = a00 * a11 - a01 * a10;
    [
        (r[0] * a11 - a01 * r[1]) / det,
        (a00 * r[1] - a10 * r[0]) / det,
    ]
}

/// Joint reactions of every group and the driving torques of the motor elements at the
/// workspace's last forward-dynamics evaluation, into `ws.reactions` (per group, in the
/// order of its joints; a motor element's driver joint holds its driving torque in
/// `moment`, or its driving force in `force`).
pub fn reactions<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    time: f64,
) -> Result<(), StepError> {
    let mut loads = free_body_loads(model, ws);
    let mut eq = Equilibrium::new();
    for (gi, g) in model.groups().iter().enumerate().rev() {
        eq.set(model, ws, g, &loads);
        let used: usize = eq.joints.iter().map(|u| u.n).sum();
        if !(eq.solve(g) && eq.lam.iter().take(used).all(|v| v.finite())) {
            return Err(StepError::Group {
                time,
                group: group_id(g, gi),
                fault: GroupFault::Singular { conditioning: 0.0 },
            });
        }
        let mut col = 0;
        for (k, (jt, u)) in g.joints.iter().zip(&eq.joints).enumerate() {
            let r = u.reaction(eq.lam.get(col..).unwrap_or(&[]));
            col += u.n;
            if let Some(slot) = ws.reactions.get_mut(gi).and_then(|s| s.get_mut(k)) {
                *slot = r;
            }
            // The reaction on the other body, if it belongs to an earlier group.
            if eq.link_of(jt.j).is_none() {
                add_load(model, &ws.body, &mut loads, jt.j, u.at, -r.force, -r.moment);
            }
        }
    }
    Ok(())
}

/// Equilibrium rows of the largest group: 3 per link.
const GROUP_ROWS: usize = 3 * MAX_GROUP_LINKS;
const _: () = assert!(
    MAX_GROUP_LINKS == 6,
    "solve sizes above cover 2, 4 and 6 links"
);

/// The driving torque (N·m) or force (N) that the motion requires at motor element
/// `group`, from the last [`reactions`] call; `None` if `group` is not a motor element.
pub fn driving_torque<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &Workspace<T, C>,
    group: usize,
) -> Option<T> {
    let g = model.groups().get(group)?;
    let (k, jt) = g.joints.iter().enumerate().find(|(_, j)| {
        matches!(
            j.kind,
            JointKind::DriveTorque | JointKind::DriveForce { .. }
        )
    })?;
    let r = ws.reactions.get(group)?.get(k)?;
    Some(match jt.kind {
        JointKind::DriveTorque => r.moment,
        _ => {
            let bj = ws.body.get(jt.j as usize).copied().unwrap_or_default();
            let dir = match jt.kind {
                JointKind::DriveForce { dir } => rotate_cs(bj.c, bj.s, &dir),
                _ => Vec2::zeros(),
            };
            r.force.dot(&dir)
        }
    })
}
