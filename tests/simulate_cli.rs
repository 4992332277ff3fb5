//! `urdyn simulate` contract (cli.md) and the lamp-drop acceptance run.

use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn urdyn() -> Command {
    Command::new(env!("CARGO_BIN_EXE_urdyn"))
}

use crate::common::csv::read_csv;

#[test]
fn lamp_drop_acceptance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T.csv");
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--floating-base", "--duration", "3", "--initial"])
        .arg(root().join("assets/lamp_initial.json"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one summary line: {stderr}");
    assert!(stderr.contains("real-time factor") && stderr.contains("penetration"));
    let (h, rows) = read_csv(&out);
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    let last = rows.last().unwrap();
    assert_eq!(last[0], 3.0);
    assert_eq!(rows.len(), 3001);
    for (k, name) in h.iter().enumerate() {
        if name.starts_with("v:") {
            assert!(last[k].abs() < 1e-2, "{name} = {} at t = 3 s", last[k]);
        }
    }
    let (qx, qy) = (last[col("q:base_qx")], last[col("q:base_qy")]);
    let cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy);
    assert!(
        cos_tilt > 15f64.to_radians().cos(),
        "base tilted: cos = {cos_tilt}"
    );
    let pen = col("penetration");
    assert!(rows.iter().all(|r| r[pen] < 1e-3));
    let e = col("energy");
    let e0 = rows[0][e];
    let emax = rows.iter().map(|r| r[e]).fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (emax - e0) <= 1e-6 * e0.abs(),
        "energy rose: {e0} -> {emax}"
    );
    assert!(last[col("contacts")] >= 3.0);
}

#[test]
fn csv_header_last_step_and_every() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.csv");
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args([
            "--floating-base",
            "--duration",
            "0.0105",
            "--every",
            "4",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (h, rows) = read_csv(&out);
    let expect_head = [
        "t",
        "q:base_x",
        "q:base_y",
        "q:base_z",
        "q:base_qx",
        "q:base_qy",
        "q:base_qz",
        "q:base_qw",
        "q:shoulder",
        "q:elbow",
        "q:shade_tilt",
        "v:base_vx",
        "v:base_vy",
        "v:base_vz",
        "v:base_wx",
        "v:base_wy",
        "v:base_wz",
        "v:shoulder",
        "v:elbow",
        "v:shade_tilt",
        "energy",
        "contacts",
        "penetration",
        "awake",
    ];
    assert_eq!(h, expect_head);
    // steps of 1 ms, the 11th shortened to 0.5 ms; rows at 0, 4, 8 ms and the final state
    let ts: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(ts.len(), 4, "{ts:?}");
    assert_eq!(*ts.last().unwrap(), 0.0105);
    assert!((ts[1] - 0.004).abs() < 1e-12);
}

#[test]
fn bad_initial_key_is_one_line_error_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let init = dir.path().join("s.json");
    std::fs::write(&init, r#"{"base": {"positon": [0, 0, 1]}}"#).unwrap();
    let out = dir.path().join("t.csv");
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--floating-base", "--initial"])
        .arg(&init)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("positon") && err.contains("s.json"), "{err}");
    assert!(!out.exists());
    assert!(o.stdout.is_empty());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no stray files"
    );
}

#[test]
fn unknown_joint_and_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let init = dir.path().join("s.json");
    std::fs::write(&init, r#"{"q": {"elbw": 0.1}}"#).unwrap();
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .arg("--initial")
        .arg(&init)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("elbw"));
    let o = urdyn()
        .arg("simulate")
        .arg(root().join("assets/lamp.urdf"))
        .args(["--integrator", "leapfrog"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("leapfrog"));
}

#[test]
fn list_integrators_and_help() {
    let o = urdyn()
        .args(["simulate", "--list-integrators"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert_eq!(String::from_utf8_lossy(&o.stdout), "euler\nrk4\ndop853\n");
    let o = urdyn().args(["simulate", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&o.stdout);
    // the help says what a run does: self-collision, and with --scene the models
    // and obstacles (tests/contact_pairs.rs and scene_physics.rs run them), not the
    // stale "ground plane only (no self-collision)"
    assert!(!help.contains("no self-collision"), "{help}");
    assert!(help.contains("self-collision"), "{help}");
    assert!(
        help.contains("between the models and with the scene's obstacles"),
        "{help}"
    );
}

#[test]
fn missing_mesh_names_file_and_link() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("m.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="m"><link name="foot"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><mesh filename="package://nowhere/meshes/foot.stl"/></geometry></collision></link></robot>"#,
    )
    .unwrap();
    let o = urdyn()
        .arg("simulate")
        .arg(&urdf)
        .args(["--floating-base", "--duration", "0.01"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("foot.stl") && err.contains("\"foot\""),
        "{err}"
    );
    // without contact the mesh is never needed
    let o = urdyn()
        .arg("simulate")
        .arg(&urdf)
        .args(["--floating-base", "--duration", "0.01", "--no-ground"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
