//! The energy balance of every fixed step (issue 17): `Simulation::step` checks that the
//! motors' and loads' work equals the change of kinetic plus potential energy, redoes a
//! step that breaks it in sub-steps, and fails with `StepError::EnergyBalance` when
//! even those break it; the kinetostatics fails on non-finite reactions.
//!
//! The oracles are independent of the core's metering: a constant torque `τ` on a
//! coordinate does the work `τ·Δq` exactly, a constant force `F·Δr` of its point's
//! displacement (read from the workspace), and the energies are `dynamics::energy`.
//! The trajectory is checked against the error-controlled adaptive DP5(4).

use structomat::integrator::{Adaptive, AdaptiveSettings};
use structomat::mechanisms::five_bar;
use structomat::model::{Link, Load, ModelBuilder};
use structomat::motor::Motor;
use structomat::scalar::Vec2;
use structomat::structomat::{DyadRrr, MotorR, PointRef};
use structomat::{Model, Simulation, StepError};
use structomat_suite::Rng;

/// Kinetic plus potential energy of the simulation's current state, J.
fn total_energy(sim: &Simulation<f64>) -> f64 {
    let e = sim.energy();
    e.kinetic + e.potential
}

/// The state a failed step must leave as it was: time, steps, coordinates, speeds and
/// the balance, bit for bit.
fn snapshot(sim: &Simulation<f64>) -> (f64, u64, Vec<f64>, Vec<f64>, structomat::Balance<f64>) {
    (
        sim.time(),
        sim.steps(),
        sim.q().to_vec(),
        sim.qd().to_vec(),
        *sim.balance(),
    )
}

/// The README's main job: the thesis's five-bar (10 N·m on link 1, gravity), h = 1 ms,
/// 5 s. Link 2, free, spins ever faster (75 rad/s at 1 s): the steps that would break
/// the balance are redone in sub-steps, and the whole run closes its balance to 1e-6 of
/// the motor work `10 N·m · Δq1`; early on, the fixed steps agree with an adaptive
/// rtol 1e-12 run.
#[test]
fn five_bar_main_job_closes_its_energy_balance() {
    let sc = five_bar::<f64>().unwrap();
    let mut sim = sc.simulation().unwrap();
    let (e0, q0) = (total_energy(&sim), sim.q()[0]);
    let mut at = Vec::new();
    for k in 1..=5000 {
        sim.step().unwrap_or_else(|e| panic!("step {k} fails: {e}"));
        if k == 500 || k == 1000 {
            at.push(sim.q()[0]);
        }
    }
    assert_eq!(sim.time(), 5.0);
    let work = 10.0 * (sim.q()[0] - q0);
    let gained = total_energy(&sim) - e0;
    let b = *sim.balance();
    println!(
        "five-bar 5 s: work {work:.9} J, energy gained {gained:.9} J, residual {:.3e} J \
         ({:.3e} of the work); {} steps redone in {} sub-steps, worst step {:.3e}",
        work - gained,
        (work - gained) / work,
        b.redone,
        b.substeps,
        b.worst
    );
    assert!(work > 100.0, "{work} J");
    assert!(
        (gained - work).abs() <= 1e-6 * work,
        "balance off by {:.3e} J of {work} J",
        gained - work
    );
    // The metered work: the same 5th-order quadrature as q1 itself (q̇1 is the state's
    // derivative), so it agrees with τ·Δq1 to rounding.
    assert!(
        (b.motor_work - work).abs() <= 1e-9 * work,
        "{}",
        b.motor_work
    );
    assert!((b.residual() - (work - gained)).abs() <= 1e-9 * work);
    assert!(b.worst <= 1e-9 && b.redone > 0 && b.substeps >= 4 * b.redone);

    // The first second against the adaptive DP5(4) at rtol 1e-12.
    let mut reference = sc.simulation_with_step(0.5).unwrap();
    let mut adaptive = Adaptive::new(AdaptiveSettings {
        rtol: 1e-12,
        atol: 1e-12,
        ..AdaptiveSettings::default()
    })
    .unwrap();
    // The balance bounds the energy error, not the phase; the local error check keeps
    // the phase (3.0e-9 rad at 1 s, where the balance alone left 2.3e-6 rad).
    for (q, tol) in at.iter().zip([1e-8, 1e-8]) {
        reference.step_adaptive(&mut adaptive).unwrap();
        let err = (q - reference.q()[0]).abs();
        println!(
            "q1({} s): fixed {q:.12}, adaptive {:.12}, |Δ| {err:.1e}",
            reference.time(),
            reference.q()[0]
        );
        assert!(err <= tol, "q1 at {} s off by {err:e}", reference.time());
    }
}

/// A Grashof crank-rocker: ground A = (0, 0), D = (0.3, 0); crank 0.05 m, coupler
/// 0.25 m, rocker 0.2 m (s + l = 0.35 < p + q = 0.45: the crank turns fully), 0.3 kg in
/// all, gravity; `motor` on the crank, `load` (if any) on the coupler.
fn crank_rocker(
    lengths: [f64; 4],
    masses: [f64; 3],
    motor: f64,
    load: Option<Load<f64>>,
) -> Result<Model<f64>, structomat::ModelError> {
    let [ground, crank, coupler, rocker] = lengths;
    let mut b = ModelBuilder::new();
    let a = b.ground_point(0.0, 0.0)?;
    let d = b.ground_point(ground, 0.0)?;
    let mut links = [0u8; 3];
    for ((slot, l), m) in links.iter_mut().zip([crank, coupler, rocker]).zip(masses) {
        // Slender bars: I_G = m l² / 12, COG at the middle.
        *slot = b.link(Link::bar(l, m, m * l * l / 12.0, l / 2.0))?;
    }
    let [l1, l2, l3] = links;
    b.group(&MotorR {
        link: l1,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: 0.0,
    })?;
    b.group(&DyadRrr {
        a: l2,
        b: l3,
        pole_a: PointRef { body: l1, point: 1 },
        a_at_pole: 0,
        pole_b: d,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        // The open branch: coupler to the right, rocker up.
        guess: [0.3, 1.8],
    })?;
    b.drive(0, Motor::Constant(motor))?;
    if let Some(l) = load {
        b.load(l)?;
    }
    b.build()
}

/// The crank-rocker under a constant 2 N·m at h = 1 ms. Its crank speeds up without
/// bound (nothing dissipates): every accepted step keeps the balance `Δ(K+V) = 2 N·m ·
/// Δq1` to 1e-6 of the work (or of 1 J), the crank speed never reverses (one degree of
/// freedom: a reversal needs K = 0 on the way, and K = W - ΔV grows), and the run ends
/// either at 3 s or with the energy-balance error, the last good state kept.
#[test]
fn crank_rocker_never_reverses_and_keeps_its_balance() {
    let model = crank_rocker([0.3, 0.05, 0.25, 0.2], [0.05, 0.15, 0.1], 2.0, None).unwrap();
    let mut sim = Simulation::new(model, &[0.0], &[0.0], 1e-3).unwrap();
    let (e0, q0) = (total_energy(&sim), sim.q()[0]);
    let mut end = None;
    for _ in 0..3000 {
        let before = snapshot(&sim);
        match sim.step() {
            Ok(()) => {}
            Err(e) => {
                assert!(matches!(e, StepError::EnergyBalance { .. }), "{e}");
                assert!(e.to_string().contains("smaller step"), "{e}");
                assert_eq!(snapshot(&sim), before, "a failed step changed the state");
                end = Some(e);
                break;
            }
        }
        let (w0, w1) = (before.3[0], sim.qd()[0]);
        let k = sim.energy().kinetic;
        assert!(
            !(w0 * w1 < 0.0 && k > 0.0),
            "t = {}: crank speed {w0} -> {w1} rad/s in one step",
            sim.time()
        );
        let work = 2.0 * (sim.q()[0] - q0);
        let off = total_energy(&sim) - e0 - work;
        assert!(
            off.abs() <= 1e-6 * work.max(1.0),
            "t = {}: balance off by {off:e} J of {work} J",
            sim.time()
        );
    }
    let b = sim.balance();
    println!(
        "crank-rocker: t = {} s, crank {:.1} rad/s, {} steps redone in {} sub-steps, worst {:.3e}; end: {}",
        sim.time(),
        sim.qd()[0],
        b.redone,
        b.substeps,
        b.worst,
        end.map_or("3 s reached".to_string(), |e| e.to_string())
    );
    assert!(sim.qd()[0] > 0.0);
}

/// One 10 s step of the five-bar (its run is 5 s): no division into 16 sub-steps
/// follows that motion; the first step fails with the energy-balance error and the
/// state is the initial one, bit for bit.
#[test]
fn a_huge_step_fails_with_the_energy_balance_error() {
    let mut sim = five_bar::<f64>()
        .unwrap()
        .simulation_with_step(10.0)
        .unwrap();
    let before = snapshot(&sim);
    let e = sim.step().unwrap_err();
    println!("h = 10 s: {e}");
    let StepError::EnergyBalance {
        time,
        residual,
        scale,
        substeps,
    } = e
    else {
        panic!("not the energy-balance error: {e}");
    };
    assert_eq!(time, 0.0);
    assert!([1, 4, 16].contains(&substeps), "{substeps}");
    assert!(
        residual.is_finite() && residual.abs() > 1e-9 * scale,
        "{residual} J, {scale} J"
    );
    assert!(e.to_string().contains("smaller step"), "{e}");
    assert_reads(&e, substeps);
    assert_eq!(snapshot(&sim), before);
    // Stepping on with a sane step is still possible from the kept state.
    assert!(sim.kinetostatics().is_ok());

    // At h = 0.3 s the 16 sub-steps reach the step's end, off the balance by 3.8e-4 of
    // the energy scale (host-sim's `five-bar --h 0.3`): the message names the division.
    let mut sim = five_bar::<f64>()
        .unwrap()
        .simulation_with_step(0.3)
        .unwrap();
    let e = sim.step().unwrap_err();
    let StepError::EnergyBalance { substeps, .. } = e else {
        panic!("not the energy-balance error: {e}");
    };
    // The finest rung: the core's sub-steps are 4 then 16 (`balance::SUBSTEPS`).
    assert_eq!(substeps, 16, "{e}");
    assert_reads(&e, substeps);
}

/// The energy-balance error is a sentence that says which division of the step its
/// residual is of (the finest that reached the step's end, or none), in words.
fn assert_reads(e: &StepError, substeps: u32) {
    let text = e.to_string();
    let division = if substeps > 1 {
        format!("even divided into {substeps} sub-steps: ")
    } else {
        "undivided, and no division into sub-steps reached the step's end: ".to_string()
    };
    assert!(text.contains(&division), "{text}");
    assert!(!text.contains("(the residual of"), "{text}");
}

/// Random crank-rockers (Grashof, crank shortest), random masses, constant motors of
/// either sign, a constant force at the coupler's far end (its work `F·Δr` read from
/// the workspace), random h in [1e-4, 2e-2] s, for 1 s: a run that completes never has
/// its cumulative balance off by more than 1e-6 of the work (or 1e-6 J), nor a
/// non-finite value; a run that stops, stops with a named error.
#[test]
fn random_four_bars_keep_their_balance() {
    let mut rng = Rng(0x5EED_0017);
    let (mut completed, mut stopped) = (0, 0);
    for case in 0..40 {
        let ground = rng.range(0.2, 0.5);
        let crank = rng.range(0.1, 0.3) * ground;
        // Coupler and rocker with crank + ground <= coupler + rocker (Grashof, the crank
        // shortest) and a closing loop at every crank angle.
        let rocker = rng.range(0.5, 1.0) * ground;
        let lo = (ground + crank - rocker).max(rocker - ground + crank) * 1.05;
        let hi = (ground + rocker - crank) * 0.95;
        if lo >= hi {
            continue;
        }
        let coupler = rng.range(lo, hi);
        let masses = [
            rng.range(0.05, 0.5),
            rng.range(0.05, 0.5),
            rng.range(0.05, 0.5),
        ];
        let tau = rng.range(-0.5, 0.5);
        let force = Vec2::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
        let load = Load {
            body: 2,
            point: Vec2::new(coupler, 0.0),
            force,
            moment: 0.0,
        };
        let h = 10f64.powf(rng.range(-4.0, (2e-2f64).log10()));
        let Ok(model) = crank_rocker([ground, crank, coupler, rocker], masses, tau, Some(load))
        else {
            continue;
        };
        let Ok(mut sim) =
            Simulation::new(model, &[rng.range(0.0, std::f64::consts::TAU)], &[0.0], h)
        else {
            continue;
        };
        let at = |sim: &Simulation<f64>| {
            let ws = sim.workspace();
            let b = &ws.body[2];
            b.o + Vec2::new(b.c * coupler, b.s * coupler)
        };
        let (e0, q0, p0) = (total_energy(&sim), sim.q()[0], at(&sim));
        let n = (1.0 / h).ceil() as u64;
        let mut failed = None;
        for _ in 0..n {
            if let Err(e) = sim.step() {
                failed = Some(e);
                break;
            }
            let finite = sim.q().iter().chain(sim.qd()).all(|v| v.is_finite())
                && total_energy(&sim).is_finite();
            assert!(finite, "case {case}: a non-finite state");
        }
        let work = tau * (sim.q()[0] - q0) + force.dot(&(at(&sim) - p0));
        let off = total_energy(&sim) - e0 - work;
        let b = sim.balance();
        println!(
            "case {case}: h {h:.2e}, τ {tau:+.2} N·m, t {:.4} s, work {work:.4e} J, off {off:.2e} J, redone {}, worst {:.1e}{}",
            sim.time(),
            b.redone,
            b.worst,
            failed.map_or(String::new(), |e| format!(": {e}"))
        );
        if let Some(e) = failed {
            stopped += 1;
            assert!(!e.to_string().is_empty());
            continue;
        }
        completed += 1;
        assert!(
            off.abs() <= 1e-6 * work.abs().max(1.0),
            "case {case}: balance off by {off:e} J of {work} J"
        );
        assert!(sim.kinetostatics().is_ok(), "case {case}");
    }
    println!("{completed} runs completed, {stopped} stopped");
    // A regression bound (as measured, more complete): the checks above see whole runs.
    assert!(completed >= 20, "{completed} runs completed");
}

/// The adaptive integrator's intervals are metered too: the five-bar's constant
/// 10 N·m on q1 does `10·Δq1` (the oracle), and the metered balance closes to the
/// error control's tolerance. Before, their motor work was not metered (0 J).
#[test]
fn adaptive_intervals_meter_the_motor_work() {
    let scenario = five_bar::<f64>().unwrap();
    let mut sim = scenario.simulation_with_step(0.01).unwrap();
    let mut adaptive = Adaptive::new(AdaptiveSettings {
        rtol: 1e-10,
        atol: 1e-10,
        h0: 1e-3,
        h_max: 0.01,
        ..AdaptiveSettings::default()
    })
    .unwrap();
    let q0 = sim.q()[0];
    for _ in 0..100 {
        sim.step_adaptive(&mut adaptive).unwrap();
    }
    let b = *sim.balance();
    let exact = 10.0 * (sim.q()[0] - q0);
    assert!(exact > 1.0, "the motor did work: {exact} J");
    assert!(
        (b.motor_work - exact).abs() < 1e-9 * exact,
        "{} vs {exact}",
        b.motor_work
    );
    assert_eq!(b.unaudited, 100);
    assert!(b.residual().abs() < 1e-6 * exact, "{}", b.residual());
}

/// A two-link arm in a horizontal plane (no gravity), its elbow driven by a motor
/// mounted on the upper arm (motor element R pivoted on a moving link), the shoulder's
/// coordinate free. The motor's torque pair does work `τ (ω2 − ω1)`, not `τ ω2`: the
/// oracle is the energy itself, `K(t) − K(0)` against the motor's work integrated by
/// the trapezoid rule from the relative speeds, and every step's own balance (which
/// failed at once when the work was metered on the absolute speed, 1e-3 J a step).
/// The motor's law reads the relative speed: a viscous motor `−c (ω2 − ω1)` on a
/// straight arm turning as one rigid body (ω1 = ω2) gives no torque.
#[test]
fn an_elbow_motor_works_on_the_relative_speed() {
    let arm = |motor: Motor<f64>| -> Model<f64> {
        let mut b = ModelBuilder::new();
        b.gravity(Vec2::new(0.0, 0.0));
        let a = b.ground_point(0.0, 0.0).unwrap();
        let upper = b.link(Link::bar(0.4, 1.0, 1.0 * 0.16 / 12.0, 0.2)).unwrap();
        let fore = b
            .link(Link::bar(0.3, 0.5, 0.5 * 0.09 / 12.0, 0.15))
            .unwrap();
        b.group(&MotorR {
            link: upper,
            pivot: a,
            link_point: 0,
            coord: 0,
            offset: 0.0,
        })
        .unwrap();
        b.group(&MotorR {
            link: fore,
            pivot: PointRef {
                body: upper,
                point: 1,
            },
            link_point: 0,
            coord: 1,
            offset: 0.0,
        })
        .unwrap();
        b.drive(1, motor).unwrap();
        b.build().unwrap()
    };
    let mut sim = Simulation::new(arm(Motor::Constant(0.5)), &[0.0, 0.3], &[0.0, 0.0], 1e-3)
        .expect("the arm assembles");
    let k0 = sim.energy().kinetic;
    let mut work = 0.0;
    let mut rel = sim.qd()[1] - sim.qd()[0];
    for _ in 0..500 {
        sim.step()
            .unwrap_or_else(|e| panic!("t = {}: {e}", sim.time()));
        let now = sim.qd()[1] - sim.qd()[0];
        work += 0.5 * 0.5 * (rel + now) * 1e-3;
        rel = now;
    }
    assert!(
        sim.qd()[0].abs() > 0.1,
        "the shoulder turns under the reaction"
    );
    let gained = sim.energy().kinetic - k0;
    // The trapezoid's error over 0.5 s of a smooth motion at h = 1 ms.
    assert!(
        (gained - work).abs() <= 1e-4 * work.abs(),
        "ΔK {gained} against the work {work}"
    );
    assert!((sim.balance().motor_work - gained).abs() <= 1e-6 * gained.abs());
    // A viscous elbow motor on a straight arm spun as one body (the pin's force on the
    // forearm then passes through its COG: it stays straight unless the motor acts):
    // no relative speed, no torque.
    let viscous = |_t: f64, _q: f64, qd: f64| -2.0 * qd;
    let mut rigid = Simulation::new(arm(Motor::User(viscous)), &[0.0, 0.0], &[1.0, 1.0], 1e-3)
        .expect("the arm assembles");
    for _ in 0..100 {
        rigid.step().expect("a step");
    }
    let bend = rigid.qd()[1] - rigid.qd()[0];
    assert!(
        bend.abs() < 1e-12,
        "the elbow bent at {bend} rad/s: the motor read the absolute speed"
    );
}
