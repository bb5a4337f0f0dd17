//! A search: the optimizer's generations evaluated on the worker pool, every design at
//! every operating point, the results put back in job order. A design's score over the
//! points: the worst objective (the lowest mean power, the latest breakaway) and the
//! sum of the violations.

use super::evaluate::{evaluate, Evaluation};
use super::evolution::{Evolution, Score, Settings};
use super::file::Design;
use crate::jobs::pool::run_jobs;

/// One evaluated design.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Its generation (0: the initial population).
    pub generation: usize,
    /// Its place in the generation.
    pub member: usize,
    /// The free parameters' values.
    pub x: Vec<f64>,
    /// Its evaluation at each operating point.
    pub evals: Vec<Evaluation>,
    /// Its score.
    pub score: Score,
}

/// A search's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Every design evaluated, in generation and member order.
    pub rows: Vec<Row>,
    /// The best design after each generation (index into `rows`).
    pub history: Vec<usize>,
    /// The best design (index into `rows`), if any was evaluated.
    pub best: Option<usize>,
}

impl Outcome {
    /// The best row.
    pub fn best_row(&self) -> Option<&Row> {
        self.best.and_then(|k| self.rows.get(k))
    }
}

/// The score of a design from its evaluations at every point.
pub fn score(d: &Design, evals: &[Evaluation]) -> Score {
    let violation = evals
        .iter()
        .map(|e| e.violations(&d.constraints).iter().sum::<f64>())
        .sum();
    let objective =
        evals
            .iter()
            .map(|e| e.objective(d.objective))
            .fold(f64::NEG_INFINITY, |m, v| {
                if v.is_nan() || m.is_nan() {
                    f64::NAN
                } else {
                    m.max(v)
                }
            });
    Score {
        violation,
        objective,
    }
}

/// The DE settings of `d`.
pub fn settings(d: &Design) -> Settings {
    Settings {
        bounds: d.free.iter().map(|f| (f.min, f.max)).collect(),
        population: d.search.population,
        generations: d.search.generations,
        weight: d.search.weight,
        crossover: d.search.crossover,
        seed: d.search.seed,
        start: d.start(),
    }
}

/// Evaluates `points` (designs) at every operating point of `d` on `threads`
/// threads: the job `i · P + j` is design `i` at point `j`, the results in job
/// order; `tick(done, total)` as each job finishes.
pub fn evaluate_all(
    d: &Design,
    points: &[Vec<f64>],
    threads: usize,
    tick: &mut dyn FnMut(usize, usize),
) -> Vec<Vec<Evaluation>> {
    let np = d.points.len();
    let jobs: Vec<(usize, usize)> = (0..points.len())
        .flat_map(|i| (0..np).map(move |j| (i, j)))
        .collect();
    let done = run_jobs(
        &jobs,
        threads,
        |_, &(i, j)| evaluate(d, &points[i], &d.points[j]),
        |p, _| tick(p.done, p.total),
    );
    let mut out: Vec<Vec<Evaluation>> = Vec::with_capacity(points.len());
    let mut it = done.into_iter();
    for _ in 0..points.len() {
        out.push(it.by_ref().take(np).collect());
    }
    out
}

/// What evaluates a generation: `(generation, designs)` to each design's evaluations
/// at every point, in the designs' order.
pub type Evaluator<'a> = dyn FnMut(usize, &[Vec<f64>]) -> Vec<Vec<Evaluation>> + 'a;

/// Runs the search of `d` with `evaluate(generation, points)` evaluating each
/// generation (on the pool, or elsewhere: Dask); `report(generation, outcome so far)`
/// after each.
pub fn search_with(
    d: &Design,
    evaluate: &mut Evaluator<'_>,
    report: &mut dyn FnMut(usize, &Outcome),
) -> Outcome {
    let mut de = Evolution::new(settings(d));
    let mut out = Outcome {
        rows: Vec::new(),
        history: Vec::new(),
        best: None,
    };
    while !de.done() {
        let generation = de.generation();
        let points = de.ask();
        let evals = evaluate(generation, &points);
        let scores: Vec<Score> = evals.iter().map(|e| score(d, e)).collect();
        de.tell(&scores);
        for (member, ((x, evals), s)) in points.into_iter().zip(evals).zip(&scores).enumerate() {
            let k = out.rows.len();
            let better = match out.best_row() {
                Some(b) => s.compare(&b.score) == std::cmp::Ordering::Less,
                None => true,
            };
            if better {
                out.best = Some(k);
            }
            out.rows.push(Row {
                generation,
                member,
                x,
                evals,
                score: *s,
            });
        }
        if let Some(b) = out.best {
            out.history.push(b);
        }
        report(generation, &out);
    }
    out
}

/// [`search_with`] on the worker pool.
pub fn search(
    d: &Design,
    threads: usize,
    report: &mut dyn FnMut(usize, &Outcome),
    tick: &mut dyn FnMut(usize, usize),
) -> Outcome {
    search_with(
        d,
        &mut |_, points| evaluate_all(d, points, threads, tick),
        report,
    )
}

/// The search of `d` replayed from the scores of its generations so far (`history[g]`:
/// generation `g`'s scores in member order): the optimizer in the state after them,
/// ready to `ask` the next generation. The optimizer depends on nothing but its seed
/// and the scores, so a driver that keeps only the scores (Dask's, in the Python
/// package) gets the same designs as [`search`].
pub fn replay(d: &Design, history: &[Vec<Score>]) -> Evolution {
    let mut de = Evolution::new(settings(d));
    for scores in history {
        if de.done() {
            break;
        }
        let _ = de.ask();
        de.tell(scores);
    }
    de
}
