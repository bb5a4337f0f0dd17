//! Equations of motion (SPEC 1, thesis eq. 4.49): with `M = diag(m_i, m_i, I_Gi)` and
//! `F` the applied loads at the COGs,
//!
//! `(VᵀMV) q̈ = Vᵀ(F - M a_b)`.
//!
//! `VᵀMV` is symmetric positive definite away from singular configurations; it is
//! factored by Cholesky (identity padding past the degrees of freedom).

use crate::capacity::Capacity;
use crate::config::{MAX_DOF, POSE_ROWS};
use crate::error::StepError;
use crate::linalg::{cholesky, cholesky_solve};
use crate::model::{Drive, Model};
use crate::scalar::{cross, perp, rotate_cs, Real, Vec2};
use crate::structomat::JointKind;
use crate::transmission::evaluate;
use crate::workspace::{BodyState, Workspace};
use nalgebra::{SMatrix, SVector};

/// Kinetic and potential energy, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy<T> {
    /// `Σ ½ m |v_G|² + ½ I_G ω²`, J.
    pub kinetic: T,
    /// Gravity's potential `-Σ m g·r_G`, J (zero at the origin).
    pub potential: T,
}

/// Adds a force `f` (N, world) applied at world point `at` and a moment (N·m) to the
/// loads of link `body` (reduced to its COG at the poses `bodies`).
pub(crate) fn add_load<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    loads: &mut SVector<T, POSE_ROWS>,
    body: u8,
    at: Vec2<T>,
    f: Vec2<T>,
    moment: T,
) {
    let (Some(l), Some(b)) = (model.link(body), bodies.get(body as usize)) else {
        return;
    };
    let g = b.o + rotate_cs(b.c, b.s, &l.cog);
    let r = 3 * (body as usize).saturating_sub(1);
    if let Some([fx, fy, m]) = loads.as_mut_slice().get_mut(r..r + 3) {
        *fx += f.x;
        *fy += f.y;
        *m += moment + cross(&(at - g), &f);
    }
}

/// Applied loads `F`: gravity at every COG, the motors (through their motor element's
/// driver joint, reaction on the body it is mounted on) and the constant loads. Also
/// records each motor's torque in `ws.motor`.
pub fn applied_forces<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    t: T,
) -> Result<(), StepError> {
    for (k, d) in model.drives().iter().enumerate() {
        let (q, qd) = drive_motion(model, ws, d);
        let tau = d.motor.torque(t, q, qd);
        if !tau.finite() {
            return Err(StepError::NonFinite {
                time: t.to_f64(),
                what: "motor torque",
            });
        }
        if let Some(slot) = ws.motor.get_mut(k) {
            *slot = tau;
        }
    }
    // Built in place: the live rows of the links, zeros past them.
    let Workspace {
        body,
        force: f,
        applied_moment,
        motor,
        ..
    } = ws;
    loads_without_motors(model, body, applied_moment, f);
    for (d, tau) in model.drives().iter().zip(motor.iter()) {
        let Some(grp) = model.groups().get(d.group as usize) else {
            continue;
        };
        if let Some(j) = d.joint {
            add_across(model, body, f, grp, j, *tau);
            continue;
        }
        for jt in grp.joints.iter() {
            let bi = body.get(jt.i as usize).copied().unwrap_or_default();
            let bj = body.get(jt.j as usize).copied().unwrap_or_default();
            let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
            let (u, m) = match jt.kind {
                JointKind::DriveTorque => (Vec2::zeros(), *tau),
                JointKind::DriveForce { dir } => (rotate_cs(bj.c, bj.s, &dir) * *tau, T::zero()),
                _ => continue,
            };
            add_load(model, body, f, jt.i, at, u, m);
            add_load(model, body, f, jt.j, at, -u, -m);
        }
    }
    Ok(())
}

/// The motion a drive's law reads: its coordinate and rate (a motor element R pivoted
/// on a moving link: less that link's angle and speed), or for a drive across a
/// joint ([`Drive`]) the joint's relative angle `θ_i - θ_j` (rad) and speed, or the
/// offset of the slider's joint point along the guide of `j` (m, from the guide's
/// joint point) and its rate.
pub fn drive_motion<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &Workspace<T, C>,
    d: &Drive<T>,
) -> (T, T) {
    let Some(j) = d.joint else {
        let c = d.coord as usize;
        let (q, qd) = (
            ws.q.get(c).copied().unwrap_or(T::zero()),
            ws.qd.get(c).copied().unwrap_or(T::zero()),
        );
        // A motor element R's coordinate is its link's absolute angle; its motor acts
        // between the link and the body its pivot is on (the torque pair of `loads`),
        // so its law reads, and its power is, the motion relative to that body: on the
        // ground (every built-in) the coordinate itself, on a moving link (an elbow)
        // less that link's angle and speed.
        let carrier = model
            .groups()
            .get(d.group as usize)
            .and_then(|g| g.joints.iter().find(|jt| jt.kind == JointKind::DriveTorque))
            .map_or(0, |jt| jt.j);
        return match ws.body.get(carrier as usize) {
            Some(b) if carrier != 0 => (q - b.theta, qd - b.omega),
            _ => (q, qd),
        };
    };
    let Some(jt) = model
        .groups()
        .get(d.group as usize)
        .and_then(|g| g.joints.get(j as usize))
    else {
        return (T::zero(), T::zero());
    };
    let bi = ws.body.get(jt.i as usize).copied().unwrap_or_default();
    let bj = ws.body.get(jt.j as usize).copied().unwrap_or_default();
    match jt.kind {
        JointKind::Prismatic { dir } => {
            let ri = rotate_cs(bi.c, bi.s, &jt.pi);
            let rj = rotate_cs(bj.c, bj.s, &jt.pj);
            let u = rotate_cs(bj.c, bj.s, &dir);
            let gap = (bi.o + ri) - (bj.o + rj);
            let vi = bi.v + perp(&ri) * bi.omega;
            let vj = bj.v + perp(&rj) * bj.omega;
            // d/dt (gap · u), u turning with body j.
            (
                gap.dot(&u),
                (vi - vj).dot(&u) + gap.dot(&perp(&u)) * bj.omega,
            )
        }
        _ => (bi.theta - bj.theta, bi.omega - bj.omega),
    }
}

/// Adds the torque (revolute) or force along the guide (prismatic) `tau` of a drive
/// across joint `j` of group `grp` to the loads `f`: on the joint's body `i`, its
/// reaction on `j`, at `i`'s joint point.
fn add_across<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    body: &[BodyState<T>],
    f: &mut SVector<T, POSE_ROWS>,
    grp: &crate::structomat::Group<T>,
    j: u8,
    tau: T,
) {
    let Some(jt) = grp.joints.get(j as usize) else {
        return;
    };
    let bi = body.get(jt.i as usize).copied().unwrap_or_default();
    let bj = body.get(jt.j as usize).copied().unwrap_or_default();
    let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
    let (u, m) = match jt.kind {
        JointKind::Prismatic { dir } => (rotate_cs(bj.c, bj.s, &dir) * tau, T::zero()),
        _ => (Vec2::zeros(), tau),
    };
    add_load(model, body, f, jt.i, at, u, m);
    add_load(model, body, f, jt.j, at, -u, -m);
}

/// Sets `f` to the loads other than the motors: gravity at every COG, then the model's
/// constant loads and the caller-set moments ([`add_external_loads`]); zeros past the
/// live rows. Shared by the equations of motion and the kinetostatics.
pub(crate) fn loads_without_motors<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    applied_moment: &[T],
    f: &mut SVector<T, POSE_ROWS>,
) {
    f.fill(T::zero());
    let g = model.gravity();
    for (l, rows) in model
        .links()
        .iter()
        .zip(f.as_mut_slice().chunks_exact_mut(3))
    {
        if let [fx, fy, _] = rows {
            *fx = l.mass * g.x;
            *fy = l.mass * g.y;
        }
    }
    add_external_loads(model, bodies, applied_moment, f);
}

/// Adds the model's constant loads and the caller-set moments (`applied_moment`, per
/// body) to `f`, at the poses `bodies` (shared by the equations of motion and the
/// kinetostatics).
pub(crate) fn add_external_loads<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    applied_moment: &[T],
    f: &mut SVector<T, POSE_ROWS>,
) {
    for ld in model.loads() {
        let b = bodies.get(ld.body as usize).copied().unwrap_or_default();
        let at = b.o + rotate_cs(b.c, b.s, &ld.point);
        add_load(model, bodies, f, ld.body, at, ld.force, ld.moment);
    }
    let rows = f.as_mut_slice().chunks_exact_mut(3);
    for (row, m) in rows.zip(applied_moment.iter().skip(1).take(model.n_links())) {
        if let [_, _, e] = row {
            *e += *m;
        }
    }
}

/// The actual pose-space accelerations `a_G = a_b + V q̈` of link `body` (its COG's
/// acceleration and its angular acceleration) at the workspace's `q̈`, over the
/// model's `dof` coordinates (`q̈` is zero past them: the same sums, bit for bit).
pub(crate) fn link_acceleration<T: Real, C: Capacity<T>>(
    ws: &Workspace<T, C>,
    dof: usize,
    body: u8,
) -> [T; 3] {
    let r = 3 * (body as usize).saturating_sub(1);
    let mut vq = [T::zero(); 3];
    for (j, q) in ws.qdd.iter().enumerate().take(dof) {
        let at = j * POSE_ROWS + r;
        for (s, v) in vq
            .iter_mut()
            .zip(ws.v.as_slice().get(at..at + 3).unwrap_or(&[]))
        {
            *s += *v * *q;
        }
    }
    let ab = ws.a_bias.as_slice().get(r..r + 3).unwrap_or(&[]);
    let mut a = [T::zero(); 3];
    for ((a, b), s) in a.iter_mut().zip(ab).zip(vq) {
        *a = *b + s;
    }
    a
}

/// Forward dynamics at `(t, q, q̇)`: kinematics, `V`, `a_b`, `F`, `VᵀMV`, `q̈`. Leaves
/// the workspace consistent: body and group accelerations are the actual ones.
pub fn forward<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    t: T,
    q: &[T],
    qd: &[T],
) -> Result<(), StepError> {
    generalized_accelerations(model, ws, t, q, qd)?;
    finish_accelerations(model, ws);
    Ok(())
}

/// The equations of motion proper: `q̈` into `ws.qdd`, without updating the bodies'
/// accelerations (an integrator's inner stages need only `q̈`; [`forward`] and
/// [`Simulation`](crate::Simulation) finish the accepted states).
///
/// `VᵀMV` and `Vᵀ(F - M a_b)` are summed over the live rows and coordinates only, the
/// mass matrix's lower triangle then mirrored; 1 and 2 degrees of freedom are solved in
/// closed form, 3 by Cholesky.
pub fn generalized_accelerations<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    t: T,
    q: &[T],
    qd: &[T],
) -> Result<(), StepError> {
    evaluate(model, ws, q, qd, t.to_f64())?;
    solve_accelerations(model, ws, t)
}

/// The workspace's velocity matrix `V`, applied loads `F` and bias accelerations `a_b`
/// from the last evaluation, as [`generalized_terms`] reads them.
type Evaluated<'a, T> = (
    &'a SMatrix<T, POSE_ROWS, MAX_DOF>,
    &'a SVector<T, POSE_ROWS>,
    &'a SVector<T, POSE_ROWS>,
);

/// `VᵀMV` and `Vᵀ(F - M a_b)` for `M` coordinates (thesis eq. 4.49) into the top-left
/// blocks of `mq` and `gf`: one pass over the live rows (3 per link), each adding its
/// terms `m_r V_rj V_rk` (lower triangle, then mirrored) and `V_rj (F_r - m_r a_b,r)`.
fn generalized_terms<T: Real, const M: usize, C: Capacity<T>>(
    model: &Model<T, C>,
    (v, force, bias): Evaluated<'_, T>,
    mq: &mut SMatrix<T, MAX_DOF, MAX_DOF>,
    gf: &mut SVector<T, MAX_DOF>,
) {
    let v = v.as_slice();
    let cols: [&[T]; M] =
        core::array::from_fn(|j| v.get(j * POSE_ROWS..(j + 1) * POSE_ROWS).unwrap_or(&[]));
    let (force, bias) = (force.as_slice(), bias.as_slice());
    let mut a = [[T::zero(); M]; M];
    let mut b = [T::zero(); M];
    for (i, l) in model.links().iter().enumerate() {
        for (c, mr) in [l.mass, l.mass, l.inertia].into_iter().enumerate() {
            let r = 3 * i + c;
            let (Some(f), Some(ab)) = (force.get(r), bias.get(r)) else {
                continue;
            };
            let rhs = *f - mr * *ab;
            let vr: [T; M] = core::array::from_fn(|j| {
                cols.get(j)
                    .and_then(|c| c.get(r))
                    .copied()
                    .unwrap_or(T::zero())
            });
            for (j, ((vj, bj), aj)) in vr.iter().zip(b.iter_mut()).zip(a.iter_mut()).enumerate() {
                *bj += *vj * rhs;
                for (vk, ajk) in vr.iter().zip(aj.iter_mut()).take(j + 1) {
                    *ajk += mr * *vj * *vk;
                }
            }
        }
    }
    for (j, (aj, bj)) in a.iter().zip(b).enumerate() {
        if let Some(g) = gf.get_mut(j) {
            *g = bj;
        }
        for (k, e) in aj.iter().enumerate().take(j + 1) {
            for at in [(j, k), (k, j)] {
                if let Some(m) = mq.get_mut(at) {
                    *m = *e;
                }
            }
        }
    }
}

/// The second half of [`generalized_accelerations`]: applied loads, `VᵀMV`,
/// `Vᵀ(F - M a_b)` and `q̈`, at the kinematics the workspace already holds (from
/// [`evaluate`]). Lets a caller set loads that depend on the evaluated motion (a motor
/// law on a link that is not a coordinate, into `ws.applied_moment`) in between.
pub fn solve_accelerations<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    t: T,
) -> Result<(), StepError> {
    let time = t.to_f64();
    applied_forces(model, ws, t)?;
    let m = model.dof().min(MAX_DOF);
    // Into the workspace's own matrices: built locally and copied there, they cost the
    // Cortex-M7 a 72 B copy at every evaluation.
    let Workspace {
        v,
        force,
        a_bias,
        mass_q: mq,
        gen_force: gf,
        ..
    } = &mut *ws;
    *mq = SMatrix::identity();
    *gf = SVector::zeros();
    let evaluated = (&*v, &*force, &*a_bias);
    match m {
        0 => {}
        1 => generalized_terms::<T, 1, C>(model, evaluated, mq, gf),
        2 => generalized_terms::<T, 2, C>(model, evaluated, mq, gf),
        _ => generalized_terms::<T, MAX_DOF, C>(model, evaluated, mq, gf),
    }
    let (mq, gf) = (&*mq, &*gf);
    // Overflowing terms mean the state itself has run away (a step too large for the
    // motion makes the explicit integrator unstable): say so rather than blame the
    // configuration.
    if mq.iter().chain(gf.iter()).any(|v| !v.finite()) {
        return Err(StepError::NonFinite {
            time,
            what: "a term of the equations of motion (the speeds overflow it, the step is too large for the motion)",
        });
    }
    let singular = StepError::SingularMassMatrix { time };
    let mut qdd = [T::zero(); MAX_DOF];
    match m {
        0 => {}
        1 => {
            if !(mq[(0, 0)] > T::zero()) {
                return Err(singular);
            }
            qdd[0] = gf[0] / mq[(0, 0)];
        }
        2 => {
            let (a, b, d) = (mq[(0, 0)], mq[(1, 0)], mq[(1, 1)]);
            let det = a * d - b * b;
            // Positive definite: a > 0 and det > 0 (Sylvester), relative to round-off.
            if !(a > T::zero() && det > T::EPS * a * d) {
                return Err(singular);
            }
            qdd[0] = (d * gf[0] - b * gf[1]) / det;
            qdd[1] = (a * gf[1] - b * gf[0]) / det;
        }
        _ => {
            let l = cholesky(mq).ok_or(singular)?;
            let x = cholesky_solve(&l, gf);
            for (o, v) in qdd.iter_mut().zip(x.iter()) {
                *o = *v;
            }
        }
    }
    // The mass matrix passed its definiteness test: accelerations that overflow come
    // from the applied forces (a torque of 1e308 N·m), not from a singular configuration.
    if qdd.iter().any(|v| !v.finite()) {
        return Err(StepError::NonFinite {
            time,
            what: "a generalized acceleration (the applied forces overflow it)",
        });
    }
    ws.qdd = qdd;
    ws.evaluations += 1;
    Ok(())
}

/// With `q̈` known: actual COG and origin accelerations of every body
/// (`a_G = a_b + V q̈`) and every group's `ẍ = ẍ_b + C q̈`.
pub fn finish_accelerations<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
) {
    for (i, l) in model.links().iter().enumerate() {
        let [ax, ay, al] = link_acceleration(ws, model.dof(), i as u8 + 1);
        let Some(b) = ws.body.get_mut(i + 1) else {
            continue;
        };
        let r = rotate_cs(b.c, b.s, &l.cog);
        b.alpha = al;
        b.a = Vec2::new(ax, ay) - perp(&r) * al + r * (b.omega * b.omega);
    }
    let qdd = SVector::<T, MAX_DOF>::from_column_slice(&ws.qdd);
    for gd in ws.group.iter_mut().take(model.groups().len()) {
        let x = gd.dx_dq * qdd;
        for ((o, b), x) in gd.xdd.iter_mut().zip(gd.xdd_bias).zip(x.iter()) {
            *o = b + *x;
        }
    }
}

/// Kinetic and potential energy at the workspace's last evaluation.
pub fn energy<T: Real, C: Capacity<T>>(model: &Model<T, C>, ws: &Workspace<T, C>) -> Energy<T> {
    let g = model.gravity();
    let mut e = Energy::default();
    let half = T::c(0.5);
    for (i, l) in model.links().iter().enumerate() {
        let Some(b) = ws.body.get(i + 1) else {
            continue;
        };
        let r = rotate_cs(b.c, b.s, &l.cog);
        let v = b.v + perp(&r) * b.omega;
        e.kinetic += half * (l.mass * v.norm_squared() + l.inertia * b.omega * b.omega);
        e.potential -= l.mass * g.dot(&(b.o + r));
    }
    e
}
