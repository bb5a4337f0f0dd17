//! Kinematic passes over the motion-transmission sequence (thesis 3.2): each group is
//! solved in order from the ground, its output poles feeding the next groups.

use crate::capacity::Capacity;
use crate::config::{MAX_DOF, MAX_GROUP_VARS};
use crate::error::{GroupFault, GroupId, StepError};
use crate::model::Model;
use crate::scalar::Real;
use crate::structomat::{
    acceleration_pass, dyad_rrr, dyad_rrt, dyad_rtr, motor_r, newton, position_from_x,
    velocity_pass, Angles, Base, Group, GroupData, GroupKind, Term,
};
use crate::workspace::{BodyState, Workspace};

/// The identity of group `index` for error messages.
pub fn group_id<T: Real>(g: &Group<T>, index: usize) -> GroupId {
    let mut links = [0u8; crate::config::MAX_GROUP_LINKS];
    let mut count = 0u8;
    for (slot, l) in links.iter_mut().zip(g.links()) {
        *slot = l;
        count += 1;
    }
    // Ascending, as the thesis writes its groups (`RR-RR-RR(2,3,4,7)`).
    if let Some(used) = links.get_mut(..count as usize) {
        used.sort_unstable();
    }
    GroupId {
        index: index as u8,
        kind: g.kind,
        links,
        count,
    }
}

fn fail<T: Real>(g: &Group<T>, index: usize, time: f64, fault: GroupFault) -> StepError {
    StepError::Group {
        time,
        group: group_id(g, index),
        fault,
    }
}

/// Solves one group's position problem at the current branch or warm start; `qd` are
/// the rates of the evaluation that recorded the group's transmission functions (the
/// workspace's, for Newton's predictor).
fn solve_group<T: Real, C: Capacity<T>>(
    g: &Group<T>,
    gd: &mut GroupData<T>,
    model: &Model<T, C>,
    bodies: &mut [BodyState<T>],
    q: &[T],
    qd: &[T],
    angles: Angles,
) -> Result<T, GroupFault> {
    match g.kind {
        // Linear loop closures (TRT, RTT): one Newton step from anywhere is exact.
        k if k.solved_by_newton() => return newton::solve(g, gd, model, bodies, q, qd),
        // The RRR dyad factors W and places its links itself (closed forms).
        GroupKind::Rrr => {
            return dyad_rrr::solve(g, gd, model, bodies, model.singular_tol(), angles)
        }
        GroupKind::MotorR => return motor_r::position(g, gd, model, bodies, q),
        GroupKind::Rrt => dyad_rrt::solve(g, gd, model, bodies)?,
        GroupKind::Rtr => dyad_rtr::solve(g, gd, model, bodies)?,
        _ => {}
    }
    position_from_x(g, gd, model, bodies, q)
}

/// Position pass: places every link at the coordinates `q`. `time` (s) is only for
/// error messages. On error the workspace's group unknowns may have moved: callers that
/// must keep a last good state save and restore them ([`Simulation`](crate::Simulation)
/// does).
pub fn position<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    time: f64,
) -> Result<(), StepError> {
    position_with(model, ws, q, time, Angles::Record)
}

/// [`position`], the dyads' angles recorded or left stale (`angles`, see [`Angles`]).
pub fn position_with<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    time: f64,
    angles: Angles,
) -> Result<(), StepError> {
    position_by(model, ws, q, time, solve_group, angles)
}

/// A group's position solver: closed form where there is one, or Newton-Raphson.
/// Its last argument is `q̇` of the last evaluation ([`newton`]'s predictor).
type Solver<T, C> = fn(
    &Group<T>,
    &mut GroupData<T>,
    &Model<T, C>,
    &mut [BodyState<T>],
    &[T],
    &[T],
    Angles,
) -> Result<T, GroupFault>;

/// The position pass with a given group solver.
fn position_by<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    time: f64,
    solve: Solver<T, C>,
    angles: Angles,
) -> Result<(), StepError> {
    if q.iter().any(|v| !v.finite()) {
        return Err(StepError::NonFinite {
            time,
            what: "generalized coordinates",
        });
    }
    for (k, v) in ws.q.iter_mut().enumerate() {
        *v = q.get(k).copied().unwrap_or(T::zero());
    }
    // `ws.qd` still holds the rates of the last evaluation (of its velocity pass, which
    // sets them after this pass): those at which the groups' C and ẍ bias were recorded.
    let Workspace {
        body, group, qd, ..
    } = ws;
    for (i, (g, gd)) in model.groups().iter().zip(group.iter_mut()).enumerate() {
        let det = solve(g, gd, model, body, q, qd, angles).map_err(|f| fail(g, i, time, f))?;
        if !g.has_closed_form() && det * gd.det_sign < T::zero() {
            return Err(fail(g, i, time, GroupFault::BranchJump));
        }
    }
    Ok(())
}

/// Velocity pass at the rates `qd` (after a position pass).
pub fn velocity<T: Real, C: Capacity<T>>(model: &Model<T, C>, ws: &mut Workspace<T, C>, qd: &[T]) {
    let Workspace { body, group, .. } = ws;
    for (g, gd) in model.groups().iter().zip(group.iter_mut()) {
        velocity_pass(g, gd, model, body, qd);
    }
}

/// Acceleration pass at the rates `qd` and accelerations `qdd` (after the velocity pass
/// with the same `qd`).
pub fn acceleration<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    qd: &[T],
    qdd: &[T],
) {
    let Workspace { body, group, .. } = ws;
    for (g, gd) in model.groups().iter().zip(group.iter_mut()) {
        acceleration_pass(g, gd, model, body, qd, qdd);
    }
}

/// Whether unknown `k` of the group is an angle (else a slide length).
fn is_angle<T: Real>(g: &Group<T>, k: usize) -> bool {
    g.chains.iter().flat_map(|c| c.terms.iter()).any(|t| {
        let a = match t {
            Term::Arm { angle, .. } | Term::Slide { angle, .. } => angle,
        };
        a.base == Base::Var(k as u8)
    })
}

/// Distance from `x` to the group's guesses (angles compared modulo 2π).
fn distance_to_guess<T: Real>(g: &Group<T>, x: &[T; MAX_GROUP_VARS]) -> T {
    let mut d = T::zero();
    for k in 0..g.n_vars as usize {
        let (Some(&xk), Some(&gk)) = (x.get(k), g.guess.get(k)) else {
            continue;
        };
        let mut e = xk - gk;
        if is_angle(g, k) {
            e = (e + T::pi()).rem_euclid(T::two_pi()) - T::pi();
        }
        d += e * e;
    }
    d
}

trait RemEuclid {
    fn rem_euclid(self, m: Self) -> Self;
}
impl<T: Real> RemEuclid for T {
    fn rem_euclid(self, m: T) -> T {
        self - m * (self / m).floor()
    }
}

/// Assembles the mechanism at `q` from the groups' guesses (thesis tables: the initial
/// "conditions initiales"): each closed-form dyad takes the branch whose solution is
/// nearest its guesses; Newton groups start from them and record the sign of det W as
/// their branch.
pub fn assemble<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
) -> Result<(), StepError> {
    assemble_by(
        model,
        ws,
        q,
        "initial coordinates",
        |g, _| g.guess,
        |g, trial, _| distance_to_guess(g, &trial.x),
    )
}

/// Assembles the mechanism at `q` near the poses `near` (the same links under other
/// coordinates, [`crate::simulation::switch`]): each closed-form dyad takes the branch
/// that places its links nearest their poses there; Newton groups start from the link
/// angles read off them (slides from the guesses: the groups with slides Newton solves
/// are linear, one step from anywhere) and record the sign of det W as their branch.
pub(crate) fn assemble_near<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    near: &[BodyState<T>],
) -> Result<(), StepError> {
    assemble_by(
        model,
        ws,
        q,
        "coordinates to switch to",
        |g, _| {
            let mut x = g.guess;
            for p in g.placements.iter() {
                if let (Base::Var(k), Some(b)) = (p.angle.base, near.get(p.link as usize)) {
                    if let Some(v) = x.get_mut(k as usize) {
                        *v = b.theta - p.angle.offset;
                    }
                }
            }
            x
        },
        |g, _, body| {
            let mut d = T::zero();
            for l in g.links() {
                let (Some(a), Some(b)) = (body.get(l as usize), near.get(l as usize)) else {
                    continue;
                };
                let e = a.theta - b.theta;
                let e = (e + T::pi()).rem_euclid(T::two_pi()) - T::pi();
                d += (a.o - b.o).norm_squared() + e * e;
            }
            d
        },
    )
}

/// [`assemble`] with the Newton groups' starting unknowns `start(group, bodies)` and
/// the measure `distance(group, solved data, bodies)` by which a closed-form dyad picks
/// its branch; `what` names `q` if it is not finite.
fn assemble_by<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    what: &'static str,
    start: impl Fn(&Group<T>, &[BodyState<T>]) -> [T; MAX_GROUP_VARS],
    distance: impl Fn(&Group<T>, &GroupData<T>, &[BodyState<T>]) -> T,
) -> Result<(), StepError> {
    if q.iter().any(|v| !v.finite()) {
        return Err(StepError::NonFinite { time: 0.0, what });
    }
    for (k, v) in ws.q.iter_mut().enumerate() {
        *v = q.get(k).copied().unwrap_or(T::zero());
    }
    let Workspace { body, group, .. } = ws;
    for (i, (g, gd)) in model.groups().iter().zip(group.iter_mut()).enumerate() {
        *gd = GroupData::default();
        gd.x = start(g, body);
        match g.kind {
            GroupKind::Rrr | GroupKind::Rrt | GroupKind::Rtr => {
                // (distance, trial, whether it is the last trial that placed the links)
                let mut best: Option<(T, GroupData<T>, bool)> = None;
                let mut last_err = GroupFault::NonFiniteInput;
                for branch in [T::one(), -T::one()] {
                    let mut trial = *gd;
                    trial.branch = branch;
                    // This trial may move the links (even if it fails).
                    if let Some((_, _, placed)) = best.as_mut() {
                        *placed = false;
                    }
                    match solve_group(g, &mut trial, model, body, q, &[], Angles::Record) {
                        Ok(_) => {
                            let d = distance(g, &trial, body);
                            if best.as_ref().is_none_or(|(bd, _, _)| d < *bd) {
                                best = Some((d, trial, true));
                            }
                        }
                        Err(e) => last_err = e,
                    }
                }
                let Some((_, chosen, placed)) = best else {
                    return Err(fail(g, i, 0.0, last_err));
                };
                *gd = chosen;
                // Re-place with the chosen branch if a losing trial placed the links
                // after it (a closed form's solve is a function of its inputs: placing
                // again would give the same bits).
                if !placed {
                    solve_group(g, gd, model, body, q, &[], Angles::Record)
                        .map_err(|f| fail(g, i, 0.0, f))?;
                }
            }
            _ => {
                let det = solve_group(g, gd, model, body, q, &[], Angles::Record)
                    .map_err(|f| fail(g, i, 0.0, f))?;
                gd.det_sign = if det < T::zero() { -T::one() } else { T::one() };
            }
        }
    }
    Ok(())
}

/// The unit rates `e_j` (`q̇ = e_j`) used to build the transmission matrices.
pub(crate) fn unit_rate<T: Real>(j: usize) -> [T; MAX_DOF] {
    let mut e = [T::zero(); MAX_DOF];
    if let Some(v) = e.get_mut(j) {
        *v = T::one();
    }
    e
}

/// Position pass that solves *every* group by Newton-Raphson from its current unknowns
/// (the thesis's method), instead of the dyads' closed forms: the second method the
/// closed forms are tested against.
pub fn position_newton<T: Real, C: Capacity<T>>(
    model: &Model<T, C>,
    ws: &mut Workspace<T, C>,
    q: &[T],
    time: f64,
) -> Result<(), StepError> {
    position_by(
        model,
        ws,
        q,
        time,
        |g, gd, model, bodies, q, qd, _| newton::solve(g, gd, model, bodies, q, qd),
        Angles::Record,
    )
}
