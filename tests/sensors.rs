//! Sensors (`Simulation::imu`, `joint_wrench`, `contact_wrench`) against
//! closed forms: a resting body's IMU reads +g upward, a falling one 0; the
//! feet's contact forces carry the weight; a held pendulum's joint wrench.

use nalgebra::{DVector, Matrix3, Vector3};
use urdyn::sim::{Integrator, SimOptions, Simulation};
use urdyn::{load_str, LoadOptions};

#[path = "common/quadruped.rs"]
mod quadruped;
use quadruped::standing_quadruped;

const FLOAT: LoadOptions = LoadOptions {
    floating_base: true,
};

fn box_urdf() -> &'static str {
    r#"<robot name="box"><link name="box">
<inertial><mass value="2"/><inertia ixx="0.01" iyy="0.012" izz="0.015" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
<joint name="mark" type="fixed"><parent link="box"/><child link="top"/><origin xyz="0.05 0 0.05" rpy="0 0 0.7"/></joint>
<link name="top"/></robot>"#
}

#[test]
fn resting_imu_reads_g_upward_and_free_fall_reads_zero() {
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    let mut sim = Simulation::new(model.clone(), SimOptions::default()).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.05;
    sim.set_state(&q, &DVector::zeros(6)).unwrap();
    for _ in 0..1000 {
        sim.step().unwrap();
    }
    for link in ["box", "top"] {
        let (gyro, acc) = sim.imu(link).unwrap();
        // "top" is turned 0.7 rad about z: +g is still along its z
        assert!(gyro.norm() < 1e-9, "{link}: {gyro:?}");
        assert!(
            (acc - Vector3::new(0.0, 0.0, 9.81)).norm() < 1e-6,
            "{link}: {acc:?}"
        );
    }
    // falling and spinning (no ground): the body origin is its centre of mass
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let v = DVector::from_vec(vec![0.3, -0.2, 1.0, 2.0, -1.0, 3.0]);
    let q0 = sim.q().clone();
    sim.set_state(&q0, &v).unwrap();
    for _ in 0..50 {
        sim.step().unwrap();
    }
    let (gyro, acc) = sim.imu("box").unwrap();
    assert!(acc.norm() < 1e-9, "falling: {acc:?}");
    let w = Vector3::new(sim.v()[3], sim.v()[4], sim.v()[5]);
    assert!((gyro - w).norm() < 1e-12);
}

#[test]
fn standing_feet_carry_the_weight() {
    let mut sim = standing_quadruped(SimOptions::default());
    let weight = sim.model.inertias.iter().map(|i| i.mass).sum::<f64>() * 9.81;
    let mut total = Vector3::zeros();
    let mut moment = Vector3::zeros();
    for leg in ["fl", "fr", "hl", "hr"] {
        let (f, t) = sim.contact_wrench(&format!("{leg}_foot")).unwrap();
        assert!(f.z > 0.1 * weight, "{leg}: {f:?}");
        total += f;
        // a sphere's contact is below its centre, the link origin: τ = (−r ẑ) × f
        let expect = Vector3::new(0.0, 0.0, -0.02).cross(&f);
        assert!(
            (t - expect).norm() < 1e-3 * f.norm(),
            "{leg}: {t:?} vs {expect:?}"
        );
        moment += t;
    }
    assert!(
        (total.z - weight).abs() < 1e-6 * weight,
        "{total:?} vs {weight}"
    );
    assert!(total.x.abs() + total.y.abs() < 1e-3 * weight, "{total:?}");
    // a link that touches nothing: exactly zero
    assert_eq!(
        sim.contact_wrench("torso").unwrap(),
        (Vector3::zeros(), Vector3::zeros())
    );
    let _ = moment;
    // the IMU on the torso at rest reads +g along the world's z
    let (_, acc) = sim.imu("torso").unwrap();
    let q = sim.q();
    let r = urdyn::spatial::quat_to_matrix(q[3], q[4], q[5], q[6]);
    // (the servoed stance still sways by a few mm/s² after 3 s)
    assert!(
        (r * acc - Vector3::new(0.0, 0.0, 9.81)).norm() < 0.05,
        "{acc:?}"
    );
}

fn pendulum() -> String {
    // 1.5 kg at 0.4 m along x from a joint about y, tiny rotational inertia
    r#"<robot name="p"><link name="base"/>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 1"/>
<axis xyz="0 1 0"/><limit lower="-6" upper="6" effort="100" velocity="100"/></joint>
<link name="arm"><inertial><origin xyz="0.4 0 0"/><mass value="1.5"/>
<inertia ixx="1e-3" iyy="2e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#
        .into()
}

#[test]
fn joint_wrench_of_a_held_pendulum_is_the_closed_form() {
    let (m, l, g) = (1.5, 0.4, 9.81);
    for th in [std::f64::consts::FRAC_PI_2, 0.3] {
        let model = load_str(&pendulum(), "p.urdf", LoadOptions::default()).unwrap();
        let opts = SimOptions {
            ground: None,
            ..Default::default()
        };
        let mut sim = Simulation::new(model, opts).unwrap();
        // hold it at θ with the gravity torque itself: at rest, a = 0
        let tau = m * g * l * th.cos();
        sim.set_state(&DVector::from_element(1, th), &DVector::zeros(1))
            .unwrap();
        sim.set_torques(&DVector::from_element(1, -tau)).unwrap();
        sim.step().unwrap();
        let (f, t) = sim.joint_wrench("j").unwrap();
        // world: F = m g ẑ, torque about the joint −c × (m g), c = l (cos θ, 0, −sin θ)
        let c = Vector3::new(th.cos(), 0.0, -th.sin()) * l;
        let fw = Vector3::new(0.0, 0.0, m * g);
        let tw = -c.cross(&Vector3::new(0.0, 0.0, -m * g));
        let r = Matrix3::new(
            th.cos(),
            0.0,
            th.sin(),
            0.0,
            1.0,
            0.0,
            -th.sin(),
            0.0,
            th.cos(),
        );
        let (fl, tl) = (r.transpose() * fw, r.transpose() * tw);
        assert!((f - fl).norm() < 1e-6, "θ {th}: {f:?} vs {fl:?}");
        assert!((t - tl).norm() < 1e-6, "θ {th}: {t:?} vs {tl:?}");
    }
}

#[test]
fn unknown_names_are_errors_naming_the_nearest() {
    let model = load_str(&pendulum(), "p.urdf", LoadOptions::default()).unwrap();
    let mut sim = Simulation::new(model, SimOptions::default()).unwrap();
    let e = sim.imu("armm").unwrap_err().to_string();
    assert!(
        e.contains("armm") && e.contains("arm") && !e.contains('\n'),
        "{e}"
    );
    let e = sim.joint_wrench("jj").unwrap_err().to_string();
    assert!(e.contains("jj"), "{e}");
    let e = sim.contact_wrench("nope").unwrap_err().to_string();
    assert!(e.contains("nope"), "{e}");
}
