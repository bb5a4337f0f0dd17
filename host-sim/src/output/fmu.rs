//! `host-sim fmu`: the converter's twin as an FMI 2.0 Co-Simulation FMU. The zip holds
//! `modelDescription.xml` (written by `structomat_fmu::description` from the
//! converter's values: they are its start values), the binary
//! `binaries/<platform>/structomat_ccc.<so|dylib|dll>` (the structomat-fmu cdylib,
//! copied) and `resources/start.txt` (the same start values, which the binary reads
//! when it is instantiated and reset).
//!
//! The binary is the cdylib that cargo builds next to host-sim's executable
//! (`target/release/libstructomat_fmu.so` beside `target/release/host-sim`), or the
//! one `--lib` names; a missing one is an error that says how to build it.

use crate::error::{write_whole, EXIT_FAILURE, EXIT_OK, EXIT_USAGE};
use crate::model::runfile::MotorSpec;
use crate::options::{FmuOptions, Steps};
use crate::run::converter::settings;
use std::io::{Cursor, Write};
use std::path::PathBuf;
use structomat_fmu::description::{Description, MODEL_IDENTIFIER};
use structomat_fmu::variables::{vr, Start};

/// The FMI 2.0 platform folder of this host (`binaries/<platform>`).
pub fn platform() -> &'static str {
    match (std::env::consts::OS, cfg!(target_pointer_width = "64")) {
        ("windows", true) => "win64",
        ("windows", false) => "win32",
        ("macos", _) => "darwin64",
        (_, true) => "linux64",
        (_, false) => "linux32",
    }
}

/// The modelDescription's values of the converter of `opts` (its start values: the
/// converter's parameters and initial state, h, the motor's constant torque and the
/// load; the default experiment's stop time: t_end). Errors: why it has none.
pub fn description(opts: &FmuOptions) -> Result<Description, String> {
    let run = &opts.run;
    let name = run.scenario.name();
    let s = settings(run).ok_or_else(|| format!("{name} is not a converter"))?;
    let (steps, h) = Steps::of::<f64>(run).map_err(|e| e.to_string())?;
    let MotorSpec::Constant(motor) = s.motor else {
        return Err(format!(
            "{name}'s motor is a motor law: the FMU's motor is its input motor_torque (a torque held over each step); give its start value with --motor N·M"
        ));
    };
    let c = &s.converter;
    let mut params = c.params::<f64>();
    params.drive = s.drive;
    let mut start = Start::default();
    start.set_params(&params);
    let r = &mut start.reals;
    r[vr::H as usize] = h;
    r[vr::CRANK_DEG as usize] = c.crank_deg;
    r[vr::SWING_DEG as usize] = c.swing_deg;
    r[vr::CRANK_SPEED0 as usize] = c.crank_speed;
    r[vr::SWING_SPEED0 as usize] = c.swing_speed;
    r[vr::MOTOR as usize] = motor;
    r[vr::LOAD as usize] = s.load;
    start.bools[vr::CLUTCH as usize] = s.clutch;
    Ok(Description {
        start,
        stop_time: steps.t_end,
        text: format!("{name}: {s}"),
    })
}

/// The binary to package: `--lib`, or the cdylib next to this executable.
pub fn library(opts: &FmuOptions) -> Result<PathBuf, String> {
    if let Some(l) = &opts.lib {
        return Ok(l.clone());
    }
    let exe =
        std::env::current_exe().map_err(|e| format!("cannot find host-sim's own path: {e}"))?;
    let dir = exe.parent().unwrap_or(std::path::Path::new("."));
    Ok(dir.join(format!(
        "{}structomat_fmu{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )))
}

/// The FMU's bytes: the zip of `description` and the binary `lib_bytes`.
pub fn fmu_bytes(description: &Description, lib_bytes: &[u8]) -> Result<Vec<u8>, String> {
    let (xml, guid) = description.xml();
    let start = description.start.file_text(&guid);
    let binary = format!(
        "binaries/{}/{MODEL_IDENTIFIER}{}",
        platform(),
        std::env::consts::DLL_SUFFIX
    );
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let text = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let exe = text.unix_permissions(0o755);
    let entries: [(&str, &[u8], _); 3] = [
        ("modelDescription.xml", xml.as_bytes(), text),
        (&binary, lib_bytes, exe),
        ("resources/start.txt", start.as_bytes(), text),
    ];
    for (name, bytes, options) in entries {
        zip.start_file(name, options)
            .and_then(|()| zip.write_all(bytes).map_err(Into::into))
            .map_err(|e| format!("cannot zip {name}: {e}"))?;
    }
    let cursor = zip
        .finish()
        .map_err(|e| format!("cannot finish the zip: {e}"))?;
    Ok(cursor.into_inner())
}

/// Runs `host-sim fmu`: writes the FMU and a line about it on `stdout`; errors on
/// `stderr` with exit code 1 (2 for a converter the FMU cannot take).
pub fn execute(opts: &FmuOptions, stdout: &mut dyn Write, stderr: &mut dyn Write) -> u8 {
    let description = match description(opts) {
        Ok(d) => d,
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: fmu: {e}");
            return EXIT_USAGE;
        }
    };
    let made = library(opts).and_then(|lib| {
        let bytes = std::fs::read(&lib).map_err(|e| {
            format!(
                "cannot read the FMU's binary {}: {e}; build it with `cargo build --release -p structomat-fmu -p host-sim` (it is put next to host-sim), or give --lib FILE",
                lib.display()
            )
        })?;
        let fmu = fmu_bytes(&description, &bytes)?;
        write_whole(&opts.out, &fmu)
            .map_err(|e| format!("cannot write {}: {e}", opts.out.display()))?;
        Ok(lib)
    });
    match made {
        Ok(lib) => {
            let _ = writeln!(
                stdout,
                "fmu       {}: {MODEL_IDENTIFIER} (FMI 2.0 Co-Simulation), GUID {}, h = {} s, stop time {} s\nbinary    {} (binaries/{})",
                opts.out.display(),
                description.guid(),
                description.start.reals[vr::H as usize],
                description.stop_time,
                lib.display(),
                platform(),
            );
            EXIT_OK
        }
        Err(e) => {
            let _ = writeln!(stderr, "host-sim: fmu: {e}");
            EXIT_FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{parse_args, Command};
    use std::io::Read;

    fn options(args: &[&str]) -> Result<FmuOptions, String> {
        match parse_args(args.iter().copied()) {
            Ok(Command::Fmu(o)) => Ok(o),
            Ok(other) => Err(format!("{other:?}")),
            Err(crate::cli::ParseError::Usage(e)) => Err(e.0),
            Err(crate::cli::ParseError::Clap(e)) => Err(e.to_string()),
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
}
