//! Builds the core model of one mode and coordinate choice (SPEC 3's sequences) from
//! the converter's parameters and the current physical pose: nothing here is
//! hand-written kinematics, only links, ground points and groups, as in
//! [`mechanisms`](crate::mechanisms).
//!
//! A mode's model differs from the others in ways that depend on the state: a locked
//! lever is part of the ground (its pin is a ground point where it stopped), A68 joins
//! both levers and the shaft into one body (their angle difference is the one at
//! engagement), and every group's guesses are the current link angles so that assembly
//! keeps the current branch. So models are built at each mode or coordinate switch
//! (bounded work, no heap), and model bodies are mapped to the physical links.

use super::mode::{Clutch, Coordinates, Mode};
use super::params::{circle_meet, CccParams};
use crate::capacity::Capacity;
use crate::config::MAX_BODIES;
use crate::error::ModelError;
use crate::model::{Link, Model, ModelBuilder};
use crate::scalar::{unit, Real, Vec2};
use crate::structomat::{
    AssurGroup, AssurJoint, AssurLoop, AssurStep, DyadRrr, MotorR, PointRef, TriadRrRrRr,
};
use core::ops::DerefMut;

/// Physical link numbers (SPEC 3).
pub(crate) const CRANK: usize = 1;
pub(crate) const COUPLER: usize = 2;
pub(crate) const ROCKER: usize = 3;
pub(crate) const SWING: usize = 4;
/// The rods and levers of the two diode branches: `(rod, lever)`.
pub(crate) const BRANCHES: [(usize, usize); 2] = [(5, 6), (7, 8)];

/// Point indices in the link frames. Bars run from their point 0 to their point 1:
/// crank A→B, coupler B→C, rocker E→C (D is its point 2), swing link F→E, rods D→G and
/// D→I, levers H→G and H→I (the joined levers of A68: H, G, I).
const P0: u8 = 0;
const P1: u8 = 1;
const ROCKER_D: u8 = 2;
const JOINED_I: u8 = 2;
const _: () = assert!(crate::config::MAX_LINK_POINTS >= 3, "the rocker carries D");

/// Where each physical link is in a mode's model.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BodyMap<T> {
    /// Model body of physical link `p` (index `p`, 1..=8); 0 for a locked lever.
    pub body: [u8; 9],
    /// Angle of lever 6 and of lever 8 (`BRANCHES` order) minus its model body's angle
    /// (lever 8 in A68); for a locked lever, its fixed angle, rad. The other links are
    /// their bodies (offset 0): two values, not nine, keep the three slots of
    /// `Twin<f32>` within its RAM budget.
    pub lever_offset: [T; 2],
    /// Physical link of each model body (index: body), for naming groups.
    pub phys: [u8; MAX_BODIES],
    /// The physical link whose angle each coordinate is.
    pub coord_link: [u8; 2],
    /// Degrees of freedom.
    pub dof: usize,
}

fn lever_point<T: Real>(p: &CccParams<T>, lever: usize, angle: T) -> Vec2<T> {
    p.h + unit(angle) * p.link(lever).length
}

/// Physical link `k` as a core link: a bar with its COG at its midpoint; the rocker
/// also carries D (its point 2) and the oscillating mass.
pub(crate) fn physical_link<T: Real>(p: &CccParams<T>, k: usize) -> Link<T> {
    let b = p.link(k);
    let mut link = Link::bar(b.length, b.mass, b.inertia, b.length * T::c(0.5));
    if k == ROCKER {
        // Capacity: a bar has 2 of MAX_LINK_POINTS >= 3 points.
        let _ = link.add_point(Vec2::new(p.rocker_d, T::zero()));
        link.add_mass(p.mass, p.mass_inertia, Vec2::new(p.mass_at, T::zero()));
    }
    link
}

/// The core model of `mode` driven by `coords` at the physical link angles `pose` (rad,
/// index 1..=8) and the values of its coordinates there: what the twin integrates in
/// that mode. Model bodies follow the physical numbering with the locked levers left
/// out (they are ground) and, in A68, lever 8 joined to lever 6.
pub fn mode_model<T: Real>(
    p: &CccParams<T>,
    mode: Mode,
    coords: Coordinates,
    pose: &[T; 9],
) -> Result<(Model<T>, [T; 2]), ModelError> {
    let (model, map) = build(p, mode, coords, pose)?;
    Ok((model, map.coordinates_at(pose)))
}

impl<T: Real> BodyMap<T> {
    /// Angle of physical link `p` minus its model body's angle; for a locked lever,
    /// its fixed angle, rad (0 for every link but the levers).
    pub(crate) fn offset(&self, p: usize) -> T {
        let [(_, l6), (_, l8)] = BRANCHES;
        let [o6, o8] = self.lever_offset;
        if p == l6 {
            o6
        } else if p == l8 {
            o8
        } else {
            T::zero()
        }
    }

    /// The coordinates' values at the physical angles `pose` (unused slots 0).
    pub(crate) fn coordinates_at(&self, pose: &[T; 9]) -> [T; 2] {
        let mut q = [T::zero(); 2];
        for (qj, link) in q.iter_mut().zip(self.coord_link.iter()).take(self.dof) {
            *qj = pose.get(*link as usize).copied().unwrap_or(T::zero());
        }
        q
    }
}

/// The model of `mode` driven by `coords`, at the physical link angles `pose` (rad,
/// index 1..=8: group guesses, locked levers' angles, A68's lever offset).
pub(crate) fn build<T: Real>(
    p: &CccParams<T>,
    mode: Mode,
    coords: Coordinates,
    pose: &[T; 9],
) -> Result<(Model<T>, BodyMap<T>), ModelError> {
    let mut b = ModelBuilder::new();
    let map = declare(&mut b, p, mode, coords, pose)?;
    Ok((b.build()?, map))
}

/// [`build`] into `model`, in place (the twin's step path: no model on the stack). On
/// an error `model` is half-built. The declaration of each mode and coordinate choice
/// passes the full validation (the tests build them all with [`build`]), so only what
/// the pose and the parameters can make invalid is checked again
/// ([`ModelBuilder::finish_rebuilt`]): the same model, the same errors.
pub(crate) fn build_into<T: Real, C: Capacity<T>>(
    p: &CccParams<T>,
    mode: Mode,
    coords: Coordinates,
    pose: &[T; 9],
    model: &mut Model<T, C>,
) -> Result<BodyMap<T>, ModelError> {
    let mut b = ModelBuilder::in_place(model);
    let map = declare(&mut b, p, mode, coords, pose)?;
    b.finish_rebuilt(map.dof as u8)?;
    Ok(map)
}

/// Declares the model of [`build`] into the builder `b`; returns the body map.
fn declare<T: Real, C: Capacity<T>, M: DerefMut<Target = Model<T, C>>>(
    b: &mut ModelBuilder<T, M>,
    p: &CccParams<T>,
    mode: Mode,
    coords: Coordinates,
    pose: &[T; 9],
) -> Result<BodyMap<T>, ModelError> {
    if !mode.coordinate_choices().contains(&coords) {
        return Err(ModelError::Coordinates(
            "converter: this coordinate choice does not drive this mode",
        ));
    }
    let th = |k: usize| pose.get(k).copied().unwrap_or(T::zero());
    b.gravity(p.gravity);
    let a = b.ground_point(p.a.x, p.a.y)?;
    let f = b.ground_point(p.f.x, p.f.y)?;
    let h = b.ground_point(p.h.x, p.h.y)?;
    let mut map = BodyMap {
        body: [0; 9],
        lever_offset: [T::zero(); 2],
        phys: [0; MAX_BODIES],
        coord_link: [0; 2],
        dof: mode.dof(),
    };
    let clutches = mode.clutches();
    let joined = mode == Mode::A68;
    // Locked levers: their pins become ground points.
    let mut pin = [None; 2];
    for (k, (_, lever)) in BRANCHES.iter().enumerate() {
        if clutches[k] == Clutch::Locked {
            let at = lever_point(p, *lever, th(*lever));
            pin[k] = Some(b.ground_point(at.x, at.y)?);
            if let Some(o) = map.lever_offset.get_mut(k) {
                *o = th(*lever);
            }
        }
    }
    // Links, in physical order.
    for k in 1..=8 {
        let lever_branch = BRANCHES.iter().position(|(_, l)| *l == k);
        if let Some(br) = lever_branch {
            if clutches[br] == Clutch::Locked {
                continue;
            }
            if joined && k == 8 {
                map.body[8] = map.body[6];
                map.lever_offset[1] = th(8) - th(6);
                continue;
            }
        }
        let mut link = physical_link(p, k);
        if joined && k == 6 {
            // Lever 6's frame; lever 8 at the angle it had at engagement.
            let d = th(8) - th(6);
            let u = unit(d);
            let l8 = p.link(8);
            link.add_point(u * l8.length)?;
            link.add_mass(l8.mass, l8.inertia, u * (l8.length * T::c(0.5)));
        }
        let shaft_on_this = match lever_branch {
            Some(br) => clutches[br] == Clutch::Engaged && !(joined && k == 8),
            None => false,
        };
        if shaft_on_this && p.shaft_inertia > T::zero() {
            // The shaft turns with this lever about H, the lever's origin.
            link.add_mass(T::zero(), p.shaft_inertia, Vec2::zeros());
        }
        let body = b.link(link)?;
        map.body[k] = body;
        if let Some(slot) = map.phys.get_mut(body as usize) {
            *slot = k as u8;
        }
    }
    let bodies = map.body;
    let body = |k: usize| bodies.get(k).copied().unwrap_or(0);
    let pt = |k: usize, point: u8| PointRef {
        body: body(k),
        point,
    };
    let motor = |b: &mut ModelBuilder<T, M>,
                 link: usize,
                 pivot: PointRef,
                 link_point: u8,
                 coord: u8|
     -> Result<(), ModelError> {
        b.group_in_place(&MotorR {
            link: body(link),
            pivot,
            link_point,
            coord,
            offset: T::zero(),
        })?;
        Ok(())
    };
    // Dyad RRR of links `la` (on pole `pa` at its point `a_at`, joint at `a_j`) and
    // `lb` (on `pb` at `b_at`, joint at `b_j`), guessed at the current angles.
    let rrr = |b: &mut ModelBuilder<T, M>,
               (la, pa, a_at, a_j): (usize, PointRef, u8, u8),
               (lb, pb, b_at, b_j): (usize, PointRef, u8, u8)|
     -> Result<(), ModelError> {
        b.group_in_place(&DyadRrr {
            a: body(la),
            b: body(lb),
            pole_a: pa,
            a_at_pole: a_at,
            pole_b: pb,
            b_at_pole: b_at,
            a_joint: a_j,
            b_joint: b_j,
            guess: [th(la), th(lb)],
        })?;
        Ok(())
    };
    // Recurring dyads: the crank and coupler from C (RRR(1,2)), the rocker and swing
    // link from D (RRR(3,4)), a free diode branch from D (RRR(rod, lever)).
    let crank_from_c =
        |b: &mut ModelBuilder<T, M>| rrr(b, (COUPLER, pt(ROCKER, P1), P1, P0), (CRANK, a, P0, P1));
    let rocker_from = |b: &mut ModelBuilder<T, M>, d: PointRef| {
        rrr(b, (ROCKER, d, ROCKER_D, P0), (SWING, f, P0, P1))
    };
    let free_branch = |b: &mut ModelBuilder<T, M>, k: usize| {
        let (rod, lever) = BRANCHES[k];
        rrr(b, (rod, pt(ROCKER, ROCKER_D), P0, P1), (lever, h, P0, P1))
    };
    let locked = clutches.iter().position(|c| *c == Clutch::Locked);
    match coords {
        Coordinates::CrankSwing => {
            motor(b, CRANK, a, P0, 0)?;
            motor(b, SWING, f, P0, 1)?;
            rrr(
                b,
                (COUPLER, pt(CRANK, P1), P0, P1),
                (ROCKER, pt(SWING, P1), P0, P1),
            )?;
            map.coord_link = [CRANK as u8, SWING as u8];
        }
        Coordinates::CrankCoupler => {
            motor(b, CRANK, a, P0, 0)?;
            motor(b, COUPLER, pt(CRANK, P1), P0, 1)?;
            rrr(b, (ROCKER, pt(COUPLER, P1), P1, P0), (SWING, f, P0, P1))?;
            map.coord_link = [CRANK as u8, COUPLER as u8];
        }
        Coordinates::SwingRocker => {
            motor(b, SWING, f, P0, 0)?;
            motor(b, ROCKER, pt(SWING, P1), P0, 1)?;
            crank_from_c(b)?;
            map.coord_link = [SWING as u8, ROCKER as u8];
        }
        Coordinates::Crank if joined => {
            // A68 driven by its crank (SPEC 3: crank reversals happen in A68 too, and
            // the lever cannot carry the crank through them): R(1) + the six-link
            // Assur group of links 2, 3, 4, 5, 7 and the joined levers, 9 joints.
            motor(b, CRANK, a, P0, 0)?;
            let (rod5, lever6) = BRANCHES[0];
            let (rod7, _) = BRANCHES[1];
            let links = [
                body(COUPLER),
                body(ROCKER),
                body(SWING),
                body(rod5),
                body(rod7),
                body(lever6),
            ];
            let (l2, l3, l4, l5, l7, l6) = (0, 1, 2, 3, 4, 5);
            let step = |link: u8, from: u8, to: u8| AssurStep { link, from, to };
            // From B: to F through the rocker and swing link, and to H through each
            // rod and its lever.
            let to_f = [step(l2, P0, P1), step(l3, P1, P0), step(l4, P1, P0)];
            let to_h6 = [
                step(l2, P0, P1),
                step(l3, P1, ROCKER_D),
                step(l5, P0, P1),
                step(l6, P1, P0),
            ];
            let to_h8 = [
                step(l2, P0, P1),
                step(l3, P1, ROCKER_D),
                step(l7, P0, P1),
                step(l6, JOINED_I, P0),
            ];
            let start = pt(CRANK, P1);
            let joint = |link: usize, at: u8, other: PointRef| AssurJoint {
                link: body(link),
                at,
                other,
            };
            b.group_in_place(&AssurGroup {
                links: &links,
                loops: &[
                    AssurLoop {
                        start,
                        steps: &to_f,
                        end: f,
                    },
                    AssurLoop {
                        start,
                        steps: &to_h6,
                        end: h,
                    },
                    AssurLoop {
                        start,
                        steps: &to_h8,
                        end: h,
                    },
                ],
                joints: &[
                    joint(COUPLER, P0, pt(CRANK, P1)),
                    joint(ROCKER, P1, pt(COUPLER, P1)),
                    joint(SWING, P1, pt(ROCKER, P0)),
                    joint(SWING, P0, f),
                    joint(rod5, P0, pt(ROCKER, ROCKER_D)),
                    joint(rod7, P0, pt(ROCKER, ROCKER_D)),
                    joint(lever6, P1, pt(rod5, P1)),
                    joint(lever6, JOINED_I, pt(rod7, P1)),
                    joint(lever6, P0, h),
                ],
                guess: &[
                    th(COUPLER),
                    th(ROCKER),
                    th(SWING),
                    th(rod5),
                    th(rod7),
                    th(lever6),
                ],
            })?;
            map.coord_link = [CRANK as u8, 0];
            return Ok(map);
        }
        Coordinates::Crank | Coordinates::Swing | Coordinates::Rod => {
            let Some(k) = locked.filter(|_| mode.dof() == 1) else {
                return Err(ModelError::Coordinates(
                    "converter: this coordinate choice needs one locked lever",
                ));
            };
            let (rod, _) = BRANCHES[k];
            let pin = pin[k].ok_or(ModelError::Coordinates("converter: no locked pin"))?;
            match coords {
                Coordinates::Crank => {
                    motor(b, CRANK, a, P0, 0)?;
                    b.group_in_place(&TriadRrRrRr {
                        ternary: body(ROCKER),
                        ternary_joints: [P1, P0, ROCKER_D],
                        binary: [body(COUPLER), body(SWING), body(rod)],
                        binary_at_pole: [P0, P0, P1],
                        binary_at_ternary: [P1, P1, P0],
                        poles: [pt(CRANK, P1), f, pin],
                        guess: [th(COUPLER), th(SWING), th(rod), th(ROCKER)],
                    })?;
                    map.coord_link = [CRANK as u8, 0];
                }
                Coordinates::Swing => {
                    motor(b, SWING, f, P0, 0)?;
                    rrr(b, (ROCKER, pt(SWING, P1), P0, ROCKER_D), (rod, pin, P1, P0))?;
                    crank_from_c(b)?;
                    map.coord_link = [SWING as u8, 0];
                }
                _ => {
                    motor(b, rod, pin, P1, 0)?;
                    rocker_from(b, pt(rod, P0))?;
                    crank_from_c(b)?;
                    map.coord_link = [rod as u8, 0];
                }
            }
            free_branch(b, 1 - k)?;
            map.dof = 1;
            return Ok(map);
        }
        Coordinates::Lever => {
            let (rod5, lever6) = BRANCHES[0];
            let (rod7, _) = BRANCHES[1];
            motor(b, lever6, h, P0, 0)?;
            rrr(
                b,
                (rod5, pt(lever6, P1), P1, P0),
                (rod7, pt(lever6, JOINED_I), P1, P0),
            )?;
            rocker_from(b, pt(rod5, P0))?;
            crank_from_c(b)?;
            map.coord_link = [lever6 as u8, 0];
            return Ok(map);
        }
        Coordinates::Rest => {
            let (Some(g), Some(i)) = (pin[0], pin[1]) else {
                return Err(ModelError::Coordinates(
                    "converter: rest needs both levers locked",
                ));
            };
            let (rod5, _) = BRANCHES[0];
            let (rod7, _) = BRANCHES[1];
            rrr(b, (rod5, g, P1, P0), (rod7, i, P1, P0))?;
            rocker_from(b, pt(rod5, P0))?;
            crank_from_c(b)?;
            return Ok(map);
        }
    }
    // The 2-DOF sequences end with both diode branches as free dyads.
    free_branch(b, 0)?;
    free_branch(b, 1)?;
    Ok(map)
}

/// The physical link whose angle is the coordinate of a one-coordinate choice of
/// `mode` (the `coord_link` [`build`] sets: the crank, the swing link, the locked
/// branch's rod, lever 6 for the joined levers); `None` for the choices of two
/// coordinates or none, and for a choice the mode does not have. Such a choice is at
/// its dead point where this link stands still while the mechanism moves: its angle
/// cannot drive the mode there.
pub(crate) fn driving_link(mode: Mode, coords: Coordinates) -> Option<usize> {
    if mode.dof() != 1 {
        return None;
    }
    let locked = mode.clutches().iter().position(|c| *c == Clutch::Locked);
    match (coords, mode) {
        (Coordinates::Crank, _) => Some(CRANK),
        (Coordinates::Swing, Mode::I6 | Mode::I8) => Some(SWING),
        (Coordinates::Rod, Mode::I6 | Mode::I8) => {
            locked.and_then(|k| BRANCHES.get(k)).map(|b| b.0)
        }
        (Coordinates::Lever, Mode::A68) => Some(BRANCHES[0].1),
        _ => None,
    }
}

/// The conditioning of `mode`'s model in `coords` at the physical link angles `pose`
/// (rad, index 1..=8) without building it, for a choice of RRR dyads and motor
/// elements only (these are conditioned 1), as [`declare`] builds it: the least
/// |sin(θa − θb)| over its dyads of links a and b, every link's joints lying on its
/// axis (a dyad's conditioning is |w_a × w_b| / (l_a l_b), its links' joint-to-joint
/// vectors).
/// `None` for a choice with a Newton group (the crank of a 1-DOF mode) or one the mode
/// does not have.
pub(crate) fn dyads_conditioning<T: Real>(
    mode: Mode,
    coords: Coordinates,
    pose: &[T; 9],
) -> Option<T> {
    let [(rod5, _), (rod7, _)] = BRANCHES;
    // The diode branches as free dyads (rod, lever).
    let [b0, b1] = BRANCHES;
    let pairs = match coords {
        Coordinates::CrankSwing if mode.dof() == 2 => [(COUPLER, ROCKER), b0, b1],
        Coordinates::CrankCoupler if mode.dof() == 2 => [(ROCKER, SWING), b0, b1],
        Coordinates::SwingRocker if mode.dof() == 2 => [(COUPLER, CRANK), b0, b1],
        Coordinates::Swing | Coordinates::Rod if mode.dof() == 1 => {
            // The locked branch's rod closes the rocker (swing) or drives (rod); the
            // other branch is a free dyad (as `declare`'s `locked` and `free_branch`).
            let k = mode.clutches().iter().position(|c| *c == Clutch::Locked)?;
            let (rod, _) = *BRANCHES.get(k)?;
            let other = *BRANCHES.get(1 - k)?;
            let first = if coords == Coordinates::Swing {
                (ROCKER, rod)
            } else {
                (ROCKER, SWING)
            };
            [first, (COUPLER, CRANK), other]
        }
        Coordinates::Lever if mode == Mode::A68 => {
            [(rod5, rod7), (ROCKER, SWING), (COUPLER, CRANK)]
        }
        Coordinates::Rest if mode == Mode::Jam => [(rod5, rod7), (ROCKER, SWING), (COUPLER, CRANK)],
        _ => return None,
    };
    let angle = |k: usize| pose.get(k).copied().unwrap_or(T::zero());
    Some(pairs.iter().fold(T::one(), |m, (a, b)| {
        m.min((angle(*a) - angle(*b)).sincos().0.abs())
    }))
}

/// The physical link angles (rad, index 1..=8) of the converter assembled at crank
/// angle `crank` and swing-link angle `swing` on the parameters' branches (SPEC 3:
/// C from circles about B and E, D on the rocker, G and I from circles about D and H);
/// `None` if it cannot assemble there.
pub fn initial_pose<T: Real>(p: &CccParams<T>, crank: T, swing: T) -> Option<[T; 9]> {
    let u = unit::<T>;
    let angle = |v: Vec2<T>| v.y.atan2(v.x);
    let b = p.a + u(crank) * p.link(CRANK).length;
    let e = p.f + u(swing) * p.link(SWING).length;
    let c = circle_meet(
        b,
        p.link(COUPLER).length,
        e,
        p.link(ROCKER).length,
        p.branch_c,
    )?;
    let rocker = angle(c - e);
    let d = e + u(rocker) * p.rocker_d;
    let mut pose = [T::zero(); 9];
    pose[CRANK] = crank;
    pose[COUPLER] = angle(c - b);
    pose[ROCKER] = rocker;
    pose[SWING] = swing;
    for ((rod, lever), side) in BRANCHES.iter().zip([p.branch_g, p.branch_i]) {
        let pin = circle_meet(d, p.link(*rod).length, p.h, p.link(*lever).length, side)?;
        *pose.get_mut(*rod)? = angle(pin - d);
        *pose.get_mut(*lever)? = angle(pin - p.h);
    }
    Some(pose)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// [`driving_link`] names the link each one-coordinate model is built on.
    #[test]
    fn driving_link_is_the_built_coordinate() {
        let p = CccParams::<f64>::reference();
        let pose = initial_pose(&p, 0.3, 1.9).expect("the reference assembles");
        let mut checked = 0;
        for mode in Mode::ALL {
            for coords in mode.coordinate_choices().iter().copied() {
                let Ok((_, map)) = build(&p, mode, coords, &pose) else {
                    continue;
                };
                let expected = (map.dof == 1).then_some(map.coord_link[0] as usize);
                assert_eq!(driving_link(mode, coords), expected, "{mode} {coords}");
                checked += usize::from(expected.is_some());
            }
        }
        // I6, I8: crank, swing, rod; A68: lever, crank.
        assert_eq!(checked, 8);
    }

    /// [`dyads_conditioning`] is the conditioning of the built and assembled model
    /// (its worst group's) for every dyads-only choice, over a spread of poses, and
    /// `None` exactly for the choices with a Newton group.
    #[test]
    fn dyads_conditioning_is_the_built_models() {
        let p = CccParams::<f64>::reference();
        let mut checked = 0;
        for crank in [0.3, 1.2, 2.0, 2.9, 4.0, 5.3] {
            for swing in [1.6, 1.8, 2.1] {
                let Some(pose) = initial_pose(&p, crank, swing) else {
                    continue;
                };
                for mode in Mode::ALL {
                    for coords in mode.coordinate_choices().iter().copied() {
                        let (model, q) = mode_model(&p, mode, coords, &pose).unwrap();
                        let newton = model.groups().iter().any(|g| g.kind.solved_by_newton());
                        let predicted = dyads_conditioning(mode, coords, &pose);
                        assert_eq!(predicted.is_none(), newton, "{mode} {coords}");
                        let Some(predicted) = predicted else {
                            continue;
                        };
                        let mut ws = crate::workspace::Workspace::default();
                        if crate::kinematics::assemble(&model, &mut ws, &q[..model.dof()]).is_err()
                        {
                            continue;
                        }
                        let built = ws
                            .group
                            .iter()
                            .take(model.groups().len())
                            .fold(1.0f64, |m, g| m.min(g.conditioning));
                        assert!(
                            (predicted - built).abs() <= 1e-12,
                            "{mode} {coords} at crank {crank}: {predicted} vs {built}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked >= 100, "{checked}");
    }

    /// [`build_into`]'s shorter validation gives the model of [`build`], which passes
    /// the full one, for every mode and coordinate choice, over a spread of poses
    /// (locked pins and A68's lever offset move with them), and fails as it does at a
    /// pose with a non-finite angle.
    #[test]
    fn build_into_is_build() {
        let p = CccParams::<f64>::reference();
        let mut model = crate::model::ModelBuilder::new().model().clone();
        let mut poses = std::vec::Vec::new();
        for (crank, swing) in [(0.3, 1.9), (2.0, 1.7), (-1.1, 2.1), (4.0, 1.8)] {
            poses.extend(initial_pose(&p, crank, swing));
        }
        let first = poses[0];
        for k in 1..=8 {
            for bad in [f64::NAN, f64::INFINITY] {
                let mut pose = first;
                pose[k] = bad;
                poses.push(pose);
            }
        }
        let (mut built, mut failed) = (0, 0);
        for pose in poses {
            for mode in Mode::ALL {
                for coords in mode.coordinate_choices().iter().copied() {
                    let full = build(&p, mode, coords, &pose);
                    let into = build_into(&p, mode, coords, &pose, &mut model);
                    let (Ok((m, map)), Ok(map_into)) = (&full, &into) else {
                        assert_eq!(full.err(), into.err(), "{mode} {coords}");
                        failed += 1;
                        continue;
                    };
                    assert_eq!(map, map_into, "{mode} {coords}");
                    assert_eq!(m.dof(), model.dof(), "{mode} {coords}");
                    assert_eq!(m.newton_tol(), model.newton_tol(), "{mode} {coords}");
                    assert_eq!(m.groups(), model.groups(), "{mode} {coords}");
                    assert_eq!(m.links(), model.links(), "{mode} {coords}");
                    assert_eq!(m.ground_points(), model.ground_points(), "{mode} {coords}");
                    built += 1;
                }
            }
        }
        assert!(built >= 20 && failed >= 20, "{built} {failed}");
    }
}
