//! What a run runs: run files ([`runfile`]), the structomatic analysis that turns a
//! mechanism's file into the core's model ([`analysis`]), the built-in scenarios and
//! run sources ([`scenarios`]), the bench logs a replay runs from ([`bench`](mod@bench)),
//! and the converter's parameters that `host-sim identify` fits ([`identifiable`]).

pub mod alternatives;
pub mod analysis;
pub mod bench;
pub mod identifiable;
pub mod runfile;
pub mod scenarios;
