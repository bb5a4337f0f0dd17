//! The firmware harness: S2 and the five-bar run as firmware would, on an emulated
//! Cortex-M board (QEMU's MPS2 models), the twin and the simulation in statics, stepped
//! in a loop with the step's inputs, every record over semihosting (see the library's
//! header). `checks/firmware/run` builds and runs it and compares with the host.
//!
//! The instructions of each step are counted by SysTick under `qemu -icount shift=0`
//! (one instruction a nanosecond of virtual time), on the processor clock; the record
//! `calibrate` measures how many instructions a SysTick tick is with a loop of known
//! length. The stack is measured by painting: each run's `stack` record gives the
//! deepest use during construction (`Twin::new_in` into the static; below the frame
//! that calls the run, the run's own frame included) and during the steps (below the
//! run's frame: what `step` itself needs).
//!
//! The command line (`qemu -append`) selects a canary instead: `fault` (an undefined
//! instruction: the HardFault handler must exit with failure), `panic`, `hang` (only the
//! timeout ends it), `perturb` (the first S2 run with its load 2 ulps higher: its digest
//! must differ from the host's), or `profile<K>`: S2's run K alone (its records only),
//! for `checks/firmware/profile/run`, or `costs<K>`: the same with every step's
//! instructions, mode and coordinates (`profile/run BOARD K 0 costs`).
#![no_std]
#![no_main]

use core::mem::MaybeUninit;
use cortex_m_rt::entry;
use structomat::ccc::Twin;
use structomat::Simulation;
use structomat_firmware::{run_all, run_s2, Counter, Places, MAX_STEPS};

#[path = "../target.rs"]
mod target;
use target::{exit, stack, Out, SysTick, BOARD, RUNS, SCALAR};

type R = target::R;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut` owned by `main`: the firmware's
    // statics, in .bss, never on the stack.
    static mut TWIN: MaybeUninit<Twin<R>> = MaybeUninit::uninit();
    static mut PLAIN: MaybeUninit<Twin<R>> = MaybeUninit::uninit();
    static mut SIM: MaybeUninit<Simulation<R>> = MaybeUninit::uninit();
    static mut COUNTS: [u32; MAX_STEPS] = [0; MAX_STEPS];

    let mut out = Out::new();
    let mut systick = SysTick::start();
    let (known, ticks) = systick.calibrate();
    out.line(format_args!(
        "board {BOARD} scalar {SCALAR} twin {} bytes simulation {} bytes",
        core::mem::size_of::<Twin<R>>(),
        core::mem::size_of::<Simulation<R>>()
    ));
    out.line(format_args!("calibrate {known} instructions {ticks} ticks"));
    // The command line (QEMU's `-append`) asks for the canaries of `run`, which prove
    // that its checks can fail.
    let mut line = [0u8; 128];
    let word = target::command_word(&mut line);
    // `profile<K>`: S2's run K of `RUNS` alone, for an instruction profile of it
    // (`checks/firmware/profile/run`); no comparison, the run's records only.
    // `costs<K>`: the same with a record of every step's instructions.
    let alone = match *word {
        [b'p', b'r', b'o', b'f', b'i', b'l', b'e', k] => Some((k, false)),
        [b'c', b'o', b's', b't', b's', k] => Some((k, true)),
        _ => None,
    };
    if let Some((k, every)) = alone {
        let Some(run) = RUNS.get(usize::from(k.wrapping_sub(b'0'))) else {
            exit(false)
        };
        let ok = run_s2(TWIN, COUNTS, &mut systick, &mut out, run, false, every).is_ok();
        exit(ok)
    }
    let perturbed = match word {
        b"fault" => target::fault_now(),
        b"panic" => panic!("the panic canary"),
        b"hang" => loop {
            core::hint::spin_loop();
        },
        b"perturb" => true,
        _ => false,
    };
    let runs = if perturbed { &RUNS[..1] } else { &RUNS[..] };
    let places = Places {
        twin: TWIN,
        plain: PLAIN,
        sim: SIM,
        counts: COUNTS,
    };
    let result = run_all(places, &mut systick, &mut out, runs, perturbed);
    match result {
        Ok(()) => {
            out.line(format_args!("done"));
            exit(true)
        }
        Err(_) => {
            out.line(format_args!("failed"));
            exit(false)
        }
    }
}

impl Counter for SysTick {
    fn start(&mut self) {
        self.mark();
    }
    fn stop(&mut self) -> u32 {
        self.instructions()
    }
    fn counts(&self) -> bool {
        true
    }
    fn paint(&mut self) {
        stack::paint();
    }
    fn stack(&mut self) -> usize {
        stack::used()
    }
}
