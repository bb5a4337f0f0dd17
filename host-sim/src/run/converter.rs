//! The converter runner: the Constantinesco torque converter's runs (`host-sim run
//! ccc-s1|ccc-s2`, SPEC 3) on a [`structomat::ccc::Twin`]: it tells the observers every
//! state, the state rows, the log lines of the mode changes and of the coordinate
//! switches, and gathers the summary (events, energy audit, how the run ended). The
//! one place where host-sim sets up and steps the core's twin and reads its errors.
//!
//! Exit codes: 0 when the run reaches `t_end`, and for `ccc-s1` also when it ends at a
//! singularity of the mechanism ([`TwinStepError::at_singularity`]): that is S1's expected end
//! (SPEC 3), reported in the summary. Any other failed step is exit code 1, after the
//! rows and log lines before it are written and the summary is printed.

use super::interrupt;
use super::progress::Progress;
use crate::error::{Fig, RunError, Sci, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK};
use crate::model::bench::CLUTCH_EVENTS;
use crate::model::runfile::MotorSpec;
use crate::model::scenarios::CccScenario;
use crate::options::{precision, RunOptions, Steps};
use crate::output::{Cell, Observer, State, Tables};
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use structomat::ccc::{
    initial_pose, mode_model, Audit, Coordinates, DriveDirection, EventKind, Inputs, Mode,
    MotorInput, Twin, TwinSettings, TwinStepError, JOINT_NAMES,
};
use structomat::Real;

/// The event kinds, in the order of the summary's counts: the start, then the
/// changes of the diode's state that a clutch log names ([`CLUTCH_EVENTS`]).
pub const EVENT_KINDS: [EventKind; CLUTCH_EVENTS.len() + 1] = {
    let mut all = [EventKind::Start; CLUTCH_EVENTS.len() + 1];
    let mut k = 0;
    while k < CLUTCH_EVENTS.len() {
        all[k + 1] = CLUTCH_EVENTS[k];
        k += 1;
    }
    all
};

/// Header of the event log.
pub const EVENT_COLUMNS: [&str; 8] = [
    "time",
    "event",
    "from",
    "to",
    "c6",
    "c8",
    "impact_loss",
    "mismatch",
];

/// Header of the coordinate-switch log.
pub const SWITCH_COLUMNS: [&str; 6] = [
    "time",
    "mode",
    "from",
    "to",
    "conditioning_before",
    "conditioning_after",
];

/// The state CSV's column names: `t, mode, mode_code, coords, q1, q2, qd1, qd2,
/// theta1..8, omega1..8, shaft_speed, shaft_angle, c6, c8, motor_torque, R_<joint>` for
/// every joint of [`JOINT_NAMES`], then `kinetic, potential, motor_work, load_work,
/// impact_loss, audit_residual`. `q2`/`qd2` (1-DOF modes) and all four (jam) are left
/// empty past the mode's DOF.
pub fn columns() -> Vec<String> {
    let mut c: Vec<String> = ["t", "mode", "mode_code", "coords", "q1", "q2", "qd1", "qd2"]
        .map(String::from)
        .to_vec();
    c.extend((1..=8).map(|p| format!("theta{p}")));
    c.extend((1..=8).map(|p| format!("omega{p}")));
    c.extend(
        ["shaft_speed", "shaft_angle", "c6", "c8", "motor_torque"]
            .iter()
            .map(|s| s.to_string()),
    );
    c.extend(JOINT_NAMES.iter().map(|j| format!("R_{j}")));
    c.extend(
        [
            "kinetic",
            "potential",
            "motor_work",
            "load_work",
            "impact_loss",
            "audit_residual",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    c
}

/// The event and switch logs next to the state CSV `out`: its stem +
/// `.events.csv` and `.switches.csv` (`s2.csv` → `s2.events.csv`, `s2.switches.csv`).
pub fn log_paths(out: &Path) -> (PathBuf, PathBuf) {
    (
        out.with_extension("events.csv"),
        out.with_extension("switches.csv"),
    )
}

/// How a converter run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum End {
    /// It reached `t_end`.
    Completed,
    /// Step `steps + 1` failed; the twin keeps the state after `steps` steps.
    Stopped {
        /// The twin's error.
        error: TwinStepError,
        /// Whether it is the scenario's expected end (S1 at the mechanism's
        /// singularity): exit code 0, else 1.
        expected: bool,
    },
    /// SIGINT or SIGTERM stopped it after `steps` steps (their rows and log lines
    /// written): exit code 130.
    Interrupted,
}

impl End {
    /// Whether the run stopped at a singularity of the mechanism (`ccc-s1`'s expected
    /// end, or the diode's rods and levers in line).
    pub fn at_singularity(&self) -> bool {
        matches!(self, End::Stopped { error, .. } if error.at_singularity())
    }
}

/// What a converter run did (printed as a few lines by its `Display`).
#[derive(Clone, Debug, PartialEq)]
pub struct CccSummary {
    /// The scenario's name (a built-in's, or the run file's path).
    pub scenario: String,
    /// Its settings after the overrides.
    pub settings: CccScenario,
    /// `f64` or `f32`.
    pub precision: &'static str,
    /// Step size, s.
    pub h: f64,
    /// Simulated time asked for, s.
    pub t_end: f64,
    /// Steps completed.
    pub steps: u64,
    /// Time of the last good state, s.
    pub time: f64,
    /// State CSV data rows written (including the one at t = 0 and the last state).
    pub rows: u64,
    /// The event and switch logs' paths, when written.
    pub logs: Option<(String, String)>,
    /// Events by kind, in [`EVENT_KINDS`] order: `(name, count)`.
    pub events: Vec<(&'static str, u64)>,
    /// The first breakaway: the first event that starts the held shaft (a breakaway
    /// event, or a catch that the shaft must yield to, as at a crank dead point):
    /// time, s, and the event's name.
    pub first_breakaway: Option<(f64, &'static str)>,
    /// Coordinate switches.
    pub switches: u64,
    /// Events with a plastic impact (a kinetic energy loss > 0).
    pub impacts: u64,
    /// The energy audit at the last good state, J.
    pub audit: Audit<f64>,
    /// The mode at the last good state.
    pub mode: Mode,
    /// Its coordinates.
    pub coords: Coordinates,
    /// Shaft angle turned at the last good state, rad, CCW positive.
    pub shaft_angle: f64,
    /// How the run ended.
    pub end: End,
    /// With the events spread over the steps after them (`run.spread_events`): the
    /// most the twin's time lagged the clock's `n·h` after a step, s; `None` otherwise.
    pub lag: Option<f64>,
    /// Wall time of the whole run (stepping and files).
    pub wall: Duration,
    /// Wall time inside `Twin::step` only.
    pub step_wall: Duration,
}

impl CccSummary {
    /// The process exit code: 0 when the run reached `t_end` or ended as expected, 1
    /// when a step failed otherwise.
    pub fn exit_code(&self) -> u8 {
        match self.end {
            End::Completed | End::Stopped { expected: true, .. } => EXIT_OK,
            End::Interrupted => EXIT_INTERRUPTED,
            End::Stopped {
                expected: false, ..
            } => EXIT_FAILURE,
        }
    }

    /// Total events.
    pub fn event_count(&self) -> u64 {
        self.events.iter().map(|e| e.1).sum()
    }

    /// The audit residual relative to the motor work (`NaN` without motor work).
    pub fn relative_residual(&self) -> f64 {
        let w = self.audit.motor_work;
        if w == 0.0 {
            f64::NAN
        } else {
            self.audit.residual() / w.abs()
        }
    }

    /// Nanoseconds per step inside `Twin::step`.
    pub fn ns_per_step(&self) -> f64 {
        self.step_wall.as_secs_f64() * 1e9 / self.steps.max(1) as f64
    }

    /// Nanoseconds per step of the whole run.
    pub fn total_ns_per_step(&self) -> f64 {
        self.wall.as_secs_f64() * 1e9 / self.steps.max(1) as f64
    }
}

impl fmt::Display for CccSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scenario  {}: Constantinesco converter, {} ({})",
            self.scenario, self.settings, self.precision
        )?;
        self.fmt_run(f)
    }
}

impl CccSummary {
    /// The summary's lines after the first (the scenario's): the steps, the logs, the
    /// events, the energy audit, how the run ended, the wall time.
    pub fn fmt_run(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "steps     {} of h = {} s, t = 0 .. {} s, {} CSV rows",
            self.steps,
            self.h,
            Fig(self.time),
            self.rows
        )?;
        if let Some(lag) = self.lag {
            writeln!(
                f,
                "spread    each event's work spread over the steps after it: the twin lagged the clock by at most {} s ({} steps)",
                Sci(lag),
                Fig(lag / self.h)
            )?;
        }
        match &self.logs {
            Some((e, s)) => writeln!(f, "logs      {e}, {s}")?,
            None => writeln!(
                f,
                "logs      event and switch logs not written (CSV on stdout; use --out FILE)"
            )?,
        }
        match self.first_breakaway {
            Some((t, by)) => writeln!(f, "breakaway first at t = {} s ({by})", Fig(t))?,
            None => writeln!(f, "breakaway none")?,
        }
        write!(f, "events   ")?;
        for (k, (name, n)) in self.events.iter().enumerate() {
            let sep = if k == 0 { " " } else { ", " };
            write!(f, "{sep}{name} {n}")?;
        }
        writeln!(f, " ({} in all)", self.event_count())?;
        writeln!(f, "switches  {} coordinate switches", self.switches)?;
        let a = &self.audit;
        writeln!(
            f,
            "energy    motor work {} J, Δ(K + V) {} J (K + V: {} -> {} J), load work {} J, impact losses {:.3e} J",
            Fig(a.motor_work),
            Fig(a.kinetic + a.potential - a.initial),
            Fig(a.initial),
            Fig(a.kinetic + a.potential),
            Fig(a.load_work),
            a.impact_loss
        )?;
        writeln!(
            f,
            "audit     residual motor work - Δ(K + V) - load work - impact losses = {:.3e} J, {:.3e} of the motor work",
            a.residual(),
            self.relative_residual()
        )?;
        writeln!(
            f,
            "impacts   {} plastic impacts, total loss {:.6e} J",
            self.impacts, a.impact_loss
        )?;
        // A mode at rest (jam: every lever locked, the shaft held) has no coordinates.
        let coords = match self.coords {
            Coordinates::Rest => "no coordinates: the linkage is held".to_string(),
            c => format!("{c} coordinates"),
        };
        writeln!(
            f,
            "final     mode {} ({coords}) at t = {} s, shaft angle {} rad",
            self.mode,
            Fig(self.time),
            Fig(self.shaft_angle)
        )?;
        match &self.end {
            End::Completed => writeln!(f, "ended     reached t_end = {} s", self.t_end)?,
            End::Stopped {
                error,
                expected: true,
            } => writeln!(
                f,
                "ended     at the mechanism's singularity (the expected end of {}): {error}",
                self.scenario
            )?,
            End::Stopped {
                error,
                expected: false,
            } => writeln!(f, "ended     step {} failed: {error}", self.steps + 1)?,
            End::Interrupted => writeln!(
                f,
                "ended     interrupted (SIGINT or SIGTERM) after step {}: the files hold the run up to there",
                self.steps
            )?,
        }
        write!(
            f,
            "wall      {:.6} s: {:.0} ns/step in Twin::step, {:.0} ns/step with the files",
            self.wall.as_secs_f64(),
            self.ns_per_step(),
            self.total_ns_per_step()
        )
    }
}

/// The structomatic formula of the mode the twin of `s` starts from (I0, or free, in
/// its first coordinate choice), in physical link numbers; `?` if it cannot build.
pub fn start_formula(s: &CccScenario) -> String {
    let params = s.converter.params::<f64>();
    let mode = if s.clutch { Mode::I0 } else { Mode::Free };
    let coords = mode.coordinate_choices()[0];
    initial_pose(
        &params,
        s.converter.crank_deg.to_radians(),
        s.converter.swing_deg.to_radians(),
    )
    .and_then(|pose| mode_model(&params, mode, coords, &pose).ok())
    .map_or_else(
        || "?".to_string(),
        |(model, _)| format!("{} ({mode}, {coords})", model.formula()),
    )
}

/// The converter settings of `opts`: its scenario's, with the overrides `--motor`,
/// `--load`, `--ccw` and `--spread-events`; `None` for a mechanism.
pub fn settings(opts: &RunOptions) -> Option<CccScenario> {
    let mut s = opts.scenario.converter()?;
    if let Some(m) = opts.motor {
        s.motor = MotorSpec::Constant(m);
    }
    if let Some(l) = opts.load {
        s.load = l;
    }
    if opts.ccw {
        s.drive = DriveDirection::Ccw;
    }
    if opts.spread_events {
        s.converter.spread_events = true;
    }
    Some(s)
}

/// Runs the converter scenario of `opts` in scalar `T`, telling `obs` every state, the
/// state rows (at t = 0, every N-th step, and the last state) and the log lines (log 0:
/// the events, log 1: the coordinate switches). [`Observer::on_end`] is called also
/// when a step fails; a failed step is not an `Err` but the summary's
/// [`End::Stopped`]. The summary's `logs` is left `None` (the caller knows where the
/// logs went).
pub fn simulate<T: Real>(
    opts: &RunOptions,
    obs: &mut dyn Observer<T>,
) -> Result<CccSummary, RunError> {
    let name = opts.scenario.name();
    let settings = settings(opts).ok_or_else(|| {
        RunError::Setup(format!(
            "{name} is not a converter scenario: run it with host_sim::run::simulate"
        ))
    })?;
    let (Steps { t_end, n, .. }, h) = Steps::of::<T>(opts)?;
    let motor = settings
        .motor
        .motor::<T>()
        .map_err(|e| RunError::Setup(format!("cannot set up {name}: motor: {e}")))?;
    let inputs = Inputs {
        motor: MotorInput::Law(motor),
        load: T::c(settings.load),
        measured: None,
    };
    let mut twin = new_twin(name, &settings, h, inputs)?;
    let drive = Drive {
        n,
        every: opts.every.max(1),
        t_end,
        quiet: opts.quiet,
    };
    let driven = drive.run(&mut twin, &mut |_| inputs, &mut Extra::none(), obs)?;
    Ok(driven.summary(name, settings, &twin, t_end))
}

/// The twin of the converter `settings` (its parameters, drive direction, clutches and
/// initial state) at step `h`, started under `inputs`. Errors name the run `name`.
pub fn new_twin<T: Real>(
    name: &str,
    settings: &CccScenario,
    h: T,
    inputs: Inputs<T>,
) -> Result<Twin<T>, RunError> {
    let conv = &settings.converter;
    let mut params = conv.params::<T>();
    params.drive = settings.drive;
    let mut ts = TwinSettings::reference(h);
    ts.clutch = settings.clutch;
    ts.spread_events = conv.spread_events;
    // Converted as `TwinSettings::reference` does: degrees to radians in f64, then T.
    ts.crank = T::c(conv.crank_deg.to_radians());
    ts.swing = T::c(conv.swing_deg.to_radians());
    ts.crank_speed = T::c(conv.crank_speed);
    ts.swing_speed = T::c(conv.swing_speed);
    Twin::new(params, ts, inputs).map_err(|e| RunError::Setup(format!("cannot set up {name}: {e}")))
}

/// A twin's event in the run's order: time, s, the event's name, the modes before and
/// after.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Logged {
    /// Time, s.
    pub time: f64,
    /// What fired ([`EventKind`]).
    pub kind: EventKind,
    /// Mode before.
    pub from: Mode,
    /// Mode chosen.
    pub to: Mode,
}

/// What takes one step of a twin under its inputs (the twin's own step, or an
/// observer's).
pub type StepFn<'a, T> = dyn FnMut(&mut Twin<T>, &Inputs<T>) -> Result<(), TwinStepError> + 'a;

/// What appends a run's own cells to a state row, for the twin's present state.
pub type ExtraCells<'a, T> = dyn FnMut(&Twin<T>, &mut Vec<Cell<'static, T>>) + 'a;

/// Columns a run appends to each state row after [`columns`], and the cells of a row:
/// `cells(twin, row)` appends them for the twin's state.
pub struct Extra<'a, T: Real> {
    /// The column names.
    pub columns: Vec<String>,
    /// Appends the cells of the twin's present state.
    pub cells: Box<ExtraCells<'a, T>>,
}

impl<T: Real> Extra<'_, T> {
    /// No extra columns.
    pub fn none() -> Self {
        Extra {
            columns: Vec::new(),
            cells: Box::new(|_, _| {}),
        }
    }
}

/// How a converter run steps its twin: `n` steps, a row every `every`-th, to `t_end`
/// (s, for the progress line), `quiet`: no progress line.
#[derive(Clone, Copy, Debug)]
pub struct Drive {
    /// Steps to take.
    pub n: u64,
    /// A state row every N-th step (and at t = 0 and the last state).
    pub every: u64,
    /// The run's end, s.
    pub t_end: f64,
    /// No progress line.
    pub quiet: bool,
}

/// What stepping the twin did ([`Drive::run`]).
#[derive(Clone, Debug)]
pub struct Driven {
    /// Steps completed.
    pub steps: u64,
    /// State rows written.
    pub rows: u64,
    /// How the run ended.
    pub end: End,
    /// Events by kind, in [`EVENT_KINDS`] order.
    pub counts: [u64; EVENT_KINDS.len()],
    /// Every event in the run's order (the start's included).
    pub events: Vec<Logged>,
    /// The first breakaway (see [`CccSummary::first_breakaway`]).
    pub first_breakaway: Option<(f64, &'static str)>,
    /// Coordinate switches.
    pub switches: u64,
    /// Events with a plastic impact.
    pub impacts: u64,
    /// The most the twin's time lagged the clock after a step, s (0 unless it spreads
    /// its events).
    pub lag: f64,
    /// Wall time of the whole run.
    pub wall: Duration,
    /// Wall time inside `Twin::step`.
    pub step_wall: Duration,
}

impl Drive {
    /// Steps `twin` `n` times, step `k + 1` under `inputs(k)`, telling `obs` every
    /// state, the state rows (each with the `extra` cells) and the log lines (log 0:
    /// the events, log 1: the coordinate switches); [`Observer::on_end`] also when a
    /// step fails (the [`End::Stopped`] of the result).
    pub fn run<T: Real>(
        &self,
        twin: &mut Twin<T>,
        inputs: &mut dyn FnMut(u64) -> Inputs<T>,
        extra: &mut Extra<'_, T>,
        obs: &mut dyn Observer<T>,
    ) -> Result<Driven, RunError> {
        self.run_with(twin, inputs, &mut |t, i| t.step(i), extra, obs)
    }

    /// [`Drive::run`] with each step taken by `step` (the twin's own, or an observer's
    /// step of it).
    pub fn run_with<T: Real>(
        &self,
        twin: &mut Twin<T>,
        inputs: &mut dyn FnMut(u64) -> Inputs<T>,
        step: &mut StepFn<'_, T>,
        extra: &mut Extra<'_, T>,
        obs: &mut dyn Observer<T>,
    ) -> Result<Driven, RunError> {
        let start = Instant::now();
        let mut step_wall = Duration::ZERO;
        let mut counts = [0u64; EVENT_KINDS.len()];
        let mut events = Vec::new();
        let mut first_breakaway = None;
        let mut switches = 0u64;
        let mut impacts = 0u64;

        let mut all = columns();
        all.extend(extra.columns.iter().cloned());
        obs.on_start(&Tables {
            columns: &all,
            logs: &[&EVENT_COLUMNS, &SWITCH_COLUMNS],
        })?;
        // The events of the setup (the start mode's choice) and of each step.
        let mut record = |twin: &Twin<T>, obs: &mut dyn Observer<T>| -> Result<(), RunError> {
            for e in twin.events() {
                if let Some(k) = EVENT_KINDS.iter().position(|k| *k == e.kind) {
                    counts[k] += 1;
                }
                if e.impact_loss > T::zero() {
                    impacts += 1;
                }
                let starts_shaft = !e.from.shaft_turning() && e.to.shaft_turning();
                if starts_shaft && first_breakaway.is_none() {
                    first_breakaway = Some((e.time.to_f64(), e.kind.name()));
                }
                events.push(Logged {
                    time: e.time.to_f64(),
                    kind: e.kind,
                    from: e.from,
                    to: e.to,
                });
                obs.on_event(
                    0,
                    &[
                        Cell::Num(e.time),
                        Cell::Text(e.kind.name()),
                        Cell::Text(e.from.name()),
                        Cell::Text(e.to.name()),
                        Cell::Num(e.c[0]),
                        Cell::Num(e.c[1]),
                        Cell::Num(e.impact_loss),
                        Cell::Num(e.mismatch),
                    ],
                )?;
            }
            for s in twin.switches() {
                switches += 1;
                obs.on_event(
                    1,
                    &[
                        Cell::Num(s.time),
                        Cell::Text(s.mode.name()),
                        Cell::Text(s.from.name()),
                        Cell::Text(s.to.name()),
                        Cell::Num(s.conditioning[0]),
                        Cell::Num(s.conditioning[1]),
                    ],
                )?;
            }
            Ok(())
        };
        let mut cells = Vec::new();
        let mut write = |twin: &Twin<T>, obs: &mut dyn Observer<T>| {
            row(twin, &mut cells);
            (extra.cells)(twin, &mut cells);
            obs.on_row(&cells)
        };
        record(twin, obs)?;
        write(twin, obs)?;
        obs.on_state(State::Converter(twin));
        let mut rows = 1u64;
        let mut written = 0u64;
        let mut steps = 0u64;
        let mut end = End::Completed;
        let mut lag = 0.0f64;
        let mut progress = Progress::new(self.t_end, self.quiet);
        while steps < self.n {
            if interrupt::requested() {
                end = End::Interrupted;
                break;
            }
            progress.tick(twin.time().to_f64());
            let now = inputs(steps);
            let t0 = Instant::now();
            let r = step(twin, &now);
            step_wall += t0.elapsed();
            if let Err(error) = r {
                // An end at a singularity of the mechanism (S1's diode rods in line, or
                // S2's without a load to hold the shaft) is where the machine stops, in
                // either mode: one exit status for it in run, batch and sweep.
                let expected = error.at_singularity();
                end = End::Stopped { error, expected };
                break;
            }
            steps += 1;
            lag = lag.max(twin.lag().to_f64());
            record(twin, obs)?;
            obs.on_state(State::Converter(twin));
            if steps % self.every == 0 || steps == self.n {
                write(twin, obs)?;
                rows += 1;
                written = steps;
            }
        }
        if written != steps {
            // The last good state before a failed step.
            write(twin, obs)?;
            rows += 1;
        }
        progress.finish();
        obs.on_end()?;
        Ok(Driven {
            steps,
            rows,
            end,
            counts,
            events,
            first_breakaway,
            switches,
            impacts,
            lag,
            wall: start.elapsed(),
            step_wall,
        })
    }
}

impl Driven {
    /// The summary of the run `scenario` of `settings` that left `twin` (to `t_end`,
    /// s); its `logs` left `None`.
    pub fn summary<T: Real>(
        self,
        scenario: &str,
        settings: CccScenario,
        twin: &Twin<T>,
        t_end: f64,
    ) -> CccSummary {
        let a = twin.audit();
        CccSummary {
            scenario: scenario.to_string(),
            settings,
            precision: precision::<T>(),
            h: twin.h().to_f64(),
            t_end,
            steps: self.steps,
            time: twin.time().to_f64(),
            rows: self.rows,
            logs: None,
            events: EVENT_KINDS
                .iter()
                .zip(self.counts)
                .map(|(k, n)| (k.name(), n))
                .collect(),
            first_breakaway: self.first_breakaway,
            switches: self.switches,
            impacts: self.impacts,
            audit: Audit {
                motor_work: a.motor_work.to_f64(),
                load_work: a.load_work.to_f64(),
                impact_loss: a.impact_loss.to_f64(),
                kinetic: a.kinetic.to_f64(),
                potential: a.potential.to_f64(),
                initial: a.initial.to_f64(),
                correction: a.correction.to_f64(),
            },
            mode: twin.mode(),
            coords: twin.coordinates(),
            shaft_angle: twin.shaft_angle().to_f64(),
            end: self.end,
            lag: twin.settings().spread_events.then_some(self.lag),
            wall: self.wall,
            step_wall: self.step_wall,
        }
    }
}

/// The state row of `twin` into `cells` (see [`columns`]): cells past the mode's DOF
/// are empty. The one definition of a row: the CSV's and the Python twin's `state()`.
pub fn row<T: Real>(twin: &Twin<T>, cells: &mut Vec<Cell<'static, T>>) {
    cells.clear();
    let mode = twin.mode();
    cells.extend([
        Cell::Num(twin.time()),
        Cell::Text(mode.name()),
        Cell::Int(u64::from(mode.code())),
        Cell::Text(twin.coordinates().name()),
    ]);
    for v in [twin.q(), twin.qd()] {
        for j in 0..2 {
            cells.push(v.get(j).map_or(Cell::Empty, |x| Cell::Num(*x)));
        }
    }
    cells.extend((1..=8).map(|p| Cell::Num(twin.link(p).theta)));
    cells.extend((1..=8).map(|p| Cell::Num(twin.link(p).omega)));
    let [c6, c8] = twin.clutch_torques();
    cells.extend(
        [
            twin.shaft_speed(),
            twin.shaft_angle(),
            c6,
            c8,
            twin.motor_torque(),
        ]
        .map(Cell::Num),
    );
    cells.extend(twin.joint_reactions().iter().map(|r| Cell::Num(r.norm())));
    let a = twin.audit();
    cells.extend(
        [
            a.kinetic,
            a.potential,
            a.motor_work,
            a.load_work,
            a.impact_loss,
            a.residual(),
        ]
        .map(Cell::Num),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_paths_beside_the_csv() {
        let (e, s) = log_paths(Path::new("/tmp/run/s2.csv"));
        assert_eq!(e, Path::new("/tmp/run/s2.events.csv"));
        assert_eq!(s, Path::new("/tmp/run/s2.switches.csv"));
        let (e, _) = log_paths(Path::new("out"));
        assert_eq!(e, Path::new("out.events.csv"));
    }

    #[test]
    fn columns_are_unique() {
        let c = columns();
        assert_eq!(c.len(), 46);
        for (k, n) in c.iter().enumerate() {
            assert!(!c[..k].contains(n), "{n} twice");
        }
    }

    #[test]
    fn event_kind_names_are_distinct() {
        let names = EVENT_KINDS.map(EventKind::name);
        for (k, n) in names.iter().enumerate() {
            assert!(!names[..k].contains(n), "{n} twice");
        }
    }
}
