//! Many runs: the worker pool ([`pool`]), the runs of a batch file ([`batch`]), the
//! grid of variants of a parameter sweep ([`sweep`]) and the generations of a design
//! search ([`design`]), each run through the one pipeline of [`crate::run`], and the
//! replays of a bench log that identify the converter's parameters ([`identify`]).

pub mod batch;
pub mod design;
pub mod identify;
pub mod pool;
pub mod sweep;
