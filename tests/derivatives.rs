//! The analytic derivatives (docs/theory.md §"Derivatives") against central finite
//! differences of the engine's own values (q perturbed through `integrate`), on
//! fixed, floating and mimic robots, with external wrenches; and the identities
//! ∂τ/∂a = H, H⁻¹ H = 1, classical acceleration = J a + J̇ v,
//! ∂q̈/∂q = −H⁻¹ ∂τ/∂q at a = q̈.

use nalgebra::{DMatrix, DVector, Vector3};
use std::path::PathBuf;
use urdyn::cli::bench::{random_states, State};
use urdyn::dynamics_f64::{self as dynamics, LinkWrench, Reference};
use urdyn::model::configuration::{
    difference, difference_jacobians, integrate, integrate_jacobians,
};
use urdyn::spatial::Force;
use urdyn::{Data, LoadOptions, Model};

fn load(path: &str, floating_base: bool) -> Model {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::load_file(root.join(path), LoadOptions { floating_base }).unwrap()
}

const ROBOTS: [(&str, bool); 9] = [
    ("assets/robots/ur5.urdf", false),
    ("assets/robots/solo12.urdf", true),
    ("assets/robots/panda.urdf", false),
    ("tests/urdf/mimic.urdf", false),
    ("tests/urdf/mimic.urdf", true),
    // a follower across branches: the dense factor (`Topology::mimic_tree`)
    ("tests/urdf/mimic_cross.urdf", true),
    ("assets/synthetic/tree_5.urdf", false),
    ("assets/robots/anymal.urdf", true),
    ("assets/robots/ur5.urdf", true),
];

/// A few wrenches on links spread over the model (world coordinates).
fn wrenches(model: &Model) -> Vec<LinkWrench> {
    let nf = model.frames.len();
    [nf - 1, nf / 2, nf / 3, nf - 1]
        .iter()
        .enumerate()
        .map(|(k, &f)| LinkWrench {
            frame: urdyn::model::FrameId(f),
            force: Vector3::new(1.5 - k as f64, 0.7, -2.0 + 0.3 * k as f64),
            torque: Vector3::new(0.2, -0.4 * k as f64, 0.9),
        })
        .collect()
}

/// The per-body wrenches at q, as `rnea` takes them.
fn body_forces(model: &Model, data: &mut Data, q: &DVector<f64>, w: &[LinkWrench]) -> Vec<Force> {
    dynamics::forward_kinematics(model, data, q).unwrap();
    let mut f = vec![Force::zero(); model.nbodies];
    for x in w {
        dynamics::add_link_wrench(model, data, x.frame, &x.force, &x.torque, &mut f).unwrap();
    }
    f
}

fn tau_at(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    w: &[LinkWrench],
) -> DVector<f64> {
    let mut d = Data::new(model);
    let f = body_forces(model, &mut d, q, w);
    dynamics::rnea(model, &mut d, q, v, a, Some(&f))
        .unwrap()
        .clone()
}

fn qdd_at(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
    t: &DVector<f64>,
    w: &[LinkWrench],
) -> DVector<f64> {
    let mut d = Data::new(model);
    let f = body_forces(model, &mut d, q, w);
    dynamics::forward_dynamics(model, &mut d, q, v, t, Some(&f))
        .unwrap()
        .clone()
}

/// Central differences of `f` along each tangent direction of q (through
/// `integrate`) or of a vector argument.
fn fd_q(
    model: &Model,
    q: &DVector<f64>,
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
) -> DMatrix<f64> {
    let eps = 1e-6;
    let mut m = DMatrix::zeros(model.nv, model.nv);
    for k in 0..model.nv {
        let mut e = DVector::zeros(model.nv);
        e[k] = eps;
        let qp = integrate(model, q, &e).unwrap();
        let qm = integrate(model, q, &(-&e)).unwrap();
        m.set_column(k, &((f(&qp) - f(&qm)) / (2.0 * eps)));
    }
    m
}

fn fd_vec(
    x: &DVector<f64>,
    rows: usize,
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
) -> DMatrix<f64> {
    let eps = 1e-6;
    let mut m = DMatrix::zeros(rows, x.len());
    for k in 0..x.len() {
        let mut xp = x.clone();
        let mut xm = x.clone();
        xp[k] += eps;
        xm[k] -= eps;
        m.set_column(k, &((f(&xp) - f(&xm)) / (2.0 * eps)));
    }
    m
}

/// max|a − b| / max(1, max|b|).
fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    (a - b).amax() / b.amax().max(1.0)
}

fn states(model: &Model) -> Vec<State> {
    random_states(model, 3, 21)
}

#[test]
fn rnea_derivatives_match_finite_differences() {
    for (path, fb) in ROBOTS {
        let model = load(path, fb);
        let mut data = Data::new(&model);
        for (si, s) in states(&model).iter().enumerate() {
            for w in [vec![], wrenches(&model)] {
                let wf = (!w.is_empty()).then_some(w.as_slice());
                dynamics::rnea_derivatives(&model, &mut data, &s.q, &s.v, &s.a, wf).unwrap();
                let tau = tau_at(&model, &s.q, &s.v, &s.a, &w);
                assert!(
                    (&data.tau - &tau).amax() < 1e-10 * tau.amax().max(1.0),
                    "{path}: tau"
                );
                let dq = fd_q(&model, &s.q, |q| tau_at(&model, q, &s.v, &s.a, &w));
                let dv = fd_vec(&s.v, model.nv, |v| tau_at(&model, &s.q, v, &s.a, &w));
                let da = fd_vec(&s.a, model.nv, |a| tau_at(&model, &s.q, &s.v, a, &w));
                let (eq, ev, ea) = (
                    rel(&data.dtau_dq, &dq),
                    rel(&data.dtau_dv, &dv),
                    rel(&data.h, &da),
                );
                assert!(
                    eq < 1e-7 && ev < 1e-7 && ea < 1e-7,
                    "{path} fb={fb} state {si} fext={}: dq {eq:e} dv {ev:e} da {ea:e}",
                    !w.is_empty()
                );
                // ∂τ/∂a = H (the CRBA's)
                let mut d2 = Data::new(&model);
                let h = dynamics::crba(&model, &mut d2, &s.q).unwrap().clone();
                assert!(rel(&data.h, &h) < 1e-13, "{path}: H");
            }
        }
    }
}

#[test]
fn aba_derivatives_match_finite_differences_and_identities() {
    for (path, fb) in ROBOTS {
        let model = load(path, fb);
        let mut data = Data::new(&model);
        for (si, s) in states(&model).iter().enumerate() {
            for w in [vec![], wrenches(&model)] {
                let wf = (!w.is_empty()).then_some(w.as_slice());
                dynamics::aba_derivatives(&model, &mut data, &s.q, &s.v, &s.tau, wf)
                    .unwrap_or_else(|e| panic!("{path} fb={fb} state {si}: {e}"));
                let qdd = qdd_at(&model, &s.q, &s.v, &s.tau, &w);
                assert!((&data.qdd - &qdd).amax() < 1e-9 * qdd.amax().max(1.0));
                let dq = fd_q(&model, &s.q, |q| qdd_at(&model, q, &s.v, &s.tau, &w));
                let dv = fd_vec(&s.v, model.nv, |v| qdd_at(&model, &s.q, v, &s.tau, &w));
                let dt = fd_vec(&s.tau, model.nv, |t| qdd_at(&model, &s.q, &s.v, t, &w));
                let (eq, ev, et) = (
                    rel(&data.dqdd_dq, &dq),
                    rel(&data.dqdd_dv, &dv),
                    rel(&data.minv, &dt),
                );
                assert!(
                    eq < 1e-6 && ev < 1e-6 && et < 1e-6,
                    "{path} fb={fb} state {si}: dq {eq:e} dv {ev:e} dtau {et:e}"
                );
                // H⁻¹ H = 1, H⁻¹ symmetric
                let (minv, dqdd_dq) = (data.minv.clone(), data.dqdd_dq.clone());
                let mut d2 = Data::new(&model);
                let h = dynamics::crba(&model, &mut d2, &s.q).unwrap().clone();
                let id = DMatrix::identity(model.nv, model.nv);
                assert!(rel(&(&minv * &h), &id) < 1e-10, "{path}: Minv H");
                assert!(
                    rel(&minv, &minv.transpose()) < 1e-12,
                    "{path}: Minv symmetric"
                );
                // ∂q̈/∂q = −H⁻¹ ∂τ/∂q at a = q̈
                dynamics::rnea_derivatives(&model, &mut d2, &s.q, &s.v, &qdd, wf).unwrap();
                let want = -(&minv * &d2.dtau_dq);
                assert!(
                    rel(&dqdd_dq, &want) < 1e-10,
                    "{path}: dqdd_dq = -Minv dtau_dq"
                );
            }
        }
    }
}

#[test]
fn jacobian_time_variation_gives_classical_acceleration() {
    for (path, fb) in ROBOTS {
        let model = load(path, fb);
        let mut data = Data::new(&model);
        for s in &states(&model) {
            for f in [model.frames.len() - 1, model.frames.len() / 2, 0] {
                let fid = urdyn::model::FrameId(f);
                let mut jd = DMatrix::zeros(6, model.nv);
                let mut jdl = DMatrix::zeros(6, model.nv);
                dynamics::frame_jacobian_time_variation(
                    &model,
                    &mut data,
                    &s.q,
                    &s.v,
                    fid,
                    Reference::WorldAligned,
                    &mut jd,
                )
                .unwrap();
                dynamics::frame_jacobian_time_variation(
                    &model,
                    &mut data,
                    &s.q,
                    &s.v,
                    fid,
                    Reference::Local,
                    &mut jdl,
                )
                .unwrap();
                // classical acceleration = J a + J̇ v (world-aligned)
                dynamics::forward_kinematics_second_order(&model, &mut data, &s.q, &s.v, &s.a)
                    .unwrap();
                let mut j = DMatrix::zeros(6, model.nv);
                dynamics::frame_jacobian(&model, &data, fid, Reference::WorldAligned, &mut j)
                    .unwrap();
                let acc = dynamics::frame_classical_acceleration(
                    &model,
                    &data,
                    fid,
                    Reference::WorldAligned,
                )
                .unwrap();
                let got = &j * &s.a + &jd * &s.v;
                let want = DVector::from_vec(vec![
                    acc.lin.x, acc.lin.y, acc.lin.z, acc.ang.x, acc.ang.y, acc.ang.z,
                ]);
                assert!(
                    (&got - &want).amax() < 1e-11 * want.amax().max(1.0),
                    "{path}: J a + Jdot v"
                );
                // both against the time derivative of J along v (q ⊕ t v)
                for (r, jdr) in [(Reference::WorldAligned, &jd), (Reference::Local, &jdl)] {
                    let jac = |t: f64| {
                        let qt = integrate(&model, &s.q, &(&s.v * t)).unwrap();
                        let mut d = Data::new(&model);
                        dynamics::forward_kinematics(&model, &mut d, &qt).unwrap();
                        let mut j = DMatrix::zeros(6, model.nv);
                        dynamics::frame_jacobian(&model, &d, fid, r, &mut j).unwrap();
                        j
                    };
                    let eps = 1e-6;
                    let fd = (jac(eps) - jac(-eps)) / (2.0 * eps);
                    assert!(
                        rel(jdr, &fd) < 1e-7,
                        "{path} {r:?}: Jdot vs finite differences {:e}",
                        rel(jdr, &fd)
                    );
                }
            }
        }
    }
}

#[test]
fn derivative_sizes_are_checked() {
    let model = load("assets/robots/ur5.urdf", false);
    let mut data = Data::new(&model);
    let s = &states(&model)[0];
    let short = DVector::zeros(model.nv - 1);
    let e = dynamics::rnea_derivatives(&model, &mut data, &s.q, &short, &s.a, None).unwrap_err();
    assert!(e.to_string().contains("v has"), "{e}");
    let e = dynamics::aba_derivatives(&model, &mut data, &short, &s.v, &s.tau, None).unwrap_err();
    assert!(e.to_string().contains("q has"), "{e}");
    let mut j = DMatrix::zeros(6, model.nv + 1);
    let e = dynamics::frame_jacobian_time_variation(
        &model,
        &mut data,
        &s.q,
        &s.v,
        urdyn::model::FrameId(1),
        Reference::Local,
        &mut j,
    )
    .unwrap_err();
    assert!(e.to_string().contains("jacobian_dot columns"), "{e}");
    let bad = [LinkWrench {
        frame: urdyn::model::FrameId(9999),
        force: Vector3::zeros(),
        torque: Vector3::zeros(),
    }];
    assert!(dynamics::rnea_derivatives(&model, &mut data, &s.q, &s.v, &s.a, Some(&bad)).is_err());
}

#[test]
fn integrate_and_difference_jacobians_match_finite_differences() {
    for (path, fb) in [
        ("assets/robots/solo12.urdf", true),
        ("assets/robots/ur5.urdf", false),
    ] {
        let model = load(path, fb);
        for seed in 0..5u64 {
            let q = urdyn::model::configuration::random_configuration(&model, seed);
            let q1 = urdyn::model::configuration::random_configuration(&model, seed + 50);
            let dv = DVector::from_fn(model.nv, |k, _| {
                0.3 * ((k as f64) * 0.7 + seed as f64).sin()
            });
            let (jq, jv) = integrate_jacobians(&model, &q, &dv).unwrap();
            let base = integrate(&model, &q, &dv).unwrap();
            // d/dε (q ⊕ ε) ⊕ dv ⊖ (q ⊕ dv), and q ⊕ (dv + ε) ⊖ (q ⊕ dv)
            let fq = fd_q(&model, &q, |qq| {
                difference(&model, &base, &integrate(&model, qq, &dv).unwrap()).unwrap()
            });
            let fv = fd_vec(&dv, model.nv, |d| {
                difference(&model, &base, &integrate(&model, &q, d).unwrap()).unwrap()
            });
            assert!(
                rel(&jq, &fq) < 1e-8,
                "{path}: dIntegrate/dq {:e}",
                rel(&jq, &fq)
            );
            assert!(
                rel(&jv, &fv) < 1e-8,
                "{path}: dIntegrate/dv {:e}",
                rel(&jv, &fv)
            );
            let (d0, d1) = difference_jacobians(&model, &q, &q1).unwrap();
            let f0 = fd_q(&model, &q, |qq| difference(&model, qq, &q1).unwrap());
            let f1 = fd_q(&model, &q1, |qq| difference(&model, &q, qq).unwrap());
            assert!(
                rel(&d0, &f0) < 1e-8,
                "{path}: dDifference/dq0 {:e}",
                rel(&d0, &f0)
            );
            assert!(
                rel(&d1, &f1) < 1e-8,
                "{path}: dDifference/dq1 {:e}",
                rel(&d1, &f1)
            );
        }
    }
}

#[test]
fn aba_derivatives_low_rank_and_tiled_products_agree() {
    // Data::new picks the low-rank products on long chains only
    let chain = load("assets/synthetic/chain_100.urdf", false);
    assert!(
        Data::new(&chain).deriv_low_rank,
        "chain_100: low-rank products"
    );
    let solo = load("assets/robots/solo12.urdf", true);
    assert!(!Data::new(&solo).deriv_low_rank, "solo12: tiled products");
    let robots = [
        ("assets/synthetic/chain_100.urdf", false),
        ("assets/robots/talos_reduced.urdf", true),
        ("assets/robots/anymal.urdf", true),
        ("assets/synthetic/tree_5.urdf", false),
        ("assets/robots/ur5.urdf", false),
    ];
    for (path, fb) in robots {
        let model = load(path, fb);
        let mut data = Data::new(&model);
        for (si, s) in states(&model).iter().enumerate() {
            for w in [vec![], wrenches(&model)] {
                let wf = (!w.is_empty()).then_some(w.as_slice());
                let mut got = Vec::new();
                let mut minvs = Vec::new();
                for low_rank in [false, true] {
                    data.deriv_low_rank = low_rank;
                    dynamics::aba_derivatives(&model, &mut data, &s.q, &s.v, &s.tau, wf).unwrap();
                    got.push((data.dqdd_dq.clone(), data.dqdd_dv.clone()));
                    minvs.push(data.minv.clone());
                }
                // H⁻¹ the same on both routes (the same world-frame ABA)
                assert_eq!(minvs[0], minvs[1], "{path} fb={fb} state {si}: Minv");
                // ∂τ/∂x whole at a = q̈ (the low-rank route leaves in data.dtau_*
                // only each joint's own block)
                let qdd = data.qdd.clone();
                dynamics::rnea_derivatives(&model, &mut data, &s.q, &s.v, &qdd, wf).unwrap();
                // and both are −H⁻¹ ∂τ/∂x (to rounding: the routes sum in different
                // orders, on chain_100 ~1e-12 apart relative to the largest entry)
                let want_q = -(&minvs[0] * &data.dtau_dq);
                let want_v = -(&minvs[0] * &data.dtau_dv);
                for (k, (dq, dv)) in got.iter().enumerate() {
                    let (eq, ev) = (rel(dq, &want_q), rel(dv, &want_v));
                    assert!(
                        eq < 1e-11 && ev < 1e-11,
                        "{path} fb={fb} state {si} fext={} route {k}: dq {eq:e} dv {ev:e}",
                        !w.is_empty()
                    );
                }
            }
        }
    }
}
