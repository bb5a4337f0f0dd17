//! `host-sim fmu`: the converter options of `run` give the FMU's start values (ccc-s2's
//! are the FMU binary's own defaults), the zip holds its three files, and a missing
//! binary is an error that says how to build it. (The FMU itself: fmu/tests.)

use host_sim::cli::{parse_args, Command, ParseError};
use host_sim::error::EXIT_FAILURE;
use host_sim::options::FmuOptions;
use host_sim::run::fmu::{description, execute, fmu_bytes, platform};
use std::io::{Cursor, Read};
use std::path::PathBuf;
use structomat_fmu::description::Description;
use structomat_fmu::variables::{vr, Start};

fn options(args: &[&str]) -> Result<FmuOptions, String> {
    match parse_args(args.iter().copied()) {
        Ok(Command::Fmu(o)) => Ok(o),
        Ok(other) => Err(format!("{other:?}")),
        Err(ParseError::Usage(e)) => Err(e.0),
        Err(ParseError::Clap(e)) => Err(e.to_string()),
    }
}

// ccc-s2's start values are the FMU's own defaults (SPEC 3's reference converter
// from its initial state, h = 1e-4 s, 12 N·m against 800 N·m): host-sim's scenario
// file and the core's `CccParams::reference` agree.
#[test]
fn s2_is_the_defaults() {
    let o = options(&["fmu", "--out", "x.fmu"]).unwrap();
    let d = description(&o).unwrap();
    assert_eq!(d.start, Start::default());
    assert_eq!(d.stop_time, 1.0);
    assert_eq!(o.out, PathBuf::from("x.fmu"));
}

// The converter options of run set the start values; the ones that do not apply
// are refused with run's messages.
#[test]
fn converter_options_set_the_start_values() {
    let o = options(&[
        "fmu", "ccc-s2", "--out", "x.fmu", "--h", "2e-4", "--t-end", "0.5", "--load", "0",
        "--motor", "-3.5", "--ccw",
    ])
    .unwrap();
    let d = description(&o).unwrap();
    let r = &d.start.reals;
    assert_eq!(
        (
            r[vr::H as usize],
            r[vr::LOAD as usize],
            r[vr::MOTOR as usize]
        ),
        (2e-4, 0.0, -3.5)
    );
    assert!(d.start.bools[vr::CCW as usize]);
    assert_eq!(d.stop_time, 0.5);
    let s1 = description(&options(&["fmu", "ccc-s1", "--out", "x.fmu"]).unwrap()).unwrap();
    assert!(!s1.start.bools[vr::CLUTCH as usize]);
    for (args, needle) in [
        (
            &["fmu", "five-bar", "--out", "x"][..],
            "five-bar is not a converter",
        ),
        (
            &["fmu", "ccc-s1", "--out", "x", "--ccw"][..],
            "--ccw: ccc-s1",
        ),
        (
            &["fmu", "--out", "x", "--load", "-1"][..],
            "--load: -1 is negative",
        ),
        (&["fmu", "--out", ""][..], "--out: empty"),
    ] {
        let e = options(args).unwrap_err();
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}

// The zip holds the description, the binary under its model identifier and the
// start values with the description's GUID.
#[test]
fn the_zip_holds_the_three_files() {
    let d = Description::default();
    let bytes = fmu_bytes(&d, b"binary").unwrap();
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
    let mut read = |name: &str| {
        let mut s = Vec::new();
        zip.by_name(name).unwrap().read_to_end(&mut s).unwrap();
        s
    };
    let xml = String::from_utf8(read("modelDescription.xml")).unwrap();
    assert_eq!(xml, d.xml().0);
    let bin = format!(
        "binaries/{}/structomat_ccc{}",
        platform(),
        std::env::consts::DLL_SUFFIX
    );
    assert_eq!(read(&bin), b"binary");
    let start = String::from_utf8(read("resources/start.txt")).unwrap();
    let (back, guid) = Start::parse(&start).unwrap();
    assert_eq!((back, guid), (d.start, Some(d.guid())));
}

// A missing binary is an error that says how to build it.
#[test]
fn a_missing_binary_says_how_to_build_it() {
    let dir = std::env::temp_dir().join(format!("host-sim-fmu-{}", std::process::id()));
    let out = dir.join("x.fmu");
    let mut o = options(&["fmu", "--out", out.to_str().unwrap()]).unwrap();
    o.lib = Some(dir.join("missing.so"));
    let (mut stdout, mut stderr) = (Vec::new(), Vec::new());
    assert_eq!(execute(&o, &mut stdout, &mut stderr), EXIT_FAILURE);
    let e = String::from_utf8(stderr).unwrap();
    assert!(e.contains("cargo build --release -p structomat-fmu"), "{e}");
    assert!(!out.exists());
}

// A run file's losses (bench1 as `identify` found it: four joints' viscous friction)
// are the FMU's start values: the FMU's converter is the run file's, friction and all
// (the oracle: the run file's own numbers, read here).
#[test]
fn a_run_file_s_friction_is_in_the_start_values() {
    let path = "tests/data/bench1-identified.toml";
    let d = description(&options(&["fmu", path, "--out", "x.fmu"]).unwrap()).unwrap();
    let text = std::fs::read_to_string(path).unwrap();
    let value: toml::Value = toml::from_str(&text).unwrap();
    let viscous = &value["converter"]["friction"]["viscous"];
    let p = d.start.params();
    for (k, j) in structomat::ccc::FRICTION_JOINT_NAMES.iter().enumerate() {
        let want = viscous.get(*j).and_then(|v| v.as_float()).unwrap_or(0.0);
        assert_eq!(p.friction.viscous[k], want, "joint {j}");
        assert_eq!(
            d.start.reals[(vr::FRICTION as usize) + k],
            want,
            "joint {j}"
        );
    }
    assert!(p.friction.active(), "the identified machine's friction");
}
