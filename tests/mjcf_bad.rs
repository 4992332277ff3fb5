//! The MJCF bad-input corpus (tests/bad/mjcf, mjcf.md §"Errors"): every file is
//! answered by the real `urdyn` binary (`inspect` and `simulate`) with a
//! non-zero exit, nothing on standard output, no panic and one line on
//! standard error naming the file and the offending element (by name, else
//! its line) or attribute. Every file of the directory is in the table below.

use crate::common::refusal::assert_refused;
use std::path::{Path, PathBuf};
use std::process::Command;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad/mjcf")
}

/// Each file and what its one line must hold (besides the file's name).
const CASES: &[(&str, &[&str])] = &[
    ("actuator_no_target.xml", &["<motor name=\"m\">", "joint"]),
    (
        "actuator_unknown_joint.xml",
        &["<motor name=\"m\">", "joint=\"elbow\""],
    ),
    ("bad_joint_type.xml", &["<joint name=\"j\">", "universal"]),
    ("bad_number.xml", &["<geom name=\"g\">", "size"]),
    ("ball_range.xml", &["<joint name=\"j\">", "range"]),
    ("cyclic_include.xml", &["<include> (line 2)", "cyclic"]),
    ("dup_actuator.xml", &["<position name=\"m\">", "duplicate"]),
    ("dup_body.xml", &["<body name=\"a\">", "duplicate"]),
    ("empty.xml", &["empty"]),
    ("entity_bomb.xml", &["<!DOCTYPE>", "entity"]),
    (
        "equality_ball_joint.xml",
        &["<joint name=\"g\">", "joint2=\"s\"", "hinge or slide"],
    ),
    ("equality_nan_anchor.xml", &["<weld name=\"w\">", "anchor"]),
    (
        "equality_unknown_body.xml",
        &["<connect name=\"c\">", "body2=\"ghost\""],
    ),
    (
        "exclude_unknown_body.xml",
        &["<exclude name=\"e\">", "body2=\"ghost\""],
    ),
    (
        "flat_mesh.xml",
        &["<geom name=\"g\">", "mesh \"m\"", "volume"],
    ),
    (
        "free_below_top.xml",
        &["<freejoint name=\"f\">", "top-level"],
    ),
    ("inf_gear.xml", &["<motor name=\"m\">", "gear"]),
    ("inf_joint_pos.xml", &["<joint name=\"j\">", "pos"]),
    ("inf_mass.xml", &["<geom name=\"g\">", "mass"]),
    ("key_wrong_qpos.xml", &["<key name=\"k\">", "qpos"]),
    (
        "missing_include.xml",
        &["<include> (line 2)", "no_such_file.xml"],
    ),
    (
        "missing_mesh.xml",
        &["<mesh name=\"m\">", "no_such_mesh.stl"],
    ),
    ("nan_size.xml", &["<geom name=\"g\">", "size"]),
    (
        "negative_inertia.xml",
        &["<inertial> (line 4)", "diaginertia"],
    ),
    ("negative_kp.xml", &["<position name=\"p\">", "kp"]),
    ("negative_mass.xml", &["<geom name=\"g\">", "mass"]),
    ("negative_timestep.xml", &["<option> (line 2)", "timestep"]),
    ("not_xml.xml", &["XML"]),
    (
        "reversed_ctrlrange.xml",
        &["<motor name=\"m\">", "ctrlrange"],
    ),
    ("reversed_range.xml", &["<joint name=\"j\">", "range"]),
    ("truncated.xml", &["<body name=\"b\">", "truncated"]),
    (
        "two_free_joints.xml",
        &["<freejoint name=\"f2\">", "free joint"],
    ),
    (
        "two_orientations.xml",
        &["<geom name=\"g\">", "quat and euler"],
    ),
    (
        "unknown_actuator_kind.xml",
        &["<servo name=\"s\">", "unknown element"],
    ),
    ("unknown_attribute.xml", &["<geom name=\"g\">", "colour"]),
    (
        "unknown_class.xml",
        &["<geom name=\"g\">", "class=\"nope\""],
    ),
    (
        "unknown_element.xml",
        &["<bogus name=\"x\">", "unknown element"],
    ),
    ("zero_axis.xml", &["<joint name=\"j\">", "axis"]),
    ("zero_quat.xml", &["<geom name=\"g\">", "zero quaternion"]),
];

#[test]
fn every_malformed_mjcf_file_is_one_line_naming_file_and_element() {
    let mut files: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".xml"))
        .collect();
    files.sort();
    let listed: Vec<String> = CASES.iter().map(|(f, _)| f.to_string()).collect();
    assert_eq!(files, listed, "tests/bad/mjcf and the table differ");
    assert!(files.len() >= 20);
    let tmp = tempfile::tempdir().unwrap();
    for (file, expect) in CASES {
        let path = dir().join(file);
        let out = tmp.path().join("never.csv");
        for cmd in [
            vec!["inspect".to_string(), path.display().to_string()],
            vec![
                "simulate".to_string(),
                path.display().to_string(),
                "--duration".into(),
                "0.01".into(),
                "--out".into(),
                out.display().to_string(),
            ],
        ] {
            let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
                .args(&cmd)
                .env_remove("RUST_BACKTRACE")
                .output()
                .unwrap();
            let (stdout, stderr) = (
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr),
            );
            let mut want: Vec<&str> = vec![file];
            want.extend_from_slice(expect);
            assert_refused(
                &format!("{} {file}", cmd[0]),
                o.status.code(),
                &stdout,
                &stderr,
                &want,
            );
            assert!(!out.exists(), "{file}: a trajectory was written");
        }
    }
}

#[test]
fn controls_files_are_checked_naming_the_file_and_column() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/mjcf/actuators/actuator_kinds.xml");
    let tmp = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        ("no_t.csv", "time,elbow_vel\n0,1\n", &["first column", "t"]),
        (
            "unknown.csv",
            "t,elbo_vel\n0,1\n",
            &["\"elbo_vel\"", "elbow_vel"],
        ),
        (
            "twice.csv",
            "t,elbow_vel,elbow_vel\n0,1,1\n",
            &["\"elbow_vel\"", "second"],
        ),
        ("nan.csv", "t,elbow_vel\n0,nan\n", &["line 2", "elbow_vel"]),
        ("short.csv", "t,elbow_vel\n0\n", &["line 2", "columns"]),
        (
            "backwards.csv",
            "t,elbow_vel\n0.5,1\n0.2,1\n",
            &["line 3", "t = 0.2"],
        ),
        ("empty.csv", "", &["empty"]),
    ];
    for (name, text, expect) in cases {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
            .arg("simulate")
            .arg(&model)
            .arg("--controls")
            .arg(&p)
            .args(["--duration", "0.01"])
            .output()
            .unwrap();
        let mut want: Vec<&str> = vec![name, "--controls"];
        want.extend_from_slice(expect);
        assert_refused(
            name,
            o.status.code(),
            &String::from_utf8_lossy(&o.stdout),
            &String::from_utf8_lossy(&o.stderr),
            &want,
        );
    }
    // --controls beside a URDF is refused naming the option
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad/ok.urdf");
    let p = tmp.path().join("ok.csv");
    std::fs::write(&p, "t\n0\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg(&urdf)
        .arg("--controls")
        .arg(&p)
        .output()
        .unwrap();
    assert_refused(
        "controls beside a URDF",
        o.status.code(),
        &String::from_utf8_lossy(&o.stdout),
        &String::from_utf8_lossy(&o.stderr),
        &["--controls", "MJCF"],
    );
}
