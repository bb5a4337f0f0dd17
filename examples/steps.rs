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
//! `five-bar-f64`, `five-bar-f32` (the thesis's five-bar at h = 1e-3 s).

use std::hint::black_box;
use std::process::ExitCode;
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings};
use structomat::mechanisms::five_bar;
use structomat::motor::Motor;
use structomat::Real;

fn twin<T: Real>(steps: u32) -> Result<T, String> {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let settings = TwinSettings::reference(T::c(1e-4));
    let mut twin =
        Box::new(Twin::new(CccParams::reference(), settings, inputs).map_err(|e| e.to_string())?);
    for _ in 0..steps {
        twin.step(black_box(&inputs)).map_err(|e| e.to_string())?;
    }
    Ok(twin.q()[0])
}

fn five<T: Real>(steps: u32) -> Result<T, String> {
    let scenario = five_bar::<T>().map_err(|e| e.to_string())?;
    let mut sim = Box::new(scenario.simulation().map_err(|e| e.to_string())?);
    for _ in 0..steps {
        sim.step().map_err(|e| e.to_string())?;
    }
    Ok(sim.q()[0])
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(work), Some(Ok(steps))) = (args.first(), args.get(1).map(|n| n.parse::<u32>()))
    else {
        eprintln!("usage: steps twin-f64|twin-f32|five-bar-f64|five-bar-f32 STEPS");
        return ExitCode::from(2);
    };
    let result = match work.as_str() {
        "twin-f64" => twin::<f64>(steps),
        "twin-f32" => twin::<f32>(steps).map(f64::from),
        "five-bar-f64" => five::<f64>(steps),
        "five-bar-f32" => five::<f32>(steps).map(f64::from),
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
