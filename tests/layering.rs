//! The one-way flow of the library's layers: spatial ← model ← urdf ← scene, with the
//! algorithms (dynamics, contact, sim) on top; mesh files read in `src/mesh`, below
//! the importers and contact, naming nothing else of the crate. No source file of `src/spatial`,
//! `src/model`, `src/urdf` or `src/scene` names a module above it (doc comments may link to
//! one); `src/spatial` does not name `model` or `urdf` either.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("source folder") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Lines of the files under `src/<layer>` (comments left out) naming any of `above`.
fn offending_lines(layer: &str, above: &[&str]) -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src")
        .join(layer);
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    assert!(!files.is_empty(), "no sources under {}", root.display());
    let mut bad = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).expect("source file");
        for (n, line) in text.lines().enumerate() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            for m in above {
                if code.contains(&format!("crate::{m}"))
                    || code.contains(&format!("super::super::{m}"))
                {
                    bad.push(format!("{}:{}: {line}", f.display(), n + 1));
                }
            }
        }
    }
    bad
}

#[test]
fn lower_layers_do_not_reach_up() {
    let mut bad = Vec::new();
    for layer in ["spatial", "model", "urdf", "mjcf", "scene"] {
        bad.extend(offending_lines(
            layer,
            &["dynamics", "contact", "sim", "cli"],
        ));
    }
    bad.extend(offending_lines("spatial", &["model", "urdf"]));
    // mesh files are read in a room below import and contact: it names no
    // other module, and contact names no importer
    bad.extend(offending_lines(
        "mesh",
        &[
            "spatial", "model", "urdf", "mjcf", "scene", "dynamics", "contact", "sim", "cli",
        ],
    ));
    bad.extend(offending_lines("contact", &["urdf", "mjcf", "scene"]));
    bad.extend(offending_lines("model", &["urdf", "mjcf", "scene"]));
    bad.extend(offending_lines("mjcf", &["urdf", "scene"]));
    bad.extend(offending_lines("urdf", &["scene"]));
    assert!(bad.is_empty(), "layering broken:\n{}", bad.join("\n"));
}

/// The checker finds what it looks for (a test that cannot fail is no test).
#[test]
fn the_checker_sees_a_violation() {
    // src/dynamics names crate::model, so "model" above "dynamics" is reported.
    assert!(!offending_lines("dynamics", &["model"]).is_empty());
}
