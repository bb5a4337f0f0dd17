//! Robustness (issue 4): property tests of the model builder, the simulation step and
//! the converter twin with random geometries and inputs, from a seeded PRNG (splitmix64,
//! fixed seeds: every CI run draws the same cases).
//!
//! Values come from a mix: the reference values, perturbations of them (a per-case
//! spread from 0 to 30 %), ordinary ranges, and specials (NaN, ±inf, ±0, ±1e300,
//! 1e-300, f64::MAX, MIN_POSITIVE, a subnormal, negated references). Each case picks
//! how often a value is replaced by a special (never, 1 %, ... 50 %), so that some cases
//! are sane enough to reach the step path and some are garbage throughout.
//!
//! The properties, for every case:
//! - no panic (each case runs under `catch_unwind`; a panic is a failure with the
//!   case's seed);
//! - no NaN or infinity in any output after a successful setup or step;
//! - every failure is a named error: a non-empty `Display` that names the field, the
//!   group or the time;
//! - after a failed step the state is bit-identical to the state before it;
//! - an invalid input (NaN, ±inf, a negative load) is never accepted.
//!
//! Replay one case: `ROBUSTNESS_SEED=0x... cargo test --test robustness -- --nocapture`
//! (each suite then runs that seed alone; `ROBUSTNESS_DEBUG=1` also prints the
//! generated model or converter; `ROBUSTNESS_LOG=path` writes every failure there).
//! The long variant: `cargo test --release --test robustness -- --ignored --nocapture`.

// `!(x > 0)` rejects NaN along with non-positive values, as in the core.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::fmt::Display;
use std::panic::{self, AssertUnwindSafe};
use std::sync::Once;
use std::time::Instant;

use structomat::ccc::{
    Bar, CccParams, DriveDirection, Inputs, Measurement, MotorInput, Side, Twin, TwinSettings,
    TwinSetupError, TwinStepError,
};
use structomat::config::{MAX_DOF, MAX_DRIVES, MAX_GROUND_POINTS, MAX_GROUPS, MAX_LINKS};
use structomat::model::{Link, Load, ModelBuilder};
use structomat::motor::{Asynchronous, Motor};
use structomat::scalar::Vec2;
use structomat::structomat::{
    AssurGroup, AssurJoint, AssurLoop, AssurStep, DyadRrr, DyadRrt, DyadRtr, DyadRtt, DyadTrt,
    MotorR, MotorT, PointRef, TriadRrRrRr,
};
use structomat::{Model, ModelError, Real, SetupError, Simulation, StepError};
use structomat_suite::Rng;

// ---------------------------------------------------------------------------------------
// Deterministic randomness
// ---------------------------------------------------------------------------------------

/// The special values every numeric input meets now and then.
const SPECIALS: [f64; 17] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e300,
    -1e300,
    1e-300,
    -1e-300,
    f64::MAX,
    f64::MIN,
    f64::MIN_POSITIVE,
    5e-324,
    1e6,
    -1.0,
    1e12,
    -1e6,
];

/// A case's value generator.
struct Gen {
    rng: Rng,
    /// Probability that a value is replaced by a special.
    garbage: f64,
    /// Relative spread of the perturbations of reference values.
    spread: f64,
}

impl Gen {
    fn new(seed: u64) -> Self {
        let mut rng = Rng(seed);
        let garbage = rng.pick(&[0.0, 0.0, 0.0, 0.005, 0.02, 0.05, 0.2, 0.5]);
        let spread = rng.pick(&[0.0, 1e-9, 1e-4, 1e-2, 0.05, 0.3]);
        Gen {
            rng,
            garbage,
            spread,
        }
    }
    fn special(&mut self) -> f64 {
        self.rng.pick(&SPECIALS)
    }
    /// A value around `reference`: a special (including `-reference`) with the case's
    /// garbage rate, else the reference perturbed by the case's spread.
    fn val(&mut self, reference: f64) -> f64 {
        if self.rng.chance(self.garbage) {
            return if self.rng.chance(0.15) {
                -reference
            } else {
                self.special()
            };
        }
        let s = self.spread;
        reference * (1.0 + self.rng.range(-s, s))
            + if reference == 0.0 {
                s * self.rng.range(-1.0, 1.0)
            } else {
                0.0
            }
    }
    /// An ordinary value in `[lo, hi)`, or a special at the garbage rate.
    fn any(&mut self, lo: f64, hi: f64) -> f64 {
        if self.rng.chance(self.garbage) {
            self.special()
        } else {
            self.rng.range(lo, hi)
        }
    }
    fn t<T: Real>(&mut self, reference: f64) -> T {
        T::c(self.val(reference))
    }
    fn v2<T: Real>(&mut self, x: f64, y: f64) -> Vec2<T> {
        Vec2::new(self.t(x), self.t(y))
    }
    /// An index below `n` mostly; past it or 255 at the garbage rate.
    fn index(&mut self, n: usize) -> u8 {
        if self.rng.chance(self.garbage) {
            self.rng
                .pick(&[n.min(255) as u8, (n + 1).min(255) as u8, 255, 7])
        } else {
            self.rng.below(n.max(1)) as u8
        }
    }
}

// ---------------------------------------------------------------------------------------
// Running cases: panics caught and attributed to seeds, counts kept
// ---------------------------------------------------------------------------------------

thread_local! {
    static IN_CASE: Cell<bool> = const { Cell::new(false) };
    static PANIC_MSG: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// A panic hook that records (instead of printing) the panics of a running case; other
/// panics (the tests' own assertions) go to the default hook.
fn install_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let prev = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if IN_CASE.with(|c| c.get()) {
                let msg = info
                    .payload()
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| info.payload().downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(non-string panic)".into());
                let loc = info
                    .location()
                    .map(|l| format!("{}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                PANIC_MSG.with(|p| *p.borrow_mut() = Some(format!("panic: {msg} at {loc}")));
            } else {
                prev(info)
            }
        }));
    });
}

/// What a suite did.
#[derive(Default)]
struct Tally {
    cases: u64,
    /// Descriptions accepted (builder, twin setup).
    accepted: u64,
    /// Simulations or twins set up.
    setups: u64,
    steps_ok: u64,
    steps_err: u64,
    /// Errors by kind (type and variant).
    errors: BTreeMap<String, u64>,
    /// Failures of the properties, with the seed of their case.
    failures: Vec<String>,
}

impl Tally {
    fn error(&mut self, kind: String) {
        *self.errors.entry(kind).or_default() += 1;
    }
    fn merge(&mut self, o: &Tally) {
        self.cases += o.cases;
        self.accepted += o.accepted;
        self.setups += o.setups;
        self.steps_ok += o.steps_ok;
        self.steps_err += o.steps_err;
        for (k, v) in &o.errors {
            *self.errors.entry(k.clone()).or_default() += v;
        }
        self.failures.extend(o.failures.iter().cloned());
    }
    fn report(&self, name: &str, secs: f64) {
        println!(
            "{name}: {} cases, {} accepted, {} set up, {} steps ok, {} steps refused, {} failures ({secs:.1} s)",
            self.cases,
            self.accepted,
            self.setups,
            self.steps_ok,
            self.steps_err,
            self.failures.len()
        );
        for (k, v) in &self.errors {
            println!("    {v:>7} × {k}");
        }
    }
}

/// The variant of an error, from its `Debug` form (`Type::Variant`).
fn kind_of(prefix: &str, e: &impl std::fmt::Debug) -> String {
    let d = format!("{e:?}");
    let end = d.find(['(', ' ', '{']).unwrap_or(d.len());
    format!("{prefix}::{}", &d[..end])
}

type Case = fn(u64, &mut Tally) -> Result<(), String>;

/// Runs `cases` cases of `case` from `base` (or the seed in `ROBUSTNESS_SEED` alone),
/// each under `catch_unwind`; prints the counts and returns the tally.
fn run_suite(name: &str, base: u64, cases: u64, case: Case) -> Tally {
    install_hook();
    let replay = std::env::var("ROBUSTNESS_SEED").ok().map(|s| {
        let s = s.trim_start_matches("0x");
        u64::from_str_radix(s, 16).expect("ROBUSTNESS_SEED: hex")
    });
    let seeds: Vec<u64> = match replay {
        Some(s) => vec![s],
        None => {
            let mut r = Rng(base);
            (0..cases).map(|_| r.next_u64()).collect()
        }
    };
    let start = Instant::now();
    let mut tally = Tally::default();
    for seed in seeds {
        tally.cases += 1;
        IN_CASE.with(|c| c.set(true));
        let r = panic::catch_unwind(AssertUnwindSafe(|| case(seed, &mut tally)));
        IN_CASE.with(|c| c.set(false));
        match r {
            Ok(Ok(())) => {}
            Ok(Err(msg)) => tally
                .failures
                .push(format!("{name} seed {seed:#018x}: {msg}")),
            Err(_) => {
                let msg = PANIC_MSG
                    .with(|p| p.borrow_mut().take())
                    .unwrap_or_default();
                tally
                    .failures
                    .push(format!("{name} seed {seed:#018x}: {msg}"));
            }
        }
    }
    tally.report(name, start.elapsed().as_secs_f64());
    tally
}

fn assert_no_failures(t: &Tally) {
    if let Ok(path) = std::env::var("ROBUSTNESS_LOG") {
        std::fs::write(path, t.failures.join("\n")).expect("ROBUSTNESS_LOG: writable");
    }
    assert!(
        t.failures.is_empty(),
        "{} failures (replay with ROBUSTNESS_SEED):\n{}",
        t.failures.len(),
        t.failures
            .iter()
            .take(20)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// Oracles: named errors, finite outputs, untouched state
// ---------------------------------------------------------------------------------------

/// An error's message is not empty, names something (at least a few words) and, when it
/// carries a time, that time is finite and printed.
fn check_named(e: &impl Display, time: Option<f64>) -> Result<(), String> {
    let msg = e.to_string();
    if msg.trim().len() < 12 || !msg.contains(' ') {
        return Err(format!("error message names nothing: {msg:?}"));
    }
    if msg.contains("NaN") {
        return Err(format!("error message carries a NaN: {msg}"));
    }
    if let Some(t) = time {
        if !t.is_finite() {
            return Err(format!("error time is not finite: {msg}"));
        }
        if !msg.contains("t = ") {
            return Err(format!("error message does not give the time: {msg}"));
        }
    }
    Ok(())
}

fn check_model_error(e: &ModelError) -> Result<(), String> {
    check_named(e, None)
}

fn check_step_error(e: &StepError) -> Result<(), String> {
    check_named(e, Some(e.time()))?;
    let msg = e.to_string();
    match e {
        StepError::Group { group, .. } => {
            if !msg.contains(&group.to_string()) {
                return Err(format!("group error does not name its group: {msg}"));
            }
        }
        StepError::NonFinite { what, .. } => {
            // `what` is "value (cause)": the message reads "value is not finite: cause".
            let (value, cause) = what
                .strip_suffix(')')
                .and_then(|w| w.split_once(" ("))
                .unwrap_or((what, ""));
            if !(msg.contains(value) && msg.contains(cause)) {
                return Err(format!("non-finite error does not name what: {msg}"));
            }
        }
        StepError::SingularMassMatrix { .. } => {}
        StepError::EnergyBalance { .. } => {
            if !msg.contains("smaller step") {
                return Err(format!("energy-balance error does not advise: {msg}"));
            }
        }
    }
    Ok(())
}

fn check_setup_error(e: &SetupError) -> Result<(), String> {
    match e {
        SetupError::Model(m) => check_model_error(m),
        SetupError::Initial(s) => check_step_error(s),
        SetupError::Setting(_) => check_named(e, None),
    }
}

fn twin_error_time(e: &TwinStepError) -> Option<f64> {
    match e {
        TwinStepError::TimeOverflow { .. } => None,
        TwinStepError::Step(s) => Some(s.time()),
        TwinStepError::BadInput { time, .. }
        | TwinStepError::Model { time, .. }
        | TwinStepError::Mechanism { time, .. }
        | TwinStepError::Diverged { time, .. }
        | TwinStepError::Diode { time, .. } => Some(*time),
    }
}

fn check_twin_setup_error(e: &TwinSetupError) -> Result<(), String> {
    match e {
        TwinSetupError::Start(s) => {
            check_twin_error(s)?;
            check_named(e, twin_error_time(s))
        }
        e => check_named(e, None),
    }
}

fn check_twin_error(e: &TwinStepError) -> Result<(), String> {
    check_named(e, twin_error_time(e))?;
    if let TwinStepError::Step(s) = e {
        check_step_error(s)?;
    }
    if let TwinStepError::Diverged { jump, .. } = e {
        // The jump is what broke the balance: NaN would say nothing.
        if jump.is_nan() {
            return Err(format!("diverged with a NaN jump: {e}"));
        }
    }
    Ok(())
}

/// Named float outputs: checked finite, compared bit for bit.
#[derive(Default, Debug, PartialEq)]
struct Snap {
    ints: Vec<(&'static str, u64)>,
    text: Vec<(&'static str, String)>,
    floats: Vec<(&'static str, u64)>,
    /// Floats that may be +inf by design (a candidate mode's violation), never NaN.
    may_be_inf: Vec<(&'static str, u64)>,
}

impl Snap {
    fn f<T: Real>(&mut self, what: &'static str, x: T) {
        self.floats.push((what, x.to_f64().to_bits()));
    }
    fn fs<T: Real>(&mut self, what: &'static str, xs: &[T]) {
        for x in xs {
            self.f(what, *x);
        }
    }
    fn v<T: Real>(&mut self, what: &'static str, v: &Vec2<T>) {
        self.f(what, v.x);
        self.f(what, v.y);
    }
    fn all_finite(&self) -> Result<(), String> {
        for (what, b) in &self.floats {
            let x = f64::from_bits(*b);
            if !x.is_finite() {
                return Err(format!("output {what} is {x}"));
            }
        }
        for (what, b) in &self.may_be_inf {
            if f64::from_bits(*b).is_nan() {
                return Err(format!("output {what} is NaN"));
            }
        }
        Ok(())
    }
    /// The first difference to `before`, named.
    fn same_as(&self, before: &Snap) -> Result<(), String> {
        if self == before {
            return Ok(());
        }
        let diff = |a: &[(&str, u64)], b: &[(&str, u64)]| {
            if a.len() != b.len() {
                return Some(format!("{} values, was {}", a.len(), b.len()));
            }
            a.iter().zip(b).find(|(x, y)| x != y).map(|(x, y)| {
                format!(
                    "{}: {:e} (was {:e})",
                    x.0,
                    f64::from_bits(x.1),
                    f64::from_bits(y.1)
                )
            })
        };
        let d = if self.ints != before.ints {
            format!("{:?} (was {:?})", self.ints, before.ints)
        } else if self.text != before.text {
            format!("{:?} (was {:?})", self.text, before.text)
        } else {
            diff(&self.floats, &before.floats)
                .or_else(|| diff(&self.may_be_inf, &before.may_be_inf))
                .unwrap_or_default()
        };
        Err(format!("a failed step changed the state: {d}"))
    }
}

// ---------------------------------------------------------------------------------------
// Generic mechanisms: random descriptions and perturbed built-ins
// ---------------------------------------------------------------------------------------

fn nan_after_10ms<T: Real>(t: T, _q: T, _qd: T) -> T {
    if t.to_f64() > 0.01 {
        T::c(f64::NAN)
    } else {
        T::c(5.0)
    }
}
fn inf_at_speed<T: Real>(_t: T, _q: T, qd: T) -> T {
    if qd.to_f64().abs() > 1.0 {
        T::c(f64::INFINITY)
    } else {
        T::c(2.0)
    }
}
fn huge<T: Real>(_t: T, _q: T, _qd: T) -> T {
    T::c(1e300)
}
/// A sudden load change: 0, then 1e6 N·m for 5 ms, then 0 again.
fn kick<T: Real>(t: T, _q: T, _qd: T) -> T {
    let t = t.to_f64();
    T::c(if (0.005..0.01).contains(&t) { 1e6 } else { 0.0 })
}
fn viscous<T: Real>(_t: T, _q: T, qd: T) -> T {
    T::c(20.0) - T::c(3.0) * qd
}

/// A motor law: constants (ordinary or special), the asynchronous parabola with
/// possibly garbage coefficients, or a user function that goes NaN, infinite or huge.
fn random_motor<T: Real>(g: &mut Gen, reference: f64) -> Motor<T> {
    match g.rng.below(6) {
        0 | 1 => Motor::Constant(g.t(reference)),
        2 => match Asynchronous::through(g.t(1.0), g.t(10.0), g.t(4.7), g.t(3.0), g.t(7.3)) {
            Ok(a) => Motor::Asynchronous(a),
            Err(e) => {
                assert!(!e.to_string().is_empty());
                Motor::Asynchronous(Asynchronous {
                    a: g.t(15.0),
                    b: g.t(-1.0),
                    c: g.t(-0.1),
                })
            }
        },
        _ => Motor::User(g.rng.pick(&[
            nan_after_10ms::<T> as fn(T, T, T) -> T,
            inf_at_speed::<T>,
            huge::<T>,
            kick::<T>,
            viscous::<T>,
        ])),
    }
}

fn random_link<T: Real>(g: &mut Gen) -> Link<T> {
    let mut l = if g.rng.chance(0.8) {
        let len = g.any(0.05, 2.0);
        Link::bar(T::c(len), g.t(0.5), g.t(0.01), T::c(g.val(len / 2.0)))
    } else {
        Link::block(g.t(0.3), g.t(1e-3))
    };
    for _ in 0..g.rng.below(3) {
        if let Err(e) = l.add_point(g.v2(0.1, 0.05)) {
            assert!(!e.to_string().is_empty());
        }
    }
    if g.rng.chance(0.2) {
        l.add_mass(g.t(1.0), g.t(0.01), g.v2(0.2, 0.0));
    }
    l
}

fn point_ref(g: &mut Gen, bodies: usize) -> PointRef {
    PointRef {
        body: g.index(bodies),
        point: g.index(3),
    }
}

/// A group of a random kind with random references and values.
fn random_group<T: Real>(
    g: &mut Gen,
    b: &mut ModelBuilder<T>,
    n_links: usize,
) -> Result<(), String> {
    let bodies = n_links + 1;
    let link = |g: &mut Gen| g.index(n_links.max(1)).saturating_add(1);
    let coord = |g: &mut Gen| g.index(MAX_DOF);
    let r = match g.rng.below(9) {
        0 | 1 => {
            let spec = MotorR {
                link: link(g),
                pivot: point_ref(g, bodies),
                link_point: g.index(2),
                coord: coord(g),
                offset: g.t(0.0),
            };
            b.group(&spec)
        }
        2 => {
            let spec = MotorT {
                link: link(g),
                guide: point_ref(g, bodies),
                guide_angle: g.t(0.5),
                link_point: g.index(2),
                link_angle: g.t(0.5),
                coord: coord(g),
            };
            b.group(&spec)
        }
        3 => {
            let spec = DyadRrr {
                a: link(g),
                b: link(g),
                pole_a: point_ref(g, bodies),
                a_at_pole: g.index(2),
                pole_b: point_ref(g, bodies),
                b_at_pole: g.index(2),
                a_joint: g.index(2),
                b_joint: g.index(2),
                guess: [g.t(0.5), g.t(2.0)],
            };
            b.group(&spec)
        }
        4 => {
            let spec = DyadRrt {
                rod: link(g),
                slider: link(g),
                pole: point_ref(g, bodies),
                rod_at_pole: g.index(2),
                rod_joint: g.index(2),
                slider_joint: g.index(2),
                guide: point_ref(g, bodies),
                guide_angle: g.t(0.0),
                slider_on_guide: g.index(2),
                slider_angle: g.t(0.0),
                guess: [g.t(6.0), g.t(0.2)],
            };
            b.group(&spec)
        }
        5 => {
            let spec = DyadRtr {
                a: link(g),
                b: link(g),
                pole_a: point_ref(g, bodies),
                a_at_pole: g.index(2),
                pole_b: point_ref(g, bodies),
                b_at_pole: g.index(2),
                b_line: g.index(3),
                b_line_angle: g.t(0.0),
                a_on_line: g.index(2),
                a_angle: g.t(0.1),
                guess: [g.t(1.6), g.t(0.35)],
            };
            b.group(&spec)
        }
        6 => {
            let spec = DyadTrt {
                a: link(g),
                b: link(g),
                guide_a: point_ref(g, bodies),
                guide_a_angle: g.t(1.0),
                a_on_guide: g.index(2),
                a_angle: g.t(0.0),
                guide_b: point_ref(g, bodies),
                guide_b_angle: g.t(1.0),
                b_on_guide: g.index(2),
                b_angle: g.t(1.0),
                a_joint: g.index(2),
                b_joint: g.index(2),
            };
            b.group(&spec)
        }
        7 => {
            let spec = DyadRtt {
                a: link(g),
                b: link(g),
                pole_a: point_ref(g, bodies),
                a_at_pole: g.index(2),
                guide: point_ref(g, bodies),
                guide_angle: g.t(0.3),
                b_on_guide: g.index(2),
                b_angle: g.t(0.3),
                b_line: g.index(3),
                b_line_angle: g.t(1.4),
                a_on_line: g.index(2),
                a_angle: g.t(0.2),
            };
            b.group(&spec)
        }
        _ => {
            if g.rng.chance(0.5) {
                let spec = TriadRrRrRr {
                    ternary: link(g),
                    ternary_joints: [g.index(3), g.index(3), g.index(3)],
                    binary: [link(g), link(g), link(g)],
                    binary_at_pole: [g.index(2), g.index(2), g.index(2)],
                    binary_at_ternary: [g.index(2), g.index(2), g.index(2)],
                    poles: [
                        point_ref(g, bodies),
                        point_ref(g, bodies),
                        point_ref(g, bodies),
                    ],
                    guess: [g.t(0.4), g.t(1.6), g.t(-0.6), g.t(0.0)],
                };
                b.group(&spec)
            } else {
                // A general Assur group with slices of random lengths.
                let n = g.rng.below(8);
                let links: Vec<u8> = (0..n).map(|_| link(g)).collect();
                let steps: Vec<AssurStep> = (0..g.rng.below(6))
                    .map(|_| AssurStep {
                        link: g.index(n),
                        from: g.index(3),
                        to: g.index(3),
                    })
                    .collect();
                let loops: Vec<AssurLoop> = (0..g.rng.below(5))
                    .map(|_| AssurLoop {
                        start: point_ref(g, bodies),
                        steps: &steps[..g.rng.below(steps.len() + 1)],
                        end: point_ref(g, bodies),
                    })
                    .collect();
                let joints: Vec<AssurJoint> = (0..g.rng.below(12))
                    .map(|_| AssurJoint {
                        link: link(g),
                        at: g.index(3),
                        other: point_ref(g, bodies),
                    })
                    .collect();
                let guess: Vec<T> = (0..g.rng.below(8)).map(|_| g.t(0.5)).collect();
                b.group(&AssurGroup {
                    links: &links,
                    loops: &loops,
                    joints: &joints,
                    guess: &guess,
                })
            }
        }
    };
    match r {
        Err(e) => check_model_error(&e),
        Ok(_) => Ok(()),
    }
}

/// A random description: garbage in every part, bad indices, capacities exceeded.
fn case_random_description<T: Real>(seed: u64, tally: &mut Tally) -> Result<(), String> {
    let mut g = Gen::new(seed);
    // More garbage here: the builder is the door.
    g.garbage = g.garbage.max(0.02);
    let mut b = ModelBuilder::<T>::new();
    if g.rng.chance(0.3) {
        b.gravity(g.v2(0.0, -9.81));
    }
    if g.rng.chance(0.1) {
        b.singular_tol(g.t(1.5e-9));
    }
    for _ in 0..g.rng.below(MAX_GROUND_POINTS + 3) {
        if let Err(e) = b.ground_point(g.t(0.5), g.t(0.2)) {
            check_model_error(&e)?;
        }
    }
    let mut n_links = 0;
    for _ in 0..g.rng.below(MAX_LINKS + 3) {
        let l = random_link::<T>(&mut g);
        match b.link(l) {
            Ok(_) => n_links += 1,
            Err(e) => check_model_error(&e)?,
        }
    }
    for _ in 0..g.rng.below(MAX_GROUPS + 3) {
        random_group(&mut g, &mut b, n_links)?;
    }
    for _ in 0..g.rng.below(MAX_DRIVES + 2) {
        let m = random_motor(&mut g, 10.0);
        if let Err(e) = b.drive(g.index(MAX_DOF), m) {
            check_model_error(&e)?;
        }
    }
    for _ in 0..g.rng.below(3) {
        let load = Load {
            body: g.index(n_links + 1),
            point: g.v2(0.1, 0.0),
            force: g.v2(1.0, -2.0),
            moment: g.t(0.5),
        };
        if let Err(e) = b.load(load) {
            check_model_error(&e)?;
        }
    }
    match b.build() {
        Err(e) => {
            tally.error(kind_of("ModelError", &e));
            check_model_error(&e)
        }
        Ok(model) => {
            tally.accepted += 1;
            check_model(&model)?;
            let q0: Vec<f64> = (0..model.dof()).map(|_| g.rng.range(-3.0, 3.0)).collect();
            simulate(model, &q0, &mut g, tally, 10)
        }
    }
}

/// Everything a built model holds is finite (the builder's promise to the step path).
fn check_model<T: Real>(m: &Model<T>) -> Result<(), String> {
    let mut s = Snap::default();
    for p in m.ground_points() {
        s.v("ground point", p);
    }
    for l in m.links() {
        s.f("link mass", l.mass);
        s.f("link inertia", l.inertia);
        s.v("link COG", &l.cog);
        for p in &l.points {
            s.v("link point", p);
        }
    }
    for grp in m.groups() {
        s.fs("group guess", &grp.guess);
        s.fs("group constant", &grp.consts);
        for p in &grp.placements {
            s.f("placement angle offset", p.angle.offset);
            s.v("placement point", &p.local);
        }
        for j in &grp.joints {
            s.v("joint point", &j.pi);
            s.v("joint point", &j.pj);
        }
        for c in &grp.chains {
            for t in &c.terms {
                match t {
                    structomat::structomat::Term::Arm { angle, v } => {
                        s.f("arm angle offset", angle.offset);
                        s.v("arm vector", v);
                    }
                    structomat::structomat::Term::Slide { angle, dir, .. } => {
                        s.f("slide angle offset", angle.offset);
                        s.v("slide direction", dir);
                    }
                }
            }
        }
    }
    for l in m.loads() {
        s.v("load point", &l.point);
        s.v("load force", &l.force);
        s.f("load moment", l.moment);
    }
    s.v("gravity", &m.gravity());
    s.f("singularity threshold", m.singular_tol());
    s.f("Newton tolerance", m.newton_tol());
    s.all_finite().map_err(|e| format!("built model: {e}"))
}

/// Everything a simulation shows: time, steps, state, accelerations, every body, the
/// group unknowns, the energy.
fn sim_snapshot<T: Real>(sim: &Simulation<T>) -> Snap {
    let mut s = Snap::default();
    s.ints.push(("steps", sim.steps()));
    s.f("time", sim.time());
    s.fs("q", sim.q());
    s.fs("qd", sim.qd());
    s.fs("qdd", sim.qdd());
    let ws = sim.workspace();
    for b in ws.body.iter().skip(1).take(sim.model().n_links()) {
        s.f("body theta", b.theta);
        s.f("body omega", b.omega);
        s.f("body alpha", b.alpha);
        s.v("body origin", &b.o);
        s.v("body velocity", &b.v);
        s.v("body acceleration", &b.a);
    }
    for grp in ws.group.iter().take(sim.model().groups().len()) {
        s.fs("group unknowns", &grp.x);
    }
    let e = sim.energy();
    s.f("kinetic energy", e.kinetic);
    s.f("potential energy", e.potential);
    s
}

/// Sets up a simulation of `model` (from `q0`, perturbed) and steps it, checking the
/// properties at every step.
fn simulate<T: Real>(
    model: Model<T>,
    q0: &[f64],
    g: &mut Gen,
    tally: &mut Tally,
    max_steps: usize,
) -> Result<(), String> {
    let q: Vec<T> = q0.iter().map(|x| g.t(*x)).collect();
    let qd: Vec<T> = q0.iter().map(|_| T::c(g.any(-2.0, 2.0))).collect();
    let h0 = g
        .rng
        .pick(&[1e-3, 1e-2, 1e-4, 1e-3, 1e-2, 1e-4, 1e300, f64::MAX, 1e-300]);
    let h: T = g.t(h0);
    if std::env::var("ROBUSTNESS_DEBUG").is_ok() {
        println!("q0 {q:?} qd0 {qd:?} h {h:?}");
    }
    let bad_setting = !(h.finite() && h > T::zero()) || q.iter().chain(&qd).any(|x| !x.finite());
    let mut sim = match Simulation::new(model, &q, &qd, h) {
        Err(e) => {
            tally.error(kind_of("SetupError", &e));
            if bad_setting && !matches!(e, SetupError::Setting(_)) {
                return Err(format!("a bad step or initial state reported as {e}"));
            }
            return check_setup_error(&e);
        }
        Ok(_) if bad_setting => {
            return Err(format!(
                "setup accepted h = {h:?}, q0 = {q:?}, qd0 = {qd:?}"
            ));
        }
        Ok(s) => s,
    };
    tally.setups += 1;
    sim_snapshot(&sim).all_finite()?;
    for k in 0..g.rng.below(max_steps + 1) {
        let before = sim_snapshot(&sim);
        let t0 = sim.time().to_f64();
        match sim.step() {
            Ok(()) => {
                tally.steps_ok += 1;
                let after = sim_snapshot(&sim);
                after.all_finite().map_err(|e| format!("step {k}: {e}"))?;
                if sim.steps() != k as u64 + 1 {
                    return Err(format!("step {k}: step count {}", sim.steps()));
                }
                if k % 3 == 0 {
                    match sim.kinetostatics() {
                        Ok(ws) => {
                            for r in ws.reactions.iter().flatten() {
                                if !(r.force.x.finite() && r.force.y.finite() && r.moment.finite())
                                {
                                    return Err(format!(
                                        "step {k}: a joint reaction is not finite"
                                    ));
                                }
                            }
                        }
                        Err(e) => {
                            tally.error(kind_of("Kinetostatics", &e));
                            check_step_error(&e)?;
                        }
                    }
                }
            }
            Err(e) => {
                tally.steps_err += 1;
                tally.error(kind_of("StepError", &e));
                check_step_error(&e).map_err(|m| format!("step {k}: {m}"))?;
                let h = sim.h().to_f64();
                if !(e.time() >= t0 && e.time() <= t0 + 2.0 * h) {
                    return Err(format!(
                        "step {k}: error time {} outside the step [{t0}, {}]",
                        e.time(),
                        t0 + h
                    ));
                }
                sim_snapshot(&sim)
                    .same_as(&before)
                    .map_err(|m| format!("step {k} ({e}): {m}"))?;
                // The last good state is kept: stepping again fails the same way.
                let again = sim.step().err();
                if again != Some(e) {
                    return Err(format!("step {k}: second try gave {again:?}, first {e:?}"));
                }
                return Ok(());
            }
        }
    }
    Ok(())
}

/// The thesis's five-bar with every value drawn around its reference.
fn five_bar<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    use structomat::mechanisms::five_bar::{INERTIAS, K, LENGTHS, MASSES};
    let mut b = ModelBuilder::<T>::new();
    b.gravity(g.v2(0.0, -9.81));
    let a = b.ground_point(g.t(0.0), g.t(0.0))?;
    let e = b.ground_point(g.t(K), g.t(0.0))?;
    let mut l = [0u8; 4];
    for k in 0..4 {
        let len = LENGTHS[k];
        l[k] = b.link(Link::bar(
            g.t(len),
            g.t(MASSES[k]),
            g.t(INERTIAS[k]),
            g.t(len / 2.0),
        ))?;
    }
    b.group(&MotorR {
        link: l[0],
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: g.t(0.0),
    })?;
    b.group(&MotorR {
        link: l[1],
        pivot: e,
        link_point: 0,
        coord: 1,
        offset: g.t(0.0),
    })?;
    b.group(&DyadRrr {
        a: l[2],
        b: l[3],
        pole_a: PointRef {
            body: l[0],
            point: 1,
        },
        a_at_pole: 0,
        pole_b: PointRef {
            body: l[1],
            point: 1,
        },
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [g.t(30f64.to_radians()), g.t(132f64.to_radians())],
    })?;
    b.drive(0, random_motor(g, 10.0))?;
    if g.rng.chance(0.3) {
        b.drive(1, random_motor(g, -3.0))?;
    }
    if g.rng.chance(0.3) {
        b.load(Load {
            body: l[2],
            point: g.v2(0.9, 0.0),
            force: g.v2(0.0, -5.0),
            moment: g.t(1.0),
        })?;
    }
    b.build()
}

/// The thesis's slider-crank with every value drawn around its reference.
fn slider_crank<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    let mut b = ModelBuilder::<T>::new();
    b.gravity(g.v2(0.0, -9.81));
    let a = b.ground_point(g.t(0.0), g.t(0.0))?;
    let crank = b.link(Link::bar(g.t(0.06), g.t(0.24), g.t(0.04), g.t(0.02)))?;
    let rod = b.link(Link::bar(g.t(0.225), g.t(0.90), g.t(0.06), g.t(0.10)))?;
    let slider = b.link(Link::block(g.t(0.62), g.t(0.0)))?;
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: g.t(0.0),
    })?;
    b.group(&DyadRrt {
        rod,
        slider,
        pole: PointRef {
            body: crank,
            point: 1,
        },
        rod_at_pole: 0,
        rod_joint: 1,
        slider_joint: 0,
        guide: a,
        guide_angle: g.t(0.0),
        slider_on_guide: 0,
        slider_angle: g.t(0.0),
        guess: [g.t(345f64.to_radians()), g.t(0.21)],
    })?;
    b.drive(0, random_motor(g, 3.0))?;
    b.build()
}

/// A crank driving a triad RR-RR-RR (tests/errors.rs), every value drawn.
fn crank_triad<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    let mut b = ModelBuilder::<T>::new();
    let a = b.ground_point(g.t(0.0), g.t(0.0))?;
    let k2 = b.ground_point(g.t(0.9), g.t(-0.2))?;
    let k3 = b.ground_point(g.t(0.3), g.t(0.9))?;
    let crank = b.link(Link::bar(g.t(0.1), g.t(0.2), g.t(1e-3), g.t(0.05)))?;
    let l2 = (0.5f64.powi(2) + 0.2f64.powi(2)).sqrt();
    let b2 = b.link(Link::bar(g.t(l2), g.t(0.3), g.t(5e-3), g.t(l2 / 2.0)))?;
    let b3 = b.link(Link::bar(g.t(0.5), g.t(0.3), g.t(5e-3), g.t(0.25)))?;
    let b4 = b.link(Link::bar(g.t(0.5), g.t(0.3), g.t(5e-3), g.t(0.25)))?;
    let mut tern = Link::bar(g.t(0.4), g.t(1.0), g.t(0.02), g.t(0.2));
    tern.add_point(g.v2(0.2, 0.3))?;
    let t = b.link(tern)?;
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: g.t(0.0),
    })?;
    b.group(&TriadRrRrRr {
        ternary: t,
        ternary_joints: [0, 1, 2],
        binary: [b2, b3, b4],
        binary_at_pole: [0, 0, 0],
        binary_at_ternary: [1, 1, 1],
        poles: [
            PointRef {
                body: crank,
                point: 1,
            },
            k2,
            k3,
        ],
        guess: [
            g.t(0.2f64.atan2(0.5)),
            g.t(90f64.to_radians()),
            g.t((-0.3f64).atan2(0.4)),
            g.t(0.0),
        ],
    })?;
    b.drive(0, random_motor(g, 1.0))?;
    b.build()
}

/// The quick-return RTR of tests/groups.rs, every value drawn.
fn crank_rtr<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    let mut b = ModelBuilder::<T>::new();
    let a = b.ground_point(g.t(0.0), g.t(0.0))?;
    let c = b.ground_point(g.t(0.02), g.t(-0.25))?;
    let crank = b.link(Link::bar(g.t(0.10), g.t(0.5), g.t(1.0e-3), g.t(0.04)))?;
    let mut rk = Link::bar(g.t(0.5), g.t(1.2), g.t(0.03), g.t(0.25));
    let line = rk.add_point(g.v2(0.0, 0.015))?;
    let rocker = b.link(rk)?;
    let mut bl = Link::block(g.t(0.3), g.t(5.0e-4));
    let pin = bl.add_point(g.v2(0.01, -0.02))?;
    let block = b.link(bl)?;
    b.group(&MotorR {
        link: crank,
        pivot: a,
        link_point: 0,
        coord: 0,
        offset: g.t(0.0),
    })?;
    b.group(&DyadRtr {
        a: block,
        b: rocker,
        pole_a: PointRef {
            body: crank,
            point: 1,
        },
        a_at_pole: pin,
        pole_b: c,
        b_at_pole: 0,
        b_line: line,
        b_line_angle: g.t(0.0),
        a_on_line: 0,
        a_angle: g.t(0.1),
        guess: [g.t(1.6), g.t(0.35)],
    })?;
    b.drive(0, random_motor(g, 1.0))?;
    b.build()
}

/// A slider (motor element T) driving an RRR dyad (tests/groups.rs), every value drawn.
fn slider_rrr<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    let th = 30f64.to_radians();
    let mut b = ModelBuilder::<T>::new();
    let g0 = b.ground_point(g.t(0.0), g.t(0.0))?;
    let d = b.ground_point(g.t(-0.4), g.t(-0.6))?;
    let mut sl = Link::block(g.t(0.3), g.t(1.0e-3));
    let pin = sl.add_point(g.v2(0.0, 0.02))?;
    let slider = b.link(sl)?;
    let l2 = b.link(Link::bar(g.t(0.30), g.t(0.8), g.t(0.006), g.t(0.15)))?;
    let l3 = b.link(Link::bar(g.t(0.40), g.t(0.7), g.t(0.0093), g.t(0.2)))?;
    b.group(&MotorT {
        link: slider,
        guide: g0,
        guide_angle: g.t(th),
        link_point: 0,
        link_angle: g.t(th),
        coord: 0,
    })?;
    b.group(&DyadRrr {
        a: l2,
        b: l3,
        pole_a: PointRef {
            body: slider,
            point: pin,
        },
        a_at_pole: 0,
        pole_b: d,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [g.t(-0.4), g.t(0.78)],
    })?;
    b.drive(0, random_motor(g, 0.5))?;
    b.build()
}

/// A structure (no degree of freedom): a dyad RRR on two ground points. It steps at any
/// h, which is how a huge h reaches the time n·h.
fn structure<T: Real>(g: &mut Gen) -> Result<Model<T>, ModelError> {
    let mut b = ModelBuilder::<T>::new();
    let a = b.ground_point(g.t(0.0), g.t(0.0))?;
    let c = b.ground_point(g.t(1.5), g.t(0.0))?;
    let l1 = b.link(Link::bar(g.t(1.0), g.t(1.0), g.t(0.1), g.t(0.5)))?;
    let l2 = b.link(Link::bar(g.t(1.0), g.t(1.0), g.t(0.1), g.t(0.5)))?;
    b.group(&DyadRrr {
        a: l1,
        b: l2,
        pole_a: a,
        a_at_pole: 0,
        pole_b: c,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [g.t(0.8), g.t(2.3)],
    })?;
    b.build()
}

/// A built-in (or test-suite) mechanism with its values perturbed, set up and stepped.
fn case_mechanism<T: Real>(seed: u64, tally: &mut Tally) -> Result<(), String> {
    let mut g = Gen::new(seed);
    let (built, q0): (Result<Model<T>, ModelError>, Vec<f64>) = match g.rng.below(11) {
        0 | 1 => (
            five_bar(&mut g),
            vec![80f64.to_radians(), 70f64.to_radians()],
        ),
        2 | 3 => (slider_crank(&mut g), vec![100f64.to_radians()]),
        4 | 5 => (crank_triad(&mut g), vec![90f64.to_radians()]),
        6 | 7 => (crank_rtr(&mut g), vec![0.5]),
        8 | 9 => (slider_rrr(&mut g), vec![-0.44]),
        _ => (structure(&mut g), vec![]),
    };
    match built {
        Err(e) => {
            tally.error(kind_of("ModelError", &e));
            check_model_error(&e)
        }
        Ok(model) => {
            tally.accepted += 1;
            check_model(&model)?;
            if std::env::var("ROBUSTNESS_DEBUG").is_ok() {
                println!("{model:?}");
            }
            simulate(model, &q0, &mut g, tally, 40)
        }
    }
}

// ---------------------------------------------------------------------------------------
// The converter twin
// ---------------------------------------------------------------------------------------

/// Everything the twin shows.
fn twin_snapshot<T: Real>(tw: &Twin<T>) -> Snap {
    let mut s = Snap::default();
    s.ints.push(("steps", tw.steps()));
    s.ints.push(("events", tw.events().len() as u64));
    s.ints.push(("switches", tw.switches().len() as u64));
    s.ints.push(("candidates", tw.candidates().len() as u64));
    s.text.push(("mode", format!("{:?}", tw.mode())));
    s.text
        .push(("coordinates", format!("{:?}", tw.coordinates())));
    s.f("time", tw.time());
    s.fs("q", tw.q());
    s.fs("qd", tw.qd());
    s.fs("qdd", tw.qdd());
    for p in 1..=8 {
        let l = tw.link(p);
        s.f("link theta", l.theta);
        s.f("link omega", l.omega);
        s.f("link alpha", l.alpha);
        s.v("link origin", &l.origin);
        s.v("link velocity", &l.velocity);
        for k in 0..3 {
            s.v("joint position", &tw.joint_position(p, k));
        }
    }
    s.f("shaft speed", tw.shaft_speed());
    s.f("shaft angle", tw.shaft_angle());
    s.fs("clutch torques", &tw.clutch_torques());
    for r in tw.joint_reactions() {
        s.v("joint reaction", r);
    }
    s.f("motor torque", tw.motor_torque());
    let a = tw.audit();
    s.f("audit motor work", a.motor_work);
    s.f("audit load work", a.load_work);
    s.f("audit impact loss", a.impact_loss);
    s.f("audit kinetic", a.kinetic);
    s.f("audit potential", a.potential);
    s.f("audit initial", a.initial);
    s.f("audit residual", a.residual());
    if let Some(r) = tw.measurement_residual() {
        for (name, v) in [
            ("measurement residual crank", r.crank),
            ("measurement residual shaft", r.shaft),
            ("measurement residual rocker", r.rocker),
        ] {
            if let Some(v) = v {
                s.f(name, v);
            }
        }
    }
    for e in tw.events() {
        s.text
            .push(("event", format!("{:?} {:?}->{:?}", e.kind, e.from, e.to)));
        s.f("event time", e.time);
        s.fs("event c", &e.c);
        s.f("event impact loss", e.impact_loss);
        s.f("event mismatch", e.mismatch);
        s.f("event position gap", e.position_gap);
        s.f("event speed gap", e.speed_gap);
    }
    for w in tw.switches() {
        s.f("switch time", w.time);
        s.fs("switch conditioning", &w.conditioning);
        s.f("switch position gap", w.position_gap);
        s.f("switch speed gap", w.speed_gap);
    }
    for (m, v) in tw.candidates() {
        s.text.push(("candidate", format!("{m:?}")));
        s.may_be_inf
            .push(("candidate violation", v.to_f64().to_bits()));
    }
    s.f("conditioning", tw.conditioning());
    s
}

/// Whether the inputs are ones the twin must refuse (SPEC 3: T_r ≥ 0; everything finite).
fn inputs_invalid<T: Real>(i: &Inputs<T>) -> bool {
    let motor_bad = match i.motor {
        MotorInput::Torque(v) => !v.finite(),
        MotorInput::Law(Motor::Constant(v)) => !v.finite(),
        MotorInput::Law(Motor::Asynchronous(a)) => !(a.a.finite() && a.b.finite() && a.c.finite()),
        MotorInput::Law(Motor::User(_)) => false,
    };
    let measured_bad = i.measured.is_some_and(|m| {
        [m.crank, m.shaft, m.rocker]
            .into_iter()
            .flatten()
            .any(|e| e.per_turn == 0 || !e.zero.finite())
    });
    let load_bad = !(i.load.finite() && i.load >= T::zero() && i.load.to_f64() < 1e6);
    motor_bad || measured_bad || load_bad
}

/// A load schedule: the reference 800 N·m, ordinary values, or sudden jumps
/// 0 → 1e6 → 0, with specials at the garbage rate.
fn random_load(g: &mut Gen, step: usize, schedule: usize) -> f64 {
    if g.rng.chance(g.garbage) {
        return g.rng.pick(&[
            f64::NAN,
            f64::INFINITY,
            -1.0,
            -0.0,
            f64::NEG_INFINITY,
            1e300,
            -800.0,
        ]);
    }
    match schedule {
        0 => 800.0,
        1 => g.rng.range(0.0, 2000.0),
        // Sudden changes: 0 for 5 steps, 1e6 for 5, 0 again.
        2 => [0.0, 1e6, 0.0][(step / 5) % 3],
        _ => g.rng.pick(&[0.0, 800.0, 1e6, 5.0, 1e4]),
    }
}

fn random_inputs<T: Real>(
    g: &mut Gen,
    step: usize,
    schedule: usize,
    crank: (f64, f64),
) -> Inputs<T> {
    let motor = match g.rng.below(5) {
        0 => MotorInput::Torque(T::c(g.any(-50.0, 50.0))),
        1 => MotorInput::Torque(g.t(12.0)),
        _ => MotorInput::Law(random_motor(g, 12.0)),
    };
    // The crank's encoder near the crank's angle (`crank.1`, its speed, is not
    // measured by an encoder), its resolution and zero at the garbage rate.
    let counts = (crank.0 / (std::f64::consts::TAU / 4096.0)).floor() as i64;
    let measured = match g.rng.below(3) {
        0 => None,
        1 => Some(Measurement::crank(
            counts + g.rng.below(16) as i64 - 8,
            4096,
            T::c(g.any(-0.1, 0.1)),
        )),
        _ => Some(Measurement::crank(
            counts,
            if g.rng.chance(g.garbage) { 0 } else { 4096 },
            g.t(0.0),
        )),
    };
    Inputs {
        motor,
        load: T::c(random_load(g, step, schedule)),
        measured,
    }
}

/// Steps `tw` up to `steps` times with inputs from `g`, checking the properties.
fn run_twin<T: Real>(
    tw: &mut Twin<T>,
    g: &mut Gen,
    tally: &mut Tally,
    steps: usize,
    per_step_inputs: bool,
) -> Result<(), String> {
    let schedule = g.rng.below(4);
    let mut inputs = random_inputs::<T>(g, 0, schedule, (1.8, 0.0));
    let mut refused_in_row = 0;
    for k in 0..steps {
        let c = tw.link(1);
        if per_step_inputs || g.rng.chance(0.05) {
            inputs = random_inputs(g, k, schedule, (c.theta.to_f64(), c.omega.to_f64()));
        }
        let invalid = inputs_invalid(&inputs);
        let before = twin_snapshot(tw);
        let t0 = tw.time().to_f64();
        match tw.step(&inputs) {
            Ok(()) => {
                if invalid {
                    return Err(format!("step {k}: invalid inputs accepted: {inputs:?}"));
                }
                tally.steps_ok += 1;
                refused_in_row = 0;
                twin_snapshot(tw)
                    .all_finite()
                    .map_err(|e| format!("step {k} ({:?}, {inputs:?}): {e}", tw.mode()))?;
            }
            Err(e) => {
                tally.steps_err += 1;
                tally.error(kind_of("TwinStepError", &e));
                check_twin_error(&e).map_err(|m| format!("step {k}: {m}"))?;
                if let Some(t) = twin_error_time(&e) {
                    // The step attempted: h, or up to CATCH_UP steps for a twin that
                    // spreads its events and is catching up with the clock.
                    let h = tw.h().to_f64()
                        * if tw.settings().spread_events {
                            structomat::ccc::CATCH_UP
                        } else {
                            1.0
                        };
                    // A few ulps of slack: t0 + h rounds in the scalar (one f32 ulp at
                    // 0.31 s is 3e-8 s).
                    let slack = 4.0 * T::EPS.to_f64() * (t0.abs() + h);
                    if !(t >= t0 - slack && t <= t0 + h + slack) {
                        return Err(format!(
                            "step {k}: error time {t} outside [{t0}, +{h}]: {e}"
                        ));
                    }
                }
                twin_snapshot(tw)
                    .same_as(&before)
                    .map_err(|m| format!("step {k} ({e}): {m}"))?;
                refused_in_row += 1;
                if refused_in_row > 3 && !per_step_inputs {
                    // The mechanism is stuck (a singularity): nothing more to learn.
                    return Ok(());
                }
                if !per_step_inputs {
                    // New inputs after a refusal, so that the run goes on.
                    inputs = random_inputs(g, k, schedule, (c.theta.to_f64(), c.omega.to_f64()));
                }
            }
        }
    }
    Ok(())
}

fn random_settings<T: Real>(g: &mut Gen) -> TwinSettings<T> {
    let r = TwinSettings::<f64>::reference(1e-4);
    TwinSettings {
        h: T::c(if g.rng.chance(0.8) {
            let h0 = g.rng.pick(&[1e-4, 5e-5, 1e-3]);
            g.val(h0)
        } else {
            g.any(1e-6, 0.05)
        }),
        clutch: g.rng.chance(0.85),
        crank: g.t(r.crank),
        swing: g.t(r.swing),
        crank_speed: T::c(if g.rng.chance(0.6) {
            g.val(0.0)
        } else {
            g.any(-20.0, 20.0)
        }),
        swing_speed: T::c(if g.rng.chance(0.6) {
            g.val(0.0)
        } else {
            g.any(-5.0, 5.0)
        }),
        switch_below: g.t(r.switch_below),
        energy_tol: T::c(g.val(TwinSettings::<T>::reference(T::c(1e-4)).energy_tol.to_f64())),
        spread_events: g.rng.chance(0.3),
    }
}

/// Whether the parameters break SPEC 3's ranges (finite; lengths, masses and D's place
/// positive; inertias, the oscillating mass, its place and J_s not negative).
fn params_invalid<T: Real>(p: &CccParams<T>) -> bool {
    let f = |x: T| x.to_f64();
    let mut finite = vec![
        p.rocker_d,
        p.mass,
        p.mass_inertia,
        p.mass_at,
        p.shaft_inertia,
    ];
    for v in [p.a, p.f, p.h, p.gravity] {
        finite.extend([v.x, v.y]);
    }
    for b in &p.links {
        finite.extend([b.length, b.mass, b.inertia]);
    }
    finite.iter().any(|x| !x.finite())
        || p.links
            .iter()
            .any(|b| !(f(b.length) > 0.0 && f(b.mass) > 0.0 && f(b.inertia) >= 0.0))
        || !(f(p.rocker_d) > 0.0)
        || [p.mass, p.mass_inertia, p.mass_at, p.shaft_inertia]
            .iter()
            .any(|x| f(*x) < 0.0)
}

/// Whether the settings are out of range: a step that is not positive and finite, a
/// switch threshold outside (0, 1), a tolerance that is not positive and finite, a
/// non-finite initial state.
fn settings_invalid<T: Real>(s: &TwinSettings<T>) -> bool {
    let f = |x: T| x.to_f64();
    let valid = f(s.h) > 0.0
        && s.h.finite()
        && f(s.switch_below) > 0.0
        && f(s.switch_below) < 1.0
        && f(s.energy_tol) > 0.0
        && s.energy_tol.finite()
        && [s.crank, s.swing, s.crank_speed, s.swing_speed]
            .iter()
            .all(|x| x.finite());
    !valid
}

/// Random converter parameters (every one), settings and inputs; set up and stepped.
fn case_twin_geometry<T: Real>(seed: u64, tally: &mut Tally) -> Result<(), String> {
    let mut g = Gen::new(seed);
    let r = CccParams::<f64>::reference();
    let side = |g: &mut Gen, s: Side| {
        if g.rng.chance(0.15) {
            if s == Side::Left {
                Side::Right
            } else {
                Side::Left
            }
        } else {
            s
        }
    };
    let mut links = [Bar {
        length: T::zero(),
        mass: T::zero(),
        inertia: T::zero(),
    }; 8];
    for (l, b) in links.iter_mut().zip(r.links.iter()) {
        *l = Bar {
            length: g.t(b.length),
            mass: g.t(b.mass),
            inertia: g.t(b.inertia),
        };
    }
    let p = CccParams::<T> {
        a: g.v2(r.a.x, r.a.y),
        f: g.v2(r.f.x, r.f.y),
        h: g.v2(r.h.x, r.h.y),
        links,
        rocker_d: g.t(r.rocker_d),
        mass: g.t(r.mass),
        mass_inertia: g.t(r.mass_inertia),
        mass_at: g.t(r.mass_at),
        shaft_inertia: T::c(if g.rng.chance(0.7) {
            g.val(0.0)
        } else {
            g.any(0.0, 0.5)
        }),
        drive: if g.rng.chance(0.7) {
            DriveDirection::Cw
        } else {
            DriveDirection::Ccw
        },
        // The losses stay off: this fuzzes SPEC's ideal machine.
        friction: structomat::ccc::Friction::none(),
        gravity: g.v2(r.gravity.x, r.gravity.y),
        branch_c: side(&mut g, r.branch_c),
        branch_g: side(&mut g, r.branch_g),
        branch_i: side(&mut g, r.branch_i),
    };
    let settings = random_settings::<T>(&mut g);
    if std::env::var("ROBUSTNESS_DEBUG").is_ok() {
        println!("{p:?}\n{settings:?}");
    }
    let schedule = g.rng.below(4);
    let inputs = random_inputs::<T>(&mut g, 0, schedule, (1.8, 0.0));
    // What must be refused, in the order the door checks it.
    let refuse = if params_invalid(&p) {
        Some("Params")
    } else if settings_invalid(&settings) {
        Some("Setting")
    } else if inputs_invalid(&inputs) {
        Some("Start")
    } else {
        None
    };
    match Twin::new(p, settings, inputs) {
        Err(e) => {
            tally.error(kind_of("TwinSetupError", &e));
            let kind = kind_of("TwinSetupError", &e);
            // Parameters finite and in range can still overflow the scalar (a length
            // of 1e200 m squared): a parameter error too, checked before the settings.
            let overflow = matches!(e, TwinSetupError::Params(ModelError::Overflow(_)));
            if let Some(want) = refuse.filter(|_| !overflow) {
                if kind != format!("TwinSetupError::{want}") {
                    return Err(format!("expected a {want} error, got {e}"));
                }
            }
            check_twin_setup_error(&e)
        }
        Ok(mut tw) => {
            if let Some(want) = refuse {
                return Err(format!(
                    "setup accepted what is a {want} error: {p:?} {settings:?} {inputs:?}"
                ));
            }
            tally.accepted += 1;
            tally.setups += 1;
            twin_snapshot(&tw)
                .all_finite()
                .map_err(|e| format!("after setup: {e}"))?;
            let steps = g.rng.below(25);
            run_twin(&mut tw, &mut g, tally, steps, false)
        }
    }
}

/// The reference converter (or the CCW one) from a random initial state, stepped with
/// random inputs each step: garbage inputs, load jumps, NaN measurements.
fn case_twin_inputs<T: Real>(seed: u64, tally: &mut Tally) -> Result<(), String> {
    let mut g = Gen::new(seed);
    let mut p = CccParams::<T>::reference();
    if g.rng.chance(0.3) {
        p.drive = DriveDirection::Ccw;
    }
    if g.rng.chance(0.2) {
        p.shaft_inertia = T::c(g.rng.range(0.0, 0.5));
    }
    let mut s = TwinSettings::<T>::reference(T::c(g.rng.pick(&[1e-4, 1e-4, 5e-4, 2e-3])));
    s.crank = T::c(g.rng.range(0.0, std::f64::consts::TAU));
    s.swing = T::c(90f64.to_radians() + g.rng.range(-0.3, 0.3));
    s.crank_speed = T::c(g.rng.range(-10.0, 10.0));
    s.clutch = g.rng.chance(0.9);
    let start = Inputs {
        motor: MotorInput::Law(Motor::Constant(T::c(12.0))),
        load: T::c(800.0),
        measured: None,
    };
    let mut tw = match Twin::new(p, s, start) {
        Err(e) => {
            tally.error(kind_of("TwinSetupError", &e));
            return check_twin_setup_error(&e);
        }
        Ok(t) => t,
    };
    tally.accepted += 1;
    tally.setups += 1;
    twin_snapshot(&tw)
        .all_finite()
        .map_err(|e| format!("after setup: {e}"))?;
    let steps = 10 + g.rng.below(30);
    run_twin(&mut tw, &mut g, tally, steps, true)
}

// ---------------------------------------------------------------------------------------
// The suites
// ---------------------------------------------------------------------------------------

/// Cases per suite in the default (debug) run and in the long (ignored) run.
struct Counts {
    description: u64,
    mechanism: u64,
    twin_geometry: u64,
    twin_inputs: u64,
}

/// Sized for CI's debug build on 2 cores: about 30 s for the three suites together.
const DEFAULT: Counts = Counts {
    description: 3000,
    mechanism: 1500,
    twin_geometry: 400,
    twin_inputs: 100,
};

/// A few minutes in release.
const LONG: Counts = Counts {
    description: 500_000,
    mechanism: 300_000,
    twin_geometry: 60_000,
    twin_inputs: 10_000,
};

fn builder_suites(n: &Counts, seed: u64) -> Tally {
    let mut t = run_suite(
        "descriptions f64",
        seed,
        n.description,
        case_random_description::<f64>,
    );
    t.merge(&run_suite(
        "descriptions f32",
        seed ^ 1,
        n.description / 3,
        case_random_description::<f32>,
    ));
    t.merge(&run_suite(
        "mechanisms f64",
        seed ^ 2,
        n.mechanism,
        case_mechanism::<f64>,
    ));
    t.merge(&run_suite(
        "mechanisms f32",
        seed ^ 3,
        n.mechanism / 3,
        case_mechanism::<f32>,
    ));
    t
}

fn twin_geometry_suites(n: &Counts, seed: u64) -> Tally {
    let mut t = run_suite(
        "converter geometries f64",
        seed,
        n.twin_geometry,
        case_twin_geometry::<f64>,
    );
    t.merge(&run_suite(
        "converter geometries f32",
        seed ^ 1,
        n.twin_geometry / 3,
        case_twin_geometry::<f32>,
    ));
    t
}

fn twin_input_suites(n: &Counts, seed: u64) -> Tally {
    let mut t = run_suite(
        "converter inputs f64",
        seed,
        n.twin_inputs,
        case_twin_inputs::<f64>,
    );
    t.merge(&run_suite(
        "converter inputs f32",
        seed ^ 1,
        n.twin_inputs / 2,
        case_twin_inputs::<f32>,
    ));
    t
}

#[test]
fn model_builder_and_simulation_survive_random_descriptions() {
    let t = builder_suites(&DEFAULT, 0x5EED_0001);
    t.report("builder total", 0.0);
    // The failures first: a replayed seed (ROBUSTNESS_SEED) may reach no step.
    assert_no_failures(&t);
    assert!(
        t.setups > 0 && t.steps_ok > 0,
        "no case reached the step path"
    );
}

#[test]
fn twin_survives_random_geometries() {
    let t = twin_geometry_suites(&DEFAULT, 0x5EED_0002);
    t.report("converter geometries total", 0.0);
    assert!(
        t.setups > 0 && t.steps_ok > 0,
        "no case reached the step path"
    );
    assert_no_failures(&t);
}

#[test]
fn twin_survives_random_inputs_each_step() {
    let t = twin_input_suites(&DEFAULT, 0x5EED_0003);
    t.report("converter inputs total", 0.0);
    assert!(
        t.steps_ok > 0 && t.steps_err > 0,
        "no step succeeded, or none was refused"
    );
    assert_no_failures(&t);
}

/// Many more cases (other seeds): `cargo test --release --test robustness -- --ignored`.
#[test]
#[ignore]
fn long_run_all_suites() {
    let start = Instant::now();
    let mut t = builder_suites(&LONG, 0x1_0000_5EED);
    t.merge(&twin_geometry_suites(&LONG, 0x2_0000_5EED));
    t.merge(&twin_input_suites(&LONG, 0x3_0000_5EED));
    t.report("long run total", start.elapsed().as_secs_f64());
    assert_no_failures(&t);
}

// ---------------------------------------------------------------------------------------
// Regressions: one test per defect the suites found (seed in the name's doc)
// ---------------------------------------------------------------------------------------

/// Found by `mechanisms f64` (seeds 0xa6e3552d662bbaad, 0x04343d5b80e8d76d, ...): a
/// group's angle offset, guide angle or guess could be NaN or infinite, and a link
/// point at 1e300 m made a dyad's arm length infinite; the builder accepted them and the
/// model held non-finite constants (checked by `check_model` in every case).
#[test]
fn regression_group_with_non_finite_values_is_refused() {
    // A crank (R) and a dyad RRR of links 2 and 3 on the crank's end and a ground point.
    let build = |offset: f64, guess: f64, b_joint: Vec2<f64>| {
        let mut b = ModelBuilder::<f64>::new();
        let a = b.ground_point(0.0, 0.0).unwrap();
        let c = b.ground_point(2.0, 0.0).unwrap();
        let l1 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
        let l2 = b.link(Link::bar(1.5, 1.0, 0.1, 0.5)).unwrap();
        let mut bar = Link::bar(1.5, 1.0, 0.1, 0.5);
        let joint = bar.add_point(b_joint).unwrap();
        let l3 = b.link(bar).unwrap();
        b.group(&MotorR {
            link: l1,
            pivot: a,
            link_point: 0,
            coord: 0,
            offset,
        })
        .unwrap();
        b.group(&DyadRrr {
            a: l2,
            b: l3,
            pole_a: PointRef { body: l1, point: 1 },
            a_at_pole: 0,
            pole_b: c,
            b_at_pole: 0,
            a_joint: 1,
            b_joint: joint,
            guess: [0.5, guess],
        })
        .unwrap();
        b.build()
    };
    let e = build(f64::NAN, 2.0, Vec2::new(1.5, 0.0)).unwrap_err();
    assert!(
        matches!(e, ModelError::GroupNonFinite { group: 0, .. }),
        "{e:?}"
    );
    assert_eq!(e.to_string(), "group 0 (R): an angle offset is not finite");
    let e = build(0.0, f64::INFINITY, Vec2::new(1.5, 0.0)).unwrap_err();
    assert_eq!(e.to_string(), "group 1 (RRR): a guess is not finite");
    // A finite point whose squared length overflows (the RRR's arm length would be
    // infinite) is named by the size check, before the groups are looked at.
    let e = build(0.0, 2.0, Vec2::new(1e300, 1e300)).unwrap_err();
    assert_eq!(e, ModelError::Overflow("the mechanism's size squared"));
    build(0.0, 2.0, Vec2::new(1.5, 0.0)).unwrap();
}

/// Found by `mechanisms f64` seed 0xb2ad83eb4794bbda: the slider-crank with its pivot
/// at y = f64::MAX was accepted (every value finite), and its potential energy was
/// infinite (Newton's tolerance, 64 ulps of the size, was 2.6e294 m).
#[test]
fn regression_mechanism_whose_size_overflows_is_refused() {
    let build = |y: f64, mass: f64| {
        let mut b = ModelBuilder::<f64>::new();
        let a = b.ground_point(0.0, y).unwrap();
        let l = b.link(Link::bar(1.0, mass, 0.1, 0.5)).unwrap();
        b.group(&MotorR {
            link: l,
            pivot: a,
            link_point: 0,
            coord: 0,
            offset: 0.0,
        })
        .unwrap();
        b.build()
    };
    let e = build(f64::MAX, 1.0).unwrap_err();
    assert_eq!(e, ModelError::Overflow("the mechanism's size squared"));
    assert!(e.to_string().contains("overflows"), "{e}");
    // 1e150 m squares to 4e300: finite, but its weight times its size is not.
    let e = build(1e150, 1e160).unwrap_err();
    assert!(matches!(e, ModelError::Overflow(_)), "{e:?}");
    // At sane sizes nothing changes.
    build(1e3, 1e3).unwrap();
}

/// Found by `converter inputs f64` seed 0x7588ff52ced1f484 (and 70 more): a step that
/// failed had already cleared the last good step's events, coordinate switches and mode
/// candidates (or filled them with the failed attempt's).
#[test]
fn regression_failed_twin_step_keeps_its_event_log() {
    let good = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: 800.0,
        measured: None,
    };
    let mut tw = Twin::new(
        CccParams::<f64>::reference(),
        TwinSettings::reference(1e-4),
        good,
    )
    .unwrap();
    assert!(!tw.events().is_empty(), "the setup logs its start event");
    let before = twin_snapshot(&tw);
    // The law's torque goes NaN inside the step: refused during evaluation.
    let bad = Inputs {
        motor: MotorInput::Law(Motor::User(|_, _, _| f64::NAN)),
        ..good
    };
    let e = tw.step(&bad).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    twin_snapshot(&tw).same_as(&before).unwrap();
    assert_eq!(tw.events().len(), 1);
    // And the twin steps on from there.
    tw.step(&good).unwrap();
    assert_eq!(tw.steps(), 1);
}

/// Found by reading `Twin::new` against the converter suites' settings oracle: a NaN
/// energy tolerance was accepted (every step then failed as "breaks the energy
/// balance"), and a NaN initial crank angle was reported as a geometry that cannot
/// assemble.
#[test]
fn regression_twin_settings_are_named() {
    let inputs = Inputs {
        motor: MotorInput::Torque(12.0),
        load: 800.0,
        measured: None,
    };
    let p = CccParams::<f64>::reference();
    let msg = |s: TwinSettings<f64>| Twin::new(p, s, inputs).unwrap_err().to_string();
    let mut s = TwinSettings::reference(1e-4);
    s.energy_tol = f64::NAN;
    assert!(msg(s).contains("energy_tol"), "{}", msg(s));
    let mut s = TwinSettings::reference(1e-4);
    s.crank = f64::NAN;
    assert!(msg(s).contains("crank angle"), "{}", msg(s));
    let law = Inputs {
        motor: MotorInput::Law(Motor::Constant(f64::INFINITY)),
        ..inputs
    };
    let e = Twin::new(p, TwinSettings::reference(1e-4), law).unwrap_err();
    assert!(e.to_string().contains("motor law"), "{e}");
}

/// A structure (no degree of freedom) steps at any h: with h = f64::MAX the second step's
/// time n·h overflowed to infinity and was committed.
#[test]
fn regression_time_overflow_is_an_error() {
    let mut b = ModelBuilder::<f64>::new();
    let a = b.ground_point(0.0, 0.0).unwrap();
    let c = b.ground_point(1.5, 0.0).unwrap();
    let l1 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    let l2 = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
    b.group(&DyadRrr {
        a: l1,
        b: l2,
        pole_a: a,
        a_at_pole: 0,
        pole_b: c,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [0.8, 2.3],
    })
    .unwrap();
    let model = b.build().unwrap();
    assert_eq!(model.dof(), 0);
    let mut sim = Simulation::new(model, &[], &[], f64::MAX).unwrap();
    sim.step().unwrap();
    assert_eq!(sim.time(), f64::MAX);
    let before = sim_snapshot(&sim);
    let e = sim.step().unwrap_err();
    assert!(
        matches!(e, StepError::NonFinite { what, .. } if what.contains("n·h")),
        "{e:?}"
    );
    assert!(e.time().is_finite());
    sim_snapshot(&sim).same_as(&before).unwrap();
}

/// Found probing the twin with torques near f64::MAX: a torque of 1e308 N·m gave
/// accelerations that overflow, and the error blamed "a singular configuration" (the
/// mass matrix had passed its definiteness test).
#[test]
fn regression_overflowing_accelerations_are_not_called_singular() {
    let inputs = Inputs {
        motor: MotorInput::Torque(12.0),
        load: 800.0,
        measured: None,
    };
    let mut tw = Twin::new(
        CccParams::<f64>::reference(),
        TwinSettings::reference(1e-4),
        inputs,
    )
    .unwrap();
    let before = twin_snapshot(&tw);
    let huge = Inputs {
        motor: MotorInput::Torque(1e308),
        ..inputs
    };
    let e = tw.step(&huge).unwrap_err();
    assert!(
        matches!(e, TwinStepError::Step(StepError::NonFinite { what, .. }) if what.contains("acceleration")),
        "{e}"
    );
    twin_snapshot(&tw).same_as(&before).unwrap();
    let model = structomat::mechanisms::five_bar_model(2.5, Some(Motor::Constant(1e308))).unwrap();
    let e = Simulation::new(model, &[1.4, 1.2], &[0.0, 0.0], 1e-3)
        .err()
        .unwrap();
    assert!(e.to_string().contains("acceleration"), "{e}");
}

/// Found by the long run (`mechanisms f64` seed 0xc81be1a03a4c1b60 and 5 more): a link
/// inertia of f64::MAX is finite and the dynamics run (q̈ = τ / I ≈ 0), but the kinetic
/// energy `½Iω²` overflowed at any speed above 1.4 rad/s; setup and steps accepted it.
#[test]
fn regression_energy_overflow_is_refused() {
    let crank = |inertia: f64, torque: f64| {
        let mut b = ModelBuilder::<f64>::new();
        b.gravity(Vec2::zeros());
        let a = b.ground_point(0.0, 0.0).unwrap();
        let l = b.link(Link::bar(1.0, 1.0, inertia, 0.5)).unwrap();
        b.group(&MotorR {
            link: l,
            pivot: a,
            link_point: 0,
            coord: 0,
            offset: 0.0,
        })
        .unwrap();
        b.drive(0, Motor::Constant(torque)).unwrap();
        b.build().unwrap()
    };
    let e = Simulation::new(crank(f64::MAX, 0.0), &[0.0], &[2.0], 1e-2)
        .err()
        .unwrap();
    assert!(e.to_string().contains("kinetic or potential energy"), "{e}");
    // Spun up by 1e308 N·m against 1e307 kg·m² (10 rad/s²): the motor's power τω, whose
    // work the energy balance meters, passes f64::MAX at ω = 1.80 rad/s, after 0.18 s
    // (before the product Iω² would, at 4.24 rad/s). That step is refused and the state
    // kept: the last good one is at 0.16 s, 1.6 rad/s.
    let mut sim = Simulation::new(crank(1e307, 1e308), &[0.0], &[0.0], 1e-2).unwrap();
    let e = loop {
        let before = sim_snapshot(&sim);
        match sim.step() {
            Ok(()) => sim_snapshot(&sim).all_finite().unwrap(),
            Err(e) => {
                sim_snapshot(&sim).same_as(&before).unwrap();
                break e;
            }
        }
        assert!(sim.time() < 1.0, "the energy never overflowed");
    };
    assert!(e.to_string().contains("work of the motors"), "{e}");
    assert!((sim.qd()[0] - 1.6).abs() < 0.15, "{}", sim.qd()[0]);
    // The twin: a crank of 1e307 kg·m² started at 10 rad/s.
    let mut p = CccParams::<f64>::reference();
    p.links[0].inertia = 1e307;
    let mut s = TwinSettings::reference(1e-4);
    s.crank_speed = 10.0;
    let inputs = Inputs {
        motor: MotorInput::Torque(0.0),
        load: 800.0,
        measured: None,
    };
    let e = Twin::new(p, s, inputs).unwrap_err();
    assert!(e.to_string().contains("energy audit"), "{e}");
}

/// Found reading `CccParams::validate` against the geometry suite's oracle: a zero link
/// mass was reported as "link mass or inertia must not be negative" (0 is not negative,
/// and which link?), and lengths of 1e200 m passed and then failed as "cannot assemble"
/// (their squares overflow).
#[test]
fn regression_converter_parameters_are_named() {
    let mut p = CccParams::<f64>::reference();
    p.links[2].mass = 0.0;
    assert_eq!(
        p.validate().unwrap_err().to_string(),
        "link 3 (rocker) mass must be positive"
    );
    let mut p = CccParams::<f64>::reference();
    p.links[7].inertia = -1.0;
    assert_eq!(
        p.validate().unwrap_err().to_string(),
        "link 8 (lever 8) inertia must not be negative"
    );
    let mut p = CccParams::<f64>::reference();
    p.links[1].length = 1e200;
    assert!(matches!(p.validate(), Err(ModelError::Overflow(_))));
    // Named once as the converter's through the twin.
    let inputs = Inputs {
        motor: MotorInput::Torque(12.0),
        load: 800.0,
        measured: None,
    };
    let e = Twin::new(p, TwinSettings::reference(1e-4), inputs).unwrap_err();
    assert_eq!(
        e.to_string(),
        "converter: its size squared overflows the scalar type"
    );
    let mut p = CccParams::<f64>::reference();
    p.h.x = f64::NAN;
    assert_eq!(
        p.validate().unwrap_err().to_string(),
        "output shaft H is not finite"
    );
    CccParams::<f64>::reference().validate().unwrap();
    CccParams::<f32>::reference().validate().unwrap();
}

/// Found by the long run (`mechanisms f64` seeds 0x2fc077bdd9854ba3, 0xa021c6dc52df95fc
/// and 2 more): values finite each whose combination overflows a link's state while q,
/// q̇, q̈ stay finite: an angle offset of -1e300 rad plus q0 = -f64::MAX gave a link
/// angle of -inf; an asynchronous motor with c = -f64::MAX gave q̈ ≈ 1e308, whose
/// `V q̈` (the links' accelerations) overflowed. Both setups were accepted.
#[test]
fn regression_link_state_overflow_is_refused() {
    let crank = |offset: f64, motor: Motor<f64>| {
        let mut b = ModelBuilder::<f64>::new();
        let a = b.ground_point(0.0, 0.0).unwrap();
        let l = b.link(Link::bar(1.0, 1.0, 0.1, 0.5)).unwrap();
        b.group(&MotorR {
            link: l,
            pivot: a,
            link_point: 0,
            coord: 0,
            offset,
        })
        .unwrap();
        b.drive(0, motor).unwrap();
        b.build().unwrap()
    };
    let e = Simulation::new(
        crank(-1e300, Motor::Constant(0.0)),
        &[f64::MIN],
        &[0.0],
        1e-3,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("a link's angle or position"), "{e}");
    // The found case: the slider of T+RRR (tests/groups.rs) pushed by an asynchronous
    // motor with c = f64::MIN at q̇ = 0.719 m/s: F = -0.52 f64::MAX, q̈ finite, and the
    // links' accelerations V q̈ overflow.
    let th = 30f64.to_radians();
    let mut b = ModelBuilder::<f64>::new();
    let g0 = b.ground_point(0.0, 0.0).unwrap();
    let d = b.ground_point(-0.4, -0.6).unwrap();
    let mut sl = Link::block(0.3, 1.0e-3);
    let pin = sl.add_point(Vec2::new(0.0, 0.02)).unwrap();
    let slider = b.link(sl).unwrap();
    let l2 = b.link(Link::bar(0.30, 0.8, 0.006, 0.15)).unwrap();
    let l3 = b.link(Link::bar(0.40, 0.7, 0.0093, 0.2)).unwrap();
    b.group(&MotorT {
        link: slider,
        guide: g0,
        guide_angle: th,
        link_point: 0,
        link_angle: th,
        coord: 0,
    })
    .unwrap();
    b.group(&DyadRrr {
        a: l2,
        b: l3,
        pole_a: PointRef {
            body: slider,
            point: pin,
        },
        a_at_pole: 0,
        pole_b: d,
        b_at_pole: 0,
        a_joint: 1,
        b_joint: 1,
        guess: [-0.4, 0.78],
    })
    .unwrap();
    let motor = Motor::Asynchronous(Asynchronous {
        a: 15.0,
        b: -1.0,
        c: f64::MIN,
    });
    b.drive(0, motor).unwrap();
    let e = Simulation::new(b.build().unwrap(), &[-0.44], &[0.7189504127191539], 1e-3)
        .err()
        .unwrap();
    assert!(e.to_string().contains("a link's acceleration"), "{e}");
}
