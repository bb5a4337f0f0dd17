//! The slot's unit tests: its speed rows against finite differences, its build errors.

use super::super::super::build::initial_pose;
use super::super::super::mode::Mode;
use super::super::super::params::CccParams;
use super::super::error::TwinStepError;
use super::{unwrap_near, Slot, STATE};
use crate::ccc::mode_model;
use crate::structomat::GroupKind;
use crate::workspace::keeps_warm_start;
use nalgebra::SVector;
extern crate std;
use std::string::ToString;

/// A mode whose model cannot be built at a pose (a locked lever's pin at a
/// non-finite angle) fails the slot's rebuild with the model builder's own error,
/// the one the public builder [`mode_model`] gives at that pose (the oracle), named
/// with the mode and time, not as a non-finite evaluation.
#[test]
fn a_model_that_cannot_be_built_keeps_the_builders_error() {
    let p = CccParams::<f64>::reference();
    let good = initial_pose(&p, 105f64.to_radians(), 90f64.to_radians()).unwrap();
    let mut slot = Slot::empty();
    let mut named = 0;
    for (mode, lever) in [(Mode::I6, 6), (Mode::I8, 8), (Mode::Jam, 6)] {
        for bad in [f64::NAN, f64::INFINITY] {
            let mut pose = good;
            pose[lever] = bad;
            for coords in mode.coordinate_choices() {
                let Err(want) = mode_model(&p, mode, *coords, &pose) else {
                    continue;
                };
                let got = slot.rebuild(&p, mode, *coords, &pose, 0.25).unwrap_err();
                assert_eq!(
                    got,
                    TwinStepError::Model {
                        time: 0.25,
                        mode,
                        error: want
                    },
                    "{mode} {coords:?}"
                );
                let msg = got.to_string();
                assert!(
                    msg.contains(&want.to_string()) && msg.contains("t = 0.250000 s"),
                    "{msg}"
                );
                assert!(!slot.built);
                named += 1;
            }
        }
    }
    assert!(named >= 6, "{named}");
}

/// The rows the impact's constraints are made of (`omega_row`, `lever_row`): each
/// link's angular speed per unit rate of each coordinate, against a central finite
/// difference of the link's angle in the coordinate (step 1e-6 rad: error ~1e-12
/// from the third derivative, ~1e-10 from rounding), in every coordinate choice of
/// I0 and of I6 (lever 6 locked: its row is zero).
#[test]
fn each_link_speed_row_is_the_derivative_of_its_angle() {
    let p = CccParams::<f64>::reference();
    let pose = initial_pose(&p, 105f64.to_radians(), 90f64.to_radians()).unwrap();
    let mut slot = Slot::empty();
    let eps = 1e-6;
    for mode in [Mode::I0, Mode::I6] {
        for coords in mode.coordinate_choices() {
            let q = slot.rebuild(&p, mode, *coords, &pose, 0.0).unwrap();
            let n = slot.map.dof;
            let angles = |slot: &mut Slot<f64>, q: [f64; 2]| {
                let mut y = SVector::<f64, STATE>::zeros();
                y[0] = q[0];
                y[1] = q[1];
                slot.eval_speeds(0.0, &y).unwrap();
                slot.links(&p).map(|l| l.theta)
            };
            angles(&mut slot, q);
            let rows: [[f64; 2]; 9] = core::array::from_fn(|l| slot.omega_row(l));
            for (l, row) in rows.iter().enumerate() {
                let r = slot.lever_row(l);
                assert_eq!([r[0], r[1], r[2]], [row[0], row[1], 0.0]);
            }
            for k in 0..n {
                let (mut qp, mut qm) = (q, q);
                qp[k] += eps;
                qm[k] -= eps;
                let (ap, am) = (angles(&mut slot, qp), angles(&mut slot, qm));
                for l in 1..9 {
                    let fd = (unwrap_near(ap[l], am[l]) - am[l]) / (2.0 * eps);
                    assert!(
                        (rows[l][k] - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                        "{mode} {coords:?}: link {l}, coordinate {k}: {} vs {fd}",
                        rows[l][k]
                    );
                }
            }
            if mode == Mode::I6 {
                assert_eq!(rows[6], [0.0, 0.0], "{coords:?}: locked lever 6");
            }
        }
    }
}

/// The joints' look-up table is [`JOINTS`] both ways round, every pair once: the
/// scan it replaced (each model joint against the eleven) finds the same joint.
#[test]
fn the_joint_table_is_the_joint_list_both_ways() {
    use super::{JOINTS, JOINT_AT};
    let mut found = 0;
    for i in 0..9u8 {
        for j in 0..9u8 {
            let scan = JOINTS.iter().enumerate().find_map(|(k, &(a, b))| {
                if (i, j) == (a, b) {
                    Some(k as i8 + 1)
                } else if (i, j) == (b, a) {
                    Some(-(k as i8 + 1))
                } else {
                    None
                }
            });
            assert_eq!(
                JOINT_AT[i as usize][j as usize],
                scan.unwrap_or(0),
                "({i}, {j})"
            );
            found += usize::from(scan.is_some());
        }
    }
    assert_eq!(found, 2 * JOINTS.len());
}

/// The warm start a failed step restores: saved at a state of A68 with the crank as
/// coordinate (its six-link group by Newton), then moved past by two evaluations
/// elsewhere, restored, the state evaluated again gives its first evaluation's bits
/// (which a retried step relies on). The same re-evaluation from the moved warm start
/// converges to other bits (Newton stops within its tolerance, not at the same
/// iterate): the restore is what makes them equal. One entry per group of the slot's
/// workspace, for the unknowns too.
#[test]
fn a_restored_warm_start_reproduces_the_evaluations_bits() {
    use crate::ccc::mode::Coordinates;
    let p = CccParams::<f64>::reference();
    let pose = initial_pose(&p, 105f64.to_radians(), 90f64.to_radians()).unwrap();
    let mut slot = Slot::empty();
    let q = slot
        .rebuild(&p, Mode::A68, Coordinates::Crank, &pose, 0.0)
        .unwrap();
    assert!(slot
        .model
        .groups()
        .iter()
        .any(|g| g.kind.solved_by_newton()));
    let state = |crank: f64| {
        let mut y = SVector::<f64, STATE>::zeros();
        y[0] = crank;
        y[2] = 8.0;
        y
    };
    let bits = |slot: &Slot<f64>| {
        slot.links(&p)
            .map(|l| (l.theta.to_bits(), l.omega.to_bits()))
    };
    slot.eval_speeds(0.0, &state(q[0] - 0.01)).unwrap();
    slot.eval_speeds(0.0, &state(q[0])).unwrap();
    let first = bits(&slot);
    let saved = slot.warm_start();
    let unknowns = slot.ws.unknowns();
    // The RRR dyads' are not saved: their re-evaluation reads nothing of them (the
    // restored state's bits below are the oracle).
    let kinds = || slot.model.groups().iter().map(|g| g.kind);
    assert_eq!(
        saved.groups.len(),
        kinds().filter(|k| keeps_warm_start(*k)).count()
    );
    assert!(!saved.groups.is_empty());
    assert_eq!(unknowns.len(), slot.ws.group.iter().count());
    let elsewhere = |slot: &mut Slot<f64>| {
        slot.eval_speeds(0.0, &state(q[0] + 0.013)).unwrap();
        slot.eval_speeds(0.0, &state(q[0] + 0.027)).unwrap();
    };
    elsewhere(&mut slot);
    slot.eval_speeds(0.0, &state(q[0])).unwrap();
    assert_ne!(bits(&slot), first, "the moved warm start's own bits");
    elsewhere(&mut slot);
    slot.ws.restore_warm_start(slot.model.groups(), &saved);
    slot.eval_speeds(0.0, &state(q[0])).unwrap();
    assert_eq!(bits(&slot), first);
    let kept = slot
        .model
        .groups()
        .iter()
        .zip(slot.ws.group.iter())
        .filter(|(g, _)| keeps_warm_start(g.kind));
    for ((_, gd), (x, _)) in kept.zip(saved.groups.iter()) {
        assert_eq!(gd.x, *x);
    }
    elsewhere(&mut slot);
    slot.ws.restore_unknowns(&unknowns);
    for (g, x) in slot.ws.group.iter().zip(unknowns.iter()) {
        assert_eq!(g.x, *x);
    }
}

/// S2's inputs for a slot's evaluation (12 N·m, a light load) and a pose of `mode`
/// with `coords` where the choice is conditioned (0.3 at least: far from its dead
/// points, so the states 0.002 rad on assemble), the slot built there, and its
/// coordinates.
fn conditioned(
    slot: &mut Slot<f64>,
    p: &CccParams<f64>,
    mode: Mode,
    coords: crate::ccc::mode::Coordinates,
) -> (super::super::inputs::Inputs<f64>, [f64; 2]) {
    use super::super::inputs::{Inputs, MotorInput};
    use crate::motor::Motor;
    let (pose, q) = [30.0f64, 60.0, 150.0, 200.0, 250.0, 300.0]
        .iter()
        .find_map(|deg| {
            let pose = initial_pose(p, deg.to_radians(), 70f64.to_radians())?;
            let q = slot.rebuild(p, mode, coords, &pose, 0.0).ok()?;
            (slot.conditioning() >= 0.3).then_some((pose, q))
        })
        .expect("a conditioned pose");
    slot.rebuild(p, mode, coords, &pose, 0.0).unwrap();
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 30.0,
        measured: None,
    };
    (inputs, q)
}

/// An RRR dyad keeps no warm start ([`keeps_warm_start`]): in A68 with the lever as
/// coordinate (its driver and three RRR dyads) a step's start evaluated again, after
/// evaluations elsewhere with the angles recorded and left stale and a restore of the
/// driver's alone, gives its first evaluation's bits in every body's motion, angle
/// and `q̈` (the oracle: that first evaluation, made from a fresh build).
#[test]
fn an_rrr_dyad_needs_no_warm_start() {
    use super::Angles;
    use crate::ccc::mode::Coordinates;
    let p = CccParams::<f64>::reference();
    let mut slot = Slot::empty();
    let (inputs, q) = conditioned(&mut slot, &p, Mode::A68, Coordinates::Lever);
    // The crank's driver and three RRR dyads.
    let rrr = slot
        .model
        .groups()
        .iter()
        .filter(|g| g.kind == GroupKind::Rrr)
        .count();
    assert_eq!((rrr, slot.model.groups().len()), (3, 4));
    let state = |dq: f64| {
        let mut y = SVector::<f64, STATE>::zeros();
        y[0] = q[0] + dq;
        y[2] = 5.0;
        y
    };
    let eval = |slot: &mut Slot<f64>, dq: f64, a: Angles| {
        slot.eval_with(0.0, &state(dq), &inputs, (1.0, None, 0.0), Some(a))
            .unwrap();
        let mut m: std::vec::Vec<u64> = slot.ws.qdd.iter().map(|v| v.to_bits()).collect();
        for b in slot.ws.body.iter() {
            for v in [b.theta, b.c, b.s, b.o.x, b.o.y, b.omega, b.v.x, b.alpha] {
                m.push(v.to_bits());
            }
        }
        m
    };
    let first = eval(&mut slot, 0.0, Angles::Record);
    let saved = slot.warm_start();
    assert_eq!(saved.groups.len(), 1);
    eval(&mut slot, 0.001, Angles::Record);
    let stale = eval(&mut slot, 0.002, Angles::Stale);
    slot.ws.restore_warm_start(slot.model.groups(), &saved);
    assert_eq!(eval(&mut slot, 0.0, Angles::Record), first);
    // The stale evaluation did leave other angles in the unknowns: the restore had
    // something it could have restored.
    assert_ne!(stale, eval(&mut slot, 0.002, Angles::Record));
}

/// An evaluation with the dyads' angles left stale ([`Angles::Stale`], the DP5 stages
/// before a step's end) gives the recorded evaluation's bits in every position, cosine
/// and sine, speed, acceleration and rate at the state (the oracle: the same state
/// evaluated with the angles recorded), and the dyads' links keep the angles of the
/// last recorded evaluation (a state 0.002 rad on: they differ). The coordinates'
/// links' angles are the state's. A motor law of the crank's angle gets the angles
/// recorded anyway. In A68 with the lever as coordinate and I0 (dyads only).
#[test]
fn stale_angles_change_nothing_but_the_angles() {
    use super::super::inputs::{Inputs, MotorInput};
    use super::Angles;
    use crate::ccc::mode::Coordinates;
    use crate::motor::Motor;
    let p = CccParams::<f64>::reference();
    let bits = |v: f64| v.to_bits();
    let motion = |slot: &Slot<f64>| {
        let mut m: std::vec::Vec<u64> = std::vec::Vec::new();
        for b in slot.ws.body.iter() {
            for v in [
                b.c, b.s, b.o.x, b.o.y, b.omega, b.v.x, b.v.y, b.alpha, b.a.x, b.a.y,
            ] {
                m.push(bits(v));
            }
        }
        m.extend(slot.ws.qdd.iter().map(|v| bits(*v)));
        m
    };
    let angles = |slot: &Slot<f64>| slot.ws.body.map(|b| b.theta);
    let mut slot = Slot::empty();
    let mut stale_links = 0;
    for (mode, coords) in [
        (Mode::A68, Coordinates::Lever),
        (Mode::I0, Coordinates::CrankSwing),
    ] {
        let (constant, q) = conditioned(&mut slot, &p, mode, coords);
        let of_angle = Inputs {
            motor: MotorInput::Law(Motor::User(|_, theta: f64, _| 12.0 + theta.sin())),
            ..constant
        };
        let n = slot.map.dof;
        let state = |dq: f64| {
            let mut y = SVector::<f64, STATE>::zeros();
            for k in 0..n {
                y[k] = q[k] + dq;
                y[2 + k] = 5.0 - 3.0 * k as f64;
            }
            y
        };
        let eval = |slot: &mut Slot<f64>, dq: f64, inputs: &Inputs<f64>, a: Angles| {
            slot.eval_with(0.0, &state(dq), inputs, (1.0, None, 0.0), Some(a))
                .unwrap();
        };
        eval(&mut slot, -0.002, &constant, Angles::Record);
        let (recorded, recorded_angles) = (motion(&slot), angles(&slot));
        eval(&mut slot, 0.0, &constant, Angles::Record);
        let before = angles(&slot);
        eval(&mut slot, -0.002, &constant, Angles::Stale);
        assert_eq!(motion(&slot), recorded, "{mode}");
        let coordinate_links: std::vec::Vec<usize> = (0..n)
            .map(|k| slot.map.coord_link[k] as usize)
            .map(|l| slot.body(l) as usize)
            .collect();
        for (b, (now, (rec, old))) in angles(&slot)
            .iter()
            .zip(recorded_angles.iter().zip(before.iter()))
            .enumerate()
            .skip(1)
            .take(slot.model.links().len())
        {
            if coordinate_links.contains(&b) {
                assert_eq!(bits(*now), bits(*rec), "{mode}: body {b}, a coordinate's");
            } else {
                assert_eq!(bits(*now), bits(*old), "{mode}: body {b} kept");
                assert_ne!(bits(*now), bits(*rec), "{mode}: body {b} moved");
                stale_links += 1;
            }
        }
        eval(&mut slot, 0.0, &of_angle, Angles::Record);
        eval(&mut slot, -0.002, &of_angle, Angles::Record);
        let with_law = angles(&slot).map(bits);
        eval(&mut slot, 0.0, &of_angle, Angles::Record);
        eval(&mut slot, -0.002, &of_angle, Angles::Stale);
        assert_eq!(
            angles(&slot).map(bits),
            with_law,
            "{mode}: a law of the angle"
        );
    }
    assert!(stale_links >= 8, "{stale_links}");
}
