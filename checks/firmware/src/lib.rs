//! The workloads of the firmware harness, shared by the target binary and the host
//! program so that both run exactly the same code around the core.
//!
//! What a run prints, in order, one record a line:
//!
//! - `<run> event step <k> t=<t> <mode>/<coords> -> <mode>/<coords>: <events> <switches>`
//!   for every S2 step with an event, a coordinate switch or a mode change (the format of
//!   `examples/steps.rs twin-f64-log`);
//! - `<run> digest <hex> steps <n> t <t_end>`: FNV-1a (64 bit) over the bits of every
//!   step's outputs ([`hash_twin`], [`hash_simulation`]);
//! - `<run> count ...`: instructions per step ([`Stats`]), only where a [`Counter`]
//!   counts (the target); the host prints none.
//!
//! The first two kinds must be identical on the target and on the host; `run` compares
//! them. After S2, the bench log observed ([`bench`]: the twin following the machine).
#![no_std]

/// Writes a record; a failed write (an output too long for its line) fails the run.
macro_rules! record {
    ($out:expr, $($arg:tt)*) => {
        if writeln!($out, $($arg)*).is_err() {
            return Err(Failed);
        }
    };
}

mod bench;

use core::fmt::{self, Write};
use core::mem::MaybeUninit;
use structomat::ccc::{
    CccParams, Inputs, MotorInput, Twin, TwinSettings, TwinSetupError, TwinStepError,
};
use structomat::motor::Motor;
use structomat::{Real, Simulation};

/// One S2 run of the harness: a name (the records' first word), the step and the number
/// of steps.
#[derive(Clone, Copy, Debug)]
pub struct S2Run {
    /// The records' first word.
    pub name: &'static str,
    /// Step, s.
    pub h: f64,
    /// Steps: S2's first second.
    pub steps: u32,
    /// [`TwinSettings::spread_events`]: each event's work spread over the steps
    /// after it (issue 18's budget runs).
    pub spread: bool,
}

/// S2's first second at the recommended f64 step, 1e-4 s.
const S2_H1E4: S2Run = S2Run {
    name: "s2-h1e-4",
    h: 1e-4,
    steps: 10_000,
    spread: false,
};

/// S2's first second at the 1 kHz loop's step, 1e-3 s.
const S2_H1E3: S2Run = S2Run {
    name: "s2-h1e-3",
    h: 1e-3,
    steps: 1_000,
    spread: false,
};

/// S2's first second at the 1 kHz loop's step with each event's work spread over the
/// steps after it: the real-time budget's run.
const S2_H1E3_SPREAD: S2Run = S2Run {
    name: "s2-h1e-3-spread",
    h: 1e-3,
    steps: 1_000,
    spread: true,
};

/// The f32 runs (Cortex-M4F): the recommended f32 step first (README, "In firmware":
/// h = 2e-4 s), then 1e-4 s and 1e-3 s, and 1e-3 s with its events spread.
pub const RUNS_F32: [S2Run; 4] = [
    S2Run {
        name: "s2-h2e-4",
        h: 2e-4,
        steps: 5_000,
        spread: false,
    },
    S2_H1E4,
    S2_H1E3,
    S2_H1E3_SPREAD,
];

/// The f64 runs (Cortex-M7): the recommended f64 step (1e-4 s), then 1e-3 s, and
/// 1e-3 s with its events spread.
pub const RUNS_F64: [S2Run; 3] = [S2_H1E4, S2_H1E3, S2_H1E3_SPREAD];

/// The five-bar's steps: 0.5 s at its scenario's h = 1 ms.
pub const FIVE_BAR_STEPS: u32 = 500;

/// The most steps of one run ([`S2Run::steps`]): the length of the counts buffer.
pub const MAX_STEPS: usize = 10_000;

/// FNV-1a, 64 bit: a digest that is the same code on every target.
#[derive(Clone, Copy, Debug)]
pub struct Digest(u64);

impl Default for Digest {
    fn default() -> Self {
        Self::new()
    }
}

impl Digest {
    /// The FNV-1a offset basis.
    pub const fn new() -> Self {
        Digest(0xcbf2_9ce4_8422_2325)
    }

    /// Adds bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    /// Adds a word, little-endian.
    pub fn word(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }

    /// Adds a real's bits (widened to f64, which is exact from f32).
    pub fn real<T: Real>(&mut self, x: T) {
        self.word(x.to_f64().to_bits());
    }

    /// The digest so far.
    pub fn value(&self) -> u64 {
        self.0
    }
}

/// The twin's outputs after a step, into `d`: time, step count, mode, coordinates, q, qd,
/// clutch torques, motor torque, shaft speed, the audit's residual and the number of
/// events and switches.
pub fn hash_twin<T: Real>(d: &mut Digest, twin: &Twin<T>) {
    d.real(twin.time());
    d.word(twin.steps());
    d.bytes(twin.mode().name().as_bytes());
    d.bytes(twin.coordinates().name().as_bytes());
    for v in twin.q().iter().chain(twin.qd()) {
        d.real(*v);
    }
    let [c6, c8] = twin.clutch_torques();
    d.real(c6);
    d.real(c8);
    d.real(twin.motor_torque());
    d.real(twin.shaft_speed());
    d.real(twin.audit().residual());
    d.word(twin.events().len() as u64);
    d.word(twin.switches().len() as u64);
}

/// The simulation's outputs after a step, into `d`: time, q, qd, qdd.
pub fn hash_simulation<T: Real>(d: &mut Digest, sim: &Simulation<T>) {
    d.real(sim.time());
    for v in sim.q().iter().chain(sim.qd()).chain(sim.qdd()) {
        d.real(*v);
    }
}

/// Counts the instructions of a stretch of code (the target's SysTick) and measures the
/// stack (the target's paint); the host's counts nothing.
pub trait Counter {
    /// Starts counting.
    fn start(&mut self);
    /// Instructions since [`Counter::start`].
    fn stop(&mut self) -> u32;
    /// Whether the counts mean anything (the `count` records are printed only then).
    fn counts(&self) -> bool;
    /// Starts a stack measurement: paints the free stack below the caller's frame.
    fn paint(&mut self) {}
    /// The deepest stack use since [`Counter::paint`], bytes below the frame it was
    /// called from.
    fn stack(&mut self) -> usize {
        0
    }
}

/// The host's counter: counts nothing.
pub struct NoCounter;

impl Counter for NoCounter {
    fn start(&mut self) {}
    fn stop(&mut self) -> u32 {
        0
    }
    fn counts(&self) -> bool {
        false
    }
}

/// Instructions per step over a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Steps.
    pub n: u32,
    /// Mean, rounded down.
    pub mean: u32,
    /// The lower median.
    pub median: u32,
    /// The 99th percentile (the smallest count that at least 99 % of the steps stay under
    /// or equal).
    pub p99: u32,
    /// The worst step's count.
    pub worst: u32,
    /// The worst step's index (the first of equals).
    pub worst_step: u32,
}

impl Stats {
    /// The statistics of `counts` (sorted in place).
    pub fn of(counts: &mut [u32]) -> Stats {
        let n = counts.len();
        if n == 0 {
            return Stats::default();
        }
        let mut worst = 0;
        let mut worst_step = 0;
        let mut sum = 0u64;
        for (k, &c) in counts.iter().enumerate() {
            sum += u64::from(c);
            if c > worst {
                worst = c;
                worst_step = k;
            }
        }
        counts.sort_unstable();
        let p99 = (n * 99).div_ceil(100).max(1) - 1;
        Stats {
            n: n as u32,
            mean: (sum / n as u64) as u32,
            median: counts[(n - 1) / 2],
            p99: counts[p99],
            worst,
            worst_step: worst_step as u32,
        }
    }
}

/// S2's inputs (SPEC: 12 N·m constant motor, T_r = 800 N·m, nothing measured).
pub fn s2_inputs<T: Real>() -> Inputs<T> {
    Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    }
}

/// A line of at most 256 bytes, for the event records.
pub type Line = heapless::String<256>;

/// Writes S2's event record of step `k` (format of `examples/steps.rs twin-f64-log`);
/// `before` is the mode and coordinates before the step.
pub fn event_line<T: Real, W: Write>(
    w: &mut W,
    k: u32,
    before: (structomat::ccc::Mode, structomat::ccc::Coordinates),
    twin: &Twin<T>,
) -> fmt::Result {
    write!(
        w,
        "step {k} t={:.4} {}/{} -> {}/{}: ",
        twin.time().to_f64(),
        before.0.name(),
        before.1.name(),
        twin.mode().name(),
        twin.coordinates().name()
    )?;
    for (i, e) in twin.events().iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        write!(
            w,
            "{sep}{} {}->{}",
            e.kind.name(),
            e.from.name(),
            e.to.name()
        )?;
    }
    w.write_char(' ')?;
    for (i, s) in twin.switches().iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        write!(
            w,
            "{sep}switch {} {}->{}",
            s.mode.name(),
            s.from.name(),
            s.to.name()
        )?;
    }
    Ok(())
}

/// Why a run stopped.
#[derive(Debug)]
pub struct Failed;

/// Where the runs live: the firmware's statics (the host's boxes).
pub struct Places<'a, T: Real> {
    /// The twin of each run.
    pub twin: &'a mut MaybeUninit<Twin<T>>,
    /// bench1's plain copy of the observed twin, stepped beside it.
    pub plain: &'a mut MaybeUninit<Twin<T>>,
    /// The five-bar's simulation.
    pub sim: &'a mut MaybeUninit<Simulation<T>>,
    /// The instructions of each step, at least [`MAX_STEPS`].
    pub counts: &'a mut [u32],
}

/// Runs everything for scalar `T` in `places`: each of `runs` (S2), bench1 observed
/// (unless `perturbed`), then the five-bar for [`FIVE_BAR_STEPS`], printing the records
/// to `out`.
///
/// `perturbed` raises S2's load by its last bits (a factor 1 + ε, 2 ulps of 800 N·m):
/// the check that a digest sees the least change of an input.
///
/// Each twin is built where it lives, in `twin_slot` (`Twin::new_in`): no twin, slot,
/// model or workspace on the stack; the `stack new` record is what that construction
/// needs.
pub fn run_all<T: Real, C: Counter, W: Write>(
    places: Places<'_, T>,
    counter: &mut C,
    out: &mut W,
    runs: &[S2Run],
    perturbed: bool,
) -> Result<(), Failed> {
    let Places {
        twin: twin_slot,
        plain: plain_slot,
        sim: sim_slot,
        counts,
    } = places;
    for run in runs {
        run_s2(twin_slot, counts, counter, out, run, perturbed, false)?;
    }
    if !perturbed {
        for tuning in [bench::Tuning::Nominal, bench::Tuning::Identified] {
            bench::run_bench1(twin_slot, plain_slot, counts, counter, out, tuning)?;
        }
    }
    counter.paint();
    run_five_bar(sim_slot, counter, out)
}

/// S2 for `run.steps` steps at `run.h` (its load raised by 2 ulps if `perturbed`): the
/// records of `run`. Its stack records are what construction and the steps use below
/// this function's frame (painted here before each). With `every`, a `cost` record of
/// each step as well (`checks/firmware/profile/run BOARD RUN 0 costs`): its instructions
/// and the mode and coordinates it started in, `event` if it had an event, a coordinate
/// switch or a mode change.
#[inline(never)]
pub fn run_s2<T: Real, C: Counter, W: Write>(
    twin_slot: &mut MaybeUninit<Twin<T>>,
    counts: &mut [u32],
    counter: &mut C,
    out: &mut W,
    run: &S2Run,
    perturbed: bool,
    every: bool,
) -> Result<(), Failed> {
    let name = run.name;
    let mut inputs = s2_inputs::<T>();
    if perturbed {
        inputs.load *= T::one() + T::EPS;
    }
    counter.paint();
    counter.start();
    let mut settings = TwinSettings::reference(T::c(run.h));
    settings.spread_events = run.spread;
    let built = new_twin(twin_slot, settings, inputs);
    let twin = match built {
        Ok(t) => t,
        Err(e) => {
            record!(out, "{name} error new: {e}");
            return Err(Failed);
        }
    };
    let new = counter.stop();
    let stack_new = counter.stack();
    counter.paint();
    let steps = (run.steps as usize).min(counts.len());
    let mut d = Digest::new();
    let mut worst = 0;
    let mut worst_at = Line::new();
    let mut last_event = Line::new();
    for (k, count) in counts[..steps].iter_mut().enumerate() {
        let k = k as u32;
        let before = (twin.mode(), twin.coordinates());
        counter.start();
        let stepped = step(twin, &inputs);
        let c = counter.stop();
        if let Err(e) = stepped {
            record!(out, "{name} error step {k}: {e}");
            return Err(Failed);
        }
        *count = c;
        hash_twin(&mut d, twin);
        let event =
            !twin.events().is_empty() || !twin.switches().is_empty() || before.0 != twin.mode();
        if every {
            record!(
                out,
                "{name} cost {k} {c} {}/{}{}",
                before.0.name(),
                before.1.name(),
                if event { " event" } else { "" }
            );
        }
        if event {
            last_event.clear();
            if event_line(&mut last_event, k, before, twin).is_err() {
                return Err(Failed);
            }
            record!(out, "{name} event {last_event}");
        }
        if c > worst {
            worst = c;
            worst_at.clear();
            let described = if event {
                write!(worst_at, "{last_event}")
            } else if last_event.is_empty() {
                write!(worst_at, "step {k}, before any event")
            } else {
                write!(worst_at, "step {k}, after {last_event}")
            };
            if described.is_err() {
                worst_at.clear();
            }
        }
    }
    record!(
        out,
        "{name} digest {:016x} steps {steps} t {:.6}",
        d.value(),
        twin.time().to_f64()
    );
    refuse_nan_load(twin, &inputs, out, name)?;
    if counter.counts() {
        let stack_step = counter.stack();
        // The dear steps, for whoever works on the budget: every step within half of
        // the worst, in step order.
        for (k, &c) in counts[..steps].iter().enumerate() {
            if c >= worst / 2 {
                record!(out, "{name} dear step {k} count {c}");
            }
        }
        let s = Stats::of(&mut counts[..steps]);
        record!(out, "{name} stack new {stack_new} step {stack_step}");
        record!(
            out,
            "{name} count new {new} mean {} median {} p99 {} worst {} step {} at {}",
            s.mean,
            s.median,
            s.p99,
            s.worst,
            s.worst_step,
            worst_at.trim_end()
        );
    }
    Ok(())
}

/// The one call site of `Twin::new_in` (SPEC's converter with `settings`, started
/// under `inputs`): S2's runs and bench1's build their twins through the same code, so
/// the construction [`run_s2`] measures is the one every run makes.
#[inline(never)]
pub fn new_twin<T: Real>(
    slot: &mut MaybeUninit<Twin<T>>,
    settings: TwinSettings<T>,
    inputs: Inputs<T>,
) -> Result<&mut Twin<T>, TwinSetupError> {
    Twin::new_in(slot, CccParams::reference(), settings, inputs)
}

/// The one call site of `Twin::step`, so that how the optimiser treats the step (what
/// it inlines into it) does not change with the harness's other calls.
#[inline(never)]
pub fn step<T: Real>(twin: &mut Twin<T>, inputs: &Inputs<T>) -> Result<(), TwinStepError> {
    twin.step(inputs)
}

/// A step with a NaN load must fail with a named error and keep the twin's state bit
/// for bit (the core's contract for a bad input): the record `<run> refused ...`.
fn refuse_nan_load<T: Real, W: Write>(
    twin: &mut Twin<T>,
    inputs: &Inputs<T>,
    out: &mut W,
    name: &str,
) -> Result<(), Failed> {
    let mut before = Digest::new();
    hash_twin(&mut before, twin);
    let mut bad = *inputs;
    bad.load = T::c(f64::NAN);
    let Err(e) = step(twin, &bad) else {
        record!(out, "{name} error: a NaN load was accepted");
        return Err(Failed);
    };
    let mut after = Digest::new();
    hash_twin(&mut after, twin);
    if after.value() != before.value() {
        record!(
            out,
            "{name} error: a refused NaN load changed the state ({e})"
        );
        return Err(Failed);
    }
    record!(out, "{name} refused a NaN load, state kept: {e}");
    Ok(())
}

/// The five-bar (the generic core's `Simulation`) for [`FIVE_BAR_STEPS`]: the records
/// of `five-bar`.
#[inline(never)]
pub fn run_five_bar<T: Real, C: Counter, W: Write>(
    sim_slot: &mut MaybeUninit<Simulation<T>>,
    counter: &mut C,
    out: &mut W,
) -> Result<(), Failed> {
    let scenario = match structomat::mechanisms::five_bar::<T>() {
        Ok(s) => s,
        Err(e) => {
            record!(out, "five-bar error model: {e}");
            return Err(Failed);
        }
    };
    counter.start();
    let sim = match scenario.simulation() {
        Ok(s) => sim_slot.write(s),
        Err(e) => {
            record!(out, "five-bar error new: {e}");
            return Err(Failed);
        }
    };
    let new = counter.stop();
    let stack_new = counter.stack();
    counter.paint();
    let mut d = Digest::new();
    let (mut worst, mut worst_step, mut sum) = (0, 0, 0u64);
    for k in 0..FIVE_BAR_STEPS {
        counter.start();
        let stepped = sim.step();
        let c = counter.stop();
        if let Err(e) = stepped {
            record!(out, "five-bar error step {k}: {e}");
            return Err(Failed);
        }
        sum += u64::from(c);
        if c > worst {
            worst = c;
            worst_step = k;
        }
        hash_simulation(&mut d, sim);
    }
    record!(
        out,
        "five-bar digest {:016x} steps {FIVE_BAR_STEPS} t {:.6}",
        d.value(),
        sim.time().to_f64()
    );
    if counter.counts() {
        let stack_step = counter.stack();
        record!(out, "five-bar stack new {stack_new} step {stack_step}");
        record!(
            out,
            "five-bar count new {new} mean {} worst {worst} step {worst_step}",
            sum / u64::from(FIVE_BAR_STEPS)
        );
    }
    Ok(())
}
