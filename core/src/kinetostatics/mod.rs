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

mod reduced;

use reduced::Sizes;

/// Loads on each body without the motors: gravity, constant and caller-set loads, and
/// inertia (`F - M a_G`, live rows only), added to `f` (zero on entry). Written in
/// place: returned by value, the 288 B vector (f64) was copied out at every call.
fn free_body_loads<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &Workspace<T, C>,
    f: &mut SVector<T, POSE_ROWS>,
) {
    loads_without_motors(model, &ws.body, &ws.applied_moment, f);
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
    /// The group's unknowns, `Σ n` over its joints (the used part of `lam`).
    used: usize,
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
            used: 0,
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
        // The group's unknowns only: nothing reads `λ` past them (a dyad's 6 of 18).
        self.used = self.joints.iter().map(|u| u.n).sum();
        for l in self.lam.iter_mut().take(self.used) {
            *l = T::zero();
        }
    }

    /// Solves for `λ` by the group's structure (see the module docs); `false` when the
    /// dense system is singular (the closed forms leave non-finite values instead).
    fn solve(&mut self, g: &Group<T>) -> bool {
        let links = g.placements.len();
        let closed = match (links, self.used) {
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
    let mut loads = SVector::<T, POSE_ROWS>::zeros();
    free_body_loads(model, ws, &mut loads);
    let mut eq = Equilibrium::new();
    for (gi, g) in model.groups().iter().enumerate().rev() {
        eq.set(model, ws, g, &loads);
        if !(eq.solve(g) && eq.lam.iter().take(eq.used).all(|v| v.finite())) {
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
