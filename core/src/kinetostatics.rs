//! Kinetostatics (SPEC 1, thesis 3.3): with `q, q̇, q̈` known, the d'Alembert inertia
//! loads `(-m a_G, -I_G α)` are added to the applied loads and each group's equilibrium
//! (3 equations per link) is solved for its joint reactions, walking the sequence
//! backwards (last group first). A group's reactions on the bodies of earlier groups
//! are loads of those groups. A motor element's driver joint yields the driving torque
//! (or force) that the motion requires.
//!
//! Applied motor torques are *not* among the loads: the driving torques are unknowns,
//! so that in a forward-dynamics run they must come out equal to the applied ones.

use crate::config::{MAX_BODIES, MAX_GROUP_LINKS, POSE_ROWS};
use crate::dynamics::{add_external_loads, add_load, mass_times};
use crate::error::{GroupFault, StepError};
use crate::kinematics::group_id;
use crate::model::Model;
use crate::scalar::{cross, perp, rotate_cs, Real, Vec2};
use crate::structomat::{Group, JointKind};
use crate::workspace::{Reaction, Workspace};
use nalgebra::{SMatrix, SVector};

/// Loads on each body without the motors: gravity, constant and caller-set loads, and
/// inertia.
fn free_body_loads<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> SVector<T, POSE_ROWS> {
    let mut f = SVector::<T, POSE_ROWS>::zeros();
    let g = model.gravity();
    for (i, l) in model.links().iter().enumerate() {
        if let Some(e) = f.get_mut(3 * i) {
            *e = l.mass * g.x;
        }
        if let Some(e) = f.get_mut(3 * i + 1) {
            *e = l.mass * g.y;
        }
    }
    add_external_loads(model, ws, &mut f);
    let qdd = SVector::from_column_slice(&ws.qdd);
    let acc = ws.a_bias + ws.v * qdd;
    f - mass_times(model, &acc)
}

/// The unit reaction directions of a joint on body `i` (force, at world point `at`)
/// and the moments they make about `i`'s COG; one entry per unknown.
fn unit_reactions<T: Real>(kind: JointKind<T>, u_world: Vec2<T>) -> ([(Vec2<T>, T); 2], usize) {
    let x = Vec2::new(T::one(), T::zero());
    let y = Vec2::new(T::zero(), T::one());
    let z = Vec2::zeros();
    match kind {
        JointKind::Revolute => ([(x, T::zero()), (y, T::zero())], 2),
        JointKind::Prismatic { .. } => ([(perp(&u_world), T::zero()), (z, T::one())], 2),
        JointKind::DriveTorque => ([(z, T::one()), (z, T::zero())], 1),
        JointKind::DriveForce { .. } => ([(u_world, T::zero()), (z, T::zero())], 1),
    }
}

/// Solves one group's equilibrium `A λ = b` (size `N = 3 × links`, padded with identity).
fn solve_group<T: Real, const N: usize>(
    model: &Model<T>,
    ws: &Workspace<T>,
    g: &Group<T>,
    loads: &SVector<T, POSE_ROWS>,
) -> Option<SVector<T, N>> {
    let mut a = SMatrix::<T, N, N>::identity();
    let mut b = SVector::<T, N>::zeros();
    let row_of = |body: u8| {
        g.placements
            .iter()
            .position(|p| p.link == body)
            .map(|k| 3 * k)
    };
    for (k, p) in g.placements.iter().enumerate() {
        let r = 3 * (p.link as usize).checked_sub(1)?;
        for c in 0..3 {
            *b.get_mut(3 * k + c)? = -*loads.get(r + c)?;
            *a.get_mut((3 * k + c, 3 * k + c))? = T::zero();
        }
    }
    let mut col = 0;
    for jt in g.joints.iter() {
        let bi = ws.body.get(jt.i as usize)?;
        let bj = ws.body.get(jt.j as usize)?;
        let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
        let u = match jt.kind {
            JointKind::Prismatic { dir } | JointKind::DriveForce { dir } => {
                rotate_cs(bj.c, bj.s, &dir)
            }
            _ => Vec2::zeros(),
        };
        let (units, n) = unit_reactions(jt.kind, u);
        for (force, moment) in units.iter().take(n) {
            for (body, sign) in [(jt.i, T::one()), (jt.j, -T::one())] {
                let Some(r) = row_of(body) else { continue };
                let m = *moment + cross(&(at - ws.cog(model, body)), force);
                *a.get_mut((r, col))? += sign * force.x;
                *a.get_mut((r + 1, col))? += sign * force.y;
                *a.get_mut((r + 2, col))? += sign * m;
            }
            col += 1;
        }
    }
    crate::linalg::solve(a, b)
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
    for (gi, g) in model.groups().iter().enumerate().rev() {
        // Sized to the group: 6 unknowns for a dyad, 12 for a triad, 18 for a
        // six-link Assur group (3 equations per link).
        let sol: Option<[T; GROUP_ROWS]> = match g.placements.len() {
            0..=2 => solve_group::<T, 6>(model, ws, g, &loads).map(|s| pad(s.as_slice())),
            3..=4 => solve_group::<T, 12>(model, ws, g, &loads).map(|s| pad(s.as_slice())),
            _ => solve_group::<T, GROUP_ROWS>(model, ws, g, &loads).map(|s| pad(s.as_slice())),
        };
        let Some(lam) = sol.filter(|l| l.iter().all(|v| v.finite())) else {
            return Err(StepError::Group {
                time,
                group: group_id(g, gi),
                fault: GroupFault::Singular { conditioning: 0.0 },
            });
        };
        let mut col = 0;
        for (k, jt) in g.joints.iter().enumerate() {
            let bi = ws.body.get(jt.i as usize).copied().unwrap_or_default();
            let bj = ws.body.get(jt.j as usize).copied().unwrap_or_default();
            let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
            let l0 = lam.get(col).copied().unwrap_or(T::zero());
            let l1 = lam.get(col + 1).copied().unwrap_or(T::zero());
            let (force, moment) = match jt.kind {
                JointKind::Revolute => (Vec2::new(l0, l1), T::zero()),
                JointKind::Prismatic { dir } => (perp(&rotate_cs(bj.c, bj.s, &dir)) * l0, l1),
                JointKind::DriveTorque => (Vec2::zeros(), l0),
                JointKind::DriveForce { dir } => (rotate_cs(bj.c, bj.s, &dir) * l0, T::zero()),
            };
            col += jt.kind.unknowns();
            if let Some(slot) = ws.reactions.get_mut(gi).and_then(|r| r.get_mut(k)) {
                *slot = Reaction { force, moment };
            }
            // The reaction on the other body, if it belongs to an earlier group.
            if !g.placements.iter().any(|p| p.link == jt.j) && (jt.j as usize) < MAX_BODIES {
                add_load(model, ws, &mut loads, jt.j, at, -force, -moment);
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

fn pad<T: Real>(s: &[T]) -> [T; GROUP_ROWS] {
    let mut out = [T::zero(); GROUP_ROWS];
    for (o, v) in out.iter_mut().zip(s.iter()) {
        *o = *v;
    }
    out
}

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
