//! Every printed figure right (issue 17, items 3, 7, 8 and the step checks of item 1):
//! the summary's time means and balances, the last state in the CSV, the end time of a
//! run whose `t_end` is not a multiple of `h`, `h <= t_end`, the motors' checks, loads
//! too large for the tolerances, numbers with exponents and sentences that read.

mod common;

use common::{number_after, numeric_csv, run, TempDir};

/// The column `name` of a parsed CSV.
fn col(names: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no column {name} in {names:?}"));
    rows.iter().map(|r| r[k]).collect()
}

/// `host-sim run ARGS --out DIR/run.csv`: exit code, summary (stdout), stderr, CSV text.
fn run_to_csv(dir: &TempDir, args: &[&str]) -> (u8, String, String, String) {
    let out = dir.join("run.csv");
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", &out]);
    let (code, summary, err) = run(&all);
    let csv = std::fs::read_to_string(&out).unwrap_or_default();
    (code, summary, err, csv)
}

/// The slider-crank's printed mean speed is the time mean over the second half of the
/// run. Oracle: the trapezoidal rule over every step of `qd1` in the CSV (error
/// `O(h²)`, ~1e-6 rad/s here), and `(q1(T) - q1(t0)) / (T - t0)` from the CSV's own
/// coordinates. The sample mean printed before (7.339558 rad/s) is 6e-4 rad/s off.
#[test]
fn mean_speed_is_the_time_mean() {
    let dir = TempDir::new("figures-mean");
    let (code, summary, err, csv) = run_to_csv(&dir, &["slider-crank"]);
    assert_eq!(code, 0, "{err}");
    let (names, rows) = numeric_csv(&csv);
    let (t, q, qd) = (
        col(&names, &rows, "t"),
        col(&names, &rows, "q1"),
        col(&names, &rows, "qd1"),
    );
    let printed = number_after(&summary, "] s: ");
    let from = number_after(&summary, "over t in [");
    let k0 = t
        .iter()
        .position(|x| (x - from).abs() < 1e-9)
        .expect("t0 in the CSV");
    let n = t.len() - 1;
    let span = t[n] - t[k0];
    let trapezoid: f64 = (k0..n)
        .map(|k| 0.5 * (t[k + 1] - t[k]) * (qd[k] + qd[k + 1]))
        .sum::<f64>()
        / span;
    let exact = (q[n] - q[k0]) / span;
    assert!((printed - exact).abs() < 1e-6, "{printed} vs {exact}");
    assert!(
        (printed - trapezoid).abs() < 2e-5,
        "{printed} vs {trapezoid}"
    );
    let samples = qd[k0..].iter().sum::<f64>() / (n - k0 + 1) as f64;
    assert!(
        (samples - trapezoid).abs() > 1e-4,
        "the test tells the sample mean {samples} from the time mean {trapezoid}"
    );
}

/// `h > t_end` is refused before anything runs, naming both (exit 2). It used to take
/// one 10 s step past the 5 s end and fail on its energy balance.
#[test]
fn a_step_longer_than_the_run_is_refused() {
    let (code, out, err) = run(&["run", "five-bar", "--h", "10"]);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("h = 10 s") && err.contains("t_end = 5 s"),
        "{err}"
    );
}

/// A `t_end` that is not a multiple of `h` ends there: the last step is shortened.
/// Oracle: the same run at h/2, whose t_end (21 steps of 0.5 ms) is a multiple:
/// the two final states agree to the DP5 error (~1e-12 here), where a run that ended at
/// 11 ms would be 3e-4 rad off.
#[test]
fn the_last_step_lands_on_t_end() {
    let dir = TempDir::new("figures-last-step");
    let (code, summary, err, csv) =
        run_to_csv(&dir, &["five-bar", "--h", "0.001", "--t-end", "0.0105"]);
    assert_eq!(code, 0, "{err}");
    let (names, rows) = numeric_csv(&csv);
    let t = col(&names, &rows, "t");
    assert_eq!(t.len(), 12, "11 steps and t = 0");
    assert_eq!(*t.last().unwrap(), 0.0105, "{t:?}");
    assert!(
        (t[10] - 0.01).abs() < 1e-15,
        "the steps before keep h: {t:?}"
    );
    assert!(summary.contains("t = 0 .. 0.010500 s"), "{summary}");
    let (code, _, err, fine) =
        run_to_csv(&dir, &["five-bar", "--h", "0.0005", "--t-end", "0.0105"]);
    assert_eq!(code, 0, "{err}");
    let (_, fine_rows) = numeric_csv(&fine);
    let (a, b) = (rows.last().unwrap(), fine_rows.last().unwrap());
    assert_eq!(b[0], 0.0105);
    for k in 1..3 {
        assert!(
            (a[k] - b[k]).abs() < 1e-9,
            "column {}: {} vs {}",
            names[k],
            a[k],
            b[k]
        );
    }
}

/// A run file of a crank-rocker four-bar (the `balance` property test's family) with
/// the motor and load TOML snippets given.
fn four_bar(motor: &str, load: &str, run: &str) -> String {
    format!(
        r#"name = "four-bar"
gravity = [0.0, -9.81]
[[ground]]
name = "A"
at = [0.0, 0.0]
[[ground]]
name = "D"
at = [0.4, 0.0]
[[link]]
name = "crank"
length = 0.1
mass = 0.2
inertia = 0.002
cog = 0.05
angle_deg = 60.0
[[link]]
name = "coupler"
length = 0.45
mass = 0.5
inertia = 0.01
cog = 0.225
angle_deg = 20.0
[[link]]
name = "rocker"
length = 0.35
mass = 0.4
inertia = 0.005
cog = 0.175
angle_deg = 100.0
[[joint]]
name = "A"
type = "revolute"
points = ["A", "crank.start"]
[[joint]]
name = "B"
type = "revolute"
points = ["crank.end", "coupler.start"]
[[joint]]
name = "C"
type = "revolute"
points = ["coupler.end", "rocker.end"]
[[joint]]
name = "D"
type = "revolute"
points = ["D", "rocker.start"]
[[driver]]
link = "crank"
joint = "A"
q0_deg = 60.0
qd0 = 0.0
motor = {motor}
{load}
[run]
{run}
"#
    )
}

/// Writes `text` as `dir/name` and returns the path.
fn write(dir: &TempDir, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write the run file");
    p
}

/// The work of a `[[load]]` moment is in the balance with the adaptive integrator too,
/// and the motors' work is metered there. Oracle: a constant moment `M` on the driven
/// crank does the work `M (q1(T) - q1(0))`, a constant motor torque `τ (q1(T) - q1(0))`.
#[test]
fn load_work_is_in_every_balance() {
    let dir = TempDir::new("figures-loads");
    let text = four_bar(
        "{ type = \"constant\", torque = 2.0 }",
        "[[load]]\nlink = \"crank\"\nmoment = -0.5\n",
        "integrator = \"adaptive\"\nh = 0.01\nt_end = 0.5\n",
    );
    let file = write(&dir, "loaded.toml", &text);
    let (code, summary, err, csv) = run_to_csv(&dir, &[&file]);
    assert_eq!(code, 0, "{err}");
    let (names, rows) = numeric_csv(&csv);
    let q = col(&names, &rows, "q1");
    let want = -0.5 * (q[q.len() - 1] - q[0]);
    let loads = number_after(&summary, "+ loads ");
    // Printed to six decimals.
    assert!((loads - want).abs() < 1e-6, "{loads} vs {want}\n{summary}");
    // The motors' work is metered with the state too, not the trapezoid on the output
    // grid (which was 8e-2 J off here): a constant 2 N·m does 2 (q1(T) - q1(0)), and
    // the balance closes to the adaptive tolerance.
    let motors = number_after(&summary, "work of the motors ");
    let exact = 2.0 * (q[q.len() - 1] - q[0]);
    assert!(
        (motors - exact).abs() < 1e-6,
        "{motors} vs {exact}\n{summary}"
    );
    let residual = number_after(&summary, "end - start - work = ");
    assert!(residual.abs() < 1e-6 * motors, "{residual}\n{summary}");
}

/// An asynchronous motor whose parabola gives a negative torque at standstill is
/// refused at set-up with its numbers. Oracle: the parabola through (900 rpm, 10 N·m),
/// (1400 rpm, 5 N·m), (1500 rpm, 0) has `a = T(0) = -65 N·m` (Lagrange's form by hand).
#[test]
fn a_motor_that_cannot_start_is_refused() {
    let dir = TempDir::new("figures-motor");
    let motor = "{ type = \"asynchronous\", breakdown_rpm = 900.0, breakdown_torque = 10.0, \
                 rated_rpm = 1400.0, rated_torque = 5.0, synchronous_rpm = 1500.0 }";
    let file = write(
        &dir,
        "m.toml",
        &four_bar(motor, "", "h = 0.001\nt_end = 0.1\n"),
    );
    let (code, _, err) = run(&["run", &file, "--quiet"]);
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("driver[0].motor") && err.contains("T(0) = -65") && err.contains("< 0"),
        "{err}"
    );
}

/// A motor driven past the speed where its parabola turns up again gets a warning,
/// with the time and its numbers, not only a failed step. Oracle: the polynomial
/// `T = 2 - 0.4 ω + 0.01 ω²` turns up at `ω = 0.4 / 0.02 = 20 rad/s` (set-up warning);
/// a 5 N·m load moment in the sense of rotation drives the crank past it (run-time
/// warning).
#[test]
fn a_motor_past_its_working_zone_is_warned_about() {
    let dir = TempDir::new("figures-zone");
    let text = four_bar(
        "{ type = \"polynomial\", a = 2.0, b = -0.4, c = 0.01 }",
        "[[load]]\nlink = \"crank\"\nmoment = 5.0\n",
        "h = 0.0005\nt_end = 0.3\n",
    );
    let file = write(&dir, "zone.toml", &text);
    let (code, summary, err, _) = run_to_csv(&dir, &[&file]);
    let all = format!("{summary}{err}");
    assert!(
        all.contains("rises again past ω = 20 rad/s"),
        "{code}: {all}"
    );
    assert!(
        all.contains("outside its working zone [0, 20] rad/s"),
        "{code}: {all}"
    );
}

/// Loads from 1e12 N·m (N) on are refused at set-up, naming the field: the tolerances
/// lose their meaning there.
#[test]
fn loads_too_large_for_the_tolerances_are_refused() {
    let (code, _, err) = run(&["run", "ccc-s2", "--load", "1e12", "--quiet"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--load") && err.contains("1e12"), "{err}");
    let dir = TempDir::new("figures-big-load");
    let text = four_bar(
        "2.0",
        "[[load]]\nlink = \"rocker\"\nmoment = 2e12\n",
        "h = 0.001\nt_end = 0.1\n",
    );
    let file = write(&dir, "big.toml", &text);
    let (code, _, err) = run(&["run", &file, "--quiet"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("load[0].moment") && err.contains("2e12"),
        "{err}"
    );
}

/// The summary prints tiny and huge figures with exponents: no `0.000000` hiding a
/// small value. Oracle: over 2 µs from rest the kinetic energy is ~1e-9 J (K grows as
/// t²), which six decimals would print as 0.000000.
#[test]
fn tiny_figures_have_exponents() {
    let (code, out, err) = run(&[
        "run", "five-bar", "--h", "1e-6", "--t-end", "2e-6", "--out", "-",
    ]);
    assert_eq!(code, 0, "{err}");
    let summary = err;
    assert!(!summary.contains("0.000000 "), "{summary}");
    assert!(out.lines().count() == 4, "{out}");
    let k = number_after(&summary, "end ");
    assert!(k > 0.0 && k < 1e-6, "K(2 µs) = {k}\n{summary}");
}

/// The summary's switch lines read as sentences: one switch is "1 change", and a
/// switch back to the first coordinates says so instead of a `-` for the group.
/// `stretched-four-bar.toml` switches once (at t = 0.853 s), `crank-triad.toml`
/// switches away and back twice each in its first 1.1 s (at 0.455, 0.593, 0.992, 1.083 s).
#[test]
fn switch_lines_read() {
    let mechanisms = concat!(env!("CARGO_MANIFEST_DIR"), "/mechanisms");
    let one = format!("{mechanisms}/stretched-four-bar.toml");
    let (code, _, summary) = run(&["run", &one, "--out", "-"]);
    assert_eq!(code, 0, "{summary}");
    assert!(
        summary.contains("switches  1 change of coordinates"),
        "{summary}"
    );
    let triad = format!("{mechanisms}/crank-triad.toml");
    let (code, _, summary) = run(&["run", &triad, "--t-end", "1.1", "--out", "-"]);
    assert_eq!(code, 0, "{summary}");
    assert!(summary.contains("switches  4 changes"), "{summary}");
    assert!(
        summary.contains("(back to the first coordinates: conditioning "),
        "{summary}"
    );
    assert!(!summary.contains("(- at"), "{summary}");
}

/// The converter's load torque is refused from 1e6 N·m on, on the command line and in
/// a run file: the twin's clutch tolerance, 1e-9 (T_r + 1 N·m), would let a locked
/// lever hold a negative torque (S2 at T_r = 1e7 N·m had c8 = -7.4e-3 N·m in its CSV,
/// at 1e11 -98 N·m). Below the bound the clutch rule holds in every row: c6, c8 ≥ 0
/// to that tolerance (1e-3 N·m at most).
#[test]
fn converter_loads_keep_the_clutch_rules() {
    for load in ["1e6", "1e7", "1e11"] {
        let (code, _, err) = run(&["run", "ccc-s2", "--load", load, "--quiet"]);
        assert_eq!(code, 2, "{load}: {err}");
        assert!(
            err.contains("--load") && err.contains("negative torque"),
            "{err}"
        );
    }
    let dir = TempDir::new("figures-converter-load");
    let text = host_sim::ScenarioId::CccS2
        .file_text()
        .replace("load = 800.0", "load = 2e7");
    assert!(text.contains("load = 2e7"));
    let file = write(&dir, "heavy.toml", &text);
    let (code, _, err) = run(&["run", &file, "--quiet"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("run.load") && err.contains("2e7"), "{err}");
    for load in [1e3, 9.9e5] {
        let arg = format!("{load}");
        let (code, _, err, csv) = run_to_csv(&dir, &["ccc-s2", "--load", &arg, "--t-end", "0.1"]);
        assert_eq!(code, 0, "{load}: {err}");
        // The converter's CSV has text columns (mode, coords): read c6 and c8 only.
        let header = csv.lines().next().expect("a header");
        let names: Vec<&str> = header.split(',').collect();
        let tol = 1e-9 * (load + 1.0);
        for c in ["c6", "c8"] {
            let k = names.iter().position(|n| *n == c).expect("a clutch column");
            let low = csv
                .lines()
                .skip(1)
                .map(|l| {
                    l.split(',')
                        .nth(k)
                        .expect("a field")
                        .parse::<f64>()
                        .expect("a number")
                })
                .fold(f64::INFINITY, f64::min);
            assert!(low >= -tol, "T_r = {load}: {c} down to {low} N·m");
        }
    }
}
