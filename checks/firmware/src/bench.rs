//! The twin following a machine on the target: the prototype's bench log `bench1`
//! (`host-sim/tests/data/bench1.csv`, compiled in) replayed as `host-sim replay
//! --observer` replays it on the PC, twice ([`Tuning`]): on SPEC's nominal converter
//! with the nominal tuning (`bench1-observed`), and on bench1's identified converter
//! with the identified tuning (`bench1-identified`, as `replay --params
//! known-machine.toml --observer identified`). The log's 1 ms, its measured motor
//! torque and load each step, and the crank's and the shaft's counts at the step's
//! end into a [`TwinObserver`].
//!
//! What each run prints (the first two kinds must equal the host's; `<run>` its name):
//! - `<run> event ...` for every step with an event, a switch or a mode change;
//! - `<run> digest <hex> steps <n> t <t_end>`: every step's twin outputs
//!   ([`hash_twin`]) and the observer's innovation and torque estimate;
//! - on the target, `<run> count observer mean .. worst .. step .. plain
//!   mean .. worst .. ratio-permille ..`: the instructions of each observer step, and of
//!   a plain [`Twin::step`] from the same state under the same inputs (a copy of the
//!   twin stepped beside it, not counted into the other), and the ratio of their sums
//!   (issue 19: an observer step at most 2× a plain one).

use super::*;
use structomat::ccc::{
    DriveDirection, Encoder, Measurement, ObserverSettings, Side, TwinObserver,
    FRICTION_JOINT_NAMES,
};
use structomat::scalar::Vec2;

/// bench1's log: `t,motor_torque,load_torque,crank_counts,shaft_counts` at 1 kHz.
const BENCH1: &str = include_str!("../../../host-sim/tests/data/bench1.csv");

/// The bench's encoders: counts per turn.
const COUNTS_PER_TURN: u32 = 4096;

/// The log's period, s.
const PERIOD: f64 = 1e-3;

/// The converter and the observer's tuning of a bench1 run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tuning {
    /// SPEC's converter, [`ObserverSettings::reference`].
    Nominal,
    /// bench1's identified converter ([`identified_converter`]),
    /// [`ObserverSettings::identified`].
    Identified,
}

impl Tuning {
    /// The records' first word.
    fn name(self) -> &'static str {
        match self {
            Tuning::Nominal => "bench1-observed",
            Tuning::Identified => "bench1-identified",
        }
    }
}

// bench1's identified machine (`identified_converter`): SPEC's converter with the
// values of `host-sim/tests/data/known-machine.toml` (`host-sim identify` of bench1),
// written by `build.rs` from that file, so that this run is the PC's `replay --params
// known-machine.toml`.
include!(concat!(env!("OUT_DIR"), "/identified.rs"));

/// The index of the friction joint `name` in [`FRICTION_JOINT_NAMES`] (SPEC's letters,
/// as the run files name them); a name that is none of them fails the build (the
/// generated code calls it in a `const` block).
const fn friction_joint(name: &str) -> usize {
    let mut k = 0;
    while k < FRICTION_JOINT_NAMES.len() {
        let (a, b) = (FRICTION_JOINT_NAMES[k].as_bytes(), name.as_bytes());
        if a.len() == b.len() {
            let mut i = 0;
            while i < a.len() && a[i] == b[i] {
                i += 1;
            }
            if i == a.len() {
                return k;
            }
        }
        k += 1;
    }
    panic!("a friction joint of known-machine.toml is none of FRICTION_JOINT_NAMES")
}

/// One row of the log; the torques as decimals ([`decimal`]).
#[derive(Clone, Copy, Debug)]
struct Sample {
    motor: (i64, usize),
    load: (i64, usize),
    crank: i64,
    shaft: i64,
}

/// Row `line` of the log (`None` if it is not one).
fn sample(line: &str) -> Option<Sample> {
    let mut f = line.split(',').map(str::trim);
    let _t = f.next()?;
    Some(Sample {
        motor: decimal(f.next()?)?,
        load: decimal(f.next()?)?,
        crank: f.next()?.parse().ok()?,
        shaft: f.next()?.parse().ok()?,
    })
}

/// Powers of ten exact in f64.
const TENS: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// A decimal `[-]digits[.digits]` as `(m, k)`, its value `m / 10^k`: the log's torques
/// read without core's float parser, whose f64 arithmetic is soft-float on this target
/// (its core library is built for the M4F's single-precision FPU), where `m / 10^k`
/// is one division of two exact numbers: the correctly rounded value, as a parser's.
fn decimal(s: &str) -> Option<(i64, usize)> {
    let (int, frac) = s.split_once('.').unwrap_or((s, ""));
    let k = frac.len();
    if k >= TENS.len() || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let negative = int.starts_with('-');
    let mut m: i64 = int.trim_start_matches('-').parse().ok()?;
    for b in frac.bytes() {
        m = m.checked_mul(10)?.checked_add(i64::from(b - b'0'))?;
    }
    // Exact in f64: the division then rounds once.
    if m >= 1 << 53 {
        return None;
    }
    Some((if negative { -m } else { m }, k))
}

/// The value of a decimal of [`decimal`].
fn value<T: Real>((m, k): (i64, usize)) -> T {
    T::c(m as f64) / T::c(TENS.get(k).copied().unwrap_or(1.0))
}

/// The log's rows in order, the header left out.
fn samples() -> impl Iterator<Item = Option<Sample>> {
    BENCH1.lines().skip(1).map(sample)
}

/// An encoder of the bench with `counts` (count 0's cell starts at angle 0: the crank's
/// `floor(θ1 / resolution)`, the shaft's 0 at the start).
fn encoder<T: Real>(counts: i64) -> Encoder<T> {
    Encoder {
        counts,
        per_turn: COUNTS_PER_TURN,
        zero: T::zero(),
    }
}

/// bench1 observed with `tuning`, from twins built into `twin_slot` (the observed one)
/// and `plain_slot` (each step's copy, stepped plainly); `counts` holds twice the
/// log's steps (the observer's counts, then the plain steps').
#[inline(never)]
pub fn run_bench1<T: Real, C: Counter, W: Write>(
    twin_slot: &mut MaybeUninit<Twin<T>>,
    plain_slot: &mut MaybeUninit<Twin<T>>,
    counts: &mut [u32],
    counter: &mut C,
    out: &mut W,
    tuning: Tuning,
) -> Result<(), Failed> {
    let name = tuning.name();
    let Some(Some(first)) = samples().next() else {
        record!(out, "{name} error: bench1's first row does not parse");
        return Err(Failed);
    };
    // The filter starts from the first measurement: the crank at the middle of the
    // log's first count (as the PC's replay starts it); the rest is the run file's
    // start (SPEC's, `TwinSettings::reference`, for the nominal run).
    let mut settings = TwinSettings::reference(T::c(PERIOD));
    if tuning == Tuning::Identified {
        identified_start(&mut settings);
    }
    settings.crank = (T::c(first.crank as f64) + T::c(0.5)) * encoder::<T>(0).resolution();
    let start = Inputs {
        motor: MotorInput::Torque(value(first.motor)),
        load: value(first.load),
        measured: None,
    };
    let (params, observer_settings) = match tuning {
        Tuning::Nominal => (CccParams::reference(), ObserverSettings::reference()),
        Tuning::Identified => (identified_converter(), ObserverSettings::identified()),
    };
    let twin = match Twin::new_in(twin_slot, params, settings, start) {
        Ok(t) => t,
        Err(e) => {
            record!(out, "{name} error new: {e}");
            return Err(Failed);
        }
    };
    let mut observer = TwinObserver::new(observer_settings);
    let steps = (samples().count().saturating_sub(1)).min(counts.len() / 2);
    let (observed_counts, rest) = counts.split_at_mut(steps);
    let plain_counts = &mut rest[..steps];
    let mut d = Digest::new();
    let mut now = first;
    for (k, next) in samples().skip(1).take(steps).enumerate() {
        let Some(next) = next else {
            record!(out, "{name} error: bench1's row {} does not parse", k + 2);
            return Err(Failed);
        };
        // Step k + 1 ends at sample k + 1: what the encoders read there.
        let inputs = Inputs {
            motor: MotorInput::Torque(value(now.motor)),
            load: value(now.load),
            measured: Some(Measurement {
                crank: Some(encoder(next.crank)),
                shaft: Some(encoder(next.shaft)),
                rocker: None,
            }),
        };
        let plain = plain_slot.write(twin.clone());
        counter.start();
        let stepped = plain.step(&inputs);
        let c_plain = counter.stop();
        if let Err(e) = stepped {
            record!(out, "{name} error plain step {k}: {e}");
            return Err(Failed);
        }
        let before = (twin.mode(), twin.coordinates());
        counter.start();
        let observed = observer_step(&mut observer, twin, &inputs);
        let c = counter.stop();
        let up = match observed {
            Ok(up) => up,
            Err(e) => {
                record!(out, "{name} error step {k}: {e}");
                return Err(Failed);
            }
        };
        observed_counts[k] = c;
        plain_counts[k] = c_plain;
        hash_twin(&mut d, twin);
        d.real(up.innovation.unwrap_or(T::zero()));
        d.real(up.torque);
        d.real(up.friction);
        if !twin.events().is_empty() || !twin.switches().is_empty() || before.0 != twin.mode() {
            let mut line = Line::new();
            if event_line(&mut line, k as u32, before, twin).is_err() {
                return Err(Failed);
            }
            record!(out, "{name} event {line}");
        }
        now = next;
    }
    record!(
        out,
        "{name} digest {:016x} steps {steps} t {:.6}",
        d.value(),
        twin.time().to_f64()
    );
    if counter.counts() {
        let sum = |c: &[u32]| c.iter().map(|&x| u64::from(x)).sum::<u64>();
        let ratio = 1000 * sum(observed_counts) / sum(plain_counts).max(1);
        let o = Stats::of(observed_counts);
        let p = Stats::of(plain_counts);
        record!(
            out,
            "{name} count observer mean {} median {} worst {} step {} plain mean {} median {} worst {} ratio-permille {ratio}",
            o.mean,
            o.median,
            o.worst,
            o.worst_step,
            p.mean,
            p.median,
            p.worst
        );
    }
    Ok(())
}

/// The one call site of `TwinObserver::step` (see [`step`]).
#[inline(never)]
fn observer_step<T: Real>(
    observer: &mut TwinObserver<T>,
    twin: &mut Twin<T>,
    inputs: &Inputs<T>,
) -> Result<structomat::ccc::Update<T>, TwinStepError> {
    observer.step(twin, inputs)
}
