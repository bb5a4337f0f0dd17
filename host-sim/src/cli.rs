//! Command-line parsing (hand-written, std only) and the usage text.

use crate::scenarios::{ScenarioId, Source};
use crate::sweep::{ProgressStyle, SweepOptions};
use std::ffi::OsString;
use std::fmt;
use std::path::PathBuf;

/// The usage text of `host-sim help`.
pub const USAGE: &str = "\
host-sim: simulate the built-in mechanisms of the structomat core, or mechanisms and
the Constantinesco converter described in run files (TOML)

Usage:
  host-sim list                      list the built-in scenarios and their formulas
  host-sim run <scenario> [options]  simulate a scenario and write CSV
  host-sim run FILE.toml [options]   simulate a run file (options override its values)
  host-sim analyze FILE.toml|<scenario>
                                     find and print the structomatic formula, the DOF
                                     and each group with its links and joints
  host-sim batch FILE --out-dir DIR [--threads N] [--quiet]
                                     run the runs listed in FILE, N at a time
  host-sim sweep FILE --out-dir DIR [--threads N] [--progress bar|lines|none]
                   [--keep-runs] [--quiet]
                                     run a grid of variants of a run (a sweep file)
                                     and write a table and heat-maps
  host-sim plot RUN.csv --out-dir DIR
                                     plot a CSV that host-sim run wrote (as --plot)
  host-sim help | --help | -h        show this help

Scenarios: slider-crank, five-bar (mechanisms);
           ccc-s1, ccc-s2 (the Constantinesco torque converter, SPEC 3)
  Each ships as a run file, host-sim/scenarios/<name>.toml (embedded): copy one to
  start your own.
Examples: host-sim/mechanisms/*.toml (run files), host-sim/sweeps/*.toml (sweep
  files), host-sim/batches/*.batch (batch files).

Options of run:
  --out FILE|-       write the CSV to FILE, the summary to stdout;
                     '-' or no --out: the CSV to stdout, the summary to stderr
  --h SECONDS        step size (default: the scenario's own)
  --t-end SECONDS    simulated time (default: the scenario's own);
                     runs ceil(t_end / h) fixed steps
  --every N          write every N-th step (default: the file's, else 1); the row at
                     t = 0 is always written
  --f32, --f64       run the core in single (f32) or double (f64) precision
                     (default: the file's f32 key, else f64)
  --quiet            no summary
  --plot DIR         draw the run's plots into DIR (created if missing), each as .svg
                     and .png: converter: crank, motor_torque, reactions, speeds,
                     clutch_torques, mode, energy; mechanisms: coordinates, torques,
                     reactions (the CSV's rows: --every thins them too)
  --animate FILE     animate the mechanism: FILE.svg (animated SVG, plays in a
                     browser) or FILE.gif; may be given twice (one .svg, one .gif)
  --fps N            frames a second of the animation, 1..=50 (default 25)
  --slow X           slow motion: the animation lasts X times the simulated time,
                     0.01..=1000 (default 1); frames are taken every 1/(fps·X) s of
                     simulated time, at most 5000 of them
  Values may also be given as --option=VALUE.

Options of the converter scenarios only:
  --motor N·M        constant motor torque on the crank, CCW positive (default 12)
  --load N·M         ccc-s2: load torque T_r >= 0 on the shaft (default 800)
  --ccw              ccc-s2: the shaft turns counter-clockwise (SPEC 3's CCW variant;
                     default clockwise)
  ccc-s1 runs in free mode, without clutches: --load and --ccw do not apply to it.

CSV columns (one row at t = 0, then one per written step):
  t                  time, s
  q{j} qd{j} qdd{j}  coordinate j (1-based), its rate and acceleration
  motor_torque{j}    applied torque (N·m) or force (N) of the drive on coordinate j
  then, for every group of the sequence and every joint of the group (kinetostatics):
  R{i}_{j}           revolute joint between bodies i and j (0 = ground): |reaction|, N
  N{i}_{j} M{i}_{j}  prismatic joint: |normal force|, N, and reaction moment, N·m
  drive_torque{j}    driving torque (force) the motion requires on coordinate j
  A repeated name gets a suffix _2, _3, ...

Converter scenarios (ccc-s1: free mode, h = 1e-4 s, t_end = 1 s; ccc-s2: h = 1e-4 s,
t_end = 1 s): a row at t = 0, every N-th step and the last state, columns
  t mode mode_code coords       time, s; mode name (free I0 I6 I8 jam A6 A8 A68), its
                                code 0..7 in that order, the independent coordinates
  q1 q2 qd1 qd2                 coordinates (rad) and speeds (rad/s); empty past the
                                mode's DOF (q2 in 1-DOF modes, all four in jam)
  theta{p} omega{p}             angle (rad, unwrapped) and speed (rad/s) of link p = 1..8
  shaft_speed shaft_angle       output shaft, rad/s and rad turned, CCW positive
  c6 c8                         torque each clutch transmits, N·m, + in drive direction
  motor_torque                  motor torque on the crank, N·m
  R_A R_B R_C R_E R_F R_D5 R_D7 R_G R_I R_H6 R_H8   |joint reaction|, N
  kinetic potential             energy now, J
  motor_work load_work impact_loss audit_residual   energy audit since t = 0, J
  With --out FILE, the mode changes go to FILE's stem + .events.csv (time, event,
  from, to, c6, c8, impact_loss, mismatch; the first row is the start event, except in
  free mode, which has no mode choice) and the coordinate switches to stem +
  .switches.csv (time, mode, from, to, conditioning_before, conditioning_after); with
  the CSV on stdout these two logs are not written.
  The summary gives the first breakaway, the events by kind, the coordinate switches,
  the energy audit and how the run ended; it is printed also when a step fails.
  ccc-s1 ending at the mechanism's singularity is its expected end: exit status 0.

Batch (host-sim batch FILE --out-dir DIR):
  FILE lists one run a line, written like the arguments of run, e.g.
    ccc-s2 --load 600 --motor 10 --t-end 0.3
  without --out (the batch names the files); '#' starts a comment, blank lines are
  skipped. Every line is checked before anything runs: a bad line is an error naming
  its line number (exit status 2).
  --out-dir DIR      where the files go (created if missing; files of the same names
                     are replaced)
  --threads N        runs at a time, on N threads (default 2); the files are the same
                     for any N
  --quiet            no progress lines, no closing summary
  Files, for job k (0, 1, ... in line order, written with at least 3 digits):
  k-<scenario>.csv, and for the converter scenarios k-<scenario>.events.csv and
  .switches.csv: byte for byte what `host-sim run <line> --out k-<scenario>.csv` writes.
  batch.csv, one row per job in job order, columns
  job line scenario args file   job index, its line in FILE, the scenario, the
                                line's arguments, the job's CSV file name
  exit end                      the exit status the run alone gives; how it ended:
                                completed, singularity (at a singularity of the
                                mechanism: ccc-s1's expected end, or the diode's rods
                                and levers in line), failed (a step failed otherwise)
                                or error (setup, file)
  steps time rows               steps completed, time of the last state, s (empty when a
                                mechanism's step failed), CSV data rows
  first_breakaway events switches audit_residual
                                converter runs: first breakaway, s (empty if none),
                                events, coordinate switches, energy audit residual, J
  message                       the error of a run that did not complete
  Exit status: 0 when every run succeeded (exit status 0 alone), 1 otherwise.

Run files (TOML; the full reference with every key: host-sim/scenarios/README.md).
  SI units (m, kg, kg·m², s, N, N·m, rad/s); angles in degrees in keys ending in _deg,
  motor speeds in rpm in keys ending in _rpm. Unknown keys are errors; every value is
  checked before the first step; an error names the file, the line:column when the
  toml parser knows it, and the field, e.g.  my.toml: link \"coupler\".mass: must be >= 0
  A mechanism:
    name, description, gravity = [gx, gy] (m/s², default [0, -9.81])
    [[ground]]  name, at = [x, y]
    [[link]]    name, mass, inertia (about the COG), length (a bar: points start, end)
                or none (a block: point origin), points = { D = [x, y], ... } (link
                frame), cog = distance along the bar or [x, y] (default: the midpoint),
                angle_deg (the initial guess of the link's angle: picks the branch)
    [[joint]]   name, type = \"revolute\", points = [\"A\", \"crank.start\"]
                or type = \"prismatic\", slider = \"slider.origin\", guide = \"A\",
                guide_angle_deg, slider_angle_deg, offset (the guess along the guide, m)
                A point is a ground point's name or link.point (start, end, origin, a
                named point, or an index).
    [[driver]]  link, joint (the motor element: link about/along joint; coordinates
                q1, q2, ... in driver order), q0_deg (revolute) or q0 (prismatic, m),
                qd0, offset_deg, motor
    [[load]]    link, at = [x, y] (link frame), force = [fx, fy] (N), moment (N·m)
    The motion-transmission sequence is found by `host-sim analyze`'s search.
  The converter: [converter] a, f, h (pivots A, F and shaft H), [[converter.link]] x 8
    (length, mass, inertia), rocker_d, mass, mass_inertia, mass_at, shaft_inertia,
    drive = \"cw\"|\"ccw\", gravity, branch_c, branch_g, branch_i = \"left\"|\"right\",
    crank_deg, swing_deg, crank_speed, swing_speed
  [run] h, t_end (s), every, f32, integrator = \"dp5\" (the fixed-step Dormand-Prince,
    step h; the default) or \"adaptive\" (the adaptive DP5(4) between output times h
    apart, with rtol, atol (default 1e-9 each) and h_max (default 10 h); mechanisms
    only: the twin steps with a fixed h); converter only: mode =
    \"clutch\"|\"free\", motor, load (T_r, N·m)
  motor = a torque in N·m, or { type = \"constant\", torque }, { type = \"asynchronous\",
    breakdown_rpm, breakdown_torque, rated_rpm, rated_torque, synchronous_rpm },
    { type = \"polynomial\", a, b, c } (T = a + b ω + c ω², ω in rad/s)

Sweep (host-sim sweep FILE --out-dir DIR): every combination of the axes' values of a
base run, N at a time; example: host-sim/sweeps/mass-motor.toml
  base = \"ccc-s2\"     a built-in scenario, or a run file (path relative to FILE)
  threads = N         runs at a time (default 2; --threads overrides it)
  [set]               fixed changes to the base: \"run.t_end\" = 0.3, ...
  [[axis]]            key = \"converter.mass\" (a dotted key of the run file; a number
                      picks an array element: \"converter.link.2.mass\"), label, and
                      values = [..] or from, to, steps (evenly spaced, ends included)
  [[heatmap]]         metric (a numeric column below), x, y (axis keys; default: the
                      first two numeric axes); default: first_breakaway
  Every variant is checked as a run file before anything runs (exit status 2 on a
  bad one, named by its number and axis values). Variants are numbered in grid order
  (the first axis outermost); the files do not depend on --threads.
  --out-dir DIR      where the files go (created if missing)
  --threads N        runs at a time, on N threads
  --progress STYLE   bar (redrawn in place), lines (one per tenth) or none; default:
                     bar on a terminal, else lines
  --keep-runs        also write each variant's CSV and logs, named as by batch
  --quiet            no progress, no closing summary
  Files: sweep.csv, one row per variant, columns
    job, the axes' keys, exit, end, steps, time, first_breakaway, events, switches,
    shaft_angle, motor_work, load_work, load_power (load_work / time, W),
    impact_loss, message  (empty where it does not apply);
  heatmap<n>-<metric>.svg and .png per [[heatmap]] (with -<k> per combination of the
  other axes' values). The summary gives the lowest and highest value of each
  heat-map's metric and the variant that gave it. A variant that fails is a row
  (end = singularity or failed, as in batch.csv), not a failure of the sweep: exit
  status 0 when the files are written.

Exit status: 0 success, 1 run failure (step error, file error), 2 bad arguments or a
bad run file.
";

/// The hint appended to argument errors.
pub const HINT: &str = "run `host-sim help` for usage";

/// Where the CSV goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// Standard output (the summary then goes to standard error).
    Stdout,
    /// A file (the summary then goes to standard output).
    File(PathBuf),
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

/// Options of `host-sim plot`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlotOptions {
    /// The CSV a run wrote.
    pub csv: PathBuf,
    /// Where the plots go.
    pub out_dir: PathBuf,
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

/// A parsed command line.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// `host-sim help`, `--help`, `-h`.
    Help,
    /// `host-sim list`.
    List,
    /// `host-sim run <scenario> [options]`.
    Run(RunOptions),
    /// `host-sim analyze FILE.toml|<scenario>`.
    Analyze(Source),
    /// `host-sim batch FILE --out-dir DIR [--threads N] [--quiet]`.
    Batch(BatchOptions),
    /// `host-sim plot RUN.csv --out-dir DIR`.
    Plot(PlotOptions),
    /// `host-sim sweep FILE --out-dir DIR [options]`.
    Sweep(SweepOptions),
}

/// A bad command line: the one-line message names the argument and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UsageError(pub String);

impl fmt::Display for UsageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

fn usage_err(msg: impl Into<String>) -> UsageError {
    UsageError(msg.into())
}

/// Parses the arguments after the program name.
pub fn parse_args<I, S>(args: I) -> Result<Command, UsageError>
where
    I: IntoIterator<Item = S>,
    S: Into<OsString>,
{
    let mut words = Vec::new();
    for a in args {
        let a: OsString = a.into();
        match a.into_string() {
            Ok(s) => words.push(s),
            Err(a) => return Err(usage_err(format!("argument {a:?} is not valid UTF-8"))),
        }
    }
    let Some(command) = words.first() else {
        return Err(usage_err(
            "missing command (list, run, batch, plot or help)",
        ));
    };
    let rest = &words[1..];
    match command.as_str() {
        "help" | "--help" | "-h" => Ok(Command::Help),
        "list" => match rest.first() {
            None => Ok(Command::List),
            Some(a) if is_help(a) => Ok(Command::Help),
            Some(a) => Err(usage_err(format!("list: unexpected argument '{a}'"))),
        },
        "run" => parse_run(rest),
        "batch" => parse_batch(rest),
        "analyze" => parse_analyze(rest),
        "plot" => parse_plot(rest),
        "sweep" => parse_sweep(rest),
        other if other.starts_with('-') => Err(usage_err(format!(
            "unknown option '{other}' before the command (commands: list, run, analyze, batch, sweep, plot, help)"
        ))),
        other => Err(usage_err(format!(
            "unknown command '{other}' (commands: list, run, analyze, batch, sweep, plot, help)"
        ))),
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

fn parse_analyze(args: &[String]) -> Result<Command, UsageError> {
    match args {
        [] => Err(usage_err(format!(
            "analyze: missing run file or scenario (known: {})",
            ScenarioId::names()
        ))),
        [a, ..] if is_help(a) => Ok(Command::Help),
        [a] => parse_source("analyze", a).map(Command::Analyze),
        [_, b, ..] => Err(usage_err(format!("analyze: unexpected argument '{b}'"))),
    }
}

fn is_help(a: &str) -> bool {
    a == "--help" || a == "-h"
}

/// An option's name and, for `--name=value`, its inline value.
fn split_option(arg: &str) -> (&str, Option<String>) {
    match arg.split_once('=') {
        Some((n, v)) if n.starts_with("--") => (n, Some(v.to_string())),
        _ => (arg, None),
    }
}

/// A flag (`--quiet`) must not be given a value.
fn no_value(name: &str, inline: Option<String>, arg: &str) -> Result<(), UsageError> {
    match inline {
        Some(_) => Err(usage_err(format!("{name}: takes no value (got '{arg}')"))),
        None => Ok(()),
    }
}

/// An option's value: inline (`--name=value`) or the next argument, `args[*k]`, which
/// is then consumed.
fn option_value(
    name: &str,
    inline: Option<String>,
    args: &[String],
    k: &mut usize,
) -> Result<String, UsageError> {
    match inline {
        Some(v) => Ok(v),
        None => {
            let v = args
                .get(*k)
                .ok_or_else(|| usage_err(format!("{name}: missing value")))?;
            *k += 1;
            Ok(v.clone())
        }
    }
}

fn parse_run(args: &[String]) -> Result<Command, UsageError> {
    let mut scenario = None;
    let mut out = Output::Stdout;
    let (mut h, mut t_end, mut every) = (None, None, None);
    // `--f32` / `--f64`: the precision, over the run file's `f32`.
    let (mut single, mut quiet, mut ccw): (Option<bool>, bool, bool) = (None, false, false);
    let (mut load, mut motor) = (None, None);
    let (mut plot, mut animate, mut fps, mut slow) = (None, Vec::new(), None, None);
    let mut k = 0;
    while k < args.len() {
        let arg = args[k].as_str();
        k += 1;
        if is_help(arg) {
            return Ok(Command::Help);
        }
        if arg == "-" || !arg.starts_with('-') {
            if let Some(first) = &scenario {
                return Err(usage_err(format!(
                    "run: unexpected argument '{arg}' (the scenario is already '{}')",
                    Source::name(first)
                )));
            }
            scenario = Some(parse_source("run", arg)?);
            continue;
        }
        let (name, inline) = split_option(arg);
        match name {
            "--f32" | "--f64" | "--quiet" | "--ccw" => {
                no_value(name, inline, arg)?;
                match name {
                    "--f32" | "--f64" => {
                        let want = name == "--f32";
                        if single.is_some_and(|s| s != want) {
                            return Err(usage_err("--f32 and --f64: give one precision"));
                        }
                        single = Some(want);
                    }
                    "--quiet" => quiet = true,
                    _ => ccw = true,
                }
            }
            "--out" | "--h" | "--t-end" | "--every" | "--load" | "--motor" => {
                let value = option_value(name, inline, args, &mut k)?;
                match name {
                    "--out" => out = parse_out(&value)?,
                    "--h" => h = Some(parse_seconds(name, &value)?),
                    "--t-end" => t_end = Some(parse_seconds(name, &value)?),
                    "--load" => load = Some(parse_load(&value)?),
                    "--motor" => motor = Some(parse_torque(name, &value)?),
                    _ => every = Some(parse_every(&value)?),
                }
            }
            "--plot" | "--animate" | "--fps" | "--slow" => {
                let value = option_value(name, inline, args, &mut k)?;
                match name {
                    "--plot" => plot = Some(parse_path(name, &value)?),
                    "--animate" => animate.push(parse_animation(&value, &animate)?),
                    "--fps" => fps = Some(parse_fps(&value)?),
                    _ => slow = Some(parse_slow(&value)?),
                }
            }
            _ => return Err(usage_err(format!("run: unknown option '{name}'"))),
        }
    }
    let scenario = scenario.ok_or_else(|| {
        usage_err(format!(
            "run: missing scenario (known: {})",
            ScenarioId::names()
        ))
    })?;
    check_converter_options(&scenario, ccw, load.is_some(), motor.is_some())?;
    if animate.is_empty() {
        if let Some(name) = [("--fps", fps.is_some()), ("--slow", slow.is_some())]
            .iter()
            .find_map(|(n, g)| g.then_some(*n))
        {
            return Err(usage_err(format!("{name}: only with --animate FILE")));
        }
    }
    // The run file's own output settings, unless the command line gives them.
    let file = scenario.run_file().ok();
    let every = every.unwrap_or_else(|| file.as_ref().map_or(1, |f| f.run.every));
    let f32 = single.unwrap_or_else(|| file.is_some_and(|f| f.run.f32));
    Ok(Command::Run(RunOptions {
        scenario,
        out,
        h,
        t_end,
        every,
        f32,
        quiet,
        ccw,
        load,
        motor,
        plot,
        animate,
        fps: fps.unwrap_or(DEFAULT_FPS),
        slow: slow.unwrap_or(DEFAULT_SLOW),
    }))
}

fn parse_plot(args: &[String]) -> Result<Command, UsageError> {
    let mut out_dir = None;
    let Some(csv) = parse_file_command("plot", "CSV file", args, |name, inline, _, args, k| {
        match name {
            "--out-dir" => out_dir = Some(parse_path(name, &option_value(name, inline, args, k)?)?),
            _ => return Err(usage_err(format!("plot: unknown option '{name}'"))),
        }
        Ok(())
    })?
    else {
        return Ok(Command::Help);
    };
    Ok(Command::Plot(PlotOptions {
        csv,
        out_dir: out_dir.ok_or_else(|| usage_err("plot: missing --out-dir DIR"))?,
    }))
}

fn parse_sweep(args: &[String]) -> Result<Command, UsageError> {
    let (mut out_dir, mut threads) = (None, None);
    let (mut quiet, mut keep_runs, mut progress) = (false, false, ProgressStyle::Auto);
    let Some(file) =
        parse_file_command("sweep", "sweep file", args, |name, inline, arg, args, k| {
            match name {
                "--quiet" | "--keep-runs" => {
                    no_value(name, inline, arg)?;
                    match name {
                        "--quiet" => quiet = true,
                        _ => keep_runs = true,
                    }
                }
                "--out-dir" => {
                    out_dir = Some(parse_path(name, &option_value(name, inline, args, k)?)?)
                }
                "--threads" => {
                    threads = Some(parse_threads(&option_value(name, inline, args, k)?)?)
                }
                "--progress" => {
                    let value = option_value(name, inline, args, k)?;
                    progress = match value.as_str() {
                        "bar" => ProgressStyle::Bar,
                        "lines" => ProgressStyle::Lines,
                        "none" => ProgressStyle::None,
                        _ => {
                            return Err(usage_err(format!(
                                "--progress: '{value}' is not bar, lines or none"
                            )))
                        }
                    };
                }
                _ => return Err(usage_err(format!("sweep: unknown option '{name}'"))),
            }
            Ok(())
        })?
    else {
        return Ok(Command::Help);
    };
    Ok(Command::Sweep(SweepOptions {
        file,
        out_dir: out_dir.ok_or_else(|| usage_err("sweep: missing --out-dir DIR"))?,
        threads,
        progress,
        keep_runs,
        quiet,
    }))
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
    let format = crate::animate::AnimFormat::of(&path).map_err(usage_err)?;
    if given
        .iter()
        .any(|p| crate::animate::AnimFormat::of(p) == Ok(format))
    {
        return Err(usage_err(format!(
            "--animate: '{value}': one .svg and one .gif at most"
        )));
    }
    Ok(path)
}

fn parse_fps(value: &str) -> Result<u32, UsageError> {
    let (lo, hi) = crate::animate::FPS_RANGE;
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
    let (lo, hi) = crate::animate::SLOW_RANGE;
    let what = format!("a slow-motion factor {lo}..={hi}");
    let x = parse_finite("--slow", value, &what)?;
    if !(lo..=hi).contains(&x) {
        return Err(usage_err(format!(
            "--slow: {value} is out of range ({what} expected)"
        )));
    }
    Ok(x)
}

fn parse_batch(args: &[String]) -> Result<Command, UsageError> {
    let (mut out_dir, mut threads, mut quiet) = (None, 2, false);
    let Some(file) =
        parse_file_command("batch", "batch file", args, |name, inline, arg, args, k| {
            match name {
                "--quiet" => {
                    no_value(name, inline, arg)?;
                    quiet = true;
                }
                "--threads" => threads = parse_threads(&option_value(name, inline, args, k)?)?,
                "--out-dir" => {
                    let value = option_value(name, inline, args, k)?;
                    if value.is_empty() {
                        return Err(usage_err("--out-dir: empty directory name"));
                    }
                    out_dir = Some(PathBuf::from(value));
                }
                _ => return Err(usage_err(format!("batch: unknown option '{name}'"))),
            }
            Ok(())
        })?
    else {
        return Ok(Command::Help);
    };
    let out_dir = out_dir.ok_or_else(|| usage_err("batch: missing --out-dir DIR"))?;
    Ok(Command::Batch(BatchOptions {
        file,
        out_dir,
        threads,
        quiet,
    }))
}

/// The arguments of a command that takes one file and options (`batch`, `sweep`,
/// `plot`): `option(name, inline value, the argument, args, &mut k)` handles each option
/// (it may consume the next argument through [`option_value`]). `None` when help is
/// asked for; an error when the file is missing or given twice.
fn parse_file_command(
    command: &str,
    what: &str,
    args: &[String],
    mut option: impl FnMut(&str, Option<String>, &str, &[String], &mut usize) -> Result<(), UsageError>,
) -> Result<Option<PathBuf>, UsageError> {
    let mut file = None;
    let mut k = 0;
    while k < args.len() {
        let arg = args[k].as_str();
        k += 1;
        if is_help(arg) {
            return Ok(None);
        }
        if arg == "-" || !arg.starts_with('-') {
            if file.is_some() {
                return Err(usage_err(format!(
                    "{command}: unexpected argument '{arg}' (one {what})"
                )));
            }
            file = Some(parse_path(command, arg)?);
            continue;
        }
        let (name, inline) = split_option(arg);
        option(name, inline, arg, args, &mut k)?;
    }
    file.map(Some)
        .ok_or_else(|| usage_err(format!("{command}: missing {what}")))
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
fn check_converter_options(
    scenario: &Source,
    ccw: bool,
    load: bool,
    motor: bool,
) -> Result<(), UsageError> {
    let given = [("--ccw", ccw), ("--load", load), ("--motor", motor)];
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Command, UsageError> {
        parse_args(args.iter().copied())
    }

    // `--f64` overrides a run file's `f32 = true`, `--f32` a file's default; both at
    // once are an error.
    #[test]
    fn precision_over_the_file() {
        let dir = std::env::temp_dir().join(format!("host-sim-cli-f64-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("single.toml");
        let text = ScenarioId::FiveBar
            .file_text()
            .replace("f32 = false", "f32 = true");
        assert!(text.contains("f32 = true"));
        std::fs::write(&path, text).unwrap();
        let file = path.to_str().unwrap();
        let f32_of = |extra: &[&str]| match parse(&[&["run", file][..], extra].concat()) {
            Ok(Command::Run(o)) => Ok(o.f32),
            Ok(other) => panic!("{other:?}"),
            Err(e) => Err(e.0),
        };
        assert_eq!(f32_of(&[]), Ok(true));
        assert_eq!(f32_of(&["--f64"]), Ok(false));
        assert_eq!(f32_of(&["--f32", "--f32"]), Ok(true));
        assert!(f32_of(&["--f32", "--f64"])
            .unwrap_err()
            .contains("give one precision"));
        let builtin = |extra: &[&str]| match parse(&[&["run", "five-bar"][..], extra].concat()) {
            Ok(Command::Run(o)) => o.f32,
            other => panic!("{other:?}"),
        };
        assert!(!builtin(&[]) && builtin(&["--f32"]) && !builtin(&["--f64"]));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn run_options_in_any_order() {
        let c = parse(&[
            "run",
            "--h=0.002",
            "five-bar",
            "--every",
            "5",
            "--out",
            "x.csv",
            "--f32",
            "--quiet",
        ]);
        let mut want = RunOptions::new(ScenarioId::FiveBar);
        want.h = Some(0.002);
        want.every = 5;
        want.out = Output::File("x.csv".into());
        want.f32 = true;
        want.quiet = true;
        assert_eq!(c, Ok(Command::Run(want)));
    }

    #[test]
    fn negative_value_is_a_value_not_an_option() {
        let e = parse(&["run", "five-bar", "--h", "-1"]).unwrap_err();
        assert!(e.0.starts_with("--h: -1 is not positive"), "{e}");
        let e = parse(&["run", "five-bar", "--t-end", "inf"]).unwrap_err();
        assert!(e.0.contains("--t-end") && e.0.contains("not finite"), "{e}");
        let e = parse(&["run", "five-bar", "--t-end", "NaN"]).unwrap_err();
        assert!(e.0.contains("--t-end"), "{e}");
    }

    #[test]
    fn errors_name_the_argument() {
        for (args, needle) in [
            (&["run"][..], "missing scenario"),
            (&["run", "four-bar"][..], "'four-bar'"),
            (&["run", "five-bar", "--h"][..], "--h: missing value"),
            (&["run", "five-bar", "--every", "-3"][..], "--every"),
            (&["run", "five-bar", "--every", "1.5"][..], "--every"),
            (&["run", "five-bar", "--frob"][..], "'--frob'"),
            (&["run", "five-bar", "--quiet=1"][..], "--quiet"),
            (&["run", "five-bar", "slider-crank"][..], "'slider-crank'"),
            (&["run", "five-bar", "--out", ""][..], "--out"),
            (&["list", "x"][..], "'x'"),
            (&["walk"][..], "'walk'"),
            (&[][..], "missing command"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn converter_options() {
        let c = parse(&["run", "--ccw", "ccc-s2", "--load=0", "--motor", "-3.5"]);
        let mut want = RunOptions::new(ScenarioId::CccS2);
        want.ccw = true;
        want.load = Some(0.0);
        want.motor = Some(-3.5);
        assert_eq!(c, Ok(Command::Run(want)));
        // -0 is a load of 0.
        let Ok(Command::Run(o)) = parse(&["run", "ccc-s2", "--load", "-0"]) else {
            panic!("--load -0")
        };
        assert!(o.load.is_some_and(|l| l == 0.0 && l.is_sign_positive()));
        // S1 takes a motor override.
        let mut want = RunOptions::new(ScenarioId::CccS1);
        want.motor = Some(6.0);
        assert_eq!(
            parse(&["run", "ccc-s1", "--motor", "6"]),
            Ok(Command::Run(want))
        );
        for (args, needle) in [
            (
                &["run", "ccc-s2", "--load", "-1"][..],
                "--load: -1 is negative",
            ),
            (&["run", "ccc-s2", "--motor", "inf"][..], "--motor"),
            (
                &["run", "five-bar", "--ccw"][..],
                "--ccw: only for the converter",
            ),
            (&["run", "ccc-s1", "--load", "1"][..], "--load: ccc-s1"),
            (&["run", "ccc-s1", "--ccw"][..], "--ccw: ccc-s1"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn batch_options() {
        let c = parse(&[
            "batch",
            "--threads=3",
            "b.batch",
            "--out-dir",
            "out",
            "--quiet",
        ]);
        assert_eq!(
            c,
            Ok(Command::Batch(BatchOptions {
                file: "b.batch".into(),
                out_dir: "out".into(),
                threads: 3,
                quiet: true,
            }))
        );
        let Ok(Command::Batch(b)) = parse(&["batch", "b", "--out-dir=o"]) else {
            panic!("batch b --out-dir=o")
        };
        assert_eq!(b.threads, 2, "default threads");
        for (args, needle) in [
            (&["batch", "--out-dir", "o"][..], "missing batch file"),
            (&["batch", "b"][..], "missing --out-dir"),
            (&["batch", "b", "--out-dir", ""][..], "--out-dir: empty"),
            (&["batch", "b", "--out-dir"][..], "--out-dir: missing value"),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "0"][..],
                "--threads: 0",
            ),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "x"][..],
                "'x'",
            ),
            (
                &["batch", "b", "--out-dir", "o", "--threads", "257"][..],
                "257",
            ),
            (&["batch", "b", "c", "--out-dir", "o"][..], "'c'"),
            (
                &["batch", "b", "--out-dir", "o", "--t-end", "1"][..],
                "'--t-end'",
            ),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {e}");
        }
    }

    #[test]
    fn help_anywhere() {
        for args in [
            &["help"][..],
            &["-h"],
            &["--help"],
            &["run", "--help"],
            &["run", "five-bar", "-h"],
            &["batch", "--help"],
        ] {
            assert_eq!(parse(args), Ok(Command::Help), "{args:?}");
        }
    }
}
