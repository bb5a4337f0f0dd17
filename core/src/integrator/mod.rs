//! Dormand-Prince 5(4) integrators (SPEC 1, thesis 5.4).
//!
//! - [`Dp5`]: the fixed-step DP5 with FSAL and dense output, the twin's integrator;
//! - [`ThesisAdaptive`]: the thesis's step rule `s = (tol h / (2|E|))^(1/4)`;
//! - [`Adaptive`]: a standard error-controlled DP5(4) for accurate reference runs.
//!
//! All work on an [`OdeSystem`] over a fixed-size state vector, never allocate and have a
//! bounded amount of work per call.

use crate::scalar::Real;
use nalgebra::SVector;

mod adaptive;
mod dp5;
mod tableau;
mod thesis;

pub use adaptive::{Adaptive, AdaptiveError, AdaptiveSettings, AdaptiveStats};
pub use dp5::{Dp5, StepReport};
pub use tableau::Tableau;
pub use thesis::ThesisSettingsError;
pub use thesis::{ThesisAdaptive, ThesisSettings};

/// A first-order ODE `y' = f(t, y)` over a state of `N` scalars.
///
/// An evaluation may fail (a mechanism that cannot assemble, a singular configuration);
/// integrators then return the error and leave their caller's `t` and `y` untouched.
pub trait OdeSystem<T: Real, const N: usize> {
    /// The failure of one evaluation.
    type Error;
    /// Writes `f(t, y)` into `dy`.
    fn eval(&mut self, t: T, y: &SVector<T, N>, dy: &mut SVector<T, N>) -> Result<(), Self::Error>;

    /// Says whether the next [`OdeSystem::eval`] is an inner stage of a step: one whose
    /// state nothing but its rates leaves (a Runge-Kutta stage before the step's end).
    /// A system may skip there what only the state's own outputs need. The default
    /// does nothing.
    fn inner_stage(&mut self, _inner: bool) {}

    /// How many of the `N` scalars are the system's (the first ones and any others
    /// the system keeps at 0 count for nothing else): an error norm is their mean. A
    /// system padded to a fixed `N` (a mechanism of fewer degrees of freedom than the
    /// state holds) says how many it uses, so that its zeros do not dilute the norm
    /// (a 1-DOF mechanism in a 6-scalar state had a tolerance √3 times the one asked).
    /// The default: all `N`.
    fn live(&self) -> usize {
        N
    }
}
