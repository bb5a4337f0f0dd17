//! The step at rest: skipped ([`Twin::step_at_rest`]) only where the full step (the
//! oracle: the rest branch's evaluation, done) commits the same bits. The energy
//! check's rungs: which are tried after a failed attempt. A motor law whose
//! coefficients change: new inputs, as a held torque's change is.

use super::{Inputs, MotorInput, Twin, TwinSettings};
use crate::ccc::{CccParams, Mode};
use crate::motor::Motor;
extern crate std;
use std::boxed::Box;
use std::format;
use std::string::String;

/// Everything a step commits, printed (`{:?}` of a float is its shortest round-trip
/// form: two prints are equal only if the bits are, a -0 included).
fn committed(t: &Twin<f64>) -> String {
    format!(
        "{:?} {} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        t.t,
        t.steps,
        t.y,
        t.links,
        t.joints,
        t.c,
        t.guards,
        t.guard_rates,
        t.last_guards,
        t.audit,
        t.shaft_angle,
        t.coast,
        t.events,
        t.switches,
        t.candidates,
        t.torque_source,
    )
}

/// S2's twin (12 N·m, T_r = 800 N·m, SPEC's machine) at its start with step `h`
/// (s), and its inputs: the twin's own tests' fixture.
pub(super) fn s2(h: f64) -> (Box<Twin<f64>>, Inputs<f64>) {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 800.0,
        measured: None,
    };
    let twin = Twin::new(CccParams::reference(), TwinSettings::reference(h), inputs);
    (Box::new(twin.unwrap()), inputs)
}

/// S2 at h = 1 ms up to its first step committed at rest (the jam at 0.8185 s), and
/// its inputs.
fn s2_at_rest() -> (Box<Twin<f64>>, Inputs<f64>) {
    let (mut twin, inputs) = s2(1e-3);
    for _ in 0..1000 {
        twin.step(&inputs).unwrap();
        if twin.at_rest {
            break;
        }
    }
    assert!(twin.at_rest, "S2 jams before 1 s");
    assert_eq!(twin.slots.cur().mode, Mode::Jam);
    assert!(twin.time() > 0.8 && twin.time() < 0.83, "{}", twin.time());
    (twin, inputs)
}

/// At rest under S2's unchanged inputs, each skipped step commits what the full step
/// (the same twin with the skip barred) commits, bit for bit, for 50 steps.
#[test]
fn a_step_at_rest_commits_the_full_steps_bits() {
    let (mut fast, inputs) = s2_at_rest();
    let mut full = Box::new((*fast).clone());
    for k in 0..50 {
        assert!(fast.repeats_at_rest(&inputs), "step {k}");
        full.at_rest = false;
        assert!(!full.repeats_at_rest(&inputs));
        fast.step(&inputs).unwrap();
        full.step(&inputs).unwrap();
        assert!(full.at_rest, "the full step at rest takes the rest branch");
        assert_eq!(committed(&fast), committed(&full), "step {k}");
    }
}

/// Other inputs, or a motor law of time, are evaluated in full: a different load, a
/// different held torque, a user law (its torque may change with time).
#[test]
fn a_step_at_rest_under_other_inputs_is_evaluated() {
    let (twin, inputs) = s2_at_rest();
    assert!(twin.repeats_at_rest(&inputs));
    let load = Inputs {
        load: 801.0,
        ..inputs
    };
    assert!(!twin.repeats_at_rest(&load));
    let ramp: fn(f64, f64, f64) -> f64 = |t, _, _| 12.0 + t;
    let law = Inputs {
        motor: MotorInput::Law(Motor::User(ramp)),
        ..inputs
    };
    assert!(!twin.repeats_at_rest(&law));
    // A held torque is not the law's: its first step is evaluated in full, the next
    // (the same torque again) is skipped.
    let mut held = twin;
    let torque = Inputs {
        motor: MotorInput::Torque(12.0),
        ..inputs
    };
    assert!(!held.repeats_at_rest(&torque));
    held.step(&torque).unwrap();
    assert!(held.repeats_at_rest(&torque));
    let other = Inputs {
        motor: MotorInput::Torque(12.5),
        ..inputs
    };
    assert!(!held.repeats_at_rest(&other));
}

/// The rungs after a failed attempt: the core's (4 and 16) always; 2 and 3 only where
/// DP5's O(h⁶) energy error per step, divided into `n` where there were `done`, brings
/// the jump under the tolerance by the safety factor 2: a jump of `e` tolerances
/// becomes e·(done/n)⁵, so 3 after 1 passes for e ≤ 3⁵/2 = 121.5 and 2 after 1 for
/// e ≤ 2⁵/2 = 16 (S2 in f64 at h = 1 ms: 70.2 at its catch I0 -> A8 at 0.1763 s, which
/// 3 sub-steps then passed; 135 at the release at 0.2629 s, which goes to 4).
#[test]
fn the_rungs_are_tried_where_the_h6_law_predicts_they_pass() {
    use super::rung_may_pass;
    use super::settings::{RETRY_SUBSTEPS, RUNG_SAFETY, SUBSTEPS};
    assert_eq!(RUNG_SAFETY, 2.0);
    // The core's rungs are all the twin's, in the same order, with 2 and 3 before 4.
    assert_eq!(RETRY_SUBSTEPS, [1, 2, 3, 4, 16]);
    assert!(SUBSTEPS.iter().all(|n| RETRY_SUBSTEPS.contains(n)));
    for n in SUBSTEPS {
        assert!(rung_may_pass::<f64>(n, 1, None), "{n}");
        assert!(rung_may_pass::<f64>(n, 3, Some(1e6)), "{n}");
    }
    // 3 after 1: 243 / 2 = 121.5 tolerances.
    assert!(rung_may_pass(3, 1, Some(70.2f64)));
    assert!(rung_may_pass(3, 1, Some(121.5f64)));
    assert!(!rung_may_pass(3, 1, Some(121.6f64)));
    assert!(!rung_may_pass(3, 1, Some(135.0f64)));
    // 2 after 1: 32 / 2 = 16.
    assert!(rung_may_pass(2, 1, Some(16.0f64)));
    assert!(!rung_may_pass(2, 1, Some(16.1f64)));
    // 3 after 2: 1.5⁵ / 2 = 3.796875.
    assert!(rung_may_pass(3, 2, Some(3.796875f64)));
    assert!(!rung_may_pass(3, 2, Some(3.8f64)));
    // A failure without an energy jump (a mechanism failure) goes to the core's rungs.
    assert!(!rung_may_pass::<f64>(2, 1, None) && !rung_may_pass::<f64>(3, 1, None));
    // In f32 the same law.
    assert!(rung_may_pass(3, 1, Some(121.5f32)) && !rung_may_pass(3, 1, Some(122.0f32)));
}

/// A motor law whose coefficients change from one step to the next is new inputs, as a
/// held torque that changes is: the step evaluates its start under the new law rather
/// than going on from the last step's final stage (DP5's first-same-as-last). The
/// oracle is the held torque's path: S2 stepped under a constant law whose torque
/// changes every step (12 N·m ± 0.5, and an asynchronous motor's characteristic with
/// `b` = 0, its `a` the same torque) commits the bits of S2 stepped under the same
/// torques held, step after step (an observer moves its estimates so).
#[test]
fn a_law_whose_coefficients_change_is_new_inputs() {
    use crate::motor::Asynchronous;
    let torque = |k: u32| {
        if k % 3 == 0 {
            12.0
        } else {
            12.0 + 0.5 * f64::from(k % 2) - 0.25
        }
    };
    let inputs = |motor| Inputs {
        motor,
        load: 800.0,
        measured: None,
    };
    let new = || {
        Box::new(
            Twin::new(
                CccParams::reference(),
                TwinSettings::reference(1e-3),
                inputs(MotorInput::Torque(12.0)),
            )
            .unwrap(),
        )
    };
    let (mut held, mut constant, mut asynchronous) = (new(), new(), new());
    for k in 0..150 {
        let v = torque(k);
        held.step(&inputs(MotorInput::Torque(v))).unwrap();
        constant
            .step(&inputs(MotorInput::Law(Motor::Constant(v))))
            .unwrap();
        asynchronous
            .step(&inputs(MotorInput::Law(Motor::Asynchronous(
                Asynchronous {
                    a: v,
                    b: 0.0,
                    c: 0.0,
                },
            ))))
            .unwrap();
        let (h, c, a) = (
            committed(&held),
            committed(&constant),
            committed(&asynchronous),
        );
        assert_eq!(h, c, "step {k}: the constant law");
        assert_eq!(h, a, "step {k}: the asynchronous law");
    }
}
