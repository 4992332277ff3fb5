//! CRBA, the tree-sparse LTDL, ABA and the engine's `fd` against the seed's
//! methods: agreement to 1e-10 relative on every fixture robot (random states),
//! and relative backward errors ≤ 1e-13 on long ill-conditioned chains.

use nalgebra::{DMatrix, DVector};
use std::path::PathBuf;
use urdyn::cli::bench::{random_states, State};
use urdyn::dynamics_f64::{self as dynamics, ltdl};
use urdyn::model::FdMethod;
use urdyn::{Data, LoadOptions, Model};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn fixtures() -> Vec<(String, Model)> {
    let mut out = Vec::new();
    let mut dirs: Vec<_> = std::fs::read_dir(root().join("tests/fixtures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("meta.json").is_file())
        .collect();
    dirs.sort();
    for d in dirs {
        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("meta.json")).unwrap()).unwrap();
        let urdf = root().join(meta["urdf"].as_str().unwrap());
        let floating_base = meta["floating_base"].as_bool().unwrap();
        let model = urdyn::load_file(&urdf, LoadOptions { floating_base }).unwrap();
        out.push((d.file_name().unwrap().to_string_lossy().into_owned(), model));
    }
    out
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

#[test]
fn crba_matches_rnea_columns_on_fixtures() {
    for (name, model) in fixtures() {
        let mut data = Data::new(&model);
        for s in random_states(&model, 8, 11) {
            dynamics::mass_matrix_rnea(&model, &mut data, &s.q).unwrap();
            let want = data.h.clone();
            // Stale H from another state first: every entry on the tree pattern
            // must be rewritten (off-pattern entries stay the zeros of Data::new).
            let other = &random_states(&model, 1, 99)[0];
            dynamics::crba(&model, &mut data, &other.q).unwrap();
            dynamics::crba(&model, &mut data, &s.q).unwrap();
            let e = (&data.h - &want).amax() / want.amax();
            assert!(e < 1e-12, "{name}: crba vs rnea columns {e:e}");
            assert_eq!(data.h, data.h.transpose(), "{name}: H not symmetric");
        }
    }
}

#[test]
fn forward_dynamics_methods_agree_on_fixtures() {
    let mut worst = 0.0f64;
    for (name, model) in fixtures() {
        let mut data = Data::new(&model);
        for s in random_states(&model, 8, 12) {
            let want = dynamics::forward_dynamics_rnea(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let crba = dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let fd = dynamics::forward_dynamics(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let e1 = rel(&crba, &want);
            let e2 = rel(&fd, &want);
            assert!(e1 < 1e-10, "{name}: crba+ltdl vs fd-rnea {e1:e}");
            assert!(e2 < 1e-10, "{name}: fd vs fd-rnea {e2:e}");
            worst = worst.max(e1).max(e2);
            if model.has_mimic {
                assert!(dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None).is_err());
                assert_eq!(model.topology.fd_method, FdMethod::CrbaDense);
            } else {
                let aba = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                    .unwrap()
                    .clone();
                let e3 = rel(&aba, &want);
                assert!(e3 < 1e-10, "{name}: aba vs fd-rnea {e3:e}");
                worst = worst.max(e3);
            }
        }
    }
    eprintln!("worst relative disagreement with fd-rnea: {worst:e}");
}

#[test]
fn external_forces_agree() {
    use urdyn::spatial::Force;
    for (name, model) in fixtures() {
        if model.has_mimic {
            continue;
        }
        let mut data = Data::new(&model);
        let fext: Vec<Force<f64>> = (0..model.nbodies)
            .map(|i| {
                let x = i as f64;
                Force::new(
                    nalgebra::Vector3::new(0.1 * x, -0.2, 0.3),
                    nalgebra::Vector3::new(1.0, 0.5 * x, -2.0),
                )
            })
            .collect();
        for s in random_states(&model, 3, 13) {
            let want =
                dynamics::forward_dynamics_rnea(&model, &mut data, &s.q, &s.v, &s.tau, Some(&fext))
                    .unwrap()
                    .clone();
            let aba = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, Some(&fext))
                .unwrap()
                .clone();
            let e = rel(&aba, &want);
            assert!(e < 1e-10, "{name}: aba with fext {e:e}");
            let fd =
                dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, Some(&fext))
                    .unwrap()
                    .clone();
            let e = rel(&fd, &want);
            assert!(e < 1e-10, "{name}: crba with fext {e:e}");
        }
    }
}

#[test]
fn ltdl_solves_like_dense_cholesky() {
    for (name, model) in fixtures() {
        if model.has_mimic {
            continue;
        }
        let mut data = Data::new(&model);
        let s = &random_states(&model, 1, 14)[0];
        dynamics::crba(&model, &mut data, &s.q).unwrap();
        let h = data.h.clone();
        let mut u = DMatrix::zeros(model.nv, model.nv);
        ltdl::ltdl(&h, &model.dof_parent, &mut u).unwrap();
        let mut x = s.tau.clone();
        ltdl::ltdl_solve(&u, &model.dof_parent, &mut x);
        let r = &h * &x - &s.tau;
        assert!(
            r.amax() < 1e-11 * h.amax() * x.amax().max(1.0),
            "{name}: residual {}",
            r.amax()
        );
    }
}

#[test]
fn ltdl_reports_singular_pivots() {
    let model = load("assets/synthetic/chain_5.urdf");
    let lambda = &model.dof_parent;
    let mut h = DMatrix::<f64>::identity(5, 5);
    h[(2, 2)] = 0.0;
    let mut u = DMatrix::zeros(5, 5);
    assert_eq!(ltdl::ltdl(&h, lambda, &mut u), Err(2));
    h[(2, 2)] = f64::NAN;
    assert_eq!(ltdl::ltdl(&h, lambda, &mut u), Err(2));
}

fn load(rel: &str) -> Model {
    urdyn::load_file(root().join(rel), LoadOptions::default()).unwrap()
}

/// ‖H q̈ + C − τ‖ / (‖H‖ ‖q̈‖ + ‖τ‖) with C and H from the seed's methods.
fn backward_error(model: &Model, s: &State, qdd: &DVector<f64>) -> f64 {
    let mut data = Data::new(model);
    let c = dynamics::bias(model, &mut data, &s.q, &s.v, None)
        .unwrap()
        .clone();
    dynamics::mass_matrix_rnea(model, &mut data, &s.q).unwrap();
    let h = data.h.clone();
    let r = &h * qdd + c - &s.tau;
    r.norm() / (h.norm() * qdd.norm() + s.tau.norm())
}

#[test]
fn long_chains_backward_error() {
    for n in [100, 500, 1000] {
        let model = load(&format!("assets/synthetic/chain_{n}.urdf"));
        assert_eq!(model.topology.fd_method, FdMethod::Aba, "chain_{n}");
        let mut data = Data::new(&model);
        let s = &random_states(&model, 1, 15)[0];
        let aba = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None)
            .unwrap()
            .clone();
        let crba = dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, None)
            .unwrap()
            .clone();
        let fd = dynamics::forward_dynamics(&model, &mut data, &s.q, &s.v, &s.tau, None)
            .unwrap()
            .clone();
        for (what, x) in [("aba", &aba), ("crba+ltdl", &crba), ("fd", &fd)] {
            let e = backward_error(&model, s, x);
            eprintln!("chain_{n} {what}: backward error {e:e}");
            assert!(e <= 1e-13, "chain_{n} {what}: backward error {e:e}");
        }
        if n <= 500 {
            let seed = dynamics::forward_dynamics_rnea(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let e = backward_error(&model, s, &seed);
            eprintln!("chain_{n} fd-rnea: backward error {e:e}");
            assert!(e <= 1e-13, "chain_{n} fd-rnea: backward error {e:e}");
        }
    }
}

#[test]
fn tree_crba_and_fd() {
    for d in [4, 6, 8] {
        let model = load(&format!("assets/synthetic/tree_{d}.urdf"));
        let mut data = Data::new(&model);
        for s in random_states(&model, 2, 16) {
            let want = dynamics::forward_dynamics_rnea(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let aba = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let crba = dynamics::forward_dynamics_crba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            assert!(rel(&aba, &want) < 1e-10, "tree_{d} aba");
            assert!(rel(&crba, &want) < 1e-10, "tree_{d} crba");
        }
    }
}

/// The fd rule (`Topology::choose`, fitted on callgrind counts): CRBA + LTDL on a
/// small branching tree, ABA on a 6-DoF arm and on a chain of 50, and `fd` there
/// equal to the method it names.
#[test]
fn fd_rule_picks_per_model() {
    for (file, want) in [
        ("assets/synthetic/tree_4.urdf", FdMethod::CrbaSparse),
        ("assets/robots/ur5.urdf", FdMethod::Aba),
        ("assets/synthetic/chain_50.urdf", FdMethod::Aba),
    ] {
        let model = load(file);
        assert_eq!(model.topology.fd_method, want, "{file}");
        let mut data = Data::new(&model);
        let s = &random_states(&model, 1, 3)[0];
        let fd = dynamics::forward_dynamics(&model, &mut data, &s.q, &s.v, &s.tau, None)
            .unwrap()
            .clone();
        let aba = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None)
            .unwrap()
            .clone();
        assert!((&fd - &aba).norm() <= 1e-10 * (1.0 + aba.norm()), "{file}");
    }
}

/// Joints about negative coordinate axes (Gymnasium's hopper and walker2d hinge
/// about `0 -1 0`, the humanoid also about `-1 0 0` and `0 0 -1`) run as the
/// positive axis with the coordinate negated (src/model/joint/mod.rs,
/// `dispatch_of`). Checked against independent routes: a model whose negative
/// axes are written as the positive axis at −q (the same mechanism) gives the same
/// H, τ and q̈ with the rows and columns of those coordinates negated, and ABA
/// agrees with the CRBA + Cholesky solve, on random states.
#[test]
fn negative_axes_match_the_mirrored_model() {
    let dir = root().join("tests/fixtures/mjcf/gymnasium");
    for name in ["hopper", "walker2d", "humanoid"] {
        let text = std::fs::read_to_string(dir.join(format!("{name}.xml"))).unwrap();
        let model = urdyn::mjcf::load_str(&text, name, &dir).unwrap();
        // the mirrored file: each negative coordinate axis written positive
        let mut flipped = Vec::new();
        let mut mirrored = String::new();
        let mut rest = text.as_str();
        let mut joint = 0usize;
        while let Some(at) = rest.find("<joint") {
            let end = at + rest[at..].find('>').unwrap();
            let tag = &rest[at..=end];
            let mut new_tag = tag.to_string();
            for (neg, pos) in [
                ("axis=\"-1 0 0\"", "axis=\"1 0 0\""),
                ("axis=\"0 -1 0\"", "axis=\"0 1 0\""),
                ("axis=\"0 0 -1\"", "axis=\"0 0 1\""),
            ] {
                if tag.contains(neg) {
                    new_tag = tag.replace(neg, pos);
                }
            }
            // joints inside <default> have no name and no coordinate
            if tag.contains(" name=") {
                let jname = tag
                    .split("name=\"")
                    .nth(1)
                    .unwrap()
                    .split('"')
                    .next()
                    .unwrap();
                if new_tag != tag {
                    flipped.push(jname.to_string());
                }
                joint += 1;
            }
            mirrored.push_str(&rest[..at]);
            mirrored.push_str(&new_tag);
            rest = &rest[end + 1..];
        }
        mirrored.push_str(rest);
        assert!(
            joint > 0 && !flipped.is_empty(),
            "{name}: no negative axis found"
        );
        let model_m = urdyn::mjcf::load_str(&mirrored, name, &dir).unwrap();
        assert_eq!((model.nq, model.nv), (model_m.nq, model_m.nv));
        // the sign of each velocity coordinate (and of its q, for 1-DoF joints)
        let mut sign = DVector::from_element(model.nv, 1.0);
        let mut qsign = DVector::from_element(model.nq, 1.0);
        for d in &model.dofs {
            if flipped.contains(&d.name) {
                sign[d.iv] = -1.0;
                qsign[d.iq] = -1.0;
            }
        }
        assert_eq!(
            sign.iter().filter(|&&s| s < 0.0).count(),
            flipped.len(),
            "{name}"
        );
        let (mut data, mut data_m) = (Data::new(&model), Data::new(&model_m));
        for s in random_states(&model, 5, 7) {
            let (qm, vm, tm) = (
                s.q.component_mul(&qsign),
                s.v.component_mul(&sign),
                s.tau.component_mul(&sign),
            );
            let qdd = dynamics::aba(&model, &mut data, &s.q, &s.v, &s.tau, None)
                .unwrap()
                .clone();
            let qdd_m = dynamics::aba(&model_m, &mut data_m, &qm, &vm, &tm, None)
                .unwrap()
                .component_mul(&sign);
            let e = rel(&qdd, &qdd_m);
            assert!(e < 1e-10, "{name}: aba vs the mirrored model {e:e}");
            let h = dynamics::mass_matrix(&model, &mut data, &s.q)
                .unwrap()
                .clone();
            let h_m = dynamics::mass_matrix(&model_m, &mut data_m, &qm)
                .unwrap()
                .clone();
            let d = DMatrix::from_diagonal(&sign);
            let eh = (&h - &d * h_m * &d).amax() / h.amax();
            assert!(eh < 1e-12, "{name}: H vs the mirrored model {eh:e}");
            let c = dynamics::bias(&model, &mut data, &s.q, &s.v, None)
                .unwrap()
                .clone();
            // ABA against H⁻¹ (τ − C) by a dense Cholesky
            let mut l = DMatrix::zeros(model.nv, model.nv);
            dynamics::linalg::cholesky(&h, &mut l).unwrap();
            let mut x = &s.tau - &c;
            dynamics::linalg::cholesky_solve(&l, &mut x);
            let e2 = rel(&qdd, &x);
            assert!(e2 < 1e-10, "{name}: aba vs crba + cholesky {e2:e}");
        }
    }
}
