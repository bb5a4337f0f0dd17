//! What a command is asked to do: the options of `run`, `replay`, `identify`, `batch`,
//! `sweep` and `plot` (parsed from the command line by [`args`]), and the checks every run makes on them
//! before its first step ([`Steps`]).

pub mod args;

use crate::error::{RunError, Sci, UsageError};
use crate::model::bench::{BenchLog, ClutchLog};
use crate::model::identifiable::Param;
use crate::model::scenarios::Source;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use structomat::Real;

/// Where the CSV goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// Standard output (the summary then goes to standard error).
    Stdout,
    /// A file (the summary then goes to standard output).
    File(PathBuf),
}

/// Options of `host-sim fmu`.
#[derive(Clone, Debug, PartialEq)]
pub struct FmuOptions {
    /// The converter and its overrides, as for `run` (`h`, `t_end`, `motor`, `load`,
    /// `ccw`); the other fields unused.
    pub run: RunOptions,
    /// Where the FMU goes.
    pub out: PathBuf,
    /// The FMU's binary (`None`: next to the executable).
    pub lib: Option<PathBuf>,
}

/// Frames a second of an animation unless `--fps` says otherwise.
pub const DEFAULT_FPS: u32 = 25;
/// Slow-motion factor of an animation unless `--slow` says otherwise (real time).
pub const DEFAULT_SLOW: f64 = 1.0;

/// Options of `host-sim run`.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOptions {
    /// The scenario: a built-in or a run file's contents.
    pub scenario: Source,
    /// Where the CSV goes.
    pub out: Output,
    /// Step size, s (`None`: the scenario's).
    pub h: Option<f64>,
    /// Simulated time, s (`None`: the scenario's).
    pub t_end: Option<f64>,
    /// Write every N-th step (at least 1): `--every`, else the run file's.
    pub every: u64,
    /// Run the core in `f32`: `--f32`, else the run file's.
    pub f32: bool,
    /// No summary.
    pub quiet: bool,
    /// Converter scenarios: the shaft turns counter-clockwise (SPEC 3's CCW variant).
    pub ccw: bool,
    /// Converter scenarios: load torque T_r on the shaft, N·m (`None`: the scenario's).
    pub load: Option<f64>,
    /// Converter scenarios: constant motor torque on the crank, N·m, CCW positive
    /// (`None`: the scenario's).
    pub motor: Option<f64>,
    /// Converter scenarios: `--spread-events`, each event's work spread over the steps
    /// after it (`false`: the run file's `run.spread_events`).
    pub spread_events: bool,
    /// `--plot DIR`: where the plots go.
    pub plot: Option<PathBuf>,
    /// `--animate FILE`: the animations to write (`.svg`, `.gif`).
    pub animate: Vec<PathBuf>,
    /// `--fps`: frames a second of the animation.
    pub fps: u32,
    /// `--slow`: the animation lasts `slow` times the simulated time.
    pub slow: f64,
}

impl RunOptions {
    /// The default options for `scenario`: CSV to stdout, the scenario's own `h` and
    /// `t_end`, every step, `f64`, with a summary (see [`RunOptions::from_source`] for
    /// the run file's `every` and `f32`).
    pub fn new(scenario: impl Into<Source>) -> Self {
        RunOptions {
            scenario: scenario.into(),
            out: Output::Stdout,
            h: None,
            t_end: None,
            every: 1,
            f32: false,
            quiet: false,
            ccw: false,
            load: None,
            motor: None,
            spread_events: false,
            plot: None,
            animate: Vec::new(),
            fps: DEFAULT_FPS,
            slow: DEFAULT_SLOW,
        }
    }
}

impl RunOptions {
    /// The options `host-sim run` gives a scenario without options: its run file's
    /// `every` and `f32` (what a parameter sweep starts from). A built-in whose
    /// embedded file does not parse keeps the defaults of [`RunOptions::new`] (its run
    /// reports the file's error).
    pub fn from_source(scenario: impl Into<Source>) -> Self {
        let mut o = RunOptions::new(scenario);
        if let Ok(f) = o.scenario.run_file() {
            o.every = f.run.every;
            o.f32 = f.run.f32;
        }
        o
    }
}

/// The observer's tuning (`replay --observer TUNING`): how far the twin's model is
/// trusted, the filter's process noise.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObserverTuning {
    /// A twin with the drawing's nominal parameters
    /// (`structomat::ccc::ObserverSettings::reference`).
    Nominal,
    /// A twin whose parameters `host-sim identify` fitted to the machine's logs
    /// (`ObserverSettings::identified`).
    Identified,
}

/// Options of `host-sim replay`: a bench log, read and validated, and the converter to
/// replay it on.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayOptions {
    /// The bench log: the path as given and its contents.
    pub log: (PathBuf, Arc<BenchLog>),
    /// `--params`: the converter's run file (default: ccc-s2, SPEC's machine).
    pub params: Source,
    /// `--clutch-log`: the machine's clutch events, path and contents.
    pub clutch: Option<(PathBuf, Arc<ClutchLog>)>,
    /// `--out`: the state CSV (its event and switch logs next to it).
    pub out: PathBuf,
    /// `--observer [TUNING]`: the twin corrected from the log's encoders, so tuned.
    pub observer: Option<ObserverTuning>,
    /// No summary.
    pub quiet: bool,
}

/// Options of `host-sim plot`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlotOptions {
    /// The CSV a run wrote.
    pub csv: PathBuf,
    /// Where the plots go.
    pub out_dir: PathBuf,
}

/// Options of `host-sim identify`: a bench log (and clutch log), read and validated,
/// the converter to start from and the parameters to fit.
#[derive(Clone, Debug, PartialEq)]
pub struct IdentifyOptions {
    /// The bench log: the path as given and its contents.
    pub log: (PathBuf, Arc<BenchLog>),
    /// `--clutch-log`: the machine's clutch events, path and contents.
    pub clutch: Option<(PathBuf, Arc<ClutchLog>)>,
    /// `--params`: the converter's run file to start from (default: ccc-s2).
    pub params: Source,
    /// Its text (the identified file is it with the values set).
    pub base_text: String,
    /// `--fit`: the parameters to fit.
    pub fit: Vec<Param>,
    /// `--fit`'s stages: how many of the parameters (the first ones) each searches.
    pub stages: Vec<usize>,
    /// `--max-iters`: Nelder-Mead's iterations at most.
    pub max_iters: u64,
    /// `--out`: the identified run file.
    pub out: PathBuf,
    /// No progress lines, no summary.
    pub quiet: bool,
}

/// The most threads `host-sim batch --threads` takes (a guard against a typo that
/// would spawn thousands).
pub const MAX_THREADS: usize = 256;

/// Options of `host-sim batch`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BatchOptions {
    /// The batch file: one run a line.
    pub file: PathBuf,
    /// Where the files go.
    pub out_dir: PathBuf,
    /// Runs at a time (1..=[`MAX_THREADS`]).
    pub threads: usize,
    /// No progress lines, no closing summary.
    pub quiet: bool,
}

/// Frames a second: the bounds of `--fps` (GIF delays are in 1/100 s, and browsers slow
/// down delays under 2/100 s).
pub const FPS_RANGE: (u32, u32) = (1, 50);
/// The bounds of `--slow`.
pub const SLOW_RANGE: (f64, f64) = (0.01, 1000.0);
/// The most frames an animation may have.
pub const MAX_FRAMES: u64 = 5000;
/// An animation file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimFormat {
    /// Animated SVG (SMIL).
    Svg,
    /// GIF.
    Gif,
}

impl AnimFormat {
    /// By the extension of `path`: `.svg` or `.gif`.
    pub fn of(path: &Path) -> Result<AnimFormat, String> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Ok(AnimFormat::Svg),
            Some("gif") => Ok(AnimFormat::Gif),
            _ => Err(format!(
                "--animate: '{}' has no .svg or .gif extension",
                path.display()
            )),
        }
    }
}

/// How a sweep shows its progress on `stderr`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressStyle {
    /// A bar redrawn in place (`\r`): for a terminal.
    Bar,
    /// A line at every tenth of the variants: for a log file or a pipe.
    Lines,
    /// Nothing.
    None,
    /// `Bar` when `stderr` is a terminal, else `Lines`.
    Auto,
}

/// Options of `host-sim sweep`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SweepOptions {
    /// The sweep file.
    pub file: PathBuf,
    /// Where the table and pictures go.
    pub out_dir: PathBuf,
    /// Runs at a time (`None`: the file's `threads`, else 2).
    pub threads: Option<usize>,
    /// The progress display.
    pub progress: ProgressStyle,
    /// Also write each variant's CSV and logs (as `host-sim batch` names them).
    pub keep_runs: bool,
    /// No progress, no closing summary.
    pub quiet: bool,
}

/// Options of `host-sim design`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DesignOptions {
    /// The design file.
    pub file: PathBuf,
    /// Where the best design, the table and the pictures go.
    pub out_dir: PathBuf,
    /// Runs at a time (`None`: the file's `threads`, else 2).
    pub threads: Option<usize>,
    /// Skip the winner's run (its CSV, plots and animation) and its check at h/2.
    pub no_winner: bool,
    /// No progress, no closing summary.
    pub quiet: bool,
}

/// The most steps a run may take (a guard against `--h 1e-300`).
pub const MAX_STEPS: u64 = 1_000_000_000;

/// `"f32"` or `"f64"`: the name of the scalar `T` in summaries and messages.
pub fn precision<T: Real>() -> &'static str {
    if core::mem::size_of::<T>() == 4 {
        "f32"
    } else {
        "f64"
    }
}

/// A run's fixed steps: its options' `--h` and `--t-end`, or else its scenario's.
///
/// [`Steps::of`] makes the checks every run makes before its first step, so that
/// `host-sim batch` can reject a bad line before anything runs, with the same message
/// `host-sim run` would give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Steps {
    /// Step size as given (or the scenario's), s, in `f64`.
    pub h: f64,
    /// Simulated time, s.
    pub t_end: f64,
    /// Number of steps ([`step_count`]).
    pub n: u64,
    /// Whether `t_end` is not a multiple of `h` (to 1e-9): the last of the `n` steps is
    /// then shorter, landing on `t_end`.
    pub short_last: bool,
}

impl Steps {
    /// The steps of `opts` in scalar `T`, and the step size as a `T`. Errors: `--h` is
    /// not a positive `T` (an `f32` underflow), or more than [`MAX_STEPS`] steps
    /// ([`RunError::Usage`]); the scenario's defaults cannot be built
    /// ([`RunError::Setup`]).
    pub fn of<T: Real>(opts: &RunOptions) -> Result<(Steps, T), RunError> {
        // The defaults as f64 (the f32 scenario's 0.01 s step is 0.0099999998 s).
        let (h64, t_end) = match (opts.h, opts.t_end) {
            (Some(h), Some(t)) => (h, t),
            (h, t) => {
                let (dh, dt) = opts.scenario.default_steps().map_err(|e| {
                    RunError::Setup(format!("cannot read {}: {e}", opts.scenario.name()))
                })?;
                (h.unwrap_or(dh), t.unwrap_or(dt))
            }
        };
        let h = T::c(h64);
        if !(h.finite() && h > T::zero()) {
            return Err(RunError::Usage(UsageError(format!(
                "--h: {h64} s is not a positive {}",
                precision::<T>()
            ))));
        }
        if h64 > t_end {
            return Err(RunError::Usage(UsageError(format!(
                "--h / --t-end: the step h = {} s is longer than the run, t_end = {} s; \
                 take h <= t_end",
                Sci(h64),
                Sci(t_end)
            ))));
        }
        // Counted with the f64 step as given (an f32 step of 0.01 is 0.0099999998).
        let n = step_count(h64, t_end).map_err(RunError::Usage)?;
        let short_last = (n as f64) * h64 > t_end * (1.0 + 1e-9);
        Ok((
            Steps {
                h: h64,
                t_end,
                n,
                short_last,
            },
            h,
        ))
    }

    /// The steps of `opts` in its own precision (`--f32` or `f64`).
    pub fn check(opts: &RunOptions) -> Result<Steps, RunError> {
        if opts.f32 {
            Steps::of::<f32>(opts).map(|(s, _)| s)
        } else {
            Steps::of::<f64>(opts).map(|(s, _)| s)
        }
    }
}

/// Number of fixed steps of size `h` to reach `t_end`: `t_end / h` when that is an
/// integer to 1e-9 relative, else rounded up; at least 1.
pub fn step_count(h: f64, t_end: f64) -> Result<u64, UsageError> {
    let r = t_end / h;
    if !(r.is_finite() && r <= MAX_STEPS as f64) {
        return Err(UsageError(format!(
            "--t-end / --h: {} s / {} s is more than {MAX_STEPS} steps",
            Sci(t_end),
            Sci(h)
        )));
    }
    let n = if (r - r.round()).abs() <= 1e-9 * r.max(1.0) {
        r.round()
    } else {
        r.ceil()
    };
    Ok((n as u64).max(1))
}
