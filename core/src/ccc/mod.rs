//! The Constantinesco torque converter (SPEC 3) as a digital twin on the core: its
//! parameters, its modes and their motion-transmission sequences, and [`Twin`], the
//! fixed-step stepper with the mechanical diode's events, consistent mode choice,
//! plastic impacts and coordinate switching at dead points.

mod build;
pub mod mode;
pub mod params;

pub use build::{initial_pose, mode_model};
pub use mode::{Clutch, Coordinates, Mode};
pub use params::{
    Bar, CccParams, DriveDirection, Friction, Side, FRICTION_JOINTS, FRICTION_JOINT_NAMES,
};
mod observer;
mod twin;

pub use observer::{
    quantization_variance, BiasWatch, Covariance, Diagnostic, Diagnostics, ObserverSettings,
    TwinObserver, Update, COUNT_STEPS_MAX,
};
pub use twin::{
    energy_tolerance, Audit, Converter, CoordinateSwitch, Correction, Encoder, EncoderResiduals,
    Event, EventKind, Failure, Inputs, LinkState, Measurement, MotorInput, Twin, TwinSettings,
    TwinSetupError, TwinStepError, CATCH_UP, DIODE_HORIZON_STEPS, ENERGY_TOL_STEP, JOINTS,
    JOINT_NAMES, MAX_CONVERTER_LOAD, MAX_EVENTS_PER_STEP, MAX_LOCATE_ITER, MAX_RETRIES,
    SINGULAR_CONDITIONING, SUBSTEPS,
};
