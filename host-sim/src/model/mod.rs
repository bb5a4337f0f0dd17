//! What a run runs: run files ([`runfile`]), the structomatic analysis that turns a
//! mechanism's file into the core's model ([`analysis`]), and the built-in scenarios
//! and run sources ([`scenarios`]).

pub mod alternatives;
pub mod analysis;
pub mod runfile;
pub mod scenarios;
