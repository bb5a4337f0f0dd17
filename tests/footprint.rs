//! Footprint of the core in RAM (issue 4): the static size of the data a firmware keeps
//! (model, workspace, simulation, twin) and the stack high-water of a step, measured by
//! painting the stack.
//!
//! Every size is fixed at compile time by the capacities in `structomat::config`, so it is
//! the same for every mechanism; the tables printed here (`--nocapture`) are the ones in
//! the README. The budgets asserted are those of a Cortex-M4F with 128 KiB of RAM
//! (e.g. an STM32F4): the f32 twin and its worst step must fit in half of it.
//!
//! Run `cargo test --release --test footprint -- --nocapture` for the figures of an
//! optimised build (the README's); the debug build's frames are several times larger,
//! and its budgets below are correspondingly looser.

use std::hint::black_box;
use std::mem::{size_of, MaybeUninit};
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinObserver, TwinSettings};
use structomat::mechanisms::{five_bar, slider_crank};
use structomat::model::Model;
use structomat::motor::Motor;
use structomat::workspace::Workspace;
use structomat::{Real, Simulation};

const KIB: usize = 1024;

/// The pattern painted on the free stack; a word that still holds it was not written.
const PAINT: u64 = 0x5A5A_C3C3_A5A5_3C3C;

/// Paints `depth` bytes of free stack below this function's frame. Runs in its own
/// (never inlined) frame, which is gone before the measured code runs.
#[inline(never)]
fn paint(depth: usize) -> usize {
    let here = 0u8;
    // 1 KiB below this frame's own local: past this frame's spills and call area.
    let top = (black_box(&here) as *const u8 as usize - KIB) & !7;
    let bottom = top - depth;
    let mut a = bottom;
    while a < top {
        // SAFETY: `[bottom, top)` lies inside this thread's stack (`measure_stack` spawns
        // the thread with room for `depth` plus a margin), below every live frame; no
        // one else uses it while it is painted.
        unsafe { std::ptr::write_volatile(a as *mut u64, PAINT) };
        a += 8;
    }
    bottom
}

/// Runs `f` on a thread of its own and returns how many bytes of stack `f` used below
/// the caller's frame: the distance from a local of the measuring frame down to the
/// lowest painted word that `f` overwrote.
fn measure_stack<R: Send>(depth: usize, f: impl FnOnce() -> R + Send) -> (usize, R) {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(depth + 256 * KIB)
            .spawn_scoped(s, move || {
                let marker = 0u8;
                let reference = black_box(&marker) as *const u8 as usize;
                let bottom = paint(depth);
                let result = f();
                let mut a = bottom;
                // SAFETY: the same painted region; `f` has returned, nothing lives there.
                while a < reference && unsafe { std::ptr::read_volatile(a as *const u64) } == PAINT
                {
                    a += 8;
                }
                assert!(
                    a > bottom,
                    "the painted {depth} B were all used: paint deeper"
                );
                (reference - a, result)
            })
            .expect("spawn the measuring thread")
            .join()
            .expect("the measured code panicked")
    })
}

/// Uses `n` bytes of stack in one frame (writes every byte, reads them back).
#[inline(never)]
fn use_stack<const N: usize>() -> u64 {
    let mut buf = [0u8; N];
    for (i, b) in buf.iter_mut().enumerate() {
        *b = black_box(i as u8);
    }
    black_box(&buf).iter().map(|b| u64::from(*b)).sum()
}

/// The painter against a known frame: a 64 KiB array is seen as 64 KiB (plus the small
/// frames around it), and nothing much beyond.
#[test]
fn the_stack_painter_sees_a_known_frame() {
    let (used, _) = measure_stack(512 * KIB, use_stack::<{ 64 * KIB }>);
    println!("64 KiB array: {used} B of stack");
    assert!(used >= 64 * KIB, "{used} B < the 64 KiB array");
    let slack = if cfg!(debug_assertions) {
        16 * KIB
    } else {
        4 * KIB
    };
    assert!(
        used <= 64 * KIB + slack,
        "{used} B: the painter over-counts"
    );
}

/// S2's inputs (12 N·m, T_r = 800 N·m), with a measured crank state to compare against.
fn s2_inputs<T: Real>() -> Inputs<T> {
    Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: Some(structomat::ccc::Measurement {
            crank: Some(structomat::ccc::Encoder {
                counts: 1194,
                per_turn: 4096,
                zero: T::zero(),
            }),
            shaft: Some(structomat::ccc::Encoder {
                counts: 0,
                per_turn: 4096,
                zero: T::zero(),
            }),
            rocker: None,
        }),
    }
}

/// A boxed twin of S2 (CW shaft), built outside the measured region.
fn s2_twin<T: Real>() -> Box<Twin<T>> {
    Box::new(
        Twin::new(
            CccParams::<T>::reference(),
            TwinSettings::reference(T::c(1e-4)),
            s2_inputs(),
        )
        .expect("the reference converter builds"),
    )
}

/// Steps `twin` `steps` times; returns the successful steps and the events logged.
fn step_s2<T: Real>(twin: &mut Twin<T>, steps: u32) -> (u32, usize) {
    let inputs = s2_inputs();
    let (mut ok, mut events) = (0, 0);
    for _ in 0..steps {
        if twin.step(&inputs).is_ok() {
            ok += 1;
        }
        events += twin.events().len();
    }
    (ok, events)
}

/// The stack high-water of a twin step, over the first 0.1 s of S2 (every step measured
/// together: the deepest one counts). The first 0.1 s holds the first breakaway at
/// 0.0666 s (a catch: four candidate modes, a plastic impact) and coordinate switches,
/// the twin's deepest paths.
#[test]
fn stack_of_a_twin_step() {
    let depth = if cfg!(debug_assertions) { 4096 } else { 512 } * KIB;
    let mut twin = s2_twin::<f64>();
    let (f64_used, (ok, events)) = measure_stack(depth, || step_s2(&mut twin, 1000));
    assert_eq!(ok, 1000, "every S2 step succeeds");
    assert!(events >= 1, "the first 0.1 s of S2 has a breakaway");
    let mut twin32 = s2_twin::<f32>();
    let (f32_used, (ok32, _)) = measure_stack(depth, || step_s2(&mut twin32, 1000));
    assert_eq!(ok32, 1000);
    println!("stack of a twin step (1000 steps of S2, 0.1 s, events included): f64 {f64_used} B, f32 {f32_used} B");
    // Release: 14.5 KiB (f64) and 8.5 KiB (f32) measured on x86_64; the scratch slots (30 KB in
    // f64) are rebuilt in place, never held on the stack, and these budgets catch a
    // slot, a model or a workspace that comes back as a temporary.
    let budget = if cfg!(debug_assertions) { 128 } else { 24 } * KIB;
    assert!(f64_used < budget, "f64: {f64_used} B of stack");
    let budget32 = if cfg!(debug_assertions) { 96 } else { 12 } * KIB;
    assert!(f32_used < budget32, "f32: {f32_used} B of stack");
    // f32 halves every buffer: its frames cannot be larger than f64's.
    assert!(f32_used <= f64_used, "f32 {f32_used} B > f64 {f64_used} B");
}

/// The stack of construction: [`Twin::new_in`] builds the twin where it lives, with no
/// slot, model or workspace on the stack (at most a group's data, 1.2 KB in f64, and
/// the frames of the first mode choice, which are a step's); [`Twin::new`] by value
/// needs several times the twin's size.
#[test]
fn stack_of_construction_in_place() {
    fn build<T: Real>(place: &mut MaybeUninit<Twin<T>>) -> u64 {
        let twin = Twin::new_in(
            place,
            CccParams::<T>::reference(),
            TwinSettings::reference(T::c(1e-4)),
            s2_inputs(),
        )
        .expect("the reference converter builds in place");
        twin.steps()
    }
    let depth = if cfg!(debug_assertions) { 4096 } else { 512 } * KIB;
    let mut place64 = Box::new(MaybeUninit::<Twin<f64>>::uninit());
    let (f64_used, _) = measure_stack(depth, || build(&mut place64));
    let mut place32 = Box::new(MaybeUninit::<Twin<f32>>::uninit());
    let (f32_used, _) = measure_stack(depth, || build(&mut place32));
    let (by_value, _) = measure_stack(depth, || {
        Twin::new(
            CccParams::<f64>::reference(),
            TwinSettings::reference(1e-4),
            s2_inputs(),
        )
        .expect("the reference converter builds")
        .steps()
    });
    println!("stack of construction: in place f64 {f64_used} B, f32 {f32_used} B; by value f64 {by_value} B");
    // In place it is a step's stack (the first mode choice is one), under the budgets of
    // `stack_of_a_twin_step`; by value it holds at least the twin itself.
    let budget = if cfg!(debug_assertions) { 128 } else { 24 } * KIB;
    assert!(f64_used < budget, "f64 in place: {f64_used} B of stack");
    let budget32 = if cfg!(debug_assertions) { 96 } else { 12 } * KIB;
    assert!(f32_used < budget32, "f32 in place: {f32_used} B of stack");
    assert!(by_value >= size_of::<Twin<f64>>(), "by value: {by_value} B");
}

/// The stack high-water of the generic core's step: 1000 DP5 steps and the kinetostatics
/// of each thesis mechanism.
#[test]
fn stack_of_a_core_step() {
    fn run<T: Real>(sim: &mut Simulation<T>) -> u32 {
        let mut ok = 0;
        for _ in 0..1000 {
            if sim.step().is_ok() && sim.kinetostatics().is_ok() {
                ok += 1;
            }
        }
        ok
    }
    fn measure<T: Real>(scenario: structomat::mechanisms::Scenario<T>) -> (usize, u32) {
        let mut sim = Box::new(scenario.simulation().expect("the scenario assembles"));
        let depth = if cfg!(debug_assertions) { 2048 } else { 256 } * KIB;
        measure_stack(depth, || run(&mut sim))
    }
    // Release: 6.5 KiB (f64), 3.5 KiB (f32) measured.
    let budget = if cfg!(debug_assertions) { 32 } else { 10 } * KIB;
    for (name, (used, ok)) in [
        ("five-bar f64", measure(five_bar::<f64>().unwrap())),
        ("five-bar f32", measure(five_bar::<f32>().unwrap())),
        ("slider-crank f64", measure(slider_crank::<f64>().unwrap())),
        ("slider-crank f32", measure(slider_crank::<f32>().unwrap())),
    ] {
        println!("stack of a core step + kinetostatics, {name}: {used} B");
        assert_eq!(ok, 1000, "{name}: every step succeeds");
        assert!(used < budget, "{name}: {used} B of stack");
    }
}

/// Static sizes: fixed by `structomat::config`'s capacities, the same for every
/// mechanism. The twin holds three slots (the current mode, the backup and the
/// candidate slot; the mode choice's reference I0 model is built in the one it leaves
/// free), each a model and a workspace sized for the converter.
#[test]
fn static_sizes_fit_the_budget() {
    let rows = [
        ("Model<f64>", size_of::<Model<f64>>()),
        ("Model<f32>", size_of::<Model<f32>>()),
        ("Workspace<f64>", size_of::<Workspace<f64>>()),
        ("Workspace<f32>", size_of::<Workspace<f32>>()),
        ("Simulation<f64>", size_of::<Simulation<f64>>()),
        ("Simulation<f32>", size_of::<Simulation<f32>>()),
        ("Twin<f64>", size_of::<Twin<f64>>()),
        ("Twin<f32>", size_of::<Twin<f32>>()),
        ("TwinObserver<f64>", size_of::<TwinObserver<f64>>()),
        ("TwinObserver<f32>", size_of::<TwinObserver<f32>>()),
    ];
    for (name, bytes) in rows {
        println!(
            "{name:18} {bytes:7} B  {:6.1} KiB",
            bytes as f64 / KIB as f64
        );
    }
    // A simulation is its model, its workspace and a few states. The twin holds three
    // slots, each a model and a workspace sized for the converter, smaller than these
    // generic ones (the core's tests check it is three slots and its state).
    for (sim, twin, model, ws) in [
        (
            size_of::<Simulation<f64>>(),
            size_of::<Twin<f64>>(),
            size_of::<Model<f64>>(),
            size_of::<Workspace<f64>>(),
        ),
        (
            size_of::<Simulation<f32>>(),
            size_of::<Twin<f32>>(),
            size_of::<Model<f32>>(),
            size_of::<Workspace<f32>>(),
        ),
    ] {
        assert!(sim >= model + ws && sim <= model + ws + 2 * KIB);
        assert!(
            twin < 3 * (model + ws),
            "{twin} B: more than three generic slots"
        );
    }
    // Budgets: the f32 twin in 32 KiB (a quarter of the RAM of a 128 KiB Cortex-M4F),
    // the f64 twin in 64 KiB (issue 18; the core asserts them at compile time too), a
    // generic simulation in 32 KiB (f64) / 16 KiB (f32).
    assert!(size_of::<Twin<f32>>() <= 32 * KIB);
    assert!(size_of::<Twin<f64>>() <= 64 * KIB);
    assert!(size_of::<Simulation<f64>>() <= 32 * KIB);
    assert!(size_of::<Simulation<f32>>() <= 16 * KIB);
    // f32 halves the floating-point data; indices and flags stay.
    let ratio = size_of::<Twin<f32>>() as f64 / size_of::<Twin<f64>>() as f64;
    assert!(
        (0.5..0.56).contains(&ratio),
        "f32/f64 twin size ratio {ratio}"
    );
}
