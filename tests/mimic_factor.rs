//! Mimic joints and H's factor (`Topology::mimic_tree`): where the followers
//! keep the tree pattern (tests/urdf/mimic.urdf) the reduced
//! H = Gᵀ H G is factorised tree-sparse, elsewhere (tests/urdf/mimic_cross.urdf,
//! a follower across branches) densely. Both routes must give the same
//! forward dynamics, constrained dynamics and derivatives, and each satisfies
//! the identities H q̈ + C − τ = J_cᵀ λ (H from the CRBA, C from RNEA), H H⁻¹ = 1.

use nalgebra::DMatrix;
use std::path::PathBuf;
use urdyn::cli::bench::random_states;
use urdyn::dynamics_f64::{self as dynamics, ConstraintData};
use urdyn::model::Constraints;
use urdyn::{Data, LoadOptions, Model};

fn load(path: &str, floating_base: bool) -> Model {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::load_file(root.join(path), LoadOptions { floating_base }).unwrap()
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let s = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / s
}

#[test]
fn which_mimic_models_keep_the_tree_pattern() {
    for (path, tree) in [
        ("tests/urdf/mimic.urdf", true),
        ("tests/urdf/mimic_cross.urdf", false),
    ] {
        for fb in [false, true] {
            let m = load(path, fb);
            assert!(m.has_mimic, "{path}");
            assert_eq!(m.topology.mimic_tree, tree, "{path} floating {fb}");
        }
    }
    // no mimic joint (talos_reduced's gripper followers are fixed joints)
    for path in ["assets/robots/ur5.urdf", "assets/robots/talos_reduced.urdf"] {
        assert!(!load(path, false).topology.mimic_tree, "{path}");
    }
}

/// The dense route of the same model.
fn dense(m: &Model) -> Model {
    let mut d = m.clone();
    d.topology.mimic_tree = false;
    d
}

#[test]
fn tree_and_dense_factors_agree_on_derivatives() {
    for (path, fb) in [
        ("tests/urdf/mimic.urdf", false),
        ("tests/urdf/mimic.urdf", true),
    ] {
        let tree = load(path, fb);
        let full = dense(&tree);
        let (mut dt, mut dd) = (Data::new(&tree), Data::new(&full));
        for st in random_states(&tree, 4, 7) {
            dynamics::aba_derivatives(&tree, &mut dt, &st.q, &st.v, &st.tau, None).unwrap();
            dynamics::aba_derivatives(&full, &mut dd, &st.q, &st.v, &st.tau, None).unwrap();
            let e = rel(dt.qdd.as_slice(), dd.qdd.as_slice());
            assert!(e < 1e-10, "{path}: qdd off by {e:e}");
            for (a, b, what) in [
                (&dt.dqdd_dq, &dd.dqdd_dq, "dq"),
                (&dt.dqdd_dv, &dd.dqdd_dv, "dv"),
                (&dt.minv, &dd.minv, "minv"),
            ] {
                let e = rel(a.as_slice(), b.as_slice());
                assert!(e < 1e-10, "{path}: {what} off by {e:e}");
            }
            // H⁻¹ H = 1 with H from the CRBA
            let h = dynamics::mass_matrix(&tree, &mut Data::new(&tree), &st.q)
                .unwrap()
                .clone();
            let h = DMatrix::from_fn(h.nrows(), h.ncols(), |i, j| {
                if i <= j {
                    h[(i, j)]
                } else {
                    h[(j, i)]
                }
            });
            let e = (&dt.minv * &h - DMatrix::identity(tree.nv, tree.nv)).amax();
            assert!(e < 1e-9, "{path}: H⁻¹ H − 1 = {e:e}");
        }
    }
}

#[test]
fn tree_and_dense_factors_agree_on_constrained_dynamics() {
    let point = [serde_json::json!({"kind": "point", "link1": "arm_l"})];
    let frame = [serde_json::json!({"kind": "frame", "link1": "arm_t"})];
    for (path, fb, cons) in [
        ("tests/urdf/mimic.urdf", true, &point[..]),
        ("tests/urdf/mimic.urdf", true, &frame[..]),
    ] {
        let tree = load(path, fb);
        let full = dense(&tree);
        let (mut dt, mut dd) = (Data::new(&tree), Data::new(&full));
        let states = random_states(&tree, 4, 11);
        let mut c = Constraints::from_json(&tree, cons).unwrap();
        dynamics::forward_kinematics(&tree, &mut dt, &states[0].q).unwrap();
        c.place_holds(&dt);
        let (mut ct, mut cf) = (
            ConstraintData::new(&tree, &c),
            ConstraintData::new(&full, &c),
        );
        for st in &states {
            let (q, v, tau) = (&st.q, &st.v, &st.tau);
            dynamics::constraint_dynamics(&tree, &mut dt, &mut ct, &c, q, v, tau, None).unwrap();
            dynamics::constraint_dynamics(&full, &mut dd, &mut cf, &c, q, v, tau, None).unwrap();
            let e = rel(ct.qdd.as_slice(), cf.qdd.as_slice());
            assert!(e < 1e-10, "{path}: qdd off by {e:e}");
            // H q̈ + C − τ = J_cᵀ λ with H from the CRBA, C from RNEA
            let mut d2 = Data::new(&tree);
            let h = dynamics::mass_matrix(&tree, &mut d2, q).unwrap().clone();
            let h = DMatrix::from_fn(tree.nv, tree.nv, |i, j| h[(i.min(j), i.max(j))]);
            let cb = dynamics::bias(&tree, &mut d2, q, v, None).unwrap().clone();
            let lhs = &h * &ct.qdd + cb - tau;
            let e = rel(lhs.as_slice(), ct.generalized_force.as_slice());
            assert!(e < 1e-9, "{path}: H qdd + C - tau - Jc^T lambda = {e:e}");
            dynamics::constraint_dynamics_derivatives(&tree, &mut dt, &mut ct, &c, q, v, tau, None)
                .unwrap();
            dynamics::constraint_dynamics_derivatives(&full, &mut dd, &mut cf, &c, q, v, tau, None)
                .unwrap();
            for (a, b, what) in [
                (&ct.dqdd_dq, &cf.dqdd_dq, "dq"),
                (&ct.dqdd_dv, &cf.dqdd_dv, "dv"),
                (&ct.dqdd_dtau, &cf.dqdd_dtau, "dtau"),
            ] {
                let e = rel(a.as_slice(), b.as_slice());
                assert!(e < 1e-9, "{path}: {what} off by {e:e}");
            }
        }
    }
}
