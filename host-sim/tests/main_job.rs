//! The README's main job as written: `host-sim run five-bar --out five_bar.csv`, the
//! scenario's own data (h = 1 ms, 5 s). Its fixed steps keep their local error
//! (`structomat::simulation::substeps`) and their energy balance, so
//!
//! - q1(0.5 s) and q1(1 s) agree with an adaptive DP5(4) run at rtol = atol = 1e-12 (the
//!   same scenario file with `integrator = "adaptive"`) to 1e-8 rad;
//! - the energy balance closes to 1e-6 of the motor work over the 5 s, the work taken
//!   independently of the core's metering: 10 N·m on crank 1 does `10·Δq1` exactly.

mod common;

use common::{number_after, numeric_csv, run, TempDir};

/// The scenario's run file, as the binary embeds it.
fn scenario() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/five-bar.toml");
    std::fs::read_to_string(path).expect("the five-bar scenario")
}

/// The CSV's q1 at time `t` (a row of the output grid), rad.
fn q1_at(names: &[String], rows: &[Vec<f64>], t: f64) -> f64 {
    let q1 = names.iter().position(|n| n == "q1").expect("a q1 column");
    rows.iter()
        .find(|r| (r[0] - t).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no row at t = {t}"))[q1]
}

#[test]
fn the_main_job_is_accurate_and_keeps_its_energy_balance() {
    let dir = TempDir::new("main-job");
    let csv = dir.join("five_bar.csv");
    let (code, summary, err) = run(&["run", "five-bar", "--out", &csv]);
    assert_eq!(code, 0, "{err}");
    let (names, rows) = numeric_csv(&std::fs::read_to_string(&csv).expect("the CSV"));

    // The oracle: the same file integrated by the adaptive DP5(4) at 1e-12, 1 s.
    let file = dir.join("adaptive.toml");
    let text = scenario()
        .replace(
            "integrator = \"dp5\"",
            "integrator = \"adaptive\"\nrtol = 1e-12\natol = 1e-12",
        )
        .replace("t_end = 5.0", "t_end = 1.0");
    assert!(text.contains("\"adaptive\"") && text.contains("t_end = 1.0"));
    std::fs::write(&file, text).expect("write");
    let reference = dir.join("adaptive.csv");
    let (code, _, err) = run(&["run", &file, "--out", &reference]);
    assert_eq!(code, 0, "{err}");
    let (ref_names, ref_rows) = numeric_csv(&std::fs::read_to_string(&reference).expect("CSV"));
    for t in [0.5, 1.0] {
        let (q, r) = (q1_at(&names, &rows, t), q1_at(&ref_names, &ref_rows, t));
        eprintln!(
            "q1({t} s): fixed {q:.12}, adaptive {r:.12}, |Δ| {:.1e}",
            (q - r).abs()
        );
        assert!((q - r).abs() <= 1e-8, "q1({t} s) off by {:e}", q - r);
    }

    // The balance over 5 s: 10 N·m · Δq1 against Δ(K + V) of the summary's energies.
    let (first, last) = (rows.first().unwrap(), rows.last().unwrap());
    assert_eq!(last[0], 5.0);
    let q1 = names.iter().position(|n| n == "q1").unwrap();
    let work = 10.0 * (last[q1] - first[q1]);
    let line = summary.lines().find(|l| l.starts_with("energy")).unwrap();
    // "K + V: start K0 + V0 = E0 J, end K1 + V1 = E1 J"
    let totals: Vec<f64> = line
        .split(" = ")
        .skip(1)
        .map(|s| s.split(' ').next().unwrap().parse().unwrap())
        .collect();
    let gained = totals[1] - totals[0];
    eprintln!("work {work:.6} J, gained {gained:.6} J");
    assert!(work > 100.0, "{work}");
    // The summary prints the energies to 1e-6 J.
    assert!(
        (gained - work).abs() <= 1e-6 * work,
        "{gained} J vs {work} J"
    );
    // And it says how: the steps redone for either reason.
    let substeps = summary.lines().find(|l| l.starts_with("substeps")).unwrap();
    assert!(
        number_after(substeps, "for the energy balance, ") > 0.0,
        "{substeps}"
    );
    assert!(substeps.contains("for the local error"), "{substeps}");
}
