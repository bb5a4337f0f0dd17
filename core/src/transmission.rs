//! Transmission matrices from the group models (SPEC 1, thesis 5.1.3), without
//! symbolic algebra:
//! - column j of `V = ∂P/∂q`: the COG velocities of a velocity pass with `q̇ = e_j`;
//! - `a_b = V̇ q̇`: the COG accelerations of an acceleration pass with `q̈ = 0`;
//! - `C = ∂x/∂q` (each group's transmission functions) from the same passes;
//! - `D = ∂²/∂q_j∂q_k` of `P` and `x` by polarization: the acceleration pass (`q̈ = 0`)
//!   at `q̇ = e_j + e_k`, minus those at `e_j` and `e_k`, halved.
//!
//! `P` stacks `(x_G, y_G, θ)` of every moving link: rows `3(i-1)..3i` for body `i`.

use crate::capacity::Capacity;
use crate::config::{MAX_BODIES, MAX_DOF, MAX_GROUPS, MAX_GROUP_VARS, POSE_ROWS};
use crate::error::StepError;
use crate::kinematics::{acceleration, position_with, unit_rate, velocity};
use crate::model::Model;
use crate::scalar::{perp, rotate_cs, Real, Vec2};
use crate::structomat::Angles;
use crate::structomat::GroupData;
use crate::workspace::{BodyState, Workspace};
use nalgebra::{SMatrix, SVector};

/// Writes the COG velocities (`ẋ_G, ẏ_G, θ̇` per link) of the last velocity pass into
/// column `j` of `V` and the groups' `ẋ` into column `j` of their `C`.
fn record_velocity_column<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    j: usize,
) {
    let Workspace { body, group, v, .. } = ws;
    // Column j of the column-major V: its live rows, 3 per link.
    if let Some(col) = v.as_mut_slice().get_mut(j * POSE_ROWS..(j + 1) * POSE_ROWS) {
        for ((l, b), rows) in model
            .links()
            .iter()
            .zip(body.iter().skip(1))
            .zip(col.chunks_exact_mut(3))
        {
            let r = rotate_cs(b.c, b.s, &l.cog);
            let vg = b.v + perp(&r) * b.omega;
            if let [x, y, w] = rows {
                (*x, *y, *w) = (vg.x, vg.y, b.omega);
            }
        }
    }
    for gd in group.iter_mut().take(model.groups().len()) {
        if let Some(col) = gd
            .dx_dq
            .as_mut_slice()
            .get_mut(j * MAX_GROUP_VARS..(j + 1) * MAX_GROUP_VARS)
        {
            col.copy_from_slice(&gd.xd);
        }
    }
}

/// COG accelerations (`ẍ_G, ÿ_G, θ̈` per link) of the last acceleration pass, into the
/// live rows of `a`.
pub(crate) fn cog_accelerations<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    bodies: &[BodyState<T>],
    a: &mut SVector<T, POSE_ROWS>,
) {
    // The live rows, 3 per link.
    for ((l, b), rows) in model
        .links()
        .iter()
        .zip(bodies.iter().skip(1))
        .zip(a.as_mut_slice().chunks_exact_mut(3))
    {
        let r = rotate_cs(b.c, b.s, &l.cog);
        let acc = b.a + perp(&r) * b.alpha - r * (b.omega * b.omega);
        if let [x, y, w] = rows {
            (*x, *y, *w) = (acc.x, acc.y, b.alpha);
        }
    }
}

/// Evaluates the kinematics at `(q, q̇)`: positions, `V`, `C`, `a_b` and each group's
/// `ẍ` bias. Leaves the bodies at the actual velocities and at the accelerations of
/// `q̈ = 0`. `time` (s) is for error messages.
pub fn evaluate<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    qd: &[T],
    time: f64,
) -> Result<(), StepError> {
    evaluate_with(model, ws, q, qd, time, Angles::Record)
}

/// [`evaluate`], the dyads' angles recorded or left stale (`angles`, see [`Angles`]).
pub fn evaluate_with<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    qd: &[T],
    time: f64,
    angles: Angles,
) -> Result<(), StepError> {
    evaluate_velocities(model, ws, q, qd, time, angles)?;
    let zero = [T::zero(); MAX_DOF];
    acceleration(model, ws, qd, &zero);
    cog_accelerations(model, &ws.body, &mut ws.a_bias);
    for gd in ws.group.iter_mut().take(model.groups().len()) {
        gd.xdd_bias = gd.xdd;
    }
    Ok(())
}

/// The first half of [`evaluate`]: positions, `V`, `C` and the actual velocities of the
/// bodies and groups, without the acceleration pass (the bodies' and groups'
/// accelerations are left as they were). For what needs speeds only, e.g. locating an
/// event whose function is a speed. `angles`: the dyads' link angles recorded or left
/// stale (see [`Angles`]).
pub fn evaluate_velocities<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    qd: &[T],
    time: f64,
    angles: Angles,
) -> Result<(), StepError> {
    if qd.iter().any(|v| !v.finite()) {
        return Err(StepError::NonFinite {
            time,
            what: "generalized speeds",
        });
    }
    position_with(model, ws, q, time, angles)?;
    let m = model.dof().min(MAX_DOF);
    let nb = (model.n_links() + 1).min(MAX_BODIES);
    for j in 0..m {
        velocity(model, ws, &unit_rate::<T>(j));
        record_velocity_column(model, ws, j);
    }
    // Where C was recorded: the next position pass predicts Newton's start from it.
    for (g, gd) in model.groups().iter().zip(ws.group.iter_mut()) {
        if g.kind.solved_by_newton() {
            gd.dx_dq_at = (ws.q, gd.x);
        }
    }
    let mut rates = [T::zero(); MAX_DOF];
    for (k, r) in rates.iter_mut().enumerate().take(m) {
        *r = qd.get(k).copied().unwrap_or(T::zero());
    }
    ws.qd = rates;
    let Workspace { body, group, v, .. } = ws;
    if let (1, [r, ..]) = (m, rates) {
        // One degree of freedom: the bodies and groups hold the pass at q̇ = e_0, and
        // speeds are linear in q̇: scaled by q̇_0, they are the actual speeds.
        for b in body.iter_mut().skip(1).take(nb - 1) {
            b.omega *= r;
            b.v *= r;
        }
        for gd in group.iter_mut().take(model.groups().len()) {
            for x in gd.xd.iter_mut() {
                *x *= r;
            }
        }
        return Ok(());
    }
    // Speeds are linear in q̇: the actual COG speeds are V q̇, and each frame origin's
    // follows as v_o = v_G - ω J R(θ) c (no further velocity pass).
    let mut vq = [T::zero(); POSE_ROWS];
    times_rates(v, &rates, m, &mut vq);
    for ((l, b), rows) in model
        .links()
        .iter()
        .zip(body.iter_mut().skip(1))
        .take(nb - 1)
        .zip(vq.chunks_exact(3))
    {
        if let [vx, vy, w] = rows {
            b.omega = *w;
            b.v = Vec2::new(*vx, *vy) - perp(&rotate_cs(b.c, b.s, &l.cog)) * *w;
        }
    }
    for gd in group.iter_mut().take(model.groups().len()) {
        let GroupData { xd, dx_dq, .. } = gd;
        times_rates(dx_dq, &rates, m, xd);
    }
    Ok(())
}

/// `out = M q̇` over the first `cols` columns of the column-major `M` (`V` or `C`),
/// column by column over their slices: each row summed in the columns' order, as
/// nalgebra's matrix-vector product does (the padding columns' rates are zero: they
/// add nothing); zeros for no column.
#[inline]
fn times_rates<T: Real, const R: usize>(
    m: &SMatrix<T, R, MAX_DOF>,
    rates: &[T; MAX_DOF],
    cols: usize,
    out: &mut [T],
) {
    if cols == 0 {
        out.fill(T::zero());
    }
    for (j, (col, r)) in m
        .as_slice()
        .chunks_exact(R)
        .zip(rates)
        .enumerate()
        .take(cols)
    {
        for (o, x) in out.iter_mut().zip(col) {
            *o = if j == 0 { *x * *r } else { *o + *x * *r };
        }
    }
}

/// Second derivatives `∂²P/∂q_j∂q_k` (into `pose`) and `∂²x/∂q_j∂q_k` of every group
/// (into `vars`, in sequence order) at the configuration of the last position pass, by
/// polarization. Overwrites the workspace's body velocities and accelerations: call
/// [`evaluate`] again before using them.
pub fn second_derivative<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    j: usize,
    k: usize,
    pose: &mut SVector<T, POSE_ROWS>,
    vars: &mut [[T; MAX_GROUP_VARS]; MAX_GROUPS],
) {
    let zero = [T::zero(); MAX_DOF];
    let pass = |rate: &[T; MAX_DOF], ws: &mut Workspace<T, C>| {
        velocity(model, ws, rate);
        acceleration(model, ws, rate, &zero);
        let mut x = [[T::zero(); MAX_GROUP_VARS]; MAX_GROUPS];
        for (row, gd) in x.iter_mut().zip(ws.group.iter()) {
            *row = gd.xdd;
        }
        let mut acc = SVector::<T, POSE_ROWS>::zeros();
        cog_accelerations(model, &ws.body, &mut acc);
        (acc, x)
    };
    let (ej, ek) = (unit_rate::<T>(j), unit_rate::<T>(k));
    let mut ejk = ej;
    for (a, b) in ejk.iter_mut().zip(ek.iter()) {
        *a += *b;
    }
    let (pj, xj) = pass(&ej, ws);
    let (pk, xk) = pass(&ek, ws);
    let (pjk, xjk) = pass(&ejk, ws);
    let half = T::c(0.5);
    *pose = (pjk - pj - pk) * half;
    for (g, ((a, b), c)) in vars
        .iter_mut()
        .zip(xjk.iter().zip(xj.iter()).zip(xk.iter()))
    {
        for (o, ((p, r), s)) in g.iter_mut().zip(a.iter().zip(b.iter()).zip(c.iter())) {
            *o = (*p - *r - *s) * half;
        }
    }
}
