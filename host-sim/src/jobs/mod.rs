//! Many runs: the worker pool ([`pool`]), the runs of a batch file ([`batch`]) and the
//! grid of variants of a parameter sweep ([`sweep`]), each run through the one
//! pipeline of [`crate::run`].

pub mod batch;
pub mod design;
pub mod pool;
pub mod sweep;
