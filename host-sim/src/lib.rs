//! # host-sim
//!
//! A command-line simulator of the built-in mechanisms of the `structomat` core
//! ([`structomat::mechanisms`]) and of mechanisms and the Constantinesco torque
//! converter described in run files (TOML, [`model::runfile`]): `host-sim list`,
//! `host-sim run <scenario>|FILE.toml [options]` (CSV of the state, the applied and
//! kinetostatic driving torques and the joint reactions, plus a summary; for the
//! converter, SPEC 3, also the logs of the mode changes and of the coordinate
//! switches), `host-sim replay LOG.csv` (a bench log replayed open-loop on the
//! converter's twin: encoder residuals, the machine's clutch events paired with the
//! twin's), `host-sim analyze`, `host-sim batch`, `host-sim sweep`, `host-sim plot`,
//! `host-sim help [COMMAND]` (each command's options and reference).
//!
//! The output is deterministic: the same command writes the same bytes on every run,
//! in debug and release builds, on 1 or N threads (the core's math is `libm`; the
//! golden SHA-256 hashes of every built-in scenario's CSV are pinned in
//! `host-sim/tests/golden.rs`).
//!
//! ## Layers
//!
//! The modules stand in layers; a module imports from its own layer and the ones below
//! it, never from one above (`host-sim/tests/layers.rs` checks every `crate::` path),
//! and nothing inside them uses this root's re-exports. From the bottom:
//!
//! 0. [`error`]: the errors of a run and of a command line, the exit codes, the
//!    number formats of messages and summaries.
//! 1. [`draw`]: figures and their SVG and PNG rendering (plots, heat maps, frames).
//! 2. [`model`]: what a run runs: run files, the structomatic analysis, the built-in
//!    scenarios and run sources.
//! 3. [`options`]: what a command is asked to do: the options of every command, their
//!    command-line arguments (clap) and checks, the step count of a run.
//! 4. [`output`]: the one observer interface a runner drives ([`output::Observer`])
//!    and its observers: the CSV writer, the plots' table, the animation's frames.
//! 5. [`run`]: the runners (mechanism and converter) and the one pipeline that drives
//!    either through the observers ([`run::execute`]).
//! 6. [`jobs`]: many runs: the worker pool, batches, sweeps and design searches.
//! 7. [`cli`]: the command line on top of everything ([`main_with`]); the binary is a
//!    thin wrapper over it.
//!
//! Tests and benches can call [`main_with`], [`cli::parse_args`], [`run::simulate`]
//! (any runner, any observer) or [`simulate`] (a mechanism's CSV) directly. A
//! parameter sweep runs files the way `host-sim run` does:
//! [`model::runfile::parse_value`], [`model::runfile::set_dotted`],
//! [`run_file_from_value`], then [`Source::from_file`] into
//! [`RunOptions::from_source`] and [`jobs::batch::run_one`].

#![warn(missing_docs)]

pub mod cli;
pub mod draw;
pub mod error;
pub mod jobs;
pub mod model;
pub mod options;
pub mod output;
pub mod run;

pub use cli::main_with;
pub use error::{RunError, UsageError, EXIT_FAILURE, EXIT_OK, EXIT_USAGE, HINT};
pub use jobs::pool::{run_jobs, Progress};
pub use jobs::{batch, sweep};
pub use model::alternatives::alternatives as model_alternatives;
pub use model::runfile::{parse_run_file, run_file_from_value, FileError, RunFile};
pub use model::scenarios::{ScenarioId, Source};
pub use model::{analysis, runfile, scenarios};
pub use options::{BatchOptions, Output, PlotOptions, RunOptions};
pub use output::{animate, pictures, plot};
pub use run::converter as ccc;
pub use run::mechanism::{simulate_csv as simulate, Summary};
