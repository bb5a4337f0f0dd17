#![no_std]
#![warn(missing_docs)]
//! # structomat
//!
//! Real-time dynamics of planar linkages by *structomats* (Assur groups), transmission
//! matrices, Lagrange's equations and Dormand-Prince, after a thesis on the
//! Constantinesco torque converter; the physics and the conventions are in the
//! repository's `docs/model.md`.
//!
//! A mechanism is a [`Model`]: links, ground points and an ordered
//! motion-transmission sequence of groups ([`structomat`]), validated once by a
//! [`ModelBuilder`]. Algorithms are functions over the model and
//! a preallocated [`Workspace`]:
//!
//! | stage | module | SPEC / thesis |
//! |---|---|---|
//! | group kinematics (position, velocity, acceleration) | [`structomat`], [`kinematics`] | SPEC 1; thesis 3.2 |
//! | `V`, `a_b`, `C`, `D` from the group models | [`transmission`] | SPEC 1; thesis 5.1.3 |
//! | `(VᵀMV) q̈ = Vᵀ(F - M a_b)` | [`dynamics`] | thesis eq. 4.49 |
//! | joint reactions, driving torques | [`kinetostatics`] | thesis 3.3 |
//! | DP5 fixed, thesis-adaptive, adaptive | [`integrator`] | SPEC 1; thesis 5.4 |
//! | each fixed step's energy balance, sub-steps | [`balance`] | SPEC 3's audit |
//! | motor laws | [`motor`] | thesis 5.3 |
//! | the stepper of a model | [`simulation`] | SPEC 1 |
//! | fixed-size LU, Cholesky, small inverses | [`linalg`] | |
//! | the thesis's slider-crank and five-bar | [`mechanisms`] | thesis ch. 6 |
//! | the Constantinesco converter and its twin | [`ccc`], [`ccc::Twin`] | SPEC 3; thesis ch. 2, 5.5, 7 |
//!
//! SPEC n names a section of `docs/model.md`.
//!
//! No heap, no panics on the step path, bounded iterations, `libm` math everywhere
//! (bit-identical results on every platform), generic over `f64` and `f32`.
//!
//! Cargo feature `log` (off by default): the twin's diagnostic records (mode changes,
//! coordinate switches, refused mode candidates) through the `log` crate's macros.
//! Without it they compile to nothing: their arguments are type-checked, but no
//! formatting code and no `log` is linked into the firmware.
//!
//! ```
//! use structomat::mechanisms::five_bar;
//! let scenario = five_bar::<f64>()?;
//! assert_eq!(scenario.model.formula().to_string(), "Z(0) + R(1) + R(2) + RRR(3,4)");
//! let mut sim = scenario.simulation()?;
//! // The dyad assembles on the branch of the thesis's guesses (table 7: 30°, 132°).
//! let x = sim.workspace().group[2].x;
//! assert!((x[0].to_degrees() - 30.2).abs() < 0.1 && (x[1].to_degrees() - 131.9).abs() < 0.1);
//! for _ in 0..100 {
//!     sim.step()?;
//! }
//! assert!((sim.time() - 0.1).abs() < 1e-15);
//! // The kinetostatics recovers the motor's 10 N·m on link 1.
//! let model = sim.model().clone();
//! let ws = sim.kinetostatics()?;
//! let tau = structomat::kinetostatics::driving_torque(&model, ws, 0).unwrap();
//! assert!((tau - 10.0).abs() < 1e-9);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// `!(x > 0)` is how the core rejects NaN along with non-positive values: a NaN compares
// false with everything, so the negated test catches it where `x <= 0` would not.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod balance;
pub mod capacity;
pub mod ccc;
pub mod config;
pub mod dynamics;
pub mod error;
mod in_place;
pub mod integrator;
pub mod kinematics;
pub mod kinetostatics;
pub mod linalg;
pub mod mechanisms;
pub mod model;
pub mod motor;
pub mod scalar;
pub mod simulation;
pub mod structomat;
mod trace;
pub mod transmission;
pub mod workspace;

pub use balance::Balance;
pub use error::{GroupFault, GroupId, ModelError, StepError};
pub use model::{Link, Model, ModelBuilder};
pub use scalar::Real;
pub use simulation::{SetupError, Simulation};
pub use workspace::Workspace;
