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

use super::converter::settings;
use crate::error::{write_whole, EXIT_FAILURE, EXIT_OK, EXIT_USAGE};
use crate::model::runfile::MotorSpec;
use crate::options::{FmuOptions, Steps};
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
