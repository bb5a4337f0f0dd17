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
//! - any other group (the triad, a six-link Assur group) as one dense system.

use crate::config::{MAX_GROUP_JOINTS, MAX_GROUP_LINKS, POSE_ROWS};
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
fn free_body_loads<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> SVector<T, POSE_ROWS> {
    let mut f = SVector::<T, POSE_ROWS>::zeros();
    loads_without_motors(model, &ws.body, &ws.applied_moment, &mut f);
    for (i, (l, rows)) in model
        .links()
        .iter()
        .zip(f.as_mut_slice().chunks_exact_mut(3))
        .enumerate()
    {
        let acc = link_acceleration(ws, i as u8 + 1);
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
    fn of(ws: &Workspace<T>, jt: &Joint<T>) -> Self {
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
            cog: [Vec2::zeros(); MAX_GROUP_LINKS],
            load: [Vector3::zeros(); MAX_GROUP_LINKS],
            joints: [none; MAX_GROUP_JOINTS],
            lam: [T::zero(); GROUP_ROWS],
        }
    }

    /// Sets up group `g`'s equilibrium at the workspace's pose under `loads`.
    fn set(
        &mut self,
        model: &Model<T>,
        ws: &Workspace<T>,
        g: &Group<T>,
        loads: &SVector<T, POSE_ROWS>,
    ) {
        for ((p, c), l) in g.placements.iter().zip(&mut self.cog).zip(&mut self.load) {
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
        // Reduced sizes: 6 covers the triad (4 links, 3 outer joints), 12 the six-link
        // group (3 outer joints); a group whose reduced system is larger is solved dense.
        let reduced = match links {
            0..=4 => self.reduced::<6>(g),
            _ => self.reduced::<12>(g),
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
    /// dyad's method generalized: a link with an outer joint keeps only its row
    /// `n = w_1 × w_2` (the moment about a revolute joint) which does not see that
    /// joint, a link without one keeps its 3 rows; these rows are as many as the inner
    /// joints' unknowns (3 × links = 2 × joints), which they determine (a sparse system
    /// of size `3 × links - 2 × outer joints`: 6 for the triad instead of 12, 12 for
    /// the six-link group instead of 18). Then each outer joint from its link's
    /// remaining rows, `W_o λ_o = -L - Σ (inner reactions' wrenches)`, by Cramer with
    /// `n` completing `W_o`'s columns (its coefficient comes out zero to rounding).
    /// `None` if the group is not of this shape (the dense system then solves it),
    /// `Some(false)` if it is singular.
    fn reduced<const N: usize>(&mut self, g: &Group<T>) -> Option<bool> {
        let links = g.placements.len();
        // Per joint: its link `i`'s index, its other body's (`None`: an earlier body),
        // and its first unknown's index in `λ` and, for an inner joint, in the reduced
        // system. Per link: its outer joint.
        let mut on = [(0, None); MAX_GROUP_JOINTS];
        let mut col = [(0, 0); MAX_GROUP_JOINTS];
        let mut outer = [None; MAX_GROUP_LINKS];
        let (mut full, mut m) = (0, 0);
        for (k, (((jt, u), o), c)) in g
            .joints
            .iter()
            .zip(&self.joints)
            .zip(&mut on)
            .zip(&mut col)
            .enumerate()
        {
            let i = link_index(g, jt.i)?;
            let j = link_index(g, jt.j);
            *o = (i, j);
            *c = (full, m);
            full += u.n;
            match j {
                Some(j) if j == i => return None,
                Some(_) => m += u.n,
                None if u.n == 2 => {
                    if outer.get_mut(i)?.replace(k).is_some() {
                        return None;
                    }
                }
                None => return None,
            }
        }
        // Per link: its first reduced row, and the rows it keeps: `n` for a link with an
        // outer joint (with that joint's wrench columns `W_o`), else its 3 rows.
        let mut proj = [(0, None); MAX_GROUP_LINKS];
        let mut rows = 0;
        for ((pr, o), cog) in proj.iter_mut().zip(&outer).zip(&self.cog).take(links) {
            let w = o.and_then(|o| self.joints.get(o)).map(|u| {
                let w = u.wrenches(*cog);
                (w, w[0].cross(&w[1]))
            });
            *pr = (rows, w);
            rows += if w.is_some() { 1 } else { 3 };
        }
        if rows != m || m > N {
            return None;
        }
        // `A x = b`: per link's kept rows, `-L` and the inner joints' wrench columns
        // (`+W` on the joint's link `i`, `-W` on the other).
        let mut a = [[T::zero(); N]; N];
        let mut b = [T::zero(); N];
        let mut put = |r0: usize, n: Option<&Vector3<T>>, v: &Vector3<T>, col: usize| {
            let entries = match n {
                Some(n) => [(r0, n.dot(v)), (N, T::zero()), (N, T::zero())],
                None => [(r0, v.x), (r0 + 1, v.y), (r0 + 2, v.z)],
            };
            for (r, e) in entries {
                if let Some(x) = a.get_mut(r).and_then(|row| row.get_mut(col)) {
                    *x += e;
                }
            }
        };
        for ((r0, w), load) in proj.iter().zip(&self.load).take(links) {
            let nl = -*load;
            let entries = match w {
                Some((_, n)) => [(*r0, n.dot(&nl)), (N, T::zero()), (N, T::zero())],
                None => [(*r0, nl.x), (r0 + 1, nl.y), (r0 + 2, nl.z)],
            };
            for (r, e) in entries {
                if let Some(x) = b.get_mut(r) {
                    *x = e;
                }
            }
        }
        for ((u, (i, j)), (_, c0)) in self.joints.iter().zip(&on).zip(&col).take(g.joints.len()) {
            let Some(j) = j else {
                continue;
            };
            for (link, neg) in [(*i, false), (*j, true)] {
                let (Some((r0, w)), Some(cog)) = (proj.get(link), self.cog.get(link)) else {
                    continue;
                };
                let n = w.as_ref().map(|(_, n)| n);
                for (c, v) in u.wrenches(*cog).iter().take(u.n).enumerate() {
                    let v = if neg { -*v } else { *v };
                    put(*r0, n, &v, c0 + c);
                }
            }
        }
        if !crate::linalg::solve_rows(&mut a, &mut b, m) {
            return Some(false);
        }
        // The inner joints' unknowns, and their wrenches on each link with an outer
        // joint into that link's right-hand side `-L - Σ ±W λ`.
        let mut rhs = [Vector3::zeros(); MAX_GROUP_LINKS];
        for (r, l) in rhs.iter_mut().zip(&self.load) {
            *r = -*l;
        }
        for ((u, (i, j)), (f0, c0)) in self.joints.iter().zip(&on).zip(&col).take(g.joints.len()) {
            let Some(j) = j else {
                continue;
            };
            let x = b.get(*c0..c0 + u.n).unwrap_or(&[]);
            for (o, v) in self.lam.iter_mut().skip(*f0).zip(x) {
                *o = *v;
            }
            let r = u.reaction(x);
            for (link, sign) in [(*i, T::one()), (*j, -T::one())] {
                let (Some((_, Some(_))), Some(cog), Some(rl)) =
                    (proj.get(link), self.cog.get(link), rhs.get_mut(link))
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
            let Some((f0, _)) = col.get(*k) else {
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
                let Some((k, cog)) = link_index(g, body).and_then(|k| Some((k, *self.cog.get(k)?)))
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

/// The placement index of `body` in group `g`, if it is one of its links.
fn link_index<T: Real>(g: &Group<T>, body: u8) -> Option<usize> {
    g.placements.iter().position(|p| p.link == body)
}

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
pub fn reactions<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    time: f64,
) -> Result<(), StepError> {
    let mut loads = free_body_loads(model, ws);
    let mut eq = Equilibrium::new();
    for (gi, g) in model.groups().iter().enumerate().rev() {
        eq.set(model, ws, g, &loads);
        if !(eq.solve(g) && eq.lam.iter().all(|v| v.finite())) {
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
            if link_index(g, jt.j).is_none() {
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
pub fn driving_torque<T: Real>(model: &Model<T>, ws: &Workspace<T>, group: usize) -> Option<T> {
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
