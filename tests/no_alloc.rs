//! The step path does not touch the heap: a counting global allocator around 1000 DP5
//! steps and a kinetostatics call of each thesis mechanism, and 2000 steps of the
//! converter's twin on S2 (its first 0.2 s: the start, mode events, plastic impacts,
//! coordinate switches), in `f64` and `f32`. The counter is shown to count: the same
//! measurement around a closure that allocates a `Vec` must see it.
//!
//! Only the test's own thread counts (the core has no threads: its allocations would
//! be there): the harness's main thread may allocate while a region is measured, and
//! did (4 allocations in one run of `cargo test --workspace` on a busy machine). This
//! file still holds exactly one test. Nothing inside the measured regions formats or
//! panics; failures are recorded and asserted afterwards.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use structomat::ccc::{CccParams, Inputs, MotorInput, Twin, TwinSettings, TwinStepError};
use structomat::mechanisms::{five_bar, slider_crank, Scenario};
use structomat::motor::Motor;
use structomat::{Real, StepError};

/// `System`, counting the calls that obtain memory (`alloc`, `alloc_zeroed`, `realloc`).
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    // Const-initialized and without a destructor: reading it never allocates.
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.try_with(Cell::get).unwrap_or(false) {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

// SAFETY: every call is forwarded unchanged to `System`; the counter has no effect on
// the memory handed out.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract for `alloc` is passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract for `alloc_zeroed` is passed on.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: the caller's contract for `realloc` is passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract for `dealloc` is passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.load(Ordering::SeqCst)
}

/// The allocations `f` makes.
fn counted<R>(f: impl FnOnce() -> R) -> (usize, R) {
    let before = allocations();
    let r = std::hint::black_box(f());
    (allocations() - before, r)
}

/// Twin steps in the measured region (S2 at h = 1e-4 s: 0.2 s).
const TWIN_STEPS: usize = 2000;

/// Allocations during [`TWIN_STEPS`] steps of the reference converter on S2, the
/// steps done, and the first error.
fn measure_twin<T: Real>() -> (usize, usize, Option<TwinStepError>) {
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let mut twin = Twin::new(
        CccParams::<T>::reference(),
        TwinSettings::reference(T::c(1e-4)),
        inputs,
    )
    .expect("the reference converter sets up");
    let mut done = 0;
    let mut error = None;
    let (n, ()) = counted(|| {
        for _ in 0..TWIN_STEPS {
            match twin.step(&inputs) {
                Ok(()) => done += 1,
                Err(e) => {
                    error = Some(e);
                    break;
                }
            }
            std::hint::black_box(twin.clutch_torques());
        }
    });
    (n, done, error)
}

/// Steps of each mechanism in the measured region.
const STEPS: usize = 1000;

/// What one measured run found: allocations during the steps and during the
/// kinetostatics, and the first error (outside the counted regions' concern).
struct Run {
    step_allocations: usize,
    kinetostatics_allocations: usize,
    steps_done: usize,
    error: Option<StepError>,
}

fn measure<T: Real>(scenario: &Scenario<T>) -> Run {
    // Setup may allocate as it likes (it should not either, but it is not measured).
    let mut sim = scenario.simulation().expect("simulation setup");
    let mut run = Run {
        step_allocations: 0,
        kinetostatics_allocations: 0,
        steps_done: 0,
        error: None,
    };

    let before = allocations();
    for _ in 0..STEPS {
        match sim.step() {
            Ok(()) => run.steps_done += 1,
            Err(e) => {
                run.error = Some(e);
                break;
            }
        }
    }
    run.step_allocations = allocations() - before;
    std::hint::black_box(sim.q());

    if run.error.is_none() {
        let before = allocations();
        let r = sim
            .kinetostatics()
            .map(|ws| std::hint::black_box(ws.reactions[0][0]));
        run.kinetostatics_allocations = allocations() - before;
        run.error = r.err();
    }
    run
}

#[test]
fn step_and_kinetostatics_do_not_allocate() {
    COUNTED.with(|c| c.set(true));
    // The counter works (the test is not vacuous): the measurement sees one `Vec`.
    let (n, v) = counted(|| vec![0u8; 16]);
    drop(v);
    assert_eq!(n, 1, "the counting allocator is not in use");
    let (n, ()) = counted(|| ());
    assert_eq!(n, 0, "the measurement allocates by itself");

    let slider_f64 = slider_crank::<f64>().expect("slider-crank model");
    let five_f64 = five_bar::<f64>().expect("five-bar model");
    let slider_f32 = slider_crank::<f32>().expect("slider-crank model");
    let five_f32 = five_bar::<f32>().expect("five-bar model");

    let runs = [
        ("slider_crank/f64", measure(&slider_f64)),
        ("five_bar/f64", measure(&five_f64)),
        ("slider_crank/f32", measure(&slider_f32)),
        ("five_bar/f32", measure(&five_f32)),
    ];

    for (name, (n, done, error)) in [
        ("twin/f64", measure_twin::<f64>()),
        ("twin/f32", measure_twin::<f32>()),
    ] {
        assert!(
            error.is_none(),
            "{name}: failed after {done} steps: {error:?}"
        );
        assert_eq!(done, TWIN_STEPS, "{name}: steps done");
        assert_eq!(n, 0, "{name}: heap allocations during {TWIN_STEPS} steps");
    }

    for (name, run) in &runs {
        assert!(
            run.error.is_none(),
            "{name}: failed after {} steps: {:?}",
            run.steps_done,
            run.error
        );
        assert_eq!(run.steps_done, STEPS, "{name}: steps done");
        assert_eq!(
            run.step_allocations, 0,
            "{name}: heap allocations during {STEPS} steps"
        );
        assert_eq!(
            run.kinetostatics_allocations, 0,
            "{name}: heap allocations during kinetostatics()"
        );
    }
}
