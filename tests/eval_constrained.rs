//! `eval`'s loop constraints (mechanisms.md §"In `eval` (version 4)"): a states
//! file with a top-level `"constraints"` list gives each result a `"constrained"`
//! block equal to the oracle's (tests/oracle/make_constraint_fixtures.py): q̈ and
//! J_cᵀλ by joint name, the base block (floating base), λ per constraint, the
//! violation, and the derivatives with `"derivatives": true`. World anchors
//! left out hold the link where it is in each state.

use serde_json::{json, Map, Value};
use std::path::PathBuf;
use urdyn::cli::{eval, state};
use urdyn::LoadOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: sizes");
    let s = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= tol * s, "{what}: {got:?} vs {want:?}");
    }
}

fn run(name: &str) {
    let path = root().join(format!("tests/fixtures/constraints/{name}.json"));
    let fix: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let fb = fix["floating_base"].as_bool().unwrap();
    let model = urdyn::load_file(
        root().join(fix["robot"].as_str().unwrap()),
        LoadOptions { floating_base: fb },
    )
    .unwrap();
    let names: Vec<String> = model.dof_names().iter().map(|s| s.to_string()).collect();
    let o = model.joint_v_offset();
    let qo = model.joint_q_offset();
    let by_name = |x: &[f64], off: usize| -> Value {
        let mut m = Map::new();
        for (k, n) in names.iter().enumerate() {
            m.insert(n.clone(), json!(x[off + k]));
        }
        Value::Object(m)
    };
    let mut states = Vec::new();
    for st in fix["states"].as_array().unwrap() {
        let (q, v, tau) = (nums(&st["q"]), nums(&st["v"]), nums(&st["tau"]));
        let mut s = json!({"q": by_name(&q, qo), "v": by_name(&v, o), "tau": by_name(&tau, o),
                           "derivatives": true});
        if fb {
            s["base"] = json!({"position": &q[0..3], "orientation_xyzw": &q[3..7],
                "linear_velocity": &v[0..3], "angular_velocity": &v[3..6],
                "force": &tau[0..3], "torque": &tau[3..6]});
        }
        states.push(s);
    }
    let text = json!({"constraints": fix["constraints"], "states": states}).to_string();
    let sf = state::parse_states(&text, "states.json").unwrap();
    let out = eval::evaluate(&model, &sf, "robot.urdf", "states.json").unwrap();
    let cons = fix["constraints"].as_array().unwrap();
    for (i, (st, r)) in fix["states"]
        .as_array()
        .unwrap()
        .iter()
        .zip(out["results"].as_array().unwrap())
        .enumerate()
    {
        let c = &r["constrained"];
        let what = format!("{name} state {i}");
        let qdd = nums(&st["qdd"]);
        let gf = nums(&st["generalized_force"]);
        let got: Vec<f64> = names.iter().map(|n| c["qdd"][n].as_f64().unwrap()).collect();
        close(&got, &qdd[o..], 1e-10, &format!("{what} qdd"));
        let got: Vec<f64> = names
            .iter()
            .map(|n| c["generalized_force"][n].as_f64().unwrap())
            .collect();
        close(&got, &gf[o..], 1e-10, &format!("{what} generalized_force"));
        if fb {
            let b = &c["base"];
            let mut got = nums(&b["linear_acceleration"]);
            got.extend(nums(&b["angular_acceleration"]));
            close(&got, &qdd[..6], 1e-10, &format!("{what} base accelerations"));
            let mut got = nums(&b["force"]);
            got.extend(nums(&b["torque"]));
            close(&got, &gf[..6], 1e-10, &format!("{what} base force"));
        }
        let mut row = 0;
        for (k, con) in cons.iter().enumerate() {
            let cname = con["name"].as_str().map_or(format!("constraint_{k}"), String::from);
            let viol = c["violation"][&cname].as_f64().unwrap();
            let want = st["violation"][k].as_f64().unwrap();
            assert!((viol - want).abs() < 1e-10, "{what}: violation of {cname}");
            let f = &c["constraint_forces"][&cname];
            let mut got = Vec::new();
            match con["kind"].as_str().unwrap() {
                "point" => got.extend(nums(&f["force"])),
                "frame" => {
                    got.extend(nums(&f["force"]));
                    got.extend(nums(&f["torque"]));
                }
                _ => got.push(f["torque"].as_f64().unwrap()),
            }
            if let Some(l) = st["lambda"].as_array() {
                let l: Vec<f64> = l.iter().map(|x| x.as_f64().unwrap()).collect();
                close(&got, &l[row..row + got.len()], 1e-9, &format!("{what} λ of {cname}"));
            }
            row += got.len();
        }
        for key in ["dqdd_dq", "dqdd_dv", "dqdd_dtau"] {
            let got: Vec<f64> = c[key].as_array().unwrap().iter().flat_map(nums).collect();
            let want: Vec<f64> = st[key].as_array().unwrap().iter().flat_map(nums).collect();
            close(&got, &want, 1e-7, &format!("{what} {key}"));
        }
    }
}

#[test]
fn eval_constrained_solo12_feet_held_where_they_stand() {
    run("solo12_feet");
}

#[test]
fn eval_constrained_planar_four_bar_and_gear() {
    run("four_bar_planar");
    run("ur5_gear");
}

#[test]
fn eval_constrained_talos_hands() {
    run("talos_hands");
}

#[test]
fn no_constraints_no_block() {
    let model = urdyn::load_file(root().join("tests/urdf/four_bar_planar.urdf"), LoadOptions::default())
        .unwrap();
    let sf = state::parse_states(r#"{"states": [{}]}"#, "s.json").unwrap();
    let out = eval::evaluate(&model, &sf, "r.urdf", "s.json").unwrap();
    assert!(out["results"][0].get("constrained").is_none());
}
