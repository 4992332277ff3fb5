//! The integration tests: two test binaries, `integration` (this file: every test
//! file but one) and `integration-stress` (`tests/main_stress.rs`: `stress.rs`, whose
//! double-double and 1000-link runs instantiate every algorithm for a second scalar
//! type and take as long to compile as all the rest), each `tests/NAME.rs` a module of
//! one of them: the suite is linked twice instead of once a file, and the two halves
//! compile side by side on two cores. Cargo.toml sets
//! `autotests = false`: a file under `tests/` is compiled only through a `mod` line,
//! and [`every_test_file_is_a_module`] fails for one that has none.
//!
//! Adding a test file `tests/NAME.rs`: one line `mod NAME;` here or in
//! `main_stress.rs`. Its helpers come from
//! `use crate::common::...` (an older `#[path = "common/lcg.rs"] mod lcg;` still works,
//! except for `counting_alloc`, the binary's one global allocator).
//! One module alone: `cargo test --release --test integration NAME::`.

mod common;

mod alloc;
mod ant_rest;
mod api;
mod bad_cli;
mod bad_inputs;
mod cli_errors;
mod cli_tour;
mod constraint_dynamics;
mod contact_pairs;
mod contact_spin;
mod derivatives;
mod doc_examples;
mod eval_constrained;
mod eval_singular;
mod example_scenes;
mod fast_dynamics;
mod islands;
mod joint_kinds;
mod kinematics_energy;
mod layering;
mod loops_sim;
mod mechanism_examples;
mod mimic_factor;
mod mjcf_actuators;
mod mjcf_bad;
mod mjcf_cli;
mod mjcf_equality;
mod mjcf_oracle;
mod mjcf_sim;
mod mjcf_view;
mod output_files;
mod pinocchio_derivatives;
mod pinocchio_fixtures;
mod rocking;
mod scene;
mod scene_bad;
mod scene_mjcf;
mod scene_physics;
mod seed_examples;
mod sensors;
mod servo;
mod sim;
mod sim_clone;
mod sim_no_alloc;
mod sim_trust;
mod simulate_cli;
mod simulate_trust;
mod sleep;
mod step_jacobians;
mod unit;
mod view;

/// Every `tests/*.rs` file is a module of this binary (with `autotests = false` a file
/// without its `mod` line would silently never be compiled or run).
#[test]
fn every_test_file_is_a_module() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let main = std::fs::read_to_string(dir.join("main.rs")).expect("tests/main.rs")
        + &std::fs::read_to_string(dir.join("main_stress.rs")).expect("tests/main_stress.rs");
    let mut missing = Vec::new();
    for e in std::fs::read_dir(&dir).expect("tests/") {
        let p = e.expect("entry").path();
        let Some(stem) = p.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if p.extension().is_some_and(|x| x == "rs")
            && stem != "main"
            && stem != "main_stress"
            && !main.lines().any(|l| l.trim() == format!("mod {stem};"))
        {
            missing.push(format!(
                "tests/{stem}.rs: add `mod {stem};` to tests/main.rs or tests/main_stress.rs"
            ));
        }
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}
