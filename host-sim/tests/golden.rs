//! Golden hashes: the SHA-256 of the output of every built-in scenario, pinned.
//!
//! [`PINS`] holds, per run (`host-sim run <args>` with its default settings unless the
//! arguments say otherwise), the exit status and the SHA-256 of the state CSV and, for
//! the converter scenarios, of the event and switch logs written next to `--out FILE`.
//! Any change of a single bit of a trajectory, of a number's formatting or of an event
//! fails this test, naming the run, the file, the expected and the actual hash.
//!
//! Reproduce a pin by hand:
//!
//! ```sh
//! cargo run --release -p host-sim -- run ccc-s2 --quiet | sha256sum     # the state CSV
//! cargo run --release -p host-sim -- run ccc-s2 --quiet --out s2.csv
//! sha256sum s2.csv s2.events.csv s2.switches.csv                       # and the logs
//! ```
//!
//! (The state CSV on stdout and in `--out FILE` are the same bytes.)
//!
//! Regenerate the pins ON PURPOSE only, when a change is meant to move the output:
//!
//! ```sh
//! GOLDEN_PRINT=1 cargo test -p host-sim --test golden -- --nocapture
//! ```
//!
//! prints the current table in the source form of [`PINS`] instead of asserting; paste
//! it over the table. The rule: the commit that changes a pin says why (which change
//! moved which output, and why the new output is right). A pin that moves in a commit
//! that did not mean to move it is a bug, not a pin to update.
//!
//! Why the hashes hold across builds and machines: the core does its math with `libm`
//! (nalgebra's `libm-force`), not the platform's; Rust does no fast-math and no FMA
//! contraction, so the optimization level does not change a result; the CSV prints
//! numbers in shortest round-trip form. (Checked: debug and release on x86_64 Linux;
//! other targets are expected to agree for the same reasons, not checked here.)
//!
//! The runs are the full default lengths: in the debug test profile about 37 s of CPU
//! time, run here on all cores (about 20 s on 2 idle cores); in release about 1.3 s.

mod common;

use common::{read, utf8, TempDir};
use host_sim::run_jobs;
use sha2::{Digest, Sha256};
use std::path::Path;

/// One pinned run: `host-sim run <args> --quiet --out FILE`.
struct Pin<'a> {
    /// The arguments of `host-sim run`.
    args: &'a str,
    /// Its exit status.
    exit: u8,
    /// SHA-256 of the state CSV, hex.
    csv: &'a str,
    /// SHA-256 of the event log and of the switch log (converter scenarios only).
    logs: Option<(&'a str, &'a str)>,
}

/// The pins. The same in the debug (test) profile and with `--release`: checked when
/// they were minted, by `cargo test -p host-sim --test golden` and
/// `cargo test --release -p host-sim --test golden` (x86_64 Linux, rustc 1.95).
/// `ccc-s1` ends at the mechanism's singularity (its expected end, exit status 0), and
/// so does `ccc-s1 --f32`, 1.9 ms earlier: rounding breaks its energy balance while the
/// diode's branches are 2.0 ms from in line (`TwinStepError::Diode`'s horizon). Both S1 logs hold only their
/// header (free mode has no start event and S1 no coordinate switch), hence the same
/// log hashes.
///
/// The three mechanism pins (`slider-crank`, `five-bar`, `five-bar --f32`) are
/// regression values of the steps that keep their local error
/// (`structomat::simulation::substeps`), checked when minted against an adaptive DP5(4)
/// run of the same files at rtol = atol = 1e-12: slider-crank q1 within 1.5e-11 rad
/// at 1, 5 and 10 s (its h = 1e-2 under the local tolerance per unit time); five-bar q1 within 7.6e-12 rad to 0.5 s and 6.5e-9 rad to 1 s
/// (`tests/main_job.rs`; past 2 s the five-bar's free link makes the motion too
/// sensitive for any reference); five-bar --f32 within 1.6e-5 rad to 0.5 s.
const PINS: &[Pin<'static>] = &[
    Pin {
        args: "slider-crank",
        exit: 0,
        csv: "9e185af9b65f6d16f5ea18466671ed0de15adfc182b495a4da38ab45a169e8ad",
        logs: None,
    },
    Pin {
        args: "five-bar",
        exit: 0,
        csv: "4a4d364d7d7eeb0a42b60987a6a6ee3a29cab15ad36fa40de5127016bd952e91",
        logs: None,
    },
    Pin {
        args: "ccc-s1",
        exit: 0,
        csv: "8b5ca62e33704427c28928cde8fbf2348ddc1258c08470160933211332c0a984",
        logs: Some((
            "2a18d19a58b935cc5a81a088e9c456f81ad855f74a9f76a5d7ec92b8b8ba339b",
            "9a52b761f69ab666f48cadb42b788f2fabceddd39201f1066997acf316fd6238",
        )),
    },
    Pin {
        args: "ccc-s2",
        exit: 0,
        csv: "c5220b8cf7fa222305373148b2591bcd4e9edd04c33f20503d5d82b1d5955ffa",
        logs: Some((
            "f0685a912b9e10742cbad92054e38c07d490577af130eee89a9d7fdfdcfe1244",
            "83e8472c982508bdc4062a2ed86d3d3d318487711b58ec6d9cf8bafecf034907",
        )),
    },
    Pin {
        args: "ccc-s2 --ccw",
        exit: 0,
        csv: "3523c3e2cda32d751a937b1516cb248a090efa54a55e7ec032bbd63d44ccc38e",
        logs: Some((
            "f2ab28ba80baedfb11a6256415900e137765474446899c0212646f1851f16ea4",
            "55e2b79936ae19cb61b7e61637efd3e36b56b8278e5e0d0d5815d0bac7b97b16",
        )),
    },
    Pin {
        args: "five-bar --f32",
        exit: 0,
        csv: "d6c98d5e67676b19f8af8ba6a689f97aa8df4042866393b53d1cea60919d3947",
        logs: None,
    },
    Pin {
        args: "ccc-s1 --f32",
        exit: 0,
        csv: "06b29c1e781435f18a112bb32eed564cde22fcd3389461dcb557262f50e4caf5",
        logs: Some((
            "2a18d19a58b935cc5a81a088e9c456f81ad855f74a9f76a5d7ec92b8b8ba339b",
            "9a52b761f69ab666f48cadb42b788f2fabceddd39201f1066997acf316fd6238",
        )),
    },
    Pin {
        args: "ccc-s2 --f32",
        exit: 0,
        csv: "1ad7277eccf72665ae724464481993257ebbebdaa230a41cd434ac90cdbd5109",
        logs: Some((
            "08d0b3d94cef65c024903893e7f31b3619455c52ae0cdbf34c412c2cc5996e13",
            "99715c7df387733c960831f25d6518894969cd34c0fa88c861cc88b33d263fb6",
        )),
    },
];

/// What a run produced: its exit status and the hashes of its files.
#[derive(Debug, PartialEq)]
struct Produced {
    exit: u8,
    csv: String,
    logs: Option<(String, String)>,
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Runs `pin.args` with its CSV to `csv` and hashes what it wrote.
fn produce(pin: &Pin<'_>, csv: &Path) -> Produced {
    let mut args = vec!["run"];
    args.extend(pin.args.split_whitespace());
    args.extend(["--quiet", "--out", utf8(csv)]);
    let (exit, _, _) = common::run(&args);
    let hash = |p: &Path| sha256_hex(&read(p));
    let logs = pin.logs.map(|_| {
        let (events, switches) = host_sim::ccc::log_paths(csv);
        (hash(&events), hash(&switches))
    });
    Produced {
        exit,
        csv: hash(csv),
        logs,
    }
}

/// `Pin { .. }` in the source form of [`PINS`] (as rustfmt lays it out).
fn source(args: &str, p: &Produced) -> String {
    let logs = match &p.logs {
        Some((e, s)) => format!("Some((\n            \"{e}\",\n            \"{s}\",\n        ))"),
        None => "None".to_string(),
    };
    format!(
        "    Pin {{\n        args: \"{args}\",\n        exit: {},\n        csv: \"{}\",\n        logs: {logs},\n    }},",
        p.exit, p.csv
    )
}

/// How `got` differs from `pin`: one message per file (or exit status), naming the
/// run, the file, the expected and the actual value.
fn mismatches(pin: &Pin<'_>, got: &Produced) -> Vec<String> {
    let run = format!("`host-sim run {}`", pin.args);
    let mut out = Vec::new();
    if got.exit != pin.exit {
        out.push(format!(
            "{run}: exit status: expected {}, actual {}",
            pin.exit, got.exit
        ));
    }
    let mut check = |file: &str, expected: &str, actual: &str| {
        if expected != actual {
            out.push(format!(
                "{run}: {file}:\n    expected {expected}\n    actual   {actual}"
            ));
        }
    };
    check("state CSV", pin.csv, &got.csv);
    let none = ("(none)", "(none)");
    let (e, s) = pin.logs.unwrap_or(none);
    let (ge, gs) = got
        .logs
        .as_ref()
        .map_or(none, |(e, s)| (e.as_str(), s.as_str()));
    check("event log", e, ge);
    check("switch log", s, gs);
    out
}

#[test]
fn golden_hashes() {
    let dir = TempDir::new("golden");
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    // Each run to its own files (`{k}.csv`, `{k}.events.csv`, ...).
    let produced = run_jobs(
        PINS,
        threads,
        |k, pin| produce(pin, &dir.path.join(format!("{k}.csv"))),
        |_, _| {},
    );
    if std::env::var_os("GOLDEN_PRINT").is_some_and(|v| v == "1") {
        println!("const PINS: &[Pin<'static>] = &[");
        for (pin, p) in PINS.iter().zip(&produced) {
            println!("{}", source(pin.args, p));
        }
        println!("];");
        return;
    }
    let failures: Vec<String> = PINS
        .iter()
        .zip(&produced)
        .flat_map(|(pin, got)| mismatches(pin, got))
        .collect();
    assert!(
        failures.is_empty(),
        "{} golden pin(s) differ:\n{}\nIf the change is on purpose, regenerate the table \
         (GOLDEN_PRINT=1, see the top of host-sim/tests/golden.rs) and say why in the commit.",
        failures.len(),
        failures.join("\n")
    );
}

// The check itself can fail: other bytes are reported with the run, the file and both
// hashes; and the pin of the CSV in `--out FILE` is that of the CSV on stdout.
#[test]
fn a_wrong_pin_is_reported() {
    let dir = TempDir::new("golden-wrong");
    let zeros = "0000000000000000000000000000000000000000000000000000000000000000";
    let pin = Pin {
        args: "five-bar --t-end 0.01",
        exit: 0,
        csv: zeros,
        logs: None,
    };
    let got = produce(&pin, &dir.path.join("w.csv"));
    let m = mismatches(&pin, &got);
    assert_eq!(m.len(), 1, "{m:?}");
    for needle in [
        "five-bar --t-end 0.01",
        "state CSV",
        zeros,
        got.csv.as_str(),
    ] {
        assert!(m[0].contains(needle), "{:?} lacks {needle:?}", m[0]);
    }
    let right = Pin {
        csv: &got.csv,
        ..pin
    };
    assert!(mismatches(&right, &got).is_empty());
    let (code, out, _) = common::run(&["run", "five-bar", "--t-end", "0.01", "--quiet"]);
    assert_eq!(code, 0);
    assert_eq!(sha256_hex(out.as_bytes()), got.csv);
}

// The known answer of SHA-256 (FIPS 180-2, "abc"), so a pin is the `sha256sum` of the
// file.
#[test]
fn sha256_is_the_standard_one() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}
