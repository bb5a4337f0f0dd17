//! Shared test oracles for the top-level tests and benches: tolerant comparison,
//! 4th-order central differences (thesis eq. 5.12-5.13), the stacked pose `P` and
//! SPEC 3's law on the converter's free levers.

use structomat::ccc::{Clutch, Mode, Twin};
use structomat::config::POSE_ROWS;
use structomat::model::Model;
use structomat::workspace::Workspace;

/// `|a - b| <= atol + rtol * max(|a|, |b|)`.
pub fn isclose(a: f64, b: f64, rtol: f64, atol: f64) -> bool {
    (a - b).abs() <= atol + rtol * a.abs().max(b.abs())
}

/// Asserts [`isclose`] with a message naming `what`.
#[track_caller]
pub fn assert_close(a: f64, b: f64, rtol: f64, atol: f64, what: &str) {
    assert!(
        isclose(a, b, rtol, atol),
        "{what}: {a:.15e} vs {b:.15e} (diff {:.3e})",
        (a - b).abs()
    );
}

/// 4th-order central difference of `f` at `x` with step `h` (thesis eq. 5.12):
/// `(f(x-2h) - 8 f(x-h) + 8 f(x+h) - f(x+2h)) / 12h`, componentwise.
pub fn central_diff4(f: &mut dyn FnMut(f64) -> Vec<f64>, x: f64, h: f64) -> Vec<f64> {
    let (m2, m1, p1, p2) = (f(x - 2.0 * h), f(x - h), f(x + h), f(x + 2.0 * h));
    (0..m2.len())
        .map(|k| (m2[k] - 8.0 * m1[k] + 8.0 * p1[k] - p2[k]) / (12.0 * h))
        .collect()
}

/// 4th-order central second difference (thesis eq. 5.13):
/// `(-f(x-2h) + 16 f(x-h) - 30 f(x) + 16 f(x+h) - f(x+2h)) / 12h²`.
pub fn central_second_diff4(f: &mut dyn FnMut(f64) -> Vec<f64>, x: f64, h: f64) -> Vec<f64> {
    let (m2, m1, z, p1, p2) = (f(x - 2.0 * h), f(x - h), f(x), f(x + h), f(x + 2.0 * h));
    (0..m2.len())
        .map(|k| (-m2[k] + 16.0 * m1[k] - 30.0 * z[k] + 16.0 * p1[k] - p2[k]) / (12.0 * h * h))
        .collect()
}

/// The stacked pose `P` (`x_G, y_G, θ` per moving link) of the workspace's last
/// position pass. Angles are unwrapped against `reference` when given (so that finite
/// differences do not straddle ±π).
pub fn pose(model: &Model<f64>, ws: &Workspace<f64>, reference: Option<&[f64]>) -> Vec<f64> {
    let mut p = Vec::with_capacity(3 * model.n_links());
    for b in 1..=model.n_links() as u8 {
        let g = ws.cog(model, b);
        let mut th = ws.body[b as usize].theta;
        if let Some(r) = reference {
            let r = r[3 * (b as usize - 1) + 2];
            th = r + (th - r + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
        }
        p.extend_from_slice(&[g.x, g.y, th]);
    }
    assert!(p.len() <= POSE_ROWS);
    p
}

/// Unwraps angle `a` to the branch nearest `reference`.
pub fn unwrap_near(a: f64, reference: f64) -> f64 {
    reference + (a - reference + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI
}

/// SPEC 3: a free lever does not move past the shaft in the drive direction (it would
/// catch it): `d·(ω_k − ω_s)` within 1e-6 of the largest link speed (at least 1 rad/s).
pub fn check_free_levers(twin: &Twin<f64>) {
    if twin.mode() == Mode::Free {
        return; // no diode: the levers are not tied to the shaft
    }
    let d: f64 = twin.params().drive.sign();
    let scale = (1..=8).fold(1.0_f64, |m, p| m.max(twin.link(p).omega.abs()));
    let shaft = twin.shaft_speed();
    for (lever, clutch) in [6usize, 8].into_iter().zip(twin.mode().clutches()) {
        if clutch == Clutch::Free {
            let past = d * (twin.link(lever).omega - shaft);
            assert!(
                past <= 1e-6 * scale,
                "t = {}: free lever {lever} {past:e} rad/s past the shaft in {}",
                twin.time(),
                twin.mode()
            );
        }
    }
}

mod rng;
pub use rng::Rng;
