//! Loop constraints (mechanisms.md §"Loop constraints") against the fixtures of
//! tests/oracle/make_constraint_fixtures.py: q̈ and J_cᵀλ within 1e-10 of an
//! independent KKT solve on Pinocchio's H, C, Jacobians (itself checked against
//! Pinocchio's `constraintDynamics`), λ where J_c has full row rank, the
//! violations, and ∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ within 1e-7 relative of Richardson-
//! extrapolated central differences. Cases: planar four-bar (a redundant row),
//! the same loop stated twice, a spatial four-bar, solo12's four feet held,
//! talos_reduced's hands welded, a geared pair of ur5 joints.

use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::path::PathBuf;
use urdyn::dynamics_f64::{self as dynamics, ConstraintData};
use urdyn::model::Constraints;
use urdyn::{Data, LoadOptions};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c])
}

/// max|a − b| / max(1, max|b|).
fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let s = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / s
}

/// A fixture of tests/fixtures/constraints: its JSON, the robot it names
/// (with its base) and its constraints.
fn fixture(name: &str) -> (Value, urdyn::Model, Constraints) {
    let path = root().join(format!("tests/fixtures/constraints/{name}.json"));
    let fix: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let floating_base = fix["floating_base"].as_bool().unwrap();
    let model = urdyn::load_file(
        root().join(fix["robot"].as_str().unwrap()),
        LoadOptions { floating_base },
    )
    .unwrap();
    let base = Constraints::from_value(&model, &fix["constraints"]).unwrap();
    (fix, model, base)
}

/// A fixture state's q, v, τ and the constraints with their holds placed at
/// that q (forward kinematics into `data`).
fn state(
    model: &urdyn::Model,
    data: &mut Data,
    base: &Constraints,
    st: &Value,
) -> (DVector<f64>, DVector<f64>, DVector<f64>, Constraints) {
    let q = DVector::from_vec(vecf(&st["q"]));
    let v = DVector::from_vec(vecf(&st["v"]));
    let tau = DVector::from_vec(vecf(&st["tau"]));
    let mut c = base.clone();
    dynamics::forward_kinematics(model, data, &q).unwrap();
    c.place_holds(data);
    (q, v, tau, c)
}

fn check(name: &str) {
    let (fix, model, base) = fixture(name);
    let mut data = Data::new(&model);
    let mut cd = ConstraintData::new(&model, &base);
    let mut worst = [0.0f64; 4];
    for (i, st) in fix["states"].as_array().unwrap().iter().enumerate() {
        let (q, v, tau, c) = state(&model, &mut data, &base, st);
        let qdd = dynamics::constraint_dynamics(&model, &mut data, &mut cd, &c, &q, &v, &tau, None)
            .unwrap()
            .clone();
        let e_qdd = rel(qdd.as_slice(), &vecf(&st["qdd"]));
        let e_gf = rel(
            cd.generalized_force.as_slice(),
            &vecf(&st["generalized_force"]),
        );
        assert!(e_qdd < 1e-10, "{name} state {i}: qdd off by {e_qdd:e}");
        assert!(
            e_gf < 1e-10,
            "{name} state {i}: J_c^T lambda off by {e_gf:e}"
        );
        if let Some(l) = st["lambda"].as_array() {
            let l: Vec<f64> = l.iter().map(|x| x.as_f64().unwrap()).collect();
            let e = rel(cd.lambda.as_slice(), &l);
            assert!(e < 1e-10, "{name} state {i}: lambda off by {e:e}");
        }
        let mut viol = vec![0.0; c.items.len()];
        dynamics::constraint_violation(&model, &mut data, &c, &q, &mut viol).unwrap();
        let e = rel(&viol, &vecf(&st["violation"]));
        assert!(e < 1e-10, "{name} state {i}: violation {viol:?}");
        worst[0] = worst[0].max(e_qdd.max(e_gf));
        dynamics::constraint_dynamics_derivatives(
            &model, &mut data, &mut cd, &c, &q, &v, &tau, None,
        )
        .unwrap();
        let e = rel(cd.qdd.as_slice(), &vecf(&st["qdd"]));
        assert!(e < 1e-10, "{name} state {i}: derivatives' qdd off by {e:e}");
        for (k, (got, key)) in [
            (&cd.dqdd_dq, "dqdd_dq"),
            (&cd.dqdd_dv, "dqdd_dv"),
            (&cd.dqdd_dtau, "dqdd_dtau"),
        ]
        .into_iter()
        .enumerate()
        {
            let want = mat(&st[key]);
            let e = rel(got.as_slice(), want.as_slice());
            worst[k + 1] = worst[k + 1].max(e);
            assert!(
                e < 1e-7,
                "{name} state {i}: {key} off by {e:e}\n{got}\n{want}"
            );
        }
    }
    eprintln!(
        "{name}: worst qdd {:.1e}, dq {:.1e}, dv {:.1e}, dtau {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

#[test]
fn four_bar_planar_redundant_row() {
    check("four_bar_planar");
}

#[test]
fn four_bar_planar_loop_stated_twice() {
    check("four_bar_planar_twice");
}

#[test]
fn four_bar_spatial() {
    check("four_bar_spatial");
}

#[test]
fn solo12_four_feet_held() {
    check("solo12_feet");
}

#[test]
fn talos_hands_welded() {
    check("talos_hands");
}

#[test]
fn ur5_geared_pair() {
    check("ur5_gear");
}

/// The constrained algorithms allocate nothing per call on a preallocated
/// workspace (solo12's four feet held; the planar four-bar's redundant row takes
/// the pseudo-inverse route).
#[test]
fn constrained_hot_path_does_not_allocate() {
    use crate::common::counting_alloc::{allocations, measure_this_thread};
    measure_this_thread();
    for name in ["solo12_feet", "four_bar_planar"] {
        let (fix, model, base) = fixture(name);
        let mut data = Data::new(&model);
        let mut cd = ConstraintData::new(&model, &base);
        let (q, v, tau, c) = state(&model, &mut data, &base, &fix["states"][1]);
        let mut jc = DMatrix::zeros(c.rows(), model.nv);
        let mut viol = vec![0.0; c.items.len()];
        // warm
        dynamics::constraint_dynamics_derivatives(
            &model, &mut data, &mut cd, &c, &q, &v, &tau, None,
        )
        .unwrap();
        let mut counts = [0usize; 4];
        let before = allocations();
        dynamics::constraint_dynamics(&model, &mut data, &mut cd, &c, &q, &v, &tau, None).unwrap();
        counts[0] = allocations() - before;
        let before = allocations();
        dynamics::constraint_dynamics_derivatives(
            &model, &mut data, &mut cd, &c, &q, &v, &tau, None,
        )
        .unwrap();
        counts[1] = allocations() - before;
        let before = allocations();
        dynamics::constraint_jacobian(&model, &mut data, &c, &q, &mut jc).unwrap();
        counts[2] = allocations() - before;
        let before = allocations();
        dynamics::constraint_violation(&model, &mut data, &c, &q, &mut viol).unwrap();
        counts[3] = allocations() - before;
        assert_eq!(
            counts, [0; 4],
            "{name}: allocations of dynamics, derivatives, jacobian, violation"
        );
    }
}

/// K solved from its blocks (src/dynamics/kkt_blocks.rs: four feet, two hands
/// beside the shared base and torso) against K's dense factor (the
/// derivatives' route, through H⁻¹): the same q̈ and λ to rounding.
#[test]
fn blocked_and_dense_routes_agree() {
    for name in ["solo12_feet", "talos_hands"] {
        let (fix, model, base) = fixture(name);
        let mut data = Data::new(&model);
        let mut cd = ConstraintData::new(&model, &base);
        let mut worst = [0.0f64; 2];
        for st in fix["states"].as_array().unwrap() {
            let (q, v, tau, c) = state(&model, &mut data, &base, st);
            let qdd =
                dynamics::constraint_dynamics(&model, &mut data, &mut cd, &c, &q, &v, &tau, None)
                    .unwrap()
                    .clone();
            let lambda = cd.lambda.clone();
            dynamics::constraint_dynamics_derivatives(
                &model, &mut data, &mut cd, &c, &q, &v, &tau, None,
            )
            .unwrap();
            worst[0] = worst[0].max(rel(qdd.as_slice(), cd.qdd.as_slice()));
            worst[1] = worst[1].max(rel(lambda.as_slice(), cd.lambda.as_slice()));
        }
        eprintln!(
            "{name}: blocked vs dense, qdd {:e}, lambda {:e}",
            worst[0], worst[1]
        );
        assert!(worst[0] < 1e-12 && worst[1] < 1e-12, "{name}: {worst:?}");
    }
}
