//! Step-time benches of the core (criterion, `harness = false`):
//!
//! - `dp5_step/{slider_crank,five_bar}/{f64,f32}`: one fixed-step DP5 step
//!   ([`Simulation::step`]: 6 evaluations of the equations of motion, FSAL);
//! - `eom/{slider_crank,five_bar}/{f64,f32}`: one evaluation of the equations of motion
//!   ([`dynamics::forward`]: kinematics, `V`, `a_b`, `F`, `VᵀMV`, Cholesky);
//! - `kinetostatics/{slider_crank,five_bar}/{f64,f32}`: one kinetostatics call
//!   ([`Simulation::kinetostatics`]: joint reactions and driving torques);
//! - `energy_check/{slider_crank,five_bar}/{checked,plain}` (f64): 100 steps of
//!   [`Simulation::step`] with the energy balance checked (the local-error check off)
//!   against 100 bare [`Dp5::step`]s from the same state: the check's cost.
//!
//! **Reading the `dp5_step` numbers.** One iteration is [`STEPS`] = 100 consecutive steps
//! from a cloned, warmed-up simulation (the five-bar under its constant torque speeds up
//! without bound, so it is never stepped far from its prepared state), measured with
//! `iter_batched` (the clone is not timed). The `time:` column is therefore per 100
//! steps: **ns/step = time / 100** (e.g. `120 µs` → 1.2 µs/step), and the `thrpt:`
//! column, set by `Throughput::Elements(100)`, is steps per second. The `eom` and
//! `kinetostatics` numbers are per call.
//!
//! Prepared states: the slider-crank (h = 10 ms) after 2 s, when it runs its periodic
//! motion; the five-bar (h = 1 ms) at t = 0.5 s. `eom` re-evaluates the same state every
//! iteration (the Newton position pass is warm-started at the solution, so it is a
//! lower bound of an evaluation inside a step).
//!
//! Run: `cargo bench --bench step` (bench profile: release, thin LTO); a filter selects,
//! e.g. `cargo bench --bench step -- five_bar/f64`.

use criterion::{criterion_group, criterion_main, BatchSize, Bencher, Criterion, Throughput};
use nalgebra::SVector;
use std::hint::black_box;
use std::time::Duration;
use structomat::config::{MAX_DOF, STATE_DIM};
use structomat::dynamics;
use structomat::integrator::Dp5;
use structomat::mechanisms::{five_bar, slider_crank, Scenario};
use structomat::simulation::Equations;
use structomat::{Real, Simulation};

/// Steps per timed iteration of the `dp5_step` benches.
const STEPS: u64 = 100;

/// A mechanism under test: its name, its scenario and the time it is advanced to
/// before measuring.
struct Case<T: Real> {
    name: &'static str,
    scenario: Scenario<T>,
    warm_up: f64,
}

fn cases<T: Real>() -> [Case<T>; 2] {
    [
        Case {
            name: "slider_crank",
            scenario: slider_crank::<T>().unwrap_or_else(|e| panic!("slider-crank model: {e}")),
            warm_up: 2.0,
        },
        Case {
            name: "five_bar",
            scenario: five_bar::<T>().unwrap_or_else(|e| panic!("five-bar model: {e}")),
            warm_up: 0.5,
        },
    ]
}

/// The case's simulation advanced to (the first step at or past) `warm_up` seconds.
fn prepared<T: Real>(case: &Case<T>) -> Simulation<T> {
    let mut sim = case
        .scenario
        .simulation()
        .unwrap_or_else(|e| panic!("{}: setup: {e}", case.name));
    // Fixed step count (not a time comparison) so f64 and f32 land on the same step.
    let n = (case.warm_up / case.scenario.h.to_f64()).round() as u64;
    for _ in 0..n {
        step(&mut sim, case.name);
    }
    sim
}

#[inline(always)]
fn step<T: Real>(sim: &mut Simulation<T>, name: &str) {
    if let Err(e) = sim.step() {
        panic!("{name}: step at t = {}: {e}", sim.time());
    }
}

/// Times [`STEPS`] steps of a clone of `sim` (the clone not timed).
fn steps_of<T: Real>(b: &mut Bencher<'_>, sim: &Simulation<T>, name: &str) {
    b.iter_batched(
        || sim.clone(),
        |mut s| {
            for _ in 0..STEPS {
                step(&mut s, name);
            }
            black_box(s)
        },
        BatchSize::SmallInput,
    )
}

fn bench_type<T: Real>(c: &mut Criterion, ty: &str) {
    let cases = cases::<T>();
    let sims: Vec<Simulation<T>> = cases.iter().map(prepared).collect();

    let mut g = c.benchmark_group("dp5_step");
    g.throughput(Throughput::Elements(STEPS));
    for (case, sim) in cases.iter().zip(&sims) {
        g.bench_function(format!("{}/{ty}", case.name), |b| {
            steps_of(b, sim, case.name)
        });
    }
    g.finish();

    let mut g = c.benchmark_group("eom");
    for (case, sim) in cases.iter().zip(&sims) {
        let model = sim.model().clone();
        let mut ws = sim.workspace().clone();
        let (t, q, qd) = (sim.time(), sim.q().to_vec(), sim.qd().to_vec());
        g.bench_function(format!("{}/{ty}", case.name), |b| {
            b.iter(|| {
                let r = dynamics::forward(
                    black_box(&model),
                    &mut ws,
                    black_box(t),
                    black_box(&q),
                    black_box(&qd),
                );
                if let Err(e) = r {
                    panic!("{}: equations of motion: {e}", case.name);
                }
                black_box(&ws.qdd);
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("kinetostatics");
    for (case, sim) in cases.iter().zip(&sims) {
        let mut sim = sim.clone();
        g.bench_function(format!("{}/{ty}", case.name), |b| {
            b.iter(|| match black_box(&mut sim).kinetostatics() {
                Ok(ws) => {
                    black_box(&ws.reactions);
                }
                Err(e) => panic!("{}: kinetostatics: {e}", case.name),
            })
        });
    }
    g.finish();
}

/// The cost of the energy check: `energy_check/{case}/{checked,plain}`, 100 steps from
/// the same prepared state, [`Simulation::step`] with the local-error check off (the
/// energy balance only: metered work, K + V, the residual) against the bare
/// [`Dp5::step`] on the same equations, integrator (FSAL stage) and workspace. No step
/// of the window is redone in sub-steps (checked here), so the difference is the check.
fn bench_energy_check(c: &mut Criterion) {
    let mut g = c.benchmark_group("energy_check");
    g.throughput(Throughput::Elements(STEPS));
    for case in cases::<f64>() {
        // From the case's prepared state, else from 0.1 s (the five-bar's spin-up
        // already redoes steps for the balance at 0.5 s), else from the start: the
        // first whose window redoes no step.
        let h = case.scenario.h;
        let sim = [case.warm_up, 0.1, 0.0]
            .into_iter()
            .find_map(|warm_up| {
                let mut sim = case.scenario.simulation().unwrap();
                sim.set_local_tolerance(f64::INFINITY, 0.0).unwrap();
                for _ in 0..(warm_up / h).round() as u64 {
                    step(&mut sim, case.name);
                }
                let mut probe = sim.clone();
                let before = probe.balance().redone;
                for _ in 0..STEPS {
                    step(&mut probe, case.name);
                }
                (probe.balance().redone == before).then_some(sim)
            })
            .unwrap_or_else(|| panic!("{}: every window redoes a step", case.name));
        println!("energy_check/{}: from t = {} s", case.name, sim.time());
        g.bench_function(format!("{}/checked", case.name), |b| {
            steps_of(b, &sim, case.name)
        });
        let m = sim.model().dof();
        let mut y = SVector::<f64, STATE_DIM>::zeros();
        for k in 0..m {
            y[k] = sim.q()[k];
            y[MAX_DOF + k] = sim.qd()[k];
        }
        let start = (
            sim.integrator().clone(),
            sim.workspace().clone(),
            sim.time(),
            y,
        );
        let model = sim.model();
        g.bench_function(format!("{}/plain", case.name), |b| {
            b.iter_batched(
                || start.clone(),
                |(mut dp5, mut ws, mut t, mut y): (Dp5<f64, STATE_DIM>, _, _, _)| {
                    let mut sys = Equations { model, ws: &mut ws };
                    for _ in 0..STEPS {
                        dp5.step(&mut sys, &mut t, &mut y, h).unwrap();
                    }
                    black_box((dp5, t, y))
                },
                BatchSize::SmallInput,
            )
        });
    }
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_type::<f64>(c, "f64");
    bench_type::<f32>(c, "f32");
    bench_energy_check(c);
}

criterion_group! {
    name = step_benches;
    // 16 benches × (1 s warm-up + 4 s measurement + analysis): about 1 min 40 s in all.
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .sample_size(50);
    targets = benches
}
criterion_main!(step_benches);
