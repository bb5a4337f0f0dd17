//! The layers of host-sim (the order in `src/lib.rs`'s docs): every `crate::` path in
//! `src/**/*.rs` names a module of the file's own layer or of one below it, never one
//! above and never the crate root's re-exports. Each file's layer is its top-level
//! module (`src/run/converter.rs` and `src/run/mod.rs` are `run`); `main.rs` uses the
//! library from outside, through `host_sim::`.

use std::fs;
use std::path::{Path, PathBuf};

/// The layers from the bottom, as `src/lib.rs` lists them.
const LAYERS: [&str; 8] = [
    "error", "draw", "model", "options", "output", "run", "jobs", "cli",
];

/// A file's top-level module: `src/run/mod.rs` → `run`, `src/error.rs` → `error`;
/// `None` for the crate root and the binary.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (name != "lib" && name != "main").then(|| name.to_string())
}

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| *l == module)
}

/// The code of a line: what comes before a `//` comment (doc comments included).
fn code(line: &str) -> &str {
    match line.find("//") {
        Some(k) => &line[..k],
        None => line,
    }
}

/// The top-level modules that `text` reaches through `crate::`: each `crate::name`,
/// and each name of a grouped `use crate::{a, b::c}`.
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    for (k, line) in text.lines().enumerate() {
        let line = code(line);
        let mut rest = line;
        while let Some(at) = rest.find("crate::") {
            let before = &rest[..at];
            // `$crate::` or `host_crate::` are not this crate's root.
            let bound = before
                .chars()
                .last()
                .is_none_or(|c| !(c.is_alphanumeric() || c == '_' || c == '$'));
            let after = &rest[at + "crate::".len()..];
            if bound {
                if let Some(group) = after.strip_prefix('{') {
                    let inner = group.split('}').next().unwrap_or("");
                    for part in inner.split(',') {
                        let name = ident(part.trim());
                        if !name.is_empty() {
                            found.push((k + 1, name));
                        }
                    }
                } else {
                    found.push((k + 1, ident(after)));
                }
            }
            rest = after;
        }
    }
    found
}

/// The upward (or root) imports of the file `file` of module `module`: `(line, what)`.
fn violations(module: &str, text: &str) -> Vec<(usize, String)> {
    let Some(own) = layer(module) else {
        return vec![(0, format!("module '{module}' is in no layer"))];
    };
    crate_paths(text)
        .into_iter()
        .filter_map(|(line, name)| match layer(&name) {
            Some(l) if l <= own => None,
            Some(l) => Some((
                line,
                format!(
                    "{module} (layer {own}) imports crate::{name} (layer {l}, above it)"
                ),
            )),
            None => Some((
                line,
                format!("{module} imports crate::{name}, which is no layer's module (the root's re-exports are for users outside)"),
            )),
        })
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("read src") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_module_imports_only_downward() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut checked = 0;
    let mut bad = Vec::new();
    for file in &files {
        let text = fs::read_to_string(file).expect("read a source file");
        let Some(module) = module_of(&src, file) else {
            continue;
        };
        assert!(
            !text.contains("super::super"),
            "{}: reaches above its folder with super::super",
            file.display()
        );
        for (line, what) in violations(&module, &text) {
            bad.push(format!("{}:{line}: {what}", file.display()));
        }
        checked += 1;
    }
    assert!(checked >= 25, "only {checked} files checked");
    assert!(bad.is_empty(), "upward imports:\n{}", bad.join("\n"));
}

// Every top-level module of lib.rs has a layer, and lib.rs's docs list the layers in
// this order.
#[test]
fn lib_docs_list_the_layers() {
    let lib = fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"))
        .expect("read lib.rs");
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    let mut sorted: Vec<&str> = LAYERS.to_vec();
    sorted.sort_unstable();
    let mut declared = modules.clone();
    declared.sort_unstable();
    assert_eq!(declared, sorted, "lib.rs's modules and the layers");
    let listed: Vec<String> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//! "))
        .filter_map(|l| {
            let (n, rest) = l.split_once(". [`")?;
            n.parse::<usize>().ok()?;
            rest.split('`').next().map(str::to_string)
        })
        .collect();
    assert_eq!(listed, LAYERS, "the layer list in lib.rs's docs");
}

// The check can fail: a synthetic upward import, a grouped one, a root re-export and a
// module in no layer are found; downward, same-layer, `super::` and commented paths
// are not.
#[test]
fn a_synthetic_upward_import_is_detected() {
    let upward = "use crate::error::RunError;\nuse crate::run::Report;\n";
    assert_eq!(
        violations("output", upward),
        [(
            2,
            "output (layer 4) imports crate::run (layer 5, above it)".to_string()
        )]
    );
    let grouped = "use crate::{model::scenarios::Source, cli::Command};";
    assert_eq!(violations("options", grouped).len(), 1);
    let inline = "    let x = crate::jobs::batch::run_one(o, p);";
    assert_eq!(violations("run", inline).len(), 1);
    let root = "use crate::run_jobs;";
    assert!(violations("jobs", root)[0].1.contains("no layer's module"));
    assert_eq!(violations("nowhere", "").len(), 1);
    let fine = "use crate::error::HINT;\nuse crate::run::mechanism::Summary;\nuse super::pool;\n\
                // see crate::cli\n/// [`crate::cli::main_with`]\nlet m = $crate::x;";
    assert_eq!(violations("jobs", fine), []);
}
