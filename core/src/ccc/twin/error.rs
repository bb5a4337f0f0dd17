//! Why the twin could not be set up ([`TwinSetupError`]) or step ([`TwinStepError`]).

use super::super::build::{BRANCHES, ROCKER};
use super::super::mode::{Coordinates, Mode};
use super::inputs::MAX_CONVERTER_LOAD;
use super::settings::*;
use super::slot::physical;
use super::Twin;
use crate::error::{GroupFault, GroupId, ModelError, StepError};
use crate::scalar::Real;
use core::fmt;

/// A group that failed in one coordinate choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    /// The coordinate choice.
    pub coords: Coordinates,
    /// The group, in physical link numbers.
    pub group: GroupId,
    /// Why.
    pub fault: GroupFault,
}

/// Why a twin could not be set up ([`Twin::new`]): nothing was built.
#[derive(Clone, Debug, PartialEq)]
pub enum TwinSetupError {
    /// A parameter of the converter is invalid.
    Params(ModelError),
    /// A field of [`TwinSettings`] is invalid.
    Setting {
        /// The field, as [`TwinSettings`] names it.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The converter cannot assemble at the initial crank and swing-link angles.
    Assembly {
        /// [`TwinSettings::crank`], rad.
        crank: f64,
        /// [`TwinSettings::swing`], rad.
        swing: f64,
    },
    /// The initial state (the first mode's coordinates and speeds) is not finite.
    InitialState,
    /// The first evaluation, the first mode choice or the first inputs failed: the
    /// error a step would give there.
    Start(TwinStepError),
}

/// Why a step of the twin failed ([`Twin::step`]). The twin keeps its last good state.
#[derive(Clone, Debug, PartialEq)]
pub enum TwinStepError {
    /// A per-step input is invalid: the twin did not step.
    BadInput {
        /// Time of the last good state, s.
        time: f64,
        /// The input ([`Inputs`](super::Inputs)' field and what of it).
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The time `(n + 1)·h` of the next step overflows the scalar type, or the scalar no
    /// longer resolves the step there (its spacing h/2 or more: f32 at h = 1 ms from
    /// 8192 s on).
    TimeOverflow {
        /// Steps taken, n.
        steps: u64,
        /// The fixed step, s.
        h: f64,
    },
    /// A mode's model could not be built at the pose (its geometry degenerates there,
    /// or a value overflows): the model builder's own error.
    Model {
        /// Time, s.
        time: f64,
        /// The mode being built.
        mode: Mode,
        /// The model builder's error.
        error: ModelError,
    },
    /// An evaluation failed (not a group: a non-finite input, a singular mass matrix).
    Step(StepError),
    /// Every coordinate choice of the mode fails here: a singularity of the mechanism
    /// itself (SPEC 3: its constraints lose rank), or a dead point of every choice the
    /// mode has.
    Mechanism {
        /// Time, s.
        time: f64,
        /// The mode.
        mode: Mode,
        /// The group that fails in each choice.
        failures: heapless::Vec<Failure, 3>,
    },
    /// One step breaks the energy balance past [`TwinSettings::energy_tol`] even in the
    /// finest sub-steps tried (the finest of [`SUBSTEPS`], or the twin's finer rungs
    /// where the failed attempts predicted them to pass): the motion runs into a
    /// singularity of the mechanism faster than the step can follow (the worst group's
    /// conditioning is then near 0), or the step is far too coarse for the motion, or
    /// near a dead point of the coordinates the scalar's rounding breaks it (`stalled`).
    /// Names the sub-steps and the worst-conditioned group.
    Diverged {
        /// Time at the start of the step, s.
        time: f64,
        /// The mode.
        mode: Mode,
        /// Change of the audit residual over the step, J.
        jump: f64,
        /// The sub-steps of the last attempt, the finest tried.
        substeps: u32,
        /// The worst-conditioned group of the sequence (fault: its conditioning).
        worst: Failure,
        /// The jump did not fall with the sub-steps: between the last two rungs it fell
        /// by less than the square of their ratio, where DP5's truncation error falls
        /// as its fifth power. Not the step's size, then, but rounding amplified near
        /// a dead point, which finer steps do not mend: f32 at light loads after a
        /// catch into A68 in the levers' coordinates (20/200 N·m: 4.4 and 2.0
        /// tolerances in 32 and 64 sub-steps). Before it refuses such a step the twin
        /// redoes it in the mode's other coordinates, if it has any.
        stalled: bool,
    },
    /// A diode branch's rod and lever came in line (stretched, |DH| = rod + lever, or
    /// folded) and the step could not go on: a singularity of the mechanism itself
    /// (SPEC 3, the end of S1). The branch's dyad loses rank; with the reference's equal
    /// branches both come in line at once, G and I meet, and the two branches'
    /// constraints become one. Replaces the [`TwinStepError::Mechanism`] or singular
    /// [`TwinStepError::Diverged`] error it explains.
    Diode {
        /// Time of the last good state, s (the failing step starts there).
        time: f64,
        /// The mode.
        mode: Mode,
        /// |DH| at the last good state, m.
        reach: f64,
        /// Per branch (rod 5 and lever 6, rod 7 and lever 8): |sin| of the angle between
        /// rod and lever at the last good state (0: in line).
        sines: [f64; 2],
        /// Per branch: whether it is named in line: |sin| under
        /// [`SINGULAR_CONDITIONING`], or closing so fast that it reaches 0 within
        /// [`DIODE_HORIZON_STEPS`] steps at its present rate.
        in_line: [bool; 2],
        /// Per branch: |sin| over its rate of decrease, s (the time to in line at the
        /// present rate; infinite when it is not closing).
        closing_in: [f64; 2],
        /// Rod plus lever of each branch, m (the stretched reach).
        stretched_reach: [f64; 2],
        /// Time at which the first branch named in line comes in line, s, located
        /// inside the failing step: `time` plus the least `closing_in` of the branches
        /// in line (the rod-lever angle closes at a finite rate while |DH| touches its
        /// limit); `time` if none closes at its rate.
        at: f64,
    },
}

/// A value as an error message gives it: in words when it is not finite.
struct Value(f64);

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            v if v.is_nan() => f.write_str("not a number"),
            v if v.is_infinite() && v > 0.0 => f.write_str("+infinity"),
            v if v.is_infinite() => f.write_str("-infinity"),
            v => write!(f, "{v:e}"),
        }
    }
}

/// What a [`TwinSettings`] field is and what it must be.
fn setting_rule(field: &str) -> (&'static str, &'static str) {
    match field {
        "h" => ("the step, s", "must be positive and finite"),
        "energy_tol" => ("the energy tolerance", "must be positive and finite"),
        "switch_below" => ("the coordinate switch threshold", "must be in (0, 1)"),
        "crank" => ("the initial crank angle, rad", "must be finite"),
        "swing" => ("the initial swing-link angle, rad", "must be finite"),
        "crank_speed" => ("the initial crank speed, rad/s", "must be finite"),
        "swing_speed" => ("the initial swing-link speed, rad/s", "must be finite"),
        _ => ("a setting", "must be finite"),
    }
}

impl fmt::Display for TwinSetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TwinSetupError::Params(e) => write!(f, "converter: {e}"),
            TwinSetupError::Setting { field, value } => {
                let (what, rule) = setting_rule(field);
                write!(
                    f,
                    "converter: the setting {field} ({what}) = {} {rule}",
                    Value(*value)
                )
            }
            TwinSetupError::Assembly { crank, swing } => write!(
                f,
                "converter: it cannot assemble at the initial crank angle {crank} rad and swing-link angle {swing} rad"
            ),
            TwinSetupError::InitialState => {
                f.write_str("converter: the initial state (coordinates and speeds) is not finite")
            }
            TwinSetupError::Start(e) => write!(f, "converter: the first evaluation failed: {e}"),
        }
    }
}

impl core::error::Error for TwinSetupError {}

impl From<ModelError> for TwinSetupError {
    fn from(e: ModelError) -> Self {
        TwinSetupError::Params(e)
    }
}

impl From<TwinStepError> for TwinSetupError {
    fn from(e: TwinStepError) -> Self {
        TwinSetupError::Start(e)
    }
}

impl fmt::Display for TwinStepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TwinStepError::BadInput { time, field, value } => {
                if *field == "load" {
                    return write!(
                        f,
                        "t = {time:.6} s: the input load = {} must be finite, ≥ 0 and under {} N·m (the clutches' torque tolerance scales with it): no step taken",
                        Value(*value),
                        Value(MAX_CONVERTER_LOAD)
                    );
                }
                let rule = if field.starts_with("observer settings") {
                    "cannot make a filter (a noise, σ or band must be finite and ≥ 0, a limit or gate ≥ 0, a gain within 0 to 1, bias_time > 0)"
                } else if field.starts_with("twin settings") {
                    "is not allowed"
                } else if *field == "oscillating mass" {
                    "must be finite and > 0"
                } else if field.contains("resolution") {
                    "must be > 0"
                } else if field.contains("jump") {
                    "must be under half a turn (the direction of a larger one is unknown)"
                } else {
                    "must be finite"
                };
                write!(
                    f,
                    "t = {time:.6} s: the input {field} = {} {rule}: no step taken",
                    Value(*value)
                )
            }
            TwinStepError::TimeOverflow { steps, h } => write!(
                f,
                "the time of step {} at h = {h:e} s overflows the scalar type or no longer resolves the step in it (a longer run needs f64)",
                steps.saturating_add(1)
            ),
            TwinStepError::Model { time, mode, error } => write!(
                f,
                "t = {time:.6} s: mode {mode}: its model cannot be built at this pose: {error}"
            ),
            TwinStepError::Step(e) => write!(f, "{e}"),
            TwinStepError::Mechanism {
                time,
                mode,
                failures,
            } => {
                write!(
                    f,
                    "t = {time:.6} s: mode {mode}: no coordinate choice drives the mechanism here (a singularity of the mechanism, or a dead point of every choice the mode has): "
                )?;
                for (k, x) in failures.iter().enumerate() {
                    let sep = if k == 0 { "" } else { "; " };
                    write!(f, "{sep}{} coordinates: {} {}", x.coords, x.group, x.fault)?;
                }
                Ok(())
            }
            TwinStepError::Diverged {
                time,
                mode,
                jump,
                substeps,
                worst,
                stalled,
            } => write!(
                f,
                "t = {time:.6} s: mode {mode}: one step breaks the energy balance by {jump:.3e} J even in {substeps} sub-steps: {} (worst group in {} coordinates: {} {})",
                if self.at_singularity() {
                    "a singularity of the mechanism is near"
                } else if *stalled {
                    "it did not fall with the sub-steps: rounding near a dead point of the coordinates, not the step's size"
                } else {
                    "the step is too coarse for the motion"
                },
                worst.coords,
                worst.group,
                worst.fault
            ),
            TwinStepError::Diode { .. } => self.fmt_diode(f),
        }
    }
}

impl core::error::Error for TwinStepError {}

impl TwinStepError {
    /// [`TwinStepError::Diode`]'s message: the branches in line and the reach.
    fn fmt_diode(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let TwinStepError::Diode {
            time,
            mode,
            reach,
            sines,
            stretched_reach,
            in_line,
            closing_in,
            at,
        } = self
        else {
            return Ok(());
        };
        write!(
            f,
            "t = {time:.6} s: mode {mode}: a singularity of the mechanism at t = {at:.7} s (located inside the step): the diode's rods and levers in line, "
        )?;
        let mut first = true;
        // The stretched length of the first branch in line (the branches may differ).
        let mut full_in_line = None;
        for (k, (rod, lever)) in BRANCHES.into_iter().enumerate() {
            let (Some(sine), Some(full), Some(true), Some(within)) = (
                sines.get(k),
                stretched_reach.get(k),
                in_line.get(k).copied(),
                closing_in.get(k),
            ) else {
                continue;
            };
            let sep = if first { "" } else { " and " };
            let how = if *reach > full * 0.5 {
                "stretched"
            } else {
                "folded"
            };
            write!(f, "{sep}RRR({rod},{lever}) {how} (|sin| {sine:.1e}")?;
            if *sine >= SINGULAR_CONDITIONING {
                write!(f, ", in line in {:.2} ms at its rate", within * 1e3)?;
            }
            f.write_str(")")?;
            first = false;
            full_in_line.get_or_insert(*full);
        }
        let full = full_in_line.unwrap_or(stretched_reach[0]);
        write!(
            f,
            ", |DH| = {reach:.7} m of rod + lever = {full:.7} m: their constraints lose rank, no coordinate choice drives it"
        )
    }

    /// Whether the twin stopped at a singularity of the mechanism itself (SPEC 3: the
    /// end of S1), rather than at a bad input or a step too coarse.
    pub fn at_singularity(&self) -> bool {
        match self {
            TwinStepError::Mechanism { .. } | TwinStepError::Diode { .. } => true,
            TwinStepError::Diverged { worst, .. } => matches!(
                worst.fault,
                GroupFault::Singular { conditioning } if conditioning < SINGULAR_CONDITIONING
            ),
            _ => false,
        }
    }

    /// Whether finer sub-steps may pass the step: a group that fails, or an energy
    /// balance that breaks, may be a step too coarse for a fast passage.
    pub(super) fn retry_finer(&self) -> bool {
        matches!(
            self,
            TwinStepError::Mechanism { .. } | TwinStepError::Diverged { .. }
        )
    }
}

impl<T: Real> Twin<T> {
    /// [`TwinStepError::Diode`] if a diode branch's rod and lever are in line at the last
    /// good state: |sin| of their angle under [`SINGULAR_CONDITIONING`], or closing
    /// towards 0 fast enough to get there within [`DIODE_HORIZON_STEPS`] steps
    /// (d|sin Δ|/dt = sign(sin Δ)·cos Δ·(ω_rod − ω_lever), Δ = θ_rod − θ_lever).
    pub(super) fn diode_in_line(&self) -> Option<TwinStepError> {
        let reach = (self.joint_position(ROCKER, 2) - self.params.h).norm();
        let horizon = DIODE_HORIZON_STEPS * self.h().to_f64();
        let mut sines = [1.0; 2];
        let mut stretched_reach = [0.0; 2];
        let mut in_line = [false; 2];
        let mut closing_in = [f64::INFINITY; 2];
        for (k, (rod, lever)) in BRANCHES.into_iter().enumerate() {
            let (r, l) = (self.link(rod), self.link(lever));
            let delta = r.theta - l.theta;
            let (sin, cos) = delta.sincos();
            let (sin, cos) = (sin.to_f64(), cos.to_f64());
            let rate = sin.signum() * cos * (r.omega - l.omega).to_f64();
            let sine = sin.abs();
            let within = if rate < 0.0 {
                sine / -rate
            } else {
                f64::INFINITY
            };
            let full = (self.params.link(rod).length + self.params.link(lever).length).to_f64();
            if let (Some(s), Some(fr), Some(il), Some(ci)) = (
                sines.get_mut(k),
                stretched_reach.get_mut(k),
                in_line.get_mut(k),
                closing_in.get_mut(k),
            ) {
                (*s, *fr, *ci) = (sine, full, within);
                *il = sine < SINGULAR_CONDITIONING || within < horizon;
            }
        }
        if !in_line.iter().any(|b| *b) {
            return None;
        }
        // The rod-lever angle passes zero at a finite rate (the levers' speeds stay
        // finite while |DH| touches its limit like the square of the time left): its
        // sine's linear extrapolation locates the in-line pose, exact to second order.
        let at = self.t.to_f64()
            + closing_in
                .iter()
                .zip(&in_line)
                .filter(|(c, il)| **il && c.is_finite())
                .fold(f64::INFINITY, |m, (c, _)| m.min(*c));
        let at = if at.is_finite() { at } else { self.t.to_f64() };
        Some(TwinStepError::Diode {
            at,
            time: self.t.to_f64(),
            mode: self.slots.cur().mode,
            reach: reach.to_f64(),
            sines,
            stretched_reach,
            in_line,
            closing_in,
        })
    }

    pub(super) fn physical_error(&self, e: StepError) -> TwinStepError {
        match e {
            StepError::Group { .. } => {
                let StepError::Group { time, group, fault } = physical(&self.slots.cur().map, e)
                else {
                    return TwinStepError::Step(e);
                };
                let mut failures = heapless::Vec::new();
                let _ = failures.push(Failure {
                    coords: self.slots.cur().coords,
                    group,
                    fault,
                });
                TwinStepError::Mechanism {
                    time,
                    mode: self.slots.cur().mode,
                    failures,
                }
            }
            e => TwinStepError::Step(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::mode::{Coordinates, Mode};
    use super::super::settings::SINGULAR_CONDITIONING;
    use super::{Failure, TwinStepError};
    use crate::error::{GroupFault, GroupId};
    use crate::structomat::GroupKind;
    extern crate std;
    use std::string::{String, ToString};

    /// A refused step's message says what broke its balance, by the error's fields: a
    /// group conditioned under [`SINGULAR_CONDITIONING`] is the mechanism's singularity
    /// whatever the jumps did; otherwise a jump that did not fall with the sub-steps
    /// (`stalled`) is rounding, and one that fell too slowly the step's size. The
    /// worst group is named in the thesis's notation.
    #[test]
    fn a_refused_step_says_what_broke_its_balance() {
        let mut links = [0u8; crate::config::MAX_GROUP_LINKS];
        links[..2].copy_from_slice(&[5, 7]);
        let group = GroupId {
            index: 3,
            kind: GroupKind::Rrr,
            links,
            count: 2,
        };
        let message = |conditioning: f64, stalled: bool| -> String {
            TwinStepError::Diverged {
                time: 0.241,
                mode: Mode::A68,
                jump: -0.165,
                substeps: 64,
                worst: Failure {
                    coords: Coordinates::Lever,
                    group,
                    fault: GroupFault::Singular { conditioning },
                },
                stalled,
            }
            .to_string()
        };
        let stalled = message(0.1, true);
        assert!(
            stalled.contains("did not fall with the sub-steps"),
            "{stalled}"
        );
        assert!(!stalled.contains("too coarse"), "{stalled}");
        assert!(
            stalled.contains("RRR(5,7)") && stalled.contains("64 sub-steps"),
            "{stalled}"
        );
        let coarse = message(0.1, false);
        assert!(coarse.contains("too coarse"), "{coarse}");
        for stalled in [false, true] {
            let singular = message(0.5 * SINGULAR_CONDITIONING, stalled);
            assert!(
                singular.contains("a singularity of the mechanism is near"),
                "{singular}"
            );
        }
    }
}
