//! On a bare-metal target there is no C runtime to call `main`: make it the ELF entry
//! point, so that the linker's section garbage collection keeps everything reachable
//! from it (and nothing else). No linker script is needed: the check only links, it is
//! never flashed.
fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    if target.contains("-none") {
        println!("cargo:rustc-link-arg-bins=--entry=main");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
