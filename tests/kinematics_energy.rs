//! Identities between independently computed quantities: frame Jacobians against
//! finite differences of forward kinematics, kinetic energy against ½ vᵀ H v,
//! gravity torques against the gradient of the potential energy, centroidal
//! momentum against the centre of mass's velocity.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use urdyn::dynamics_f64::{
    self as dynamics, center_of_mass, forward_kinematics, update_frames, Reference,
};
use urdyn::model::FrameId;
use urdyn::{Data, LoadOptions, Model};

use crate::common::lcg::Lcg;

fn load(path: &str, floating: bool) -> Model {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    urdyn::load_file(
        p,
        LoadOptions {
            floating_base: floating,
        },
    )
    .unwrap()
}

const ROBOTS: [&str; 5] = [
    "assets/robots/ur5.urdf",
    "assets/robots/panda.urdf",
    "tests/urdf/mimic.urdf",
    "tests/urdf/prismatic_continuous.urdf",
    "tests/urdf/fixed_chain.urdf",
];

/// q advanced along the joint velocities only (the base velocity must be zero).
fn advance(model: &Model, q: &DVector<f64>, v: &DVector<f64>, s: f64) -> DVector<f64> {
    let mut qs = q.clone();
    for k in 0..model.dofs.len() {
        qs[model.joint_q_offset() + k] += v[model.joint_v_offset() + k] * s;
    }
    qs
}

fn random_state(model: &Model, rng: &mut Lcg, joints_only: bool) -> (DVector<f64>, DVector<f64>) {
    let mut q = model.neutral();
    for k in model.joint_q_offset()..model.nq {
        q[k] = rng.uniform(-2.0, 2.0);
    }
    if model.floating_base {
        let r = nalgebra::UnitQuaternion::from_euler_angles(
            rng.uniform(-3.0, 3.0),
            rng.uniform(-1.5, 1.5),
            rng.uniform(-3.0, 3.0),
        );
        q[0] = rng.uniform(-1.0, 1.0);
        q[3] = r.i;
        q[4] = r.j;
        q[5] = r.k;
        q[6] = r.w;
    }
    let mut v = DVector::from_fn(model.nv, |_, _| rng.uniform(-1.0, 1.0));
    if joints_only {
        v.rows_mut(0, model.joint_v_offset()).fill(0.0);
    }
    (q, v)
}

/// The rotation vector of a small rotation: vee((R − Rᵀ)/2) = sin θ · axis, exact to
/// O(θ³) (acos-based logs lose half the digits at tiny angles).
fn log3(r: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5
}

#[test]
fn frame_jacobians_match_finite_differences() {
    let mut rng = Lcg(1);
    for path in ROBOTS {
        for floating in [false, true] {
            let model = load(path, floating);
            let mut data = Data::new(&model);
            let mut j = DMatrix::zeros(6, model.nv);
            for _ in 0..5 {
                // base velocity zero: q then moves along a straight line in joint space
                let (q, v) = random_state(&model, &mut rng, true);
                let h = 1e-6;
                let poses = |data: &mut Data, s: f64| {
                    let qs = advance(&model, &q, &v, s);
                    forward_kinematics(&model, data, &qs).unwrap();
                    update_frames(&model, data);
                    data.o_m_f.clone()
                };
                let plus = poses(&mut data, h);
                let minus = poses(&mut data, -h);
                forward_kinematics(&model, &mut data, &q).unwrap();
                update_frames(&model, &mut data);
                for k in 0..model.frames.len() {
                    dynamics::frame_jacobian(
                        &model,
                        &data,
                        FrameId(k),
                        Reference::WorldAligned,
                        &mut j,
                    )
                    .unwrap();
                    let jv = &j * &v;
                    let lin = (plus[k].trans - minus[k].trans) / (2.0 * h);
                    let ang = log3(&(plus[k].rot * minus[k].rot.transpose())) / (2.0 * h);
                    let err = (Vector3::new(jv[0], jv[1], jv[2]) - lin).norm()
                        + (Vector3::new(jv[3], jv[4], jv[5]) - ang).norm();
                    assert!(
                        err < 1e-7 * (1.0 + jv.norm()),
                        "{path} frame {} error {err:e}",
                        model.frames[k].name
                    );
                }
            }
        }
    }
}

#[test]
fn floating_root_jacobian_rotates_body_velocities_into_the_world() {
    let model = load("assets/robots/solo12.urdf", true);
    let mut data = Data::new(&model);
    let mut rng = Lcg(2);
    let (q, _) = random_state(&model, &mut rng, false);
    forward_kinematics(&model, &mut data, &q).unwrap();
    let root = model.frame_index(&model.body_link_names[1]).unwrap();
    let mut j = DMatrix::zeros(6, model.nv);
    dynamics::frame_jacobian(
        &model,
        &data,
        FrameId(root),
        Reference::WorldAligned,
        &mut j,
    )
    .unwrap();
    let r = data.o_m_i[1].rot;
    assert!((j.view((0, 0), (3, 3)) - r).amax() < 1e-14);
    assert!((j.view((3, 3), (3, 3)) - r).amax() < 1e-14);
    assert!(j.view((0, 3), (3, 3)).amax() < 1e-14 && j.view((3, 0), (3, 3)).amax() < 1e-14);
    assert!(j.columns(6, model.nv - 6).amax() == 0.0);
}

#[test]
fn kinetic_energy_is_half_v_h_v() {
    let mut rng = Lcg(3);
    for path in ROBOTS.iter().chain(&["assets/robots/talos_reduced.urdf"]) {
        for floating in [false, true] {
            let model = load(path, floating);
            let mut data = Data::new(&model);
            for _ in 0..5 {
                let (q, v) = random_state(&model, &mut rng, false);
                let ke = dynamics::kinetic_energy(&model, &mut data, &q, &v).unwrap();
                dynamics::mass_matrix(&model, &mut data, &q).unwrap();
                let vhv = 0.5 * v.dot(&(&data.h * &v));
                assert!(
                    (ke - vhv).abs() < 1e-12 * (1.0 + ke.abs()),
                    "{path}: {ke} vs {vhv}"
                );
            }
        }
    }
}

#[test]
fn gravity_torques_are_the_gradient_of_potential_energy() {
    let mut rng = Lcg(4);
    for path in ROBOTS {
        let model = load(path, false);
        let mut data = Data::new(&model);
        let (q, _) = random_state(&model, &mut rng, false);
        let zero = DVector::zeros(model.nv);
        let g = dynamics::bias(&model, &mut data, &q, &zero, None)
            .unwrap()
            .clone();
        for k in 0..model.nv {
            let h = 1e-6;
            let mut pe = |s: f64| {
                let mut qs = q.clone();
                qs[k] += s;
                forward_kinematics(&model, &mut data, &qs).unwrap();
                dynamics::potential_energy(&model, &data)
            };
            let dpe = (pe(h) - pe(-h)) / (2.0 * h);
            assert!(
                (dpe - g[k]).abs() < 1e-7 * (1.0 + g[k].abs()),
                "{path} dof {k}: {dpe} vs {}",
                g[k]
            );
        }
    }
}

#[test]
fn centroidal_linear_momentum_is_mass_times_com_velocity() {
    let mut rng = Lcg(5);
    for path in ROBOTS {
        for floating in [false, true] {
            let model = load(path, floating);
            let mut data = Data::new(&model);
            let (q, v) = random_state(&model, &mut rng, true);
            let h = 1e-6;
            let mut com = |s: f64| {
                forward_kinematics(&model, &mut data, &advance(&model, &q, &v, s)).unwrap();
                center_of_mass(&model, &data)
            };
            let cdot = (com(h) - com(-h)) / (2.0 * h);
            let (_, lin) = dynamics::centroidal_momentum(&model, &mut data, &q, &v).unwrap();
            let m = model.total_mass();
            assert!(
                (lin - cdot * m).norm() < 1e-7 * (1.0 + lin.norm()),
                "{path}"
            );
        }
    }
}

/// A revolute joint whose placement rotation is a rotation about its own axis
/// (`rpy="0 0.7 0"` on a y axis) is loaded with that angle folded into the joint
/// offset (identity placement rotation, the axis-rotation fast path); the link
/// poses are those of the URDF: oM = T(xyz) Ry(0.7) Ry(q) for the first link, and a
/// general placement (`rpy="0.3 0.7 0"`) is left as it is.
#[test]
fn axis_placement_folded_into_offset() {
    let urdf = r#"<robot name="fold">
      <link name="base"/>
      <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
        <origin xyz="0.1 0.2 0.3" rpy="0 0.7 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
        <origin xyz="0 0 0.4" rpy="0.3 0.7 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
    </robot>"#;
    let model = urdyn::load_str(urdf, "fold.urdf", LoadOptions::default()).unwrap();
    assert_eq!(model.placement_identity[1..], [true, false]);
    let (q1, q2) = (0.25, -0.6);
    let q = DVector::from_vec(vec![q1, q2]);
    let mut data = Data::new(&model);
    dynamics::forward_kinematics(&model, &mut data, &q).unwrap();
    let ry = |t: f64| nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), t);
    let ra = ry(0.7) * ry(q1);
    let pa = nalgebra::Vector3::new(0.1, 0.2, 0.3);
    let rb = ra * nalgebra::Rotation3::from_euler_angles(0.3, 0.7, 0.0) * ry(q2);
    let pb = pa + ra * nalgebra::Vector3::new(0.0, 0.0, 0.4);
    let (oa, ob) = (&data.o_m_i[1], &data.o_m_i[2]);
    assert!((oa.rot - ra.matrix()).norm() < 1e-15 && (oa.trans - pa).norm() < 1e-15);
    assert!((ob.rot - rb.matrix()).norm() < 1e-15 && (ob.trans - pb).norm() < 1e-15);
}
