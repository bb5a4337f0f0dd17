//! The Constantinesco converter's digital twin ([`structomat::ccc::Twin`]) as an FMI
//! 2.0 Co-Simulation FMU.
//!
//! - [`variables`]: the one table of the FMU's variables (parameters: the converter's,
//!   its initial state and h; inputs: motor and load torque; outputs: the mode, crank
//!   and shaft angle and speed, c6, c8 and the energy audit) and their start values;
//! - [`description`]: the modelDescription.xml written from that table, and its GUID;
//! - [`instance`]: one instance's FMI state machine, values and twin, in safe Rust;
//! - [`ffi`]: every FMI 2.0 C function, exported, each a thin door onto
//!   [`instance::Instance`] with no panic crossing it.
//!
//! `host-sim fmu --out ccc.fmu` zips this crate's cdylib with the description.

pub mod description;
pub mod ffi;
pub mod instance;
pub mod variables;
