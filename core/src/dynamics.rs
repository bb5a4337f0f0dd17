//! Equations of motion (SPEC 1, thesis eq. 4.49): with `M = diag(m_i, m_i, I_Gi)` and
//! `F` the applied loads at the COGs,
//!
//! `(VᵀMV) q̈ = Vᵀ(F - M a_b)`.
//!
//! `VᵀMV` is symmetric positive definite away from singular configurations; it is
//! factored by Cholesky (identity padding past the degrees of freedom).

use crate::config::{MAX_DOF, POSE_ROWS};
use crate::error::StepError;
use crate::model::Model;
use crate::scalar::{cross, perp, rotate_cs, Real, Vec2};
use crate::structomat::JointKind;
use crate::transmission::evaluate;
use crate::workspace::Workspace;
use nalgebra::{Cholesky, SMatrix, SVector};

/// Kinetic and potential energy, J.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy<T> {
    /// `Σ ½ m |v_G|² + ½ I_G ω²`, J.
    pub kinetic: T,
    /// Gravity's potential `-Σ m g·r_G`, J (zero at the origin).
    pub potential: T,
}

/// Adds a force `f` (N, world) applied at world point `at` and a moment (N·m) to the
/// loads of link `body` (reduced to its COG).
pub(crate) fn add_load<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    loads: &mut SVector<T, POSE_ROWS>,
    body: u8,
    at: Vec2<T>,
    f: Vec2<T>,
    moment: T,
) {
    if body == 0 {
        return;
    }
    let g = ws.cog(model, body);
    let r = 3 * (body as usize - 1);
    for (row, val) in [
        (r, f.x),
        (r + 1, f.y),
        (r + 2, moment + cross(&(at - g), &f)),
    ] {
        if let Some(e) = loads.get_mut(row) {
            *e += val;
        }
    }
}

/// Applied loads `F`: gravity at every COG, the motors (through their motor element's
/// driver joint, reaction on the body it is mounted on) and the constant loads. Also
/// records each motor's torque in `ws.motor`.
pub fn applied_forces<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    t: T,
) -> Result<(), StepError> {
    // Built in place over the live rows (rows past the links stay zero).
    let mut f = core::mem::replace(&mut ws.force, SVector::zeros());
    let g = model.gravity();
    for (i, l) in model.links().iter().enumerate() {
        for (row, val) in [
            (3 * i, l.mass * g.x),
            (3 * i + 1, l.mass * g.y),
            (3 * i + 2, T::zero()),
        ] {
            if let Some(e) = f.get_mut(row) {
                *e = val;
            }
        }
    }
    add_external_loads(model, ws, &mut f);
    for (d, slot) in model.drives().iter().zip(ws.motor.iter_mut()) {
        let j = d.coord as usize;
        let (q, qd) = (
            ws.q.get(j).copied().unwrap_or(T::zero()),
            ws.qd.get(j).copied().unwrap_or(T::zero()),
        );
        let tau = d.motor.torque(t, q, qd);
        if !tau.finite() {
            return Err(StepError::NonFinite {
                time: t.to_f64(),
                what: "motor torque",
            });
        }
        *slot = tau;
    }
    for (d, tau) in model.drives().iter().zip(ws.motor) {
        let Some(grp) = model.groups().get(d.group as usize) else {
            continue;
        };
        for jt in grp.joints.iter() {
            let bi = ws.body.get(jt.i as usize).copied().unwrap_or_default();
            let bj = ws.body.get(jt.j as usize).copied().unwrap_or_default();
            let at = bi.o + rotate_cs(bi.c, bi.s, &jt.pi);
            match jt.kind {
                JointKind::DriveTorque => {
                    add_load(model, ws, &mut f, jt.i, at, Vec2::zeros(), tau);
                    add_load(model, ws, &mut f, jt.j, at, Vec2::zeros(), -tau);
                }
                JointKind::DriveForce { dir } => {
                    let u = rotate_cs(bj.c, bj.s, &dir) * tau;
                    add_load(model, ws, &mut f, jt.i, at, u, T::zero());
                    add_load(model, ws, &mut f, jt.j, at, -u, T::zero());
                }
                _ => {}
            }
        }
    }
    ws.force = f;
    Ok(())
}

/// Adds the model's constant loads and the workspace's caller-set moments
/// (`ws.applied_moment`) to `f` (shared by the equations of motion and the
/// kinetostatics).
pub(crate) fn add_external_loads<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    f: &mut SVector<T, POSE_ROWS>,
) {
    for ld in model.loads() {
        let b = ws.body.get(ld.body as usize).copied().unwrap_or_default();
        let at = b.o + rotate_cs(b.c, b.s, &ld.point);
        add_load(model, ws, f, ld.body, at, ld.force, ld.moment);
    }
    for (i, m) in ws
        .applied_moment
        .iter()
        .enumerate()
        .skip(1)
        .take(model.n_links())
    {
        if let Some(e) = f.get_mut(3 * (i - 1) + 2) {
            *e += *m;
        }
    }
}

/// `M·v` for a pose-space vector (`m` on the two translations, `I_G` on the rotation).
pub(crate) fn mass_times<T: Real>(
    model: &Model<T>,
    v: &SVector<T, POSE_ROWS>,
) -> SVector<T, POSE_ROWS> {
    let mut out = SVector::<T, POSE_ROWS>::zeros();
    for (i, l) in model.links().iter().enumerate() {
        for (k, m) in [(3 * i, l.mass), (3 * i + 1, l.mass), (3 * i + 2, l.inertia)] {
            if let (Some(o), Some(x)) = (out.get_mut(k), v.get(k)) {
                *o = m * *x;
            }
        }
    }
    out
}

/// Forward dynamics at `(t, q, q̇)`: kinematics, `V`, `a_b`, `F`, `VᵀMV`, `q̈`. Leaves
/// the workspace consistent: body and group accelerations are the actual ones.
pub fn forward<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
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
pub fn generalized_accelerations<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    t: T,
    q: &[T],
    qd: &[T],
) -> Result<(), StepError> {
    evaluate(model, ws, q, qd, t.to_f64())?;
    solve_accelerations(model, ws, t)
}

/// The second half of [`generalized_accelerations`]: applied loads, `VᵀMV`,
/// `Vᵀ(F - M a_b)` and `q̈`, at the kinematics the workspace already holds (from
/// [`evaluate`]). Lets a caller set loads that depend on the evaluated motion (a motor
/// law on a link that is not a coordinate, into `ws.applied_moment`) in between.
pub fn solve_accelerations<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    t: T,
) -> Result<(), StepError> {
    let time = t.to_f64();
    applied_forces(model, ws, t)?;
    let m = model.dof().min(MAX_DOF);
    let rows = 3 * model.n_links();
    // Live rows of F - M a_b and of the mass diagonal, then of each column of V, as
    // plain slices (no 2-D indexing in the inner products).
    let mut rhs = [T::zero(); POSE_ROWS];
    let mut mass = [T::zero(); POSE_ROWS];
    for (i, l) in model.links().iter().enumerate() {
        for (c, mi) in [l.mass, l.mass, l.inertia].into_iter().enumerate() {
            let row = 3 * i + c;
            if let (Some(r), Some(mm), Some(&f), Some(&ab)) = (
                rhs.get_mut(row),
                mass.get_mut(row),
                ws.force.get(row),
                ws.a_bias.get(row),
            ) {
                *r = f - mi * ab;
                *mm = mi;
            }
        }
    }
    let v = ws.v.as_slice();
    let col = |j: usize| v.get(j * POSE_ROWS..j * POSE_ROWS + rows).unwrap_or(&[]);
    let mut mq = SMatrix::<T, MAX_DOF, MAX_DOF>::identity();
    let mut gf = SVector::<T, MAX_DOF>::zeros();
    for j in 0..m {
        let vj = col(j);
        gf[j] = vj
            .iter()
            .zip(rhs.iter())
            .fold(T::zero(), |s, (a, b)| s + *a * *b);
        for k in 0..=j {
            let e = vj
                .iter()
                .zip(col(k).iter())
                .zip(mass.iter())
                .fold(T::zero(), |s, ((a, b), w)| s + *w * *a * *b);
            mq[(j, k)] = e;
            mq[(k, j)] = e;
        }
    }
    ws.mass_q = mq;
    ws.gen_force = gf;
    // Overflowing terms mean the state itself has run away (a step too large for the
    // motion makes the explicit integrator unstable): say so rather than blame the
    // configuration.
    if mq.iter().chain(gf.iter()).any(|v| !v.finite()) {
        return Err(StepError::NonFinite {
            time,
            what: "equations of motion (speeds overflow: the step is too large for the motion)",
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
            let chol = Cholesky::new(mq).ok_or(singular)?;
            let x = chol.solve(&gf);
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
            what: "generalized accelerations (the applied forces overflow them)",
        });
    }
    ws.qdd = qdd;
    ws.evaluations += 1;
    Ok(())
}

/// With `q̈` known: actual COG and origin accelerations of every body
/// (`a_G = a_b + V q̈`) and every group's `ẍ = ẍ_b + C q̈`.
pub fn finish_accelerations<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) {
    let qdd = SVector::<T, MAX_DOF>::from_column_slice(&ws.qdd);
    let a = ws.a_bias + ws.v * qdd;
    for (i, l) in model.links().iter().enumerate() {
        let Some(b) = ws.body.get_mut(i + 1) else {
            continue;
        };
        let r = rotate_cs(b.c, b.s, &l.cog);
        let (Some(&ax), Some(&ay), Some(&al)) = (a.get(3 * i), a.get(3 * i + 1), a.get(3 * i + 2))
        else {
            continue;
        };
        b.alpha = al;
        b.a = Vec2::new(ax, ay) - perp(&r) * al + r * (b.omega * b.omega);
    }
    for gd in ws.group.iter_mut().take(model.groups().len()) {
        let x = gd.dx_dq * qdd;
        for (k, o) in gd.xdd.iter_mut().enumerate() {
            *o = gd.xdd_bias.get(k).copied().unwrap_or(T::zero())
                + x.get(k).copied().unwrap_or(T::zero());
        }
    }
}

/// Kinetic and potential energy at the workspace's last evaluation.
pub fn energy<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> Energy<T> {
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
