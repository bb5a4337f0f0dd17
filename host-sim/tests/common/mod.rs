//! Helpers shared by the test files (`golden.rs`, `batch.rs`, `sweep.rs`, `ccc_cli.rs`,
//! the bench logs' `replay.rs`, `replay_observer.rs` and `identify.rs`, ...: each uses a
//! part, hence the `dead_code` allowance).

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Runs the command line through the library; returns (exit code, stdout, stderr).
pub fn run(args: &[&str]) -> (u8, String, String) {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = host_sim::main_with(args.iter().copied(), &mut out, &mut err);
    (
        code,
        String::from_utf8(out).expect("utf-8 stdout"),
        String::from_utf8(err).expect("utf-8 stderr"),
    )
}

/// A fresh directory under the system's temp directory, unique to this process and
/// call, removed with its files when dropped.
pub struct TempDir {
    pub path: PathBuf,
}

impl TempDir {
    pub fn new(name: &str) -> TempDir {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("host-sim-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("create {}: {e}", path.display()));
        TempDir { path }
    }

    /// A path inside the directory, as a `&str` argument.
    pub fn join(&self, name: &str) -> String {
        utf8(&self.path.join(name)).to_string()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// A path as UTF-8 (the temp directory's paths are).
pub fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// Reads a file the test expects to exist.
pub fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("read {}: {e}", p.display()))
}

/// Every file of `dir` by name, with its bytes.
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("read dir {}: {e}", dir.display()))
        .map(|e| {
            let e = e.expect("dir entry");
            let name = e.file_name().into_string().expect("utf-8 file name");
            let bytes = read(&e.path());
            (name, bytes)
        })
        .collect()
}

/// A CSV that `host-sim run` wrote: its header and its rows of numbers, every field
/// parsed (an empty field is NaN). Panics, naming the row, when a row has another
/// column count than the header or a field is not a number: a cut or garbled file.
pub fn numeric_csv(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let names: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .enumerate()
        .map(|(k, l)| {
            let row: Vec<f64> = l
                .split(',')
                .map(|v| {
                    if v.is_empty() {
                        f64::NAN
                    } else {
                        v.parse()
                            .unwrap_or_else(|_| panic!("row {}: '{v}' is not a number", k + 1))
                    }
                })
                .collect();
            assert_eq!(
                row.len(),
                names.len(),
                "row {} has {} fields: {l}",
                k + 1,
                row.len()
            );
            row
        })
        .collect();
    (names, rows)
}

/// The number after `key` in `text` (up to the next space or comma), e.g. the
/// summary's `end - start - work = ` figure.
pub fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("'{key}' not in:\n{text}"));
    let rest = &text[at + key.len()..];
    let end = rest.find([' ', ',', ';', '\n']).unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("'{}' after '{key}' is not a number", &rest[..end]))
}

/// The path of `host-sim/tests/data/NAME` (the bench logs and their clutch logs).
pub fn data(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    p.to_str().expect("utf-8 path").to_string()
}

/// The bench's encoder law (its README): `floor(theta / (2π/4096))`.
pub fn counts(theta: f64) -> i64 {
    (theta / (std::f64::consts::TAU / 4096.0)).floor() as i64
}

/// The summary of `host-sim replay ARGS` (run through the library, as the command
/// line parses it).
pub fn replay_of(args: &[&str]) -> host_sim::run::replay::ReplaySummary {
    let cmd = host_sim::cli::parse_args([&["replay"][..], args].concat())
        .unwrap_or_else(|e| panic!("{e:?}"));
    let host_sim::cli::Command::Replay(opts) = cmd else {
        panic!("not a replay: {cmd:?}")
    };
    host_sim::run::replay::run(&opts).unwrap_or_else(|e| panic!("replay: {e}"))
}
