//! Differential evolution (Storn & Price 1997, the DE/rand/1/bin scheme), seeded, in
//! ask/tell form: [`Evolution::ask`] hands out a generation's points, the caller
//! evaluates them anywhere (host-sim's thread pool, Dask workers) and gives the scores
//! back in the same order to [`Evolution::tell`]. Nothing in the search depends on
//! where or in which order the points were evaluated, so the same seed gives the same
//! designs, bit for bit.
//!
//! Why not the `cmaes` crate: its generations are evaluated inside `CMAES::next` /
//! `run_parallel` (rayon) by a closure; a generation cannot be handed to Dask and
//! put back. argmin's population solvers have the same shape. DE is a few lines on
//! top of a seeded generator (`oorandom`, PCG).
//!
//! Constraints (Deb 2000, "An efficient constraint handling method for genetic
//! algorithms"): a [`Score`] is a total violation (0: feasible) and an objective to
//! minimise; a feasible score beats every infeasible one, two feasible ones compare by
//! objective, two infeasible ones by violation. No penalty weight to tune: every
//! infeasible design ranks below every feasible one, by how far it is from feasible.
//!
//! The search works in the unit cube (each parameter scaled by its bounds); a trial
//! coordinate that leaves the box is put halfway between its parent's and the bound it
//! crossed (bounce-back), so every point handed out is inside the bounds.

use oorandom::Rand64;
use std::cmp::Ordering;

/// A design's score: its total constraint violation and its objective (minimised).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    /// Sum of the constraints' violations, each ≥ 0; 0 when every constraint holds.
    pub violation: f64,
    /// The objective, minimised (only compared between feasible scores).
    pub objective: f64,
}

impl Score {
    /// A feasible score of `objective`.
    pub fn feasible(objective: f64) -> Score {
        Score {
            violation: 0.0,
            objective,
        }
    }

    /// Whether every constraint holds and the objective is a number.
    pub fn is_feasible(&self) -> bool {
        self.violation == 0.0 && self.objective.is_finite()
    }

    /// Deb's order: `Less` when `self` is better than `other`. A non-finite
    /// violation (an evaluation that gave nothing) ranks below every finite one.
    pub fn compare(&self, other: &Score) -> Ordering {
        match (self.is_feasible(), other.is_feasible()) {
            (true, true) => self.objective.total_cmp(&other.objective),
            (true, false) => Ordering::Less,
            (false, true) => Ordering::Greater,
            (false, false) => self.rank_violation().total_cmp(&other.rank_violation()),
        }
    }

    fn rank_violation(&self) -> f64 {
        if self.violation.is_finite() && self.violation > 0.0 {
            self.violation
        } else if self.violation == 0.0 {
            // Feasible constraints with a non-finite objective: the least infeasible.
            f64::MIN_POSITIVE
        } else {
            f64::INFINITY
        }
    }
}

/// The settings of a search.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Lower and upper bound of each parameter (`lo < hi`).
    pub bounds: Vec<(f64, f64)>,
    /// Points per generation (at least 4: DE/rand/1 draws three others).
    pub population: usize,
    /// Generations after the initial one.
    pub generations: usize,
    /// The differential weight F (0..=2; 0.5 to 0.8 usual).
    pub weight: f64,
    /// The crossover rate CR (0..=1).
    pub crossover: f64,
    /// The generator's seed.
    pub seed: u64,
    /// A point of the initial population (e.g. the reference design), if any: it
    /// replaces the first random point.
    pub start: Option<Vec<f64>>,
}

/// A search under way.
#[derive(Clone, Debug)]
pub struct Evolution {
    settings: Settings,
    rng: Rand64,
    /// The population, in unit coordinates, and its scores (empty before the first
    /// `tell`).
    points: Vec<Vec<f64>>,
    scores: Vec<Score>,
    /// The points handed out by the last `ask`, in unit coordinates.
    asked: Vec<Vec<f64>>,
    generation: usize,
    best: Option<(Vec<f64>, Score)>,
}

impl Evolution {
    /// A new search: the initial population drawn uniformly in the bounds (at least
    /// 4 members: a trial needs three others).
    pub fn new(mut settings: Settings) -> Evolution {
        settings.population = settings.population.max(4);
        Evolution {
            rng: Rand64::new(u128::from(settings.seed)),
            settings,
            points: Vec::new(),
            scores: Vec::new(),
            asked: Vec::new(),
            generation: 0,
            best: None,
        }
    }

    /// The generation the next `ask` hands out (0: the initial population).
    pub fn generation(&self) -> usize {
        self.generation
    }

    /// Whether every generation has been told.
    pub fn done(&self) -> bool {
        self.generation > self.settings.generations
    }

    /// The next generation's points, in the parameters' units: the initial population
    /// first, then one trial per member (DE/rand/1/bin).
    pub fn ask(&mut self) -> Vec<Vec<f64>> {
        let n = self.settings.bounds.len();
        let np = self.settings.population;
        self.asked = if self.points.is_empty() {
            let mut pop: Vec<Vec<f64>> = (0..np)
                .map(|_| (0..n).map(|_| self.rng.rand_float()).collect())
                .collect();
            if let (Some(start), Some(first)) = (&self.settings.start, pop.first_mut()) {
                *first = self.in_unit(start);
            }
            pop
        } else {
            (0..np).map(|i| self.trial(i)).collect()
        };
        self.asked.iter().map(|u| self.in_bounds(u)).collect()
    }

    /// The scores of the points of the last `ask`, in its order: each trial replaces
    /// its parent unless the parent is better (a tie goes to the trial, which lets the
    /// population drift across flat regions).
    pub fn tell(&mut self, scores: &[Score]) {
        let asked = std::mem::take(&mut self.asked);
        if self.points.is_empty() {
            self.points = asked;
            self.scores = scores.to_vec();
        } else {
            for (i, (u, s)) in asked.into_iter().zip(scores).enumerate() {
                if let (Some(p), Some(ps)) = (self.points.get_mut(i), self.scores.get_mut(i)) {
                    if s.compare(ps) != Ordering::Greater {
                        *p = u;
                        *ps = *s;
                    }
                }
            }
        }
        for (u, s) in self.points.iter().zip(&self.scores) {
            let better = match &self.best {
                Some((_, b)) => s.compare(b) == Ordering::Less,
                None => true,
            };
            if better {
                self.best = Some((u.clone(), *s));
            }
        }
        self.generation += 1;
    }

    /// The best point so far (parameters' units) and its score; the first of equals in
    /// population order.
    pub fn best(&self) -> Option<(Vec<f64>, Score)> {
        self.best.as_ref().map(|(u, s)| (self.in_bounds(u), *s))
    }

    /// Member `i`'s trial: `a + F·(b − c)` of three distinct others, crossed over
    /// with the member (at least one coordinate from the mutant), bounced back into
    /// the box.
    fn trial(&mut self, i: usize) -> Vec<f64> {
        let np = self.points.len();
        let pick = |taken: &[usize], rng: &mut Rand64| loop {
            let k = rng.rand_range(0..np as u64) as usize;
            if !taken.contains(&k) {
                break k;
            }
        };
        let a = pick(&[i], &mut self.rng);
        let b = pick(&[i, a], &mut self.rng);
        let c = pick(&[i, a, b], &mut self.rng);
        let n = self.settings.bounds.len();
        let forced = self.rng.rand_range(0..n.max(1) as u64) as usize;
        let (pa, pb, pc, pi) = (
            &self.points[a],
            &self.points[b],
            &self.points[c],
            &self.points[i],
        );
        let mut out = Vec::with_capacity(n);
        for j in 0..n {
            let cross = self.rng.rand_float() < self.settings.crossover || j == forced;
            let v = if cross {
                pa[j] + self.settings.weight * (pb[j] - pc[j])
            } else {
                pi[j]
            };
            out.push(if v < 0.0 {
                0.5 * pi[j]
            } else if v > 1.0 {
                0.5 * (pi[j] + 1.0)
            } else {
                v
            });
        }
        out
    }

    fn in_bounds(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(&self.settings.bounds)
            .map(|(x, (lo, hi))| lo + x * (hi - lo))
            .collect()
    }

    fn in_unit(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(&self.settings.bounds)
            .map(|(v, (lo, hi))| ((v - lo) / (hi - lo)).clamp(0.0, 1.0))
            .collect()
    }
}

/// Runs a whole search with `evaluate` scoring a generation (its points in order),
/// calling `generation(k, best)` after each; returns the best point and score.
pub fn minimise(
    settings: Settings,
    mut evaluate: impl FnMut(&[Vec<f64>]) -> Vec<Score>,
    mut generation: impl FnMut(usize, &(Vec<f64>, Score)),
) -> Option<(Vec<f64>, Score)> {
    let mut de = Evolution::new(settings);
    while !de.done() {
        let k = de.generation();
        let points = de.ask();
        let scores = evaluate(&points);
        de.tell(&scores);
        if let Some(b) = de.best() {
            generation(k, &b);
        }
    }
    de.best()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(bounds: Vec<(f64, f64)>, population: usize, generations: usize) -> Settings {
        Settings {
            bounds,
            population,
            generations,
            weight: 0.7,
            crossover: 0.9,
            seed: 7,
            start: None,
        }
    }

    // Rosenbrock's valley, f = (1 − x)² + 100 (y − x²)²: the minimum 0 at (1, 1)
    // (Rosenbrock 1960), a curved narrow valley that defeats coordinate searches.
    #[test]
    fn rosenbrock_reaches_its_minimum() {
        let f = |p: &[f64]| (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2);
        let (best, score) = minimise(
            settings(vec![(-2.0, 2.0), (-1.0, 3.0)], 30, 300),
            |pts| pts.iter().map(|p| Score::feasible(f(p))).collect(),
            |_, _| {},
        )
        .expect("a best point");
        assert!((best[0] - 1.0).abs() < 1e-3, "{best:?}");
        assert!((best[1] - 1.0).abs() < 2e-3, "{best:?}");
        assert!(score.objective < 1e-6, "{score:?}");
    }

    // min (x − 2)² + (y − 1)² subject to x + y ≤ 2: the unconstrained minimum (2, 1)
    // is infeasible, the constrained one is its projection onto the line x + y = 2,
    // (1.5, 0.5), with f = 0.5 (Lagrange: ∇f = λ·(1, 1)).
    #[test]
    fn constrained_quadratic_reaches_the_projection() {
        let (best, score) = minimise(
            settings(vec![(-3.0, 3.0), (-3.0, 3.0)], 24, 200),
            |pts| {
                pts.iter()
                    .map(|p| Score {
                        violation: (p[0] + p[1] - 2.0).max(0.0),
                        objective: (p[0] - 2.0).powi(2) + (p[1] - 1.0).powi(2),
                    })
                    .collect()
            },
            |_, _| {},
        )
        .expect("a best point");
        assert!(score.is_feasible(), "{score:?}");
        assert!((best[0] - 1.5).abs() < 1e-3, "{best:?}");
        assert!((best[1] - 0.5).abs() < 1e-3, "{best:?}");
        assert!((score.objective - 0.5).abs() < 1e-5, "{score:?}");
    }

    // Deb's order: every feasible score beats every infeasible one whatever their
    // objectives; infeasible ones rank by violation; an evaluation that gave nothing
    // (NaN) is the worst.
    #[test]
    fn feasible_beats_infeasible() {
        let good = Score::feasible(1e9);
        let bad = Score {
            violation: 1e-12,
            objective: -1e9,
        };
        let worse = Score {
            violation: 2.0,
            objective: -1e12,
        };
        let nothing = Score {
            violation: f64::NAN,
            objective: f64::NAN,
        };
        assert_eq!(good.compare(&bad), Ordering::Less);
        assert_eq!(bad.compare(&worse), Ordering::Less);
        assert_eq!(worse.compare(&nothing), Ordering::Less);
        assert_eq!(
            Score::feasible(1.0).compare(&Score::feasible(2.0)),
            Ordering::Less
        );
    }

    // Every point handed out lies inside the bounds, and the same seed gives the same
    // points (the search depends on nothing but the seed and the scores).
    #[test]
    fn points_inside_bounds_and_seeded() {
        let bounds = vec![(0.1, 0.2), (-5.0, 5.0), (100.0, 1000.0)];
        let run = || {
            let mut de = Evolution::new(settings(bounds.clone(), 8, 5));
            let mut all = Vec::new();
            while !de.done() {
                let pts = de.ask();
                for p in &pts {
                    for (x, (lo, hi)) in p.iter().zip(&bounds) {
                        assert!(lo <= x && x <= hi, "{x} outside {lo}..{hi}");
                    }
                }
                // A steep score pushes trials out of the box often.
                let s: Vec<Score> = pts.iter().map(|p| Score::feasible(-p[1] * 1e3)).collect();
                de.tell(&s);
                all.extend(pts);
            }
            all
        };
        let (a, b) = (run(), run());
        assert_eq!(a.len(), 6 * 8);
        assert!(a
            .iter()
            .zip(&b)
            .all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits())));
    }
}
