use structomat::ccc::*;
use structomat::motor::Motor;

struct L;
impl log::Log for L {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        if std::env::var("LOG").is_ok() {
            eprintln!("{}: {}", r.level(), r.args());
        }
    }
    fn flush(&self) {}
}
static LOGGER: L = L;

#[test]
#[ignore]
fn probe_s2() {
    let _ = log::set_logger(&LOGGER).map(|()| log::set_max_level(log::LevelFilter::Debug));
    let h = std::env::var("H")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1e-4);
    let t_end: f64 = std::env::var("T")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    let clutch = std::env::var("FREE").is_err();
    let mut p = CccParams::<f64>::reference();
    if std::env::var("CCW").is_ok() {
        p.drive = DriveDirection::Ccw;
    }
    let mut s = TwinSettings::reference(h);
    s.clutch = clutch;
    let inputs = Inputs {
        motor: MotorInput::Law(Motor::Constant(12.0)),
        load: if clutch { 800.0 } else { 0.0 },
        measured: None,
    };
    let mut twin = Twin::new(p, s, inputs).unwrap();
    for e in twin.events() {
        println!("{:?}", e);
    }
    println!(
        "start mode {} coords {} c {:?}",
        twin.mode(),
        twin.coordinates(),
        twin.clutch_torques()
    );
    let n = (t_end / h).round() as u64;
    let mut counts = std::collections::BTreeMap::new();
    for k in 0..n {
        match twin.step(&inputs) {
            Ok(()) => {}
            Err(e) => {
                println!("ERROR at step {k}: {e} cands {:?}", twin.candidates());
                break;
            }
        }
        for e in twin.events() {
            *counts.entry(e.kind.name()).or_insert(0) += 1;
            if counts.values().sum::<i32>() < 60 {
                println!(
                    "t={:.6} {} {} -> {} c={:?} loss={:.3e} mism={:.2e} cands {:?}",
                    e.time,
                    e.kind.name(),
                    e.from,
                    e.to,
                    e.c,
                    e.impact_loss,
                    e.mismatch,
                    twin.candidates()
                );
            }
        }
        for s in twin.switches() {
            println!(
                "  switch t={:.6} {} {} -> {} cond {:?}",
                s.time, s.mode, s.from, s.to, s.conditioning
            );
        }
        let verbose_from: f64 = std::env::var("VF")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1e9);
        if k % (n / 10).max(1) == 0 || (twin.time() >= verbose_from && k % 5 == 0) {
            let a = twin.audit();
            println!("t={:.5} mode={} qd={:?} links1/4/6/8 w={:.3} {:.3} {:.3} {:.3} q={:?} shaft={:.4} c={:?} Wm={:.4} res={:.3e} cond={:.3}", twin.time(), twin.mode(), twin.qd(), twin.link(1).omega, twin.link(4).omega, twin.link(6).omega, twin.link(8).omega, twin.q(), twin.shaft_speed(), twin.clutch_torques(), a.motor_work, a.residual(), twin.conditioning());
        }
    }
    let a = twin.audit();
    println!(
        "end t={} mode={} audit {:?} residual {:.3e} rel {:.3e}",
        twin.time(),
        twin.mode(),
        a,
        a.residual(),
        a.residual() / a.motor_work
    );
    println!("{counts:?}");
}
