//! The command line's bad inputs (split from `bad_inputs.rs`, whose corpus of
//! malformed files and states this shares the runner of): option errors, output
//! files never half written or special files replaced, mesh paths and external
//! entities never opened, a 50 MB URDF answered, `simulate` and `bench` refusals —
//! each a non-zero exit with one line naming the option, file or key, and no panic.

use crate::bad_inputs::{assert_rejected, bad_dir, run, run_in};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

#[test]
fn cli_errors_are_one_line() {
    assert_rejected(
        &["eval", "ok.urdf", "--states", "states_one.json", "--bogus"],
        &["--bogus"],
    );
    assert_rejected(&["frobnicate", "ok.urdf"], &["frobnicate"]);
    assert_rejected(
        &["eval", "missing.urdf", "--states", "states_one.json"],
        &["missing.urdf", "cannot read"],
    );
    assert_rejected(&["inspect", "missing.urdf"], &["missing.urdf"]);
    assert_rejected(
        &["eval", "ok.urdf", "--states", "missing.json"],
        &["missing.json", "cannot read"],
    );
    assert_rejected(
        &["eval", "../bad", "--states", "states_one.json"],
        &["../bad", "directory"],
    );
    assert_rejected(
        &["eval", "ok.urdf", "--states", "../bad"],
        &["../bad", "directory"],
    );
    assert_rejected(&["eval", "ok.urdf"], &["--states"]);
    assert_rejected(
        &[
            "eval",
            "ok.urdf",
            "--states",
            "states_one.json",
            "--output",
            "/nonexistent-dir/out.json",
        ],
        &["/nonexistent-dir/out.json"],
    );
    // /proc takes no new files, whoever runs the test (root included).
    assert_rejected(
        &[
            "eval",
            "ok.urdf",
            "--states",
            "states_one.json",
            "--output",
            "/proc/urdyn-out.json",
        ],
        &["/proc/urdyn-out.json", "cannot write"],
    );
    assert_rejected(
        &[
            "eval",
            "ok.urdf",
            "--states",
            "states_one.json",
            "--output",
            "../bad",
        ],
        &["../bad", "directory"],
    );
}

/// `--output` failures leave no file and no temporary file; an existing output is
/// left as it was.
#[test]
fn failures_leave_no_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.json");
    let bad = bad_dir();
    let b = |f: &str| bad.join(f).display().to_string();
    let cases: &[(&str, &str)] = &[
        ("ok.urdf", "states_unknown_joint.json"), // state 1 is bad, state 0 fine
        ("singular_at_zero.urdf", "states_singular_second.json"), // fails computing state 1
        ("massless_joint.urdf", "states_one.json"),
        ("truncated.urdf", "states_one.json"),
        ("ok.urdf", "states_trailing.json"),
    ];
    for (urdf, states) in cases {
        let (o, u, st) = (out.display().to_string(), b(urdf), b(states));
        let args = ["eval", &u, "--states", &st, "--output", &o];
        let r = run_in(dir.path(), &args, Duration::from_secs(60));
        assert_ne!(r.code, Some(0));
        assert!(r.stdout.is_empty());
        assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{urdf} {states}: left {left:?}");
        // With an existing output file: untouched.
        std::fs::write(&out, "previous").unwrap();
        let r = run_in(dir.path(), &args, Duration::from_secs(60));
        assert_ne!(r.code, Some(0));
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        std::fs::remove_file(&out).unwrap();
    }
    // Success writes the same bytes as stdout, and nothing else.
    let (o, u, st) = (out.display().to_string(), b("ok.urdf"), b("states_ok.json"));
    let ok = run_in(
        dir.path(),
        &["eval", &u, "--states", &st, "--output", &o],
        Duration::from_secs(60),
    );
    assert_eq!(ok.code, Some(0), "{}", ok.stderr);
    assert!(ok.stdout.is_empty());
    let stdout = run(&["eval", "ok.urdf", "--states", "states_ok.json"]).stdout;
    assert_eq!(std::fs::read_to_string(&out).unwrap(), stdout);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

fn mkfifo(path: &Path) {
    let st = Command::new("mkfifo").arg(path).status().expect("mkfifo");
    assert!(st.success());
}

/// Mesh paths (absolute, `file://`, `..`) are never opened by eval or inspect: a
/// FIFO as a mesh would block any reader, and the run must finish.
#[test]
fn mesh_files_are_never_opened() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("mesh.fifo");
    mkfifo(&fifo);
    let text = std::fs::read_to_string(bad_dir().join("mesh_fifo.urdf.in"))
        .unwrap()
        .replace("@FIFO@", &fifo.display().to_string());
    std::fs::write(dir.path().join("robot.urdf"), text).unwrap();
    std::fs::copy(bad_dir().join("states_one.json"), dir.path().join("s.json")).unwrap();
    let limit = Duration::from_secs(20);
    for args in [
        vec!["eval", "robot.urdf", "--states", "s.json"],
        vec![
            "eval",
            "robot.urdf",
            "--states",
            "s.json",
            "--floating-base",
        ],
        vec!["inspect", "robot.urdf"],
    ] {
        let r = run_in(dir.path(), &args, limit);
        assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
    }
    let r = run(&["eval", "mesh_dotdot.urdf", "--states", "states_one.json"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

/// An external entity pointing at a FIFO: it is rejected from the DOCTYPE, never read.
#[test]
fn external_entity_is_never_read() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("secret.fifo");
    mkfifo(&fifo);
    let text = format!(
        "<?xml version=\"1.0\"?>\n<!DOCTYPE robot [ <!ENTITY x SYSTEM \"file://{}\"> ]>\n<robot name=\"&x;\"><link name=\"a\"/></robot>\n",
        fifo.display()
    );
    std::fs::write(dir.path().join("r.urdf"), text).unwrap();
    let r = run_in(dir.path(), &["inspect", "r.urdf"], Duration::from_secs(20));
    assert_ne!(r.code, Some(0));
    assert_eq!(r.stderr.lines().count(), 1);
    assert!(r.stderr.contains("r.urdf") && r.stderr.contains("<!DOCTYPE>"));
}

/// A 50 MB URDF (a chain of ~130 000 links) is answered in under 120 s wall (a
/// quadratic pass over its links would take hours; the optimised build takes a few
/// seconds on an idle machine, 30 s on a loaded one) and 1 GiB: `inspect` describes
/// it, `eval` refuses its dense output.
#[test]
fn fifty_megabyte_urdf_is_answered() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.urdf");
    let mut s = String::with_capacity(52_000_000);
    s.push_str("<?xml version=\"1.0\"?>\n<robot name=\"big\">\n");
    let mut i = 0usize;
    while s.len() < 50_000_000 {
        s.push_str(&format!(
            "<link name=\"link_{i}\"><inertial><origin xyz=\"0 0 0.1\" rpy=\"0 0 0\"/><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial></link>\n"
        ));
        if i > 0 {
            s.push_str(&format!(
                "<joint name=\"joint_{i}\" type=\"revolute\"><parent link=\"link_{}\"/><child link=\"link_{i}\"/><origin xyz=\"0 0 0.2\" rpy=\"0 0 0\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n",
                i - 1
            ));
        }
        i += 1;
    }
    s.push_str("</robot>\n");
    std::fs::write(&path, &s).unwrap();
    drop(s);
    std::fs::write(dir.path().join("s.json"), "{\"states\": [{}]}").unwrap();
    // A wall-clock bound against a blow-up, not a speed test (the suite runs in the
    // release profile on a shared machine).
    let limit = 120;
    let e = run_in(
        dir.path(),
        &["eval", "big.urdf", "--states", "s.json"],
        Duration::from_secs(150),
    );
    assert_ne!(e.code, Some(0));
    assert!(e.stdout.is_empty());
    assert_eq!(e.stderr.lines().count(), 1, "{}", e.stderr);
    assert!(e.stderr.contains("big.urdf") && e.stderr.contains("degrees of freedom"));
    let r = run_in(
        dir.path(),
        &["inspect", "big.urdf"],
        Duration::from_secs(150),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.contains(&format!("link_{}", i - 1)));
    for (what, run) in [("eval", &e), ("inspect", &r)] {
        eprintln!(
            "50 MB URDF ({i} links), {what}: {:.2} s, peak RSS {:?} kB",
            run.elapsed.as_secs_f64(),
            run.peak_rss_kb
        );
        assert!(
            run.elapsed < Duration::from_secs(limit),
            "{what} took {:?}",
            run.elapsed
        );
        if let Some(kb) = run.peak_rss_kb {
            assert!(kb < 1024 * 1024, "{what}: peak RSS {kb} kB");
        }
    }
}

/// `evaluate_json` (what the binary prints) is byte for byte the serialisation of
/// `evaluate` (what library users get).
#[test]
fn evaluate_json_matches_evaluate() {
    let bad = bad_dir();
    for fb in [false, true] {
        let model = urdyn::load_file(
            bad.join("ok.urdf"),
            urdyn::LoadOptions { floating_base: fb },
        )
        .unwrap();
        let text = std::fs::read_to_string(bad.join("states_ok.json")).unwrap();
        let states = urdyn::cli::state::parse_states(&text, "s").unwrap();
        let v = urdyn::cli::eval::evaluate(&model, &states, "u", "s").unwrap();
        let j = urdyn::cli::eval::evaluate_json(&model, &states, "u", "s").unwrap();
        assert_eq!(serde_json::to_string(&v).unwrap(), j);
    }
}

/// 200 000 nested elements inside a link: rejected naming the link (before the
/// depth limit, dropping the element tree overflowed the stack and aborted).
#[test]
fn deep_nesting_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let n = 200_000;
    let text = format!(
        "<robot name=\"d\"><link name=\"a\">{}{}</link></robot>\n",
        "<x>".repeat(n),
        "</x>".repeat(n)
    );
    std::fs::write(dir.path().join("deep.urdf"), text).unwrap();
    let r = run_in(
        dir.path(),
        &["inspect", "deep.urdf"],
        Duration::from_secs(60),
    );
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(r.stdout.is_empty());
    assert_eq!(r.stderr.lines().count(), 1);
    assert!(r.stderr.contains("deep.urdf") && r.stderr.contains("link \"a\""));
}

/// `urdyn simulate` (run in tests/bad; the lamp is `../../assets/lamp.urdf`): every
/// bad option, file or key is one line naming it.
#[test]
fn simulate_bad_inputs_are_one_line() {
    let lamp = "../../assets/lamp.urdf";
    let s = |args: &[&str], expect: &[&str]| {
        let mut a = vec!["simulate"];
        a.extend_from_slice(args);
        assert_rejected(&a, expect);
    };
    // CLI shape and files
    s(&["sim_ok.urdf", "--bogus"], &["--bogus"]);
    s(&[], &["URDF"]);
    s(&["missing.urdf"], &["missing.urdf", "cannot read"]);
    s(&["../bad"], &["../bad", "directory"]);
    s(&["not_xml.urdf"], &["not_xml.urdf"]);
    s(
        &["massless_joint.urdf"],
        &["massless_joint.urdf", "\"wrist\"", "massless"],
    );
    // --initial
    s(
        &["sim_ok.urdf", "--initial", "missing.json"],
        &["missing.json", "cannot read"],
    );
    s(
        &["sim_ok.urdf", "--initial", "../bad"],
        &["../bad", "directory"],
    );
    s(
        &["sim_ok.urdf", "--initial", "states_not_json.json"],
        &["states_not_json.json", "not valid JSON"],
    );
    s(
        &["sim_ok.urdf", "--initial", "initial_bad_key.json"],
        &["initial_bad_key.json", "bogus"],
    );
    s(
        &["sim_ok.urdf", "--initial", "initial_a.json"],
        &["initial_a.json", ": a:", "not allowed"],
    );
    s(
        &["sim_ok.urdf", "--initial", "initial_fext.json"],
        &["initial_fext.json", ": fext:", "not allowed"],
    );
    s(
        &["sim_ok.urdf", "--initial", "initial_gravity.json"],
        &["initial_gravity.json", "gravity"],
    );
    s(
        &["sim_ok.urdf", "--initial", "states_ok.json"],
        &["states_ok.json", "states"],
    );
    s(
        &[
            lamp,
            "--floating-base",
            "--initial",
            "initial_base_acc.json",
        ],
        &[
            "initial_base_acc.json",
            "angular_acceleration",
            "not allowed",
        ],
    );
    // numeric options: non-finite, negative, zero
    for (opt, vals) in [
        ("--dt", &["nan", "inf", "-1", "0", "-inf"][..]),
        ("--duration", &["nan", "inf", "-1"][..]),
        ("--friction", &["nan", "inf", "-0.5"][..]),
        ("--tol", &["nan", "inf", "-1", "0"][..]),
        ("--every", &["0", "-1", "1.5"][..]),
        ("--ground", &["nan", "inf"][..]),
        ("--gravity", &["nan,0,0", "0,0", "0,0,-9.81,1", "0,x,0"][..]),
    ] {
        for v in vals {
            let arg = format!("{opt}={v}");
            s(&[lamp, "--floating-base", &arg], &[opt]);
        }
    }
    s(
        &[lamp, "--integrator", "leapfrog"],
        &["--integrator", "leapfrog"],
    );
    // unwritable or impossible --out
    s(
        &[
            "sim_ok.urdf",
            "--duration",
            "0.01",
            "--out",
            "/nonexistent-dir/t.csv",
        ],
        &["/nonexistent-dir/t.csv"],
    );
    s(
        &[
            "sim_ok.urdf",
            "--duration",
            "0.01",
            "--out",
            "/proc/urdyn-t.csv",
        ],
        &["/proc/urdyn-t.csv"],
    );
    s(
        &["sim_ok.urdf", "--duration", "0.01", "--out", "../bad"],
        &["../bad", "directory"],
    );
    // a collision mesh that cannot be found, needed for ground contact
    s(
        &[
            "sim_missing_mesh.urdf",
            "--floating-base",
            "--duration",
            "0.01",
        ],
        &["sim_missing_mesh.urdf", "foot_missing.stl", "\"foot\""],
    );
}

/// `urdyn simulate --out` failing before or during the run leaves no file (and an
/// existing file untouched); a run that succeeds writes only the file.
#[test]
fn simulate_failures_leave_no_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.csv");
    let bad = bad_dir();
    let b = |f: &str| bad.join(f).display().to_string();
    let o = out.display().to_string();
    let lamp = b("../../assets/lamp.urdf");
    let cases: Vec<Vec<String>> = vec![
        vec![
            b("sim_ok.urdf"),
            "--initial".into(),
            b("initial_bad_key.json"),
        ],
        vec![b("sim_ok.urdf"), "--dt=nan".into()],
        vec![b("sim_missing_mesh.urdf"), "--floating-base".into()],
        vec![b("truncated.urdf")],
        // fails mid-run: 1e300 N on the base overflows the state
        vec![
            lamp.clone(),
            "--floating-base".into(),
            "--initial".into(),
            b("initial_huge_force.json"),
        ],
    ];
    for case in &cases {
        let mut args: Vec<&str> = vec!["simulate"];
        args.extend(case.iter().map(|x| x.as_str()));
        args.extend(["--duration", "0.2", "--out", &o]);
        let r = run_in(dir.path(), &args, Duration::from_secs(60));
        assert_ne!(r.code, Some(0), "{args:?}");
        assert!(r.stdout.is_empty(), "{args:?}: {}", r.stdout);
        assert_eq!(r.stderr.lines().count(), 1, "{args:?}: {}", r.stderr);
        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{args:?}: left {left:?}");
        std::fs::write(&out, "previous").unwrap();
        let r = run_in(dir.path(), &args, Duration::from_secs(60));
        assert_ne!(r.code, Some(0));
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        std::fs::remove_file(&out).unwrap();
    }
    let ok = run_in(
        dir.path(),
        &[
            "simulate",
            &b("sim_ok.urdf"),
            "--initial",
            &b("initial_ok.json"),
            "--duration",
            "0.01",
            "--out",
            &o,
        ],
        Duration::from_secs(60),
    );
    assert_eq!(ok.code, Some(0), "{}", ok.stderr);
    assert!(ok.stdout.is_empty());
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("t,"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// `urdyn bench` on a robot of one link welded to the world (no degree of freedom)
/// times every algorithm instead of failing on an empty output (it once stopped with
/// "internal error ... Matrix index out of bounds"); with a free base the constrained
/// algorithms run too, and the table's name column fits the longest name.
#[test]
fn bench_times_a_model_without_degrees_of_freedom() {
    let ball = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/urdf/ball.urdf");
    let ball = ball.to_str().unwrap();
    let r = run(&[
        "bench",
        ball,
        "--samples",
        "5",
        "--budget",
        "0.05",
        "--json",
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("bench --json");
    assert_eq!(v["nv"], 0);
    assert_eq!(
        v["results"].as_object().map(|o| o.len()),
        Some(11),
        "{}",
        r.stdout
    );
    let r = run(&[
        "bench",
        ball,
        "--floating-base",
        "--samples",
        "5",
        "--budget",
        "0.05",
        "--algo",
        "rnea",
        "--algo",
        "constraint-dynamics-derivatives",
        "--hold",
        "ball",
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let rows: Vec<&str> = r.stdout.lines().skip(1).collect();
    assert_eq!(rows.len(), 3, "{}", r.stdout);
    // right-aligned columns: the header and every row end at the same place
    assert!(
        rows.iter().all(|l| l.len() == rows[0].len()),
        "{}",
        r.stdout
    );
}

/// `urdyn bench`: unknown algorithm, zero samples, bad budget, bad files.
#[test]
fn bench_bad_inputs_are_one_line() {
    let s = |args: &[&str], expect: &[&str]| {
        let mut a = vec!["bench"];
        a.extend_from_slice(args);
        assert_rejected(&a, expect);
    };
    s(&["sim_ok.urdf", "--algo", "nope"], &["--algo", "nope"]);
    s(
        &["sim_ok.urdf", "--algo", "rnea", "--algo", "nope"],
        &["nope"],
    );
    s(&["sim_ok.urdf", "--samples", "0"], &["--samples"]);
    s(&["sim_ok.urdf", "--samples=-1"], &["--samples"]);
    s(&["sim_ok.urdf", "--budget", "0"], &["--budget"]);
    s(&["sim_ok.urdf", "--budget=nan"], &["--budget"]);
    s(&["sim_ok.urdf", "--budget=-1"], &["--budget"]);
    s(&["sim_ok.urdf", "--bogus"], &["--bogus"]);
    s(&["missing.urdf"], &["missing.urdf", "cannot read"]);
    s(&["../bad"], &["../bad", "directory"]);
    s(&[], &["URDF"]);
    s(
        &["massless_joint.urdf", "--algo", "fd"],
        &["massless_joint.urdf", "\"wrist\""],
    );
}
