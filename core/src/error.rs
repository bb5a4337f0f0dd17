//! Errors: one small enum per operation, each saying which group, when, and why.

use crate::structomat::GroupKind;
use core::fmt;

/// Identifies a group of a motion-transmission sequence in messages:
/// its position in the sequence, its kind and its links (thesis numbering).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroupId {
    /// Position in the sequence (0 = first group after the ground).
    pub index: u8,
    /// Kind of structomat.
    pub kind: GroupKind,
    /// Link numbers (bodies `1..`), `links[..count]`.
    pub links: [u8; crate::config::MAX_GROUP_LINKS],
    /// Number of links.
    pub count: u8,
}

impl fmt::Display for GroupId {
    /// The thesis's notation, e.g. `RRR(2,3)` or `R(1)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}(", self.kind.symbol())?;
        for (k, l) in self.links.iter().take(self.count as usize).enumerate() {
            if k > 0 {
                f.write_str(",")?;
            }
            write!(f, "{l}")?;
        }
        f.write_str(")")
    }
}

/// Why a model description was rejected ([`ModelBuilder`](crate::model::ModelBuilder)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelError {
    /// A parameter is NaN or infinite.
    NonFinite(&'static str),
    /// A parameter that must be positive (a mass, a length) is not.
    NotPositive(&'static str),
    /// A parameter that must not be negative is.
    Negative(&'static str),
    /// A fixed capacity of [`config`](crate::config) is exceeded.
    Capacity(&'static str),
    /// A group refers to a link or point that does not exist.
    UnknownReference(&'static str),
    /// A group uses a link that no earlier group has placed, or places a link twice.
    Sequence {
        /// The group at fault.
        group: u8,
        /// What is wrong.
        why: &'static str,
    },
    /// Links that no group of the sequence places.
    Unplaced {
        /// Link number (body index) of the first unplaced link.
        link: u8,
    },
    /// A generalized coordinate is driven by no motor element, or by two.
    Coordinates(&'static str),
    /// A geometric parameter makes a group degenerate (e.g. a zero-length arm).
    Degenerate(&'static str),
    /// Values that are finite but whose products overflow the scalar: the step squares
    /// distances and multiplies masses by gravity and heights.
    Overflow(&'static str),
    /// A value of a group (an angle offset, a guess, or a length or direction derived
    /// from its links' points, which can overflow) is NaN or infinite.
    GroupNonFinite {
        /// Position of the group in the sequence.
        group: u8,
        /// Its kind.
        kind: GroupKind,
        /// Which value.
        what: &'static str,
    },
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelError::NonFinite(w) => write!(f, "{w} is not finite"),
            ModelError::NotPositive(w) => write!(f, "{w} must be positive"),
            ModelError::Negative(w) => write!(f, "{w} must not be negative"),
            ModelError::Capacity(w) => write!(f, "too many {w} for the fixed capacity"),
            ModelError::UnknownReference(w) => write!(f, "{w} refers to nothing"),
            ModelError::Sequence { group, why } => write!(f, "group {group}: {why}"),
            ModelError::Unplaced { link } => {
                write!(f, "link {link} is placed by no group of the sequence")
            }
            ModelError::Coordinates(w) => write!(f, "generalized coordinates: {w}"),
            ModelError::Degenerate(w) => write!(f, "degenerate geometry: {w}"),
            ModelError::Overflow(w) => write!(f, "{w} overflows the scalar type"),
            ModelError::GroupNonFinite { group, kind, what } => {
                write!(f, "group {group} ({}): {what} is not finite", kind.symbol())
            }
        }
    }
}

impl core::error::Error for ModelError {}

/// What went wrong inside one group's kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GroupFault {
    /// The group cannot assemble: its input poles are too far apart or too close
    /// (`gap` > 0 is by how much, m, the closure misses).
    CannotAssemble {
        /// How far the closest configuration is from closing, m.
        gap: f64,
    },
    /// Its Jacobian W is singular (a dead point): `conditioning` is the normalized
    /// determinant (the sine of the transmission angle for a dyad).
    Singular {
        /// |det W| divided by the product of its column norms.
        conditioning: f64,
    },
    /// Newton-Raphson did not converge within the bound.
    NewtonDidNotConverge {
        /// Iterations used (the bound).
        iterations: u32,
        /// Residual norm at the end, m.
        residual: f64,
    },
    /// Newton converged on the other assembly branch (the determinant changed sign):
    /// the configuration passed through a singular position.
    BranchJump,
    /// An input (coordinate, speed) is NaN or infinite.
    NonFiniteInput,
    /// A dead point of the coordinates that no other choice of coordinates passes
    /// ([`crate::simulation::switch`]): the group is singular there (conditioning
    /// `conditioning`) and so is every alternative tried (`alternatives` of them; `best`
    /// the worst-group conditioning of the best of them, NaN if none assembles there).
    DeadPoint {
        /// The group's normalized determinant at the last good state.
        conditioning: f64,
        /// The best alternative's worst normalized determinant there (NaN: none
        /// assembles at the pose).
        best: f32,
        /// Alternative choices of coordinates tried.
        alternatives: u8,
    },
}

impl fmt::Display for GroupFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GroupFault::CannotAssemble { gap } => {
                write!(f, "cannot assemble (the loop misses closing by {gap:.3e} m)")
            }
            GroupFault::Singular { conditioning } => write!(
                f,
                "singular Jacobian (normalized determinant {conditioning:.3e})"
            ),
            GroupFault::NewtonDidNotConverge {
                iterations,
                residual,
            } => write!(
                f,
                "Newton-Raphson did not converge in {iterations} iterations (residual {residual:.3e} m)"
            ),
            GroupFault::BranchJump => f.write_str("left its assembly branch"),
            GroupFault::NonFiniteInput => f.write_str("non-finite input"),
            GroupFault::DeadPoint {
                conditioning,
                alternatives,
                best,
            } => {
                write!(
                    f,
                    "dead point: the driven coordinates lose the mechanism (normalized determinant {conditioning:.3e}) and no other choice of coordinates drives it there ({alternatives} tried"
                )?;
                if best.is_nan() {
                    f.write_str("; none assembles at the pose)")
                } else {
                    write!(f, "; the best is conditioned at {best:.3e})")
                }
            }
        }
    }
}

/// Why an evaluation or a step failed. The simulation that returns it keeps its last
/// good state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepError {
    /// A group of the sequence failed.
    Group {
        /// Time of the failing evaluation, s.
        time: f64,
        /// The group.
        group: GroupId,
        /// The cause.
        fault: GroupFault,
    },
    /// The reduced mass matrix `VᵀMV` is not positive definite (the coordinates do
    /// not describe the motion: a singular configuration of the mechanism).
    SingularMassMatrix {
        /// Time, s.
        time: f64,
    },
    /// The state or an input (motor torque, load) is NaN or infinite.
    NonFinite {
        /// Time, s.
        time: f64,
        /// What was not finite, with its cause, when known, in trailing parentheses
        /// (`"a link's speed (the state has run away)"`): the message reads
        /// "t = … s: a link's speed is not finite: the state has run away".
        what: &'static str,
    },
    /// One fixed step breaks the energy balance (the work of the motors and loads
    /// against the change of kinetic plus potential energy) past its tolerance even in
    /// the finest sub-steps ([`balance`](crate::balance)): the step is too large for the
    /// motion.
    EnergyBalance {
        /// Time at the start of the step (the last good state), s.
        time: f64,
        /// Work in minus energy gained over the step, J.
        residual: f64,
        /// The energy scale of the tolerance, `1 J + |works| + |K| + |V|`, J.
        scale: f64,
        /// Sub-steps of the division whose residual this is: the finest that reached
        /// the step's end (a finer one failed otherwise, or none did).
        substeps: u32,
    },
}

impl StepError {
    /// The same failure at time `time` (s): where it was located inside the step
    /// ([`Simulation::locate_failure`](crate::Simulation::locate_failure)). A broken
    /// energy balance keeps its time, the step's start.
    pub fn at_time(self, time: f64) -> StepError {
        match self {
            StepError::Group { group, fault, .. } => StepError::Group { time, group, fault },
            StepError::SingularMassMatrix { .. } => StepError::SingularMassMatrix { time },
            StepError::NonFinite { what, .. } => StepError::NonFinite { time, what },
            e @ StepError::EnergyBalance { .. } => e,
        }
    }

    /// Time of the failure, s.
    pub fn time(&self) -> f64 {
        match *self {
            StepError::Group { time, .. }
            | StepError::SingularMassMatrix { time }
            | StepError::NonFinite { time, .. }
            | StepError::EnergyBalance { time, .. } => time,
        }
    }
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepError::Group { time, group, fault } => {
                write!(f, "t = {} s: group {group}: {fault}", Time(*time))
            }
            StepError::SingularMassMatrix { time } => write!(
                f,
                "t = {} s: the reduced mass matrix is singular (singular configuration)",
                Time(*time)
            ),
            StepError::NonFinite { time, what } => {
                // `what` may carry its cause in trailing parentheses: "X (cause)" reads
                // "X is not finite: cause".
                match what.strip_suffix(')').and_then(|w| w.split_once(" (")) {
                    Some((value, cause)) => {
                        write!(f, "t = {} s: {value} is not finite: {cause}", Time(*time))
                    }
                    None => write!(f, "t = {} s: {what} is not finite", Time(*time)),
                }
            }
            StepError::EnergyBalance {
                time,
                residual,
                scale,
                substeps,
            } => {
                write!(
                    f,
                    "t = {} s: one step breaks the energy balance by {residual:.3e} J ({:.1e} of the energy scale {scale:.3e} J) ",
                    Time(*time),
                    residual.abs() / scale
                )?;
                // `substeps` is the division this residual is of: 1 when no finer
                // division reached the step's end.
                if *substeps > 1 {
                    write!(f, "even divided into {substeps} sub-steps")?;
                } else {
                    write!(
                        f,
                        "undivided, and no division into sub-steps reached the step's end"
                    )?;
                }
                write!(
                    f,
                    ": the step is too large for the motion; take a smaller step"
                )
            }
        }
    }
}

impl core::error::Error for StepError {}

/// A time in a message, s: six decimals (`1.234000`), or seven significant digits with
/// an exponent below 1e-3 and from 1e9 on (`2.500000e-8`), where six decimals would print `0.000000` or a long run
/// of digits.
struct Time(f64);

impl fmt::Display for Time {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.0;
        if t == 0.0 || !t.is_finite() || (1e-3..1e9).contains(&t.abs()) {
            write!(f, "{t:.6}")
        } else {
            write!(f, "{t:.6e}")
        }
    }
}
