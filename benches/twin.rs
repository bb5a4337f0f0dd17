//! Step-time benches of the CCC digital twin ([`structomat::ccc::Twin`], f64, criterion,
//! `harness = false`), on scenario S2: SPEC 3's reference converter from rest, a
//! constant 12 N·m motor, an 800 N·m load, h = 1e-4 s.
//!
//! - `twin/plain_step/I`: a step in an I mode (I6 or I8, 1 DOF) with no event and no
//!   coordinate switch;
//! - `twin/plain_step/A`: the same in an A mode (A6, A8: 2 DOF; A68: 1 DOF);
//! - `twin/event_step/shaft_start`: the step holding S2's first breakaway (catch8 at a
//!   crank dead point, I6 → A68 driven by the crank, t ≈ 0.0666 s: the slowest event
//!   step under criterion), located inside the step, with its mode switch;
//! - `twin/event_step/catch`: the first catch that changes the mode (I0 → I6);
//! - `twin/event_step/shaft_stop`: the first shaft stop (A → I);
//! - `twin/switch_step`: the first step with a change of independent coordinates and
//!   no event;
//! - `twin/event_step/worst`: the slowest step of the worst-step report below (chosen
//!   at run time);
//! - `twin/observer_step/I`, `twin/observer_step/A`: the windows of `plain_step/I` and
//!   `/A` stepped by the observer ([`TwinObserver::step`]: the twin's step, then the
//!   update from the crank's and shaft's encoders, 4096 counts a turn, read from the
//!   twin's own run), its cost against the plain step's.
//!
//! **Reading the numbers.** Every `time:` is **per twin step**; the clone of the twin
//! (several KB) is never timed. They are measured with `iter_custom`: each iteration
//! clones the prepared twin (untimed, which also leaves it in cache, as a running twin
//! is), then times with `Instant` either [`WINDOW`] = 100 consecutive steps, divided by
//! 100 (`plain_step/*`: the mean of a plain step over a 10 ms stretch of motion), or the
//! single step (`event_step/*`, `switch_step`; the `Instant` pair adds some 20–40 ns to a
//! step of several µs). The prepared states are found by a dry run of S2 (the first
//! run of the report below) and every measured step is checked in setup: the plain
//! windows hold no event, no switch and no mode change, the event steps hold theirs.
//!
//! Criterion repeats the same event step thousands of times, so its code and branch
//! history are warm; inside a real run, after thousands of plain steps, the same step
//! is slower (about 1.4× in the report below): the report's worst step is the figure
//! to hold against a real-time budget, the benches the figures to compare changes.
//!
//! Before the criterion benches, one informative report is printed on stderr (not a
//! criterion measurement): every step of a full S2 run of 1 s (10 000 steps) timed with
//! `Instant`, its median and its worst step (index, time, mode, events), for the first
//! (cold) run and for the per-step minimum over [`RUNS`] runs (which removes
//! preemption noise). S2 runs its full second (it ends stalled in jam at t ≈ 0.818 s,
//! where a step is nearly free); the loop would stop at an error and say so.
//!
//! Run: `cargo bench --bench twin` (bench profile: release, thin LTO); a filter selects,
//! e.g. `cargo bench --bench twin -- event_step`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::{Duration, Instant};
use structomat::ccc::{
    CccParams, Encoder, EventKind, Inputs, Measurement, Mode, MotorInput, ObserverSettings, Twin,
    TwinObserver, TwinSettings,
};
use structomat::motor::Motor;

/// The step of S2, s.
const H: f64 = 1e-4;
/// Length of the S2 run, s (10 000 steps).
const T_END: f64 = 1.0;
/// Steps per timed iteration of the `plain_step` benches (and clean steps required).
const WINDOW: usize = 100;
/// Runs of S2 for the worst-step report.
const RUNS: usize = 5;

/// S2's twin at its start and its inputs.
fn s2() -> (Twin<f64>, Inputs<f64>) {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 800.0,
        measured: None,
    };
    let twin = Twin::new(
        CccParams::<f64>::reference(),
        TwinSettings::reference(H),
        inputs,
    )
    .unwrap_or_else(|e| panic!("S2: setup: {e}"));
    (twin, inputs)
}

fn steps_total() -> usize {
    (T_END / H).round() as usize
}

/// What one step of the dry run did.
#[derive(Clone, Debug)]
struct Record {
    /// Time at the start of the step, s.
    t: f64,
    before: Mode,
    after: Mode,
    /// `(kind, from, to, impact loss)` of each event of the step.
    events: Vec<(EventKind, Mode, Mode, f64)>,
    switches: usize,
}

impl Record {
    fn plain(&self) -> bool {
        self.events.is_empty() && self.switches == 0 && self.before == self.after
    }

    fn describe(&self) -> String {
        let mut s = format!("t = {:.4} s, {} -> {}", self.t, self.before, self.after);
        for (kind, from, to, loss) in &self.events {
            s += &format!(", {} {from} -> {to}", kind.name());
            if *loss > 0.0 {
                s += &format!(" (impact loss {loss:.1e} J)");
            }
        }
        if self.switches > 0 {
            s += &format!(", {} coordinate switch(es)", self.switches);
        }
        s
    }
}

fn record(twin: &Twin<f64>, t: f64, before: Mode) -> Record {
    Record {
        t,
        before,
        after: twin.mode(),
        events: twin
            .events()
            .iter()
            .map(|e| (e.kind, e.from, e.to, e.impact_loss))
            .collect(),
        switches: twin.switches().len(),
    }
}

/// The start of a [`WINDOW`]-step stretch of plain steps in one of `modes`: centered in
/// the longest such run (so it is far from any event).
fn plain_window(records: &[Record], modes: &[Mode]) -> Option<usize> {
    let ok = |r: &Record| r.plain() && modes.contains(&r.before);
    let (mut best, mut k) = (None::<(usize, usize)>, 0);
    while k < records.len() {
        if !ok(&records[k]) {
            k += 1;
            continue;
        }
        let start = k;
        while k < records.len() && ok(&records[k]) && records[k].before == records[start].before {
            k += 1;
        }
        let len = k - start;
        if len >= WINDOW && best.is_none_or(|(_, l)| len > l) {
            best = Some((start, len));
        }
    }
    best.map(|(start, len)| start + (len - WINDOW) / 2)
}

/// A prepared case: the twin before step `index`, and how many steps an iteration times.
struct Case {
    name: &'static str,
    index: usize,
    steps: usize,
}

/// The twin after `index` steps of S2.
fn twin_at(index: usize) -> (Twin<f64>, Inputs<f64>) {
    let (mut twin, inputs) = s2();
    for k in 0..index {
        twin.step(&inputs)
            .unwrap_or_else(|e| panic!("S2: step {k} at t = {}: {e}", twin.time()));
    }
    (twin, inputs)
}

fn cases(records: &[Record]) -> Vec<Case> {
    let mut cases = Vec::new();
    let mut push = |name, index: Option<usize>, steps| match index {
        Some(index) => cases.push(Case { name, index, steps }),
        None => eprintln!("twin bench: no step found for {name}, skipped"),
    };
    let first = |f: &dyn Fn(&Record) -> bool| records.iter().position(f);
    let has = |r: &Record, f: &dyn Fn(EventKind, Mode, Mode) -> bool| {
        r.events.iter().any(|&(k, from, to, _)| f(k, from, to))
    };
    push(
        "plain_step/I",
        plain_window(records, &[Mode::I6, Mode::I8]),
        WINDOW,
    );
    push(
        "plain_step/A",
        plain_window(records, &[Mode::A6, Mode::A8, Mode::A68]),
        WINDOW,
    );
    push(
        "event_step/shaft_start",
        first(&|r| {
            has(r, &|_, from, to| {
                !from.shaft_turning() && to.shaft_turning()
            })
        }),
        1,
    );
    push(
        "event_step/catch",
        first(&|r| {
            has(r, &|k, from, to| {
                matches!(k, EventKind::Catch(_)) && from != to
            })
        }),
        1,
    );
    push(
        "event_step/shaft_stop",
        first(&|r| has(r, &|k, _, _| k == EventKind::ShaftStop)),
        1,
    );
    push(
        "switch_step",
        first(&|r| r.events.is_empty() && r.switches > 0),
        1,
    );
    cases
}

/// Checks, on a clone, that the `steps` steps from `twin` do what the dry run recorded
/// (the same modes, events and switches), and that a plain window is plain.
fn check(case: &Case, twin: &Twin<f64>, inputs: &Inputs<f64>, records: &[Record]) {
    let mut t = twin.clone();
    let want = &records[case.index..case.index + case.steps];
    for (k, want) in (case.index..).zip(want) {
        let (time, before) = (t.time(), t.mode());
        t.step(inputs)
            .unwrap_or_else(|e| panic!("{}: step {k}: {e}", case.name));
        let r = record(&t, time, before);
        assert!(
            r.before == want.before
                && r.after == want.after
                && r.events.len() == want.events.len()
                && r.switches == want.switches,
            "{}: step {k} not reproduced: {} vs {}",
            case.name,
            r.describe(),
            want.describe()
        );
        if case.name.starts_with("plain_step") {
            assert!(
                r.plain(),
                "{}: step {k} is not plain: {}",
                case.name,
                r.describe()
            );
        } else {
            assert!(!r.plain(), "{}: step {k} is plain", case.name);
        }
    }
}

/// The dry run of S2 and the worst-step report: every step of S2 up to [`T_END`] or the
/// first error, timed with `Instant`, [`RUNS`] runs. Returns what each step did and the
/// index of the slowest step (of the per-step minimum over the runs).
fn dry_run_and_report() -> (Vec<Record>, usize) {
    let mut times: Vec<Vec<Duration>> = Vec::new();
    let mut records = Vec::new();
    let mut failure = None;
    for run in 0..RUNS {
        let (mut twin, inputs) = s2();
        let mut ts = Vec::with_capacity(steps_total());
        for k in 0..steps_total() {
            let (t, before) = (twin.time(), twin.mode());
            let start = Instant::now();
            let r = twin.step(black_box(&inputs));
            let dt = start.elapsed();
            if let Err(e) = r {
                failure = Some((k, t, e.to_string()));
                break;
            }
            ts.push(dt);
            if run == 0 {
                records.push(record(&twin, t, before));
            }
        }
        times.push(ts);
    }
    let n = times.iter().map(Vec::len).min().unwrap_or(0);
    let min: Vec<Duration> = (0..n)
        .map(|k| times.iter().map(|ts| ts[k]).min().unwrap_or_default())
        .collect();
    eprintln!(
        "twin bench: worst-step report, S2 (h = {H} s, {} steps asked), each step timed with Instant",
        steps_total()
    );
    match &failure {
        Some((k, t, e)) => eprintln!(
            "  S2 stopped at its first error, step {k} (t = {t:.4} s): {e}; {n} steps timed"
        ),
        None => eprintln!("  S2 ran all {n} steps"),
    }
    let plain: Vec<Duration> = (0..n)
        .filter(|&k| records[k].plain())
        .map(|k| min[k])
        .collect();
    let busy = n - plain.len();
    let mut slowest = 0;
    for (label, ts) in [
        ("first (cold) run", &times[0][..n]),
        ("per-step min of runs", &min),
    ] {
        let mut sorted = ts.to_vec();
        sorted.sort();
        let (k, max) = ts
            .iter()
            .enumerate()
            .max_by_key(|(_, d)| **d)
            .map(|(k, d)| (k, *d))
            .unwrap_or_default();
        slowest = k;
        eprintln!(
            "  {label}: median {:.2} µs, p99 {:.2} µs, max {:.2} µs at step {k}: {}",
            us(sorted[n / 2]),
            us(sorted[n * 99 / 100]),
            us(max),
            records[k].describe()
        );
    }
    let mut worst: Vec<usize> = (0..n).filter(|&k| !records[k].plain()).collect();
    worst.sort_by_key(|&k| std::cmp::Reverse(min[k]));
    eprintln!(
        "  per-step min of {RUNS} runs: {} plain steps (median {:.2} µs), {busy} steps with an event, a switch or a mode change; the slowest of those:",
        plain.len(),
        us({
            let mut p = plain.clone();
            p.sort();
            p.get(p.len() / 2).copied().unwrap_or_default()
        }),
    );
    for &k in worst.iter().take(5) {
        eprintln!(
            "    {:.2} µs at step {k}: {}",
            us(min[k]),
            records[k].describe()
        );
    }
    records.truncate(n);
    (records, slowest)
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn benches(c: &mut Criterion) {
    let (records, slowest) = dry_run_and_report();
    let mut cases = cases(&records);
    cases.push(Case {
        name: "event_step/worst",
        index: slowest,
        steps: 1,
    });
    let mut g = c.benchmark_group("twin");
    for case in &cases {
        let (twin, inputs) = twin_at(case.index);
        check(case, &twin, &inputs, &records);
        let last = &records[case.index + case.steps - 1];
        eprintln!(
            "twin bench: {}: steps {}..{} ({}); {}",
            case.name,
            case.index,
            case.index + case.steps,
            if case.steps == 1 {
                "one step per iteration".to_string()
            } else {
                format!("{} steps per iteration, time / {}", case.steps, case.steps)
            },
            if case.steps == 1 {
                last.describe()
            } else {
                format!(
                    "t = {:.4}..{:.4} s in {}",
                    records[case.index].t,
                    last.t + H,
                    last.before
                )
            }
        );
        let steps = case.steps;
        g.bench_function(case.name, |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let mut t = twin.clone();
                    let start = Instant::now();
                    for _ in 0..steps {
                        if let Err(e) = black_box(&mut t).step(black_box(&inputs)) {
                            panic!("{}: {e}", case.name);
                        }
                    }
                    total += start.elapsed();
                    black_box(&t);
                }
                total / steps as u32
            })
        });
    }
    for name in ["plain_step/I", "plain_step/A"] {
        let Some(case) = cases.iter().find(|c| c.name == name) else {
            continue;
        };
        let (twin, inputs) = twin_at(case.index);
        // The encoders' readings at each step's end, from the twin's own run.
        let mut machine = twin.clone();
        let encoder = |x: f64| Encoder {
            counts: (x / (std::f64::consts::TAU / 4096.0)).floor() as i64,
            per_turn: 4096,
            zero: 0.0,
        };
        let readings: Vec<Inputs<f64>> = (0..case.steps)
            .map(|_| {
                machine.step(&inputs).expect("the window's step");
                Inputs {
                    measured: Some(Measurement {
                        crank: Some(encoder(machine.link(1).theta)),
                        shaft: Some(encoder(machine.shaft_drive_angle())),
                        rocker: None,
                    }),
                    ..inputs
                }
            })
            .collect();
        let observer = TwinObserver::new(ObserverSettings::reference());
        let label = name.replace("plain_step", "observer_step");
        g.bench_function(label.as_str(), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let (mut t, mut o) = (twin.clone(), observer);
                    let start = Instant::now();
                    for r in &readings {
                        if let Err(e) = black_box(&mut o).step(black_box(&mut t), black_box(r)) {
                            panic!("{label}: {e}");
                        }
                    }
                    total += start.elapsed();
                    black_box(&t);
                }
                total / readings.len() as u32
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = twin_benches;
    // 10 benches × (1 s warm-up + 4 s measurement + analysis): about 45 s in all.
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .sample_size(50);
    targets = benches
}
criterion_main!(twin_benches);
