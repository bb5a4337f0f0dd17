//! The fit of `host-sim identify`: the converter's unknown parameters fitted to a
//! bench log by minimizing the simulation error of its open-loop replay
//! ([`crate::run::replay`]).
//!
//! **The error.** Each replay of the log on the twin with a trial of the free
//! parameters ([`crate::model::identifiable`]) gives a residual vector: per sample and
//! encoder, the twin's angle in counts (continuous, through the encoder law's offset)
//! less the middle of the count measured (`m + 0.5`: the encoder's `floor` leaves the
//! angle uniform in `[m, m + 1)`, so a perfect twin's residuals are quantization noise
//! of RMS `1/√12 ≈ 0.29` counts); with a clutch log, per pair of events, the time
//! difference over [`EVENT_SCALE`] when both are the same event between the same modes,
//! else [`EVENT_MISMATCH`]. The cost is the sum of the squares.
//!
//! **The search.** argmin's Nelder-Mead on the parameters scaled to their bounds (0 at
//! the lower, 1 at the upper): a trial outside is evaluated at the nearest point inside
//! plus [`OUT_OF_BOUNDS`] times the squared distance, so the simplex stays inside.
//! The first simplex is the base file's values (clamped into the bounds) and a step of
//! [`RESTART_STEPS`]`[0]` of each range, and the search is
//! restarted once from its best with a step of `[1]`. It ends after `max_iters` iterations or when the
//! simplex's costs agree to [`COST_TOLERANCE`]. Single-threaded and without random
//! numbers: the same inputs give the same bits.
//!
//! **The horizons and the starts.** The search fits the log's first [`HORIZONS`]`[0]`
//! from [`STARTS`] starts (the base and points spread around it, [`starts`]), then its
//! first [`HORIZONS`]`[1]` and the whole log, each from the last one's best. A trial whose clutch events leave the machine's
//! sequence partway through the log has residuals that grow from there on and jump with
//! the parameters (an event missed, the twin in another mode), and a heavier link 2
//! with more friction at E imitates the machine over part of a log: valleys a simplex
//! settles in. On 15 logs the twin wrote with bench1's identified machine at T_r of 400
//! to 1000 N·m and motors of 10 to 16 N·m (the torque sensor's noise of 3 seeds), the
//! whole log from SPEC's machine alone missed issue 19's 0.5 ms on 7 (up to 2.5 ms off,
//! the crank up to 8.6 counts RMS); the first 0.3 s first, from one start, on 4 (up to
//! 0.75 ms); from 4 starts on none (every event within 0.26 ms, the crank under 0.6
//! counts RMS), at 5.2 times the replays (bench1: 6891 against 1319, 24.5 s against
//! 9.8 s on these machines). With the stages below (seven parameters) and those two
//! horizons, the third seed of 1000/14 settled in a valley, 0.54 ms off (the six alone,
//! 0.54 ms too); the 0.6 s horizon between them takes it to 0.015 ms, the other 14
//! within 0.26 ms (400/12's third seed, in a valley of its own: 0.09 ms without the
//! middle horizon), for 20 % more replays.
//!
//! **The stages.** A problem may free its parameters in stages
//! ([`Problem::in_stages`]): the first `k` searched (horizons and starts as above) with
//! the others at their base values, then the first `k'` from that best, the last stage
//! all of them, each stage within the same bounds. The default parameters are two
//! stages: the six that explain most of bench1, then the friction at F (swing link on
//! the ground), which takes the fit to the counts' quantization (README, "From a bench
//! log to an identified twin"). All seven at once found bench1's optimum too, but on
//! the known machine's log at 800 N·m and 10 N·m (no friction at F) settled in a valley
//! of the rocker's mass and the friction at B and F (5.46 kg, 0.010, 0.0075 for the
//! machine's 5.36, 0.014 and 0: 3.5 to 3.9 σ off, 0.22 ms, from 8 starts as from 4);
//! in stages, 5.40 kg, 0.0138 and 0 (2.0 σ at most) and 0.09 ms. A stage's result is
//! kept only where its whole-log cost is below its start's (the last stage's best,
//! its new parameters at their base): the stages never end worse than the first. It
//! doubles the replays (bench1: 13,609 with the three horizons, 31 s on these
//! machines).
//!
//! **The uncertainty.** At the optimum, the Jacobian `J` of the residuals by central
//! differences (a step of [`JACOBIAN_STEP`] of each range), the residual variance
//! `s² = rᵀr / (N - p)` and the Gauss-Newton covariance `s² (JᵀJ)⁻¹`: each parameter's
//! σ is the root of its diagonal, with `s²` inflated by the residuals'
//! autocorrelation ([`correlation_factor`]): quantization of a smooth signal is not
//! independent from sample to sample.

use crate::error::{RunError, Sci};
use crate::model::bench::{BenchLog, ClutchLog, COUNTS_PER_TURN};
use crate::model::identifiable::Param;
use crate::model::scenarios::CccScenario;
use crate::output::{Observer, State};
use crate::run::interrupt;
use crate::run::replay::{self, EncoderLaw, ReplaySummary};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{CostFunction, Error as ArgminError, Executor, State as _, KV};
use argmin::solver::neldermead::NelderMead;
use nalgebra::DMatrix;
use std::cell::Cell;
use std::io::Write;
use std::rc::Rc;

/// An event's time difference that weighs as much as one count of encoder residual, s.
pub const EVENT_SCALE: f64 = 5e-5;

/// The residual of a pair of events that differ, or of an event missing in either
/// list: as an event 200 · [`EVENT_SCALE`] = 10 ms off.
pub const EVENT_MISMATCH: f64 = 200.0;

/// The cost of a trial the twin cannot be set up with (a mass that makes the
/// parameters invalid): above any replay's.
const SETUP_FAILED: f64 = 1e15;

/// The penalty of a trial outside the bounds, per squared scaled distance.
pub const OUT_OF_BOUNDS: f64 = 1e9;

/// The first simplex's step along each parameter, a fraction of its range, of the
/// search and of its restart from the first's best.
pub const RESTART_STEPS: [f64; 2] = [0.25, 0.05];

/// The search ends when the simplex's costs have a standard deviation below this.
pub const COST_TOLERANCE: f64 = 1e-3;

/// The central differences' step of the Jacobian, a fraction of each range.
pub const JACOBIAN_STEP: f64 = 1e-4;

/// The fractions of the log fitted in turn, each search from the last one's best (see
/// the module's "horizons"); the last is the whole log.
pub const HORIZONS: [f64; 3] = [0.3, 0.6, 1.0];

/// The first horizon's starts: the base values and `STARTS - 1` points around them
/// ([`starts`]).
pub const STARTS: usize = 4;

/// How far [`starts`] spreads its points around the base, a fraction of each range.
pub const START_SPREAD: f64 = 0.5;

/// `n` starts in the scaled box: `u0`, then points of Roberts' low-discrepancy sequence
/// (`frac(½ + j·α_i)`, `α_i = φ_d^-(i+1)`, `φ_d` the root of `x^(d+1) = x + 1`)
/// scaled by [`START_SPREAD`] around `u0` and clamped into the box: deterministic, for
/// any number of parameters, spread evenly.
pub fn starts(u0: &[f64], n: usize) -> Vec<Vec<f64>> {
    let d = u0.len();
    let mut phi = 2.0_f64;
    for _ in 0..64 {
        phi = (1.0 + phi).powf(1.0 / (d as f64 + 1.0));
    }
    (0..n)
        .map(|j| {
            u0.iter()
                .enumerate()
                .map(|(i, &u)| {
                    if j == 0 {
                        return u;
                    }
                    let alpha = phi.powi(-(i as i32 + 1));
                    let r = (0.5 + j as f64 * alpha).fract();
                    (u + START_SPREAD * (r - 0.5)).clamp(0.0, 1.0)
                })
                .collect()
        })
        .collect()
}

/// The continuous encoder signals of a replay: per state, the twin's crank and shaft
/// angle in counts through the encoder law (without its `floor`).
struct Angles {
    first_crank: i64,
    law: Option<EncoderLaw>,
    counts: Vec<(f64, f64)>,
}

impl Observer<f64> for Angles {
    fn on_state(&mut self, state: State<'_, f64>) {
        let State::Converter(twin) = state else {
            return;
        };
        let law = *self
            .law
            .get_or_insert_with(|| EncoderLaw::new(twin, self.first_crank));
        let per_count = std::f64::consts::TAU / f64::from(COUNTS_PER_TURN);
        self.counts.push((
            twin.link(1).theta / per_count + law.crank_offset as f64,
            law.shaft_sign * twin.shaft_angle() / per_count,
        ));
    }
}

/// One replay of a trial: its residuals and summary.
pub struct Trial {
    /// Crank residuals (twin - the measured count's middle), counts, a sample each.
    pub crank: Vec<f64>,
    /// Shaft residuals, counts.
    pub shaft: Vec<f64>,
    /// Per pair of events: the time difference / [`EVENT_SCALE`], or [`EVENT_MISMATCH`].
    pub events: Vec<f64>,
    /// The replay's summary (its integer residuals and the pairs of events).
    pub summary: ReplaySummary,
}

impl Trial {
    /// Every residual, in one vector.
    pub fn residuals(&self) -> Vec<f64> {
        let mut r = self.crank.clone();
        r.extend(&self.shaft);
        r.extend(&self.events);
        r
    }

    /// The sum of the squared residuals.
    pub fn cost(&self) -> f64 {
        self.residuals().iter().map(|r| r * r).sum()
    }
}

/// The fitting problem: the base converter, the log, the parameters set free.
pub struct Problem<'a> {
    /// The converter the trials start from.
    pub base: CccScenario,
    /// Its name in messages.
    pub name: String,
    /// The bench log.
    pub log: &'a BenchLog,
    /// The machine's clutch log.
    pub clutch: Option<&'a ClutchLog>,
    /// The free parameters.
    pub free: Vec<Param>,
    /// Their bounds.
    pub bounds: Vec<(f64, f64)>,
    /// The stages of the search: how many of `free` (the first ones) each searches,
    /// increasing, the last all of them (see the module's "stages").
    pub stages: Vec<usize>,
    /// Trials replayed (shared with the progress lines).
    evaluations: Rc<Cell<u64>>,
}

impl<'a> Problem<'a> {
    /// The problem of fitting `free` in `base` to `log` (and `clutch`).
    pub fn new(
        name: &str,
        base: CccScenario,
        log: &'a BenchLog,
        clutch: Option<&'a ClutchLog>,
        free: Vec<Param>,
    ) -> Problem<'a> {
        let bounds = free
            .iter()
            .map(|p| p.bounds(p.get(&base.converter)))
            .collect();
        let stages = vec![free.len()];
        Problem {
            base,
            name: name.to_string(),
            log,
            clutch,
            free,
            bounds,
            stages,
            evaluations: Rc::new(Cell::new(0)),
        }
    }

    /// The problem searched in stages: the first `stages[0]` parameters, then the
    /// first `stages[1]` from their best, and so on (counts that do not increase, or
    /// past the parameters, are dropped; all of them are searched last).
    pub fn in_stages(mut self, stages: &[usize]) -> Self {
        let n = self.free.len();
        let mut kept: Vec<usize> = Vec::new();
        for &k in stages {
            if k > 0 && k < n && kept.last().is_none_or(|last| k > *last) {
                kept.push(k);
            }
        }
        kept.push(n);
        self.stages = kept;
        self
    }

    /// The problem of the first `k` free parameters, the others held at `values`
    /// (all of them, in `free`'s order): the same bounds, the same log.
    fn first(&self, k: usize, values: &[f64]) -> Problem<'a> {
        Problem {
            base: self.settings(values),
            name: self.name.clone(),
            log: self.log,
            clutch: self.clutch,
            free: self.free.iter().take(k).copied().collect(),
            bounds: self.bounds.iter().take(k).copied().collect(),
            stages: vec![k],
            evaluations: Rc::clone(&self.evaluations),
        }
    }

    /// The same problem over `log` and `clutch` (a head of the log), counting its
    /// replays with this one's.
    fn over<'b>(&self, log: &'b BenchLog, clutch: Option<&'b ClutchLog>) -> Problem<'b> {
        Problem {
            base: self.base.clone(),
            name: self.name.clone(),
            log,
            clutch,
            free: self.free.clone(),
            bounds: self.bounds.clone(),
            stages: self.stages.clone(),
            evaluations: Rc::clone(&self.evaluations),
        }
    }

    /// The base values of the free parameters.
    pub fn base_values(&self) -> Vec<f64> {
        self.free
            .iter()
            .map(|p| p.get(&self.base.converter))
            .collect()
    }

    /// The converter with the free parameters at `values`.
    pub fn settings(&self, values: &[f64]) -> CccScenario {
        let mut s = self.base.clone();
        for (p, v) in self.free.iter().zip(values) {
            p.set(&mut s.converter, *v);
        }
        s
    }

    /// Replays the log with the free parameters at `values`.
    pub fn trial(&self, values: &[f64]) -> Result<Trial, RunError> {
        self.evaluations.set(self.evaluations.get() + 1);
        let mut angles = Angles {
            first_crank: self.log.crank.first().copied().unwrap_or(0),
            law: None,
            counts: Vec::with_capacity(self.log.len()),
        };
        let summary = replay::simulate::<f64>(
            &self.name,
            self.settings(values),
            self.log,
            self.clutch,
            &mut angles,
        )?;
        // Past a failed step (or a jam) the twin stands where it stopped.
        let last = angles
            .counts
            .last()
            .copied()
            .unwrap_or((f64::NAN, f64::NAN));
        let at = |k: usize| angles.counts.get(k).copied().unwrap_or(last);
        let middle = |m: i64| m as f64 + 0.5;
        let crank = (0..self.log.len())
            .map(|k| at(k).0 - middle(self.log.crank[k]))
            .collect();
        let shaft = (0..self.log.len())
            .map(|k| at(k).1 - middle(self.log.shaft[k]))
            .collect();
        let events = summary.matching.as_ref().map_or_else(Vec::new, |m| {
            m.pairs
                .iter()
                .map(|p| match p.dt() {
                    Some(dt) if p.same() => dt / EVENT_SCALE,
                    _ => EVENT_MISMATCH,
                })
                .collect()
        });
        Ok(Trial {
            crank,
            shaft,
            events,
            summary,
        })
    }

    /// The values of scaled coordinates `u` (0 at each lower bound, 1 at the upper).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(u)
            .map(|(&(lo, hi), &u)| lo + (hi - lo) * u)
            .collect()
    }

    /// The scaled coordinates of `values`.
    pub fn scaled(&self, values: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(values)
            .map(|(&(lo, hi), &v)| if hi > lo { (v - lo) / (hi - lo) } else { 0.0 })
            .collect()
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Vec<f64>) -> Result<f64, ArgminError> {
        // SIGINT or SIGTERM: the search stops here (a replay stopped at its start would
        // cost the same at any values, and the search would end on it as converged).
        if interrupt::requested() {
            return Err(ArgminError::msg("interrupted"));
        }
        let inside: Vec<f64> = u.iter().map(|x| x.clamp(0.0, 1.0)).collect();
        let out: f64 = u.iter().zip(&inside).map(|(a, b)| (a - b) * (a - b)).sum();
        let cost = match self.trial(&self.values(&inside)) {
            Ok(t) => t.cost(),
            Err(_) => SETUP_FAILED,
        };
        // A NaN (a twin that failed at its first state) is the worst cost, not a
        // value the simplex's ordering would misplace.
        let cost = if cost.is_finite() { cost } else { SETUP_FAILED };
        Ok(cost + OUT_OF_BOUNDS * out)
    }
}

/// Draws a line on `stderr` every `every`-th iteration: the best cost so far and the
/// replays done.
struct ProgressLines {
    evaluations: Rc<Cell<u64>>,
    max_iters: u64,
}

impl<I: argmin::core::State<Float = f64>> Observe<I> for ProgressLines {
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), ArgminError> {
        let _ = writeln!(
            std::io::stderr(),
            "host-sim: identify: iteration {} of at most {}, best cost {}, {} replays",
            state.get_iter(),
            self.max_iters,
            Sci(state.get_best_cost()),
            self.evaluations.get()
        );
        Ok(())
    }
}

/// One identified parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Identified {
    /// Which.
    pub param: Param,
    /// The base file's value.
    pub base: f64,
    /// The search's bounds.
    pub bounds: (f64, f64),
    /// The value found.
    pub value: f64,
    /// Its standard uncertainty (Gauss-Newton), `NaN` when `JᵀJ` is singular.
    pub sigma: f64,
}

/// What an identification found.
pub struct Fit {
    /// The parameters, as given.
    pub params: Vec<Identified>,
    /// The cost at the base values and at the optimum.
    pub cost: (f64, f64),
    /// The residual standard deviation `s`, counts (or scaled event units).
    pub s: f64,
    /// Residuals.
    pub residuals: usize,
    /// Nelder-Mead's iterations.
    pub iterations: u64,
    /// Replays (the search's and the Jacobian's).
    pub replays: u64,
    /// Why the search ended.
    pub termination: String,
    /// The replay at the optimum.
    pub replay: ReplaySummary,
}

/// Fits `problem`'s free parameters, at most `max_iters` Nelder-Mead iterations;
/// progress lines on `stderr` every 10 iterations unless `quiet`.
pub fn fit(problem: Problem<'_>, max_iters: u64, quiet: bool) -> Result<Fit, RunError> {
    let base = problem.base_values();
    let start_trial = problem.trial(&base)?;
    let u0: Vec<f64> = problem
        .scaled(&base)
        .iter()
        .map(|u| u.clamp(0.0, 1.0))
        .collect();
    let evaluations = Rc::clone(&problem.evaluations);
    let mut best_u = u0;
    let mut search = Search {
        iterations: 0,
        termination: String::new(),
        max_iters,
        quiet,
    };
    // The whole log's cost at `best_u`: a stage's result is taken only if it improves
    // on its start (the last stage's best, a point of its problem too). Each stage is
    // the problem of its first `k` parameters, the others at the best so far (the last
    // stage's is the whole problem: every parameter free, the same bounds and costs).
    let mut best_cost = f64::INFINITY;
    let n = best_u.len();
    for k in problem.stages.clone() {
        if !quiet && problem.stages.len() > 1 {
            let _ = writeln!(
                std::io::stderr(),
                "host-sim: identify: the first {k} of the {n} parameters"
            );
        }
        let inside: Vec<f64> = best_u.iter().map(|x| x.clamp(0.0, 1.0)).collect();
        let stage = problem.first(k, &problem.values(&inside));
        let (_, u, cost) = search.horizons(stage, best_u.iter().take(k).copied().collect())?;
        if cost < best_cost {
            best_cost = cost;
            for (b, u) in best_u.iter_mut().zip(u) {
                *b = u;
            }
        }
    }
    let Search {
        iterations,
        termination,
        ..
    } = search;
    let inside: Vec<f64> = best_u.iter().map(|x| x.clamp(0.0, 1.0)).collect();
    let values = problem.values(&inside);
    let best = problem.trial(&values)?;
    let sigmas = uncertainty(&problem, &values, &best)?;
    let r = best.residuals();
    let dof = r.len().saturating_sub(values.len()).max(1);
    let s = (best.cost() / dof as f64).sqrt();
    let params = problem
        .free
        .iter()
        .zip(&base)
        .zip(&problem.bounds)
        .zip(values.iter().zip(&sigmas))
        .map(|(((p, b), bd), (v, sg))| Identified {
            param: *p,
            base: *b,
            bounds: *bd,
            value: *v,
            sigma: *sg,
        })
        .collect();
    Ok(Fit {
        params,
        cost: (start_trial.cost(), best.cost()),
        s,
        residuals: r.len(),
        iterations,
        replays: evaluations.get(),
        termination,
        replay: best.summary,
    })
}

/// The Nelder-Mead searches of [`fit`], their iterations and how each ended.
struct Search {
    iterations: u64,
    termination: String,
    max_iters: u64,
    quiet: bool,
}

impl Search {
    /// Searches `problem` from the scaled point `start` over the log's [`HORIZONS`] in
    /// turn, the first from [`STARTS`] starts around it (see the module's "horizons");
    /// returns the problem, the best point and its cost over the whole log.
    fn horizons<'b>(
        &mut self,
        problem: Problem<'b>,
        start: Vec<f64>,
    ) -> Result<(Problem<'b>, Vec<f64>, f64), RunError> {
        let quiet = self.quiet;
        let mut problem = problem;
        let mut best_u = start;
        let mut cost = f64::INFINITY;
        let whole = problem.log.len();
        for (k, horizon) in HORIZONS.into_iter().enumerate() {
            let n = ((whole as f64 * horizon).round() as usize).clamp(2, whole);
            if n < whole {
                let log = problem.log.head(n);
                let clutch = problem.clutch.map(|c| c.until(log.duration()));
                if !quiet {
                    let _ = writeln!(
                        std::io::stderr(),
                        "host-sim: identify: the log's first {:.3} s",
                        log.duration()
                    );
                }
                let mut stage = problem.over(&log, clutch.as_ref());
                // The first horizon from several starts, the best of them on: where
                // the residuals are cheapest (a fraction of the log) and the valleys
                // fewest.
                let mut best: Option<(f64, Vec<f64>)> = None;
                let starts = if k == 0 {
                    starts(&best_u, STARTS)
                } else {
                    vec![best_u.clone()]
                };
                for start in starts {
                    let (u, cost);
                    (stage, u, cost) = self.run(stage, start)?;
                    if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                        best = Some((cost, u));
                    }
                }
                if let Some((_, u)) = best {
                    best_u = u;
                }
            } else {
                if !quiet && HORIZONS.len() > 1 {
                    let _ = writeln!(std::io::stderr(), "host-sim: identify: the whole log");
                }
                (problem, best_u, cost) = self.run(problem, best_u)?;
            }
        }
        Ok((problem, best_u, cost))
    }

    /// Searches `problem` from the scaled point `start`: a search with a simplex of
    /// [`RESTART_STEPS`]`[0]`, then one restarted from its best with `[1]` (a collapsed
    /// simplex is Nelder-Mead's known failure on a narrow valley). Returns the problem,
    /// the best point and its cost (the search's own, no replay more).
    fn run<'b>(
        &mut self,
        problem: Problem<'b>,
        start: Vec<f64>,
    ) -> Result<(Problem<'b>, Vec<f64>, f64), RunError> {
        let (max_iters, quiet) = (self.max_iters, self.quiet);
        let evaluations = Rc::clone(&problem.evaluations);
        let mut problem = problem;
        let mut best_u = start;
        let mut best_cost = f64::INFINITY;
        for step in RESTART_STEPS {
            let mut simplex = vec![best_u.clone()];
            for i in 0..best_u.len() {
                let mut v = best_u.clone();
                // Into the box: up from the lower half, down from the upper.
                v[i] += if v[i] + step <= 1.0 { step } else { -step };
                simplex.push(v);
            }
            let solver = NelderMead::new(simplex)
                .with_sd_tolerance(COST_TOLERANCE)
                .map_err(|e| RunError::Setup(format!("identify: Nelder-Mead: {e}")))?;
            let mut exec = Executor::new(problem, solver).configure(|s| s.max_iters(max_iters));
            if !quiet {
                exec = exec.add_observer(
                    ProgressLines {
                        evaluations: Rc::clone(&evaluations),
                        max_iters,
                    },
                    ObserverMode::Every(10),
                );
            }
            let mut result = exec.run().map_err(|e| {
                if interrupt::requested() {
                    RunError::Interrupted("identify's search")
                } else {
                    RunError::Setup(format!("identify: the search failed: {e}"))
                }
            })?;
            problem = result.problem.take_problem().ok_or_else(|| {
                RunError::Setup("identify: the search kept its problem".to_string())
            })?;
            let state = &result.state;
            if let Some(b) = state.get_best_param() {
                best_u = b.clone();
                best_cost = state.get_best_cost();
            }
            self.iterations += state.get_iter();
            if !self.termination.is_empty() {
                self.termination.push_str(", then ");
            }
            self.termination
                .push_str(&state.get_termination_status().to_string());
        }
        Ok((problem, best_u, best_cost))
    }
}

/// The most lags of the residuals' autocorrelation summed by [`correlation_factor`].
pub const MAX_LAG: usize = 100;

/// The variance inflation of a mean over correlated residuals `r`, `1 + 2 Σ ρ_k` (ρ_k
/// the lag-k autocorrelation, summed while positive, up to [`MAX_LAG`]): the number of
/// samples over the number of independent ones. An encoder's quantization error is
/// the same for the samples that a slow angle spends in one count, so the residuals
/// are not independent and `s² (JᵀJ)⁻¹` alone understates σ.
pub fn correlation_factor(r: &[f64]) -> f64 {
    let n = r.len();
    if n < 2 {
        return 1.0;
    }
    let mean = r.iter().sum::<f64>() / n as f64;
    let c = |k: usize| -> f64 {
        (0..n - k)
            .map(|i| (r[i] - mean) * (r[i + k] - mean))
            .sum::<f64>()
            / n as f64
    };
    let c0 = c(0);
    if c0 <= 0.0 {
        return 1.0;
    }
    let mut sum = 0.0;
    for k in 1..MAX_LAG.min(n) {
        let rho = c(k) / c0;
        if rho <= 0.0 {
            break;
        }
        sum += rho;
    }
    1.0 + 2.0 * sum
}

/// The Gauss-Newton σ of each value at the optimum `values` (its trial `best`).
fn uncertainty(problem: &Problem<'_>, values: &[f64], best: &Trial) -> Result<Vec<f64>, RunError> {
    let r0 = best.residuals();
    let n = r0.len();
    let p = values.len();
    let mut j = DMatrix::<f64>::zeros(n, p);
    for (i, &(lo, hi)) in problem.bounds.iter().enumerate() {
        let h = JACOBIAN_STEP * (hi - lo);
        // Central differences inside the bounds; one-sided at a bound (a friction
        // coefficient of 0: the twin refuses a negative one).
        let v = values[i];
        let (up, down) = (v + h <= hi, v - h >= lo);
        let (a, b) = match (up, down) {
            (true, true) | (false, false) => (v + h, v - h),
            (true, false) => (v + h, v),
            (false, true) => (v, v - h),
        };
        let at = |x: f64| {
            let mut w = values.to_vec();
            w[i] = x;
            problem.trial(&w).map(|t| t.residuals())
        };
        let (plus, minus) = (at(a)?, at(b)?);
        for k in 0..n {
            j[(k, i)] = match (plus.get(k), minus.get(k)) {
                (Some(p), Some(m)) => (p - m) / (a - b),
                _ => 0.0,
            };
        }
    }
    let dof = n.saturating_sub(p).max(1);
    let s2 = r0.iter().map(|r| r * r).sum::<f64>() / dof as f64
        * correlation_factor(&best.crank).max(correlation_factor(&best.shaft));
    let jtj = j.transpose() * &j;
    Ok(match jtj.try_inverse() {
        Some(inv) => (0..p).map(|i| (s2 * inv[(i, i)]).sqrt()).collect(),
        None => vec![f64::NAN; p],
    })
}
