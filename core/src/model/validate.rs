//! The checks a model passes before any step runs on it: every reference in range,
//! every value finite, the groups' sequence solvable in order (each group's inputs
//! known when it is reached), the drives and loads on existing bodies.

use super::Model;
use crate::capacity::Capacity;
use crate::config::{MAX_DOF, MAX_LINKS};
use crate::error::ModelError;
use crate::scalar::{Real, Vec2};
use crate::structomat::{Base, Group, GroupKind, JointKind, Length, Term};

/// Validates a declared model and completes its derived data (Newton tolerance, the
/// drives' motor elements): the end of [`ModelBuilder::build`](super::ModelBuilder::build) and
/// [`ModelBuilder::finish`](super::ModelBuilder::finish).
pub(super) fn validate<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<(), ModelError> {
    let size = validate_bodies(m)?;
    // After the points: a group's values derive from them, and a non-finite point
    // is named as such above.
    for (k, g) in m.groups.iter().enumerate() {
        if let Err(what) = group_values_finite(g) {
            return Err(ModelError::GroupNonFinite {
                group: k as u8,
                kind: g.kind,
                what,
            });
        }
    }
    check_sequence(m)?;
    validate_drives_and_loads(m, size)
}

/// [`validate`] for a model rebuilt in place whose sequence is known to be valid and
/// whose group constructors are known to derive their values from its points only,
/// apart from the guesses (the converter's modes, [`ModelBuilder::finish_rebuilt`](super::ModelBuilder::finish_rebuilt)):
/// the same checks of the links, ground points, guesses, drives and loads, the same
/// Newton tolerance, but no walk of the sequence and of the groups' derived values,
/// which a finite mechanism of finite size squared keeps finite (differences of its
/// points, their lengths, directions and angles). `dof` is the number of coordinates
/// the sequence drives.
pub(super) fn validate_rebuilt<T: Real, C: Capacity<T>>(
    m: &mut Model<T, C>,
    dof: u8,
) -> Result<(), ModelError> {
    let size = validate_bodies(m)?;
    for (k, g) in m.groups.iter().enumerate() {
        if !g.guess.iter().all(|x| x.finite()) {
            return Err(ModelError::GroupNonFinite {
                group: k as u8,
                kind: g.kind,
                what: "a guess",
            });
        }
    }
    m.dof = dof;
    validate_drives_and_loads(m, size)
}

/// The first part of [`validate`]: gravity, the singularity threshold, the ground
/// points and the links, and the Newton tolerance from the mechanism's scale; returns
/// the mechanism's size (twice its largest coordinate, m).
fn validate_bodies<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<T, ModelError> {
    if !(m.gravity.x.finite() && m.gravity.y.finite()) {
        return Err(ModelError::NonFinite("gravity"));
    }
    if !(m.singular_tol.finite() && m.singular_tol > T::zero()) {
        return Err(ModelError::NotPositive("singularity threshold"));
    }
    let mut scale = T::one();
    for p in m.ground.iter() {
        finite2(p, "ground point")?;
        scale = scale.max(p.x.abs()).max(p.y.abs());
    }
    for l in m.links.iter() {
        mass_properties(l.mass, l.inertia, &l.cog)?;
        for p in l.points.iter() {
            finite2(p, "link point")?;
            scale = scale.max(p.x.abs()).max(p.y.abs());
        }
    }
    // The step squares distances (closed forms, Newton's residual, speeds) and
    // multiplies masses by gravity and heights (weights, potential energy): a
    // description finite in itself can still overflow there (a point at 1e200 m; in
    // f32 past 1.8e19 m). Twice the largest coordinate bounds every distance.
    let cogs = m
        .links
        .iter()
        .fold(T::zero(), |a, l| a.max(l.cog.x.abs()).max(l.cog.y.abs()));
    let size = T::c(2.0) * scale.max(cogs);
    if !(size * size).finite() {
        return Err(ModelError::Overflow("the mechanism's size squared"));
    }
    let g = m.gravity.x.abs().max(m.gravity.y.abs());
    for l in m.links.iter() {
        if !(l.mass * size * size + l.inertia).finite() {
            return Err(ModelError::Overflow(
                "a link's moment of inertia about a point of the mechanism",
            ));
        }
        if !(l.mass * g * size).finite() {
            return Err(ModelError::Overflow(
                "a link's weight times the mechanism's size (its potential energy)",
            ));
        }
    }
    // Newton stops at 64 ulps of the mechanism's size in f64 (1.4e-14 m per metre)
    // and at 8 ulps in f32 (9.5e-7 m per metre). f32's 64 ulps, 7.6e-6 m per metre,
    // left the joints of a triad or of A68's six-link group that far apart, and that
    // broke the twin's energy balance at S2's dead points (0.1789 s, in 16 sub-steps
    // too). f32's residual gets under 1 ulp; 8 still takes at most one iteration a
    // solve in S2, as 64 did.
    m.newton_tol = T::c(64.0 * f64::EPSILON).max(T::c(8.0) * T::EPS) * scale;
    Ok(size)
}

/// The last part of [`validate`], after the sequence: each drive's motor element and
/// motor law, each load's body and values (`size`: the mechanism's, m).
fn validate_drives_and_loads<T: Real, C: Capacity<T>>(
    m: &mut Model<T, C>,
    size: T,
) -> Result<(), ModelError> {
    let Model {
        drives,
        groups,
        dof,
        loads,
        links,
        ..
    } = m;
    for d in drives.iter_mut() {
        if let Some(on) = d.joint {
            let (body, on) = (d.group, on);
            let (g, j) = joint_between(groups, body, on).ok_or(ModelError::Coordinates(
                "a drive across a joint names bodies that no revolute or prismatic joint of the group placing the first joins",
            ))?;
            (d.group, d.joint) = (g, Some(j));
            d.motor.validate()?;
            continue;
        }
        if d.coord >= *dof {
            return Err(ModelError::Coordinates(
                "a drive names a coordinate no motor element has",
            ));
        }
        d.group = groups
            .iter()
            .position(|g| g.coord == Some(d.coord))
            .map(|k| k as u8)
            .ok_or(ModelError::Coordinates(
                "a drive names a coordinate no motor element has",
            ))?;
        d.motor.validate()?;
    }
    for l in loads.iter() {
        if l.body == 0 || l.body as usize > links.len() {
            return Err(ModelError::UnknownReference("load: body"));
        }
        finite2(&l.point, "load point")?;
        finite2(&l.force, "load force")?;
        finite(l.moment, "load moment")?;
        let size = size.max(T::c(2.0) * l.point.x.abs().max(l.point.y.abs()));
        if !((l.force.x.abs() + l.force.y.abs()) * size + l.moment.abs()).finite() {
            return Err(ModelError::Overflow(
                "a load's moment about a point of the mechanism",
            ));
        }
    }
    Ok(())
}

/// The group that places link `body` and the index of its revolute or prismatic joint
/// from `body` to `on`.
fn joint_between<T: Real>(groups: &[Group<T>], body: u8, on: u8) -> Option<(u8, u8)> {
    let (g, grp) = groups
        .iter()
        .enumerate()
        .find(|(_, g)| g.links().any(|l| l == body))?;
    let j = grp.joints.iter().position(|jt| {
        jt.i == body
            && jt.j == on
            && matches!(jt.kind, JointKind::Revolute | JointKind::Prismatic { .. })
    })?;
    Some((g as u8, j as u8))
}

/// Every value of a built group is finite, or the name of the first that is not.
fn group_values_finite<T: Real>(g: &Group<T>) -> Result<(), &'static str> {
    let ok = |x: T, what| if x.finite() { Ok(()) } else { Err(what) };
    let ok2 = |v: &Vec2<T>, what| ok(v.x, what).and_then(|()| ok(v.y, what));
    for x in g.guess.iter() {
        ok(*x, "a guess")?;
    }
    for x in g.consts.iter() {
        ok(*x, "a length or angle of its closed form")?;
    }
    for c in g.chains.iter() {
        for t in c.terms.iter() {
            match t {
                Term::Arm { angle, v } => {
                    ok(angle.offset, "an angle offset")?;
                    ok2(v, "an arm (a link's joint-to-joint vector)")?;
                }
                Term::Slide { angle, dir, .. } => {
                    ok(angle.offset, "a guide angle")?;
                    ok2(dir, "a guide direction")?;
                }
            }
        }
    }
    for p in g.placements.iter() {
        ok(p.angle.offset, "an angle offset")?;
        ok2(&p.local, "a link point")?;
    }
    for j in g.joints.iter() {
        ok2(&j.pi, "a joint point")?;
        ok2(&j.pj, "a joint point")?;
        if let JointKind::Prismatic { dir } | JointKind::DriveForce { dir } = j.kind {
            ok2(&dir, "a guide direction")?;
        }
    }
    Ok(())
}

/// A link's mass (kg), moment of inertia (kg·m²) and COG (m): finite, the first two not
/// negative.
pub(super) fn mass_properties<T: Real>(
    mass: T,
    inertia: T,
    cog: &Vec2<T>,
) -> Result<(), ModelError> {
    finite(mass, "link mass")?;
    finite(inertia, "link inertia")?;
    finite2(cog, "link COG")?;
    if mass < T::zero() {
        return Err(ModelError::Negative("link mass"));
    }
    if inertia < T::zero() {
        return Err(ModelError::Negative("link inertia"));
    }
    Ok(())
}

fn finite<T: Real>(x: T, what: &'static str) -> Result<(), ModelError> {
    if x.finite() {
        Ok(())
    } else {
        Err(ModelError::NonFinite(what))
    }
}

fn finite2<T: Real>(v: &Vec2<T>, what: &'static str) -> Result<(), ModelError> {
    finite(v.x, what)?;
    finite(v.y, what)
}

/// Checks that the sequence places every link once, each group using only what earlier
/// groups placed, and that the coordinates are `0..dof`, each driven.
fn check_sequence<T: Real, C: Capacity<T>>(m: &mut Model<T, C>) -> Result<(), ModelError> {
    let mut placed = [false; MAX_LINKS + 1];
    placed[0] = true;
    let mut coord_used = [false; MAX_DOF];
    let n_links = m.links.len();
    let known = |placed: &[bool], b: u8| placed.get(b as usize).copied().unwrap_or(false);
    for (gi, g) in m.groups.iter().enumerate() {
        let gi = gi as u8;
        let err = |why| ModelError::Sequence { group: gi, why };
        for ch in g.chains.iter() {
            if !known(&placed, ch.start.body) || ch.end.is_some_and(|e| !known(&placed, e.body)) {
                return Err(err("an input pole is on a link no earlier group places"));
            }
            for t in ch.terms.iter() {
                let (angle, len) = match t {
                    Term::Arm { angle, .. } => (angle, None),
                    Term::Slide { angle, s, .. } => (angle, Some(*s)),
                };
                match angle.base {
                    Base::Body(b) if !known(&placed, b) => {
                        return Err(err("a guide is on a link no earlier group places"))
                    }
                    Base::Var(k) if k >= g.n_vars => return Err(err("unknown index out of range")),
                    Base::Coord(j) if j as usize >= MAX_DOF => {
                        return Err(ModelError::Capacity("coordinates"))
                    }
                    _ => {}
                }
                match len {
                    Some(Length::Var(k)) if k >= g.n_vars => {
                        return Err(err("unknown index out of range"))
                    }
                    Some(Length::Coord(j)) if j as usize >= MAX_DOF => {
                        return Err(ModelError::Capacity("coordinates"))
                    }
                    _ => {}
                }
            }
        }
        if g.chains.iter().filter(|c| c.end.is_some()).count() * 2 != g.n_vars as usize {
            return Err(err("unknowns and loop-closure equations differ in number"));
        }
        for p in g.placements.iter() {
            if p.link == 0 || p.link as usize > n_links {
                return Err(ModelError::UnknownReference("group: link"));
            }
            if known(&placed, p.link) {
                return Err(err("places a link an earlier group placed"));
            }
            if p.chain as usize >= g.chains.len() {
                return Err(err("placement on a missing chain"));
            }
        }
        for p in g.placements.iter() {
            if let Some(s) = placed.get_mut(p.link as usize) {
                *s = true;
            }
        }
        for j in g.joints.iter() {
            if !known(&placed, j.j) || !known(&placed, j.i) {
                return Err(err("a joint names a link that is not placed"));
            }
        }
        if let Some(c) = g.coord {
            let slot = coord_used
                .get_mut(c as usize)
                .ok_or(ModelError::Capacity("coordinates"))?;
            *slot = true;
            if !matches!(g.kind, GroupKind::MotorR | GroupKind::MotorT) {
                return Err(err("only motor elements drive coordinates"));
            }
        }
    }
    if let Some(k) = placed.iter().take(n_links + 1).position(|p| !p) {
        return Err(ModelError::Unplaced { link: k as u8 });
    }
    let dof = coord_used.iter().rposition(|u| *u).map_or(0, |k| k + 1);
    if coord_used.iter().take(dof).any(|u| !u) {
        return Err(ModelError::Coordinates(
            "a coordinate below the highest one is driven by no motor element",
        ));
    }
    m.dof = dof as u8;
    Ok(())
}
