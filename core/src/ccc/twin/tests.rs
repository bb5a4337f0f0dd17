//! The step at rest: skipped ([`Twin::step_at_rest`]) only where the full step (the
//! oracle: the rest branch's evaluation, done) commits the same bits.

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
        "{:?} {} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
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
        t.events,
        t.switches,
        t.candidates,
        t.torque_source,
    )
}

/// S2 (12 N·m, T_r = 800 N·m) at h = 1 ms up to its first step committed at rest
/// (the jam at 0.8185 s), and its inputs.
fn s2_at_rest() -> (Box<Twin<f64>>, Inputs<f64>) {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 800.0,
        measured: None,
    };
    let mut twin = Box::new(
        Twin::new(
            CccParams::reference(),
            TwinSettings::reference(1e-3),
            inputs,
        )
        .unwrap(),
    );
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
