//! The board's memory layout for cortex-m-rt's `link.x`, written into OUT_DIR: the core
//! and the repository stay board-agnostic (no `memory.x` anywhere in the sources).
//!
//! Both MPS2 images QEMU models here map ZBT SSRAM1 (4 MiB, where the image is loaded)
//! at 0x0000_0000 and ZBT SSRAM2/3 (4 MiB) at 0x2000_0000 (QEMU 7.2 `info mtree` of
//! `mps2-an386` and `mps2-an500`; ARM AN386 and AN500). The stack starts at the top of
//! SSRAM2/3 and grows down towards the statics.
use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
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
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out.join("memory.x"), memory).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
}
