//! The README's Rust examples and src/lib.rs's first one, compiled into this test
//! binary and run here (rustdoc would compile them again, unoptimised and apart from
//! everything else: ~45 s of the README's `cargo test --release` for five blocks).
//! Each lives in `tests/doc_examples/NAME.rs`, and a test checks that the README and
//! lib.rs show exactly that code, so what a reader copies is what runs here.

use std::path::Path;

mod readme_dynamics {
    include!("doc_examples/readme_dynamics.rs");
    pub(super) fn run() -> Result<(), Box<dyn std::error::Error>> {
        main()
    }
}
mod readme_kinematics {
    include!("doc_examples/readme_kinematics.rs");
    pub(super) fn run() -> Result<(), Box<dyn std::error::Error>> {
        main()
    }
}
mod readme_simulation {
    include!("doc_examples/readme_simulation.rs");
    pub(super) fn run() -> Result<(), Box<dyn std::error::Error>> {
        main()
    }
}
mod lib_dynamics {
    include!("doc_examples/lib_dynamics.rs");
}

#[test]
fn the_readme_dynamics_example_runs() {
    readme_dynamics::run().expect("README's dynamics example");
}

#[test]
fn the_readme_kinematics_example_runs() {
    readme_kinematics::run().expect("README's kinematics example");
}

#[test]
fn the_readme_simulation_example_runs() {
    readme_simulation::run().expect("README's simulation example");
}

#[test]
fn the_lib_rs_dynamics_example_runs() {
    lib_dynamics::main().expect("src/lib.rs's first example");
}

fn read(rel: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The file's code without its first comment lines (the "verbatim" note).
fn code_of(rel: &str) -> String {
    read(rel)
        .lines()
        .skip_while(|l| l.starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// The README's ```rust blocks, in order.
fn rust_blocks(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur: Option<String> = None;
    for line in text.lines() {
        match (&mut cur, line) {
            (None, "```rust") => cur = Some(String::new()),
            (Some(_), "```") => out.push(cur.take().unwrap_or_default()),
            (Some(b), l) => {
                b.push_str(l);
                b.push('\n');
            }
            (None, _) => {}
        }
    }
    out
}

#[test]
fn the_readme_shows_exactly_the_code_tested_here() {
    let blocks = rust_blocks(&read("README.md"));
    let files = ["readme_dynamics", "readme_kinematics", "readme_simulation"];
    assert_eq!(
        blocks.len(),
        files.len(),
        "README's ```rust blocks: one file each under tests/doc_examples/"
    );
    for (block, name) in blocks.iter().zip(files) {
        let file = format!("tests/doc_examples/{name}.rs");
        assert_eq!(
            block,
            &code_of(&file),
            "README's block differs from {file}: edit both"
        );
    }
}

#[test]
fn lib_rs_shows_exactly_the_code_tested_here() {
    let lib = read("src/lib.rs");
    // The first ``` block of the crate docs, its `//! ` prefix off, hidden `# ` lines out.
    let mut lines = lib
        .lines()
        .skip_while(|l| l.trim() != "//! ```ignore")
        .skip(1);
    let mut shown = String::new();
    for l in lines.by_ref() {
        if l.trim() == "//! ```" {
            break;
        }
        let l = l
            .strip_prefix("//! ")
            .or_else(|| l.strip_prefix("//!"))
            .unwrap_or(l);
        if !l.starts_with("# ") {
            shown.push_str(l);
            shown.push('\n');
        }
    }
    // The file: the same lines indented inside `main`, then `Ok(())`.
    let code = code_of("tests/doc_examples/lib_dynamics.rs");
    let body: Vec<&str> = code.lines().collect();
    assert!(
        body.len() > 3,
        "tests/doc_examples/lib_dynamics.rs is empty"
    );
    let inner: String = body[1..body.len() - 2]
        .iter()
        .map(|l| format!("{}\n", l.strip_prefix("    ").unwrap_or(l)))
        .collect();
    assert_eq!(
        shown, inner,
        "src/lib.rs's first example differs from tests/doc_examples/lib_dynamics.rs: edit both"
    );
}
