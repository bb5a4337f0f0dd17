//! What the twin is given each step (the motor, the load, the encoders' counts) and the
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

    /// Whether the torque is a user's law ([`Motor::User`]): the one input that may
    /// read the time and the crank's angle (the others: a held torque, a constant, a
    /// characteristic of the speed).
    pub fn is_user_law(&self) -> bool {
        matches!(self, MotorInput::Law(Motor::User(_)))
    }
}

/// What the twin is given each step.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<T: Real> {
    /// The motor on the crank.
    pub motor: MotorInput<T>,
    /// The load's resistive torque on the shaft T_r ≥ 0, N·m.
    pub load: T,
    /// What the bench's encoders read at the step's end, to compare the twin against
    /// (and, with an [`TwinObserver`](crate::ccc::TwinObserver), to correct it by).
    pub measured: Option<Measurement<T>>,
}

/// An incremental encoder's reading: its count and its resolution.
///
/// The angle it stands for is `zero + (counts + ½)·2π/per_turn`, rad: the middle of the
/// count's cell for an encoder that counts `floor((angle - zero)/(2π/per_turn))` (the
/// bench's law), whose error is then uniform over the cell, variance `(2π/per_turn)²/12`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Encoder<T> {
    /// The count.
    pub counts: i64,
    /// Counts per turn (> 0).
    pub per_turn: u32,
    /// The angle at the start of count 0's cell, rad, in the measured angle's sense.
    pub zero: T,
}

impl<T: Real> Encoder<T> {
    /// One count, rad (`per_turn` > 0).
    pub fn resolution(&self) -> T {
        T::c(core::f64::consts::TAU / f64::from(self.per_turn.max(1)))
    }

    /// The angle the count stands for (its cell's middle), rad.
    pub fn angle(&self) -> T {
        self.zero + T::c(self.counts as f64 + 0.5) * self.resolution()
    }
}

/// What the bench measures at a step's end: the crank's encoder (θ1, SPEC's q1, CCW,
/// unwrapped), the output shaft's (its angle turned in the drive direction), and
/// optionally the rocker's (link 3's θ, CCW).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement<T> {
    /// The crank's encoder.
    pub crank: Option<Encoder<T>>,
    /// The shaft's encoder, positive in the drive direction.
    pub shaft: Option<Encoder<T>>,
    /// The rocker's encoder.
    pub rocker: Option<Encoder<T>>,
}

impl<T: Real> Measurement<T> {
    /// The crank's encoder alone.
    pub fn crank(counts: i64, per_turn: u32, zero: T) -> Self {
        Measurement {
            crank: Some(Encoder {
                counts,
                per_turn,
                zero,
            }),
            shaft: None,
            rocker: None,
        }
    }

    /// The encoders, with the fields a bad reading of each is named by: its
    /// resolution, its zero.
    fn fields(&self) -> [(Option<Encoder<T>>, [&'static str; 2]); 3] {
        [
            (
                self.crank,
                [
                    "crank encoder resolution (counts per turn)",
                    "crank encoder zero",
                ],
            ),
            (
                self.shaft,
                [
                    "shaft encoder resolution (counts per turn)",
                    "shaft encoder zero",
                ],
            ),
            (
                self.rocker,
                [
                    "rocker encoder resolution (counts per turn)",
                    "rocker encoder zero",
                ],
            ),
        ]
    }
}

/// What the twin keeps of the last step's inputs: the motor and the load, and the
/// encoders' angles ([`Encoder::angle`], rad: crank, shaft, rocker) for
/// [`Twin::measurement_residual`](super::Twin::measurement_residual). (Not the
/// [`Measurement`] itself: the f32 twin's 32 KiB budget has room for three angles, not
/// three encoders.)
#[derive(Clone, Copy, Debug)]
pub(super) struct Held<T: Real> {
    pub motor: MotorInput<T>,
    pub load: T,
    pub angles: Option<[Option<T>; 3]>,
}

impl<T: Real> Held<T> {
    pub(super) fn of(i: &Inputs<T>) -> Self {
        let angle = |e: Option<Encoder<T>>| e.map(|e| e.angle());
        Held {
            motor: i.motor,
            load: i.load,
            angles: i
                .measured
                .map(|m| [angle(m.crank), angle(m.shaft), angle(m.rocker)]),
        }
    }

    /// The inputs to evaluate the models with (the encoders play no part there).
    pub(super) fn inputs(&self) -> Inputs<T> {
        Inputs {
            motor: self.motor,
            load: self.load,
            measured: None,
        }
    }
}

/// Whether a step's inputs are the last step's, bit for bit: a held torque or a law's
/// coefficients (a constant's, an asynchronous motor's; an observer moves them from
/// step to step), and a user's law taken to be the same law. Where they are the same,
/// the step goes on from the last one's final stage (DP5's first-same-as-last).
pub(super) fn same_inputs<T: Real>(a: &Held<T>, b: &Inputs<T>) -> bool {
    let motor = match (a.motor, b.motor) {
        (MotorInput::Torque(x), MotorInput::Torque(y))
        | (MotorInput::Law(Motor::Constant(x)), MotorInput::Law(Motor::Constant(y))) => {
            same_bits(x, y)
        }
        (MotorInput::Law(Motor::Asynchronous(x)), MotorInput::Law(Motor::Asynchronous(y))) => {
            same_bits(x.a, y.a) && same_bits(x.b, y.b) && same_bits(x.c, y.c)
        }
        (MotorInput::Law(Motor::User(_)), MotorInput::Law(Motor::User(_))) => true,
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

/// The converter's load torque T_r (N·m) from which on a step is refused: the twin
/// releases a locked lever when its clutch torque falls below -1e-9 (T_r + 1 N·m) (the
/// event functions' torque tolerance, `guards.rs`), so from 1e6 N·m on an accepted state
/// may hold a clutch torque below -1e-3 N·m and a release comes late by that tolerance
/// over the torque's rate (S2 at T_r = 1e7: c8 = -7.4e-3 N·m, the release 5e-5 s late;
/// at 1e11, -98 N·m), far coarser than the converter's own torques.
pub const MAX_CONVERTER_LOAD: f64 = 1e6;

/// The per-step inputs are valid, or the error that names the first that is not
/// (`time`: the twin's, s). A count's jump between steps is the observer's to judge
/// ([`TwinObserver`](crate::ccc::TwinObserver)): the twin keeps no count.
pub(crate) fn check_inputs<T: Real>(inputs: &Inputs<T>, time: T) -> Result<(), TwinStepError> {
    let bad = |field, value: T| {
        Err(TwinStepError::BadInput {
            time: time.to_f64(),
            field,
            value: value.to_f64(),
        })
    };
    let load = inputs.load;
    if !(load.finite() && load >= T::zero() && load < T::c(MAX_CONVERTER_LOAD)) {
        return bad("load", load);
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
    let Some(m) = inputs.measured else {
        return Ok(());
    };
    for (e, [resolution, zero]) in m.fields() {
        let Some(e) = e else { continue };
        if e.per_turn == 0 {
            return bad(resolution, T::zero());
        }
        if !e.zero.finite() {
            return bad(zero, e.zero);
        }
    }
    Ok(())
}
