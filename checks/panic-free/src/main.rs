//! Panic-freedom check: no panic is reachable from the twin's step path.
//!
//! The panic handler below calls [`structomat_step_path_can_panic`], which is declared
//! and never defined. A release build with fat LTO keeps only the code reachable from
//! `main`, so the build links if and only if the optimiser proved every panic on these
//! paths unreachable (every bounds check, every `unwrap`, every slice split). If one
//! survives, the link fails and the linker names the function that still calls the
//! handler.
//!
//! Every input passes through [`core::hint::black_box`], so nothing is folded away
//! because its value happens to be known at compile time: the proof holds for any
//! parameters, inputs and measured values, including NaN and infinities.
//!
//! What is checked, for `f64` and `f32`:
//! - [`Twin::new_in`] (and [`Twin::new`], feature `twin-by-value`) with arbitrary
//!   parameters and settings, [`Twin::step`] with arbitrary inputs, and the twin's
//!   output accessors;
//! - the observed twin (features `observer-f64`, `observer-f32`): [`TwinObserver::step`]
//!   with arbitrary encoder counts, resolutions and zeros (its update, the correction
//!   [`Twin::correct_crank`] and the diagnostics), and what it reports;
//! - the generic core: building the thesis's five-bar, [`Simulation::step`] (through
//!   the dead-point switching's `Alternatives::step`), the kinetostatics, and the first
//!   model's evaluation while an alternative drives (`Alternatives::first_evaluation`).
#![no_std]
#![no_main]

use core::hint::black_box;
use core::mem::MaybeUninit;
use core::panic::PanicInfo;
use structomat::ccc::{
    CccParams, Encoder, Inputs, Measurement, MotorInput, ObserverSettings, Twin, TwinObserver,
    TwinSettings,
};
use structomat::motor::Motor;
use structomat::simulation::switch::{Alternatives, SwitchSettings};
use structomat::Real;

// On the host `main` is called by the C runtime: link libc (a no_std binary gets
// `-nodefaultlibs`). On bare metal `build.rs` makes `main` the entry point.
#[cfg_attr(target_os = "linux", link(name = "c"))]
extern "C" {}

extern "Rust" {
    /// Defined nowhere: a reachable panic makes the link fail on this symbol.
    fn structomat_step_path_can_panic() -> !;
}

#[cfg(not(feature = "diagnose"))]
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    // SAFETY: never runs: the binary only links when no call to it remains.
    unsafe { structomat_step_path_can_panic() }
}

/// With `--features diagnose` the binary links whatever panics remain, so that its
/// disassembly shows which functions still call into `core::panicking` (see README).
#[cfg(feature = "diagnose")]
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

/// Runs the twin for `steps` steps with opaque parameters and inputs; returns a checksum
/// of the outputs so that none of them is optimised away.
fn twin<T: Real>(steps: u32) -> T {
    let params: CccParams<T> = black_box(CccParams::reference());
    let settings: TwinSettings<T> = black_box(TwinSettings::reference(black_box(T::c(1e-4))));
    let mut inputs = Inputs {
        motor: MotorInput::Law(black_box(Motor::Constant(T::c(12.0)))),
        load: T::c(800.0),
        measured: None,
    };
    // Built in place, as firmware builds it (in a static there; here the binary only
    // links); `Twin::new` by value too with the feature `twin-by-value`.
    let mut by_value = None;
    let mut place = MaybeUninit::uninit();
    let twin = if cfg!(feature = "twin-by-value") && black_box(steps) % 2 == 1 {
        match Twin::new(params, settings, black_box(inputs)) {
            Ok(t) => by_value.insert(t),
            Err(_) => return T::zero(),
        }
    } else {
        match Twin::new_in(&mut place, params, settings, black_box(inputs)) {
            Ok(t) => t,
            Err(_) => return T::zero(),
        }
    };
    let mut sum = T::zero();
    for _ in 0..black_box(steps) {
        inputs = black_box(inputs);
        if twin.step(&inputs).is_err() {
            sum += T::one();
        }
        let [c6, c8] = twin.clutch_torques();
        sum += c6 + c8 + twin.shaft_speed() + twin.audit().residual() + twin.motor_torque();
        for v in twin.q().iter().chain(twin.qd()).chain(twin.qdd()) {
            sum += *v;
        }
        for r in twin.joint_reactions() {
            sum += r.x + r.y;
        }
        for p in 1..=8 {
            sum += twin.link(black_box(p)).theta;
        }
        if let Some(r) = twin.measurement_residual() {
            for v in [r.crank, r.shaft, r.rocker].into_iter().flatten() {
                sum += v;
            }
        }
        sum += T::c((twin.events().len() + twin.switches().len()) as f64) + twin.lag();
    }
    sum
}

/// The observed twin: built in place, `steps` observer steps with opaque encoder
/// readings (any counts, resolutions and zeros, NaN included); returns a checksum of
/// what the observer reports.
fn observed<T: Real>(steps: u32) -> T {
    let params: CccParams<T> = black_box(CccParams::reference());
    let settings: TwinSettings<T> = black_box(TwinSettings::reference(black_box(T::c(1e-3))));
    let encoder = |counts: i64| Encoder {
        counts: black_box(counts),
        per_turn: black_box(4096),
        zero: black_box(T::zero()),
    };
    let mut inputs = Inputs {
        motor: MotorInput::Torque(black_box(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let mut place = MaybeUninit::uninit();
    let Ok(twin) = Twin::new_in(&mut place, params, settings, black_box(inputs)) else {
        return T::zero();
    };
    let mut observer = TwinObserver::new(black_box(ObserverSettings::reference()));
    let mut sum = T::zero();
    for k in 0..black_box(steps) {
        inputs.measured = black_box(Some(Measurement {
            crank: Some(encoder(i64::from(k))),
            shaft: Some(encoder(-i64::from(k))),
            rocker: Some(encoder(i64::from(k) / 2)),
        }));
        match observer.step(twin, &black_box(inputs)) {
            Ok(up) => {
                for v in [up.innovation, up.innovation_var, up.shaft_innovation]
                    .into_iter()
                    .flatten()
                {
                    sum += v;
                }
                sum += up.torque + T::c(up.diagnostics.iter().count() as f64);
                if let Some(c) = up.correction {
                    sum += c.crank.0 + c.crank.1;
                }
            }
            Err(_) => sum += T::one(),
        }
        let p = observer.covariance();
        sum += p.angle() + p.speed() + p.torque() + observer.torque() + twin.shaft_drive_angle();
    }
    sum
}

/// The generic core: the five-bar, `steps` fixed DP5 steps and the kinetostatics.
fn five_bar<T: Real>(steps: u32) -> T {
    let Ok(scenario) = structomat::mechanisms::five_bar::<T>() else {
        return T::zero();
    };
    let Ok(mut sim) = black_box(scenario).simulation() else {
        return T::zero();
    };
    let mut sum = T::zero();
    // The dead-point switching, with the model itself as its one alternative (the
    // optimiser cannot tell it from another choice of coordinates).
    let Ok(mut alts) = Alternatives::<T, 2>::new(&sim, SwitchSettings::default()) else {
        return T::zero();
    };
    if alts.add(black_box(sim.model().clone())).is_err() {
        return T::zero();
    }
    for _ in 0..black_box(steps) {
        if alts.step(&mut sim).is_err() {
            sum += T::one();
        }
        if sim.kinetostatics().is_err() {
            sum += T::one();
        }
        if let Some((_, ws)) = alts.first_evaluation(&sim) {
            sum += ws.qdd[0] + ws.motor[0];
        }
        for v in sim.q() {
            sum += *v;
        }
    }
    sum
}

#[no_mangle]
extern "C" fn main(argc: i32, _argv: *const *const u8) -> i32 {
    let steps = black_box(argc as u32);
    #[cfg(feature = "canary")]
    {
        // One reachable panic (an index the optimiser cannot prove in bounds).
        let table = black_box([1u8, 2, 3]);
        if table[black_box(steps as usize)] == 0 {
            return 3;
        }
    }
    let mut bad = 0;
    if cfg!(feature = "twin-f64") {
        bad += i32::from(!twin::<f64>(steps).finite());
    }
    if cfg!(feature = "twin-f32") {
        bad += i32::from(!twin::<f32>(steps).finite());
    }
    if cfg!(feature = "observer-f64") {
        bad += i32::from(!observed::<f64>(steps).finite());
    }
    if cfg!(feature = "observer-f32") {
        bad += i32::from(!observed::<f32>(steps).finite());
    }
    if cfg!(feature = "core-f64") {
        bad += i32::from(!five_bar::<f64>(steps).finite());
    }
    if cfg!(feature = "core-f32") {
        bad += i32::from(!five_bar::<f32>(steps).finite());
    }
    bad
}
