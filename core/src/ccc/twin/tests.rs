//! The step at rest: skipped ([`Twin::step_at_rest`]) only where the full step (the
//! oracle: the rest branch's evaluation, done) commits the same bits. The energy
//! check's first rung, predicted from the last steps' jumps. A motor law whose
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
    // Regression bracket around S2's jam, 0.8185 s as measured.
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

/// A step started at the rung its predecessors' energy jumps predict
/// ([`JumpHistory`](super::rungs::JumpHistory)) commits the bits of the ladder from
/// rung 1: the attempts below it, made and failed, leave only their work behind (a
/// failed attempt's restore seeds DP5 with the step's start as the last step's final
/// stage had). The oracle is the same step from the same state with no history. S2 at
/// h = 1 ms: the step from 0.262 s, with the release of lever 8, after jumps of 2.97
/// and 20.7 tolerances (242 undivided: the ladder's rung is 4, the predicted one).
/// Where the prediction overshoots (S2's steps from 0.173 s, at 4 where 1 + 3 passed,
/// and from 0.268 s, at 3 where 1 passed) the step is the finer rung's, its balance
/// kept as well.
#[test]
fn a_predicted_first_rung_commits_the_ladders_bits() {
    let (mut twin, inputs) = s2(1e-3);
    for _ in 0..262 {
        twin.step(&inputs).unwrap();
    }
    // Regression value: the rung the last steps' jumps predict, 4, as measured (the
    // oracle is the bit comparison below).
    assert_eq!(twin.jumps.start_rung(), 4);
    let mut ladder = Box::new((*twin).clone());
    ladder.jumps = super::rungs::JumpHistory::NONE;
    assert_eq!(ladder.jumps.start_rung(), 1);
    twin.step(&inputs).unwrap();
    ladder.step(&inputs).unwrap();
    assert_eq!(committed(&twin), committed(&ladder));
    assert!(twin
        .events
        .iter()
        .any(|e| e.kind == super::EventKind::Release(8)));
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

/// Step `k`'s inputs of a run.
type InputsOf = fn(u32) -> Inputs<f64>;

/// S2 at h = 1 ms, unspread and spread, under its constant law and under a torque that
/// changes every step (12 ± 1e-3 N·m, alternately): step `k`'s inputs.
fn s2_variants() -> [(bool, InputsOf); 4] {
    fn law(_: u32) -> Inputs<f64> {
        s2(1e-3).1
    }
    fn changing(k: u32) -> Inputs<f64> {
        let d = if k % 2 == 0 { 1e-3 } else { -1e-3 };
        Inputs {
            motor: MotorInput::Torque(12.0 + d),
            ..s2(1e-3).1
        }
    }
    [
        (false, law),
        (false, changing),
        (true, law),
        (true, changing),
    ]
}

/// S2's twin at h = 1 ms with its events spread or not.
fn s2_spread(spread: bool) -> Box<Twin<f64>> {
    let (twin, inputs) = s2(1e-3);
    let mut settings = *twin.settings();
    settings.spread_events = spread;
    Box::new(Twin::new(CccParams::reference(), settings, inputs).unwrap())
}

/// What `Twin::state_evaluated` stands for: after every step the current slot's
/// workspace holds the committed state's full evaluation, bit for bit the one a fresh
/// evaluation there makes (the oracle: `Stage::Motion` at the state on a clone, the
/// kinematics solved anew). Through S2's events, mode changes, coordinate switches and
/// Newton groups (A68 with the crank as coordinate), spread or not.
#[test]
fn after_a_step_the_workspace_holds_the_committed_state() {
    use super::evaluate::{Stage, Torques};
    for (spread, inputs_of) in s2_variants() {
        let mut twin = s2_spread(spread);
        for k in 0..820 {
            twin.step(&inputs_of(k)).unwrap();
            assert!(twin.state_evaluated, "spread {spread}, step {k}");
            let mut fresh = twin.clone();
            let w = fresh.work_from_state();
            let held = fresh.inputs.inputs();
            fresh
                .evaluate_from(Stage::Motion, &w, &held, Torques::Kinetostatics)
                .unwrap();
            let (a, b) = (&twin.slots.cur().ws, &fresh.slots.cur().ws);
            let same = format!(
                "{:?} {:?} {:?} {:?} {:?}",
                a.body, a.v, a.a_bias, a.qdd, a.reactions
            ) == format!(
                "{:?} {:?} {:?} {:?} {:?}",
                b.body, b.v, b.a_bias, b.qdd, b.reactions
            );
            assert!(
                same,
                "spread {spread}, step {k}, t = {}: {:?}",
                twin.t,
                twin.mode()
            );
        }
    }
}

/// A step under new inputs evaluates only the loads and `q̈` at the kinematics the
/// workspace holds (`Stage::Loads`): it commits the bits of a step that evaluates the
/// state in full (the oracle: a twin whose flag is cleared before every step), step
/// for step.
#[test]
fn new_inputs_at_the_kinematics_held_commit_a_full_evaluations_bits() {
    for (spread, inputs_of) in s2_variants() {
        let (mut reused, mut full) = (s2_spread(spread), s2_spread(spread));
        for k in 0..820 {
            full.state_evaluated = false;
            reused.step(&inputs_of(k)).unwrap();
            full.step(&inputs_of(k)).unwrap();
            assert_eq!(
                committed(&reused),
                committed(&full),
                "spread {spread}, step {k}"
            );
        }
    }
}

/// An f32 twin's clock: `(n + 1)·h` in f32 resolves a step of 1 ms up to about 8192 s
/// (the spacing of f32 there, 2^-10 s, is then over h/2: a step would be rounded to 0 or
/// 2h). The oracle is f32's spacing itself: at n = 2^20 (1049 s, spacing 1.2e-4 s) every
/// step is taken, at n = 2^23 (8389 s, spacing 9.8e-4 s: a step's rounded length is 0,
/// 0.98 or 1.95 ms) a step is refused, named, the state kept, and none is taken whose
/// length is off h by h/2 or more; the twin is S2's at rest after its jam, whose state
/// does not depend on the time.
#[test]
fn an_f32_clock_that_no_longer_resolves_the_step_is_refused() {
    use crate::ccc::twin::TwinStepError;
    use std::string::ToString;
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0f32)),
        load: 800.0,
        measured: None,
    };
    let h = 1e-3f32;
    let mut twin = Box::new(
        Twin::new(
            CccParams::<f32>::reference(),
            TwinSettings::reference(h),
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
    assert!(twin.at_rest, "S2 jams before 1 s in f32");
    let at = |twin: &mut Twin<f32>, n: u64| {
        twin.steps = n;
        twin.t = n as f32 * h;
    };
    at(&mut twin, 1 << 20);
    for _ in 0..100 {
        twin.step(&inputs)
            .expect("f32 resolves a 1 ms step at 1049 s");
    }
    at(&mut twin, 1 << 23);
    let mut refused = None;
    for _ in 0..100 {
        let (t, n, links) = (twin.t, twin.steps, twin.links);
        match twin.step(&inputs) {
            Ok(_) => {
                let len = twin.t - t;
                assert!((len - h).abs() < 0.5 * h, "a step of {len} s taken");
            }
            Err(e) => {
                assert!(matches!(e, TwinStepError::TimeOverflow { .. }), "{e}");
                assert!(e.to_string().contains("no longer resolves"), "{e}");
                assert_eq!((twin.t, twin.steps), (t, n), "the clock kept");
                assert_eq!(format!("{:?}", twin.links), format!("{links:?}"));
                refused = Some(n);
                break;
            }
        }
    }
    assert!(
        refused.is_some(),
        "no step refused within 100 steps at 8389 s"
    );
}
