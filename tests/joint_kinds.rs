//! The joint kinds of mechanisms.md (spherical, planar — one about a tilted axis
//! — and floating inside the tree, mixed with revolute and prismatic joints,
//! with and without a floating base) against Pinocchio 4.1's `addJoint` models
//! (tests/oracle/make_joint_fixtures.py, tests/fixtures/joints/): RNEA, CRBA,
//! ABA, CRBA + LTDL, the n+1 RNEA method, H⁻¹, bias, frame Jacobians and their
//! time variation, frame placements, centre of mass, centroidal momentum,
//! energies, RNEA and ABA derivatives in the tangent space, integrate,
//! difference and their Jacobians: all within 1e-10 relative to
//! max(1, max|reference|) per quantity (the derivatives within 1e-9).

use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::path::PathBuf;
use urdyn::dynamics_f64::{self as dynamics, Reference};
use urdyn::model::configuration;
use urdyn::model::Data;
use urdyn::LoadOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn flat(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN)),
        Value::Array(a) => a.iter().for_each(|x| flat(x, out)),
        _ => out.push(f64::NAN),
    }
}

fn vecof(v: &Value) -> DVector<f64> {
    let mut out = Vec::new();
    flat(v, &mut out);
    DVector::from_vec(out)
}

/// Row-major JSON matrix entries, compared with a column-major `DMatrix`.
fn mat_rows(m: &DMatrix<f64>) -> Vec<f64> {
    let mut out = Vec::with_capacity(m.len());
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            out.push(m[(r, c)]);
        }
    }
    out
}

struct Check {
    fails: Vec<String>,
    worst: f64,
}

impl Check {
    fn cmp(&mut self, what: &str, got: &[f64], want: &Value, tol: f64) {
        let mut w = Vec::new();
        flat(want, &mut w);
        if got.len() != w.len() {
            self.fails
                .push(format!("{what}: {} entries, want {}", got.len(), w.len()));
            return;
        }
        let scale = w.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let e = got
            .iter()
            .zip(&w)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        let e = if e.is_nan() { f64::INFINITY } else { e };
        self.worst = self.worst.max(e);
        if e > tol {
            self.fails.push(format!("{what}: error {e:.3e}"));
        }
    }
}

fn run(fixture: &str) {
    let text = std::fs::read_to_string(root().join("tests/fixtures/joints").join(fixture)).unwrap();
    let fx: Value = serde_json::from_str(&text).unwrap();
    let model = urdyn::load_file(
        root().join(fx["urdf"].as_str().unwrap()),
        LoadOptions {
            floating_base: fx["floating_base"].as_bool().unwrap(),
        },
    )
    .unwrap();
    assert_eq!(model.nq as u64, fx["nq"].as_u64().unwrap(), "nq");
    assert_eq!(model.nv as u64, fx["nv"].as_u64().unwrap(), "nv");
    let names: Vec<&str> = model.body_joint_names[1..]
        .iter()
        .map(|s| s.as_str())
        .collect();
    let want_names: Vec<&str> = fx["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(names, want_names, "joint order");
    let mut ck = Check {
        fails: Vec::new(),
        worst: 0.0,
    };
    const TOL: f64 = 1e-10;
    const DTOL: f64 = 1e-9;
    let nv = model.nv;
    for (s, st) in fx["states"].as_array().unwrap().iter().enumerate() {
        let (q, v, a, tau, v2) = (
            vecof(&st["q"]),
            vecof(&st["v"]),
            vecof(&st["a"]),
            vecof(&st["tau"]),
            vecof(&st["v2"]),
        );
        let e = &st["expected"];
        let mut d = Data::new(&model);
        let tag = |w: &str| format!("{fixture} state {s} {w}");
        let got = dynamics::rnea(&model, &mut d, &q, &v, &a, None)
            .unwrap()
            .clone();
        ck.cmp(&tag("rnea"), got.as_slice(), &e["tau"], TOL);
        let h = dynamics::crba(&model, &mut d, &q).unwrap().clone();
        ck.cmp(&tag("crba"), &mat_rows(&h), &e["H"], TOL);
        dynamics::mass_matrix_rnea(&model, &mut d, &q).unwrap();
        ck.cmp(&tag("mass_matrix_rnea"), &mat_rows(&d.h), &e["H"], TOL);
        let qdd = dynamics::aba(&model, &mut d, &q, &v, &tau, None)
            .unwrap()
            .clone();
        ck.cmp(&tag("aba"), qdd.as_slice(), &e["qdd"], TOL);
        let qdd = dynamics::forward_dynamics_crba(&model, &mut d, &q, &v, &tau, None)
            .unwrap()
            .clone();
        ck.cmp(&tag("crba+ltdl"), qdd.as_slice(), &e["qdd"], TOL);
        let qdd = dynamics::forward_dynamics_rnea(&model, &mut d, &q, &v, &tau, None)
            .unwrap()
            .clone();
        ck.cmp(&tag("n+1 rnea"), qdd.as_slice(), &e["qdd"], TOL);
        let b = dynamics::bias(&model, &mut d, &q, &v, None)
            .unwrap()
            .clone();
        ck.cmp(&tag("bias"), b.as_slice(), &e["bias"], TOL);
        // frames
        dynamics::forward_kinematics(&model, &mut d, &q).unwrap();
        dynamics::update_frames(&model, &mut d);
        for f in fx["frames"].as_array().unwrap() {
            let f = f.as_str().unwrap();
            let id = model.frame_id(f).unwrap();
            let ef = &e["frames"][f];
            let m = d.o_m_f[id.0];
            let mut hom = DMatrix::<f64>::identity(4, 4);
            for r in 0..3 {
                for c in 0..3 {
                    hom[(r, c)] = m.rot[(r, c)];
                }
                hom[(r, 3)] = m.trans[r];
            }
            ck.cmp(
                &tag(&format!("{f} placement")),
                &mat_rows(&hom),
                &ef["placement"],
                TOL,
            );
            for (key, reference) in [
                ("world_aligned", Reference::WorldAligned),
                ("local", Reference::Local),
            ] {
                let mut j = DMatrix::zeros(6, nv);
                dynamics::frame_jacobian(&model, &d, id, reference, &mut j).unwrap();
                ck.cmp(
                    &tag(&format!("{f} jacobian {key}")),
                    &mat_rows(&j),
                    &ef[key],
                    TOL,
                );
                let mut jd = DMatrix::zeros(6, nv);
                dynamics::frame_jacobian_time_variation(
                    &model, &mut d, &q, &v, id, reference, &mut jd,
                )
                .unwrap();
                ck.cmp(
                    &tag(&format!("{f} jacobian_dot {key}")),
                    &mat_rows(&jd),
                    &ef[&format!("dot_{key}")],
                    TOL,
                );
            }
        }
        // centre of mass, momentum, energies
        dynamics::rnea(&model, &mut d, &q, &v, &a, None).unwrap();
        let c = dynamics::center_of_mass(&model, &d);
        ck.cmp(&tag("com"), c.as_slice(), &e["com"], TOL);
        let cv = dynamics::center_of_mass_velocity(&model, &d);
        ck.cmp(&tag("com velocity"), cv.as_slice(), &e["com_velocity"], TOL);
        let mut jc = DMatrix::zeros(3, nv);
        dynamics::center_of_mass_jacobian(&model, &d, &mut jc).unwrap();
        ck.cmp(
            &tag("com jacobian"),
            &mat_rows(&jc),
            &e["com_jacobian"],
            TOL,
        );
        let (k, l) = dynamics::centroidal_momentum(&model, &mut d, &q, &v).unwrap();
        ck.cmp(
            &tag("momentum angular"),
            k.as_slice(),
            &e["momentum_angular"],
            TOL,
        );
        ck.cmp(
            &tag("momentum linear"),
            l.as_slice(),
            &e["momentum_linear"],
            TOL,
        );
        let (ke, pe) = dynamics::energies(&model, &q, &v).unwrap();
        ck.cmp(&tag("kinetic"), &[ke], &e["kinetic"], TOL);
        ck.cmp(&tag("potential"), &[pe], &e["potential"], TOL);
        // derivatives
        dynamics::rnea_derivatives(&model, &mut d, &q, &v, &a, None).unwrap();
        ck.cmp(&tag("dtau_dq"), &mat_rows(&d.dtau_dq), &e["dtau_dq"], DTOL);
        ck.cmp(&tag("dtau_dv"), &mat_rows(&d.dtau_dv), &e["dtau_dv"], DTOL);
        dynamics::aba_derivatives(&model, &mut d, &q, &v, &tau, None).unwrap();
        ck.cmp(&tag("dqdd_dq"), &mat_rows(&d.dqdd_dq), &e["dqdd_dq"], DTOL);
        ck.cmp(&tag("dqdd_dv"), &mat_rows(&d.dqdd_dv), &e["dqdd_dv"], DTOL);
        ck.cmp(&tag("minv"), &mat_rows(&d.minv), &e["minv"], DTOL);
        // the configuration manifold
        let q1 = configuration::integrate(&model, &q, &v2).unwrap();
        ck.cmp(&tag("integrate"), q1.as_slice(), &e["integrate"], TOL);
        let dv = configuration::difference(&model, &q, &q1).unwrap();
        ck.cmp(&tag("difference"), dv.as_slice(), &e["difference"], TOL);
        let (jq, jv) = configuration::integrate_jacobians(&model, &q, &v2).unwrap();
        ck.cmp(
            &tag("dintegrate_dq"),
            &mat_rows(&jq),
            &e["dintegrate_dq"],
            TOL,
        );
        ck.cmp(
            &tag("dintegrate_dv"),
            &mat_rows(&jv),
            &e["dintegrate_dv"],
            TOL,
        );
        let (j0, j1) = configuration::difference_jacobians(&model, &q, &q1).unwrap();
        ck.cmp(
            &tag("ddifference_dq0"),
            &mat_rows(&j0),
            &e["ddifference_dq0"],
            TOL,
        );
        ck.cmp(
            &tag("ddifference_dq1"),
            &mat_rows(&j1),
            &e["ddifference_dq1"],
            TOL,
        );
    }
    assert!(
        ck.fails.is_empty(),
        "{} mismatches against Pinocchio (worst {:.3e}):\n{}",
        ck.fails.len(),
        ck.worst,
        ck.fails.join("\n")
    );
    eprintln!("{fixture}: worst relative error {:.3e}", ck.worst);
}

#[test]
fn mixed_joint_kinds_match_pinocchio() {
    run("mech.json");
}

#[test]
fn mixed_joint_kinds_on_a_floating_base_match_pinocchio() {
    run("mech_floating.json");
}

/// `eval` version 4 (mechanisms.md "In `eval` (version 4)"): `q_names` and
/// `v_names` in the engine's order, arrays for the joints of several degrees of
/// freedom in `tau`, `qdd` and `bias`, a quaternion within 1e-3 of unit norm
/// normalised, and every value the library's at the same (normalised) state; the
/// simulate CSV's columns are `q:`/`v:` before the same names.
#[test]
fn eval_v4_arrays_and_names() {
    use urdyn::cli::{eval, state};
    let dir = root().join("tests/bad");
    let model = urdyn::load_file(dir.join("joints_ok.urdf"), LoadOptions::default()).unwrap();
    let text = std::fs::read_to_string(dir.join("states_joints_ok.json")).unwrap();
    let states = state::parse_states(&text, "states_joints_ok.json").unwrap();
    let out = eval::evaluate(&model, &states, "joints_ok.urdf", "states_joints_ok.json").unwrap();
    let strs = |v: &Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect()
    };
    let q_names: Vec<String> = [
        "ball:qx",
        "ball:qy",
        "ball:qz",
        "ball:qw",
        "hinge",
        "mount:x",
        "mount:y",
        "mount:z",
        "mount:qx",
        "mount:qy",
        "mount:qz",
        "mount:qw",
        "slide:x",
        "slide:y",
        "slide:theta",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let v_names: Vec<String> = [
        "ball:wx", "ball:wy", "ball:wz", "hinge", "mount:vx", "mount:vy", "mount:vz", "mount:wx",
        "mount:wy", "mount:wz", "slide:vx", "slide:vy", "slide:wz",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    assert_eq!(strs(&out["q_names"]), q_names);
    assert_eq!(strs(&out["v_names"]), v_names);
    assert_eq!(model.q_names(), q_names);
    assert_eq!(strs(&out["dof_names"]), ["ball", "hinge", "mount", "slide"]);
    let (qc, vc) = urdyn::sim::column_names(&model);
    assert_eq!(qc[0], "q:ball:qx");
    assert_eq!(vc[12], "v:slide:wz");
    // the library at the normalised state
    let mut q = model.neutral();
    let mq = [0.1, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0];
    q.rows_mut(0, 4).copy_from_slice(&[0.0, 0.0, 0.6, 0.8]);
    q[4] = 0.3;
    q.rows_mut(5, 7).copy_from_slice(&mq);
    q.rows_mut(12, 3).copy_from_slice(&[0.1, 0.2, 0.3]);
    let mut v = DVector::zeros(13);
    v.rows_mut(0, 3).copy_from_slice(&[0.1, 0.2, 0.3]);
    v.rows_mut(10, 3).copy_from_slice(&[1.0, 0.0, 0.5]);
    let mut tau = DVector::zeros(13);
    tau[6] = 1.0;
    let mut d = Data::new(&model);
    let want_tau = dynamics::rnea(&model, &mut d, &q, &v, &DVector::zeros(13), None)
        .unwrap()
        .clone();
    let want_qdd = dynamics::aba(&model, &mut d, &q, &v, &tau, None)
        .unwrap()
        .clone();
    let r = &out["results"][0];
    let mut ck = Check {
        fails: Vec::new(),
        worst: 0.0,
    };
    for (key, want) in [("tau", &want_tau), ("qdd", &want_qdd)] {
        let m = &r[key];
        assert_eq!(m["ball"].as_array().unwrap().len(), 3, "{key}.ball");
        assert_eq!(m["mount"].as_array().unwrap().len(), 6, "{key}.mount");
        assert_eq!(m["slide"].as_array().unwrap().len(), 3, "{key}.slide");
        assert!(m["hinge"].is_number(), "{key}.hinge");
        let got: Vec<f64> = ["ball", "hinge", "mount", "slide"]
            .iter()
            .flat_map(|n| {
                let mut x = Vec::new();
                flat(&m[*n], &mut x);
                x
            })
            .collect();
        ck.cmp(key, &got, &serde_json::json!(want.as_slice()), 1e-12);
    }
    assert_eq!(r["mass_matrix"].as_array().unwrap().len(), 13);
    assert_eq!(r["derivatives"]["dqdd_dq"].as_array().unwrap().len(), 13);
    assert!(ck.fails.is_empty(), "{:?}", ck.fails);
}

/// Simulation of spherical, floating and planar joints inside a tree (no contact,
/// gravity on): RK4 keeps the energy within 1e-8 relative over 1 s at dt = 1e-3
/// (a wrong quaternion or planar rate would drift by orders more), the default
/// semi-implicit step never raises it by more than 1e-3 relative, every
/// quaternion stays unit, and the transition Jacobians (central differences
/// through integrate/difference here) are finite and of size 2 nv.
#[test]
fn simulation_with_multi_dof_joints_conserves_energy() {
    use urdyn::sim::{Integrator, SimOptions, Simulation};
    let model = urdyn::load_file(
        root().join("tests/bad/joints_ok.urdf"),
        LoadOptions::default(),
    )
    .unwrap();
    let nv = model.nv;
    for (integrator, tol) in [(Some(Integrator::Rk4), 1e-8), (None, 1e-3)] {
        let opts = SimOptions {
            integrator,
            dt: 1e-3,
            ..Default::default()
        };
        let mut sim = Simulation::new(model.clone(), opts).unwrap();
        assert!(!sim.has_contact());
        let q = configuration::random_configuration(&model, 5);
        let v = DVector::from_fn(nv, |k, _| 0.3 * ((k as f64) * 1.3).sin());
        sim.set_state(&q, &v).unwrap();
        let e0 = sim.energy();
        let mut worst = 0.0f64;
        while sim.time() < 1.0 {
            sim.step_until(sim.time() + 0.05).unwrap();
            worst = worst.max(sim.energy() - e0);
            let q = sim.q();
            for at in [0usize, 8] {
                let n = q.rows(at, 4).norm();
                assert!((n - 1.0).abs() < 1e-9, "quaternion at {at}: norm {n}");
            }
        }
        let scale = e0.abs() + model.total_mass() * 9.81;
        eprintln!("{integrator:?}: energy rise {:.3e} of {scale:.3}", worst);
        assert!(
            worst <= tol * scale,
            "{integrator:?}: energy rose by {worst:e} (scale {scale})"
        );
        let tau = DVector::zeros(nv);
        let j = sim
            .transition_jacobians(&tau, urdyn::sim::JacobianMethod::Analytic, 1e-6)
            .unwrap();
        assert_eq!(
            (j.a.nrows(), j.a.ncols(), j.b.ncols()),
            (2 * nv, 2 * nv, nv)
        );
        assert!(j.a.iter().all(|x| x.is_finite()));
    }
}
