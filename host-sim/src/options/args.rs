//! The command-line arguments of `run`, `batch`, `sweep`, `plot` and `analyze` (clap's
//! derive API) and their checks, which turn them into the options of [`super`]. The
//! values are taken as text and checked here, so that an error names the option and
//! says what it expects in this crate's words (`--h: -1 is not positive (a positive
//! number of seconds expected)`); clap refuses unknown, misspelled (with a suggestion)
//! and repeated options.

use super::{
    AnimFormat, BatchOptions, DesignOptions, FmuOptions, IdentifyOptions, ObserverTuning, Output,
    PlotOptions, ProgressStyle, ReplayOptions, RunOptions, SweepOptions, DEFAULT_FPS, DEFAULT_SLOW,
    FPS_RANGE, MAX_THREADS, SLOW_RANGE,
};
use crate::error::{usage_err, Sci, UsageError};
use crate::model::bench::{BenchLog, ClutchLog};
use crate::model::identifiable::{self, DEFAULT_FIT, DEFAULT_MAX_ITERS, MAX_ITERS};
use crate::model::runfile::spreading_refused;
use crate::model::runfile::MAX_CONVERTER_LOAD;
use crate::model::scenarios::{ScenarioId, Source};
use clap::{Args, Parser};
use std::path::PathBuf;
use std::sync::Arc;

/// The help's heading of the pictures' options.
const PICTURES: &str = "Pictures";
/// The help's heading of the converter's options.
const CONVERTER: &str = "Converter scenarios";

/// The arguments of `host-sim run` (and of a batch file's line).
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct RunArgs {
    /// A built-in scenario (slider-crank, five-bar, ccc-s1, ccc-s2) or a run file
    #[arg(value_name = "SCENARIO|FILE.toml")]
    pub scenario: String,
    /// Write the CSV to FILE, the summary to stdout; '-' or no --out: the CSV to stdout,
    /// the summary to stderr
    #[arg(long, value_name = "FILE|-")]
    pub out: Option<String>,
    /// The step and the horizon.
    #[command(flatten)]
    pub time: TimeArgs,
    /// Write every N-th step (default: the file's, else 1); the row at t = 0 is always
    /// written
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub every: Option<String>,
    /// Run the core in single precision (default: the file's f32 key, else f64)
    #[arg(long, conflicts_with = "f64")]
    pub f32: bool,
    /// Run the core in double precision
    #[arg(long)]
    pub f64: bool,
    /// No summary
    #[arg(long)]
    pub quiet: bool,
    /// Draw the run's plots into DIR (created if missing), each as .svg and .png
    /// (converter: crank, motor_torque, reactions, speeds, clutch_torques, mode, energy;
    /// mechanisms: coordinates, torques, reactions; the CSV's rows: --every thins them)
    #[arg(long, value_name = "DIR", help_heading = PICTURES)]
    pub plot: Option<String>,
    /// Animate the mechanism: FILE.svg (animated SVG, plays in a browser) or FILE.gif;
    /// may be given twice (one .svg, one .gif)
    #[arg(long, value_name = "FILE", help_heading = PICTURES)]
    pub animate: Vec<String>,
    /// Frames a second of the animation, 1..=50 (default 25)
    #[arg(long, value_name = "N", requires = "animate", help_heading = PICTURES)]
    pub fps: Option<String>,
    /// Slow motion: the animation lasts X times the simulated time, 0.01..=1000 (default
    /// 1); frames are taken every 1/(fps·X) s of simulated time, at most 5000 of them
    #[arg(long, value_name = "X", requires = "animate", help_heading = PICTURES)]
    pub slow: Option<String>,
    /// The converter's motor, load and direction.
    #[command(flatten)]
    pub converter: ConverterArgs,
    /// Converter scenarios: spread each event's work over the steps after it, as a
    /// firmware twin keeping its worst step within the loop's period does (default: the
    /// run file's run.spread_events, else off); the twin's time then lags the clock by
    /// a few steps after each event
    #[arg(long, help_heading = CONVERTER)]
    pub spread_events: bool,
}

/// The step and the horizon, as `run` and `fmu` take them.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct TimeArgs {
    /// Step size (default: the scenario's own; the FMU's parameter h); also spelled
    /// --step (-h is help)
    #[arg(
        long,
        visible_alias = "step",
        value_name = "SECONDS",
        allow_negative_numbers = true
    )]
    pub h: Option<String>,
    /// Simulated time (default: the scenario's own; the FMU's default experiment's stop
    /// time); runs ceil(t_end / h) fixed steps
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub t_end: Option<String>,
}

/// The converter scenarios' options, as `run` and `fmu` take them (for the FMU, the
/// start values of its inputs and of its parameter ccw).
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct ConverterArgs {
    /// Constant motor torque on the crank, CCW positive (default: the scenario's, 12)
    #[arg(long, value_name = "N·M", allow_negative_numbers = true, help_heading = CONVERTER)]
    pub motor: Option<String>,
    /// ccc-s2: load torque T_r >= 0 on the shaft (default 800)
    #[arg(long, value_name = "N·M", allow_negative_numbers = true, help_heading = CONVERTER)]
    pub load: Option<String>,
    /// ccc-s2: the shaft turns counter-clockwise (SPEC 3's CCW variant; default
    /// clockwise); ccc-s1 runs in free mode, without clutches: no --load, no --ccw
    #[arg(long, help_heading = CONVERTER)]
    pub ccw: bool,
}

impl RunArgs {
    /// The run's options: every value checked, the scenario read (a run file is parsed
    /// and validated here, so that nothing runs half-configured and a batch checks its
    /// files up front), the run file's `every` and `f32` unless the arguments give them.
    pub fn options(&self) -> Result<RunOptions, UsageError> {
        let scenario = parse_source("run", &self.scenario)?;
        let out = self.out.as_deref().map_or(Ok(Output::Stdout), parse_out)?;
        let seconds =
            |name, v: &Option<String>| v.as_deref().map(|v| parse_seconds(name, v)).transpose();
        let h = seconds("--h", &self.time.h)?;
        let t_end = seconds("--t-end", &self.time.t_end)?;
        let every = self.every.as_deref().map(parse_every).transpose()?;
        let converter = &self.converter;
        let load = converter.load.as_deref().map(parse_load).transpose()?;
        let motor = converter
            .motor
            .as_deref()
            .map(|v| parse_torque("--motor", v))
            .transpose()?;
        let plot = self
            .plot
            .as_deref()
            .map(|v| parse_path("--plot", v))
            .transpose()?;
        let mut animate = Vec::new();
        for a in &self.animate {
            let path = parse_animation(a, &animate)?;
            animate.push(path);
        }
        let fps = self.fps.as_deref().map(parse_fps).transpose()?;
        let slow = self.slow.as_deref().map(parse_slow).transpose()?;
        check_converter_options(
            &scenario,
            converter.ccw,
            load.is_some(),
            motor.is_some(),
            self.spread_events,
        )?;
        // The run file's own output settings, unless the arguments give them.
        let file = scenario.run_file().ok();
        let every = every.unwrap_or_else(|| file.as_ref().map_or(1, |f| f.run.every));
        let single = match (self.f32, self.f64) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        };
        let f32 = single.unwrap_or_else(|| file.is_some_and(|f| f.run.f32));
        Ok(RunOptions {
            scenario,
            out,
            h,
            t_end,
            every,
            f32,
            quiet: self.quiet,
            ccw: converter.ccw,
            load,
            motor,
            spread_events: self.spread_events,
            plot,
            animate,
            fps: fps.unwrap_or(DEFAULT_FPS),
            slow: slow.unwrap_or(DEFAULT_SLOW),
        })
    }
}

/// The arguments of `host-sim fmu`: the converter (a scenario or run file, with the
/// converter options of `run`) whose twin the FMU is, and where it goes.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct FmuArgs {
    /// The converter: a built-in scenario (ccc-s2, ccc-s1) or a converter run file;
    /// its values are the FMU's start values
    #[arg(value_name = "SCENARIO|FILE.toml", default_value = "ccc-s2")]
    pub scenario: String,
    /// Write the FMU (a zip: modelDescription.xml, the binary, resources/start.txt) to
    /// FILE
    #[arg(long, value_name = "FILE")]
    pub out: String,
    /// The twin's fixed step h and the default experiment's stop time.
    #[command(flatten)]
    pub time: TimeArgs,
    /// The start values of the inputs motor_torque and load_torque and of the
    /// parameter ccw.
    #[command(flatten)]
    pub converter: ConverterArgs,
    /// The FMU's binary, the structomat-fmu cdylib (default: libstructomat_fmu.so next
    /// to this host-sim executable, as `cargo build --release -p structomat-fmu -p
    /// host-sim` leaves it)
    #[arg(long, value_name = "FILE")]
    pub lib: Option<String>,
}

impl FmuArgs {
    /// The FMU's options: the converter's as `run` checks them (the same messages),
    /// the output and the binary's path.
    pub fn options(&self) -> Result<FmuOptions, UsageError> {
        let run = RunArgs {
            scenario: self.scenario.clone(),
            time: self.time.clone(),
            converter: self.converter.clone(),
            quiet: true,
            ..RunArgs::default()
        }
        .options()?;
        match run.scenario.converter() {
            None => {
                return Err(usage_err(format!(
                    "fmu: {} is not a converter: the FMU is the converter's twin (ccc-s1, ccc-s2 or a converter run file)",
                    run.scenario.name()
                )))
            }
            Some(c) if c.converter.spread_events => {
                return Err(usage_err(format!(
                    "fmu: {}: run.spread_events = true: an FMU's outputs are the converter's at each communication point, and a twin that spreads its events lags the clock after each (remove the key for the FMU)",
                    run.scenario.name()
                )))
            }
            Some(_) => {}
        }
        let out = parse_path("--out", &self.out)?;
        let lib = self
            .lib
            .as_deref()
            .map(|v| parse_path("--lib", v))
            .transpose()?;
        Ok(FmuOptions { run, out, lib })
    }
}

/// A batch file's line: the arguments of `host-sim run`, without the program name.
#[derive(Parser, Debug)]
#[command(name = "run", no_binary_name = true, disable_version_flag = true)]
struct RunLine {
    #[command(flatten)]
    run: RunArgs,
}

/// Parses the arguments of one run (a batch file's line) as `host-sim run` does.
/// Errors: the message `host-sim run` gives, on one line.
pub fn parse_run_line(args: &[&str]) -> Result<RunOptions, String> {
    match RunLine::try_parse_from(args) {
        Ok(line) => line.run.options().map_err(|e| e.0),
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelp => {
            Err("help is not a run".to_string())
        }
        Err(e) => Err(one_line(&e)),
    }
}

/// A clap error on one line: its message and tips, without the usage and the pointer
/// to `--help` (`unexpected argument '--tt-end' found; tip: a similar argument exists:
/// '--t-end'`).
pub fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    text.lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .map(|l| l.strip_prefix("error: ").unwrap_or(l))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The arguments that `host-sim batch` and `host-sim sweep` share: where the files go,
/// how many runs at a time, quiet.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct JobArgs {
    /// Where the files go (created if missing; files of the same names are replaced)
    #[arg(long, value_name = "DIR")]
    pub out_dir: String,
    /// Runs at a time, on N threads (default 2, or a sweep file's threads); the files
    /// are the same for any N
    #[arg(long, value_name = "N")]
    pub threads: Option<String>,
    /// No progress, no closing summary
    #[arg(long)]
    pub quiet: bool,
}

impl JobArgs {
    fn out_dir(&self) -> Result<PathBuf, UsageError> {
        parse_path("--out-dir", &self.out_dir)
    }

    fn threads(&self) -> Result<Option<usize>, UsageError> {
        self.threads.as_deref().map(parse_threads).transpose()
    }
}

/// The arguments of `host-sim batch`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct BatchArgs {
    /// The batch file: one run a line, written like the arguments of run
    #[arg(value_name = "FILE")]
    pub file: String,
    /// The output and the threads.
    #[command(flatten)]
    pub jobs: JobArgs,
}

impl BatchArgs {
    /// The checked options.
    pub fn options(&self) -> Result<BatchOptions, UsageError> {
        Ok(BatchOptions {
            file: parse_path("batch", &self.file)?,
            out_dir: self.jobs.out_dir()?,
            threads: self.jobs.threads()?.unwrap_or(2),
            quiet: self.jobs.quiet,
        })
    }
}

/// The arguments of `host-sim sweep`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct SweepArgs {
    /// The sweep file (TOML): a base run, fixed changes, the axes, the heat-maps
    #[arg(value_name = "FILE")]
    pub file: String,
    /// The output and the threads.
    #[command(flatten)]
    pub jobs: JobArgs,
    /// bar (redrawn in place), lines (one per tenth) or none; default: bar on a
    /// terminal, else lines
    #[arg(long, value_name = "STYLE", value_parser = ["bar", "lines", "none"])]
    pub progress: Option<String>,
    /// Also write each variant's CSV and logs, named as by batch
    #[arg(long)]
    pub keep_runs: bool,
}

impl SweepArgs {
    /// The checked options.
    pub fn options(&self) -> Result<SweepOptions, UsageError> {
        Ok(SweepOptions {
            file: parse_path("sweep", &self.file)?,
            out_dir: self.jobs.out_dir()?,
            threads: self.jobs.threads()?,
            progress: match self.progress.as_deref() {
                Some("bar") => ProgressStyle::Bar,
                Some("lines") => ProgressStyle::Lines,
                Some(_) => ProgressStyle::None,
                None => ProgressStyle::Auto,
            },
            keep_runs: self.keep_runs,
            quiet: self.jobs.quiet,
        })
    }
}

/// The arguments of `host-sim design`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct DesignArgs {
    /// The design file (TOML): a base converter, the free parameters and their bounds,
    /// the operating points, the objective, the constraints, the search
    #[arg(value_name = "FILE")]
    pub file: String,
    /// The output and the threads.
    #[command(flatten)]
    pub jobs: JobArgs,
    /// Do not run the winner (its CSV, plots, animation and the check at h/2)
    #[arg(long)]
    pub no_winner: bool,
}

impl DesignArgs {
    /// The checked options.
    pub fn options(&self) -> Result<DesignOptions, UsageError> {
        Ok(DesignOptions {
            file: parse_path("design", &self.file)?,
            out_dir: self.jobs.out_dir()?,
            threads: self.jobs.threads()?,
            no_winner: self.no_winner,
            quiet: self.jobs.quiet,
        })
    }
}

/// The arguments of `host-sim plot`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct PlotArgs {
    /// A CSV that host-sim run wrote
    #[arg(value_name = "RUN.csv")]
    pub csv: String,
    /// Where the plots go (created if missing)
    #[arg(long, value_name = "DIR")]
    pub out_dir: String,
}

impl PlotArgs {
    /// The checked options.
    pub fn options(&self) -> Result<PlotOptions, UsageError> {
        Ok(PlotOptions {
            csv: parse_path("plot", &self.csv)?,
            out_dir: parse_path("--out-dir", &self.out_dir)?,
        })
    }
}

/// The arguments of `host-sim replay`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct ReplayArgs {
    /// The bench log (CSV: t, motor_torque, load_torque, crank_counts, shaft_counts)
    #[arg(value_name = "LOG.csv")]
    pub log: String,
    /// The converter: a converter run file as run takes (its parameters, drive and
    /// initial state; the log gives the motor, the load, h and t_end); default ccc-s2,
    /// SPEC's machine
    #[arg(long, value_name = "PARAMS.toml")]
    pub params: Option<String>,
    /// The machine's clutch events (CSV: t, event, from, to), to pair with the twin's
    #[arg(long, value_name = "CLUTCH.csv")]
    pub clutch_log: Option<String>,
    /// The state CSV with the encoder residuals; the event and switch logs go next to it
    #[arg(long, value_name = "RUN.csv")]
    pub out: String,
    /// Correct the twin from the log's encoders every step (the core's observer), tuned
    /// for a twin with the drawing's nominal parameters (nominal, the default) or with
    /// parameters identified from the machine's logs (identified)
    #[arg(
        long,
        value_enum,
        value_name = "TUNING",
        num_args = 0..=1,
        default_missing_value = "nominal"
    )]
    pub observer: Option<ObserverTuning>,
    /// No summary
    #[arg(long)]
    pub quiet: bool,
}

impl ReplayArgs {
    /// The checked options: the logs read and validated, the run file read (it must
    /// describe the converter).
    pub fn options(&self) -> Result<ReplayOptions, UsageError> {
        let log = parse_bench_log("replay", &self.log)?;
        let params = match self.params.as_deref() {
            None => Source::Builtin(ScenarioId::CccS2),
            Some(p) => parse_source("--params", p)?,
        };
        if !params.is_converter() {
            return Err(usage_err(format!(
                "--params: {} describes a mechanism, not the converter (a converter run \
                 file, as ccc-s2's, expected)",
                params.name()
            )));
        }
        not_spreading(&params, "replay")?;
        let clutch = parse_clutch_log(self.clutch_log.as_deref())?;
        Ok(ReplayOptions {
            log,
            params,
            clutch,
            out: parse_path("--out", &self.out)?,
            observer: self.observer,
            quiet: self.quiet,
        })
    }
}

/// The arguments of `host-sim identify`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct IdentifyArgs {
    /// The bench log (CSV: t, motor_torque, load_torque, crank_counts, shaft_counts)
    #[arg(value_name = "LOG.csv")]
    pub log: String,
    /// The machine's clutch events (CSV: t, event, from, to): their times are fitted too
    #[arg(long, value_name = "CLUTCH.csv")]
    pub clutch_log: Option<String>,
    /// The converter run file to start from (its values are the base of the bounds);
    /// default ccc-s2, SPEC's machine
    #[arg(long, value_name = "BASE.toml")]
    pub params: Option<String>,
    /// The parameters to fit, their run-file keys separated by commas, in stages
    /// separated by semicolons (the first stage's searched first, then with the next
    /// stage's from their best; default converter.mass, converter.link.1.mass,
    /// converter.link.2.mass, converter.friction.viscous.A,
    /// converter.friction.viscous.B, converter.friction.viscous.E; then
    /// converter.friction.viscous.F)
    #[arg(long, value_name = "KEYS")]
    pub fit: Option<String>,
    /// Nelder-Mead's iterations at most, of each of its searches (two from each start
    /// of the first horizon, two over the whole log; default 600)
    #[arg(long, value_name = "N")]
    pub max_iters: Option<String>,
    /// The identified converter run file
    #[arg(long, value_name = "PARAMS.toml")]
    pub out: String,
    /// No progress lines and no summary
    #[arg(long)]
    pub quiet: bool,
}

impl IdentifyArgs {
    /// The checked options: the logs read and validated, the base run file read (it
    /// must describe the converter with its clutches), the keys known.
    pub fn options(&self) -> Result<IdentifyOptions, UsageError> {
        let log = parse_bench_log("identify", &self.log)?;
        let (params, base_text) = match self.params.as_deref() {
            None => (
                Source::Builtin(ScenarioId::CccS2),
                ScenarioId::CccS2.file_text().to_string(),
            ),
            Some(p) => {
                let source = parse_source("--params", p)?;
                let text = match source.builtin() {
                    Some(id) => id.file_text().to_string(),
                    None => std::fs::read_to_string(p)
                        .map_err(|e| usage_err(format!("--params: {p}: cannot read: {e}")))?,
                };
                (source, text)
            }
        };
        if !params.is_converter() || params.is_free_converter() {
            return Err(usage_err(format!(
                "--params: {} is not the converter with its clutches (a converter run \
                 file, as ccc-s2's, expected)",
                params.name()
            )));
        }
        not_spreading(&params, "identify")?;
        let clutch = parse_clutch_log(self.clutch_log.as_deref())?;
        let (fit, stages) = identifiable::parse_stages(self.fit.as_deref().unwrap_or(DEFAULT_FIT))
            .map_err(|e| usage_err(format!("--fit: {e}")))?;
        let max_iters = match self.max_iters.as_deref() {
            None => DEFAULT_MAX_ITERS,
            Some(v) => match v.parse::<u64>() {
                Ok(n) if (1..=MAX_ITERS).contains(&n) => n,
                _ => {
                    return Err(usage_err(format!(
                        "--max-iters: '{v}' is not a whole number from 1 to {MAX_ITERS}"
                    )))
                }
            },
        };
        Ok(IdentifyOptions {
            log,
            clutch,
            params,
            base_text,
            fit,
            stages,
            max_iters,
            out: parse_path("--out", &self.out)?,
            quiet: self.quiet,
        })
    }
}

/// The bench log argument of `command` (`replay`, `identify`): its path and its
/// contents, read and validated (a missing column or a gap refused, named).
fn parse_bench_log(command: &str, v: &str) -> Result<(PathBuf, Arc<BenchLog>), UsageError> {
    let path = parse_path(command, v)?;
    let log = BenchLog::read(&path).map_err(|e| usage_err(format!("{command}: {e}")))?;
    Ok((path, Arc::new(log)))
}

/// `--clutch-log`, when given: its path and the machine's clutch events, read and
/// validated.
fn parse_clutch_log(v: Option<&str>) -> Result<Option<(PathBuf, Arc<ClutchLog>)>, UsageError> {
    let Some(v) = v else { return Ok(None) };
    let path = parse_path("--clutch-log", v)?;
    let c = ClutchLog::read(&path).map_err(|e| usage_err(format!("--clutch-log: {e}")))?;
    Ok(Some((path, Arc::new(c))))
}

/// The arguments of `host-sim analyze`.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct AnalyzeArgs {
    /// A run file or a built-in scenario
    #[arg(value_name = "FILE.toml|SCENARIO")]
    pub scenario: String,
}

impl AnalyzeArgs {
    /// The scenario, read and validated.
    pub fn source(&self) -> Result<Source, UsageError> {
        parse_source("analyze", &self.scenario)
    }
}

/// A scenario argument of `command`: a built-in name or a run file (read and validated
/// here, so that nothing runs half-configured and a batch checks its files up front).
fn parse_source(command: &str, arg: &str) -> Result<Source, UsageError> {
    if ScenarioId::from_name(arg).is_none() && !arg.ends_with(".toml") {
        return Err(usage_err(format!(
            "{command}: unknown scenario '{arg}' (known: {}; or a run file FILE.toml)",
            ScenarioId::names()
        )));
    }
    Source::from_arg(arg).map_err(|e| usage_err(format!("{command}: {e}")))
}

/// A file or directory name: not empty.
fn parse_path(name: &str, value: &str) -> Result<PathBuf, UsageError> {
    if value.is_empty() {
        return Err(usage_err(format!("{name}: empty file name")));
    }
    Ok(PathBuf::from(value))
}

/// An animation file: `.svg` or `.gif`, at most one of each.
fn parse_animation(value: &str, given: &[PathBuf]) -> Result<PathBuf, UsageError> {
    let path = parse_path("--animate", value)?;
    let format = AnimFormat::of(&path).map_err(usage_err)?;
    if given.iter().any(|p| AnimFormat::of(p) == Ok(format)) {
        return Err(usage_err(format!(
            "--animate: '{value}': one .svg and one .gif at most"
        )));
    }
    Ok(path)
}

fn parse_fps(value: &str) -> Result<u32, UsageError> {
    let (lo, hi) = FPS_RANGE;
    let n: u32 = value.trim().parse().map_err(|_| {
        usage_err(format!(
            "--fps: '{value}' is not a whole number ({lo}..={hi} expected)"
        ))
    })?;
    if !(lo..=hi).contains(&n) {
        return Err(usage_err(format!(
            "--fps: {n} is out of range ({lo}..={hi} frames a second)"
        )));
    }
    Ok(n)
}

fn parse_slow(value: &str) -> Result<f64, UsageError> {
    let (lo, hi) = SLOW_RANGE;
    let what = format!("a slow-motion factor {lo}..={hi}");
    let x = parse_finite("--slow", value, &what)?;
    if !(lo..=hi).contains(&x) {
        return Err(usage_err(format!(
            "--slow: {value} is out of range ({what} expected)"
        )));
    }
    Ok(x)
}

fn parse_threads(value: &str) -> Result<usize, UsageError> {
    let what = format!("a whole number 1..={MAX_THREADS} expected");
    let n: usize = value.trim().parse().map_err(|_| {
        usage_err(format!(
            "--threads: '{value}' is not a whole number ({what})"
        ))
    })?;
    if !(1..=MAX_THREADS).contains(&n) {
        return Err(usage_err(format!(
            "--threads: {n} is out of range ({what})"
        )));
    }
    Ok(n)
}

/// `--ccw`, `--load` and `--motor` apply to the converter scenarios only, and `--ccw`
/// and `--load` not to `ccc-s1` (free mode: no clutch, no shaft load, no drive
/// direction).
/// A bench log's `--params` for `command` (`replay`, `identify`): not a twin that
/// spreads its events ([`spreading_refused`]).
fn not_spreading(params: &Source, command: &str) -> Result<(), UsageError> {
    if params
        .converter()
        .is_some_and(|c| c.converter.spread_events)
    {
        let why = spreading_refused(params.name(), command);
        return Err(usage_err(format!("--params: {why}")));
    }
    Ok(())
}

fn check_converter_options(
    scenario: &Source,
    ccw: bool,
    load: bool,
    motor: bool,
    spread_events: bool,
) -> Result<(), UsageError> {
    let given = [
        ("--ccw", ccw),
        ("--load", load),
        ("--motor", motor),
        ("--spread-events", spread_events),
    ];
    if !scenario.is_converter() {
        if let Some((name, _)) = given.iter().find(|(_, g)| *g) {
            return Err(usage_err(format!(
                "{name}: only for the converter scenarios ({}), not {}",
                ScenarioId::CONVERTER.map(ScenarioId::name).join(", "),
                scenario.name()
            )));
        }
    }
    if scenario.is_free_converter() {
        if let Some((name, _)) = given[..2].iter().find(|(_, g)| *g) {
            return Err(usage_err(format!(
                "{name}: {} runs in free mode without clutches, so it has no shaft load \
                 and no drive direction (use ccc-s2, or mode = \"clutch\" in a run file)",
                scenario.name()
            )));
        }
    }
    Ok(())
}

/// A number of `what` (for messages): finite.
fn parse_finite(name: &str, value: &str, what: &str) -> Result<f64, UsageError> {
    let x: f64 = value.trim().parse().map_err(|_| {
        usage_err(format!(
            "{name}: '{value}' is not a number ({what} expected)"
        ))
    })?;
    if !x.is_finite() {
        return Err(usage_err(format!(
            "{name}: '{value}' is not finite ({what} expected)"
        )));
    }
    Ok(x)
}

/// A torque in N·m: a finite number.
fn parse_torque(name: &str, value: &str) -> Result<f64, UsageError> {
    parse_finite(name, value, "a torque in N·m")
}

/// The load torque T_r in N·m: a finite number, not negative.
fn parse_load(value: &str) -> Result<f64, UsageError> {
    let what = "a load torque T_r >= 0 in N·m";
    let x = parse_finite("--load", value, what)?;
    if x < 0.0 {
        return Err(usage_err(format!(
            "--load: {value} is negative ({what} expected)"
        )));
    }
    if x >= MAX_CONVERTER_LOAD {
        return Err(usage_err(format!(
            "--load: {value} N·m is too large: from {} N·m on the clutch tolerance \
             1e-9 (T_r + 1 N·m) lets a locked lever hold a negative torque past 1e-3 N·m \
             and releases it late ({what} below that expected)",
            Sci(MAX_CONVERTER_LOAD)
        )));
    }
    // -0 is 0.
    Ok(x + 0.0)
}

fn parse_out(value: &str) -> Result<Output, UsageError> {
    match value {
        "" => Err(usage_err("--out: empty file name (use '-' for stdout)")),
        "-" => Ok(Output::Stdout),
        path => Ok(Output::File(PathBuf::from(path))),
    }
}

/// A time in seconds: a finite number greater than zero.
fn parse_seconds(name: &str, value: &str) -> Result<f64, UsageError> {
    let x: f64 = value.trim().parse().map_err(|_| {
        usage_err(format!(
            "{name}: '{value}' is not a number (seconds expected)"
        ))
    })?;
    if !x.is_finite() {
        return Err(usage_err(format!(
            "{name}: '{value}' is not finite (a positive number of seconds expected)"
        )));
    }
    if x <= 0.0 {
        return Err(usage_err(format!(
            "{name}: {value} is not positive (a positive number of seconds expected)"
        )));
    }
    Ok(x)
}

fn parse_every(value: &str) -> Result<u64, UsageError> {
    let n: u64 = value.trim().parse().map_err(|_| {
        usage_err(format!(
            "--every: '{value}' is not a whole number (N >= 1 expected)"
        ))
    })?;
    if n == 0 {
        return Err(usage_err("--every: must be at least 1 (got 0)"));
    }
    Ok(n)
}
