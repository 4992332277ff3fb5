//! MJCF through the command line: `eval` on Gymnasium's ant (free joint, armature)
//! against MuJoCo's numbers (the committed oracle fixture), `inspect --json`'s mass
//! properties and `--floating-base` refused (malformed MJCF files: the corpus in
//! tests/bad/mjcf, tests/mjcf_bad.rs).

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_urdyn");

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf")
}

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(BIN).args(args).output().expect("run urdyn");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn near(what: &str, got: f64, want: f64, scale: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol * scale.max(1.0),
        "{what}: urdyn {got}, MuJoCo {want}"
    );
}

#[test]
fn eval_on_mjcf_matches_mujoco() {
    let fx: Value = serde_json::from_str(
        &std::fs::read_to_string(dir().join("oracle/gymnasium_ant.json")).unwrap(),
    )
    .unwrap();
    let model = dir().join("gymnasium/ant.xml");
    let (ok, out, err) = run(&["inspect", model.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let ins: Value = serde_json::from_str(&out).unwrap();
    let names: Vec<String> = ins["v_names"].as_array().unwrap()[6..]
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    assert_eq!(ins["q_names"][0], "root:x");
    assert_eq!(ins["q_names"][6], "root:qw");
    assert_eq!(ins["v_names"][5], "root:wz");
    for (name, b) in fx["bodies"].as_object().unwrap() {
        near(
            &format!("{name} mass"),
            f(&ins["bodies"][name]["mass"]),
            f(&b["mass"]),
            1.0,
            1e-10,
        );
        for k in 0..3 {
            near(
                "com",
                f(&ins["bodies"][name]["com"][k]),
                f(&b["com"][k]),
                1.0,
                1e-10,
            );
        }
    }
    let s = &fx["states"][0];
    let at = |k: &str, i: usize| f(&s[k][i]);
    // the free joint "root" is a floating joint keyed by its name with an array
    // (q: x y z qx qy qz qw; v, a, tau: linear then angular, body frame)
    let map = |k: &str| -> Value {
        let off = if k == "q" { 7 } else { 6 };
        let mut m: serde_json::Map<String, Value> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), json!(at(k, off + i))))
            .collect();
        m.insert(
            "root".into(),
            json!((0..off).map(|i| at(k, i)).collect::<Vec<_>>()),
        );
        Value::Object(m)
    };
    let states = json!({"states": [{
        "q": map("q"), "v": map("v"), "a": map("a"), "tau": map("tau_in"),
    }]});
    let tmp = tempfile::tempdir().unwrap();
    let sf = tmp.path().join("states.json");
    std::fs::write(&sf, states.to_string()).unwrap();
    let (ok, out, err) = run(&[
        "eval",
        model.to_str().unwrap(),
        "--states",
        sf.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let r = &serde_json::from_str::<Value>(&out).unwrap()["results"][0];
    let h = s["mass_matrix"].as_array().unwrap();
    let hs = h
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(f))
        .fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, row) in h.iter().enumerate() {
        for (j, x) in row.as_array().unwrap().iter().enumerate() {
            near(
                &format!("H[{i}][{j}]"),
                f(&r["mass_matrix"][i][j]),
                f(x),
                hs,
                1e-10,
            );
        }
    }
    for (key, fkey) in [("tau", "tau"), ("bias", "bias"), ("qdd", "qdd")] {
        let want: Vec<f64> = s[fkey].as_array().unwrap().iter().map(f).collect();
        let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (i, n) in names.iter().enumerate() {
            near(
                &format!("{key} {n}"),
                f(&r[key][n]),
                want[6 + i],
                scale,
                1e-10,
            );
        }
        for k in 0..6 {
            near(
                &format!("{key} root {k}"),
                f(&r[key]["root"][k]),
                want[k],
                scale,
                1e-10,
            );
        }
    }
    for (name, p) in s["poses"].as_object().unwrap() {
        let pose = &r["link_poses"][name];
        for k in 0..3 {
            near("position", f(&pose["position"][k]), f(&p[k]), 1.0, 1e-12);
            for c in 0..3 {
                near(
                    "rotation",
                    f(&pose["rotation"][k][c]),
                    f(&p[3 + 3 * k + c]),
                    1.0,
                    1e-12,
                );
            }
        }
    }
    // the comparison can fail: MuJoCo's H without the ant's armature (1 on each leg joint)
    assert!((f(&r["mass_matrix"][6][6]) - f(&h[6][6]) + 1.0).abs() > 0.5);
}

#[test]
fn mjcf_commands_refuse_floating_base() {
    let model = dir().join("gymnasium/hopper.xml");
    for cmd in [&["inspect"][..], &["bench", "--samples", "1"][..]] {
        let mut args = cmd.to_vec();
        args.push(model.to_str().unwrap());
        args.push("--floating-base");
        let (ok, _, err) = run(&args);
        assert!(!ok);
        assert!(
            err.contains("hopper.xml") && err.contains("--floating-base"),
            "{err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}
