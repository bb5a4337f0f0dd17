//! A firmware example: the twin in a 1 kHz control loop on an emulated Cortex-M board.
//!
//! Each period the loop reads the crank's incremental encoder (counts) and the motor's
//! torque sensor, steps the twin with that torque and the crank encoder's count, and
//! reports the mode and the residuals (twin minus measurement: the crank's angle, and its
//! speed against the count's rate) every 50 ms. The
//! machine itself is simulated here too: a second twin, driven by S2's 12 N·m motor
//! against a load 2 % heavier than the model's, read through a 4096-count encoder
//! and a torque sensor with a ±0.02 N·m deterministic noise.
//!
//! A step that fails (a bad reading, a step the twin cannot take) keeps the twin's last
//! good state: the loop reports it and goes on with the next period's readings.
//!
//! On the Cortex-M4F the twin spreads each event's work over the periods after it
//! (`TwinSettings::spread_events`): the period that finds an event ends the twin at
//! it, the next chooses the mode, the ones after catch up with the clock; while the
//! twin is behind it reports its lag instead of residuals.
//!
//! ```sh
//! checks/firmware/run    # builds it for both boards and runs it under QEMU
//! ```
#![no_std]
#![no_main]

use core::f64::consts::TAU;
use core::mem::MaybeUninit;
use cortex_m_rt::entry;
use structomat::ccc::{CccParams, Inputs, Measurement, MotorInput, Twin, TwinSettings};
use structomat::motor::Motor;
use structomat::Real;

#[path = "../target.rs"]
mod target;
use target::{exit, Out, SysTick, BOARD, SCALAR, SPREAD};

type R = target::R;

/// The loop's period, s: the twin's step.
const PERIOD: f64 = 1e-3;
/// Periods run: 1 s.
const PERIODS: u32 = 1_000;
/// Encoder counts per crank revolution (quadrature-decoded).
const COUNTS_PER_REV: f64 = 4096.0;
/// The load on the model's shaft, N·m (S2), and on the simulated machine's.
const LOAD: f64 = 800.0;
const MACHINE_LOAD: f64 = 816.0;

/// The simulated machine and its sensors.
struct Machine {
    plant: &'static mut Twin<R>,
    /// The crank angle at the encoder's zero, rad.
    zero: R,
    /// Noise generator state (xorshift32).
    noise: u32,
}

impl Machine {
    fn inputs() -> Inputs<R> {
        Inputs {
            motor: MotorInput::Law(Motor::Constant(R::c(12.0))),
            load: R::c(MACHINE_LOAD),
            measured: None,
        }
    }

    /// One period of the real machine; false if its simulation fails.
    fn run_period(&mut self) -> bool {
        self.plant.step(&Self::inputs()).is_ok()
    }

    /// The encoder's count now.
    fn encoder(&self) -> i32 {
        let turned = (self.plant.link(1).theta - self.zero).to_f64();
        round(turned / TAU * COUNTS_PER_REV) as i32
    }

    /// The torque sensor's reading over the last period, N·m.
    fn torque_sensor(&mut self) -> R {
        self.noise ^= self.noise << 13;
        self.noise ^= self.noise >> 17;
        self.noise ^= self.noise << 5;
        let unit = f64::from(self.noise) / f64::from(u32::MAX) * 2.0 - 1.0;
        R::c(self.plant.motor_torque().to_f64() + 0.02 * unit)
    }
}

/// Rounds half away from zero (core has no `f64::round` without std).
fn round(x: f64) -> f64 {
    let t = x as i64 as f64;
    if x - t >= 0.5 {
        t + 1.0
    } else if t - x >= 0.5 {
        t - 1.0
    } else {
        t
    }
}

#[entry]
fn main() -> ! {
    static mut TWIN: MaybeUninit<Twin<R>> = MaybeUninit::uninit();
    static mut PLANT: MaybeUninit<Twin<R>> = MaybeUninit::uninit();

    let mut out = Out::new();
    let mut clock = SysTick::start();
    out.line(format_args!(
        "example {BOARD} {SCALAR}: 1 kHz loop, encoder {COUNTS_PER_REV} counts/rev"
    ));
    let mut settings = TwinSettings::reference(R::c(PERIOD));
    // The loop's twin spreads its events where that keeps the worst step within the
    // period (the M4F); the simulated machine is not timed and takes each event whole.
    let plant_settings = settings;
    settings.spread_events = SPREAD;
    let start = Inputs {
        motor: MotorInput::Torque(R::c(12.0)),
        load: R::c(LOAD),
        measured: None,
    };
    // Each twin built where it lives, in its static: no twin on the stack.
    let twin = match Twin::new_in(TWIN, CccParams::reference(), settings, start) {
        Ok(t) => t,
        Err(e) => {
            out.line(format_args!("twin: {e}"));
            exit(false)
        }
    };
    let plant = match Twin::new_in(
        PLANT,
        CccParams::reference(),
        plant_settings,
        Machine::inputs(),
    ) {
        Ok(t) => t,
        Err(e) => {
            out.line(format_args!("machine: {e}"));
            exit(false)
        }
    };
    let zero = plant.link(1).theta;
    let mut machine = Machine {
        plant,
        zero,
        noise: 0x2545_f491,
    };
    let (mut last_count, mut worst, mut worst_at, mut sum, mut failed) =
        (0i32, 0u32, 0u32, 0u64, 0u32);
    for k in 0..PERIODS {
        // The machine moves during the period; the loop then samples its sensors.
        if !machine.run_period() {
            out.line(format_args!("the simulated machine failed at period {k}"));
            exit(false)
        }
        let count = machine.encoder();
        let torque = machine.torque_sensor();
        let speed = R::c(f64::from(count - last_count) / COUNTS_PER_REV * TAU / PERIOD);
        last_count = count;
        let inputs = Inputs {
            motor: MotorInput::Torque(torque),
            load: R::c(LOAD),
            // The machine's encoder rounds: count k's cell starts half a count below.
            measured: Some(Measurement::crank(
                i64::from(count),
                COUNTS_PER_REV as u32,
                zero - R::c(TAU / COUNTS_PER_REV / 2.0),
            )),
        };

        clock.mark();
        let stepped = twin.step(&inputs);
        let instructions = clock.instructions();
        if instructions > worst {
            (worst, worst_at) = (instructions, k);
        }
        sum += u64::from(instructions);

        if let Err(e) = stepped {
            failed += 1;
            out.line(format_args!(
                "period {k}: step refused, last good state kept: {e}"
            ));
        }
        if (k + 1) % 50 == 0 || !twin.events().is_empty() {
            let (t, mode, coordinates) = (
                twin.time().to_f64(),
                twin.mode().name(),
                twin.coordinates().name(),
            );
            let torque = torque.to_f64();
            // While the twin catches up with the clock after an event its state is not
            // the machine's at the sample: no residual then, the lag instead.
            match twin.measurement_residual().and_then(|r| r.crank) {
                Some(da) => {
                    let dw = twin.link(1).omega - speed;
                    out.line(format_args!(
                        "t={t:.3} {mode}/{coordinates} count {count} torque {torque:.3} residual {:+.2e} rad {:+.2e} rad/s step {instructions} instructions",
                        da.to_f64(),
                        dw.to_f64(),
                    ))
                }
                None => out.line(format_args!(
                    "t={t:.3} {mode}/{coordinates} count {count} torque {torque:.3} behind the clock by {:.2e} s step {instructions} instructions",
                    twin.lag().to_f64(),
                )),
            }
        }
    }
    out.line(format_args!(
        "example: {PERIODS} periods, {failed} refused, mean {} worst {worst} (period {worst_at}) instructions a step",
        sum / u64::from(PERIODS)
    ));
    out.line(format_args!("done"));
    exit(true)
}
