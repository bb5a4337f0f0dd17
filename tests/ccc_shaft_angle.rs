//! The converter's shaft angle is the integral of the shaft speed through events (SPEC
//! 3): against the load's work over T_r (integrated by DP5 with the state, a different
//! path) and against the time integral of the shaft-speed samples.

use structomat::ccc::{CccParams, EventKind, Inputs, MotorInput, Twin, TwinSettings};
use structomat::motor::Motor;

/// After S2's run (12 N·m, T_r = 800 N·m, CW shaft, 1 s; its catches and shaft stops
/// fall inside steps) the shaft angle equals the load's work over T_r to 1e-9 rad, and
/// the trapezoid of the shaft-speed samples to within that rule's bound.
#[test]
fn the_shaft_angle_through_s2_is_the_integral_of_the_shaft_speed() {
    let (h, load) = (1e-4, 800.0);
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load,
        measured: None,
    };
    let mut twin = Twin::new(
        CccParams::<f64>::reference(),
        TwinSettings::reference(h),
        inputs,
    )
    .expect("S2 sets up");
    let (mut trapezoid, mut bound) = (0.0, 0.0);
    let (mut stops_inside, mut catches_inside) = (0, 0);
    let mut w0 = twin.shaft_speed();
    for _ in 0..10_000 {
        twin.step(&inputs).expect("S2 steps");
        let w1 = twin.shaft_speed();
        trapezoid += 0.5 * h * (w0 + w1);
        // On a step where ω is monotone its integral lies within h·|Δω|/2 of the
        // trapezoid (a speed jump at an impact included).
        bound += 0.5 * h * (w1 - w0).abs();
        w0 = w1;
        for e in twin.events() {
            let inside = (e.time / h - (e.time / h).round()).abs() > 1e-6;
            match e.kind {
                EventKind::ShaftStop if inside => stops_inside += 1,
                EventKind::Catch(_) if inside => catches_inside += 1,
                _ => {}
            }
        }
    }
    assert!(
        stops_inside > 0 && catches_inside > 0,
        "S2 has shaft stops and catches inside steps"
    );
    let angle = twin.shaft_angle();
    // The load opposes the shaft's turning: its work is T_r times the angle turned.
    let from_work = twin.audit().load_work / load;
    assert!(angle < -0.1, "the CW shaft turned: {angle} rad");
    assert!(
        (angle.abs() - from_work).abs() < 1e-9,
        "shaft angle {angle} rad against load work / T_r = {from_work} rad"
    );
    assert!(
        (angle - trapezoid).abs() <= bound,
        "shaft angle {angle} rad against the trapezoid {trapezoid} rad (bound {bound:e})"
    );
}
