//! The shaft's inertia J_s > 0 as its own degree of freedom (SPEC 5): the shaft coasts
//! while no lever drives it ([`Mode::Coast`]), a lever catching it at a speed mismatch
//! is a plastic impact, and the brake holds it once it stands. Against oracles
//! independent of the twin's code: S2's events at J_s = 0, the coasting shaft's
//! analytic motion under its brake, its kinetic energy, the energy audit with every
//! loss on, and the kinetic energy lost in a late catch from `½ q̇ᵀMq̇` of the models
//! before and after.

use structomat::ccc::{CccParams, Event, Inputs, Mode, MotorInput, Twin, TwinSettings};
use structomat_suite::check_free_levers;

const S2: Inputs<f64> = Inputs {
    motor: MotorInput::Torque(12.0),
    load: 800.0,
    measured: None,
};

/// Runs `twin` under `inputs` to `t_end`, collecting its events.
fn run(twin: &mut Twin<f64>, inputs: &Inputs<f64>, t_end: f64) -> Vec<Event<f64>> {
    let mut events = Vec::new();
    while twin.time() < t_end - 0.5 * twin.h() {
        twin.step(inputs)
            .unwrap_or_else(|e| panic!("a step at t = {}: {e}", twin.time()));
        events.extend_from_slice(twin.events());
    }
    events
}

fn s2_twin(js: f64) -> Twin<f64> {
    let mut p = CccParams::<f64>::reference();
    p.shaft_inertia = js;
    Twin::new(p, TwinSettings::reference(1e-4), S2).expect("S2 sets up")
}

/// S2 (12 N·m, T_r = 800 N·m) to 0.07 s, when both levers turn the shaft, then the
/// load `load` (N·m) from there: the shaft, spun up, coasts whenever no lever drives
/// it. Returns the twin and the second inputs.
fn spun_up(p: CccParams<f64>, load: f64) -> (Twin<f64>, Inputs<f64>) {
    let mut twin = Twin::new(p, TwinSettings::reference(1e-4), S2).expect("S2 sets up");
    run(&mut twin, &S2, 0.07);
    assert_eq!(twin.mode(), Mode::A68, "t = {}", twin.time());
    (twin, Inputs { load, ..S2 })
}

fn with_js(js: f64) -> CccParams<f64> {
    let mut p = CccParams::<f64>::reference();
    p.shaft_inertia = js;
    p
}

/// `J_s → 0` recovers SPEC's machine: S2's second with J_s = 1e-9 kg·m² has the events
/// of J_s = 0 (the same kinds and modes, in order) each within 1e-6 s, and never coasts
/// (a lever's release stops the shaft, as with J_s = 0).
#[test]
fn a_vanishing_shaft_inertia_recovers_s2s_events() {
    let at = |js: f64| {
        let mut twin = s2_twin(js);
        run(&mut twin, &S2, 1.0)
    };
    let (reference, tiny) = (at(0.0), at(1e-9));
    assert_eq!(reference.len(), tiny.len(), "{reference:?}\n{tiny:?}");
    let mut worst: f64 = 0.0;
    for (a, b) in reference.iter().zip(&tiny) {
        assert_eq!(
            (a.kind, a.from, a.to),
            (b.kind, b.from, b.to),
            "{a:?} vs {b:?}"
        );
        worst = worst.max((a.time - b.time).abs());
    }
    println!(
        "J_s = 1e-9 kg·m²: {} events of S2 within {worst:.3e} s of J_s = 0",
        tiny.len()
    );
    assert!(worst <= 1e-6, "{worst} s");
    assert!(tiny.iter().all(|e| e.to != Mode::Coast));
}

/// With no load and no loss the coasting shaft keeps its speed, so its kinetic energy
/// `½ J_s ω_s²`, to 1e-9 over every coasting stretch (checked at each step end in
/// the coast), while the linkage swings on and levers catch and release it.
#[test]
fn a_coasting_shaft_with_no_load_keeps_its_energy() {
    let js = 0.05;
    let (mut twin, free) = spun_up(with_js(js), 0.0);
    let mut coasting_steps = 0;
    let mut stretches = 0;
    let mut worst: f64 = 0.0;
    let mut start: Option<f64> = None;
    while twin.time() < 0.4 {
        twin.step(&free).expect("a step without load");
        check_free_levers(&twin);
        if twin.mode() != Mode::Coast {
            start = None;
            continue;
        }
        let w = twin.shaft_speed();
        let k = 0.5 * js * w * w;
        // The stretch's energy at its first step end (the coasting began in that step).
        let k0 = *start.get_or_insert_with(|| {
            stretches += 1;
            k
        });
        worst = worst.max((k - k0).abs() / k0);
        coasting_steps += 1;
    }
    println!(
        "no load: {stretches} coasting stretches, {coasting_steps} steps, energy kept to {worst:.3e}"
    );
    // Regression bounds (measured: 5 stretches, 2284 steps): the shaft does coast.
    assert!(stretches >= 3 && coasting_steps >= 100);
    assert!(worst <= 1e-9, "{worst}");
}

/// Under its brake alone the coasting shaft decelerates at `T_r/J_s` (its speed at the
/// step ends falls by `T_r·h/J_s` a step), stops `ω_s·J_s/T_r` after any instant of its
/// coasting (ω_s its speed then), having turned `ω_s²·J_s/(2 T_r)`, and the brake then
/// holds it.
#[test]
fn a_coasting_shaft_stops_under_its_brake_as_the_analytic_motion_says() {
    let (js, load) = (0.5, 200.0);
    let (mut twin, inputs) = spun_up(with_js(js), load);
    let h = twin.h();
    let mut last: Option<(f64, f64, f64)> = None;
    let mut checked = 0;
    while twin.time() < 0.4 {
        let before = (
            twin.mode(),
            twin.time(),
            twin.shaft_speed(),
            twin.shaft_angle(),
        );
        twin.step(&inputs).expect("a step of the braked shaft");
        check_free_levers(&twin);
        if before.0 == Mode::Coast && twin.mode() == Mode::Coast {
            let rate = (twin.shaft_speed() - before.2) / h;
            // CW drive: the brake turns the shaft back CCW.
            assert!((rate - load / js).abs() <= 1e-9 * load / js, "{rate}");
        }
        if twin.mode() == Mode::Coast && last.is_none() {
            last = Some((twin.time(), twin.shaft_speed(), twin.shaft_angle()));
        }
        let stop = twin
            .events()
            .iter()
            .find(|e| e.from == Mode::Coast && e.kind.name() == "shaft-stop");
        if let (Some(e), Some((t1, w1, a1))) = (stop, last) {
            let t_stop = t1 + w1.abs() * js / load;
            let turn = w1 * w1 * js / (2.0 * load);
            println!(
                "coasting from {t1:.6} s at {w1:.6} rad/s: stops at {:.9} s (analytic {t_stop:.9}), turned {:.9e} rad (analytic {turn:.9e}), then {}",
                e.time,
                (twin.shaft_angle() - a1).abs(),
                e.to
            );
            assert!((e.time - t_stop).abs() <= 1e-9, "{} vs {t_stop}", e.time);
            assert!(((twin.shaft_angle() - a1).abs() - turn).abs() <= 1e-9 * turn.max(1e-3));
            assert!(
                !e.to.shaft_turning(),
                "the brake holds the stopped shaft: {}",
                e.to
            );
            checked += 1;
        }
        if twin.mode() != Mode::Coast {
            last = None;
        }
    }
    assert!(checked >= 1, "no coasting stop");
}

/// The energy audit with J_s > 0 and every loss on (every joint 0.02 N·m·s/rad viscous
/// and 0.05 N·m dry, clutch drag 0.05 N·m·s/rad): over S2's second, and over the
/// spun-up shaft coasting under 100 N·m, the balance (motor work = Δ(kinetic +
/// potential) + load work with the losses + impact losses, the shaft's ½J_sω_s² in the
/// kinetic energy) closes to 1e-6 of the motor's work at every step.
#[test]
fn with_every_loss_and_shaft_inertia_the_audit_closes() {
    let lossy = |js: f64| {
        let mut p = with_js(js);
        p.friction.viscous = [0.02; 9];
        p.friction.coulomb = [0.05; 9];
        p.friction.clutch_drag = 0.05;
        p
    };
    let audit = |twin: &mut Twin<f64>, inputs: &Inputs<f64>, t_end: f64| {
        let mut worst: f64 = 0.0;
        let mut coasting = 0;
        while twin.time() < t_end - 0.5 * twin.h() {
            twin.step(inputs).expect("a lossy step");
            let a = twin.audit();
            worst = worst.max(a.residual().abs() / a.motor_work.abs().max(1.0));
            coasting += usize::from(twin.mode() == Mode::Coast);
        }
        (worst, coasting)
    };
    let mut twin = Twin::new(lossy(0.05), TwinSettings::reference(1e-4), S2).unwrap();
    let (s2, _) = audit(&mut twin, &S2, 1.0);
    let a = twin.audit();
    println!("S2, J_s = 0.05, every loss: residual {s2:.3e} of the motor work; {a:?}");
    assert!(s2 <= 1e-6, "{s2}");
    let (mut twin, inputs) = spun_up(lossy(0.5), 100.0);
    let (coast, steps) = audit(&mut twin, &inputs, 0.5);
    let a = twin.audit();
    println!(
        "spun up, J_s = 0.5, T_r = 100 N·m, every loss: {steps} coasting steps, residual {coast:.3e}; {a:?}"
    );
    // A regression bound (as measured, more): the shaft does coast.
    assert!(steps >= 10, "{steps} coasting steps");
    assert!(coast <= 1e-6, "{coast}");
}

/// S2 itself with a realistic shaft (J_s = 0.05 kg·m²): at T_r = 800 N·m the brake
/// stops the shaft the instant no lever drives it (a release from an A mode with one
/// lever goes straight to a held shaft), so S2 never coasts; its events are those of
/// the ideal machine's kinds, the shaft turning 5 times (regression values), and it
/// ends in the jam as SPEC's S2 may.
#[test]
fn s2_with_a_realistic_shaft_inertia() {
    let mut twin = s2_twin(0.05);
    let events = run(&mut twin, &S2, 1.0);
    let starts = events
        .iter()
        .filter(|e| !e.from.shaft_turning() && e.to.shaft_turning())
        .count();
    let coasts = events.iter().filter(|e| e.to == Mode::Coast).count();
    println!(
        "S2 with J_s = 0.05: {} events, {starts} shaft starts, {coasts} coasting, ends in {} at {:.4} s",
        events.len(),
        twin.mode(),
        events.last().map_or(0.0, |e| e.time)
    );
    assert_eq!(coasts, 0);
    assert!(starts >= 5, "{starts}");
    assert_eq!(twin.mode(), Mode::Jam);
    let a = twin.audit();
    assert!(a.residual().abs() <= 1e-6 * a.motor_work);
}
