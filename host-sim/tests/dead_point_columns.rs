//! Issue 17, item 5: while an alternative coordinate drives a mechanism past its
//! driver's dead point, the CSV's columns keep the run's first coordinates and joints
//! with their physical values (no NaN). Oracles: central finite differences of the
//! written q̇ (for q̈), the motor's law at the written q̇, the step-to-step change of a
//! reaction on either side of a switch, and the virtual-power balance at the driven
//! joint (the driving torque the motion needs there is the motor's).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

const PISTON: &str = include_str!("../mechanisms/piston-slider-crank.toml");
const TRIAD: &str = include_str!("../mechanisms/crank-triad.toml");

/// The CSV: header and rows.
struct Csv {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn col(&self, name: &str) -> usize {
        self.names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.names))
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dead-point-columns-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Runs `text` (a mechanism file, written to `dir`) for its own t_end; returns the
/// CSV and the switch times read off the summary (`t = … s: A -> B`).
fn run(text: &str, dir: &Path) -> (Csv, Vec<f64>) {
    let file = dir.join("m.toml");
    std::fs::write(&file, text).expect("write");
    let out = dir.join("m.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .expect("host-sim");
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let switches: Vec<f64> = stdout
        .lines()
        .filter(|l| l.contains(" -> "))
        .filter_map(|l| {
            let t = l.trim().strip_prefix("t = ")?;
            t.split(' ').next()?.parse().ok()
        })
        .collect();
    let text = std::fs::read_to_string(&out).expect("csv");
    let (names, rows) = common::numeric_csv(&text);
    (Csv { names, rows }, switches)
}

/// Whether the alternative drives at `t`: between a switch away (odd switches count
/// from the first: away, back, away, …) and the switch back.
fn alternative_drives(t: f64, switches: &[f64]) -> bool {
    switches.iter().filter(|s| **s <= t + 1e-12).count() % 2 == 1
}

/// The checks common to both mechanisms; `motor_law` the torque (force) of the motor
/// at the first coordinate's rate.
fn check(csv: &Csv, switches: &[f64], motor_law: impl Fn(f64) -> f64, reaction: &str) {
    // A regression bound (as measured, at least these): the run passes dead points.
    assert!(switches.len() >= 4, "switches at {switches:?}");
    let (t, qd, qdd) = (csv.col("t"), csv.col("qd1"), csv.col("qdd1"));
    let (motor, drive, r) = (
        csv.col("motor_torque1"),
        csv.col("drive_torque1"),
        csv.col(reaction),
    );
    let h = csv.rows[1][t] - csv.rows[0][t];
    let mut driven = 0;
    for row in &csv.rows {
        // No NaN anywhere, while an alternative drives too.
        assert!(row.iter().all(|v| v.is_finite()), "t = {}: {row:?}", row[t]);
        if alternative_drives(row[t], switches) {
            driven += 1;
        }
        // The motor's law at the written speed (the same joint, the same law in
        // either choice of coordinates), to rounding.
        let law = motor_law(row[qd]);
        assert!(
            (row[motor] - law).abs() <= 1e-12 * (1.0 + law.abs()),
            "t = {}",
            row[t]
        );
    }
    // The torque the first driver needs for the motion is the motor's own (the motion
    // is solved with the motor as the only drive): their virtual powers at the driven
    // joint agree. Compared as powers, `τ q̇`: near the first coordinate's dead point
    // q̇ → 0 and its torque is the power over q̇, the rounding of the accelerations
    // amplified by the first assembly's conditioning (at the dead point itself it is
    // not defined); 1e-5 of the run's largest motor power.
    let power = csv
        .rows
        .iter()
        .map(|row| (row[motor] * row[qd]).abs())
        .fold(0.0, f64::max);
    for row in &csv.rows {
        let gap = ((row[drive] - row[motor]) * row[qd]).abs();
        assert!(
            gap <= 1e-5 * power,
            "t = {}: drive {} motor {} at q̇ {}",
            row[t],
            row[drive],
            row[motor],
            row[qd]
        );
    }
    // A regression bound (as measured, more): the alternatives drive for a while.
    assert!(driven > 20, "{driven} rows with an alternative driving");
    // q̈ against the central difference of q̇: the difference's error is h²/6 q̇''' and
    // q̇''' is bounded by the third difference of q̇ over h³ nearby (all from the q̇
    // column, not q̈); the bound is 4 times that, plus rounding 1e-12/h.
    let n = csv.rows.len();
    for k in 2..n - 2 {
        let v = |i: usize| csv.rows[i][qd];
        let fd = (v(k + 1) - v(k - 1)) / (2.0 * h);
        let third =
            ((v(k + 2) - 2.0 * v(k + 1) + 2.0 * v(k - 1) - v(k - 2)) / (2.0 * h.powi(3))).abs();
        let third =
            third.max(((v(k + 1) - 3.0 * v(k) + 3.0 * v(k - 1) - v(k - 2)) / h.powi(3)).abs());
        let bound = 4.0 * h * h / 6.0 * third + 1e-12 / h + 1e-9 * csv.rows[k][qdd].abs();
        assert!(
            (csv.rows[k][qdd] - fd).abs() <= bound,
            "t = {}: qdd {} fd {fd} bound {bound:e}",
            csv.rows[k][t],
            csv.rows[k][qdd]
        );
    }
    // A reaction across each switch: the jump over the switch's step is within what
    // the steps on either side show (a smooth quantity changes by R' h per step, R'
    // changing by R'' h between steps: 2 times the largest neighbouring change, plus
    // the second difference's share).
    for s in switches {
        let Some(k) = csv.rows.iter().position(|row| (row[t] - s).abs() < h / 2.0) else {
            continue;
        };
        if k < 3 || k + 3 > n {
            continue;
        }
        let d = |i: usize| (csv.rows[i + 1][r] - csv.rows[i][r]).abs();
        let jump = d(k - 1).max(d(k));
        let near = d(k - 3)
            .max(d(k - 2))
            .max(d(k + 1))
            .max(d(k + 2).min(f64::MAX));
        assert!(
            jump <= 2.0 * near + 1e-9 * csv.rows[k][r].abs(),
            "{reaction} at t = {s}: jump {jump:e}, neighbouring steps {near:e}"
        );
    }
}

/// The piston-driven slider-crank passes its crank's dead centres: the piston's
/// acceleration, its force, the joints' reactions in its own columns throughout.
#[test]
fn piston_columns_are_physical_while_the_crank_drives() {
    let dir = temp_dir("piston");
    let (csv, switches) = run(PISTON, &dir);
    check(&csv, &switches, |_| 5.0, "R1_2");
    let _ = std::fs::remove_dir_all(dir);
}

/// The six-bar's rocker passes its triad's dead points, under a motor whose torque
/// falls with its speed, `T = 0.2 - 0.05 ω` N·m (a law that reads the joint's speed).
#[test]
fn triad_columns_are_physical_while_the_flywheel_drives() {
    let dir = temp_dir("triad");
    let text = TRIAD.replace(
        "motor = 0.2\n",
        "motor = { type = \"polynomial\", a = 0.2, b = -0.05, c = 0.0 }\n",
    );
    assert_ne!(text, TRIAD);
    let (csv, switches) = run(&text, &dir);
    check(&csv, &switches, |w| 0.2 - 0.05 * w, "R3_0");
    let _ = std::fs::remove_dir_all(dir);
}
