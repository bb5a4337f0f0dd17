//! The encoders in the twin's inputs and the observer ([`TwinObserver`]), against
//! oracles independent of the observer's code: a second twin stepped open-loop as the
//! machine (its true angles, read through the bench's encoder law `floor(θ / (2π/N))`),
//! the crank's change asked of a correction, the energy audit's balance, and the
//! injected faults' known instants.

use std::f64::consts::TAU;
use structomat::ccc::{
    CccParams, Diagnostic, Encoder, Inputs, Measurement, Mode, MotorInput, ObserverSettings, Twin,
    TwinObserver, TwinSettings, TwinStepError,
};
use structomat::motor::{Asynchronous, Motor};
use structomat::Real;

const N: u32 = 4096;
const H: f64 = 1e-3;

/// The bench's encoder law.
fn counts(theta: f64) -> i64 {
    (theta / (TAU / f64::from(N))).floor() as i64
}

fn encoder<T: Real>(c: i64) -> Encoder<T> {
    Encoder {
        counts: c,
        per_turn: N,
        zero: T::zero(),
    }
}

/// S2's inputs (SPEC: 12 N·m, T_r = 800 N·m) with the encoders' reading `m`.
fn s2_inputs<T: Real>(m: Option<Measurement<T>>) -> Inputs<T> {
    Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: m,
    }
}

fn twin<T: Real>(crank_deg: f64) -> Twin<T> {
    let mut s = TwinSettings::reference(T::c(H));
    s.crank = T::c(crank_deg.to_radians());
    Twin::new(CccParams::reference(), s, s2_inputs(None)).expect("S2 assembles")
}

/// The machine: S2's twin in f64 stepped open-loop, read at each step's end.
struct Machine {
    twin: Twin<f64>,
}

impl Machine {
    fn new() -> Self {
        Machine { twin: twin(105.0) }
    }

    /// One period; the encoders' `(crank, shaft)` counts at its end.
    fn period(&mut self) -> (i64, i64) {
        self.period_under(&s2_inputs(None))
    }

    /// One period under the machine's own `inputs` (another motor or brake than the
    /// twin is told); the encoders' counts at its end.
    fn period_under(&mut self, inputs: &Inputs<f64>) -> (i64, i64) {
        self.twin.step(inputs).expect("the machine steps");
        (
            counts(self.twin.link(1).theta),
            counts(self.twin.shaft_drive_angle()),
        )
    }
}

fn reading<T: Real>(c: (i64, i64)) -> Measurement<T> {
    Measurement {
        crank: Some(encoder(c.0)),
        shaft: Some(encoder(c.1)),
        rocker: None,
    }
}

/// The twin's state as bits: time, every link, the audit.
fn bits<T: Real>(t: &Twin<T>) -> Vec<u64> {
    let mut v = vec![t.time().to_f64().to_bits(), t.steps()];
    for p in 1..9 {
        let l = t.link(p);
        v.extend([l.theta, l.omega, l.alpha].map(|x| x.to_f64().to_bits()));
    }
    v.push(t.audit().residual().to_f64().to_bits());
    v
}

/// S2's machine, its twin from the machine's start and the reference observer after
/// `steps` good readings; the last reading.
fn observed_for(steps: usize) -> (Machine, Twin<f64>, TwinObserver<f64>, (i64, i64)) {
    let mut machine = Machine::new();
    let mut t = twin::<f64>(105.0);
    let mut obs = TwinObserver::new(ObserverSettings::reference());
    let mut last = (0, 0);
    for _ in 0..steps {
        last = machine.period();
        obs.step(&mut t, &s2_inputs(Some(reading(last))))
            .expect("a good reading");
    }
    (machine, t, obs, last)
}

/// Each bad reading is refused by name (resolution 0, a zero angle that is not finite,
/// a count that jumps by half a turn or more in a step, of each encoder) and neither the
/// twin nor the observer moves: the state is the last good one, bit for bit.
#[test]
fn bad_readings_are_named_errors_and_the_state_is_kept() {
    let (_, mut t, mut obs, last) = observed_for(30);
    let (state, p) = (bits(&t), obs.covariance());
    let good: Measurement<f64> = reading(last);
    let mut cases: Vec<(Measurement<f64>, &str, &str)> = Vec::new();
    for (k, name) in ["crank", "shaft", "rocker"].into_iter().enumerate() {
        fn slot(m: &mut Measurement<f64>, k: usize) -> &mut Option<Encoder<f64>> {
            match k {
                0 => &mut m.crank,
                1 => &mut m.shaft,
                _ => &mut m.rocker,
            }
        }
        let mut m = good;
        let base = slot(&mut m, k).unwrap_or(encoder(0));
        let mut bad = m;
        *slot(&mut bad, k) = Some(Encoder {
            per_turn: 0,
            ..base
        });
        cases.push((bad, name, "resolution (counts per turn) = 0e0 must be > 0"));
        let mut bad = m;
        *slot(&mut bad, k) = Some(Encoder {
            zero: f64::NAN,
            ..base
        });
        cases.push((bad, name, "zero = not a number must be finite"));
    }
    for (m, name, want) in cases {
        let e = obs.step(&mut t, &s2_inputs(Some(m))).unwrap_err();
        assert!(matches!(e, TwinStepError::BadInput { .. }), "{e:?}");
        let text = e.to_string();
        assert!(text.contains(&format!("{name} encoder {want}")), "{text}");
        assert_eq!(bits(&t), state, "{name}: the twin moved");
        assert_eq!(obs.covariance(), p, "{name}: the observer moved");
    }
    // Just under half a turn is a reading (the twin takes it; the observer's gate
    // names it a jump and does not correct by it).
    let mut m = good;
    m.crank = Some(encoder(last.0 + 2047));
    let up = obs.step(&mut t, &s2_inputs(Some(m))).expect("a reading");
    assert!(up.diagnostics.contains(Diagnostic::EncoderJump("crank")));
    assert!(up.correction.is_none());
    // Half a turn in a step, of either encoder: refused, named, the state kept.
    let (crank, shaft) = (last.0 + 2047, last.1);
    for (k, name) in ["crank", "shaft"].into_iter().enumerate() {
        let (state, p) = (bits(&t), obs.covariance());
        let jumped = [crank + 2048 * (1 - k as i64), shaft + 2048 * k as i64];
        let e = obs
            .step(&mut t, &s2_inputs(Some(reading((jumped[0], jumped[1])))))
            .unwrap_err();
        let want = "encoder jump (counts in one step) = 2.048e3 must be under half a turn";
        assert!(e.to_string().contains(&format!("{name} {want}")), "{e}");
        assert_eq!(bits(&t), state, "{name}: the twin moved");
        assert_eq!(obs.covariance(), p, "{name}: the observer moved");
        // The counter keeps its new offset (a reset, an index pulse): the next reading,
        // taken from it, is no jump in a step (a refusal once, not at every step after
        // it); the crank's offset meets the innovation's gate, named, not corrected by.
        let up = obs
            .step(&mut t, &s2_inputs(Some(reading((jumped[0], jumped[1])))))
            .unwrap_or_else(|e| panic!("{name}: the reading after the offset refused: {e}"));
        if k == 0 {
            assert!(up.diagnostics.contains(Diagnostic::EncoderJump("crank")));
            assert!(up.correction.is_none());
        }
        if k == 0 {
            // Back to the machine's crank for the shaft's case: a jump again, refused,
            // then taken.
            let back = reading((crank, shaft));
            assert!(obs.step(&mut t, &s2_inputs(Some(back))).is_err());
            obs.step(&mut t, &s2_inputs(Some(back)))
                .expect("the machine's reading again");
        }
    }
}

/// Refused steps do not leave the jump check behind the machine: a motor torque that
/// is not a number for 0.3 s (the crank turns on, past half a turn
/// from the last good step's reading) refuses each step, named, and the first step
/// with a good torque is taken, the readings through the refusals its reference.
#[test]
fn readings_through_refused_steps_keep_the_jump_check_on_the_machine() {
    let (mut machine, mut t, mut obs, mut last) = observed_for(200);
    let first = last;
    for _ in 0..300 {
        last = machine.period();
        let bad = Inputs {
            motor: MotorInput::Torque(f64::NAN),
            ..s2_inputs(Some(reading(last)))
        };
        let e = obs.step(&mut t, &bad).unwrap_err();
        assert!(e.to_string().contains("motor torque"), "{e}");
    }
    assert!(
        2 * (last.0 - first.0).unsigned_abs() >= u64::from(N),
        "the machine moved {} counts",
        last.0 - first.0
    );
    last = machine.period();
    obs.step(&mut t, &s2_inputs(Some(reading(last))))
        .expect("the first good torque after the refusals is a step");
}

/// A twin that spreads its events (issue 18's real-time option) may end a step short
/// of the clock, at an event: the observer refuses it with the setting named, the twin
/// and the covariance as they were. The same twin steps on its own, and reports an
/// encoder residual only on the clock.
#[test]
fn the_observer_refuses_a_twin_that_spreads_its_events() {
    let mut s = TwinSettings::reference(H);
    s.spread_events = true;
    let mut t = Twin::new(CccParams::reference(), s, s2_inputs(None)).expect("S2 assembles");
    let mut obs = TwinObserver::new(ObserverSettings::reference());
    let (state, p) = (bits(&t), obs.covariance());
    let e = obs
        .step(
            &mut t,
            &s2_inputs(Some(reading((counts(105f64.to_radians()), 0)))),
        )
        .unwrap_err();
    assert!(matches!(e, TwinStepError::BadInput { .. }), "{e:?}");
    assert!(e.to_string().contains("spread_events"), "{e}");
    assert_eq!(bits(&t), state, "the twin moved");
    assert_eq!(obs.covariance(), p, "the observer moved");
    // Stepped on its own with the encoder's reading, it gives a residual only on the
    // clock: behind it (after S2's first release, at 0.0288 s) its state is not the
    // machine's at the reading's time.
    let (mut on, mut off) = (0, 0);
    for n in 1..=60u32 {
        let clock = f64::from(n) * H;
        let m = reading((counts(105f64.to_radians()), 0));
        t.step(&s2_inputs(Some(m)))
            .expect("a step of the spreading twin");
        let behind = t.time() < clock;
        assert_eq!(t.lag() > 0.0, behind, "step {n}");
        assert_eq!(t.measurement_residual().is_none(), behind, "step {n}");
        if behind {
            off += 1;
        } else {
            on += 1;
        }
    }
    assert!(
        off > 0 && on > 0,
        "{off} steps behind the clock, {on} on it"
    );
}

/// A correction of the crank by (1 mrad, 0.05 rad/s) in a 1-DOF mode (I8, the crank
/// its coordinate) and in a 2-DOF mode (I0): the crank moves by what was asked (to the
/// second order of the map, 1e-6 rad and 1e-3 rad/s here), the energy it
/// puts in is booked so that the audit's residual stays where it was (to 1e-12 J)
/// and equals the change of the kinetic and potential energies, and the twin steps
/// on from there with its energy balance checked each step.
#[test]
fn a_correction_moves_the_crank_and_books_its_energy() {
    for (steps, mode) in [(10, Mode::I8), (40, Mode::I0)] {
        let mut t = twin::<f64>(105.0);
        for _ in 0..steps {
            t.step(&s2_inputs(None)).unwrap();
        }
        assert_eq!(t.mode(), mode);
        let (before, audit) = (t.link(1), t.audit());
        let c = t.correct_crank(1e-3, 0.05).expect("a correction");
        assert!(c.applied);
        let after = t.link(1);
        let (dt, dw) = (after.theta - before.theta, after.omega - before.omega);
        assert!((dt - 1e-3).abs() < 1e-6, "{mode}: Δθ1 {dt}");
        assert!((dw - 0.05).abs() < 1e-3, "{mode}: Δω1 {dw}");
        assert_eq!(c.crank, (dt, dw));
        let a = t.audit();
        assert!(
            (a.residual() - audit.residual()).abs() < 1e-12,
            "{mode}: {a:?}"
        );
        let de = (a.kinetic + a.potential) - (audit.kinetic + audit.potential);
        assert!(
            (a.correction - audit.correction - de).abs() < 1e-12,
            "{mode}"
        );
        assert!((c.energy - de).abs() < 1e-12 && de != 0.0, "{mode}");
        for _ in 0..50 {
            t.step(&s2_inputs(None)).expect("steps on, balance checked");
        }
        // Not finite: refused, nothing moved.
        let s = bits(&t);
        assert!(t.correct_crank(f64::NAN, 0.0).is_err());
        assert_eq!(bits(&t), s);
    }
}

/// A twin with no model error (the machine's own twin and inputs), observed through
/// its encoders in f64 and in f32: it makes the machine's 23 events of S2 in the
/// machine's order (the same kinds and modes), each within 10 ms, raises no
/// diagnostic, and stays near the machine's crank. Tuned for nominal parameters,
/// within 2 counts (a regression bound: the estimates, which have nothing to find
/// here, move with the counts; measured 0.98 counts in f64 and 0.99 in f32, 1.52 and
/// 1.64 before the locked lever's update, 2.85 and 2.61 with the four-state tuning,
/// 7.8 and 7.5 before the friction's estimate; see
/// docs/observer.md, "Machines with one known error"). Tuned for an identified twin (a model trusted),
/// within half a count: measured 0 in f64 (the counts never leave the twin's band, so
/// it is never corrected) and 0.15 in f32.
#[test]
fn with_no_model_error_the_observer_keeps_the_machine_s_events() {
    fn run<T: Real>(settings: ObserverSettings<T>, bound: f64) {
        let mut machine = Machine::new();
        let mut t = twin::<T>(105.0);
        let mut obs = TwinObserver::new(settings);
        let res = TAU / f64::from(N);
        let (mut worst, mut ours, mut theirs) = (0.0f64, Vec::new(), Vec::new());
        for k in 0..1000 {
            let c = machine.period();
            let up = obs.step(&mut t, &s2_inputs(Some(reading(c)))).unwrap();
            assert!(up.diagnostics.is_empty(), "step {k}: {:?}", up.diagnostics);
            let off = (t.link(1).theta.to_f64() - machine.twin.link(1).theta) / res;
            worst = worst.max(off.abs());
            theirs.extend(machine.twin.events().iter().map(|e| (e.time, e.kind, e.to)));
            ours.extend(t.events().iter().map(|e| (e.time.to_f64(), e.kind, e.to)));
        }
        eprintln!("{worst} counts off the machine at worst");
        assert!(worst <= bound, "{worst} counts off the machine");
        // Regression value: S2's 23 events to 1 s, as the twin makes them; the
        // oracle is the pairing below, ours against the machine's, one by one.
        assert_eq!(theirs.len(), 23, "S2's events");
        assert_eq!(ours.len(), theirs.len());
        for (a, b) in theirs.iter().zip(&ours) {
            assert_eq!((a.1, a.2), (b.1, b.2));
            assert!((a.0 - b.0).abs() <= 0.01, "{a:?} {b:?}");
        }
    }
    run::<f64>(ObserverSettings::reference(), 2.0);
    run::<f32>(ObserverSettings::reference(), 2.0);
    run::<f64>(ObserverSettings::identified(), 0.5);
    run::<f32>(ObserverSettings::identified(), 0.5);
}

/// Faults injected into the machine's readings at a known step: the shaft's count
/// shifted by 8 from an instant in I8 (a slipping clutch: the shaft moves where the
/// mode holds it) is named within 10 ms; a crank count off by 40 for one sample is
/// named an encoder jump at that step and not corrected by.
#[test]
fn injected_faults_are_named_at_their_instants() {
    let mut machine = Machine::new();
    let mut t = twin::<f64>(105.0);
    let mut obs = TwinObserver::new(ObserverSettings::reference());
    let (slip_at, jump_at) = (12, 600);
    let mut slip_seen = None;
    for k in 0..700 {
        let mut c = machine.period();
        if k >= slip_at {
            c.1 += 8;
        }
        if k == jump_at {
            c.0 += 40;
        }
        let up = obs.step(&mut t, &s2_inputs(Some(reading(c)))).unwrap();
        if k == slip_at {
            assert_eq!(t.mode(), Mode::I8, "the shaft is held at the slip");
        }
        if up.diagnostics.contains(Diagnostic::ClutchSlip) {
            slip_seen.get_or_insert(k);
        }
        let jump = up.diagnostics.contains(Diagnostic::EncoderJump("crank"));
        assert_eq!(jump, k == jump_at, "step {k}");
        if jump {
            assert!(up.correction.is_none());
        }
    }
    let k = slip_seen.expect("the slip named");
    assert!((slip_at..slip_at + 10).contains(&k), "named at step {k}");
}

/// A reading that drifts from the twin a few counts a step is no encoder jump, one
/// that steps is: with the gate at 0 standard deviations (an innovation past 16 counts
/// is past it), the crank's counts shifted by 3 more each step for 12 steps from
/// 0.035 s, in I0 (a 2-DOF mode, corrected by a tenth of the gain, so the innovation
/// grows past 16 counts: what the former rule named a jump), name no jump, and the
/// twin, its covariance reset past the gate, follows the shifted counts back to within
/// 3 counts; the same shift of 36 counts made at one sample is named a jump there.
#[test]
fn a_drift_is_no_encoder_jump_and_a_step_is() {
    let mut settings = ObserverSettings::reference();
    settings.jump_gate = 0.0;
    for stepped in [false, true] {
        let mut machine = Machine::new();
        let mut t = twin::<f64>(105.0);
        let mut obs = TwinObserver::new(settings);
        let (from, steps) = (35, 12);
        let (mut largest, mut named, mut last) = (0.0f64, None, 0.0);
        for k in 0..80 {
            let mut c = machine.period();
            let shift = if stepped {
                if k >= from {
                    3 * steps
                } else {
                    0
                }
            } else {
                3 * (k.clamp(from - 1, from + steps - 1) - (from - 1))
            };
            c.0 += shift;
            let up = obs.step(&mut t, &s2_inputs(Some(reading(c)))).unwrap();
            if (from..from + steps).contains(&k) && !stepped {
                assert_eq!(t.mode(), Mode::I0, "step {k}: the drift is in I0");
            }
            let res = TAU / 4096.0;
            largest = largest.max(up.innovation.unwrap().abs() / res);
            if up.diagnostics.contains(Diagnostic::EncoderJump("crank")) {
                named.get_or_insert(k);
            }
            last = (c.0 - counts(t.link(1).theta)) as f64;
        }
        if stepped {
            assert_eq!(named, Some(from), "the step named where it is made");
        } else {
            assert!(
                largest > 16.0,
                "the innovation grew to {largest} counts only"
            );
            assert_eq!(named, None, "a drift named a jump");
            assert!(
                last.abs() < 3.0,
                "the twin {last} counts off the shifted counts"
            );
        }
    }
}

/// The force observer on a machine with a known torque the model lacks: S2's twin
/// stepped open-loop with 0.5 N·m more on its crank than the observed twin is told
/// (the motor's constant 12.5 N·m against 12, and the same with an asynchronous
/// motor's characteristic `a - 0.02 ω1`, which takes the estimates as a constant
/// does), read through its encoders. With the nominal tuning the twin keeps the
/// machine with no diagnostic. The torque the observer adds on the crank, `d - c ω1`
/// (its torque and friction estimates, the mass's off: with it the mass takes up part
/// of the torque's effect; the oracle: the torque put in), has the torque's sign and,
/// with the constant motor, its size: its mean from 0.1 s to the end within 0.25 and
/// 1 N·m and 40 % of the steps within 0.5 N·m of 0.5. Measured: means 0.75 and 0.75
/// N·m (f64, f32), 92 % of the steps within 0.5 N·m; with the asynchronous motor 0.85
/// in both, 67 % and 68 % within 0.5 N·m. (Before the locked lever's update: 0.33 and
/// 0.32, 85 %; with the asynchronous motor only the sign held, 0.11, `d` running to
/// its -1.25 N·m limit at 0.5 s in I6, near the crank's reversal.)
#[test]
fn the_torque_estimate_finds_a_known_extra_torque_on_the_crank() {
    /// The motor: a constant `a` (N·m), or with `asynchronous` the characteristic
    /// `a - 0.02 ω1`, which the observer's estimates enter as well.
    fn law<T: Real>(asynchronous: bool, a: f64) -> MotorInput<T> {
        MotorInput::Law(if asynchronous {
            Motor::Asynchronous(Asynchronous {
                a: T::c(a),
                b: T::c(-0.02),
                c: T::zero(),
            })
        } else {
            Motor::Constant(T::c(a))
        })
    }
    fn run<T: Real>(asynchronous: bool, settings: ObserverSettings<T>) -> Vec<f64> {
        let extra = 0.5;
        let mut machine = Machine::new();
        let mut t = twin::<T>(105.0);
        let mut obs = TwinObserver::new(settings);
        let mut estimates = Vec::new();
        for _ in 0..1000 {
            let c = machine.period_under(&Inputs {
                motor: law(asynchronous, 12.0 + extra),
                load: 800.0,
                measured: None,
            });
            let inputs = Inputs {
                motor: law(asynchronous, 12.0),
                ..s2_inputs(Some(reading(c)))
            };
            let up = obs.step(&mut t, &inputs).unwrap();
            assert!(up.diagnostics.is_empty(), "{:?}", up.diagnostics);
            // The torque the observer adds on the crank: `d - c ω1`.
            let w = t.link(1).omega.to_f64();
            estimates.push(obs.torque().to_f64() - obs.friction().to_f64() * w);
        }
        estimates
    }
    // The force observer's own estimate: the mass's off (with it the mass takes up
    // part of the torque's effect). With it on, the nominal tuning's, the twin keeps
    // the machine with no diagnostic all the same (asserted in `run`).
    fn no_mass<T: Real>() -> ObserverSettings<T> {
        ObserverSettings {
            mass_sigma: T::zero(),
            mass_noise: T::zero(),
            ..ObserverSettings::reference()
        }
    }
    for asynchronous in [false, true] {
        run::<f64>(asynchronous, ObserverSettings::reference());
        run::<f32>(asynchronous, ObserverSettings::reference());
    }
    let runs = [
        ("f64", run::<f64>(false, no_mass())),
        ("f32", run::<f32>(false, no_mass())),
        ("f64, asynchronous", run::<f64>(true, no_mass())),
        ("f32, asynchronous", run::<f32>(true, no_mass())),
    ];
    let mut failed = Vec::new();
    for (name, e) in runs {
        let late = &e[100..];
        let mean = late.iter().sum::<f64>() / late.len() as f64;
        let near = late.iter().filter(|x| (*x - 0.5).abs() <= 0.5).count();
        let near = near as f64 / late.len() as f64;
        eprintln!("{name}: mean {mean}, {near} of the steps within 0.5 N·m");
        let found = if name.ends_with("asynchronous") {
            mean > 0.0
        } else {
            (0.25..=1.0).contains(&mean) && near >= 0.4
        };
        if !found {
            failed.push((name, mean, near));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// S2's machine with the parameters `p`, stepped open-loop from SPEC's start, read
/// through its encoders and observed on S2's twin with `settings`: the twin's crank
/// off the machine's after the first 0.1 s (RMS, counts; the oracle the machine's
/// true angle) and `estimate` averaged over the last half second. No diagnostic is
/// raised, and the update reports the mass the twin carries.
fn observe_machine<T: Real>(
    p: CccParams<f64>,
    settings: ObserverSettings<T>,
    estimate: impl Fn(&TwinObserver<T>, &Twin<T>) -> f64,
) -> (f64, f64) {
    let mut s = TwinSettings::reference(H);
    s.crank = 105f64.to_radians();
    let mut machine = Twin::new(p, s, s2_inputs(None)).expect("S2 assembles");
    let mut t = twin::<T>(105.0);
    let mut obs = TwinObserver::new(settings);
    let res = TAU / f64::from(N);
    let (mut off2, mut sum, mut n) = (0.0, 0.0, 0.0);
    for k in 0..1000 {
        machine.step(&s2_inputs(None)).expect("the machine steps");
        let c = (
            counts(machine.link(1).theta),
            counts(machine.shaft_drive_angle()),
        );
        let up = obs.step(&mut t, &s2_inputs(Some(reading(c)))).unwrap();
        assert!(up.diagnostics.is_empty(), "step {k}: {:?}", up.diagnostics);
        assert_eq!(up.mass, t.oscillating_mass());
        if k >= 100 {
            off2 += ((t.link(1).theta.to_f64() - machine.link(1).theta) / res).powi(2);
        }
        if k >= 500 {
            sum += estimate(&obs, &t);
            n += 1.0;
        }
    }
    ((off2 / 900.0).sqrt(), sum / n)
}

/// The friction observer on a machine with a known friction the model lacks: S2's twin
/// stepped open-loop with a viscous friction of 0.05 N·m·s/rad in the crank's bearing
/// A (`identify` finds 0.050 there on bench1), read through its encoders,
/// observed on S2's frictionless twin with the nominal tuning without the mass's
/// estimate, and with that tuning without the friction's estimate either
/// (`friction_sigma` and `friction_noise` 0: the three-state filter). The oracle is
/// the machine's true crank angle: with the estimate the twin's crank is closer to it
/// after the first 0.1 s (RMS: measured 0.17 counts against 0.35 in f64, 0.16 against
/// 0.35 in f32; 0.44 against 1.03 before the locked lever's update), the estimate is
/// within 0.02 of the coefficient put in on average over the last half second
/// (measured 0.046 in both), and no diagnostic is raised.
#[test]
fn the_friction_estimate_finds_a_known_friction_of_the_crank_s_bearing() {
    fn run<T: Real>(settings: ObserverSettings<T>) -> (f64, f64) {
        let mut p = CccParams::<f64>::reference();
        p.friction.viscous[0] = 0.05;
        observe_machine(p, settings, |obs, _| obs.friction().to_f64())
    }
    fn both<T: Real>(name: &str) {
        // The mass's estimate off in both: the friction's is what is compared.
        let no_mass = ObserverSettings {
            mass_sigma: T::zero(),
            mass_noise: T::zero(),
            ..ObserverSettings::reference()
        };
        let with = run::<T>(no_mass);
        let without = run::<T>(ObserverSettings {
            friction_sigma: T::zero(),
            friction_noise: T::zero(),
            ..no_mass
        });
        eprintln!(
            "{name}: crank {} counts RMS off the machine with the friction's estimate ({} N·m·s/rad on average), {} without",
            with.0, with.1, without.0
        );
        assert!(with.0 < without.0, "{name}: {with:?} against {without:?}");
        assert!((with.1 - 0.05).abs() <= 0.02, "{name}: {}", with.1);
        assert_eq!(without.1, 0.0);
    }
    both::<f64>("f64");
    both::<f32>("f32");
}

/// The mass observer on a machine whose oscillating mass is not the drawing's: S2's
/// twin stepped open-loop with the known machine's 6.48 kg on the rocker (SPEC: 6),
/// read through its encoders, observed on S2's twin with the nominal tuning, and
/// with the same tuning without the mass's estimate (`mass_sigma` and `mass_noise` 0).
/// The oracles are the machine's true crank angle and its mass: with the estimate the
/// twin's crank is closer to the machine's after the first 0.1 s (RMS), the estimate
/// has moved from 6 kg towards 6.48 on average over the last half second, and no
/// diagnostic is raised. Measured: 0.45 counts against 0.56 in f64, 0.46 against
/// 0.55 in f32 (1.06 against 1.16 before the locked lever's update), the mass 6.20 kg
/// on average in both (the torque's and the friction's estimates take up the rest of
/// the mass's effect).
#[test]
fn the_mass_estimate_finds_a_known_oscillating_mass() {
    fn run<T: Real>(settings: ObserverSettings<T>) -> (f64, f64) {
        let mut p = CccParams::<f64>::reference();
        p.mass = 6.48;
        observe_machine(p, settings, |_, t| t.oscillating_mass().to_f64())
    }
    fn both<T: Real>(name: &str) {
        let with = run::<T>(ObserverSettings::reference());
        let without = run::<T>(ObserverSettings {
            mass_sigma: T::zero(),
            mass_noise: T::zero(),
            ..ObserverSettings::reference()
        });
        eprintln!(
            "{name}: crank {} counts RMS off the machine with the mass's estimate ({} kg on average), {} without",
            with.0, with.1, without.0
        );
        assert!(with.0 < without.0, "{name}: {with:?} against {without:?}");
        assert!(with.1 > 6.1 && with.1 < 6.9, "{name}: {}", with.1);
        assert_eq!(without.1, 6.0);
    }
    both::<f64>("f64");
    both::<f32>("f32");
}

/// `Twin::crank_mobility` (`r M⁻¹ rᵀ`, the force observer's `b`) against the twin's
/// own evaluation, an independent path: one N·m more of motor torque at the same state
/// changes the crank's angular acceleration by `b` (to 1e-8), in each initial mode the
/// crank angles give (I0 with its two coordinates, I8, A68 measured).
#[test]
fn the_crank_mobility_is_the_crank_s_acceleration_per_newton_metre() {
    let mut modes = Vec::new();
    for deg in [60.0, 105.0, 150.0, 200.0, 250.0, 300.0] {
        let at = |torque: f64| {
            let mut s = TwinSettings::reference(H);
            s.crank = f64::to_radians(deg);
            let inputs = Inputs {
                motor: MotorInput::Law(Motor::Constant(torque)),
                load: 800.0,
                measured: None,
            };
            Twin::<f64>::new(CccParams::reference(), s, inputs).ok()
        };
        let (Some(a), Some(b)) = (at(12.0), at(13.0)) else {
            continue;
        };
        if a.mode() != b.mode() || a.q().is_empty() {
            continue;
        }
        let da = b.link(1).alpha - a.link(1).alpha;
        let m = a.crank_mobility();
        assert!((da - m).abs() <= 1e-8 * m.abs(), "{deg}°: {da} vs {m}");
        modes.push((a.mode(), a.q().len()));
    }
    assert!(modes.len() >= 3, "{modes:?}");
}

/// In a 2-DOF mode a correction moves the coordinates along the crank's dynamically
/// consistent direction `M⁻¹rᵀ / (r M⁻¹ rᵀ)`, the direction a torque on the crank
/// accelerates them in (`Twin::correct_crank`). Oracle: the twin's own dynamics, not
/// its mass matrix: two copies in I0 of S2 stepped 0.1 ms with the motor's torque
/// 0.1 N·m apart part in the coordinates' rates along `M⁻¹rᵀ` (to first order in the
/// step); the correction's change of the coordinates has their ratio, to 1 %. The
/// swing moves with the crank (the least-norm map would leave it still).
#[test]
fn a_correction_in_a_2_dof_mode_moves_the_coordinates_as_a_crank_torque_does() {
    let mut s = TwinSettings::reference(1e-4);
    s.crank = 105f64.to_radians();
    let mut t = Twin::new(CccParams::reference(), s, s2_inputs(None)).expect("S2 assembles");
    for _ in 0..400 {
        t.step(&s2_inputs(None)).expect("S2 steps");
    }
    assert_eq!(t.mode(), Mode::I0);
    let pushed = |d: f64| {
        let mut u = t.clone();
        let inputs = Inputs {
            motor: MotorInput::Torque(12.0 + d),
            load: 800.0,
            measured: None,
        };
        u.step(&inputs).expect("a step in I0");
        assert!(u.events().is_empty() && u.mode() == Mode::I0);
        [u.qd()[0], u.qd()[1]]
    };
    let (a, b) = (pushed(0.0), pushed(0.1));
    let by_torque = (b[1] - a[1]) / (b[0] - a[0]);
    let q = [t.q()[0], t.q()[1]];
    let mut c = t.clone();
    assert!(c.correct_crank(1e-5, 0.0).expect("a correction").applied);
    let by_correction = (c.q()[1] - q[1]) / (c.q()[0] - q[0]);
    assert!(
        (by_correction - by_torque).abs() <= 1e-2 * by_torque.abs(),
        "{by_correction} against {by_torque}"
    );
    assert!(by_torque.abs() > 0.05, "{by_torque}");
}

/// A twin that cannot follow its machine is named parted, and only then. S2's machine
/// is stepped open-loop with another motor torque or brake than the twin is told
/// (`extra` N·m on the motor, the load `load` N·m against the twin's 800) and observed
/// on S2's twin from SPEC's start. The oracle is the machine's true crank angle against
/// the twin's: at every step [`Diagnostic::Parted`] is raised the twin's crank has been
/// more than `part_counts - 1` counts off (the count's quantization below the residual
/// the observer sees) for `part_steps` steps in a row, and at every step it has been
/// more than `part_counts + 1` off for that long the diagnostic is raised. The observer
/// keeps the twin on a machine with the same brake and up to 5 N·m more torque (no
/// diagnostic with 0 and 0.5 N·m, `the_torque_estimate_finds_a_known_extra_torque_on_the_crank`);
/// a machine whose brake holds half the load (the shaft breaks away where the twin's
/// holds: measured from step 216 in f64 and f32) or whose motor gives 4 N·m less
/// (from step 788) leaves it, and it is named.
#[test]
fn a_twin_the_machine_leaves_is_named_parted() {
    fn run<T: Real>(extra: f64, load: f64) -> Option<usize> {
        let settings = ObserverSettings::<T>::reference();
        let (part, steps) = (settings.part_counts.to_f64(), settings.part_steps as usize);
        let mut machine = Machine::new();
        let mut t = twin::<T>(105.0);
        let mut obs = TwinObserver::new(settings);
        let res = TAU / f64::from(N);
        let (mut over_low, mut over_high, mut first) = (0, 0, None);
        for k in 0..1000 {
            let c = machine.period_under(&Inputs {
                motor: MotorInput::Law(Motor::Constant(12.0 + extra)),
                load,
                measured: None,
            });
            let up = obs
                .step(&mut t, &s2_inputs(Some(reading(c))))
                .expect("the twin steps");
            let off = ((machine.twin.link(1).theta - t.link(1).theta.to_f64()) / res).abs();
            over_low = if off > part - 1.0 { over_low + 1 } else { 0 };
            over_high = if off > part + 1.0 { over_high + 1 } else { 0 };
            let parted = up.diagnostics.contains(Diagnostic::Parted);
            if parted {
                assert!(
                    over_low >= steps,
                    "{extra} N·m, {load} N·m, step {k}: {off} counts off"
                );
                first.get_or_insert(k);
            }
            if over_high >= steps {
                assert!(
                    parted,
                    "{extra} N·m, {load} N·m, step {k}: {off} counts off"
                );
            }
        }
        first
    }
    for extra in [0.0, 5.0] {
        assert_eq!(run::<f64>(extra, 800.0), None, "{extra} N·m more");
        assert_eq!(run::<f32>(extra, 800.0), None, "{extra} N·m more");
    }
    for (extra, load) in [(0.0, 400.0), (-4.0, 800.0)] {
        assert!(run::<f64>(extra, load).is_some(), "{extra} N·m, {load} N·m");
        assert!(run::<f32>(extra, load).is_some(), "{extra} N·m, {load} N·m");
    }
}

/// A tuning that cannot make a filter (a NaN noise, a negative σ, a gain past 1, a
/// bias time of 0) is refused at the step, its field named, twin and covariance as they
/// were: a NaN covariance would otherwise stop every correction for good, unnamed.
#[test]
fn a_tuning_that_cannot_make_a_filter_is_named() {
    let mut machine = Machine::new();
    let m = reading(machine.period());
    let good = ObserverSettings::<f64>::reference();
    let mut bad = Vec::new();
    let mut s = good;
    s.accel_noise = f64::NAN;
    bad.push((s, "accel_noise"));
    let mut s = good;
    s.initial_sigma.1 = -1.0;
    bad.push((s, "initial_sigma.1"));
    let mut s = good;
    s.held_gain = 1.5;
    bad.push((s, "held_gain"));
    let mut s = good;
    s.bias_time = 0.0;
    bad.push((s, "bias_time"));
    let mut s = good;
    s.torque_limit = f64::NAN;
    bad.push((s, "torque_limit"));
    for (s, name) in bad {
        let want = format!("observer settings: {name}");
        assert_eq!(s.fault().map(|f| f.0), Some(want.as_str()));
        let mut t = twin::<f64>(105.0);
        let mut obs = TwinObserver::new(s);
        let (state, p) = (bits(&t), obs.covariance());
        let e = obs.step(&mut t, &s2_inputs(Some(m))).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("observer settings: {name}")),
            "{e}"
        );
        assert_eq!(bits(&t), state, "{name}: the twin moved");
        assert_eq!(obs.covariance(), p, "{name}: the observer moved");
    }
    // Limits may be infinite (none): the bias diagnostic off is the reference's way.
    let mut s = good;
    s.bias_limit = f64::INFINITY;
    assert_eq!(s.fault(), None);
    assert_eq!(good.fault(), None);
    assert_eq!(ObserverSettings::<f64>::identified().fault(), None);
}
