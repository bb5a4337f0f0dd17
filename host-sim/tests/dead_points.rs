//! Issue 17, item 5: a general mechanism passes the dead points of its drivers by
//! switching to another independent coordinate (`structomat::simulation::switch`), the
//! mechanisms in `host-sim/mechanisms`. Oracles: the energy balance (the motor's work
//! against the change of K + V, metered by the core with the state), the integrator's
//! order (h against h/2 against h/4), and the slider-crank's closed-form kinematics.

use host_sim::analysis::{analyze, build_model};
use host_sim::runfile::{parse_run_file, Body, Mechanism};
use structomat::simulation::switch::{Alternatives, SwitchSettings};
use structomat::{GroupFault, Simulation, StepError};

const PISTON: &str = include_str!("../mechanisms/piston-slider-crank.toml");
const TRIAD: &str = include_str!("../mechanisms/crank-triad.toml");

fn mechanism(text: &str) -> (Mechanism, f64, f64) {
    let f = parse_run_file(text, "test.toml").expect("run file");
    let Body::Mechanism(m) = f.body else {
        panic!("a converter file")
    };
    let d = &m.drivers[0];
    let q0 = if m.joints[d.joint].kind.is_revolute() {
        d.q0_written.to_radians()
    } else {
        d.q0
    };
    (m.clone(), q0, d.qd0)
}

/// The mechanism at its initial state with step `h` and its alternatives
/// (`with_alternatives`: the ones `host-sim` finds; else none).
fn setup(
    text: &str,
    h: f64,
    with_alternatives: bool,
) -> (Simulation<f64>, Box<Alternatives<f64, 4>>) {
    let (m, q0, qd0) = mechanism(text);
    let a = analyze(&m).expect("analysis");
    let sim = Simulation::new(build_model::<f64>(&m, &a).expect("model"), &[q0], &[qd0], h)
        .expect("set-up");
    let mut alts =
        Box::new(Alternatives::new(&sim, SwitchSettings::default()).expect("alternatives"));
    if with_alternatives {
        for model in host_sim::model_alternatives::<f64>(&m).expect("alternatives") {
            alts.add(model).expect("add");
        }
    }
    (sim, alts)
}

/// Runs to `t_end`; returns the first coordinate and its rate every `every` seconds,
/// the switches, and the simulation.
fn run(text: &str, h: f64, t_end: f64, every: f64) -> (Vec<[f64; 2]>, u32, Simulation<f64>) {
    let (mut sim, mut alts) = setup(text, h, true);
    // The plain DP5 (its local error unchecked, the energy balance checked): its order
    // shows in the differences between h, h/2 and h/4.
    sim.set_local_tolerance(f64::INFINITY, 0.0)
        .expect("tolerance");
    let n = (t_end / h).round() as u64;
    let stride = (every / h).round() as u64;
    let mut out = Vec::new();
    for k in 1..=n {
        alts.step(&mut sim)
            .unwrap_or_else(|e| panic!("h = {h}: {e}"));
        if k % stride == 0 {
            let (q, qd) = alts.first_state(&sim);
            out.push([q[0], qd[0]]);
        }
    }
    (out, alts.switches(), sim)
}

fn largest_difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> [f64; 2] {
    let mut d = [0.0f64; 2];
    for (x, y) in a.iter().zip(b) {
        d[0] = d[0].max((x[0] - y[0]).abs());
        d[1] = d[1].max((x[1] - y[1]).abs());
    }
    d
}

/// `text`'s first coordinate and rate every 0.05 s to `t_end` at h = `h`, h/2 and h/4
/// (plain DP5 steps: see [`run`]) agree as DP5's order says: its global error is C h⁵ away from the switches, and a
/// switch restarts the integrator with no error of its own (the state maps exactly), so
/// the differences shrink by 2⁵ = 32 each halving; by at least 2³ = 8 is asserted,
/// allowing for the switch times, which move with h. The bound on h against h/2:
/// `bound` (rad or m, and per s for the rates: 100 times it). `a`: the run at h.
fn assert_dp5_order(text: &str, a: &[[f64; 2]], h: f64, t_end: f64, bound: f64) {
    let (b, _, _) = run(text, h / 2.0, t_end, 0.05);
    let (c, _, _) = run(text, h / 4.0, t_end, 0.05);
    let d1 = largest_difference(a, &b);
    let d2 = largest_difference(&b, &c);
    eprintln!("h vs h/2: {d1:?}; h/2 vs h/4: {d2:?}");
    assert!(d1[0] < bound && d1[1] < 100.0 * bound, "h vs h/2: {d1:?}");
    assert!(
        d2[0] < d1[0] / 8.0 && d2[1] < d1[1] / 8.0,
        "h/2 vs h/4 {d2:?}, h vs h/2 {d1:?}"
    );
}

/// The energy balance over the run, switches included: the work of the motor against
/// Δ(K + V), to 1e-6 of the energy the run moves (the scale: 1 J + |work| + K + |V|).
fn assert_balance_closed(sim: &Simulation<f64>) {
    let b = sim.balance();
    assert!(
        b.residual().abs() < 1e-6 * b.scale(),
        "residual {:e} of scale {:e}",
        b.residual(),
        b.scale()
    );
}

/// The piston-driven slider-crank passes its crank's dead centres (the RRR dyad of crank
/// and rod singular under the piston's coordinate) six times in 1 s; on the present code
/// the piston coordinate stops there ("singular Jacobian" / "cannot assemble").
#[test]
fn piston_driven_slider_crank_passes_its_dead_centres() {
    let (a, switches, sim) = run(PISTON, 1e-3, 1.0, 0.05);
    // Each dead centre is one switch away from the piston and one back. A regression
    // bound (as measured, the run makes at least these): it passes its dead centres.
    assert!(switches >= 6, "{switches} switches");
    assert_balance_closed(&sim);
    // The piston's position against the closed form of the crank angle at the end.
    let ws = sim.workspace();
    let th = ws.body[1].theta;
    let x = 0.06 * th.cos() + (0.225f64.powi(2) - (0.06 * th.sin()).powi(2)).sqrt();
    assert!(
        (ws.body[3].o.x - x).abs() < 1e-9,
        "{} vs {x}",
        ws.body[3].o.x
    );
    assert_dp5_order(PISTON, &a, 1e-3, 1.0, 1e-7);
}

/// The Stephenson six-bar's rocker drives its triad into the triad's singularity at each
/// end of its swing, twice a turn of the flywheel b2 (on the present code the run stops
/// at 0.511 s, conditioning 0.006, its steps breaking the energy balance); the run
/// switches to b2's angle there and back, eight times in 2.5 s.
#[test]
fn rocker_driving_a_triad_passes_its_dead_points() {
    let (a, switches, sim) = run(TRIAD, 1e-3, 2.5, 0.05);
    // A regression bound (as measured, at least these): it passes its dead points.
    assert!(switches >= 8, "{switches} switches");
    assert_balance_closed(&sim);
    // The rocker's angle stays in its swing, [-75.86°, -21.02°] (the four-bar
    // K2-b2-plate-b3-K3 and the dyad at A by circle intersections, in the file's notes).
    for [q, _] in &a {
        let deg = q.to_degrees();
        assert!((-75.87..=-21.01).contains(&deg), "{deg}°");
    }
    assert_dp5_order(TRIAD, &a, 1e-3, 2.5, 1e-7);
}

/// Without an alternative, the piston's coordinate meets the dead centre and the run
/// ends with an error that says "dead point", names the group and the time, and keeps
/// the last good state.
#[test]
fn no_other_coordinate_ends_with_a_dead_point_error() {
    let (mut sim, mut alts) = setup(PISTON, 1e-3, false);
    let e = loop {
        if let Err(e) = alts.step(&mut sim) {
            break e;
        }
        assert!(sim.time() < 1.0, "no dead point within 1 s");
    };
    let StepError::Group { time, group, fault } = e else {
        panic!("{e}")
    };
    assert!(
        matches!(
            fault,
            GroupFault::DeadPoint {
                alternatives: 0,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(group.to_string(), "RRR(1,2)");
    assert_eq!(time, sim.time());
    let text = e.to_string();
    assert!(
        text.contains("dead point")
            && text.contains("RRR(1,2)")
            && text.contains(&format!("t = {time:.6} s")),
        "{text}"
    );
    // The first dead centre of the run with alternatives comes at 0.13 s (a
    // regression bracket, as measured).
    assert!(time > 0.1 && time < 0.2, "{time}");
}
