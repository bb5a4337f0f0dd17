//! The twin corrected by the bench's encoders every step: an error-state (indirect)
//! Kalman filter after Sanjurjo et al. ("State and force observers based on multibody
//! models and the indirect Kalman filter"), in crank terms, with their force
//! estimation: an unknown torque on the crank.
//!
//! Why this design. The twin's step is already the best prediction there is (DP5 on the
//! mode's exact equations, its events, impacts and coordinate switches): the indirect
//! filter keeps it as the prediction and estimates only the error of its state, so the
//! observer adds no model of its own and costs a few scalar operations and one
//! re-evaluation per step. The error is carried in the crank's angle and speed
//! `(δθ1, δω1)` ([`filter`]) rather than in the mode's independent coordinates: the
//! crank is what the encoder measures in every mode and under every coordinate choice,
//! so the covariance passes unchanged through mode changes and coordinate switches (no
//! mapping of `P` between the modes' coordinates), and the correction is mapped into
//! the present coordinates by the model's own transmission at the moment it is applied
//! ([`Twin::correct_crank`]). At each mode change the speed error's variance grows by
//! [`ObserverSettings::event_speed_var`]: an impact's outcome is where the model's
//! errors show most. In the 2-DOF modes the second coordinate is not observed by the
//! crank's encoder; the shaft's encoder is used for the clutch diagnostics, not as a
//! correction (the shaft follows a lever only while engaged).
//!
//! Two tunings. How much the filter corrects is how little it trusts the model (the
//! process noise is the model's error): [`ObserverSettings::reference`] is for a twin
//! with a drawing's nominal parameters (masses within ±10 %, friction unknown: the
//! model's error carried by a fast torque estimate and the friction's, the state's own
//! noise small); [`ObserverSettings::identified`] for a twin whose parameters were
//! identified from the machine's logs, friction included: process noise small, so the
//! counts' quantization moves the torque estimate little, no friction estimated. Both
//! correct the 2-DOF modes by a fraction of the gain (a tenth, a fifth) along the
//! crank's dynamically consistent direction ([`Twin::correct_crank`]): by the whole
//! gain a correction of the crank alone moved the unobserved coordinate the wrong way.
//!
//! The force observer. A correction of the state alone leaves the model's dynamics as
//! they are, so the twin drifts again between updates and its clutch torques (which
//! set the releases' and the jam's times) stay the nominal model's. The error state is
//! augmented with `d`, a torque on the crank (N·m, CCW) that the machine has and the
//! model lacks — its joints' friction and its masses' errors, seen at the crank — as a
//! random walk; its estimate is added to the motor's torque in the prediction (the
//! twin's own step), so the correction changes the dynamics in every mode, the 2-DOF
//! ones included, where it is not updated. Its effect on the crank's acceleration is
//! `d b`, `b = r M⁻¹ rᵀ` the present mode's crank mobility ([`Twin::crank_mobility`],
//! the inverse of the crank-reduced inertia); it grows uncertain by
//! [`ObserverSettings::event_torque_var`] at each mode change (another mode, another
//! reduced inertia and so another error of it) and is held within
//! [`ObserverSettings::torque_limit`].
//!
//! The friction observer. A drawing's model has no friction, and a machine's is mostly
//! viscous, a torque that follows the crank's speed, which swings over each cycle of
//! the converter: a random walk `d` lags it. So the error state carries a fourth
//! term, `c`, the viscous friction of the crank's bearing A (N·m·s/rad), whose torque
//! `-c ω1` is applied with the motor's at every stage of the prediction (the motor
//! input becomes the characteristic `a + b ω1` with `b = -c`), its effect on the
//! crank's acceleration `-c ω1 b` ([`filter`]). It is a random walk too
//! ([`ObserverSettings::friction_noise`]), kept within 0 and
//! [`ObserverSettings::friction_limit`] (friction takes energy), updated where `d` is,
//! and it stands for whatever of the model's error goes with the crank's speed, not
//! only A's (the friction of B and E, seen at the crank, follows its speed too).
//! On bench1 with SPEC's nominal parameters it stays at 0.037 to 0.049 N·m·s/rad from
//! 0.1 s on (0.046 at the end), `d` at about -0.9 to -1.0 N·m in A68 and I6 and -0.2 to
//! -0.4 late in the run (`identify` finds 0.050 at A and 0.010 at B, E and F): the two
//! share the friction's torque, `d` its mean part
//! (docs/observer.md). The identified tuning has it off (an identified twin has
//! its friction), and so the three-state filter's bits.
//!
//! The mass observer. The heaviest part of the machine, the oscillating mass on the
//! rocker, is also its likeliest error (a drawing's 6 kg weighed 6.48 on the known
//! machine), and its error is a torque at the crank that neither `d` nor `c` can
//! follow: it goes with the rocker's acceleration and weight, which swing with every
//! stroke and differ from mode to mode. So the error state carries a fifth term, the
//! mass's error `δm`, whose effect on the crank's acceleration is its sensitivity
//! `a_m` ([`Twin::crank_mass_sensitivity`]: Lagrange's equations are linear in the
//! mass); its estimate is not a torque added to the motor's but the twin's own
//! parameter ([`Twin::set_oscillating_mass`]: every mode's model takes it, the energy
//! the change puts in booked in the audit), so a mode the filter does not update (the
//! 2-DOF ones) and the mode choice's consistency conditions have it too. A random walk
//! ([`ObserverSettings::mass_noise`]) held within
//! [`ObserverSettings::mass_limit`] of the twin's mass, updated where `d` is; off
//! (0 variance, the four-state filter's bits) in the identified tuning, whose twin
//! has the machine's mass.
//!
//! The locked lever. In I6 and I8 the locked lever's pin is a constant of the mode,
//! placed where the twin's lever stopped; the 2-DOF phases before leave one
//! coordinate unobserved, so it stands a little off the machine's (2.1 mrad on the
//! known machine's 600/12 log). Through most of the mode the crank's update takes the
//! difference up in the coordinate, but near a dead point of the crank in the mode's
//! coordinates (its reversals in I6, `|∂θ1/∂q|` under
//! [`ObserverSettings::min_transmission`], where the state is not corrected) the
//! crank's angle is set by the pin: `θ1 = g(q, ψ)`, `∂g/∂q → 0`, while
//! `∂θ1/∂ψ` ([`Twin::held_lever_sensitivity`]) stays 6 to 8 rad/rad. There the part of
//! the innovation the coordinates cannot take moves the lever
//! ([`ObserverSettings::held_gain`], [`Twin::move_held_lever`]: its pin moves, the
//! coordinates stay, the energy the move puts in booked in the audit). Not a sixth
//! filter state: the pin's error is only seen where the state's is not, and a
//! Kalman update of it, its variance collapsing on the first small innovations of
//! the approach to the reversal, stopped moving it before the reversal showed the
//! error (2.6 counts RMS on that log, against 0.94 so and 3.6 without).
//!
//! The count's cell. An encoder count places the crank's angle in a cell one count
//! wide; its quantization error is not white noise but follows the state (a slow crank
//! keeps one side of a cell for many steps). The state and the torque are corrected by
//! the innovation's part outside a band around the count's middle
//! ([`ObserverSettings::state_band`], [`ObserverSettings::torque_band`]), so that a
//! twin the count does not contradict is left as it is rather than made to chatter
//! with the counts; and a crank that takes `n` steps to cross a count is read with `n`
//! times the quantization's variance ([`quantization_variance`]): the steps on one
//! side of a cell share one quantization error.
//!
//! The innovations become named diagnostics ([`Diagnostic`]): a crank reading past the
//! innovation gate that stepped there from the last step's residual is an encoder
//! jump (not used; a few in a row are taken as real and the covariance reset), one
//! that drifted there is the twin leaving the machine (the covariance reset and the
//! reading used, no diagnostic); the shaft's motion measured since the last mode change,
//! against the twin's, names a clutch that slips or fails to catch; the corrections'
//! mean acceleration while the shaft turns against while it is held names a load off
//! its set point; a crank residual that stays large after the updates
//! ([`ObserverSettings::part_counts`] for [`ObserverSettings::part_steps`] steps) names
//! a twin parted from the machine, whose outputs are no longer the machine's (as where
//! each correction must stop short of an event function's crossing, for the twin's
//! next step to take the event, but the twin's own dynamics run the other way).
//!
//! Bounded work, no allocation, no panic: a twin step, a few 5×5 products, at most
//! one [`Twin::correct_crank`] (one evaluation of the mode, and a mode choice only
//! when the correction fires an event function) and one
//! [`Twin::set_oscillating_mass`] (one evaluation), or instead of them, where the
//! crank's transmission is too small in I6 or I8, one
//! [`Twin::held_lever_sensitivity`] (the mode assembled once in the scratch slot)
//! and one [`Twin::move_held_lever`] (assembled again, one evaluation).

mod diagnostics;
mod filter;
mod settings;

pub use diagnostics::{BiasWatch, Diagnostic, Diagnostics};
pub use filter::Covariance;
pub use settings::ObserverSettings;

use super::twin::inputs::check_inputs;
use super::twin::{Correction, Inputs, MotorInput, Twin, TwinStepError};
use crate::motor::{Asynchronous, Motor};
use crate::scalar::Real;

/// What one observer step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Update<T> {
    /// The crank's innovation (measured - predicted angle), rad, if measured.
    pub innovation: Option<T>,
    /// Its variance `H P Hᵀ + R`, rad².
    pub innovation_var: Option<T>,
    /// The shaft's innovation since the last mode change (measured - twin), counts.
    pub shaft_innovation: Option<T>,
    /// The correction applied.
    pub correction: Option<Correction<T>>,
    /// The crank's unknown torque estimated after the update, N·m (CCW; added to the
    /// motor's in the next prediction).
    pub torque: T,
    /// The crank bearing's unknown viscous friction estimated after the update,
    /// N·m·s/rad (applied as `-c ω1` with the motor's torque in the next prediction).
    pub friction: T,
    /// The oscillating mass the twin carries after the update, kg (the estimate, when
    /// the observer estimates it).
    pub mass: T,
    /// The diagnostics raised.
    pub diagnostics: Diagnostics,
}

/// The observer's state: the error's covariance and what the diagnostics watch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinObserver<T: Real> {
    settings: ObserverSettings<T>,
    p: Covariance<T>,
    /// The crank's unknown torque estimated, N·m.
    torque: T,
    /// The crank bearing's unknown viscous friction estimated, N·m·s/rad.
    friction: T,
    /// The oscillating mass's change estimated, from `nominal_mass`, kg.
    mass_offset: T,
    /// The twin's oscillating mass at the first step, kg: what the estimate starts
    /// from and is held around.
    nominal_mass: Option<T>,
    jumps: u32,
    /// Steps in a row the crank's residual has been past `part_counts`.
    parted: u32,
    /// The crank's residual (measured - twin) after the last update, rad.
    residual: Option<T>,
    /// The shaft's count and the twin's shaft angle (drive direction, rad) at the last
    /// mode change.
    shaft_ref: Option<(i64, T)>,
    bias: BiasWatch<T>,
    last: Option<Update<T>>,
    /// The crank's and the shaft's last counts read (refused steps' included).
    counts: [Option<i64>; 2],
}

/// `inputs` with `torque` (N·m) and a viscous friction `friction` (N·m·s/rad, the
/// torque `-friction ω1` at the crank's speed `ω1` of every stage) added to the motor's
/// on the crank, and whether they could be: a user's law of time cannot take them.
/// With no friction a held torque or a constant law stays one (the same bits as
/// without the friction's estimate); with it they become the asynchronous motor's
/// characteristic `a + b ω1` (its `b` the friction's), evaluated at every stage.
fn with_torque<T: Real>(inputs: &Inputs<T>, torque: T, friction: T) -> (Inputs<T>, bool) {
    let biased = |m: Asynchronous<T>| {
        MotorInput::Law(Motor::Asynchronous(Asynchronous {
            a: m.a + torque,
            b: m.b - friction,
            c: m.c,
        }))
    };
    let (motor, applied) = match inputs.motor {
        MotorInput::Torque(v) | MotorInput::Law(Motor::Constant(v)) if friction != T::zero() => {
            let held = Asynchronous {
                a: v,
                b: T::zero(),
                c: T::zero(),
            };
            (biased(held), true)
        }
        MotorInput::Torque(v) => (MotorInput::Torque(v + torque), true),
        MotorInput::Law(Motor::Constant(v)) => (MotorInput::Law(Motor::Constant(v + torque)), true),
        MotorInput::Law(Motor::Asynchronous(m)) => (biased(m), true),
        law => (law, false),
    };
    (Inputs { motor, ..*inputs }, applied)
}

/// The part of the innovation `nu` outside a band of width `band` around 0 (both
/// in rad): 0 inside, the distance to the band's edge outside, with `nu`'s sign.
fn outside<T: Real>(nu: T, band: T) -> T {
    let half = band * T::c(0.5);
    if nu > half {
        nu - half
    } else if nu < -half {
        nu + half
    } else {
        T::zero()
    }
}

/// The most steps over which one count's quantization error is taken as the same
/// ([`quantization_variance`]): a crank at rest is read as at 100 steps a count.
pub const COUNT_STEPS_MAX: f64 = 100.0;

/// The variance of an encoder's angle as a measurement of the crank, rad²: the
/// quantization's `Δ²/12` (`res` = Δ, rad), times the steps of `h` (s) the crank at
/// `omega` (rad/s) takes to cross a count, between 1 and [`COUNT_STEPS_MAX`]. A crank
/// slower than a count a step keeps one side of a cell for those steps, so their
/// quantization errors are one error, not independent ones: the count's information
/// comes at the rate the crank crosses counts. Weighted as white noise, the creep of
/// I6 before bench1's jam (a count every 2 to 5 ms) moved the rocker's speed by a
/// quarter from step to step, and the corrections that slowed it brought the jam
/// 9.7 ms early; so weighted, it is within 0.5 ms.
pub fn quantization_variance<T: Real>(res: T, omega: T, h: T) -> T {
    let steps = res / (omega.abs() * h);
    let steps = if steps.finite() {
        steps.max(T::one()).min(T::c(COUNT_STEPS_MAX))
    } else {
        T::c(COUNT_STEPS_MAX)
    };
    res * res / T::c(12.0) * steps
}

impl<T: Real> TwinObserver<T> {
    /// An observer with `settings`, its covariance the initial one.
    pub fn new(settings: ObserverSettings<T>) -> Self {
        TwinObserver {
            settings,
            p: Covariance::diagonal(
                settings.initial_sigma,
                settings.friction_sigma,
                settings.mass_sigma,
            ),
            torque: T::zero(),
            friction: T::zero(),
            mass_offset: T::zero(),
            nominal_mass: None,
            jumps: 0,
            parted: 0,
            residual: None,
            shaft_ref: None,
            bias: BiasWatch::new(),
            last: None,
            counts: [None; 2],
        }
    }

    /// The error's covariance after the last update (crank angle, speed, torque).
    pub fn covariance(&self) -> Covariance<T> {
        self.p
    }

    /// The crank's unknown torque estimated, N·m (CCW).
    pub fn torque(&self) -> T {
        self.torque
    }

    /// The crank bearing's unknown viscous friction estimated, N·m·s/rad (≥ 0; applied
    /// with the motor's torque as `-c ω1`).
    pub fn friction(&self) -> T {
        self.friction
    }

    /// The oscillating mass's change estimated from the twin's at the first step, kg
    /// (0 when not estimated).
    pub fn mass_offset(&self) -> T {
        self.mass_offset
    }

    /// The load-bias averages.
    pub fn bias(&self) -> BiasWatch<T> {
        self.bias
    }

    /// The last step's update.
    pub fn last(&self) -> Option<Update<T>> {
        self.last
    }

    /// One step of `twin` under `inputs` (the prediction), then the update from
    /// `inputs.measured` (the correction of the twin's state, the diagnostics). A
    /// refused step, or a correction that fails, leaves the twin at its last good state
    /// (the step's, for a correction) and the covariance as it was. A twin that
    /// spreads its events ([`TwinSettings::spread_events`](super::TwinSettings::spread_events))
    /// is refused: its step may end short of the measurements' time.
    pub fn step(
        &mut self,
        twin: &mut Twin<T>,
        inputs: &Inputs<T>,
    ) -> Result<Update<T>, TwinStepError> {
        if twin.settings().spread_events {
            // A step of such a twin may end short of the clock, at an event: its state
            // is not the machine's at the measurements' time.
            return Err(TwinStepError::BadInput {
                time: twin.time().to_f64(),
                field: "twin settings: spread_events (the observer needs every step to end on the clock)",
                value: 1.0,
            });
        }
        if let Some((field, value)) = self.settings.fault() {
            return Err(TwinStepError::BadInput {
                time: twin.time().to_f64(),
                field,
                value: value.to_f64(),
            });
        }
        let jumps = self.check_jumps(twin, inputs);
        // The readings are the machine's whatever comes of this step: the next step's
        // jump is measured from them, so that a counter that took a new offset (a reset,
        // an index pulse) is refused once, not at every step after it (its offset then
        // meets the innovation's jump gate), and readings through refused steps (a bad
        // torque) keep the check on the machine's motion.
        self.take_readings(inputs);
        // The inputs as given, named as given (the step below takes them with the
        // estimated torque added: a torque then stands as a motor law's coefficient).
        check_inputs(inputs, twin.time())?;
        jumps?;
        // The prediction: the twin's step with the estimated torque on the crank added
        // to the motor's (a motor law that cannot take it: the estimate is held and
        // only the state corrected).
        let (biased, applied) = with_torque(inputs, self.torque, self.friction);
        twin.step(&biased)?;
        let s = self.settings;
        let h = twin.h();
        let b = if applied {
            twin.crank_mobility()
        } else {
            T::zero()
        };
        let omega = twin.link(1).omega;
        let estimate_mass = s.mass_sigma > T::zero() || s.mass_noise > T::zero();
        let a_m = if estimate_mass {
            twin.crank_mass_sensitivity()
        } else {
            T::zero()
        };
        let nominal = *self.nominal_mass.get_or_insert(twin.oscillating_mass());
        let mut prior = self.p.predict(
            h,
            (b, omega, a_m),
            (
                s.accel_noise,
                s.torque_noise,
                s.friction_noise,
                s.mass_noise,
            ),
        );
        if !twin.events().is_empty() {
            prior.inflate(s.event_speed_var, s.event_torque_var);
            self.shaft_ref = None;
        }
        let mut up = Update {
            innovation: None,
            innovation_var: None,
            shaft_innovation: None,
            correction: None,
            torque: self.torque,
            friction: self.friction,
            mass: twin.oscillating_mass(),
            diagnostics: Diagnostics::default(),
        };
        let measured = inputs.measured;
        if let Some(e) = measured.and_then(|m| m.crank) {
            let res = e.resolution();
            let r = quantization_variance(res, omega, h);
            let nu = e.angle() - twin.link(1).theta;
            let var = prior.innovation_variance(r);
            up.innovation = Some(nu);
            up.innovation_var = Some(var);
            let gate = s.jump_gate * var.root();
            let beyond = nu.abs() > gate && nu.abs() > s.jump_counts * res;
            // An encoder jump is a step of the reading against the twin: the
            // innovation moved by `jump_counts` or more since the last step's
            // residual (or a jump is going on). One that grew to past the gate a few
            // counts a step is the twin drifting from a machine whose encoder reads
            // smoothly (the known machine's logs at 600 N·m: 52 counts in 25 steps
            // while the crank's transmission, near its reversal in I6, was too small
            // to correct it): no jump, but the covariance is reset and the reading
            // used, as for a jump taken as real.
            let stepped = self.jumps > 0
                || self
                    .residual
                    .is_none_or(|r| (nu - r).abs() > s.jump_counts * res);
            let jump = beyond && stepped;
            // In a 2-DOF mode (I0, A6, A8) the crank's encoder observes one coordinate
            // of two: a full correction there feeds the count's quantization into the
            // unobserved one (with no model error the twin left the machine's mode
            // sequence at 0.22 s of S2 so), so there the filter corrects by
            // `two_dof_gain` of its gain (0: it only predicts); the 1-DOF modes (I6,
            // I8, A68), where the crank is the whole state, take the whole update.
            let two_dof = twin.q().len() == 2;
            let [r0, r1] = twin.crank_transmission();
            let transmission = if two_dof {
                (r0 * r0 + r1 * r1).root()
            } else {
                r0.abs()
            };
            let observable =
                (!two_dof || s.two_dof_gain > T::zero()) && transmission >= s.min_transmission;
            if jump && self.jumps < s.jump_run {
                self.jumps += 1;
                up.diagnostics.insert(Diagnostic::EncoderJump("crank"));
            } else if observable {
                if beyond {
                    prior = Covariance::diagonal(s.initial_sigma, s.friction_sigma, s.mass_sigma);
                }
                self.jumps = 0;
                let mut k = prior.gain(r);
                let mut band = s.state_band;
                if two_dof {
                    k[0] *= s.two_dof_gain;
                    k[1] *= s.two_dof_gain;
                    k[2] = T::zero();
                    k[3] = T::zero();
                    k[4] = T::zero();
                    band = s.two_dof_band;
                }
                if !applied {
                    k[2] = T::zero();
                    k[3] = T::zero();
                }
                // The count's cell bounds the angle: what the prediction lies outside
                // of the bands corrects the state and the torque (see the settings).
                let (nu_d, nu) = (outside(nu, s.torque_band * res), outside(nu, band * res));
                // A correction that cannot be made (a group that does not assemble at the
                // corrected state) leaves the twin at the step's state: the prediction
                // stands, and so does its covariance.
                // Inside the band the twin is not touched: no re-evaluation, and its
                // next step keeps DP5's first-same-as-last stage.
                let c = if nu == T::zero() {
                    Correction {
                        applied: true,
                        ..Correction::none()
                    }
                } else {
                    twin.correct_crank(k[0] * nu, k[1] * nu)
                        .unwrap_or(Correction::none())
                };
                let posterior = prior.update(&k, r);
                // The update's covariance holds for the correction asked: one cut or
                // scaled to under half of it (an event function's crossing, a dead
                // point) keeps the prediction's, and the torque's estimate its own.
                let asked = (k[0] * nu).abs();
                let made = c.crank.0.abs();
                let torque = (self.torque + k[2] * nu_d)
                    .max(-s.torque_limit)
                    .min(s.torque_limit);
                let friction = (self.friction + k[3] * nu_d)
                    .max(T::zero())
                    .min(s.friction_limit);
                let limit = s.mass_limit * nominal;
                let mass = (self.mass_offset + k[4] * nu_d).max(-limit).min(limit);
                if c.applied
                    && posterior.finite()
                    && torque.finite()
                    && friction.finite()
                    && mass.finite()
                    && made + made >= asked
                {
                    let predicted = prior;
                    prior = posterior;
                    self.torque = torque;
                    self.friction = friction;
                    up.torque = torque;
                    up.friction = friction;
                    // The twin takes the mass, or keeps its own (a change that would
                    // move an event function past its crossing, or fail to evaluate):
                    // the estimate is what the twin carries.
                    if estimate_mass && mass != self.mass_offset {
                        if twin.set_oscillating_mass(nominal + mass).is_ok()
                            && twin.oscillating_mass() == nominal + mass
                        {
                            self.mass_offset = mass;
                        } else {
                            // The twin kept its mass: the update made is that of the
                            // gain without the mass's row (the Joseph form holds for
                            // any gain), so that the mass's variance does not shrink
                            // for a correction not made.
                            let mut kept = k;
                            kept[4] = T::zero();
                            let made = predicted.update(&kept, r);
                            if made.finite() {
                                prior = made;
                            }
                        }
                    }
                    up.mass = twin.oscillating_mass();
                }
                up.correction = Some(c);
            } else if !two_dof && !jump && s.held_gain > T::zero() {
                // A move the twin cannot make leaves it as predicted (the move restores
                // it), as a crank correction it refuses does.
                up.correction = self
                    .correct_held_lever(twin, nu, transmission, res)
                    .unwrap_or(None);
            }
            if !jump {
                self.jumps = 0;
            }
            let residual = e.angle() - twin.link(1).theta;
            self.residual = Some(residual);
            self.parted = if residual.abs() > s.part_counts * res {
                self.parted.saturating_add(1)
            } else {
                0
            };
            if self.parted >= s.part_steps {
                up.diagnostics.insert(Diagnostic::Parted);
            }
            self.bias
                .add(self.torque, h, twin.mode().shaft_turning(), s.bias_time);
            if self
                .bias
                .bias(s.bias_time)
                .is_some_and(|b| b.abs() > s.bias_limit)
            {
                up.diagnostics.insert(Diagnostic::LoadBias);
            }
        }
        self.p = prior;
        if let Some(e) = measured.and_then(|m| m.shaft) {
            self.watch_shaft(twin, e, &mut up);
        }
        self.last = Some(up);
        Ok(up)
    }

    /// The locked lever's update (I6, I8; [`ObserverSettings::held_gain`]) where the
    /// crank's transmission `r0` is under `min_transmission`: `nu` the crank's
    /// innovation and `res` the encoder's resolution, rad. `None` where nothing is
    /// outside the band, or the crank does not move with a locked lever (none in the
    /// mode: a sensitivity of 0).
    fn correct_held_lever(
        &mut self,
        twin: &mut Twin<T>,
        nu: T,
        r0: T,
        res: T,
    ) -> Result<Option<Correction<T>>, TwinStepError> {
        let s = self.settings;
        let nu = outside(nu, s.state_band * res);
        if nu == T::zero() {
            return Ok(None);
        }
        let sens = twin.held_lever_sensitivity();
        if sens == T::zero() {
            return Ok(None);
        }
        let share = (T::one() - r0.abs() / s.min_transmission).max(T::zero());
        twin.move_held_lever(s.held_gain * share * nu / sens)
            .map(Some)
    }

    /// Keeps `inputs`' valid crank and shaft counts as the last readings (an encoder
    /// without a reading, or one with no resolution, keeps its last).
    fn take_readings(&mut self, inputs: &Inputs<T>) {
        let Some(m) = inputs.measured else { return };
        for (last, e) in self.counts.iter_mut().zip([m.crank, m.shaft]) {
            if let Some(e) = e.filter(|e| e.per_turn > 0) {
                *last = Some(e.counts);
            }
        }
    }

    /// The crank's and shaft's counts of `inputs`, or the error that names an encoder
    /// whose count moved by half a turn or more since the last step: such a change
    /// within one step cannot be told from one the other way round, so it is no reading
    /// of a motion.
    fn check_jumps(&self, twin: &Twin<T>, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
        let Some(m) = inputs.measured else {
            return Ok(());
        };
        let encoders = [
            (m.crank, "crank encoder jump (counts in one step)"),
            (m.shaft, "shaft encoder jump (counts in one step)"),
        ];
        for (last, (e, field)) in self.counts.into_iter().zip(encoders) {
            let Some(e) = e else { continue };
            let jump = last.map_or(0, |c| e.counts.saturating_sub(c).unsigned_abs());
            if jump.saturating_mul(2) >= u64::from(e.per_turn) && e.per_turn > 0 {
                return Err(TwinStepError::BadInput {
                    time: twin.time().to_f64(),
                    field,
                    value: jump as f64,
                });
            }
        }
        Ok(())
    }

    /// The shaft's diagnostics: its motion measured since the last mode change
    /// against the twin's.
    fn watch_shaft(&mut self, twin: &Twin<T>, e: super::twin::Encoder<T>, up: &mut Update<T>) {
        let s = self.settings;
        let angle = twin.shaft_drive_angle();
        let Some((c0, a0)) = self.shaft_ref else {
            self.shaft_ref = Some((e.counts, angle));
            up.shaft_innovation = Some(T::zero());
            return;
        };
        let measured = T::c(e.counts.saturating_sub(c0) as f64);
        let twin_counts = (angle - a0) / e.resolution();
        let nu = measured - twin_counts;
        up.shaft_innovation = Some(nu);
        if nu.abs() > s.jump_counts * T::c(16.0) {
            up.diagnostics.insert(Diagnostic::EncoderJump("shaft"));
        } else if twin.mode().shaft_turning()
            && twin_counts.abs() >= s.slip_counts
            && measured.abs() < T::one()
        {
            up.diagnostics.insert(Diagnostic::FailedCatch);
        } else if nu.abs() >= s.slip_counts {
            up.diagnostics.insert(Diagnostic::ClutchSlip);
        } else {
            return;
        }
        // Raised once per departure: watched again from here.
        self.shaft_ref = Some((e.counts, angle));
    }
}

#[cfg(test)]
mod tests {
    use super::{quantization_variance, COUNT_STEPS_MAX};

    /// `Δ²/12` (a uniform error over one count) times the steps a count takes: 1 at a
    /// count a step or faster, 4 at a quarter count a step, the cap at rest or for a
    /// speed that is no number.
    #[test]
    fn a_slow_crank_s_count_weighs_as_one_reading_per_count() {
        let (res, h) = (core::f64::consts::TAU / 4096.0, 1e-3);
        let white = res * res / 12.0;
        let at = |omega: f64| quantization_variance(res, omega, h) / white;
        assert_eq!(at(res / h), 1.0);
        assert_eq!(at(-10.0 * res / h), 1.0);
        assert!((at(res / (4.0 * h)) - 4.0).abs() < 1e-12);
        assert_eq!(at(0.0), COUNT_STEPS_MAX);
        assert_eq!(at(res / (1e6 * h)), COUNT_STEPS_MAX);
        assert_eq!(at(f64::NAN), COUNT_STEPS_MAX);
    }
}
