//! The host's side of the firmware harness: the same workloads through the same library
//! code as `harness` on the target, printing the records that the target's must equal.
//!
//! ```sh
//! cargo run --release --features host --bin host -- f32   # what mps2-an386 must print
//! cargo run --release --features host --bin host -- f64   # what mps2-an500 must print
//! ```
use std::fmt;
use std::mem::MaybeUninit;
use std::process::ExitCode;
use structomat::ccc::Twin;
use structomat::{Real, Simulation};
use structomat_firmware::{run_all, NoCounter, Places, S2Run, MAX_STEPS, RUNS_F32, RUNS_F64};

/// Standard output as a `fmt::Write`.
struct Stdout;

impl fmt::Write for Stdout {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        use std::io::Write;
        std::io::stdout()
            .write_all(s.as_bytes())
            .map_err(|_| fmt::Error)
    }
}

fn run<T: Real>(runs: &[S2Run]) -> ExitCode {
    // On the heap: the twin is 63 KiB (f32) or 123 KiB (f64).
    let mut twin: Box<MaybeUninit<Twin<T>>> = Box::new_uninit();
    let mut plain: Box<MaybeUninit<Twin<T>>> = Box::new_uninit();
    let mut sim: Box<MaybeUninit<Simulation<T>>> = Box::new_uninit();
    let mut counts = vec![0u32; MAX_STEPS];
    let places = Places {
        twin: &mut twin,
        plain: &mut plain,
        sim: &mut sim,
        counts: &mut counts,
    };
    match run_all(places, &mut NoCounter, &mut Stdout, runs, false) {
        Ok(()) => ExitCode::SUCCESS,
        Err(_) => ExitCode::FAILURE,
    }
}

fn main() -> ExitCode {
    match std::env::args().nth(1).as_deref() {
        Some("f32") => run::<f32>(&RUNS_F32),
        Some("f64") => run::<f64>(&RUNS_F64),
        _ => {
            eprintln!("usage: host f32|f64");
            ExitCode::from(2)
        }
    }
}
