//! A newcomer's command-line mistakes (issue 20, item 4), each answered by the
//! real `urdyn` binary with one line on standard error that names the argument
//! and what was expected, nothing on standard output and a non-zero exit: a
//! misspelt option or subcommand gets clap's "did you mean", a list option given
//! as separate values names its form, a required option's value given as a
//! positional names the option, and a missing collision mesh names the CLI's
//! flags (the library's own message names none).

use crate::common::refusal::assert_refused;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_urdyn");

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs `urdyn ARGS` in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> Run {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .env_remove("ROS_PACKAGE_PATH")
        .stdin(Stdio::null())
        .output()
        .expect("spawn urdyn");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Asserts the contract of a refused command line (non-zero exit, one line on
/// stderr holding every `expect` substring, empty stdout, no panic) and returns
/// the line.
fn refused_in(dir: &Path, args: &[&str], expect: &[&str]) -> String {
    let r = run_in(dir, args);
    let ctx = format!("urdyn {}", args.join(" "));
    assert_refused(&ctx, r.code, &r.stdout, &r.stderr, expect)
}

fn refused(args: &[&str], expect: &[&str]) -> String {
    refused_in(&root(), args, expect)
}

#[test]
fn a_misspelt_option_gets_did_you_mean() {
    let line = refused(
        &["inspect", "assets/robots/ur5.urdf", "--floating-bse"],
        &["'--floating-bse'", "did you mean '--floating-base'?"],
    );
    assert!(line.starts_with("urdyn: "), "{line}");
    refused(
        &["simulate", "assets/lamp.urdf", "--no-gruond"],
        &["'--no-gruond'", "did you mean '--no-ground'?"],
    );
    refused(
        &["eval", "assets/robots/ur5.urdf", "--state", "x.json"],
        &["'--state'", "did you mean '--states'?"],
    );
}

#[test]
fn a_misspelt_subcommand_gets_did_you_mean() {
    refused(
        &["inspct", "assets/robots/ur5.urdf"],
        &["'inspct'", "did you mean 'inspect'?"],
    );
    refused(
        &["simulat", "assets/lamp.urdf"],
        &["'simulat'", "did you mean 'simulate'?"],
    );
}

#[test]
fn gravity_as_three_arguments_names_the_form() {
    // the URDF before the option: clap trips on the second number
    refused(
        &[
            "simulate",
            "assets/lamp.urdf",
            "--gravity",
            "0",
            "0",
            "-9.81",
        ],
        &[
            "--gravity",
            "GX,GY,GZ",
            "--gravity 0,0,-9.81",
            "3 separate values",
        ],
    );
    // the URDF after it: the second number is taken for the URDF, the third for a flag
    refused(
        &[
            "simulate",
            "--gravity",
            "0",
            "0",
            "-9.81",
            "assets/lamp.urdf",
        ],
        &["--gravity", "GX,GY,GZ", "--gravity 0,0,-9.81"],
    );
    // two numbers given apart
    refused(
        &["simulate", "assets/lamp.urdf", "--gravity", "0", "-9.81"],
        &["--gravity", "GX,GY,GZ", "2 separate values"],
    );
    // one comma-separated list of the wrong length: the binary's own check
    refused(
        &["simulate", "assets/lamp.urdf", "--gravity", "0,-9.81"],
        &["--gravity", "GX,GY,GZ"],
    );
}

#[test]
fn gravity_in_the_expected_form_runs() {
    let dir = std::env::temp_dir().join(format!("urdyn-cli-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("g.csv");
    let lamp = root().join("assets/lamp.urdf");
    let r = run_in(
        &dir,
        &[
            "simulate",
            lamp.to_str().unwrap(),
            "--gravity",
            "0,0,-1.5",
            "--duration",
            "0.01",
            "--no-ground",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(r.code, Some(0), "stderr {:?}", r.stderr);
    assert!(std::fs::metadata(&out).is_ok_and(|m| m.len() > 0));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn eval_states_as_a_positional_names_the_option() {
    refused(
        &[
            "eval",
            "assets/robots/ur5.urdf",
            "tests/fixtures/ur5/states.json",
        ],
        &[
            "eval",
            "'tests/fixtures/ur5/states.json'",
            "--states STATES.json",
            "--states tests/fixtures/ur5/states.json",
        ],
    );
    // with --states given, a second stray file is plainly unexpected
    let line = refused(
        &[
            "eval",
            "assets/robots/ur5.urdf",
            "--states",
            "tests/fixtures/ur5/states.json",
            "extra.json",
        ],
        &["'extra.json'"],
    );
    assert!(!line.contains("give it with --states"), "{line}");
}

#[test]
fn a_missing_urdf_names_the_path() {
    refused(
        &[
            "eval",
            "assets/robots/no_such_robot.urdf",
            "--states",
            "x.json",
        ],
        &["assets/robots/no_such_robot.urdf", "cannot read file"],
    );
    refused(
        &["inspect", "no_such_robot.urdf"],
        &["no_such_robot.urdf", "cannot read file"],
    );
}

#[test]
fn a_missing_collision_mesh_names_the_cli_flags() {
    refused_in(
        &root().join("tests/bad"),
        &[
            "simulate",
            "sim_missing_mesh.urdf",
            "--floating-base",
            "--duration",
            "0.01",
        ],
        &[
            "sim_missing_mesh.urdf",
            "foot_missing.stl",
            "not found",
            "--package-path",
            "--no-ground",
        ],
    );
}
