//! Runs a fixed number of steps and exits: the workload of the instruction counts in the
//! README (valgrind's callgrind counts instructions, repeatably).
//!
//! ```sh
//! cargo build --release --example steps
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/examples/steps twin-f64 10000
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/examples/steps twin-f64 0
//! ```
//!
//! The difference of the two totals over the steps is the mean instruction count of a
//! step (set-up cancels out). Workloads: `twin-f64`, `twin-f32` (S2: 12 N·m, T_r =
//! 800 N·m, h = 1e-4 s, the first 10 000 steps are its first second, events included),
//! `five-bar-f64`, `five-bar-f32` (the thesis's five-bar at h = 1e-3 s);
//! `five-bar-f64-unchecked` (its local error unchecked: no sub-steps for it) and
//! `five-bar-f64-bare` (bare `Dp5::step`s: no energy balance, no output check), the
//! references for the checks' cost.
//!
//! One step's count: `twin-f64-at K [N]` runs S2's steps before `K` untimed and steps
//! `K..K+N` (default 1) inside `measured`, which callgrind alone can count:
//!
//! ```sh
//! valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*measured*' \
//!     target/release/examples/steps twin-f64-at 666
//! ```
//!
//! `twin-f32-at` and `twin-f32-log` are the same in f32; `STEPS_H=1e-3` in the
//! environment sets the step (1e-4 s without it), `STEPS_SPREAD=1` spreads the events
//! (`TwinSettings::spread_events`).
//!
//! `STEPS_FRICTION=1` in the environment turns the losses of a real machine on (every
//! joint 0.02 N·m·s/rad viscous and 0.05 N·m dry, ε = 0.01 rad/s, the clutches' drag
//! 0.05 N·m·s/rad): the cost of the friction terms.
//!
//! `twin-f64-log` lists S2's steps (first second) that hold an event, a coordinate
//! switch or a mode change: the indices to give `twin-f64-at`.
//! With `STEPS_LOG` set in the environment, the core's `log` records (debug level:
//! each event's location, the candidate modes, the coordinate scans) are printed too.

use std::hint::black_box;
use std::process::ExitCode;
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
use structomat::mechanisms::five_bar;
use structomat::motor::Motor;
use structomat::Real;

/// SPEC's converter, with the losses of `STEPS_FRICTION` (see the top).
fn params<T: Real>() -> CccParams<T> {
    let mut p = CccParams::reference();
    if std::env::var("STEPS_FRICTION").is_ok() {
        p.friction.viscous = [T::c(0.02); 9];
        p.friction.coulomb = [T::c(0.05); 9];
        p.friction.clutch_drag = T::c(0.05);
    }
    p
}

fn twin<T: Real>(steps: u32) -> Result<T, String> {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let settings = TwinSettings::reference(T::c(1e-4));
    let mut twin = Box::new(Twin::new(params(), settings, inputs).map_err(|e| e.to_string())?);
    for _ in 0..steps {
        twin.step(black_box(&inputs)).map_err(|e| e.to_string())?;
    }
    Ok(twin.q().first().copied().unwrap_or_default())
}

/// The steps counted by `twin-f64-at` (callgrind's `--toggle-collect='*measured*'`).
#[inline(never)]
fn measured<T: Real>(twin: &mut Twin<T>, inputs: &Inputs<T>, n: u32) -> Result<(), String> {
    for _ in 0..n {
        twin.step(black_box(inputs)).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// S2 up to step `at`, then `n` steps in [`measured`]; `log`: print each step with an
/// event, a switch or a mode change. The step is `STEPS_H` from the environment (s),
/// 1e-4 s without it.
fn twin_at<T: Real>(at: u32, n: u32, log: bool) -> Result<T, String> {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let h = std::env::var("STEPS_H")
        .ok()
        .and_then(|h| h.parse::<f64>().ok())
        .unwrap_or(1e-4);
    let mut settings = TwinSettings::reference(T::c(h));
    settings.spread_events = std::env::var("STEPS_SPREAD").is_ok();
    let mut twin = Box::new(Twin::new(params(), settings, inputs).map_err(|e| e.to_string())?);
    for k in 0..at {
        let before = (twin.mode(), twin.coordinates());
        twin.step(black_box(&inputs)).map_err(|e| e.to_string())?;
        if log
            && (!twin.events().is_empty() || !twin.switches().is_empty() || before.0 != twin.mode())
        {
            let ev: Vec<String> = twin
                .events()
                .iter()
                .map(|e| format!("{} {}->{}", e.kind.name(), e.from, e.to))
                .collect();
            let sw: Vec<String> = twin
                .switches()
                .iter()
                .map(|s| format!("switch {} {}->{}", s.mode, s.from, s.to))
                .collect();
            println!(
                "step {k} t={:.4} {}/{} -> {}/{}: {} {}",
                twin.time().to_f64(),
                before.0,
                before.1,
                twin.mode(),
                twin.coordinates(),
                ev.join(", "),
                sw.join(", ")
            );
        }
    }
    measured(&mut twin, &inputs, n)?;
    Ok(twin.q().first().copied().unwrap_or_default())
}

fn five<T: Real>(steps: u32) -> Result<T, String> {
    let scenario = five_bar::<T>().map_err(|e| e.to_string())?;
    let mut sim = Box::new(scenario.simulation().map_err(|e| e.to_string())?);
    for _ in 0..steps {
        sim.step().map_err(|e| e.to_string())?;
    }
    Ok(sim.q()[0])
}

/// The five-bar's steps with the local error unchecked (the energy balance checked):
/// a plain step's work, its sub-steps for the energy balance only.
fn five_unchecked(steps: u32) -> Result<f64, String> {
    let scenario = five_bar::<f64>().map_err(|e| e.to_string())?;
    let mut sim = Box::new(scenario.simulation().map_err(|e| e.to_string())?);
    sim.set_local_tolerance(f64::INFINITY, 0.0)
        .map_err(|e| e.to_string())?;
    for _ in 0..steps {
        sim.step().map_err(|e| e.to_string())?;
    }
    Ok(sim.q()[0])
}

/// The five-bar's bare DP5 steps (`Dp5::step` on the equations of motion: no energy
/// balance, no output check): the reference for the checks' cost.
fn five_bare(steps: u32) -> Result<f64, String> {
    use structomat::config::{MAX_DOF, STATE_DIM};
    use structomat::integrator::Dp5;
    use structomat::simulation::Equations;
    let scenario = five_bar::<f64>().map_err(|e| e.to_string())?;
    let sim = scenario.simulation().map_err(|e| e.to_string())?;
    let mut ws = Box::new(sim.workspace().clone());
    let mut y = nalgebra::SVector::<f64, STATE_DIM>::zeros();
    for (k, (q, qd)) in sim.q().iter().zip(sim.qd()).enumerate() {
        y[k] = *q;
        y[MAX_DOF + k] = *qd;
    }
    let mut dp5 = Box::new(Dp5::<f64, STATE_DIM>::new());
    let mut t = 0.0;
    for n in 1..=steps {
        let mut eq = Equations {
            model: sim.model(),
            ws: &mut ws,
        };
        let h = f64::from(n) * 1e-3 - t;
        dp5.step(&mut eq, &mut t, &mut y, h)
            .map_err(|e| e.to_string())?;
    }
    Ok(y[0])
}

struct Logger;
impl log::Log for Logger {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        println!("  {}: {}", r.level(), r.args());
    }
    fn flush(&self) {}
}
static LOGGER: Logger = Logger;

fn main() -> ExitCode {
    if std::env::var_os("STEPS_LOG").is_some() {
        let _ = log::set_logger(&LOGGER);
        log::set_max_level(log::LevelFilter::Debug);
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(work), Some(Ok(steps))) = (args.first(), args.get(1).map(|n| n.parse::<u32>()))
    else {
        eprintln!("usage: steps twin-f64|twin-f32|five-bar-f64|five-bar-f32|twin-f64-at|twin-f64-log STEPS [N]");
        return ExitCode::from(2);
    };
    let n = args.get(2).and_then(|n| n.parse::<u32>().ok()).unwrap_or(1);
    let result = match work.as_str() {
        "twin-f64" => twin::<f64>(steps),
        "twin-f32" => twin::<f32>(steps).map(f64::from),
        "twin-f64-at" => twin_at::<f64>(steps, n, false),
        "twin-f64-log" => twin_at::<f64>(steps, 0, true),
        "twin-f32-at" => twin_at::<f32>(steps, n, false).map(f64::from),
        "twin-f32-log" => twin_at::<f32>(steps, 0, true).map(f64::from),
        "five-bar-f64" => five::<f64>(steps),
        "five-bar-f32" => five::<f32>(steps).map(f64::from),
        "five-bar-f64-unchecked" => five_unchecked(steps),
        "five-bar-f64-bare" => five_bare(steps),
        other => Err(format!("unknown workload {other}")),
    };
    match result {
        Ok(q) => {
            println!("{work}: {steps} steps, q1 = {q}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{work}: {e}");
            ExitCode::FAILURE
        }
    }
}
