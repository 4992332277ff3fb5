//! The course note's worked examples: the particle of its section 3.1
//! (docs/theory.md §"Particle example") and the 2D jumping lamp of its Figure 1,
//! both moving in the x–y plane with gravity along −y (docs/theory.md §"Gravity").

use nalgebra::{DVector, Vector3};
use urdyn::dynamics_f64::{self as dynamics, forward_dynamics, forward_kinematics, rnea};
use urdyn::{Data, LoadOptions, Model};

const G: f64 = 9.81;

use crate::common::lcg::Lcg;

fn load(name: &str, floating: bool) -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name);
    let mut m = urdyn::load_file(
        path,
        LoadOptions {
            floating_base: floating,
        },
    )
    .expect("asset loads");
    m.gravity = Vector3::new(0.0, -G, 0.0);
    m
}

#[test]
fn particle_inverse_dynamics_is_newtons_law() {
    // docs/theory.md §"Particle example": Q0 = m q̈0, Q1 = m (q̈1 + g)
    let model = load("particle.urdf", false);
    let m = 2.0;
    assert_eq!(model.dof_names(), vec!["x", "y"]);
    let mut data = Data::new(&model);
    let mut rng = Lcg(7);
    for _ in 0..100 {
        let q = rng.vector(2, 5.0);
        let v = rng.vector(2, 5.0);
        let a = rng.vector(2, 5.0);
        let tau = rnea(&model, &mut data, &q, &v, &a, None).unwrap().clone();
        assert!((tau[0] - m * a[0]).abs() < 1e-12 * (1.0 + tau[0].abs()));
        assert!((tau[1] - m * (a[1] + G)).abs() < 1e-12 * (1.0 + tau[1].abs()));

        // velocities: v̂0 = [0; q̇0 0 0], v̂1 = [0; q̇0 q̇1 0] (the slider frames keep the
        // world's orientation, so the notations line up)
        let (v0, v1) = (data.v[1], data.v[2]);
        assert_eq!(v0.ang, Vector3::zeros());
        assert!((v0.lin - Vector3::new(v[0], 0.0, 0.0)).norm() < 1e-14);
        assert!((v1.lin - Vector3::new(v[0], v[1], 0.0)).norm() < 1e-14);
        // accelerations: â0 = [0; q̈0 g 0], â1 = [0; q̈0 q̈1+g 0]
        assert!((data.a[1].lin - Vector3::new(a[0], G, 0.0)).norm() < 1e-13);
        assert!((data.a[2].lin - Vector3::new(a[0], a[1] + G, 0.0)).norm() < 1e-13);
        assert!(data.a[2].ang.norm() < 1e-14);
        // forces: f̂1 = [m q̈0, m(q̈1+g), 0 | 0], f̂0 adds the moment −m q1 q̈0 about z
        // (the course note writes force-first; ours is [moment; force])
        let f1 = data.f[2];
        assert!((f1.lin - Vector3::new(m * a[0], m * (a[1] + G), 0.0)).norm() < 1e-12);
        assert!(f1.ang.norm() < 1e-12);
        let f0 = data.f[1];
        assert!((f0.lin - f1.lin).norm() < 1e-12);
        assert!(
            (f0.ang - Vector3::new(0.0, 0.0, -m * q[1] * a[0])).norm()
                < 1e-11 * (1.0 + f0.ang.norm())
        );
    }
}

#[test]
fn particle_forward_dynamics_inverts_newton() {
    let model = load("particle.urdf", false);
    let mut data = Data::new(&model);
    let mut rng = Lcg(11);
    for _ in 0..50 {
        let q = rng.vector(2, 5.0);
        let v = rng.vector(2, 5.0);
        let tau = rng.vector(2, 20.0);
        let qdd = forward_dynamics(&model, &mut data, &q, &v, &tau, None)
            .unwrap()
            .clone();
        assert!((qdd[0] - tau[0] / 2.0).abs() < 1e-12);
        assert!((qdd[1] - (tau[1] / 2.0 - G)).abs() < 1e-12);
    }
}

#[test]
fn planar_lamp_mass_matrix_is_spd_with_total_mass_on_the_base_translations() {
    let model = load("planar_lamp.urdf", false);
    let names = model.dof_names();
    assert_eq!(
        names,
        vec!["x_base", "y_base", "theta_base", "theta_1", "theta_2"]
    );
    let mut data = Data::new(&model);
    let mut rng = Lcg(3);
    let total = model.total_mass();
    assert!(total > 0.0);
    for _ in 0..50 {
        let q = rng.vector(5, 3.0);
        dynamics::mass_matrix(&model, &mut data, &q).unwrap();
        let h = data.h.clone();
        assert!((&h - h.transpose()).amax() < 1e-14 * h.amax());
        let eig = h.clone().symmetric_eigenvalues();
        assert!(eig.min() > 0.0, "H not positive definite: {eig}");
        assert!((h[(0, 0)] - total).abs() < 1e-12 * total);
        assert!((h[(1, 1)] - total).abs() < 1e-12 * total);
        assert!(h[(0, 1)].abs() < 1e-12 * total);
    }
}

/// With zero torque on every joint the lamp is in free flight: its centre of mass
/// accelerates by g, whatever its joints do.
#[test]
fn planar_lamp_free_flight_centre_of_mass_falls_with_g() {
    let model = load("planar_lamp.urdf", false);
    let mut data = Data::new(&model);
    let mut rng = Lcg(5);
    for _ in 0..50 {
        let q = rng.vector(5, 3.0);
        let v = rng.vector(5, 3.0);
        let tau = DVector::zeros(5);
        let qdd = forward_dynamics(&model, &mut data, &q, &v, &tau, None)
            .unwrap()
            .clone();
        // Body velocities and accelerations of this motion, gravity off.
        let mut still = model.clone();
        still.gravity = Vector3::zeros();
        rnea(&still, &mut data, &q, &v, &qdd, None).unwrap();
        forward_kinematics(&still, &mut data, &q).unwrap();
        let mut mc = Vector3::zeros();
        for i in 1..model.nbodies {
            let inertia = &model.inertias[i];
            let (vi, ai, p) = (data.v[i], data.a[i], inertia.com);
            // classical acceleration of the body point p: a + α × p + ω × (v + ω × p)
            let acc = ai.lin + ai.ang.cross(&p) + vi.ang.cross(&(vi.lin + vi.ang.cross(&p)));
            mc += data.o_m_i[i].rot * acc * inertia.mass;
        }
        let c_ddot = mc / model.total_mass();
        assert!(
            (c_ddot - Vector3::new(0.0, -G, 0.0)).norm() < 1e-12 * G,
            "c̈ = {c_ddot}"
        );
    }
}

#[test]
fn planar_lamp_fd_of_id_is_identity_fixed_and_floating() {
    for floating in [false, true] {
        let model = load("planar_lamp.urdf", floating);
        let mut data = Data::new(&model);
        let mut rng = Lcg(9);
        for _ in 0..50 {
            let mut q = model.neutral();
            for k in model.joint_q_offset()..model.nq {
                q[k] = rng.uniform(-3.0, 3.0);
            }
            if floating {
                let quat = nalgebra::UnitQuaternion::from_euler_angles(
                    rng.uniform(-3.0, 3.0),
                    rng.uniform(-1.5, 1.5),
                    rng.uniform(-3.0, 3.0),
                );
                q[3] = quat.i;
                q[4] = quat.j;
                q[5] = quat.k;
                q[6] = quat.w;
            }
            let v = rng.vector(model.nv, 3.0);
            let a = rng.vector(model.nv, 3.0);
            let tau = rnea(&model, &mut data, &q, &v, &a, None).unwrap().clone();
            let qdd = forward_dynamics(&model, &mut data, &q, &v, &tau, None)
                .unwrap()
                .clone();
            assert!((&qdd - &a).amax() < 1e-10 * (1.0 + a.amax()));
        }
    }
}
