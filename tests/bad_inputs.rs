//! The bad-input corpus (tests/bad, issue 6): every file is answered by the real
//! `urdyn` binary with exit status non-zero, exactly one line on standard error
//! naming the file and the offending element or key, nothing on standard output
//! and no panic — or, for the warning cases, loads and `inspect` prints the warning.
//! Output files are never half written.

use crate::common::refusal::assert_refused;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

pub(crate) const BIN: &str = env!("CARGO_BIN_EXE_urdyn");

pub(crate) fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad")
}

pub(crate) struct Run {
    pub(crate) code: Option<i32>,
    pub(crate) stdout: String,
    pub(crate) stderr: String,
    pub(crate) elapsed: Duration,
    /// Peak resident set size of the child (kB), from /proc, if it could be read.
    pub(crate) peak_rss_kb: Option<u64>,
}

/// Runs `urdyn` in tests/bad with a time limit (a child still running then is
/// killed and the test fails: nothing may block, e.g. on a FIFO).
pub(crate) fn run_in(dir: &Path, args: &[&str], limit: Duration) -> Run {
    let start = Instant::now();
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn urdyn");
    let mut out_pipe = child.stdout.take().unwrap();
    let mut err_pipe = child.stderr.take().unwrap();
    let out_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out_pipe.read_to_end(&mut s);
        s
    });
    let err_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err_pipe.read_to_end(&mut s);
        s
    });
    let status_path = format!("/proc/{}/status", child.id());
    let mut peak: Option<u64> = None;
    let status = loop {
        if let Ok(text) = std::fs::read_to_string(&status_path) {
            for line in text.lines() {
                if let Some(v) = line.strip_prefix("VmHWM:") {
                    if let Some(kb) = v.split_whitespace().next().and_then(|x| x.parse().ok()) {
                        peak = Some(peak.map_or(kb, |p: u64| p.max(kb)));
                    }
                }
            }
        }
        if let Some(st) = child.try_wait().expect("wait") {
            break st;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("urdyn {args:?} still running after {limit:?} (blocked?)");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let elapsed = start.elapsed();
    let stdout = String::from_utf8_lossy(&out_t.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&err_t.join().unwrap()).into_owned();
    Run {
        code: status.code(),
        stdout,
        stderr,
        elapsed,
        peak_rss_kb: peak,
    }
}

pub(crate) fn run(args: &[&str]) -> Run {
    run_in(&bad_dir(), args, Duration::from_secs(60))
}

/// The contract of a bad input: non-zero exit, one line on stderr containing every
/// `expect` substring, empty stdout, no panic.
pub(crate) fn assert_rejected(args: &[&str], expect: &[&str]) -> String {
    let r = run(args);
    let ctx = format!("urdyn {}", args.join(" "));
    assert_refused(&ctx, r.code, &r.stdout, &r.stderr, expect)
}

/// Each malformed URDF with the substrings its error must contain (besides the
/// file name): the element, and a word of the reason.
const BAD_URDF: &[(&str, &[&str])] = &[
    ("not_xml.urdf", &["<robot>"]),
    ("binary.urdf", &["UTF-8"]),
    ("truncated.urdf", &["joint \"j2\"", "XML"]),
    ("no_robot.urdf", &["<model>", "<robot>"]),
    ("missing_parent.urdf", &["joint \"j1\"", "\"nowhere\""]),
    ("missing_child.urdf", &["joint \"j2\"", "\"ghost\""]),
    ("two_roots.urdf", &["link \"island\"", "root"]),
    ("cycle.urdf", &["joint \"jba\"", "link \"a\""]),
    ("cycle_no_root.urdf", &["link \"", "cycle"]),
    ("two_parents.urdf", &["joint \"j3\"", "link \"l2\""]),
    ("self_parent.urdf", &["joint \"jself\""]),
    ("dup_link.urdf", &["link \"l1\"", "duplicate"]),
    ("dup_joint.urdf", &["joint \"j1\"", "duplicate"]),
    (
        "mimic_missing_leader.urdf",
        &["joint \"j2\" <mimic>", "\"ghost\""],
    ),
    (
        "mimic_fixed_leader.urdf",
        &["joint \"j2\" <mimic>", "\"jf\""],
    ),
    ("mimic_cycle.urdf", &["<mimic>", "cycle"]),
    ("mimic_self.urdf", &["joint \"ms\" <mimic>", "cycle"]),
    ("nan_mimic_multiplier.urdf", &["joint \"j2\" <mimic>"]),
    ("negative_mass.urdf", &["link \"l1\" <inertial>", "mass"]),
    ("nan_mass.urdf", &["link \"l1\" <inertial>", "mass"]),
    ("inf_mass.urdf", &["link \"l1\" <inertial>", "mass"]),
    (
        "nonnumeric_mass.urdf",
        &["link \"l1\" <inertial> <mass>", "heavy"],
    ),
    ("nan_inertia.urdf", &["link \"l1\" <inertial>", "<inertia>"]),
    (
        "malformed_collision.urdf",
        &[
            "link \"l1\" <collision> <geometry> <box>",
            "size=\"1 2\" is not 3 numbers",
        ],
    ),
    (
        "inf_inertial_origin.urdf",
        &["link \"l1\" <inertial>", "<origin>"],
    ),
    ("nan_joint_origin.urdf", &["joint \"j1\"", "<origin>"]),
    ("inf_joint_origin.urdf", &["joint \"j1\"", "<origin>"]),
    ("nan_axis.urdf", &["joint \"j1\"", "<axis>"]),
    ("inf_axis.urdf", &["joint \"j1\"", "<axis>"]),
    ("zero_axis.urdf", &["joint \"j1\"", "zero <axis>"]),
    ("nan_limit.urdf", &["joint \"j1\" <limit>", "lower"]),
    (
        "inf_limit_effort.urdf",
        &["joint \"j1\" <limit>", "velocity"],
    ),
    ("reversed_limit.urdf", &["joint \"j1\" <limit>"]),
    ("unknown_joint_type.urdf", &["joint \"j1\"", "\"hinge\""]),
    (
        "mimic_spherical.urdf",
        &["joint \"j2\" <mimic>", "spherical joint cannot mimic"],
    ),
    (
        "mimic_spherical_leader.urdf",
        &["joint \"j2\" <mimic>", "several degrees of freedom"],
    ),
    ("nonnumeric_origin.urdf", &["joint \"j1\" <origin>", "xyz"]),
    ("short_origin.urdf", &["joint \"j1\" <origin>", "xyz"]),
    ("joint_no_type.urdf", &["joint \"j1\"", "type"]),
    ("joint_no_child.urdf", &["joint \"j1\"", "<child>"]),
    ("link_no_name.urdf", &["link #2", "name"]),
    ("empty.urdf", &["empty file"]),
    ("whitespace.urdf", &["empty file"]),
    ("no_links.urdf", &["<robot>", "<link>"]),
    ("entity_bomb.urdf", &["<!DOCTYPE>", "entity"]),
    ("external_entity.urdf", &["<!DOCTYPE>", "entity"]),
    ("doctype_only.urdf", &["<!DOCTYPE>"]),
    ("undeclared_entity.urdf", &["<robot>", "entity"]),
];

/// Models that load (and `inspect`) but have no forward dynamics: `eval` fails
/// naming the joint.
const MASSLESS: &[(&str, &str)] = &[
    ("massless_joint.urdf", "joint \"wrist\""),
    ("massless_joint_nointertial.urdf", "joint \"wrist\""),
];

/// Inputs that are warnings, not errors: they load, `eval` answers, and `inspect`
/// prints each substring.
const WARN: &[(&str, &[&str])] = &[
    (
        "semidefinite_inertia.urdf",
        &["link \"l2\": inertia is only semi-definite"],
    ),
    (
        "quadruped_base_1e-6.urdf",
        &["link \"base\": inertia breaks the triangle inequality"],
    ),
    (
        "triangle_inequality.urdf",
        &["link \"l1\": inertia breaks the triangle inequality"],
    ),
    (
        "no_limit.urdf",
        &["joint \"j1\": no <limit>", "joint \"j2\": no <limit>"],
    ),
    ("mesh_dotdot.urdf", &["not found"]),
    (
        "malformed_visual.urdf",
        &[
            "material \"red\" <color>: rgba=\"1 0 0\" is not 4 numbers (not used by dynamics)",
            "link \"base\" <visual> <geometry> <box>: size=\"1 2\" is not 3 numbers",
            "link \"base\" <visual> <geometry>: needs exactly one shape",
        ],
    ),
    (
        "unknown_attribute.urdf",
        &[
            "unknown attribute \"lowr\" on <limit> of joint \"j1\" (ignored; 1 more like it)",
            "unknown element <spring> in joint \"j2\"",
        ],
    ),
    ("ok.urdf", &[]),
];

/// States files on joints_ok.urdf (a spherical "ball", a revolute "hinge", a
/// floating "mount", a planar "slide") with what their error must name.
const BAD_JOINT_STATES: &[(&str, &[&str])] = &[
    (
        "states_joint_number_for_array.json",
        &[
            "states[0].q.ball",
            "array of 4 numbers [qx, qy, qz, qw], found a number",
        ],
    ),
    (
        "states_joint_wrong_length.json",
        &[
            "states[0].q.slide",
            "array of 3 numbers [x, y, theta], found 2",
        ],
    ),
    (
        "states_joint_v_wrong_length.json",
        &["states[0].v.mount", "array of 6 numbers", "found 3"],
    ),
    (
        "states_joint_quat_nonunit.json",
        &["states[0].q.ball", "not a unit quaternion"],
    ),
    (
        "states_joint_mount_quat_nonunit.json",
        &["states[0].q.mount", "not a unit quaternion (norm 2"],
    ),
    (
        "states_joint_array_for_number.json",
        &["states[0].v.hinge", "takes a number, found an array"],
    ),
    (
        "states_joint_string_in_array.json",
        &["states[0].a.ball", "string"],
    ),
    ("states_joint_nonfinite.json", &["states[0].tau.slide"]),
];

/// States files (on ok.urdf) with the key their error must name; `true`: with
/// `--floating-base`.
const BAD_STATES: &[(&str, bool, &[&str])] = &[
    ("states_not_json.json", false, &["not valid JSON"]),
    ("states_empty.txt", false, &["not valid JSON"]),
    (
        "states_top_not_object.json",
        false,
        &["(top level)", "object"],
    ),
    ("states_trailing.json", false, &["(top level)"]),
    (
        "states_wrong_type.json",
        false,
        &["states[0].q.j1", "string"],
    ),
    ("states_tau_null.json", false, &["states[0].tau.j1", "null"]),
    ("states_wrong_type_map.json", false, &["states[0].q", "map"]),
    (
        "states_states_not_list.json",
        false,
        &["states", "sequence"],
    ),
    (
        "states_state_as_array.json",
        false,
        &["states[0]", "object"],
    ),
    (
        "states_base_as_array.json",
        false,
        &["states[0].base", "object"],
    ),
    (
        "states_unknown_joint.json",
        false,
        &["states[1].v.elbow", "unknown joint"],
    ),
    ("states_mimic_key.json", false, &["states[0].q.j3", "mimic"]),
    ("states_nan.json", false, &["states[0].q.j1"]),
    ("states_inf_literal.json", false, &["states[0].v.j1"]),
    (
        "states_huge.json",
        false,
        &["states[0].a.j1", "out of range"],
    ),
    (
        "states_gravity_huge.json",
        false,
        &["gravity[2]", "out of range"],
    ),
    ("states_base_huge.json", true, &["states[0].base.position"]),
    (
        "states_quat_nonunit.json",
        true,
        &["states[0].base.orientation_xyzw", "unit"],
    ),
    (
        "states_quat_zero.json",
        true,
        &["states[0].base.orientation_xyzw", "unit"],
    ),
    (
        "states_short_position.json",
        true,
        &["states[0].base.position", "length"],
    ),
    ("states_long_gravity.json", false, &["gravity", "too many"]),
    (
        "states_missing_states.json",
        false,
        &["(top level)", "`states`"],
    ),
    ("states_misspelt_top.json", false, &["gravty"]),
    // contract v2: external wrenches and frames
    (
        "states_fext_unknown_link.json",
        false,
        &[
            "states[1].fext.link_2",
            "unknown link \"link_2\"",
            "nearest: \"l2\"",
        ],
    ),
    (
        "states_frames_unknown_link.json",
        true,
        &[
            "states[0].frames[1]",
            "unknown link \"l22\"",
            "nearest: \"l2\"",
        ],
    ),
    (
        "states_fext_four_vector.json",
        false,
        &["states[0].fext.l1.force", "too many"],
    ),
    (
        "states_fext_misspelt.json",
        false,
        &["states[0].fext.l1.forse"],
    ),
    (
        "states_fext_huge.json",
        false,
        &["states[0].fext.l2.torque", "out of range"],
    ),
    (
        "states_fext_as_array.json",
        false,
        &["states[0].fext.l2", "object"],
    ),
    (
        "states_fext_list.json",
        false,
        &["states[0].fext", "object"],
    ),
    (
        "states_frames_not_list.json",
        false,
        &["states[0].frames", "sequence"],
    ),
    ("states_misspelt_state.json", false, &["states[0].qq"]),
    // contract v3: "derivatives" is a boolean
    (
        "states_derivatives_not_bool.json",
        false,
        &["states[1].derivatives", "true or false"],
    ),
    (
        "states_derivatives_string.json",
        true,
        &["states[0].derivatives", "true or false"],
    ),
    (
        "states_misspelt_base.json",
        false,
        &["states[0].base.positon"],
    ),
    (
        "states_duplicate_key.json",
        false,
        &["duplicate field `states`"],
    ),
    // loop constraints (mechanisms.md §"Loop constraints"): one line naming constraints[K] and the key
    (
        "states_constraint_unknown_link.json",
        false,
        &["constraints[0].link1", "\"nolink\""],
    ),
    (
        "states_constraint_mimic_joint.json",
        false,
        &["constraints[0].joint1", "mimic"],
    ),
    (
        "states_constraint_multi_dof.json",
        true,
        &["constraints[0].joint2", "degrees of freedom"],
    ),
    (
        "states_constraint_one_body.json",
        false,
        &["constraints[0].link2", "one body"],
    ),
    (
        "states_constraint_world_both.json",
        false,
        &["constraints[0].link1", "world"],
    ),
    (
        "states_constraint_nonfinite.json",
        false,
        &["constraints[0].point1[1]"],
    ),
    (
        "states_constraint_unknown_key.json",
        false,
        &["constraints[0].pont2", "unknown key"],
    ),
    (
        "states_constraint_duplicate_name.json",
        false,
        &["constraints[1].name", "duplicate"],
    ),
    (
        "states_constraint_bad_quaternion.json",
        false,
        &["constraints[0].frame1.orientation_xyzw"],
    ),
    (
        "states_constraint_inconsistent.json",
        false,
        &["states[0]", "\"tip\"", "inconsistent"],
    ),
];

#[test]
fn bad_urdfs_are_rejected_by_inspect_and_eval() {
    for (file, expect) in BAD_URDF {
        let mut e: Vec<&str> = vec![file];
        e.extend_from_slice(expect);
        let a = assert_rejected(&["inspect", file], &e);
        let b = assert_rejected(&["eval", file, "--states", "states_one.json"], &e);
        assert_eq!(a, b, "inspect and eval disagree on {file}");
        assert_rejected(
            &[
                "eval",
                file,
                "--states",
                "states_one.json",
                "--floating-base",
            ],
            &e,
        );
    }
}

#[test]
fn massless_joint_fails_eval_naming_the_joint() {
    for (file, joint) in MASSLESS {
        let r = run(&["inspect", file]);
        assert_eq!(r.code, Some(0), "{file}: {}", r.stderr);
        assert!(r.stdout.contains(joint) && r.stdout.contains("massless"));
        assert_rejected(
            &["eval", file, "--states", "states_one.json"],
            &[file, joint, "massless"],
        );
        assert_rejected(
            &["eval", file, "--states", "states_empty.json"],
            &[file, joint],
        );
    }
    // A state at which H is singular to working precision names the state.
    assert_rejected(
        &[
            "eval",
            "singular_at_zero.urdf",
            "--states",
            "states_singular_second.json",
        ],
        &["states_singular_second.json", "states[1]", "singular"],
    );
}

#[test]
fn warnings_are_not_errors() {
    for (file, warnings) in WARN {
        let r = run(&["inspect", file]);
        assert_eq!(r.code, Some(0), "{file}: {}", r.stderr);
        assert!(r.stderr.is_empty(), "{file}: {}", r.stderr);
        let section = r.stdout.split("\nwarnings:").nth(1).unwrap_or("");
        for w in *warnings {
            assert!(
                section.contains(w),
                "{file}: warning {w:?} not in\n{section}"
            );
        }
        for fb in [false, true] {
            let mut args = vec!["eval", file, "--states", "states_one.json"];
            if fb {
                args.push("--floating-base");
            }
            let r = run(&args);
            assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
            let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("JSON");
            assert_eq!(v["results"].as_array().map(|a| a.len()), Some(1));
        }
    }
    // A missing <limit> is unknown, never a locked joint: inspect says so.
    let r = run(&["inspect", "no_limit.urdf"]);
    assert!(r.stdout.contains("no position limit known"));
}

/// The warnings section of `urdyn inspect FILE` (which must succeed).
fn inspect_warnings(file: &str) -> String {
    let r = run(&["inspect", file]);
    assert_eq!(r.code, Some(0), "{file}: {}", r.stderr);
    r.stdout
        .split("\nwarnings:\n")
        .nth(1)
        .unwrap_or("")
        .to_string()
}

/// An inertia that is not positive semi-definite loads as written with a warning
/// naming the link and its principal moments (Pinocchio's behaviour); the
/// dynamics are then the URDF's, and an H that is not positive definite is the
/// contract's singular-H error.
#[test]
fn indefinite_inertia_loads_as_written() {
    // izz = -0.05 about the joint axis: H = [-0.05].
    let w = inspect_warnings("indefinite_inertia.urdf");
    assert!(
        w.contains("link \"l1\": inertia is not positive semi-definite (principal moments 1.000e-1, 1.000e-1, -5.000e-2)"),
        "{w}"
    );
    assert_rejected(
        &[
            "eval",
            "indefinite_inertia.urdf",
            "--states",
            "states_one.json",
        ],
        &["states_one.json", "states[0]", "singular"],
    );
    assert_rejected(
        &["inspect", "--strict", "indefinite_inertia.urdf"],
        &[
            "indefinite_inertia.urdf",
            "link \"l1\"",
            "not positive semi-definite",
            "--strict",
        ],
    );
    // ixy = 0.5 with ixx = iyy = 0.1: principal moments 0.1 ± 0.5 and 0.1.
    let w = inspect_warnings("indefinite_offdiag.urdf");
    assert!(
        w.contains("link \"l1\": inertia is not positive semi-definite"),
        "{w}"
    );
    assert!(w.contains("-4.000e-1") && w.contains("6.000e-1"), "{w}");
    // Fixed base: the joint turns about z, where the tensor is fine: H = [izz] = [0.1].
    let r = run(&[
        "eval",
        "indefinite_offdiag.urdf",
        "--states",
        "states_one.json",
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("JSON");
    let h = v["results"][0]["mass_matrix"][0][0]
        .as_f64()
        .expect("H[0][0]");
    assert!((h - 0.1).abs() < 1e-15, "H = {h}");
    // Floating base: the base block holds the tensor about x and y, made
    // indefinite (0.45 ± 0.5 with l1 0.5 m above the base): singular.
    assert_rejected(
        &[
            "eval",
            "indefinite_offdiag.urdf",
            "--states",
            "states_one.json",
            "--floating-base",
        ],
        &["states_one.json", "states[0]", "singular"],
    );
}

/// A misspelt attribute is a warning naming it, and the value it was meant to
/// set keeps its default (here lower = 0 of URDF 1.0).
#[test]
fn unknown_attribute_is_named_and_ignored() {
    let r = run(&["inspect", "unknown_attribute.urdf"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.contains("j1  [0, 1]"), "{}", r.stdout);
    assert_rejected(
        &["inspect", "--strict", "unknown_attribute.urdf"],
        &[
            "unknown_attribute.urdf",
            "unknown attribute \"lowr\" on <limit> of joint \"j1\"",
        ],
    );
    // Without warnings --strict changes nothing.
    let plain = run(&["inspect", "ok.urdf"]);
    let strict = run(&["inspect", "--strict", "ok.urdf"]);
    assert_eq!(strict.code, Some(0), "{}", strict.stderr);
    assert_eq!(plain.stdout, strict.stdout);
    assert!(inspect_warnings("ok.urdf").trim() == "none");
}

/// What no dynamics reads never stops a load: a `<texture>` without `filename`
/// (urdfdom reads it as no texture) gives no warning at all; `<gazebo>` and
/// `<transmission>` contents are not looked into.
#[test]
fn visual_only_problems_never_stop_a_load() {
    // ... nor do `version`, `xmlns:xacro`, a xacro leftover or PyBullet's <contact>:
    // they are listed as ignored.
    assert_eq!(inspect_warnings("texture_no_filename.urdf").trim(), "none");
    let r = run(&["inspect", "texture_no_filename.urdf"]);
    for ignored in [
        "<xacro:property> elements (xacro leftovers, not expanded)",
        "<link> <contact> elements (PyBullet extension, not used by dynamics)",
    ] {
        assert!(
            r.stdout.contains(ignored),
            "{ignored:?} not in\n{}",
            r.stdout
        );
    }
    let r = run(&["inspect", "malformed_visual.urdf"]);
    assert!(r.stdout.contains("<gazebo> elements") && r.stdout.contains("<transmission> elements"));
    assert!(!r.stdout.contains("anything") && !r.stdout.contains("hardwareInterface"));
    assert_rejected(
        &["inspect", "--strict", "malformed_visual.urdf"],
        &["malformed_visual.urdf", "material \"red\" <color>"],
    );
}

#[test]
fn bad_states_are_rejected_naming_the_key() {
    for (file, fb, expect) in BAD_STATES {
        let mut args = vec!["eval", "ok.urdf", "--states", file];
        if *fb {
            args.push("--floating-base");
        }
        let mut e: Vec<&str> = vec![file];
        e.extend_from_slice(expect);
        assert_rejected(&args, &e);
    }
    // Joints of several degrees of freedom (mechanisms.md "In `eval` (version 4)"):
    // each error names the joint.
    for (file, expect) in BAD_JOINT_STATES {
        let mut e: Vec<&str> = vec![file];
        e.extend_from_slice(expect);
        assert_rejected(&["eval", "joints_ok.urdf", "--states", file], &e);
    }
    let r = run(&[
        "eval",
        "joints_ok.urdf",
        "--states",
        "states_joints_ok.json",
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    // The good states files are answered, fixed and floating.
    for (fb, file) in [false, true]
        .into_iter()
        .flat_map(|fb| [(fb, "states_ok.json"), (fb, "states_ok_v2.json")])
    {
        let mut args = vec!["eval", "ok.urdf", "--states", file];
        if fb {
            args.push("--floating-base");
        }
        let r = run(&args);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        assert!(r.stdout.ends_with('\n') && r.stdout.lines().count() == 1);
    }
}
