//! `host-sim sweep FILE --out-dir DIR`: a grid of variants of one run, on N threads,
//! with a progress bar, one table row per variant and heat-maps of a chosen outcome.
//!
//! The thesis's own recommendation (section 8.2) is to search the converter's design
//! space for the variant that stores the motor's energy fastest against a load; a sweep
//! file says which values of which keys to combine:
//!
//! ```toml
//! base = "ccc-s2"              # a built-in scenario, or a run file (path relative to this file)
//! [set]                        # fixed changes to the base, by dotted key of its run file
//! "run.t_end" = 0.3
//! [[axis]]                     # the grid: every combination of the axes' values
//! key = "converter.mass"
//! label = "oscillating mass, kg"
//! values = [20.0, 30.0, 40.0]
//! [[axis]]
//! key = "run.motor"
//! from = 8.0                   # or a range: `steps` values from `from` to `to`
//! to = 16.0
//! steps = 5
//! [[heatmap]]                  # a heat-map of a table column over two axes
//! metric = "first_breakaway"
//! x = "converter.mass"
//! y = "run.motor"
//! ```
//!
//! A variant is the base run file's TOML tree with the `[set]` keys and one value of
//! each axis written into it, parsed again by the run-file parser: a key or value the
//! run file does not take is refused with the run file's own message, for every variant
//! before anything runs. Keys are dotted paths into the tree; a number selects an
//! element of an array (`link.2.mass` is the third `[[link]]`'s mass).
//!
//! Determinism: variants are numbered in grid order (the first axis outermost, the
//! last fastest); each runs alone on its own model ([`super::pool::run_jobs`]) and the table
//! and pictures are written from the results in that order, after all have run. Only
//! the progress bar on `stderr` depends on the finishing order.

use super::batch::{self, cell};
use super::pool::run_jobs;
use crate::draw;
use crate::error::{RunError, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, HINT};
use crate::model::runfile::{self, set_dotted_in as set_dotted};
use crate::model::scenarios::{ScenarioId, Source};
use crate::options::{ProgressStyle, RunOptions, Steps, SweepOptions, MAX_THREADS};
use crate::run::interrupt;
use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use toml::{Table, Value};

mod progress;
mod results;

pub use progress::{progress_bar, redraw};
pub use results::*;

/// The most variants a sweep runs (a guard against a grid typo that would run for
/// days: 10,000 S2 variants of 0.3 s take about an hour on 2 cores).
pub const MAX_VARIANTS: usize = 10_000;

/// The most values a range axis takes.
pub const MAX_STEPS: usize = 1_000;

/// One axis of the grid: a dotted key of the run file and the values it takes.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The dotted key, e.g. `run.motor`.
    pub key: String,
    /// Its label in pictures (the key when none is given).
    pub label: String,
    /// The values, in the order given.
    pub values: Vec<Value>,
}

impl Axis {
    /// The values as numbers, or `None` if one of them is not a number (an axis of
    /// names, e.g. the drive direction, cannot be a heat-map's axis).
    pub fn numbers(&self) -> Option<Vec<f64>> {
        self.values.iter().map(number).collect()
    }
}

/// A number from a TOML integer or float.
pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The grid's variants: for each, the index of its value on every axis; the first
/// axis outermost, the last fastest. Errors when the product exceeds `max`.
pub fn grid(axes: &[Axis], max: usize) -> Result<Vec<Vec<usize>>, String> {
    let mut total: usize = 1;
    for a in axes {
        total = total
            .checked_mul(a.values.len())
            .filter(|t| *t <= max)
            .ok_or_else(|| {
                format!(
                    "the grid has more than {max} variants ({})",
                    axes.iter()
                        .map(|a| format!("{} × {}", a.values.len(), a.key))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?;
    }
    let mut out = Vec::with_capacity(total);
    for k in 0..total {
        let mut rest = k;
        let mut idx = vec![0; axes.len()];
        for (slot, a) in idx.iter_mut().zip(axes).rev() {
            *slot = rest % a.values.len();
            rest /= a.values.len();
        }
        out.push(idx);
    }
    Ok(out)
}

/// `steps` values from `from` to `to`, both included, evenly spaced; the ends are
/// exact (the k-th value is `from + (to - from)·k/(steps - 1)`, not a running sum, so
/// no rounding accumulates).
pub fn range(from: f64, to: f64, steps: usize) -> Result<Vec<f64>, String> {
    if !from.is_finite() || !to.is_finite() {
        return Err(format!("from = {from}, to = {to}: must be finite"));
    }
    if !(2..=MAX_STEPS).contains(&steps) {
        return Err(format!("steps = {steps}: must be 2..={MAX_STEPS}"));
    }
    let n = (steps - 1) as f64;
    Ok((0..steps)
        .map(|k| {
            if k == steps - 1 {
                to
            } else {
                from + (to - from) * (k as f64 / n)
            }
        })
        .collect())
}

/// A value as a table cell or a label: numbers in shortest round-trip form, strings
/// bare, anything else as TOML.
pub fn show(v: &Value) -> String {
    match v {
        Value::Float(x) => x.to_string(),
        Value::Integer(i) => i.to_string(),
        Value::String(s) => s.clone(),
        Value::Boolean(b) => b.to_string(),
        other => other.to_string(),
    }
}

/// A parsed sweep file.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The sweep file's name, for messages.
    pub origin: String,
    /// The base as written: a built-in scenario's name or a run file's path.
    pub base: String,
    /// The base's name in messages (the run file's path, or the built-in's name).
    pub base_origin: String,
    /// The base run file's TOML tree with the `[set]` keys written in.
    pub base_tree: Table,
    /// The grid's axes, in file order.
    pub axes: Vec<Axis>,
    /// The heat-maps to draw.
    pub heatmaps: Vec<HeatSpec>,
    /// Runs at a time from the file (`--threads` overrides it).
    pub threads: Option<usize>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    base: String,
    #[serde(default)]
    set: Table,
    #[serde(default)]
    axis: Vec<AxisFile>,
    #[serde(default)]
    heatmap: Vec<HeatFile>,
    threads: Option<usize>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisFile {
    key: String,
    label: Option<String>,
    values: Option<Vec<Value>>,
    from: Option<f64>,
    to: Option<f64>,
    steps: Option<usize>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct HeatFile {
    metric: String,
    x: Option<String>,
    y: Option<String>,
}

impl Sweep {
    /// The variants' run-file trees, in grid order, each with the index of its value on
    /// every axis. Errors name the variant and the key.
    pub fn variants(&self) -> Result<Vec<(Vec<usize>, Table)>, SweepError> {
        let grid = grid(&self.axes, MAX_VARIANTS).map_err(|e| self.err(e))?;
        let mut out = Vec::with_capacity(grid.len());
        for (k, idx) in grid.into_iter().enumerate() {
            let mut tree = self.base_tree.clone();
            for (a, &i) in self.axes.iter().zip(&idx) {
                let v = a.values.get(i).cloned().unwrap_or(Value::Boolean(false));
                set_dotted(&mut tree, &a.key, v)
                    .map_err(|e| self.err(format!("variant {k}: {e}")))?;
            }
            out.push((idx, tree));
        }
        Ok(out)
    }

    /// The variant's axis values as `key = value, ...`.
    pub fn describe(&self, idx: &[usize]) -> String {
        self.axes
            .iter()
            .zip(idx)
            .map(|(a, &i)| {
                format!(
                    "{} = {}",
                    a.key,
                    a.values.get(i).map(show).unwrap_or_default()
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn err(&self, msg: impl fmt::Display) -> SweepError {
        SweepError(format!("{}: {msg}", self.origin))
    }
}

/// Parses a sweep file. `load_base` turns the file's `base` into the base run file's
/// TOML tree and its name for messages (a built-in's embedded file, or a file read from
/// disk relative to the sweep file). Everything is checked here: the keys of `[set]`
/// and of the axes are written into the base tree (the run-file parser checks the
/// variants themselves), the axes have values, the heat-maps name a metric and
/// numeric axes.
pub fn parse_sweep(
    text: &str,
    origin: &str,
    load_base: impl Fn(&str) -> Result<(Table, String), String>,
) -> Result<Sweep, SweepError> {
    let err = |m: String| SweepError(format!("{origin}: {m}"));
    let file: SweepFile = toml::from_str(text)
        .map_err(|e| SweepError(runfile::toml_error(&e, text, origin).to_string()))?;
    let (mut base_tree, base_origin) =
        load_base(&file.base).map_err(|e| err(format!("base = '{}': {e}", file.base)))?;
    for (key, value) in &file.set {
        set_dotted(&mut base_tree, key, value.clone()).map_err(|e| err(format!("[set] {e}")))?;
    }
    if let Some(t) = file.threads {
        if !(1..=MAX_THREADS).contains(&t) {
            return Err(err(format!("threads = {t}: must be 1..={}", MAX_THREADS)));
        }
    }
    let mut axes: Vec<Axis> = Vec::with_capacity(file.axis.len());
    for (k, a) in file.axis.into_iter().enumerate() {
        let at = format!("axis {} ('{}')", k + 1, a.key);
        if axes.iter().any(|b| b.key == a.key) {
            return Err(err(format!("{at}: the key is already an axis")));
        }
        if a.key.trim().is_empty() {
            return Err(err(format!("axis {}: key: empty", k + 1)));
        }
        let values = match (a.values, a.from, a.to, a.steps) {
            (Some(v), None, None, None) if !v.is_empty() => v,
            (Some(_), None, None, None) => return Err(err(format!("{at}: values: empty"))),
            (None, Some(from), Some(to), Some(steps)) => range(from, to, steps)
                .map_err(|e| err(format!("{at}: {e}")))?
                .into_iter()
                .map(Value::Float)
                .collect(),
            _ => {
                return Err(err(format!(
                    "{at}: give either values = [...] or all of from, to and steps"
                )))
            }
        };
        axes.push(Axis {
            label: a.label.unwrap_or_else(|| a.key.clone()),
            key: a.key,
            values,
        });
    }
    let numeric: Vec<usize> = (0..axes.len())
        .filter(|&k| axes[k].numbers().is_some())
        .collect();
    let find = |name: &str, what: &str| -> Result<usize, SweepError> {
        let k = axes
            .iter()
            .position(|a| a.key == name)
            .ok_or_else(|| err(format!("heatmap {what} = '{name}': not an axis")))?;
        if axes[k].numbers().is_none() {
            return Err(err(format!(
                "heatmap {what} = '{name}': the axis has values that are not numbers"
            )));
        }
        Ok(k)
    };
    let mut heatmaps = Vec::new();
    for h in &file.heatmap {
        let metric = Metric::from_name(&h.metric).ok_or_else(|| {
            err(format!(
                "heatmap metric = '{}': unknown (known: {})",
                h.metric,
                Metric::names()
            ))
        })?;
        let x = match &h.x {
            Some(x) => find(x, "x")?,
            None => *numeric
                .first()
                .ok_or_else(|| err("heatmap: no axis of numbers to draw".to_string()))?,
        };
        let y = match &h.y {
            Some(y) => Some(find(y, "y")?),
            None => numeric.iter().copied().find(|&k| k != x),
        };
        if y == Some(x) {
            return Err(err(format!(
                "heatmap: x and y are the same axis '{}'",
                axes[x].key
            )));
        }
        heatmaps.push(HeatSpec { metric, x, y });
    }
    if file.heatmap.is_empty() {
        // The default: the first breakaway over the first two numeric axes.
        if let Some(&x) = numeric.first() {
            heatmaps.push(HeatSpec {
                metric: Metric::FirstBreakaway,
                x,
                y: numeric.get(1).copied(),
            });
        }
    }
    let sweep = Sweep {
        origin: origin.to_string(),
        base: file.base,
        base_origin,
        base_tree,
        axes,
        heatmaps,
        threads: file.threads,
    };
    // Every key must be writable into the base tree (the grid's size is checked too).
    sweep.variants()?;
    Ok(sweep)
}

/// The base run file's tree: a built-in scenario's embedded file, or a run file at a
/// path relative to the sweep file's directory `dir`.
/// The base of a sweep file in `dir`: a built-in scenario's embedded run file, or a run
/// file's path relative to `dir`; its TOML tree and its name for messages.
pub fn load_base(base: &str, dir: &Path) -> Result<(Table, String), String> {
    let (text, origin) = match ScenarioId::from_name(base) {
        Some(id) => (id.file_text().to_string(), id.name().to_string()),
        None => {
            let path = dir.join(base);
            let origin = path.display().to_string();
            let text = fs::read_to_string(&path).map_err(|e| {
                format!(
                    "cannot read {origin}: {e} (a base is a built-in scenario, {}, or a run file)",
                    ScenarioId::names()
                )
            })?;
            (text, origin)
        }
    };
    match runfile::parse_value(&text, &origin).map_err(|e| e.to_string())? {
        Value::Table(t) => Ok((t, origin)),
        _ => Err(format!("{origin}: not a table")),
    }
}

/// A variant ready to run.
pub struct Job {
    /// The axis indices.
    pub idx: Vec<usize>,
    /// Its run options (from its run file; quiet).
    pub opts: RunOptions,
}

/// Runs variant `k` of `total`: as `host-sim batch` runs a line, its files into `keep`
/// when given (named as the batch names them), else nothing written; a run not started
/// because SIGINT or SIGTERM came first is its row "not run". The one run of a variant,
/// on host-sim's thread pool or on a Dask worker (the Python package).
pub fn run_job(job: &Job, k: usize, total: usize, keep: Option<&Path>) -> Outcome {
    if interrupt::requested() {
        return Outcome::from(&batch::Outcome::of(&job.opts, Err(RunError::NotRun)));
    }
    let o = match keep {
        Some(out) => {
            let src = &job.opts.scenario;
            batch::run_one(&job.opts, &out.join(batch::file_name(k, total, src)))
        }
        None => batch::run_quiet(&job.opts),
    };
    Outcome::from(&o)
}

/// The ends a sweep's row can have, as its `end` column writes them.
pub const ENDS: [&str; 6] = [
    "completed",
    "singularity",
    "failed",
    "error",
    "interrupted",
    "not run",
];

/// Writes a sweep's files into `out`: `sweep.csv` ([`write_table`]) and every heat-map
/// as SVG and PNG, from the variants' outcomes in grid order; returns the table's path
/// and the heat-maps' SVG paths. Errors: the file that could not be written, and why.
pub fn write_outputs(
    out: &Path,
    sweep: &Sweep,
    variants: &[Vec<usize>],
    runs: &[Outcome],
) -> Result<(PathBuf, Vec<PathBuf>), String> {
    let table = out.join("sweep.csv");
    let written = File::create(&table).and_then(|f| {
        let mut w = BufWriter::new(f);
        write_table(&mut w, sweep, variants, runs)?;
        w.flush()
    });
    if let Err(e) = written {
        return Err(format!("cannot write {}: {e}", table.display()));
    }
    let mut pictures = Vec::new();
    for (n, spec) in sweep.heatmaps.iter().enumerate() {
        let grids = heat_grids(sweep, spec, variants, runs);
        let several = grids.len() > 1;
        for (k, g) in grids.iter().enumerate() {
            let mut stem = format!("heatmap{}-{}", n + 1, spec.metric.name());
            if several {
                stem.push_str(&format!("-{}", k + 1));
            }
            let figure = draw::heatmap(&heat_map(sweep, spec, g));
            for ext in ["svg", "png"] {
                let path = out.join(format!("{stem}.{ext}"));
                figure.write(&path).map_err(|e| e.to_string())?;
            }
            pictures.push(out.join(format!("{stem}.svg")));
        }
    }
    Ok((table, pictures))
}

/// Runs `host-sim sweep` with `opts`: checks the sweep file and every variant before
/// anything runs (a bad file or variant: exit code 2), runs the variants on N threads
/// with a progress display on `stderr`, writes `sweep.csv` and the heat-maps (SVG and
/// PNG) into `out_dir`, reports the variants that failed on `stderr` and a summary on
/// `stdout` (unless quiet). A variant whose run fails is a row of the table (its `end`
/// says how), not a failure of the sweep: exit code 0 when the files are written, 1
/// when a file cannot be written.
pub fn execute(opts: &SweepOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    let origin = opts.file.display().to_string();
    let text = match fs::read_to_string(&opts.file) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: cannot read sweep file {origin}: {e}");
            return EXIT_FAILURE;
        }
    };
    let dir = opts.file.parent().unwrap_or(Path::new("."));
    let sweep = match parse_sweep(&text, &origin, |b| load_base(b, dir)) {
        Ok(s) => s,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}\nnothing was run; {HINT}");
            return EXIT_USAGE;
        }
    };
    let jobs = match prepare(&sweep) {
        Ok(j) => j,
        Err(bad) => {
            for b in bad.iter().take(5) {
                let _ = writeln!(stderr, "host-sim: {b}");
            }
            if bad.len() > 5 {
                let _ = writeln!(
                    stderr,
                    "host-sim: ... and {} more bad variants",
                    bad.len() - 5
                );
            }
            let _ = writeln!(stderr, "nothing was run; {HINT}");
            return EXIT_USAGE;
        }
    };
    let out = &opts.out_dir;
    if let Err(e) = fs::create_dir_all(out) {
        let _ = writeln!(stderr, "host-sim: cannot create {}: {e}", out.display());
        return EXIT_FAILURE;
    }
    let threads = opts.threads.or(sweep.threads).unwrap_or(2);
    let total = jobs.len();
    let style = match opts.progress {
        _ if opts.quiet => ProgressStyle::None,
        ProgressStyle::Auto if io::stderr().is_terminal() => ProgressStyle::Bar,
        ProgressStyle::Auto => ProgressStyle::Lines,
        s => s,
    };
    let start = Instant::now();
    let mut shown = 0;
    let runs = run_jobs(
        &jobs,
        threads,
        |k, job: &Job| {
            // SIGINT or SIGTERM: the runs under way finish as interrupted; the others do
            // not start.
            run_job(job, k, total, opts.keep_runs.then_some(out.as_path()))
        },
        |p, _| {
            let line = progress_bar(p.done, p.total, start.elapsed());
            match style {
                ProgressStyle::Bar => {
                    let _ = redraw(stderr, &line, p.done == p.total);
                }
                ProgressStyle::Lines if 10 * p.done / p.total > shown || p.done == p.total => {
                    shown = 10 * p.done / p.total;
                    let _ = writeln!(stderr, "{line}");
                }
                _ => {}
            }
        },
    );
    let wall = start.elapsed();
    let variants: Vec<Vec<usize>> = jobs.into_iter().map(|j| j.idx).collect();
    let (table, pictures) = match write_outputs(out, &sweep, &variants, &runs) {
        Ok(files) => files,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: {e}");
            return EXIT_FAILURE;
        }
    };
    let stopped = interrupt::requested();
    let failed: Vec<usize> = (0..runs.len())
        .filter(|&k| runs[k].exit != EXIT_OK && !(stopped && runs[k].exit == EXIT_INTERRUPTED))
        .collect();
    for &k in &failed {
        let _ = writeln!(
            stderr,
            "host-sim: variant {k} ({}): {}",
            sweep.describe(&variants[k]),
            runs[k].message.as_deref().unwrap_or(runs[k].end)
        );
    }
    if !opts.quiet {
        let _ = report(
            stdout,
            &sweep,
            &variants,
            &runs,
            threads.clamp(1, total.max(1)),
            wall,
            &table,
            &pictures,
        );
        if stopped {
            let _ = writeln!(
                stdout,
                "sweep     interrupted (SIGINT or SIGTERM): the table's end column says which runs were interrupted or not run"
            );
        }
    }
    if stopped {
        EXIT_INTERRUPTED
    } else {
        EXIT_OK
    }
}

/// Every variant's run options, from its run file; errors: every bad variant, named by
/// its number and axis values, with the run file's message.
pub fn prepare(sweep: &Sweep) -> Result<Vec<Job>, Vec<String>> {
    let variants = sweep.variants().map_err(|e| vec![e.to_string()])?;
    let (mut jobs, mut bad) = (Vec::new(), Vec::new());
    for (k, (idx, tree)) in variants.into_iter().enumerate() {
        let name = format!("{} variant {k} ({})", sweep.origin, sweep.describe(&idx));
        let file = match runfile::run_file_from_value(Value::Table(tree), &name) {
            Ok(f) => f,
            Err(e) => {
                bad.push(e.to_string());
                continue;
            }
        };
        let mut opts = RunOptions::from_source(Source::from_file(format!("v{k}"), file));
        opts.quiet = true;
        match Steps::check(&opts) {
            Ok(_) => jobs.push(Job { idx, opts }),
            Err(e) => bad.push(format!("{name}: {e}")),
        }
    }
    if bad.is_empty() {
        Ok(jobs)
    } else {
        Err(bad)
    }
}

/// The heat-map of one grid: the axes' labels, the metric's description, and the base
/// and the other axes' values in the title.
fn heat_map(sweep: &Sweep, spec: &HeatSpec, g: &HeatGrid) -> draw::HeatMap {
    let label = |k: Option<usize>| {
        k.and_then(|k| sweep.axes.get(k))
            .map_or_else(String::new, |a| a.label.clone())
    };
    let mut title = format!("{} ({})", spec.metric.describe(), sweep.base);
    if !g.fixed.is_empty() {
        title.push_str(&format!(", {}", g.fixed));
    }
    draw::HeatMap {
        title,
        x_label: label(Some(spec.x)),
        y_label: label(spec.y),
        z_label: spec.metric.describe().to_string(),
        x: g.x.clone(),
        y: g.y.clone(),
        z: g.z.clone(),
    }
}

/// The closing summary: counts, files, and the lowest and highest value of each
/// heat-map's metric with the variant that gave it.
#[allow(clippy::too_many_arguments)]
fn report(
    w: &mut dyn Write,
    sweep: &Sweep,
    variants: &[Vec<usize>],
    runs: &[Outcome],
    threads: usize,
    wall: Duration,
    table: &Path,
    pictures: &[PathBuf],
) -> io::Result<()> {
    let total = runs.len();
    // How they ended, in batch.csv's words; "0 completed" is said, other zeros not.
    let ends = ENDS
        .iter()
        .filter_map(|&end| {
            let n = runs.iter().filter(|o| o.end == end).count();
            let what = match end {
                "singularity" => "at a singularity of the mechanism",
                other => other,
            };
            (n > 0 || end == "completed").then(|| format!("{n} {what}"))
        })
        .collect::<Vec<_>>()
        .join(", ");
    let axes = sweep
        .axes
        .iter()
        .map(|a| format!("{} {}", a.values.len(), a.key))
        .collect::<Vec<_>>()
        .join(" × ");
    writeln!(
        w,
        "sweep     {total} variants of {} ({axes}) on {threads} thread{} in {:.3} s: {ends}",
        sweep.base,
        if threads == 1 { "" } else { "s" },
        wall.as_secs_f64(),
    )?;
    writeln!(w, "table     {}", table.display())?;
    for p in pictures {
        writeln!(w, "heatmap   {} (and .png)", p.display())?;
    }
    let mut metrics: Vec<Metric> = Vec::new();
    for h in &sweep.heatmaps {
        if !metrics.contains(&h.metric) {
            metrics.push(h.metric);
        }
    }
    for m in metrics {
        let values = runs
            .iter()
            .enumerate()
            .filter_map(|(k, o)| Some((k, o.get(m)?)));
        // The first of equal values wins: grid order, so deterministic.
        let lo = values
            .clone()
            .fold(None, |b: Option<(usize, f64)>, (k, v)| match b {
                Some((_, bv)) if bv <= v => b,
                _ => Some((k, v)),
            });
        let hi = values.fold(None, |b: Option<(usize, f64)>, (k, v)| match b {
            Some((_, bv)) if bv >= v => b,
            _ => Some((k, v)),
        });
        match (lo, hi) {
            (Some((kl, vl)), Some((kh, vh))) => writeln!(
                w,
                "{}: lowest {} at {}; highest {} at {}",
                m.describe(),
                draw::heatmap::short(vl),
                sweep.describe(&variants[kl]),
                draw::heatmap::short(vh),
                sweep.describe(&variants[kh])
            )?,
            _ => writeln!(w, "{}: no variant gave a value", m.describe())?,
        }
    }
    w.flush()
}

/// A sweep file error: the file and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SweepError(pub String);

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SweepError {}

#[cfg(test)]
mod tests;
