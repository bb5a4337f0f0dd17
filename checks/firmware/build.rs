//! Two files written into OUT_DIR:
//!
//! - `identified.rs` (every build): bench1's identified converter, read from
//!   `host-sim/tests/data/known-machine.toml` (the run file `host-sim identify` wrote for
//!   bench1, which the PC's `replay --params` reads), so that the firmware's
//!   `bench1-identified` run is that file's converter with no copy of its numbers to
//!   keep in step (`identified_converter`, and `identified_start` the file's initial
//!   angles and speeds). A key of its `[converter]` this script does not know fails
//!   the build.
//! - `memory.x` (target builds): the board's memory layout for cortex-m-rt's `link.x`:
//!   the core and the repository stay board-agnostic (no `memory.x` anywhere in the
//!   sources).
//!
//! Both MPS2 images QEMU models here map ZBT SSRAM1 (4 MiB, where the image is loaded)
//! at 0x0000_0000 and ZBT SSRAM2/3 (4 MiB) at 0x2000_0000 (QEMU 7.2 `info mtree` of
//! `mps2-an386` and `mps2-an500`; ARM AN386 and AN500). The stack starts at the top of
//! SSRAM2/3 and grows down towards the statics.
use std::env;
use std::fs;
use std::path::{Path, PathBuf};

/// bench1's identified run file, from this crate's folder.
const KNOWN_MACHINE: &str = "../../host-sim/tests/data/known-machine.toml";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed={KNOWN_MACHINE}");
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let text = fs::read_to_string(KNOWN_MACHINE).unwrap_or_else(|e| panic!("{KNOWN_MACHINE}: {e}"));
    let code = identified(&text).unwrap_or_else(|e| panic!("{KNOWN_MACHINE}: {e}"));
    fs::write(out.join("identified.rs"), code).expect("OUT_DIR is writable");
    memory_layout(&out);
}

/// A number of the run file (an integer or a float).
fn float(v: &toml::Value, key: &str) -> Result<f64, String> {
    match v {
        toml::Value::Float(x) => Ok(*x),
        toml::Value::Integer(i) => Ok(*i as f64),
        _ => Err(format!("`{key}` is not a number")),
    }
}

/// A number of the run file as Rust source that keeps its bits: Rust's `{:?}` of an
/// f64 is the shortest decimal that reads back to it.
fn number(v: &toml::Value, key: &str) -> Result<String, String> {
    Ok(format!("T::c({:?})", float(v, key)?))
}

/// A pair `[x, y]` of the run file as a `Vec2`.
fn pair(v: &toml::Value, key: &str) -> Result<String, String> {
    match v.as_array().map(|a| a.as_slice()) {
        Some([x, y]) => Ok(format!(
            "Vec2::new({}, {})",
            number(x, key)?,
            number(y, key)?
        )),
        _ => Err(format!("`{key}` is not a pair of numbers")),
    }
}

/// A string value among `names`, as the Rust path `prefix` + the matching variant.
fn variant(v: &toml::Value, key: &str, names: &[(&str, &str)]) -> Result<String, String> {
    let s = v.as_str().ok_or(format!("`{key}` is not a string"))?;
    names
        .iter()
        .find(|(n, _)| *n == s)
        .map(|(_, path)| path.to_string())
        .ok_or(format!("`{key}` = {s:?} is none of {names:?}"))
}

/// `identified_converter`, the converter of the run file `text`: SPEC's
/// (`CccParams::reference`) with every value the file's `[converter]` gives.
fn identified(text: &str) -> Result<String, String> {
    let doc: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    let conv = doc
        .get("converter")
        .and_then(|c| c.as_table())
        .ok_or("no [converter] table")?;
    let (mut set, mut start) = (Vec::new(), Vec::new());
    for (key, v) in conv {
        let k = key.as_str();
        match k {
            "a" | "f" | "h" | "gravity" => set.push(format!("p.{k} = {};", pair(v, k)?)),
            "rocker_d" | "mass" | "mass_inertia" | "mass_at" | "shaft_inertia" => {
                set.push(format!("p.{k} = {};", number(v, k)?))
            }
            "branch_c" | "branch_g" | "branch_i" => {
                let side = [("left", "Side::Left"), ("right", "Side::Right")];
                set.push(format!("p.{k} = {};", variant(v, k, &side)?))
            }
            "drive" => {
                let d = [("cw", "DriveDirection::Cw"), ("ccw", "DriveDirection::Ccw")];
                set.push(format!("p.drive = {};", variant(v, k, &d)?))
            }
            // The start, converted as host-sim's run files are (degrees to radians
            // in f64, then to `T`).
            "crank_deg" | "swing_deg" => {
                let (angle, deg) = (&k[..5], float(v, k)?);
                start.push(format!("s.{angle} = T::c({deg:?}_f64.to_radians());"))
            }
            "crank_speed" | "swing_speed" => start.push(format!("s.{k} = {};", number(v, k)?)),
            "link" => {
                let links = v.as_array().ok_or("`link` is not an array of tables")?;
                if links.len() != 8 {
                    return Err(format!("{} links, not 8", links.len()));
                }
                for (i, l) in links.iter().enumerate() {
                    let l = l.as_table().ok_or("a `link` is not a table")?;
                    for (field, x) in l {
                        match field.as_str() {
                            "length" | "mass" | "inertia" => {
                                set.push(format!("p.links[{i}].{field} = {};", number(x, field)?))
                            }
                            other => return Err(format!("link key `{other}` unknown")),
                        }
                    }
                }
            }
            "friction" => {
                let f = v.as_table().ok_or("`friction` is not a table")?;
                for (field, x) in f {
                    match field.as_str() {
                        "viscous" | "coulomb" => {
                            let joints = x.as_table().ok_or("friction joints not a table")?;
                            for (joint, c) in joints {
                                set.push(format!(
                                    "p.friction.{field}[const {{ friction_joint({joint:?}) }}] = {};",
                                    number(c, joint)?
                                ));
                            }
                        }
                        "coulomb_eps" | "clutch_drag" => {
                            set.push(format!("p.friction.{field} = {};", number(x, field)?))
                        }
                        other => return Err(format!("friction key `{other}` unknown")),
                    }
                }
            }
            other => {
                return Err(format!(
                    "[converter] key `{other}` unknown to the firmware's build"
                ))
            }
        }
    }
    let mut code = String::from(
        "/// bench1's identified converter: SPEC's with the values of\n\
         /// `host-sim/tests/data/known-machine.toml` (written by `build.rs`).\n\
         pub fn identified_converter<T: Real>() -> CccParams<T> {\n    \
         let mut p = CccParams::reference();\n",
    );
    for line in set {
        code.push_str("    ");
        code.push_str(&line);
        code.push('\n');
    }
    code.push_str("    p\n}\n\n");
    code.push_str(
        "/// The start of `known-machine.toml`'s run: `s` with its initial angles and\n\
         /// speeds (written by `build.rs`).\n\
         pub fn identified_start<T: Real>(s: &mut TwinSettings<T>) {\n",
    );
    for line in start {
        code.push_str("    ");
        code.push_str(&line);
        code.push('\n');
    }
    code.push_str("}\n");
    Ok(code)
}

/// The board's `memory.x` into `out` (target builds only).
fn memory_layout(out: &Path) {
    let target = env::var("TARGET").unwrap_or_default();
    if !target.contains("-none") {
        return;
    }
    let an386 = env::var_os("CARGO_FEATURE_MPS2_AN386").is_some();
    let an500 = env::var_os("CARGO_FEATURE_MPS2_AN500").is_some();
    let memory = match (an386, an500) {
        (true, false) => {
            "/* mps2-an386 (Cortex-M4F): ZBT SSRAM1 and ZBT SSRAM2/3 */\n\
             MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  \
             RAM : ORIGIN = 0x20000000, LENGTH = 4M\n}\n"
        }
        (false, true) => {
            "/* mps2-an500 (Cortex-M7): ZBT SSRAM1 and ZBT SSRAM2/3 */\n\
             MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  \
             RAM : ORIGIN = 0x20000000, LENGTH = 4M\n}\n"
        }
        _ => panic!("build for {target} with exactly one board feature: mps2-an386 or mps2-an500"),
    };
    fs::write(out.join("memory.x"), memory).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
}
