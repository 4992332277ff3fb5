//! Bad scene files (shared/spec/scene.md): each is one line naming the scene
//! file, the key path and the offending name or value; from the CLI a non-zero
//! exit, nothing on standard output, no `--out` file. The corpus is
//! `tests/bad/scene/`.

use std::path::{Path, PathBuf};
use std::process::Command;
use urdyn::scene::Scene;

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/bad/scene")
        .join(name)
}

/// (file, substrings its error must hold: the key path and the offending name).
const CASES: &[(&str, &[&str])] = &[
    ("unknown_top_key.json", &["colour"]),
    ("unknown_model_key.json", &["models[0]", "mass"]),
    (
        "unknown_initial_key.json",
        &["models[0].initial.base", "velocity"],
    ),
    ("unknown_ground_key.json", &["ground", "mu"]),
    ("unknown_obstacle_key.json", &["obstacles[0]", "colour"]),
    (
        "missing_urdf.json",
        &[
            "models[1].urdf: file \"nothere.urdf\" not found",
            "tests/bad/scene/nothere.urdf",
        ],
    ),
    (
        "duplicate_name.json",
        &["models[1].name: duplicate name \"crate\""],
    ),
    ("slash_name.json", &["models[0].name", "\"my/lamp\"", "'/'"]),
    ("empty_name.json", &["models[0].name", "empty name"]),
    (
        "obstacle_named_as_model.json",
        &["obstacles[0].name: duplicate name \"lamp\""],
    ),
    (
        "bad_quaternion.json",
        &["models[0].orientation_xyzw", "unit quaternion", "norm 2"],
    ),
    (
        "bad_obstacle_quaternion.json",
        &["obstacles[0].orientation_xyzw", "unit quaternion"],
    ),
    (
        "bad_initial_quaternion.json",
        &["models[0].initial.base.orientation_xyzw", "unit quaternion"],
    ),
    ("non_finite.json", &["models[0].position"]),
    (
        "empty_heightfield.json",
        &["obstacles[0].heightfield.heights", "empty height grid"],
    ),
    (
        "ragged_heightfield.json",
        &["obstacles[0].heightfield.heights[1]", "ragged"],
    ),
    (
        "two_shape_keys.json",
        &["obstacles[0] (step): two shape keys box, sphere"],
    ),
    (
        "no_shape_key.json",
        &["obstacles[0] (nothing): no shape key"],
    ),
    ("negative_box.json", &["obstacles[0].box", "-1"]),
    (
        "missing_mesh.json",
        &["obstacles[0].mesh: file \"rock.stl\" not found"],
    ),
    (
        "unknown_exclude_link.json",
        &["exclude[0][0]", "\"lamp/nolink\""],
    ),
    (
        "unknown_exclude_model.json",
        &["exclude[0][1]", "\"robot\""],
    ),
    ("unknown_exclude_name.json", &["exclude[0][1]", "\"wall\""]),
    (
        "unknown_pose.json",
        &["models[0].pose", "\"away\"", "nearest: \"home\""],
    ),
    ("pose_without_srdf.json", &["models[0].pose", "srdf"]),
    (
        "missing_srdf.json",
        &["models[0].srdf: file \"nothere.srdf\" not found"],
    ),
    (
        "unknown_initial_joint.json",
        &["models[0].initial.q.elbw", "nearest: \"elbow\""],
    ),
    (
        "fixed_with_initial_base.json",
        &["models[0].initial.base", "fixed base"],
    ),
    ("not_json.json", &["not valid JSON"]),
    ("no_models.json", &["models", "at least one model"]),
    ("bad_base.json", &["models[0].base", "flying"]),
    ("negative_friction.json", &["models[0].friction", "-1"]),
    (
        "urdf_is_directory.json",
        &["models[0].urdf: \"../scene\" is a directory"],
    ),
];

#[test]
fn every_bad_scene_is_one_line_naming_the_file_and_the_key() {
    let mut listed: Vec<&str> = CASES.iter().map(|c| c.0).collect();
    listed.sort_unstable();
    let mut on_disk: Vec<String> = std::fs::read_dir(corpus(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    on_disk.sort_unstable();
    assert_eq!(
        listed, on_disk,
        "every corpus file has its expected message"
    );
    for (file, want) in CASES {
        let path = corpus(file);
        let err = match Scene::from_file(&path, &[]) {
            Ok(_) => panic!("{file}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(!err.contains('\n'), "{file}: not one line: {err}");
        assert!(
            err.starts_with(&format!("{}: ", path.display())),
            "{file}: does not name the scene file: {err}"
        );
        for w in *want {
            assert!(err.contains(w), "{file}: {err:?} lacks {w:?}");
        }
    }
}

#[test]
fn a_missing_scene_file_names_its_path() {
    let e = Scene::from_file(corpus("nothere.json"), &[]).unwrap_err();
    assert!(e.missing.is_some());
    assert!(e.to_string().contains("nothere.json"), "{e}");
}

#[test]
fn srdf_names_the_urdf_lacks_warn_once_and_load() {
    let dir = corpus("");
    let s = Scene::from_json(
        r#"{"models": [{"name": "lamp", "urdf": "../../../assets/lamp.urdf", "base": "floating",
             "srdf": "lamp.srdf", "pose": "home", "initial": {"q": {"elbow": 0.1}}}]}"#,
        "s.json",
        &dir,
        &[],
    )
    .unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(
        w.contains("no_such_link") && w.contains("wrist_extra"),
        "{w}"
    );
    assert!(
        !w.contains("root_joint"),
        "Pinocchio's root_joint is not warned about: {w}"
    );
    // the pose's values, then initial.q over them; the base from the model's pose
    let m = &s.model;
    assert_eq!(s.q0[m.q_index("lamp/shoulder").unwrap()], 0.2);
    assert_eq!(s.q0[m.q_index("lamp/elbow").unwrap()], 0.1);
    assert_eq!(
        s.q0.rows(0, 7).as_slice(),
        &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    );
    // the SRDF pair both of whose links exist
    assert_eq!(
        s.models[0].disabled,
        vec![("lamp/base".to_string(), "lamp/upper_arm".to_string())]
    );
}

fn urdyn() -> Command {
    Command::new(env!("CARGO_BIN_EXE_urdyn"))
}

/// A table and a lamp (absolute paths: the file is written to a temporary folder).
fn good() -> String {
    let a = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    format!(
        r#"{{"ground": {{"height": 0.0}},
  "models": [
    {{"name": "table", "urdf": "{}", "position": [2, 0, 0]}},
    {{"name": "lamp", "urdf": "{}", "base": "floating", "position": [0, 0, 0.3]}}]}}"#,
        a.join("table.urdf").display(),
        a.join("lamp.urdf").display()
    )
}

#[test]
fn cli_refuses_per_model_options_beside_a_scene_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("good.json");
    std::fs::write(&scene, good()).unwrap();
    let out = dir.path().join("t.csv");
    for opt in [
        &["--floating-base"][..],
        &["--initial", "x.json"],
        &["--above-ground", "0.1"],
        &["--ground", "0"],
        &["--no-ground"],
        &["--friction", "0.5"],
    ] {
        let o = urdyn()
            .arg("simulate")
            .arg("--scene")
            .arg(&scene)
            .args(opt)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{opt:?}");
        assert!(o.stdout.is_empty());
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(opt[0]), "{opt:?}: {err}");
        assert!(!out.exists());
    }
    // a bad scene: one line, non-zero, no file
    let o = urdyn()
        .args(["simulate", "--scene"])
        .arg(corpus("two_shape_keys.json"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("obstacles[0] (step): two shape keys box, sphere"),
        "{err}"
    );
    assert!(!out.exists());
    // the good scene runs: MODEL/NAME columns, models in file order
    let o = urdyn()
        .args(["simulate", "--duration", "0.05", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(&out).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(header[1], "q:lamp/base_x");
    assert_eq!(header[7], "q:lamp/base_qw");
    assert_eq!(header[8], "q:lamp/shoulder");
    assert!(header.contains(&"v:lamp/base_wz") && header.contains(&"v:lamp/shade_tilt"));
    assert_eq!(header.last(), Some(&"awake"));
    // the replay pages: every model's links as MODEL/LINK
    let page = dir.path().join("p.html");
    let o = urdyn()
        .args(["view", "--scene"])
        .arg(&scene)
        .arg(&out)
        .arg("--out")
        .arg(&page)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("\"lamp/shade\"") && html.contains("\"table/leg_4\""));
    let o = urdyn()
        .args(["view", "--scene"])
        .arg(&scene)
        .arg(&out)
        .arg("--floating-base")
        .arg("--out")
        .arg(dir.path().join("q.html"))
        .output()
        .unwrap();
    assert!(!o.status.success() && !dir.path().join("q.html").exists());
    // the first row: the lamp at its pose
    let row: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(&row[1..8], &[0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 1.0]);
}
