//! What the twin is given each step (the motor, the load, a measurement) and the
//! check that refuses a bad one by name.

use super::error::TwinStepError;
use super::same_bits;
use crate::motor::Motor;
use crate::scalar::Real;

/// The motor acting on the crank (link 1, reaction on the ground).
#[derive(Clone, Copy, Debug)]
pub enum MotorInput<T: Real> {
    /// A torque, N·m, CCW positive (e.g. measured on the prototype), held over the step.
    Torque(T),
    /// A motor law of time, crank angle and crank speed, evaluated at every stage.
    Law(Motor<T>),
}

impl<T: Real> MotorInput<T> {
    /// The torque at time `t` (s), crank angle `theta` (rad) and speed `omega` (rad/s).
    pub fn torque(&self, t: T, theta: T, omega: T) -> T {
        match self {
            MotorInput::Torque(v) => *v,
            MotorInput::Law(m) => m.torque(t, theta, omega),
        }
    }
}

/// What the twin is given each step.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<T: Real> {
    /// The motor on the crank.
    pub motor: MotorInput<T>,
    /// The load's resistive torque on the shaft T_r ≥ 0, N·m.
    pub load: T,
    /// A measured crank angle (rad) and speed (rad/s) to compare against.
    pub measured: Option<(T, T)>,
}

/// Whether two steps' inputs are the same, bit for bit (a motor law is taken to be
/// the same law).
pub(super) fn same_inputs<T: Real>(a: &Inputs<T>, b: &Inputs<T>) -> bool {
    let motor = match (a.motor, b.motor) {
        (MotorInput::Torque(x), MotorInput::Torque(y)) => same_bits(x, y),
        (MotorInput::Law(_), MotorInput::Law(_)) => true,
        _ => false,
    };
    motor && same_bits(a.load, b.load)
}

/// A motor law's first parameter that is not finite, named, if any (a user
/// function's value is checked where it is evaluated).
fn law_fault<T: Real>(m: &Motor<T>) -> Option<(&'static str, T)> {
    match *m {
        Motor::Constant(c) => Some(("motor law's constant torque", c)),
        Motor::Asynchronous(a) => [
            ("motor law's coefficient a", a.a),
            ("motor law's coefficient b", a.b),
            ("motor law's coefficient c", a.c),
        ]
        .into_iter()
        .find(|(_, v)| !v.finite()),
        Motor::User(_) => None,
    }
    .filter(|(_, v)| !v.finite())
}

/// The per-step inputs are valid, or the error that names the first that is not
/// (`time`: the twin's, s).
pub(super) fn check_inputs<T: Real>(inputs: &Inputs<T>, time: T) -> Result<(), TwinStepError> {
    let bad = |field, value: T| {
        Err(TwinStepError::BadInput {
            time: time.to_f64(),
            field,
            value: value.to_f64(),
        })
    };
    if !(inputs.load.finite() && inputs.load >= T::zero()) {
        return bad("load", inputs.load);
    }
    match inputs.motor {
        MotorInput::Torque(v) if !v.finite() => return bad("motor torque", v),
        // A law's parameters are checked here; what a user function returns is checked
        // at every evaluation (a non-finite torque fails the step, state kept).
        MotorInput::Law(m) => {
            if let Some((field, value)) = law_fault(&m) {
                return bad(field, value);
            }
        }
        _ => {}
    }
    if let Some((a, w)) = inputs.measured {
        if !a.finite() {
            return bad("measured crank angle", a);
        }
        if !w.finite() {
            return bad("measured crank speed", w);
        }
    }
    Ok(())
}
