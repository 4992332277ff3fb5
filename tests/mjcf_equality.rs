//! MJCF `<equality>` (mjcf.md, mechanisms.md): `connect`, `weld` and `joint`
//! equalities on hinge, slide, ball and free joints
//! (tests/fixtures/mjcf/equality/equalities.xml) against MuJoCo 4.0
//! (tests/oracle/make_mjcf_equality_fixtures.py): the compiled anchors equal
//! MuJoCo's `eq_data`; `eval`'s `constrained` block (qdd, J_cᵀ λ) equals a KKT
//! solve on MuJoCo's kinematics (mj_fullM, qfrc_bias, mj_jac, mj_jacDot) within
//! 1e-9 at 5 random states; an inactive equality is left out of `eval` and
//! starts off in a simulation, where the active ones close and stay closed.

use nalgebra::UnitQuaternion;
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};
use urdyn::cli::{eval, state};
use urdyn::mjcf::MjEqKind;
use urdyn::model::JointKind;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf")
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn fixture() -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(root().join("oracle_equality/equalities.json")).unwrap(),
    )
    .unwrap()
}

fn close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= tol * scale,
            "{what}[{k}]: urdyn {g}, MuJoCo {w} (scale {scale})"
        );
    }
}

#[test]
fn mjcf_equality_anchors_are_mujocos() {
    let fx = fixture();
    let world = urdyn::mjcf::load_world(root().join("equality/equalities.xml")).unwrap();
    assert_eq!(world.equalities.len(), 5);
    let quat = |q: &UnitQuaternion<f64>, want: &[f64]| {
        // q and −q are one rotation
        let s = if (q.w - want[0]).abs() < 0.5 {
            1.0
        } else {
            -1.0
        };
        vec![s * q.w, s * q.i, s * q.j, s * q.k]
    };
    for e in &world.equalities {
        let d = nums(&fx["eq_data"][&e.name]);
        match e.kind.as_ref().unwrap() {
            MjEqKind::Connect { p1, p2, .. } if e.name == "fourbar" => {
                close(p1.as_slice(), &d[0..3], 1e-14, "fourbar body1 point");
                close(p2.as_slice(), &d[3..6], 1e-14, "fourbar body2 point");
            }
            MjEqKind::Connect { .. } => assert_eq!(e.name, "loose"),
            MjEqKind::Weld { f1, f2, .. } => {
                close(
                    f2.0.as_slice(),
                    &d[0..3],
                    1e-14,
                    &format!("{} body2 anchor", e.name),
                );
                close(
                    f1.0.as_slice(),
                    &d[3..6],
                    1e-14,
                    &format!("{} body1 point", e.name),
                );
                close(
                    &quat(&f1.1, &d[6..10]),
                    &d[6..10],
                    1e-14,
                    &format!("{} relpose", e.name),
                );
                assert!(
                    f2.1.angle() == 0.0,
                    "{}: body2's frame is the anchor's",
                    e.name
                );
            }
            MjEqKind::Joint { a0, a1, joint2, .. } => {
                assert_eq!((*a0, *a1), (d[0], d[1]));
                assert!(joint2.is_some());
            }
        }
        assert_eq!(e.active, e.name != "loose", "{}: active", e.name);
    }
}

/// A state as eval's joint maps: a number per 1-DoF joint, an array for a ball
/// or free joint (mechanisms.md).
fn joint_map(model: &urdyn::Model, x: &[f64], q: bool) -> Value {
    let mut m = Map::new();
    for d in &model.dofs {
        let (at, n) = if q {
            (d.iq, d.kind.nq())
        } else {
            (d.iv, d.kind.nv())
        };
        let v = if n == 1 {
            json!(x[at])
        } else {
            json!(&x[at..at + n])
        };
        m.insert(d.name.clone(), v);
    }
    Value::Object(m)
}

fn from_map(model: &urdyn::Model, m: &Value) -> Vec<f64> {
    let mut out = vec![f64::NAN; model.nv];
    for d in &model.dofs {
        let x = &m[&d.name];
        if d.kind.nv() == 1 {
            out[d.iv] = x.as_f64().unwrap();
        } else {
            out[d.iv..d.iv + d.kind.nv()].copy_from_slice(&nums(x));
        }
    }
    out
}

#[test]
fn mjcf_equality_eval_matches_a_kkt_solve_on_mujocos_kinematics() {
    let fx = fixture();
    let model = urdyn::mjcf::load_file(root().join("equality/equalities.xml")).unwrap();
    assert_eq!((model.nq, model.nv), (24, 21));
    assert!(model
        .dofs
        .iter()
        .any(|d| matches!(d.kind, JointKind::Spherical)));
    let states: Vec<Value> = fx["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            json!({"q": joint_map(&model, &nums(&s["q"]), true),
                   "v": joint_map(&model, &nums(&s["v"]), false),
                   "tau": joint_map(&model, &nums(&s["tau"]), false)})
        })
        .collect();
    let text = json!({ "states": states }).to_string();
    let sf = state::parse_states(&text, "states.json").unwrap();
    let out = eval::evaluate(&model, &sf, "equalities.xml", "states.json").unwrap();
    for (i, (s, r)) in fx["states"]
        .as_array()
        .unwrap()
        .iter()
        .zip(out["results"].as_array().unwrap())
        .enumerate()
    {
        let c = &r["constrained"];
        let got = from_map(&model, &c["qdd"]);
        close(&got, &nums(&s["qdd"]), 1e-9, &format!("state {i} qdd"));
        let got = from_map(&model, &c["generalized_force"]);
        close(
            &got,
            &nums(&s["generalized_force"]),
            1e-9,
            &format!("state {i} generalized_force"),
        );
        let names: Vec<&String> = c["violation"].as_object().unwrap().keys().collect();
        for n in fx["active"].as_array().unwrap() {
            assert!(
                names.contains(&&n.as_str().unwrap().to_string()),
                "{n} missing"
            );
        }
        assert!(
            c["violation"].get("loose").is_none(),
            "an inactive equality is left out of eval"
        );
        // the KKT solve is not the unconstrained one
        let free = nums(&s["qdd"]);
        let unc = from_map(&model, &r["qdd"]);
        assert!(free.iter().zip(&unc).any(|(a, b)| (a - b).abs() > 1e-3));
    }
}

#[test]
fn mjcf_equality_simulation_closes_and_keeps_them() {
    let model = urdyn::mjcf::load_file(root().join("equality/equalities.xml")).unwrap();
    let opts = urdyn::sim::SimOptions {
        dt: 1e-3,
        integrator: Some(urdyn::sim::Integrator::SemiImplicitEuler),
        ground: None,
        sleep: false,
        ..Default::default()
    };
    let mut sim = urdyn::sim::Simulation::new(model, opts).unwrap();
    let set = sim.constraints().expect("the file's equalities").clone();
    assert_eq!(set.items.len(), 5);
    // gear (0.1 rad) and grip start violated: the run closes them
    assert!(sim.constraint_violation() > 1e-2);
    let lines = sim.constraint_start_lines();
    assert!(lines.iter().any(|l| l.contains("\"gear\"")), "{lines:?}");
    assert!(!lines.iter().any(|l| l.contains("\"loose\"")), "{lines:?}");
    let mut worst: f64 = 0.0;
    while sim.time() < 2.0 {
        sim.step().unwrap();
        if sim.time() > 0.5 {
            worst = worst.max(sim.constraint_violation());
        }
    }
    // closed from 0.34 (grip's angle) and 0.1 (gear): after 0.5 s the
    // violation stays below 1e-6 (2.2e-7; 3.5e-5 before the projection after
    // the step: docs/theory.md §"Loops in the simulation"; mechanisms.md asks 1e-6)
    assert!(worst < 1e-6, "violation after 0.5 s: {worst}");
    let q = sim.q().clone();
    assert!(q.iter().all(|x| x.is_finite()));
    // the gear holds: pole − ref = 0.1 − 0.5 (cart − ref) (a joint row: exact)
    let m = &sim.model;
    let dof = |n: &str| m.dofs.iter().find(|d| d.name == n).unwrap().iq;
    let (pole, cart) = (q[dof("pole")], q[dof("cart")]);
    assert!(((pole + 0.3) - (0.1 - 0.5 * (cart - 0.1))).abs() < 1e-6);
    // the inactive site connect is off until switched on
    let mut out = vec![0.0; 5];
    let mut data = urdyn::Data::new(m);
    urdyn::dynamics_f64::constraint_violation(m, &mut data, &set, &q, &mut out).unwrap();
    assert!(out[4] > 1e-3, "loose is off: its sites stay apart");
    sim.set_constraint_active("loose", true).unwrap();
    assert!(sim.constraint_violation() > 1e-3, "loose is on now");
}

/// A free body spinning at ω about a `connect` anchor off its origin (no
/// gravity): its origin circles the anchor, its body-frame (v, ω) constant. The
/// step moves a free origin on a straight line, not on the screw of a constant
/// twist: the loop rows' second-order term must be γ less R(ω × v) (docs/theory.md
/// §"Loops in the simulation"), else the anchor opens by ½h²ω²r a step
/// (5e-6 m here); with it only a third-order residual is left (h³ω³r/6 ≈ 2e-8 m).
#[test]
fn mjcf_connect_on_a_spinning_free_body_holds_to_third_order() {
    let xml = r#"<mujoco>
  <option timestep="0.001" gravity="0 0 0"><flag contact="disable"/></option>
  <worldbody>
    <body name="top" pos="0 0 1">
      <freejoint name="top"/>
      <geom type="box" size="0.05 0.03 0.02"/>
    </body>
  </worldbody>
  <equality><connect body1="top" body2="world" anchor="0.1 0 0"/></equality>
  <keyframe><key name="spin" qpos="0 0 1 1 0 0 0" qvel="0 -1 0 0 0 10"/></keyframe>
</mujoco>"#;
    let model = urdyn::mjcf::load_str(xml, "spin.xml", Path::new(".")).unwrap();
    let opts = urdyn::sim::SimOptions {
        dt: 1e-3,
        integrator: Some(urdyn::sim::Integrator::SemiImplicitEuler),
        ground: None,
        sleep: false,
        ..Default::default()
    };
    let mut sim = urdyn::sim::Simulation::new(model, opts).unwrap();
    sim.set_key("spin").unwrap();
    assert!(sim.constraint_violation() < 1e-12);
    let mut worst: f64 = 0.0;
    while sim.time() < 1.0 {
        sim.step().unwrap();
        worst = worst.max(sim.constraint_violation());
    }
    assert!(worst < 2e-7, "the anchor opened by {worst} m");
    // it still spins about the anchor (the passive run's energy projection
    // only takes energy out: 10 rad/s at most)
    let v = sim.v();
    assert!(v[5] > 9.0 && v[5] < 10.0 + 1e-9, "{v}");
}
