//! Many runs: the worker pool ([`pool`]), the runs of a batch file ([`batch`]), the
//! grid of variants of a parameter sweep ([`sweep`]) and the generations of a design
//! search ([`design`]), each run through [`crate::run`].

pub mod batch;
pub mod design;
pub mod pool;
pub mod sweep;
