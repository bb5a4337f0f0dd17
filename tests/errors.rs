//! Bad input gets a clear error, never a panic or NaN, and a failing step keeps the
//! last good state (DEVELOPERS.md standards; issue: "a geometry that cannot assemble, a
//! NaN input and a Newton failure each return the documented error").

use structomat::error::{GroupFault, ModelError, StepError};
use structomat::mechanisms::five_bar_model;
use structomat::model::{Link, ModelBuilder};
use structomat::motor::Motor;
use structomat::structomat::{GroupKind, MotorR, PointRef, TriadRrRrRr};
use structomat::{Model, SetupError, Simulation};

fn q0() -> [f64; 2] {
    [80f64.to_radians(), 70f64.to_radians()]
}

#[test]
fn geometry_that_cannot_assemble_is_named() {
    // Pivots 4 m apart: links 3 and 4 (1.85 + 1.40 m) cannot close the loop anywhere.
    let model = five_bar_model::<f64>(4.0, None).unwrap();
    let err = Simulation::new(model, &q0(), &[0.0, 0.0], 1e-3)
        .err()
        .unwrap();
    let SetupError::Initial(StepError::Group { group, fault, .. }) = err else {
        panic!("{err:?}")
    };
    assert_eq!(group.kind, GroupKind::Rrr);
    assert_eq!(&group.links[..2], &[3, 4]);
    let GroupFault::CannotAssemble { gap } = fault else {
        panic!("{fault:?}")
    };
    assert!(gap > 0.0 && gap < 1.0, "gap {gap}");
    let msg = err.to_string();
    assert!(
        msg.contains("RRR(3,4)") && msg.contains("cannot assemble"),
        "{msg}"
    );
}

/// Snapshot of everything a step must leave untouched on failure.
fn snapshot(sim: &Simulation<f64>) -> (u64, Vec<u64>, Vec<u64>, Vec<u64>) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let x: Vec<f64> = sim.workspace().group.iter().flat_map(|g| g.x).collect();
    (
        sim.time().to_bits(),
        bits(sim.q()),
        bits(sim.qd()),
        bits(&x),
    )
}

#[test]
fn a_step_that_cannot_assemble_keeps_the_last_good_state() {
    // Pivots 2.9 m apart: the dyad closes only while |BD| <= 3.25 m, i.e. not with the
    // crank pointing away from link 2. A huge torque and a long step throw the crank's
    // stages into that sector.
    let model = five_bar_model::<f64>(2.9, Some(Motor::Constant(5.0e4))).unwrap();
    let mut sim = Simulation::new(model, &q0(), &[0.0, 0.0], 0.05).unwrap();
    for _ in 0..200 {
        let before = snapshot(&sim);
        let energy = sim.energy();
        let Err(err) = sim.step() else { continue };
        // Either a stage lands where the dyad cannot close, or near its dead point,
        // where V ~ 1/sin(transmission angle) makes VᵀMV numerically indefinite.
        match err {
            StepError::Group { group, .. } => assert_eq!(group.kind, GroupKind::Rrr),
            StepError::SingularMassMatrix { .. }
            | StepError::NonFinite { .. }
            | StepError::EnergyBalance { .. } => {}
        }
        assert!(err.time() >= sim.time() && err.time() <= sim.time() + 0.05);
        assert_eq!(snapshot(&sim), before, "state changed by a failed step");
        assert_eq!(
            sim.energy(),
            energy,
            "workspace no longer describes the state"
        );
        // Failing again is deterministic.
        assert_eq!(sim.step().err(), Some(err));
        println!("{err}");
        return;
    }
    panic!("the step never failed");
}

fn nan_after_20ms(t: f64, _q: f64, _qd: f64) -> f64 {
    if t > 0.02 {
        f64::NAN
    } else {
        10.0
    }
}

#[test]
fn nan_input_is_an_error_not_a_nan_state() {
    let model = five_bar_model::<f64>(2.5, Some(Motor::User(nan_after_20ms))).unwrap();
    let mut sim = Simulation::new(model, &q0(), &[0.0, 0.0], 1e-3).unwrap();
    let mut failed = None;
    for _ in 0..100 {
        let before = snapshot(&sim);
        match sim.step() {
            Ok(()) => assert!(sim.q().iter().chain(sim.qd()).all(|v| v.is_finite())),
            Err(e) => {
                assert_eq!(snapshot(&sim), before);
                failed = Some(e);
                break;
            }
        }
    }
    let e = failed.expect("the NaN torque must be reported");
    assert!(
        matches!(
            e,
            StepError::NonFinite {
                what: "motor torque",
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.time() > 0.02 && e.time() < 0.0225, "{}", e.time());
    assert!(e.to_string().contains("motor torque"));

    // NaN in the initial state or the model is refused at the door.
    let model = five_bar_model::<f64>(2.5, None).unwrap();
    let e = Simulation::new(model, &[f64::NAN, 1.0], &[0.0, 0.0], 1e-3)
        .err()
        .unwrap();
    assert!(matches!(e, SetupError::Setting(_)), "{e:?}");
    let mut b = ModelBuilder::<f64>::new();
    b.link(Link::bar(1.0, f64::NAN, 0.1, 0.5)).unwrap();
    assert_eq!(b.build().err(), Some(ModelError::NonFinite("link mass")));
    let model = five_bar_model::<f64>(f64::INFINITY, None).err();
    assert_eq!(model, Some(ModelError::NonFinite("ground point")));
}

/// A crank driving a triad RR-RR-RR (Newton-Raphson), built from a chosen configuration
/// at q = 90°: crank A(0,0)→B(0,0.1); ternary link T1(0.5,0.3), T2(0.9,0.3), T3(0.7,0.6);
/// binary links B→T1, K2(0.9,-0.2)→T2, K3(0.3,0.9)→T3.
fn crank_triad(torque: f64) -> Model<f64> {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let k2 = b.ground_point(0.9, -0.2).unwrap();
    let k3 = b.ground_point(0.3, 0.9).unwrap();
    let crank = b.link(Link::bar(0.1, 0.2, 1e-3, 0.05)).unwrap();
    let l2 = (0.5f64.powi(2) + 0.2f64.powi(2)).sqrt();
    let b2 = b.link(Link::bar(l2, 0.3, 5e-3, l2 / 2.0)).unwrap();
    let b3 = b.link(Link::bar(0.5, 0.3, 5e-3, 0.25)).unwrap();
    let b4 = b.link(Link::bar(0.5, 0.3, 5e-3, 0.25)).unwrap();
    let mut tern = Link::bar(0.4, 1.0, 0.02, 0.2);
    tern.add_point(nalgebra::Vector2::new(0.2, 0.3)).unwrap();
    let t = b.link(tern).unwrap();
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    b.group(&TriadRrRrRr {
        ternary: t,
        ternary_joints: [0, 1, 2],
        binary: [b2, b3, b4],
        binary_at_pole: [0, 0, 0],
        binary_at_ternary: [1, 1, 1],
        poles: [
            PointRef {
                body: crank,
                point: 1,
            },
            k2,
            k3,
        ],
        guess: [
            0.2f64.atan2(0.5),
            90f64.to_radians(),
            (-0.3f64).atan2(0.4),
            0.0,
        ],
    })
    .unwrap();
    b.drive(0, Motor::Constant(torque)).unwrap();
    b.build().unwrap()
}

#[test]
fn newton_failure_is_named_and_keeps_the_state() {
    let model = crank_triad(0.0);
    let sim = Simulation::new(model, &[90f64.to_radians()], &[0.0], 1e-3).unwrap();
    assert!(sim.workspace().group[1].iterations <= 5);
    assert_eq!(
        sim.model().formula().to_string(),
        "Z(0) + R(1) + RR-RR-RR(2,3,4,5)"
    );

    // A violent torque over a long step sends the crank where the triad cannot close.
    let model = crank_triad(1.0e5);
    let mut sim = Simulation::new(model, &[90f64.to_radians()], &[0.0], 0.1).unwrap();
    let before = snapshot(&sim);
    let err = sim.step().expect_err("the step must fail");
    let StepError::Group { group, fault, .. } = err else {
        panic!("{err:?}")
    };
    assert_eq!(group.kind, GroupKind::Triad);
    assert!(
        matches!(
            fault,
            GroupFault::NewtonDidNotConverge { iterations: 30, .. }
                | GroupFault::Singular { .. }
                | GroupFault::BranchJump
        ),
        "{fault:?}"
    );
    assert_eq!(snapshot(&sim), before);
    println!("{err}");
}

#[test]
fn model_builder_rejects_bad_sequences() {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let l1 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    let _l2 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    b.group(&MotorR {
        link: l1,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    assert_eq!(
        b.clone().build().err(),
        Some(ModelError::Unplaced { link: 2 })
    );
    b.group(&MotorR {
        link: l1,
        pivot: a,
        link_point: 0,
        coord: 1,
        offset: 0.0,
    })
    .unwrap();
    assert!(matches!(
        b.build().err(),
        Some(ModelError::Sequence { group: 1, .. })
    ));
    // A pole on a link that is not placed yet.
    let mut b = ModelBuilder::<f64>::new();
    let _ = b.ground_point(0.0, 0.0).unwrap();
    let l1 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    let l2 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    b.group(&MotorR {
        link: l2,
        pivot: PointRef { body: l1, point: 1 },
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })
    .unwrap();
    assert!(matches!(
        b.build().err(),
        Some(ModelError::Sequence { group: 0, .. })
    ));
    // A point that does not exist.
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let l1 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    let e = b
        .group(&MotorR {
            link: l1,
            pivot: a,
            link_point: 7,
            coord: 0,
            offset: 0.0,
        })
        .err();
    assert!(matches!(e, Some(ModelError::UnknownReference(_))), "{e:?}");
}
