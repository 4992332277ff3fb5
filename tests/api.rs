//! The library's tool-facing API (issue 13): typed ids and lookups by name, joint
//! coordinate ranges, the configuration manifold, sizes checked at every public
//! entry point, contact forces named by link, and `Simulation::energy(&self)`.

use std::path::PathBuf;
use urdyn::dynamics_f64::{self as dynamics, DynamicsError, Reference};
use urdyn::model::configuration::{difference, integrate, random_configuration};
use urdyn::model::{DimensionError, FrameId, JointId, NameError};
use urdyn::nalgebra::{DMatrix, DVector, Vector3};
use urdyn::sim::{SimOptions, Simulation};
use urdyn::spatial::Force;
use urdyn::{Data, LoadOptions, Model};

fn load(path: &str, floating_base: bool) -> Model {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::load_file(root.join(path), LoadOptions { floating_base }).unwrap()
}

fn dim(arg: &'static str, expected: usize, got: usize) -> DynamicsError {
    DynamicsError::Dimension(DimensionError { arg, expected, got })
}

/// Every public dynamics and kinematics entry point answers a vector one entry
/// short or one entry long with the error naming the argument and both sizes.
#[test]
fn wrong_lengths_are_errors_at_every_entry_point() {
    for (path, fb) in [
        ("assets/robots/ur5.urdf", false),
        ("assets/robots/solo12.urdf", true),
    ] {
        let m = load(path, fb);
        let mut d = Data::new(&m);
        let (nq, nv, nb) = (m.nq, m.nv, m.nbodies);
        let q = m.neutral();
        let z = DVector::zeros(nv);
        let fx = vec![Force::zero(); nb];
        for delta in [-1i64, 1] {
            let qb = DVector::zeros((nq as i64 + delta) as usize);
            let vb = DVector::zeros((nv as i64 + delta) as usize);
            let fb_ = vec![Force::zero(); (nb as i64 + delta) as usize];
            let (lq, lv, lf) = (qb.len(), vb.len(), fb_.len());
            let e = |r: Result<(), DynamicsError>| r.unwrap_err();
            let d = &mut d;
            // q
            assert_eq!(
                e(dynamics::rnea(&m, d, &qb, &z, &z, None).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::bias(&m, d, &qb, &z, None).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(e(dynamics::crba(&m, d, &qb).map(|_| ())), dim("q", nq, lq));
            assert_eq!(
                e(dynamics::crba_upper(&m, d, &qb).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::mass_matrix(&m, d, &qb).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(e(dynamics::mass_matrix_rnea(&m, d, &qb)), dim("q", nq, lq));
            assert_eq!(
                e(dynamics::forward_kinematics(&m, d, &qb)),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::forward_kinematics_second_order(
                    &m, d, &qb, &z, &z
                )),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::kinetic_energy(&m, d, &qb, &z).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::energies(&m, &qb, &z).map(|_| ())),
                dim("q", nq, lq)
            );
            assert_eq!(
                e(dynamics::centroidal_momentum(&m, d, &qb, &z).map(|_| ())),
                dim("q", nq, lq)
            );
            // v, a, tau
            assert_eq!(
                e(dynamics::rnea(&m, d, &q, &vb, &z, None).map(|_| ())),
                dim("v", nv, lv)
            );
            assert_eq!(
                e(dynamics::rnea(&m, d, &q, &z, &vb, None).map(|_| ())),
                dim("a", nv, lv)
            );
            assert_eq!(
                e(dynamics::bias(&m, d, &q, &vb, None).map(|_| ())),
                dim("v", nv, lv)
            );
            for fd in [
                dynamics::aba,
                dynamics::forward_dynamics,
                dynamics::forward_dynamics_crba,
                dynamics::forward_dynamics_rnea,
            ] {
                assert_eq!(
                    e(fd(&m, d, &qb, &z, &z, None).map(|_| ())),
                    dim("q", nq, lq)
                );
                assert_eq!(
                    e(fd(&m, d, &q, &vb, &z, None).map(|_| ())),
                    dim("v", nv, lv)
                );
                assert_eq!(
                    e(fd(&m, d, &q, &z, &vb, None).map(|_| ())),
                    dim("tau", nv, lv)
                );
                assert_eq!(
                    e(fd(&m, d, &q, &z, &z, Some(&fb_)).map(|_| ())),
                    dim("fext", nb, lf)
                );
            }
            assert_eq!(
                e(dynamics::forward_kinematics_second_order(
                    &m, d, &q, &vb, &z
                )),
                dim("v", nv, lv)
            );
            assert_eq!(
                e(dynamics::forward_kinematics_second_order(
                    &m, d, &q, &z, &vb
                )),
                dim("a", nv, lv)
            );
            assert_eq!(
                e(dynamics::kinetic_energy(&m, d, &q, &vb).map(|_| ())),
                dim("v", nv, lv)
            );
            assert_eq!(
                e(dynamics::kinetic_energy_from_placements(&m, d, &vb).map(|_| ())),
                dim("v", nv, lv)
            );
            assert_eq!(
                e(dynamics::energies(&m, &q, &vb).map(|_| ())),
                dim("v", nv, lv)
            );
            assert_eq!(
                e(dynamics::centroidal_momentum(&m, d, &q, &vb).map(|_| ())),
                dim("v", nv, lv)
            );
            // fext
            assert_eq!(
                e(dynamics::rnea(&m, d, &q, &z, &z, Some(&fb_)).map(|_| ())),
                dim("fext", nb, lf)
            );
            assert_eq!(
                e(dynamics::bias(&m, d, &q, &z, Some(&fb_)).map(|_| ())),
                dim("fext", nb, lf)
            );
            let mut fb2 = fb_.clone();
            let (f0, t0) = (Vector3::zeros(), Vector3::zeros());
            assert_eq!(
                e(dynamics::add_link_wrench(
                    &m,
                    d,
                    FrameId(0),
                    &f0,
                    &t0,
                    &mut fb2
                )),
                dim("fext", nb, lf)
            );
            // matrices
            let mut j = DMatrix::zeros(6, lv);
            assert_eq!(
                e(dynamics::frame_jacobian(
                    &m,
                    d,
                    FrameId(0),
                    Reference::Local,
                    &mut j
                )),
                dim("jacobian columns", nv, lv)
            );
            let mut jc = DMatrix::zeros(3, lv);
            assert_eq!(
                e(dynamics::center_of_mass_jacobian(&m, d, &mut jc)),
                dim("com jacobian columns", nv, lv)
            );
            // the configuration manifold
            assert_eq!(
                integrate(&m, &qb, &z).unwrap_err(),
                DimensionError {
                    arg: "q",
                    expected: nq,
                    got: lq
                }
            );
            assert_eq!(
                integrate(&m, &q, &vb).unwrap_err(),
                DimensionError {
                    arg: "v",
                    expected: nv,
                    got: lv
                }
            );
            assert_eq!(
                difference(&m, &q, &qb).unwrap_err(),
                DimensionError {
                    arg: "q1",
                    expected: nq,
                    got: lq
                }
            );
            assert_eq!(m.positions_by_name(&qb).unwrap_err().got, lq);
            // the simulation
            let mut sim = Simulation::new(
                m.clone(),
                SimOptions {
                    ground: None,
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(sim.set_state(&qb, &z).is_err());
            assert!(sim.set_state(&q, &vb).is_err());
            assert!(sim.set_torques(&vb).is_err());
            assert!(sim.torques().len() == nv);
        }
        // the right sizes pass, and a frame id past the end is an error, not zeros
        dynamics::rnea(&m, &mut d, &q, &z, &z, Some(&fx)).unwrap();
        let mut j = DMatrix::zeros(6, nv);
        let bad = FrameId(m.frames.len());
        assert!(matches!(
            dynamics::frame_jacobian(&m, &d, bad, Reference::WorldAligned, &mut j),
            Err(DynamicsError::Name(NameError::OutOfRange { .. }))
        ));
        assert!(dynamics::frame_placement(&m, &d, bad).is_err());
        // frame_placement reads one frame as update_frames writes them all
        dynamics::forward_kinematics(&m, &mut d, &m.neutral()).unwrap();
        dynamics::update_frames(&m, &mut d);
        for k in 0..m.frames.len() {
            let p = dynamics::frame_placement(&m, &d, FrameId(k)).unwrap();
            assert!((p.rot - d.o_m_f[k].rot).amax() < 1e-15);
            assert!((p.trans - d.o_m_f[k].trans).amax() < 1e-15);
        }
        assert!(dynamics::frame_velocity(&m, &d, bad, Reference::Local).is_err());
        assert!(dynamics::frame_classical_acceleration(&m, &d, bad, Reference::Local).is_err());
    }
}

#[test]
fn names_resolve_and_unknown_names_name_the_nearest() {
    let m = load("assets/robots/solo12.urdf", true);
    let e = m.frame_id("FL_FOOTT").unwrap_err();
    assert_eq!(
        e,
        NameError::Unknown {
            kind: "link",
            name: "FL_FOOTT".into(),
            nearest: Some("FL_FOOT".into())
        }
    );
    assert!(
        e.to_string()
            .contains("unknown link \"FL_FOOTT\" (nearest: \"FL_FOOT\")"),
        "{e}"
    );
    let e = m.joint_id("FL_KFE_joint").unwrap_err();
    assert!(e.to_string().contains("nearest: \"FL_KFE\""), "{e}");
    // the free base: 7 q and 6 v coordinates first; each joint after it one of each
    let base = m.joint_id(&m.body_joint_names[1]).unwrap();
    assert_eq!(m.joint_q_range(base).unwrap(), 0..7);
    assert_eq!(m.joint_v_range(base).unwrap(), 0..6);
    for (d, dof) in m.dofs.iter().enumerate() {
        let j = m.joint_id(&dof.name).unwrap();
        assert_eq!(m.joint_name(j).unwrap(), dof.name);
        assert_eq!(m.joint_q_range(j).unwrap(), 7 + d..8 + d);
        assert_eq!(m.joint_v_range(j).unwrap(), 6 + d..7 + d);
        assert_eq!(m.q_index(&dof.name).unwrap(), 7 + d);
        assert_eq!(m.v_index(&dof.name).unwrap(), 6 + d);
        assert!(!m.is_mimic(j));
    }
    assert!(m.joint_q_range(JointId(m.nbodies)).is_err());
    // a link welded by a fixed joint belongs to its parent's body
    let foot = m.frame_id("FL_FOOT").unwrap();
    let body = m.body_id("FL_FOOT").unwrap();
    assert_eq!(m.frames[foot.0].body, body.0);
    assert_eq!(m.frame_name(foot).unwrap(), "FL_FOOT");
    assert!(m.link_names().contains(&"FL_FOOT"));
}

#[test]
fn a_mimic_joint_owns_no_coordinate() {
    let m = load("tests/urdf/mimic.urdf", false);
    let mut mimics = 0;
    for i in 1..m.nbodies {
        let j = JointId(i);
        let name = m.joint_name(j).unwrap();
        if m.dofs.iter().any(|d| d.name == name) {
            assert_eq!(m.joint_v_range(j).unwrap().len(), 1);
        } else {
            mimics += 1;
            assert!(m.is_mimic(j));
            assert!(m.joint_q_range(j).unwrap().is_empty());
            assert!(m.joint_v_range(j).unwrap().is_empty());
            assert!(m.q_index(name).is_err());
        }
    }
    assert!(mimics > 0);
}

#[test]
fn integrate_and_difference_are_inverse_on_the_manifold() {
    for (path, fb) in [
        ("assets/robots/solo12.urdf", true),
        ("assets/robots/ur5.urdf", false),
    ] {
        let m = load(path, fb);
        for seed in 0..20 {
            let q0 = random_configuration(&m, seed);
            let q1 = random_configuration(&m, seed + 100);
            assert_ne!(q0, q1);
            // inside the limits, unit quaternion
            let qo = m.joint_q_offset();
            for (d, dof) in m.dofs.iter().enumerate() {
                let x = q0[qo + d];
                let lo = dof.limits.lower.unwrap_or(-std::f64::consts::PI);
                let hi = dof.limits.upper.unwrap_or(std::f64::consts::PI);
                assert!(x >= lo.min(-std::f64::consts::PI) && x <= hi.max(std::f64::consts::PI));
                if !dof.continuous && lo < hi {
                    assert!(
                        x >= lo && x <= hi,
                        "{} = {x} outside [{lo}, {hi}]",
                        dof.name
                    );
                }
            }
            if fb {
                assert!((q0.rows(3, 4).norm() - 1.0).abs() < 1e-14);
            }
            let v = difference(&m, &q0, &q1).unwrap();
            let q1b = integrate(&m, &q0, &v).unwrap();
            let mut err = (q1b.rows(0, 3) - q1.rows(0, 3)).amax();
            err = err.max((q1b.rows(3, q1.len() - 3) - q1.rows(3, q1.len() - 3)).amax());
            if fb {
                // q and −q are one orientation
                let a = (q1b.rows(3, 4) - q1.rows(3, 4)).amax();
                let b = (q1b.rows(3, 4) + q1.rows(3, 4)).amax();
                err = (q1b.rows(0, 3) - q1.rows(0, 3)).amax().max(a.min(b));
                err = err.max((q1b.rows(7, m.nq - 7) - q1.rows(7, m.nq - 7)).amax());
            }
            assert!(err < 1e-12, "{path}: integrate(q0, q1 ⊖ q0) off by {err:e}");
            assert!(difference(&m, &q0, &q0).unwrap().amax() < 1e-15);
        }
        // by name
        let name = &m.dofs[1].name;
        let q = m.configuration_from_names([(name.as_str(), 0.25)]).unwrap();
        assert_eq!(q[m.q_index(name).unwrap()], 0.25);
        assert_eq!((&q - m.neutral()).amax(), 0.25);
        let back = m.positions_by_name(&q).unwrap();
        assert_eq!(back[1], (name.as_str(), 0.25));
        let e = m
            .configuration_from_names([("nonexistent_joint", 1.0)])
            .unwrap_err();
        assert!(e.to_string().contains("nonexistent_joint"));
    }
}

/// The sim's energy needs only `&self` and equals the library's energies.
#[test]
fn simulation_energy_is_read_only() {
    let m = load("assets/lamp.urdf", true);
    let mut sim = Simulation::new(m.clone(), SimOptions::default()).unwrap();
    let mut q = m.neutral();
    q[2] = 0.4;
    let v = DVector::from_fn(m.nv, |i, _| 0.1 * (i as f64 + 1.0));
    sim.set_state(&q, &v).unwrap();
    let s: &Simulation = &sim;
    let (ke, pe) = dynamics::energies(&m, s.q(), s.v()).unwrap();
    let mut d = Data::new(&m);
    let ke2 = dynamics::kinetic_energy(&m, &mut d, s.q(), s.v()).unwrap();
    let h = dynamics::mass_matrix(&m, &mut d, s.q()).unwrap().clone();
    // T = ½ vᵀ H v (an identity independent of either pass)
    let ke3 = 0.5 * s.v().dot(&(&h * s.v()));
    assert!((ke - ke3).abs() < 1e-12 * ke3.abs().max(1.0) && (ke - ke2).abs() < 1e-12);
    assert!((s.energy() - (ke + pe)).abs() < 1e-12 * (ke + pe).abs().max(1.0));
}

/// Contact forces are named by the URDF link whose collision shape touched, not
/// by the merged body: a foot welded under a base by a fixed joint.
#[test]
fn contact_forces_name_the_link_that_touched() {
    let urdf = r#"<?xml version="1.0"?>
<robot name="footed">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="foot">
    <inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="ankle" type="fixed"><parent link="base"/><child link="foot"/><origin xyz="0 0 -0.2"/></joint>
</robot>"#;
    let m = urdyn::load_str(
        urdf,
        "footed.urdf",
        LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    assert_eq!(m.body_link_names[1], "base");
    let mut sim = Simulation::new(m.clone(), SimOptions::default()).unwrap();
    let mut q = m.neutral();
    q[2] = 0.26;
    sim.set_state(&q, &DVector::zeros(m.nv)).unwrap();
    let mut touched = 0;
    for _ in 0..300 {
        sim.step().unwrap();
        for (link, f) in sim.link_contact_forces() {
            assert_eq!(link, "foot");
            assert_eq!(sim.contact_link(&f.point), Some("foot"));
            touched += 1;
        }
    }
    assert!(touched > 0, "the foot never touched the ground");
}
