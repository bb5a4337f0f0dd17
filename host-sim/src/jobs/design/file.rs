//! The design file of `host-sim design`: a base converter, the free parameters with
//! their bounds (dotted run-file keys, as a sweep's axes), the operating points, the
//! objective, the constraints, the search's settings and an optional front over loads.
//!
//! ```toml
//! base = "ccc-s2"              # a built-in scenario, or a run file (path relative to this file)
//! [set]                        # fixed changes to the base, by dotted key
//! "run.h" = 1e-4
//! [[free]]                     # a free parameter: any numeric dotted key, and its bounds
//! key = "converter.mass"
//! min = 2.0
//! max = 20.0
//! [[point]]                    # an operating point: load T_r, N·m; motor torque, N·m; horizon, s
//! load = 800.0
//! motor = 12.0
//! horizon = 5.0
//! [objective]
//! metric = "mean_power"        # or "first_breakaway"
//! [constraints]
//! margin = 0.005               # δ, m: |DH| ≤ rod + lever − δ at every step
//! [search]
//! population = 16
//! generations = 20
//! seed = 1
//! [front]                      # optional: one search per load (the first point's motor and horizon)
//! loads = [100.0, 400.0, 800.0, 1200.0]
//! population = 12              # optional: each load's search (else [search]'s)
//! generations = 8
//! ```
//!
//! Everything is checked before anything runs: the keys are written into the base tree
//! at each parameter's bounds and midpoint and the trees parsed by the run-file parser
//! (a key the run file does not take is refused with its own message), every point's
//! numbers are finite and in range, the search's settings in range.

use crate::jobs::sweep::{load_base, number};
use crate::model::runfile::{self, set_dotted_in as set_dotted};
use crate::options::MAX_THREADS;
use std::fmt;
use toml::{Table, Value};

/// The most free parameters.
pub const MAX_FREE: usize = 32;
/// The most points per generation and generations (a guard against a typo that would
/// run for days: 200 × 200 designs of 5 s take about 9 hours on 2 cores).
pub const MAX_POPULATION: usize = 200;
/// The most generations of one search.
pub const MAX_GENERATIONS: usize = 200;

/// A free parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Free {
    /// The dotted run-file key.
    pub key: String,
    /// Its label in pictures and tables (the key when none is given).
    pub label: String,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// The base's value, if it is a number inside the bounds (the search starts there).
    pub base: Option<f64>,
}

/// An operating point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Load torque T_r on the shaft, N·m.
    pub load: f64,
    /// Constant motor torque on the crank, N·m (`None`: the base's, or a free key's).
    pub motor: Option<f64>,
    /// Simulated time, s.
    pub horizon: f64,
}

/// What the search optimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Objective {
    /// Mean power to the load over the last half of the horizon, W: maximised (the
    /// lowest over the points).
    MeanPower,
    /// Time to the first breakaway, s: minimised (the latest over the points).
    FirstBreakaway,
}

impl Objective {
    /// Its name in the design file.
    pub fn name(self) -> &'static str {
        match self {
            Objective::MeanPower => "mean_power",
            Objective::FirstBreakaway => "first_breakaway",
        }
    }
}

/// The constraints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraints {
    /// δ, m: the diode's reach |DH| stays ≤ rod + lever − δ at every step.
    pub margin: f64,
    /// No step ends in the jam (the machine held at rest).
    pub no_jam: bool,
    /// The linkage assembles at every crank angle (every 5°) at the initial swing angle.
    pub assembly: bool,
    /// The twin reaches the horizon (no failed step).
    pub horizon: bool,
}

/// The search's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Search {
    /// Designs per generation.
    pub population: usize,
    /// Generations after the initial one.
    pub generations: usize,
    /// The generator's seed.
    pub seed: u64,
    /// DE's differential weight F.
    pub weight: f64,
    /// DE's crossover rate CR.
    pub crossover: f64,
}

/// A parsed design file.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    /// The design file's name, for messages.
    pub origin: String,
    /// The base as written.
    pub base: String,
    /// The base's run-file tree with the `[set]` keys written in.
    pub base_tree: Table,
    /// The free parameters, in file order.
    pub free: Vec<Free>,
    /// The operating points.
    pub points: Vec<Point>,
    /// The objective.
    pub objective: Objective,
    /// The constraints.
    pub constraints: Constraints,
    /// The search.
    pub search: Search,
    /// The loads of the front (empty: no front).
    pub front: Vec<f64>,
    /// The search of each load of the front (the main search's unless the front says).
    pub front_search: Search,
    /// Runs at a time from the file (`--threads` overrides it).
    pub threads: Option<usize>,
    /// A design the search starts from instead of the base's values (a front's
    /// searches start from the main search's best).
    pub start_point: Option<Vec<f64>>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    base: String,
    #[serde(default)]
    set: Table,
    #[serde(default)]
    free: Vec<FreeFile>,
    #[serde(default)]
    point: Vec<PointFile>,
    objective: Option<ObjectiveFile>,
    constraints: Option<ConstraintsFile>,
    search: Option<SearchFile>,
    front: Option<FrontFile>,
    threads: Option<usize>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FreeFile {
    key: String,
    label: Option<String>,
    min: f64,
    max: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PointFile {
    load: f64,
    motor: Option<f64>,
    horizon: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectiveFile {
    metric: String,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ConstraintsFile {
    margin: Option<f64>,
    no_jam: Option<bool>,
    assembly: Option<bool>,
    horizon: Option<bool>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SearchFile {
    population: Option<usize>,
    generations: Option<usize>,
    seed: Option<u64>,
    weight: Option<f64>,
    crossover: Option<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FrontFile {
    loads: Vec<f64>,
    population: Option<usize>,
    generations: Option<usize>,
}

/// A design file error: the file, the field and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DesignError(pub String);

impl fmt::Display for DesignError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DesignError {}

/// The number at the dotted `key` of `tree`, if there is one.
pub fn get_dotted(tree: &Table, key: &str) -> Option<f64> {
    let mut segments = key.split('.');
    let mut here = tree.get(segments.next()?)?;
    for seg in segments {
        here = match here {
            Value::Table(t) => t.get(seg)?,
            Value::Array(a) => a.get(seg.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    number(here)
}

impl Design {
    /// The run-file tree of design `x` (one value per free parameter) at `point`:
    /// the base with the free keys, the point's load and motor and `run.t_end` =
    /// its horizon written in.
    pub fn tree(&self, x: &[f64], point: &Point) -> Result<Table, String> {
        let mut tree = self.base_tree.clone();
        for (f, v) in self.free.iter().zip(x) {
            set_dotted(&mut tree, &f.key, Value::Float(*v))?;
        }
        set_dotted(&mut tree, "run.load", Value::Float(point.load))?;
        if let Some(m) = point.motor {
            set_dotted(&mut tree, "run.motor", Value::Float(m))?;
        }
        set_dotted(&mut tree, "run.t_end", Value::Float(point.horizon))?;
        Ok(tree)
    }

    /// The design's free values as `key = value, ...`.
    pub fn describe(&self, x: &[f64]) -> String {
        self.free
            .iter()
            .zip(x)
            .map(|(f, v)| format!("{} = {v}", f.key))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The same design searched at one load: the first point's motor and horizon.
    pub fn at_load(&self, load: f64) -> Design {
        let mut d = self.clone();
        let first = self.points.first().copied().unwrap_or(Point {
            load,
            motor: None,
            horizon: 1.0,
        });
        d.points = vec![Point { load, ..first }];
        d.front = Vec::new();
        d.search = self.front_search;
        d
    }

    /// The design the search starts from: [`Design::start_point`], else the base's
    /// values of the free parameters if every one is a number inside its bounds.
    pub fn start(&self) -> Option<Vec<f64>> {
        self.start_point
            .clone()
            .or_else(|| self.free.iter().map(|f| f.base).collect())
    }
}

/// Parses a design file (`load_base` as [`parse_sweep`](crate::jobs::sweep::parse_sweep)'s).
pub fn parse_design(
    text: &str,
    origin: &str,
    load_base: impl Fn(&str) -> Result<(Table, String), String>,
) -> Result<Design, DesignError> {
    let err = |m: String| DesignError(format!("{origin}: {m}"));
    let file: DesignFile = toml::from_str(text)
        .map_err(|e| DesignError(runfile::toml_error(&e, text, origin).to_string()))?;
    let (mut base_tree, _) =
        load_base(&file.base).map_err(|e| err(format!("base = '{}': {e}", file.base)))?;
    for (key, value) in &file.set {
        set_dotted(&mut base_tree, key, value.clone()).map_err(|e| err(format!("[set] {e}")))?;
    }
    if let Some(t) = file.threads {
        if !(1..=MAX_THREADS).contains(&t) {
            return Err(err(format!("threads = {t}: must be 1..={MAX_THREADS}")));
        }
    }
    if file.free.is_empty() {
        return Err(err(
            "free: no free parameter ([[free]] key, min, max)".into()
        ));
    }
    if file.free.len() > MAX_FREE {
        return Err(err(format!("free: more than {MAX_FREE} parameters")));
    }
    let mut free: Vec<Free> = Vec::new();
    for (k, f) in file.free.into_iter().enumerate() {
        let at = format!("free {} ('{}')", k + 1, f.key);
        if f.key.trim().is_empty() {
            return Err(err(format!("free {}: key: empty", k + 1)));
        }
        if free.iter().any(|g| g.key == f.key) {
            return Err(err(format!("{at}: the key is already free")));
        }
        if ["run.load", "run.t_end"].contains(&f.key.as_str()) {
            return Err(err(format!(
                "{at}: key: set by the operating points ([[point]] load, horizon)"
            )));
        }
        if !(f.min.is_finite() && f.max.is_finite() && f.min < f.max) {
            return Err(err(format!(
                "{at}: min = {}, max = {}: must be finite with min < max",
                f.min, f.max
            )));
        }
        let base = get_dotted(&base_tree, &f.key).filter(|v| (f.min..=f.max).contains(v));
        free.push(Free {
            label: f.label.unwrap_or_else(|| f.key.clone()),
            key: f.key,
            min: f.min,
            max: f.max,
            base,
        });
    }
    let motor_free = free.iter().any(|f| f.key == "run.motor");
    if file.point.is_empty() {
        return Err(err(
            "point: no operating point ([[point]] load, horizon)".into()
        ));
    }
    let mut points = Vec::new();
    for (k, p) in file.point.iter().enumerate() {
        let at = format!("point {}", k + 1);
        if !(p.load.is_finite() && p.load >= 0.0) {
            return Err(err(format!(
                "{at}: load = {}: must be a finite torque ≥ 0, N·m",
                p.load
            )));
        }
        if let Some(m) = p.motor {
            if !m.is_finite() {
                return Err(err(format!("{at}: motor = {m}: must be finite, N·m")));
            }
            if motor_free {
                return Err(err(format!(
                    "{at}: motor: run.motor is a free parameter; leave the point's motor out"
                )));
            }
        }
        if !(p.horizon.is_finite() && p.horizon > 0.0) {
            return Err(err(format!(
                "{at}: horizon = {}: must be a time > 0, s",
                p.horizon
            )));
        }
        points.push(Point {
            load: p.load,
            motor: p.motor,
            horizon: p.horizon,
        });
    }
    let objective = match file.objective.as_ref().map(|o| o.metric.as_str()) {
        None | Some("mean_power") => Objective::MeanPower,
        Some("first_breakaway") => Objective::FirstBreakaway,
        Some(other) => {
            return Err(err(format!(
                "objective metric = '{other}': unknown (known: mean_power, first_breakaway)"
            )))
        }
    };
    let c = file.constraints.as_ref();
    let constraints = Constraints {
        margin: c.and_then(|c| c.margin).unwrap_or(0.005),
        no_jam: c.and_then(|c| c.no_jam).unwrap_or(true),
        assembly: c.and_then(|c| c.assembly).unwrap_or(true),
        horizon: c.and_then(|c| c.horizon).unwrap_or(true),
    };
    if !(constraints.margin.is_finite() && constraints.margin >= 0.0) {
        return Err(err(format!(
            "constraints margin = {}: must be a length ≥ 0, m",
            constraints.margin
        )));
    }
    let s = file.search.as_ref();
    let search = Search {
        population: s.and_then(|s| s.population).unwrap_or(16),
        generations: s.and_then(|s| s.generations).unwrap_or(20),
        seed: s.and_then(|s| s.seed).unwrap_or(1),
        weight: s.and_then(|s| s.weight).unwrap_or(0.7),
        crossover: s.and_then(|s| s.crossover).unwrap_or(0.9),
    };
    if !(4..=MAX_POPULATION).contains(&search.population) {
        return Err(err(format!(
            "search population = {}: must be 4..={MAX_POPULATION} (DE draws three others)",
            search.population
        )));
    }
    if search.generations > MAX_GENERATIONS {
        return Err(err(format!(
            "search generations = {}: must be 0..={MAX_GENERATIONS}",
            search.generations
        )));
    }
    if !(search.weight > 0.0 && search.weight <= 2.0) {
        return Err(err(format!(
            "search weight = {}: must be in (0, 2]",
            search.weight
        )));
    }
    if !(0.0..=1.0).contains(&search.crossover) {
        return Err(err(format!(
            "search crossover = {}: must be in [0, 1]",
            search.crossover
        )));
    }
    let front_search = Search {
        population: file
            .front
            .as_ref()
            .and_then(|f| f.population)
            .unwrap_or(search.population),
        generations: file
            .front
            .as_ref()
            .and_then(|f| f.generations)
            .unwrap_or(search.generations),
        ..search
    };
    if !(4..=MAX_POPULATION).contains(&front_search.population)
        || front_search.generations > MAX_GENERATIONS
    {
        return Err(err(format!(
            "front population = {}, generations = {}: must be 4..={MAX_POPULATION} and 0..={MAX_GENERATIONS}",
            front_search.population, front_search.generations
        )));
    }
    let front = file.front.map(|f| f.loads).unwrap_or_default();
    if let Some(l) = front.iter().find(|l| !(l.is_finite() && **l >= 0.0)) {
        return Err(err(format!(
            "front loads: {l}: must be a finite torque ≥ 0, N·m"
        )));
    }
    let design = Design {
        origin: origin.to_string(),
        base: file.base,
        base_tree,
        free,
        points,
        objective,
        constraints,
        search,
        front,
        front_search,
        threads: file.threads,
        start_point: None,
    };
    check_keys(&design).map_err(err)?;
    Ok(design)
}

/// Writes every free key into the base tree at the bounds and the midpoint, at every
/// point, and parses the trees as run files: the run file's own message for a key it
/// does not take, or a value out of its range at a bound.
fn check_keys(d: &Design) -> Result<(), String> {
    let corners: [fn(&Free) -> f64; 3] = [|f| f.min, |f| f.max, |f| 0.5 * (f.min + f.max)];
    for (k, p) in d.points.iter().enumerate() {
        for (c, corner) in corners.iter().enumerate() {
            let x: Vec<f64> = d.free.iter().map(corner).collect();
            let tree = d.tree(&x, p)?;
            let what = ["min", "max", "midpoint"][c];
            let name = format!("the design at every parameter's {what}, point {}", k + 1);
            let file = runfile::run_file_from_value(Value::Table(tree), &name)
                .map_err(|e| e.to_string())?;
            if crate::model::scenarios::CccScenario::from_file(&file).is_none() {
                return Err(format!(
                    "base = '{}': not a converter run file (a design searches converters)",
                    d.base
                ));
            }
        }
    }
    Ok(())
}

/// Parses the design file `text` at `path`, its base relative to its directory.
pub fn read_design(text: &str, path: &std::path::Path) -> Result<Design, DesignError> {
    let dir = path.parent().unwrap_or(std::path::Path::new("."));
    parse_design(text, &path.display().to_string(), |b| load_base(b, dir))
}
