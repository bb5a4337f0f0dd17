//! The built-in scenarios by command-line name: the thesis's validation mechanisms of
//! [`structomat::mechanisms`], and the Constantinesco converter's scenarios S1 and S2
//! (SPEC 3, run on a [`structomat::ccc::Twin`] by [`crate::run::converter`]).
//!
//! Each ships as a run file, `host-sim/scenarios/<name>.toml`, embedded in the binary:
//! a built-in name runs its file exactly as `host-sim run FILE.toml` would (the golden
//! pins of `tests/golden.rs` show that the files describe the core's mechanisms bit
//! for bit). [`Source`] is "a built-in or a file's contents", what every run takes.

use super::analysis::{self, BuildError};
use super::runfile::{parse_run_file, Body, Converter, FileError, MotorSpec, RunFile};
use std::fmt;
use std::path::Path;
use std::sync::Arc;
use structomat::ccc::DriveDirection;
use structomat::mechanisms::Scenario;
use structomat::Real;

/// A built-in scenario.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScenarioId {
    /// `slider-crank`: [`slider_crank()`](fn@structomat::mechanisms::slider_crank).
    SliderCrank,
    /// `five-bar`: [`five_bar()`](fn@structomat::mechanisms::five_bar).
    FiveBar,
    /// `ccc-s1`: the converter in free mode (no clutch), 12 N·m on the crank, from rest
    /// (SPEC 3's S1, thesis 7.1); it ends at a singularity of the mechanism.
    CccS1,
    /// `ccc-s2`: the converter with its diode, 12 N·m on the crank, T_r = 800 N·m on the
    /// shaft from t = 0, shaft turning clockwise (SPEC 3's S2, thesis 7.2).
    CccS2,
}

impl ScenarioId {
    /// Every built-in scenario, in listing order.
    pub const ALL: [ScenarioId; 4] = [
        ScenarioId::SliderCrank,
        ScenarioId::FiveBar,
        ScenarioId::CccS1,
        ScenarioId::CccS2,
    ];

    /// The mechanism scenarios (a core [`Scenario`] each), in listing order.
    pub const MECHANISMS: [ScenarioId; 2] = [ScenarioId::SliderCrank, ScenarioId::FiveBar];

    /// The converter scenarios (a [`CccScenario`] each).
    pub const CONVERTER: [ScenarioId; 2] = [ScenarioId::CccS1, ScenarioId::CccS2];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            ScenarioId::SliderCrank => "slider-crank",
            ScenarioId::FiveBar => "five-bar",
            ScenarioId::CccS1 => "ccc-s1",
            ScenarioId::CccS2 => "ccc-s2",
        }
    }

    /// A one-line description (without the integration settings).
    pub fn description(self) -> &'static str {
        match self {
            ScenarioId::SliderCrank => {
                "slider-crank, asynchronous motor (10 N·m at 10 rpm, 3 N·m at 45 rpm, synchronous 70 rpm), from rest"
            }
            ScenarioId::FiveBar => {
                "five-bar, 2 DOF, 10 N·m on crank 1, no motor on link 2, gravity, from rest"
            }
            ScenarioId::CccS1 => {
                "Constantinesco converter, free mode (no clutch), 12 N·m on the crank, from rest; ends at a singularity of the mechanism"
            }
            ScenarioId::CccS2 => {
                "Constantinesco converter, 12 N·m on the crank, T_r = 800 N·m on the shaft from t = 0, shaft CW, from rest"
            }
        }
    }

    /// Whether this is a converter scenario (run by [`crate::run::converter`]).
    pub fn is_converter(self) -> bool {
        matches!(self, ScenarioId::CccS1 | ScenarioId::CccS2)
    }

    /// The scenario of a command-line name.
    pub fn from_name(name: &str) -> Option<ScenarioId> {
        ScenarioId::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The comma-separated list of names, for messages.
    pub fn names() -> String {
        ScenarioId::ALL.map(ScenarioId::name).join(", ")
    }

    /// The embedded text of the scenario's run file (`host-sim/scenarios/<name>.toml`).
    pub fn file_text(self) -> &'static str {
        match self {
            ScenarioId::SliderCrank => include_str!("../../scenarios/slider-crank.toml"),
            ScenarioId::FiveBar => include_str!("../../scenarios/five-bar.toml"),
            ScenarioId::CccS1 => include_str!("../../scenarios/ccc-s1.toml"),
            ScenarioId::CccS2 => include_str!("../../scenarios/ccc-s2.toml"),
        }
    }

    /// The scenario's run file, parsed and validated (origin `<name>.toml`).
    pub fn run_file(self) -> Result<RunFile, FileError> {
        parse_run_file(self.file_text(), &format!("{}.toml", self.name()))
    }

    /// Builds a mechanism scenario (model, initial state, `h`, `t_end`) in scalar `T`
    /// from its run file; `None` for a converter scenario (see [`ScenarioId::converter`]).
    pub fn build<T: Real>(self) -> Option<Result<Scenario<T>, String>> {
        if self.is_converter() {
            return None;
        }
        Some(
            self.run_file()
                .map_err(|e| e.to_string())
                .and_then(|f| analysis::scenario(&f).map_err(|e| e.to_string())),
        )
    }

    /// The scenario's own step size and simulated time `(h, t_end)`, s, from its run
    /// file; an error if the file does not parse.
    pub fn default_steps(self) -> Result<(f64, f64), FileError> {
        self.run_file().map(|f| (f.run.h, f.run.t_end))
    }

    /// The converter scenario's default settings; `None` for a mechanism scenario.
    pub fn converter(self) -> Option<CccScenario> {
        let file = self.run_file().ok()?;
        CccScenario::from_file(&file)
    }
}

/// What a run runs: a built-in scenario or the contents of a run file.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A built-in scenario (its embedded run file).
    Builtin(ScenarioId),
    /// A run file: its path as given (it names the run) and its contents.
    File {
        /// The path as given on the command line, or the name a caller gave.
        path: String,
        /// The parsed, validated file.
        file: Arc<RunFile>,
    },
}

impl From<ScenarioId> for Source {
    fn from(id: ScenarioId) -> Source {
        Source::Builtin(id)
    }
}

impl Source {
    /// A run file's contents under the name `path` (a sweep's job name, a path).
    pub fn from_file(path: impl Into<String>, file: RunFile) -> Source {
        Source::File {
            path: path.into(),
            file: Arc::new(file),
        }
    }

    /// Reads and validates the run file at `path`.
    pub fn read(path: &str) -> Result<Source, FileError> {
        let text = std::fs::read_to_string(path).map_err(|e| FileError {
            origin: path.to_string(),
            position: None,
            field: String::new(),
            message: format!("cannot read: {e}"),
        })?;
        Ok(Source::from_file(path, parse_run_file(&text, path)?))
    }

    /// A scenario argument: a built-in name, else the path of a run file (`*.toml`).
    /// Errors: an unknown name (not ending in `.toml`), or the file's error.
    pub fn from_arg(arg: &str) -> Result<Source, FileError> {
        if let Some(id) = ScenarioId::from_name(arg) {
            return Ok(Source::Builtin(id));
        }
        if arg.ends_with(".toml") {
            return Source::read(arg);
        }
        Err(FileError {
            origin: arg.to_string(),
            position: None,
            field: String::new(),
            message: format!(
                "unknown scenario (known: {}; or a run file FILE.toml)",
                ScenarioId::names()
            ),
        })
    }

    /// The name in summaries and messages: the built-in's name or the file's path.
    pub fn name(&self) -> &str {
        match self {
            Source::Builtin(id) => id.name(),
            Source::File { path, .. } => path,
        }
    }

    /// A short label for output file names: the built-in's name or the file's stem.
    pub fn label(&self) -> String {
        match self {
            Source::Builtin(id) => id.name().to_string(),
            Source::File { path, .. } => Path::new(path)
                .file_stem()
                .map_or_else(|| "run".to_string(), |s| s.to_string_lossy().into_owned()),
        }
    }

    /// The built-in scenario, if it is one.
    pub fn builtin(&self) -> Option<ScenarioId> {
        match self {
            Source::Builtin(id) => Some(*id),
            Source::File { .. } => None,
        }
    }

    /// The run file (a built-in's embedded one, parsed now).
    pub fn run_file(&self) -> Result<Arc<RunFile>, FileError> {
        match self {
            Source::Builtin(id) => id.run_file().map(Arc::new),
            Source::File { file, .. } => Ok(Arc::clone(file)),
        }
    }

    /// Whether it describes the converter (run by [`crate::run::converter`]).
    pub fn is_converter(&self) -> bool {
        match self {
            Source::Builtin(id) => id.is_converter(),
            Source::File { file, .. } => matches!(file.body, Body::Converter(_)),
        }
    }

    /// Whether it is the converter in free mode (no clutch: no shaft load, no drive
    /// direction; its run ends at the mechanism's singularity as expected).
    pub fn is_free_converter(&self) -> bool {
        match self {
            Source::Builtin(id) => *id == ScenarioId::CccS1,
            Source::File { file, .. } => matches!(&file.body, Body::Converter(c) if !c.clutch),
        }
    }

    /// The converter's settings; `None` for a mechanism.
    pub fn converter(&self) -> Option<CccScenario> {
        CccScenario::from_file(&*self.run_file().ok()?)
    }

    /// The file's own `(h, t_end)`, s.
    pub fn default_steps(&self) -> Result<(f64, f64), FileError> {
        self.run_file().map(|f| (f.run.h, f.run.t_end))
    }

    /// Builds a mechanism's core scenario in scalar `T` (the structomatic analysis of
    /// its file, then the model).
    pub fn build<T: Real>(&self) -> Result<Scenario<T>, String> {
        let file = self.run_file().map_err(|e| e.to_string())?;
        analysis::scenario(&file).map_err(|e| match e {
            BuildError::Converter => format!(
                "{} is a converter scenario: run it with host_sim::run::simulate",
                self.name()
            ),
            e => format!("cannot build {}: {e}", self.name()),
        })
    }
}

/// A converter scenario's settings (SPEC 3), after the command-line overrides: its run
/// file's `[converter]` and `[run]` ([`Converter`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CccScenario {
    /// `false`: free mode, no clutch (S1).
    pub clutch: bool,
    /// The motor on the crank (a constant torque, N·m, CCW positive, or a motor law).
    pub motor: MotorSpec,
    /// Load torque T_r on the shaft, N·m (≥ 0; no effect in free mode).
    pub load: f64,
    /// Which way the shaft turns.
    pub drive: DriveDirection,
    /// Default step, s.
    pub h: f64,
    /// Default simulated time, s.
    pub t_end: f64,
    /// The file's converter: every parameter and the initial state.
    pub converter: Box<Converter>,
}

impl CccScenario {
    /// The settings of a converter run file; `None` for a mechanism file.
    pub fn from_file(file: &RunFile) -> Option<Self> {
        let Body::Converter(c) = &file.body else {
            return None;
        };
        Some(CccScenario {
            clutch: c.clutch,
            motor: c.motor,
            load: c.load,
            drive: c.params.drive,
            h: file.run.h,
            t_end: file.run.t_end,
            converter: c.clone(),
        })
    }
}

impl fmt::Display for CccScenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.clutch {
            let dir = match self.drive {
                DriveDirection::Cw => "CW",
                DriveDirection::Ccw => "CCW",
            };
            write!(
                f,
                "motor {}, T_r = {} N·m, shaft {dir}, from rest",
                self.motor, self.load
            )
        } else {
            write!(f, "free mode (no clutch), motor {}, from rest", self.motor)
        }
    }
}
