//! Round 28's bad-input tour of the command line (benches/pile_results.md): what
//! it found that the other CLI tests did not hold. A thread count too large to
//! start (it aborted the process), standard error or output closed under the
//! program (`urdyn ... 2>&1 | head -1` aborted it, `--list-integrators | head`
//! panicked), and a symlinked or FIFO output is written through, never replaced.

use crate::bad_inputs::{run_in, BIN};
use crate::common::refusal::assert_refused;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;
use urdyn::sim::{SimOptions, Simulation};

fn lamp() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/lamp.urdf")
}

/// A scene of the lamp falling on the ground, with `extra` top-level keys.
fn scene(dir: &Path, extra: &str) -> PathBuf {
    let p = dir.join("scene.json");
    let text = format!(
        r#"{{ {extra} "models": [{{ "name": "lamp", "urdf": "{}", "base": "floating", "position": [0, 0, 1] }}] }}"#,
        lamp().display()
    );
    std::fs::write(&p, text).unwrap();
    p
}

/// More threads than a process can start: `--threads`, a scene's `"threads"`
/// and `SimOptions::threads` are refused (at most 1024) before any is started;
/// 100000 aborted the process ("failed to set up alternative stack guard
/// page") with nothing written.
#[test]
fn too_many_threads_are_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "").display().to_string();
    let out = dir.path().join("t.csv").display().to_string();
    let l = lamp().display().to_string();
    let cases: [(&[&str], &[&str]); 2] = [
        (
            &["--scene", &s, "--threads", "100000"],
            &["scene.json", "--threads", "at most 1024", "100000"],
        ),
        (
            &[&l, "--threads", "5000"],
            &["lamp.urdf", "--threads", "5000"],
        ),
    ];
    for (args, expect) in cases {
        let mut a = vec!["simulate", "--duration", "0.01", "--out", &out];
        a.extend_from_slice(args);
        let r = run_in(dir.path(), &a, Duration::from_secs(60));
        assert_refused(&a.join(" "), r.code, &r.stdout, &r.stderr, expect);
        assert!(!Path::new(&out).exists(), "{a:?} wrote {out}");
    }
    let s = scene(dir.path(), r#""threads": 100000,"#)
        .display()
        .to_string();
    let a = ["simulate", "--duration", "0.01", "--scene", &s];
    let r = run_in(dir.path(), &a, Duration::from_secs(60));
    assert_refused(
        &a.join(" "),
        r.code,
        &r.stdout,
        &r.stderr,
        &["scene.json", "\"threads\"", "100000"],
    );
    // the library's own check, and the bound itself runs
    let model = urdyn::load_file(&lamp(), Default::default()).unwrap();
    let opts = |threads| SimOptions {
        threads,
        ..SimOptions::default()
    };
    let err = Simulation::new(model.clone(), opts(1025)).unwrap_err();
    assert!(err.to_string().contains("at most 1024 (got 1025)"), "{err}");
    assert!(Simulation::new(model, opts(1024)).is_ok());
}

/// A standard error or output whose reader has gone (`urdyn ... 2>&1 | head -1`)
/// is no crash: the run's own exit status stands when only its messages are
/// lost (it aborted, status 134, as `eprintln!` panicked and the panic hook's
/// `eprintln!` panicked again), and a listing on a closed stdout is one line
/// on stderr and status 1 (it was "internal error ... failed printing").
#[test]
fn a_closed_stderr_or_stdout_is_no_crash() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "").display().to_string();
    let closed = || {
        let (r, w) = std::io::pipe().unwrap();
        drop(r);
        w
    };
    // warnings (the lamp starts inside the ground) and the summary, all lost
    let st = Command::new(BIN)
        .args([
            "simulate",
            "--duration",
            "0.02",
            "--out",
            "/dev/null",
            "--scene",
            &s,
        ])
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .stderr(closed())
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(0), "{st:?}");
    // an error whose line is lost: still status 1
    let st = Command::new(BIN)
        .args(["simulate", "--scene", "missing.json"])
        .current_dir(dir.path())
        .stderr(closed())
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(1), "{st:?}");
    // a listing on a closed stdout
    let o = Command::new(BIN)
        .args(["simulate", "--list-integrators"])
        .stdout(closed())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_refused(
        "--list-integrators > closed",
        o.status.code(),
        "",
        &err,
        &["Broken pipe"],
    );
}

/// An output path that is a symlink is written through (the link stays, its
/// target holds the CSV); a FIFO's reader gets the CSV in place.
#[test]
fn a_symlink_or_fifo_output_is_written_through_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "").display().to_string();
    let (target, link) = (dir.path().join("target.csv"), dir.path().join("link.csv"));
    std::fs::write(&target, "previous").unwrap();
    std::os::unix::fs::symlink("target.csv", &link).unwrap();
    let l = link.display().to_string();
    let a = ["simulate", "--duration", "0.01", "--scene", &s, "--out", &l];
    let r = run_in(dir.path(), &a, Duration::from_secs(60));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&target).unwrap().starts_with("t,"));
    let fifo = dir.path().join("fifo.csv");
    let st = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(st.success());
    let f = fifo.clone();
    let reader = std::thread::spawn(move || std::fs::read_to_string(f).unwrap());
    let o = fifo.display().to_string();
    let a = ["simulate", "--duration", "0.01", "--scene", &s, "--out", &o];
    let r = run_in(dir.path(), &a, Duration::from_secs(60));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(reader.join().unwrap().starts_with("t,"));
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
}

/// An output naming one of the command's inputs, or the other output, is
/// refused before anything runs, the input untouched: `simulate --scene s.json
/// --out s.json` replaced the scene with the trajectory (and `eval --output`,
/// `view --out` their URDF or CSV). `/dev/null` may take both outputs.
#[test]
fn an_output_naming_an_input_is_refused_and_the_input_kept() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "").display().to_string();
    let text = std::fs::read_to_string(&s).unwrap();
    let urdf = dir.path().join("lamp.urdf");
    std::fs::copy(lamp(), &urdf).unwrap();
    let u = urdf.display().to_string();
    let urdf_text = std::fs::read_to_string(&urdf).unwrap();
    let states = dir.path().join("states.json");
    std::fs::write(&states, r#"{"states": [{}]}"#).unwrap();
    let st = states.display().to_string();
    let traj = dir.path().join("t.csv").display().to_string();
    let ok = [
        "simulate",
        "--duration",
        "0.01",
        "--scene",
        &s,
        "--out",
        &traj,
    ];
    let r = run_in(dir.path(), &ok, Duration::from_secs(60));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let traj_text = std::fs::read_to_string(&traj).unwrap();
    fn sim<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        let mut v = vec!["simulate", "--duration", "0.01"];
        v.extend_from_slice(extra);
        v
    }
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            sim(&["--scene", &s, "--out", "scene.json"]),
            vec!["--out scene.json", "--scene"],
        ),
        (
            sim(&["--scene", &s, "--out", "a.csv", "--html", "./a.csv"]),
            vec!["--html ./a.csv", "--out a.csv"],
        ),
        (
            sim(&["--scene", &s, "--html", &s]),
            vec!["--html", "--scene"],
        ),
        (
            sim(&[&u, "--out", "lamp.urdf"]),
            vec!["--out lamp.urdf", "the model"],
        ),
        (
            vec!["eval", &u, "--states", &st, "--output", &st],
            vec!["--output", "--states"],
        ),
        (
            vec!["view", "--scene", &s, &traj, "--out", &traj],
            vec!["--out", "the trajectory"],
        ),
        (
            vec!["view", &u, &traj, "--out", "lamp.urdf"],
            vec!["--out lamp.urdf", "the model"],
        ),
    ];
    for (a, expect) in &cases {
        let r = run_in(dir.path(), a, Duration::from_secs(60));
        assert_refused(&a.join(" "), r.code, &r.stdout, &r.stderr, expect);
        assert!(r.stderr.contains("not overwritten"), "{}", r.stderr);
    }
    assert_eq!(std::fs::read_to_string(&s).unwrap(), text);
    assert_eq!(std::fs::read_to_string(&urdf).unwrap(), urdf_text);
    assert_eq!(std::fs::read_to_string(&traj).unwrap(), traj_text);
    assert!(!dir.path().join("a.csv").exists());
    let a = sim(&["--scene", &s, "--out", "/dev/null", "--html", "/dev/null"]);
    let r = run_in(dir.path(), &a, Duration::from_secs(60));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}
