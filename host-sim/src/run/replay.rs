//! `host-sim replay`: a bench log ([`crate::model::bench`]) replayed open-loop on the
//! converter's twin. The twin steps at the log's sample period, each step under the
//! motor torque and load of the sample it starts from (held over the step, as a 1 kHz
//! loop reads its sensors and then steps); its state rows are the run's
//! ([`converter::columns`]) plus the encoders measured, the twin's angles through the
//! bench's encoder law, and their residuals (measured - twin, counts). The summary
//! gives each encoder's residual RMS and largest, and, with the machine's clutch log,
//! its events paired in order with the twin's.
//!
//! With `--observer` ([`super::observed`]) the twin is stepped by the core's
//! [`TwinObserver`] with the log's encoders as its measurements (each step's, the
//! sample it ends at) and corrected by them; the crank's count is then the bench's law
//! with no offset (the measurement is absolute), and the rows gain the innovations and
//! diagnostics.
//!
//! The encoder law ([`encoder_counts`]): the crank's count is `floor(θ1 / (2π/4096))`
//! of the twin's crank angle plus an offset that makes the first row's count the
//! log's (0 when the run file's initial crank angle is the machine's); the shaft's is
//! `floor(φ / (2π/4096))` of the shaft's angle φ turned in the drive direction from 0.

use super::converter::{self, new_twin, CccSummary, Drive, Extra, Logged};
use super::observed::{self, ObservedSummary, OBSERVER_COLUMNS};
use super::{overwritten, to_files};
use crate::error::{report_run_error, usage_err, Fig, RunError};
use crate::model::bench::{encoder_counts, BenchLog, ClutchEvent, ClutchLog, COUNTS_PER_TURN};
use crate::model::runfile::spreading_refused;
use crate::model::scenarios::{CccScenario, Source};
use crate::options::{precision, ObserverTuning, ReplayOptions};
use crate::output::{Cell, Observer};
use std::cell::Cell as Shared;
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use structomat::ccc::{
    DriveDirection, EventKind, Inputs, MotorInput, ObserverSettings, Twin, TwinObserver, Update,
};
use structomat::Real;

/// The columns a replay appends to the run's state row: per encoder, the count
/// measured, the twin's count and the residual (measured - twin), counts.
pub const RESIDUAL_COLUMNS: [&str; 6] = [
    "crank_counts",
    "twin_crank_counts",
    "crank_residual",
    "shaft_counts",
    "twin_shaft_counts",
    "shaft_residual",
];

/// One encoder's residuals (measured - twin, counts) over the replayed samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residuals {
    /// Samples compared.
    pub samples: u64,
    /// Sum of the squared residuals, counts².
    pub sum_squares: f64,
    /// The largest in magnitude (the first of them), counts, and its time, s.
    pub largest: (i64, f64),
}

impl Residuals {
    pub(crate) fn add(&mut self, residual: i64, time: f64) {
        self.samples += 1;
        self.sum_squares += (residual as f64).powi(2);
        if residual.unsigned_abs() > self.largest.0.unsigned_abs() || self.samples == 1 {
            self.largest = (residual, time);
        }
    }

    /// The root mean square, counts (`NaN` without samples).
    pub fn rms(&self) -> f64 {
        if self.samples == 0 {
            f64::NAN
        } else {
            (self.sum_squares / self.samples as f64).sqrt()
        }
    }
}

impl fmt::Display for Residuals {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "residual (measured - twin) RMS {:.3} counts, largest {:+} counts at t = {} s, \
             over {} samples",
            self.rms(),
            self.largest.0,
            Fig(self.largest.1),
            self.samples
        )
    }
}

/// The twin's count of each encoder at a state, by the bench's encoder law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderLaw {
    /// Added to the crank's `floor(θ1 / resolution)`: the log's first count less the
    /// twin's first.
    pub crank_offset: i64,
    /// +1 when the shaft's drive direction is CCW (the twin's shaft angle's sense), -1
    /// when CW.
    pub shaft_sign: f64,
}

impl EncoderLaw {
    /// The law that gives `twin`'s present crank angle the count `first_crank`.
    pub fn new<T: Real>(twin: &Twin<T>, first_crank: i64) -> EncoderLaw {
        let shaft_sign = match twin.params().drive {
            DriveDirection::Cw => -1.0,
            DriveDirection::Ccw => 1.0,
        };
        EncoderLaw {
            crank_offset: first_crank - encoder_counts(twin.link(1).theta.to_f64()),
            shaft_sign,
        }
    }

    /// The twin's `(crank, shaft)` counts.
    pub fn counts<T: Real>(&self, twin: &Twin<T>) -> (i64, i64) {
        (
            encoder_counts(twin.link(1).theta.to_f64()) + self.crank_offset,
            encoder_counts(self.shaft_sign * twin.shaft_angle().to_f64()),
        )
    }
}

/// A pair of the machine's and the twin's events, the k-th of each (either missing
/// past the end of its list).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The machine's (the clutch log's).
    pub machine: Option<ClutchEvent>,
    /// The twin's.
    pub twin: Option<Logged>,
}

impl Pair {
    /// Whether both are there and the same event between the same modes. A twin's
    /// `inputs` event is the machine's event between the same modes: the same change
    /// of the diode's state, which the twin met at the start of a step (the new
    /// sample of the inputs left its mode inconsistent: the machine's change fell
    /// between two samples, where its sensors, at 1 MHz, date it) rather than inside
    /// one by an event function's crossing. The kept-back logs' clutch sensors name
    /// the state change only (a lever letting go from I8 to I0 is `release8` whatever
    /// moved its torque through 0); on the known machine's log at 1000 N·m and 14 N·m
    /// the first release came 0.03 ms after a sample, and the twin's, at the sample,
    /// was `inputs I8->I0`.
    pub fn same(&self) -> bool {
        matches!((self.machine, self.twin), (Some(m), Some(t))
            if Self::same_kind(m.kind, t.kind) && m.from == t.from && m.to == t.to)
    }

    /// The machine's event `machine` and the twin's `twin` name the same change (see
    /// [`Pair::same`]).
    fn same_kind(machine: EventKind, twin: EventKind) -> bool {
        machine == twin || twin == EventKind::Inputs
    }

    /// The twin's time less the machine's, s, when both are there.
    pub fn dt(&self) -> Option<f64> {
        match (self.machine, self.twin) {
            (Some(m), Some(t)) => Some(t.time - m.time),
            _ => None,
        }
    }

    /// What differs, named: `""` for the same event.
    pub fn difference(&self) -> String {
        match (self.machine, self.twin) {
            (Some(m), Some(t)) => {
                let mut d = Vec::new();
                if !Self::same_kind(m.kind, t.kind) {
                    d.push(format!(
                        "event: machine {}, twin {}",
                        m.kind.name(),
                        t.kind.name()
                    ));
                }
                if m.from != t.from {
                    d.push(format!(
                        "mode before: machine {}, twin {}",
                        m.from.name(),
                        t.from.name()
                    ));
                }
                if m.to != t.to {
                    d.push(format!(
                        "mode after: machine {}, twin {}",
                        m.to.name(),
                        t.to.name()
                    ));
                }
                d.join("; ")
            }
            (Some(_), None) => "missing in the twin".to_string(),
            (None, Some(_)) => "extra in the twin".to_string(),
            (None, None) => String::new(),
        }
    }
}

/// The machine's events paired in order with the twin's.
#[derive(Clone, Debug, PartialEq)]
pub struct Matching {
    /// The clutch log's name.
    pub origin: String,
    /// The pairs, as many as the longer list.
    pub pairs: Vec<Pair>,
}

impl Matching {
    /// The machine's `logged` events paired in order with the `twin`'s (its start
    /// event left out: the clutch log holds the changes of the diode's state).
    pub fn new(log: &ClutchLog, twin: &[Logged]) -> Matching {
        let twin: Vec<Logged> = twin
            .iter()
            .copied()
            .filter(|e| e.kind != EventKind::Start)
            .collect();
        let n = log.events.len().max(twin.len());
        Matching {
            origin: log.origin.clone(),
            pairs: (0..n)
                .map(|k| Pair {
                    machine: log.events.get(k).copied(),
                    twin: twin.get(k).copied(),
                })
                .collect(),
        }
    }

    /// The first pair that is not the same event (index from 0), if any.
    pub fn first_mismatch(&self) -> Option<usize> {
        self.pairs.iter().position(|p| !p.same())
    }

    /// Events in the machine's log and in the twin's.
    pub fn counts(&self) -> (usize, usize) {
        (
            self.pairs.iter().filter(|p| p.machine.is_some()).count(),
            self.pairs.iter().filter(|p| p.twin.is_some()).count(),
        )
    }
}

/// An event as a summary's cell: `0.026870 release8 I8->I0`.
fn event_text(time: f64, kind: EventKind, from: &str, to: &str) -> String {
    format!("{time:.6} {} {from}->{to}", kind.name())
}

impl fmt::Display for Matching {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (m, t) = self.counts();
        write!(
            f,
            "clutch    {}: the machine {m} events, the twin {t} (its start left out), paired in order: ",
            self.origin
        )?;
        match self.first_mismatch() {
            None => writeln!(f, "all the same")?,
            Some(k) => {
                let p = &self.pairs[k];
                let when = p
                    .machine
                    .map(|e| e.time)
                    .or(p.twin.map(|e| e.time))
                    .unwrap_or(f64::NAN);
                writeln!(
                    f,
                    "the first {k} the same; the first mismatch is pair {} (t = {when:.6} s): {}",
                    k + 1,
                    p.difference()
                )?;
            }
        }
        writeln!(
            f,
            "          pair  machine t (s), event, modes     twin t (s), event, modes        twin - machine"
        )?;
        for (k, p) in self.pairs.iter().enumerate() {
            let machine = p.machine.map_or("-".to_string(), |e| {
                event_text(e.time, e.kind, e.from.name(), e.to.name())
            });
            let twin = p.twin.map_or("-".to_string(), |e| {
                event_text(e.time, e.kind, e.from.name(), e.to.name())
            });
            let dt = p
                .dt()
                .map_or(String::new(), |d| format!("{:+.3} ms", d * 1e3));
            let note = if p.same() {
                String::new()
            } else {
                format!("  {}", p.difference())
            };
            writeln!(
                f,
                "          {:>4}  {machine:<32}  {twin:<32}  {dt}{note}",
                k + 1
            )?;
        }
        Ok(())
    }
}

/// What a replay did (printed by its `Display`).
#[derive(Clone, Debug, PartialEq)]
pub struct ReplaySummary {
    /// The bench log's name.
    pub log: String,
    /// Its samples.
    pub samples: usize,
    /// The run of the twin (its `settings` the run file's: the log gave the motor and
    /// the load).
    pub run: CccSummary,
    /// The encoder law's crank offset, counts.
    pub crank_offset: i64,
    /// The crank encoder's residuals.
    pub crank: Residuals,
    /// The shaft encoder's residuals.
    pub shaft: Residuals,
    /// The machine's events paired with the twin's, when a clutch log was given.
    pub matching: Option<Matching>,
    /// What the observer did, when it was on.
    pub observed: Option<ObservedSummary>,
}

impl ReplaySummary {
    /// The process exit code: as the run's ([`CccSummary::exit_code`]).
    pub fn exit_code(&self) -> u8 {
        self.run.exit_code()
    }
}

impl fmt::Display for ReplaySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "replay    {}: {} samples at h = {} s, t = 0 .. {} s, {}, on the converter of {} \
             ({})",
            self.log,
            self.samples,
            self.run.h,
            Fig(self.run.t_end),
            if self.observed.is_some() {
                "with the observer (corrected from the encoders)"
            } else {
                "open loop (no observer)"
            },
            self.run.scenario,
            self.run.precision
        )?;
        self.run.fmt_run(f)?;
        writeln!(f)?;
        writeln!(
            f,
            "crank     {} ({COUNTS_PER_TURN} counts a turn, offset {:+} counts to the log's first)",
            self.crank, self.crank_offset
        )?;
        write!(f, "shaft     {} (drive direction positive)", self.shaft)?;
        if let Some(o) = &self.observed {
            write!(f, "\n{}", o.to_string().trim_end())?;
        }
        if let Some(m) = &self.matching {
            write!(f, "\n{}", m.to_string().trim_end())?;
        }
        Ok(())
    }
}

/// The columns a replay writes after the converter's ([`converter::columns`]): the
/// residuals', then the observer's when it observes.
fn extra_columns(observed: bool) -> Vec<String> {
    let mut columns = RESIDUAL_COLUMNS.map(String::from).to_vec();
    if observed {
        columns.extend(OBSERVER_COLUMNS.map(String::from));
    }
    columns
}

/// Replays `log` on the twin of `settings` (named `name`) in scalar `T`, telling `obs`
/// every state, the state rows with [`RESIDUAL_COLUMNS`] and the log lines; with
/// `clutch`, pairs the machine's events with the twin's.
pub fn simulate<T: Real>(
    name: &str,
    settings: CccScenario,
    log: &BenchLog,
    clutch: Option<&ClutchLog>,
    obs: &mut dyn Observer<T>,
) -> Result<ReplaySummary, RunError> {
    simulate_with(name, settings, log, clutch, None, obs)
}

/// [`simulate`], with `observer` the twin stepped by a [`TwinObserver`] of those
/// settings and corrected from the log's encoders, the rows with [`OBSERVER_COLUMNS`]
/// too.
pub fn simulate_with<T: Real>(
    name: &str,
    settings: CccScenario,
    log: &BenchLog,
    clutch: Option<&ClutchLog>,
    observer: Option<ObserverSettings<T>>,
    obs: &mut dyn Observer<T>,
) -> Result<ReplaySummary, RunError> {
    let n = log.len().saturating_sub(1);
    let h = T::c(log.period());
    if !(h.finite() && h > T::zero()) {
        return Err(RunError::Setup(format!(
            "{}: the sample period {} s is not a positive {}",
            log.origin,
            log.period(),
            precision::<T>()
        )));
    }
    // `replay`'s and `identify`'s options refuse it; a library caller is told the same.
    if settings.converter.spread_events {
        return Err(RunError::Setup(spreading_refused(name, "replay")));
    }
    // The run file's `motor_offset` corrects the current sensor's torque (0: as logged).
    let offset = settings.converter.motor_offset;
    let start = Inputs {
        motor: MotorInput::Torque(T::c(log.motor[0] + offset)),
        load: T::c(log.load[0]),
        measured: None,
    };
    // Step k + 1 ends at sample k + 1: what the encoders read there.
    let inputs = |k: usize| Inputs {
        motor: MotorInput::Torque(T::c(log.motor[k] + offset)),
        load: T::c(log.load[k]),
        measured: observer.and_then(|_| observed::measurement(log, k + 1)),
    };
    let mut settings = settings;
    if observer.is_some() {
        // The filter's state starts from the first measurement, as a Kalman filter's
        // does: the crank at the middle of the log's first count (the rest of the
        // initial state, the swing link's angle and the speeds, is the run file's).
        let first = (log.crank[0] as f64 + 0.5) * std::f64::consts::TAU / COUNTS_PER_TURN as f64;
        settings.converter.crank_deg = first.to_degrees();
    }
    let mut twin = new_twin(name, &settings, h, start)?;
    let mut law = EncoderLaw::new(&twin, log.crank[0]);
    if observer.is_some() {
        law.crank_offset = 0;
    }
    let mut crank = Residuals::default();
    let mut shaft = Residuals::default();
    let mut filter = observer.map(TwinObserver::new);
    // The last step's update and the crank angle's variance after it, rad².
    let update: Shared<Option<(Update<T>, T)>> = Shared::new(None);
    let mut watch = observer.map(|_| ObservedSummary::default());
    let mut extra = Extra {
        columns: extra_columns(observer.is_some()),
        // A row at every state (`every` is 1): each sample's residuals counted once.
        cells: Box::new(|twin: &Twin<T>, cells: &mut Vec<Cell<'static, T>>| {
            let k = usize::try_from(twin.steps()).unwrap_or(usize::MAX);
            let (Some(&mc), Some(&ms)) = (log.crank.get(k), log.shaft.get(k)) else {
                cells.extend([Cell::Empty; RESIDUAL_COLUMNS.len()]);
                return;
            };
            let (tc, ts) = law.counts(twin);
            let time = twin.time().to_f64();
            crank.add(mc - tc, time);
            shaft.add(ms - ts, time);
            cells.extend([mc, tc, mc - tc, ms, ts, ms - ts].map(|c| Cell::Num(T::c(c as f64))));
            if let Some(w) = watch.as_mut() {
                let u = update.get();
                w.add(
                    twin,
                    u.map(|u| u.0),
                    u.map_or(T::zero(), |u| u.1),
                    mc - tc,
                    cells,
                );
            }
        }),
    };
    let drive = Drive {
        n: n as u64,
        every: 1,
        t_end: log.duration(),
        quiet: true,
    };
    let mut step = |twin: &mut Twin<T>, now: &Inputs<T>| match filter.as_mut() {
        None => twin.step(now),
        Some(f) => {
            let up = f.step(twin, now)?;
            update.set(Some((up, f.covariance().angle())));
            Ok(())
        }
    };
    let driven = drive.run_with(
        &mut twin,
        &mut |k| inputs(usize::try_from(k).unwrap_or(0)),
        &mut step,
        &mut extra,
        obs,
    )?;
    drop(extra);
    let matching = clutch.map(|c| Matching::new(c, &driven.events));
    Ok(ReplaySummary {
        log: log.origin.clone(),
        samples: log.len(),
        run: driven.summary(name, settings, &twin, log.duration()),
        crank_offset: law.crank_offset,
        crank,
        shaft,
        matching,
        observed: watch,
    })
}

/// The files a replay writes: the state CSV `out`, its event and switch logs.
pub fn outputs(out: &Path) -> Vec<PathBuf> {
    let (events, switches) = converter::log_paths(out);
    vec![out.to_path_buf(), events, switches]
}

/// The converter settings of a replay's `--params` (a run file that does not describe
/// the converter is refused by the options already; this names it should one reach here).
pub fn converter_of(params: &Source) -> Result<CccScenario, RunError> {
    params.converter().ok_or_else(|| {
        RunError::Setup(format!("{} does not describe the converter", params.name()))
    })
}

/// Refuses outputs `targets` that would overwrite an input of a bench log's command
/// (`what`: "the replay", "identify"): the log, the clutch log, a `--params` file.
pub fn refuse_overwrite(
    log: &Path,
    clutch: Option<&Path>,
    params: &Source,
    targets: &[PathBuf],
    what: &str,
) -> Result<(), RunError> {
    let name = params.name().to_string();
    let mut inputs: Vec<&Path> = vec![log];
    inputs.extend(clutch);
    if params.builtin().is_none() {
        inputs.push(Path::new(&name));
    }
    match overwritten(&inputs, targets) {
        Some((out, input)) => Err(RunError::Usage(usage_err(format!(
            "the output {} is the input {}: {what} would overwrite it; name another file",
            out.display(),
            input.display()
        )))),
        None => Ok(()),
    }
}

/// Runs the replay of `opts` in `f64` to its files ([`to_files`]); the summary names
/// the logs.
pub fn run(opts: &ReplayOptions) -> Result<ReplaySummary, RunError> {
    let settings = converter_of(&opts.params)?;
    let targets = outputs(&opts.out);
    let params = opts.params.name().to_string();
    refuse_overwrite(
        &opts.log.0,
        opts.clutch.as_ref().map(|(p, _)| p.as_path()),
        &opts.params,
        &targets,
        "the replay",
    )?;
    let clutch = opts.clutch.as_ref().map(|(_, c)| &**c);
    let observer = opts.observer.map(|t| match t {
        ObserverTuning::Nominal => ObserverSettings::reference(),
        ObserverTuning::Identified => ObserverSettings::identified(),
    });
    let mut summary = to_files(&targets, |mut csv| {
        simulate_with::<f64>(&params, settings, &opts.log.1, clutch, observer, &mut csv)
    })?;
    summary.run.logs = Some((
        targets[1].display().to_string(),
        targets[2].display().to_string(),
    ));
    Ok(summary)
}

/// Runs `host-sim replay` with `opts`: the files, the summary on `stdout` (unless
/// quiet), errors on `stderr`; returns the exit code.
pub fn execute(opts: &ReplayOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    match run(opts) {
        Ok(summary) => {
            if !opts.quiet {
                let _ = writeln!(stdout, "{summary}").and_then(|_| stdout.flush());
            }
            if let converter::End::Stopped {
                error,
                expected: false,
            } = &summary.run.end
            {
                let _ = writeln!(
                    stderr,
                    "host-sim: replay {}: step {} failed ({} rows written): {error}",
                    summary.log,
                    summary.run.steps + 1,
                    summary.run.rows
                );
            }
            summary.exit_code()
        }
        Err(e) => report_run_error(e, stderr),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::draw::{raster::has_glyph, Shape};
    use crate::output::plot::{plots, Table};
    use structomat::ccc::Mode;

    /// Every text of an observed replay's figures is drawn by the PNG's font (a
    /// character it lacks is drawn as `?`): the columns as the replay writes them (the
    /// converter's and [`extra_columns`]), every panel present.
    #[test]
    fn every_text_of_an_observed_replays_figures_has_its_glyphs() {
        let mut names = converter::columns();
        names.extend(extra_columns(true));
        let mut t = Table::new(names);
        for k in 0..3 {
            let row: Vec<f64> = (0..t.names.len()).map(|c| (k + c) as f64 * 0.1).collect();
            t.push_row(&row);
        }
        let figures = plots(&t, "run");
        assert!(figures.len() > 5, "{} figures", figures.len());
        let mut texts = 0;
        for (file, fig) in &figures {
            for shape in &fig.shapes {
                if let Shape::Text(x) = shape {
                    texts += 1;
                    let missing: String = x.text.chars().filter(|c| !has_glyph(*c)).collect();
                    assert!(missing.is_empty(), "{file}: {:?} lacks {missing:?}", x.text);
                }
            }
        }
        assert!(texts > 100, "{texts} texts");
        assert!(!has_glyph('ω'), "the font has no Greek: the check can fail");
    }

    /// A twin's `inputs` event pairs with the machine's event between the same modes
    /// (the same change of the diode's state, met at a sample); any other kind must be
    /// the machine's own, and the modes must agree either way: the difference names
    /// what differs and nothing else.
    #[test]
    fn an_inputs_event_is_the_machines_between_the_same_modes() {
        let machine = ClutchEvent {
            time: 0.035030,
            kind: EventKind::Release(8),
            from: Mode::I8,
            to: Mode::I0,
        };
        let twin = |kind, to| Logged {
            time: 0.035,
            kind,
            from: Mode::I8,
            to,
        };
        let pair = |t| Pair {
            machine: Some(machine),
            twin: Some(t),
        };
        let at_sample = pair(twin(EventKind::Inputs, Mode::I0));
        assert!(at_sample.same());
        assert_eq!(at_sample.difference(), "");
        assert!((at_sample.dt().unwrap() + 3.0e-5).abs() < 1e-12);
        let elsewhere = pair(twin(EventKind::Inputs, Mode::A8));
        assert!(!elsewhere.same());
        assert_eq!(elsewhere.difference(), "mode after: machine I0, twin A8");
        let other = pair(twin(EventKind::Release(6), Mode::I0));
        assert!(!other.same());
        assert_eq!(other.difference(), "event: machine release8, twin release6");
        assert!(pair(twin(EventKind::Release(8), Mode::I0)).same());
    }
}
