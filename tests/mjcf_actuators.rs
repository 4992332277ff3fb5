//! MJCF actuators right (issue 29's "Actuators right"): dm_control's acrobot,
//! cartpole, reacher and pendulum, Gymnasium's reacher and pusher, and
//! actuator_kinds.xml (position with kp and kv, velocity, motor, affine
//! general, gears, a clamped ctrlrange, a forcerange, two actuators on one
//! joint, an actuator beside a spring), dm_control's point_mass (motors on
//! fixed tendons) and tendon_kinds.xml (fixed tendons' springs, dampers, a
//! range, actuators pulling one- and two-joint tendons), contact off, driven 2 s by
//! piecewise-constant random controls that keep every joint off its limits:
//! urdyn's adaptive integrator (dop853, tol 1e-10) against MuJoCo's RK4 at
//! dt = 1e-5 (tests/oracle/make_mjcf_actuator_fixtures.py), every joint within
//! 1e-5 at every sample (each 0.5 s) and at the end; the CLI's `--controls`
//! on the same run; what urdyn does not model reported.

use nalgebra::DVector;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use urdyn::mjcf;
use urdyn::sim::{Integrator, SimOptions, Simulation};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf")
}

fn oracle() -> Value {
    let text = std::fs::read_to_string(dir().join("actuators/mujoco_actuated.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn adaptive() -> SimOptions {
    SimOptions {
        dt: 1e-3,
        integrator: Some(Integrator::from_name("dop853").unwrap()),
        tol: 1e-10,
        ground: None,
        sleep: false,
        ..SimOptions::default()
    }
}

/// urdyn's q and v of a MuJoCo sample.
fn start(sim: &Simulation, sample: &Value) -> (DVector<f64>, DVector<f64>) {
    let m = &sim.model;
    let qpos = DVector::from_vec(nums(&sample["qpos"]));
    let qvel = DVector::from_vec(nums(&sample["qvel"]));
    (
        mjcf::from_mujoco_qpos(m, &qpos).unwrap(),
        mjcf::from_mujoco_qvel(m, &qpos, &qvel).unwrap(),
    )
}

/// The largest |urdyn − MuJoCo| over q and v at one sample.
fn error(sim: &Simulation, sample: &Value) -> f64 {
    let (q, v) = start(sim, sample);
    (sim.q() - q).amax().max((sim.v() - v).amax())
}

#[test]
fn actuated_models_follow_mujoco_within_1e_5() {
    let fx = oracle();
    let mut report = Vec::new();
    for entry in fx["models"].as_array().unwrap() {
        let file = entry["file"].as_str().unwrap();
        let mut model = mjcf::load_file(dir().join(file)).expect(file);
        model.collisions.clear(); // contact off, as the fixture's MuJoCo run
        let names: Vec<&str> = model.actuators.iter().map(|a| a.name.as_str()).collect();
        let want: Vec<&str> = entry["actuators"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        assert_eq!(names, want, "{file}: actuator names and order");
        assert!(
            model
                .actuators
                .iter()
                .all(|a| a.dof.is_some() || !a.moment.is_empty()),
            "{file}: every actuator modelled"
        );
        assert!(
            !model.report.warnings.iter().any(|w| w.contains("tendon")),
            "{file}: {:?}",
            model.report.warnings
        );
        let mut sim = Simulation::new(model, adaptive()).unwrap();
        let samples = entry["samples"].as_array().unwrap();
        let (q0, v0) = start(&sim, &samples[0]);
        sim.set_state(&q0, &v0).unwrap();
        let rows = entry["controls"].as_array().unwrap();
        let (t_end, hold) = (2.0, fx["hold"].as_f64().unwrap());
        let mut worst = error(&sim, &samples[0]);
        let mut next_sample = 1;
        for (i, row) in rows.iter().enumerate() {
            let r = nums(row);
            sim.set_controls(&DVector::from_column_slice(&r[1..]))
                .unwrap();
            let until = if i + 1 < rows.len() {
                (i + 1) as f64 * hold
            } else {
                t_end
            };
            while sim.time() < until - 1e-12 {
                sim.step_until(until).unwrap();
            }
            let s = &samples[next_sample];
            if (s["t"].as_f64().unwrap() - sim.time()).abs() < 1e-9 {
                worst = worst.max(error(&sim, s));
                next_sample += 1;
            }
        }
        assert_eq!(next_sample, samples.len(), "{file}: every sample compared");
        let end = error(&sim, samples.last().unwrap());
        eprintln!(
            "mjcf_actuators: {file}: end error {end:.2e}, worst sample {worst:.2e} ({} steps)",
            sim.steps
        );
        report.push((file.to_string(), end, worst));
    }
    for (file, _, worst) in &report {
        assert!(
            *worst < 1e-5,
            "{file}: urdyn and MuJoCo differ by {worst:e}"
        );
    }
    assert_eq!(report.len(), 9);
}

#[test]
fn controls_csv_drives_the_cli_run_as_mujoco() {
    let fx = oracle();
    let entry = fx["models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["file"] == "actuators/actuator_kinds.xml")
        .unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("controls.csv");
    let mut text = String::from("t");
    let names = entry["actuators"].as_array().unwrap();
    // columns in another order than the file's: matched by name
    for n in names.iter().rev() {
        text.push(',');
        text.push_str(n.as_str().unwrap());
    }
    text.push('\n');
    for row in entry["controls"].as_array().unwrap() {
        let r = nums(row);
        text.push_str(&format!("{:e}", r[0]));
        for x in r[1..].iter().rev() {
            text.push_str(&format!(",{x:e}"));
        }
        text.push('\n');
    }
    std::fs::write(&csv, text).unwrap();
    let out = tmp.path().join("run.csv");
    let model = dir().join("actuators/actuator_kinds.xml");
    let status = Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .args(["simulate", model.to_str().unwrap(), "--controls"])
        .arg(&csv)
        .args(["--duration", "2", "--dt", "1e-3", "--integrator", "dop853"])
        .args(["--tol", "1e-10", "--every", "1000000", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&status.stderr);
    assert!(status.status.success(), "{err}");
    let (header, rows) = read_csv(&out);
    let last = rows.last().unwrap();
    assert!((last[0] - 2.0).abs() < 1e-12);
    let s = entry["samples"].as_array().unwrap().last().unwrap();
    let (qpos, qvel) = (nums(&s["qpos"]), nums(&s["qvel"]));
    let nq = qpos.len();
    assert_eq!(header.len(), 1 + nq + qvel.len() + 4);
    let e = (0..nq)
        .map(|k| (last[1 + k] - qpos[k]).abs())
        .chain((0..qvel.len()).map(|k| (last[1 + nq + k] - qvel[k]).abs()))
        .fold(0.0, f64::max);
    eprintln!("mjcf_actuators: CLI --controls on actuator_kinds.xml: end error {e:.2e}");
    assert!(e < 1e-5, "CLI run differs from MuJoCo by {e:e}");
}

fn read_csv(p: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn controls_are_checked_clamped_and_reported() {
    let model = mjcf::load_file(dir().join("actuators/actuator_kinds.xml")).unwrap();
    // the slide's general actuator: its symmetric forcerange is the joint's effort limit
    let slide = model.dofs.iter().find(|d| d.name == "slide").unwrap();
    assert_eq!(slide.limits.effort, Some(1.5));
    let mut sim = Simulation::new(model, adaptive()).unwrap();
    assert!(sim.set_controls(&DVector::zeros(4)).is_err(), "nu = 5");
    assert!(sim
        .set_controls(&DVector::from_vec(vec![f64::NAN, 0.0, 0.0, 0.0, 0.0]))
        .is_err());
    // shoulder_pos (gear 2, kp 8, ctrlrange ±0.5) at u = 3: clamped to 0.5,
    // K = gear²·kp = 32 about q_ref = 0 and a constant gear·kp·u = 8
    sim.set_controls(&DVector::from_vec(vec![3.0, 0.0, 0.0, 0.0, 0.0]))
        .unwrap();
    let (kp, kd) = sim.gains();
    assert_eq!((kp[1], kd[1]), (32.0, 4.0 * 0.3));
    assert_eq!(sim.actuator_torques()[1], 8.0);
    assert_eq!(sim.torques()[1], 8.0);
    // a new control replaces the old force (the torque is not accumulated)
    sim.set_controls(&DVector::from_vec(vec![-0.25, 0.0, 1.0, 0.0, 0.0]))
        .unwrap();
    assert_eq!(sim.torques()[1], -4.0);
    assert_eq!(sim.torques()[2], 0.5);
    // the wrist's spring (k 0.5 about 0.2) beside its position actuator (kp 0.8)
    let (kp, _) = sim.gains();
    assert!((kp[3] - 1.3).abs() < 1e-15);
    assert!((sim.targets().0[3] - 0.5 * 0.2 / 1.3).abs() < 1e-15);

    // what urdyn does not model is one line each in the import report
    let xml = r#"<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/>
        <body pos="0 0 -1"><joint name="b" type="ball"/><geom size="0.1"/></body></body></worldbody>
        <tendon><spatial name="t"><site site="s1"/><site site="s2"/></spatial></tendon>
        <actuator><muscle name="m" joint="j"/><motor name="onball" joint="b"/>
        <motor name="ontendon" tendon="t"/><general name="g" joint="j" dyntype="filter"/>
        <position name="p" joint="j" kp="2" forcerange="-1 2"/></actuator></mujoco>"#;
    let m = mjcf::load_str(xml, "inline.xml", Path::new(".")).unwrap();
    assert_eq!(m.actuators.len(), 5);
    let w = m.report.warnings.join("\n");
    for needle in [
        "muscle",
        "ball or free",
        "spatial tendons",
        "dyntype",
        "forcerange",
    ] {
        assert!(w.contains(needle), "no warning about {needle}: {w}");
    }
    assert!(m.actuators[0].dof.is_none() && m.actuators[4].dof.is_some());
}

#[test]
fn a_keyframe_sets_state_and_controls() {
    let xml = r#"<mujoco><worldbody><body><joint name="j" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -1" size="0.05"/></body></worldbody>
        <actuator><motor name="m" joint="j" gear="3"/></actuator>
        <keyframe><key name="push" qpos="0.3" qvel="-1" ctrl="0.5"/></keyframe></mujoco>"#;
    let model = mjcf::load_str(xml, "key.xml", Path::new(".")).unwrap();
    let mut sim = Simulation::new(model, adaptive()).unwrap();
    sim.set_key("push").unwrap();
    assert_eq!(sim.q()[0], 0.3);
    assert_eq!(sim.v()[0], -1.0);
    assert_eq!(sim.controls()[0], 0.5);
    assert_eq!(sim.torques()[0], 1.5);
    let e = sim.set_key("nope").unwrap_err().to_string();
    assert!(e.contains("nope") && e.contains("push"), "{e}");
    // a key whose ctrl does not have nu numbers is refused naming the key
    let bad = xml.replace("ctrl=\"0.5\"", "ctrl=\"0.5 1\"");
    let e = mjcf::load_str(&bad, "key.xml", Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("key.xml") && e.contains("push") && e.contains("ctrl"),
        "{e}"
    );
}

/// A one-joint tendon's range, spring and damper are its joint's, in the
/// joint's units (closed form: L = c q); a coupling tendon is reported.
#[test]
fn one_joint_tendons_become_joint_limits_springs_and_dampers() {
    let model = mjcf::load_file(dir().join("actuators/tendon_kinds.xml")).unwrap();
    let elbow = model.dofs.iter().find(|d| d.name == "elbow").unwrap();
    // range ±2.5 on L = 2 q; spring 3 about L₀ = 0.2 beside the joint's 1 about 0.1;
    // damper 0.5 beside the joint's 0.05
    assert_eq!(
        (elbow.limits.lower, elbow.limits.upper),
        (Some(-1.25), Some(1.25))
    );
    assert!((elbow.stiffness - (1.0 + 3.0 * 4.0)).abs() < 1e-15);
    let rest = (1.0 * 0.1 + 12.0 * 0.1) / 13.0; // (k_j r_j + k c² (L₀/c)) / (k_j + k c²)
    assert!(
        (elbow.springref - rest).abs() < 1e-15,
        "{}",
        elbow.springref
    );
    assert!((elbow.damping - (0.05 + 0.5 * 4.0)).abs() < 1e-15);
    // the wrist cable (coef −1.5): the default tendon damper 0.02 · 2.25
    let wrist = model.dofs.iter().find(|d| d.name == "wrist").unwrap();
    assert!((wrist.damping - (0.05 + 0.02 * 2.25)).abs() < 1e-15);
    let xml = r#"<mujoco><worldbody><body><joint name="a"/><geom size="0.1"/>
        <body pos="0 0 -1"><joint name="b"/><geom size="0.1"/></body></body></worldbody>
        <tendon><fixed name="t" stiffness="2"><joint joint="a" coef="1"/>
        <joint joint="b" coef="1"/></fixed></tendon></mujoco>"#;
    let m = mjcf::load_str(xml, "inline.xml", Path::new(".")).unwrap();
    assert!(
        m.report
            .warnings
            .iter()
            .any(|w| w.contains("coupled joints")),
        "{:?}",
        m.report.warnings
    );
    assert!(m.dofs.iter().all(|d| d.stiffness == 0.0));
}
