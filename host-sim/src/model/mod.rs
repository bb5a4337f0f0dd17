//! What a run runs: run files ([`runfile`]), the structomatic analysis that turns a
//! mechanism's file into the core's model ([`analysis`]), the built-in scenarios and
//! run sources ([`scenarios`]), and the bench logs a replay runs from ([`bench`](mod@bench)).

pub mod alternatives;
pub mod analysis;
pub mod bench;
pub mod runfile;
pub mod scenarios;
