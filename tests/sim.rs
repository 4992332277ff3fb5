//! Simulation acceptance tests: contact (incline stick/slip, bounce), free-body
//! invariants, joint friction/limits, no contact work without geometry.

use nalgebra::{DVector, Matrix3, Vector3};
use urdyn::contact::ContactParams;
use urdyn::sim::{Integrator, SimOptions, Simulation, Solver};
use urdyn::{load_str, LoadOptions};

const FLOAT: LoadOptions = LoadOptions {
    floating_base: true,
};

fn box_urdf() -> String {
    // 0.2 x 0.2 x 0.1 m, 1 kg, frame at its centre
    let (m, a, b, c) = (1.0, 0.2, 0.2, 0.1);
    format!(
        r#"<robot name="box"><link name="box">
<inertial><mass value="{m}"/><inertia ixx="{}" iyy="{}" izz="{}" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="{a} {b} {c}"/></geometry></collision></link></robot>"#,
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0
    )
}

/// A box resting flat on the ground with gravity tilted 15° (down-slope along +x).
fn incline(mu: f64, solver: Solver) -> (f64, f64, f64) {
    let mut model = load_str(&box_urdf(), "box.urdf", FLOAT).unwrap();
    let th = 15f64.to_radians();
    model.gravity = Vector3::new(9.81 * th.sin(), 0.0, -9.81 * th.cos());
    let opts = SimOptions {
        contact: ContactParams {
            friction: mu,
            ..Default::default()
        },
        solver,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    assert_eq!(sim.integrator(), Integrator::SemiImplicitEuler);
    let mut q = sim.q().clone();
    q[2] = 0.05;
    let v = sim.v().clone();
    sim.set_state(&q, &v).unwrap();
    let mut x1 = (0.0, 0.0);
    while sim.time() < 2.0 {
        sim.step_until(2.0).unwrap();
        if (sim.time() - 1.0).abs() < 1e-9 {
            x1 = (sim.q()[0], sim.v()[0]);
        }
    }
    let _ = x1;
    // acceleration from the velocity gained between t = 1 s and 2 s
    let a = sim.v()[0] - x1.1;
    (sim.q()[0], a, sim.penetration())
}

#[test]
fn incline_static_friction_holds() {
    for solver in [Solver::Pgs, Solver::Newton] {
        let (x, _, pen) = incline(0.5, solver);
        assert!(
            x.abs() < 1e-3,
            "{solver:?}: box crept {x} m in 2 s with mu = 0.5"
        );
        assert!(pen < 1e-3);
        eprintln!("{solver:?} mu=0.5: displacement after 2 s = {x:e} m, penetration {pen:e}");
    }
}

#[test]
fn incline_sliding_acceleration() {
    // the slope is along a tangent axis: the pyramid of the Newton solver has
    // the disc's friction limit there
    for solver in [Solver::Pgs, Solver::Newton] {
        let (_, a, _) = incline(0.1, solver);
        let th = 15f64.to_radians();
        let expect = 9.81 * (th.sin() - 0.1 * th.cos());
        let rel = (a - expect) / expect;
        eprintln!("{solver:?} mu=0.1: slope acceleration {a} vs {expect} (rel {rel:e})");
        assert!(rel.abs() < 0.03, "{solver:?}");
    }
}

fn tumbling(integrator: Integrator) -> (f64, f64) {
    let urdf = r#"<robot name="body"><link name="body">
<inertial><mass value="1"/><inertia ixx="1" iyy="2" izz="3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#;
    let mut model = load_str(urdf, "body.urdf", FLOAT).unwrap();
    model.gravity = Vector3::zeros();
    let opts = SimOptions {
        integrator: Some(integrator),
        dt: 1e-3,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    assert!(!sim.has_contact());
    let w = Vector3::new(0.05, 1.0, 0.05).normalize() * 5.0;
    let q = sim.q().clone();
    let mut v = DVector::zeros(6);
    v[3] = w.x;
    v[4] = w.y;
    v[5] = w.z;
    sim.set_state(&q, &v).unwrap();
    let inertia = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0));
    let momentum = |sim: &Simulation| {
        let q = sim.q();
        let r = urdyn::spatial::quat_to_matrix(q[3], q[4], q[5], q[6]);
        let v = sim.v();
        r * (inertia * Vector3::new(v[3], v[4], v[5]))
    };
    let (e0, l0) = (sim.energy(), momentum(&sim));
    while sim.time() < 1.0 {
        sim.step_until(1.0).unwrap();
    }
    assert_eq!(sim.time(), 1.0);
    let (e1, l1) = (sim.energy(), momentum(&sim));
    ((e1 - e0).abs() / e0, (l1 - l0).norm() / l0.norm())
}

#[test]
fn tumbling_rk4_conserves_energy_and_momentum() {
    let (de, dl) = tumbling(Integrator::Rk4);
    eprintln!("rk4 tumbling, 1 s at dt=1e-3: energy rel {de:e}, world angular momentum rel {dl:e}");
    assert!(de < 1e-10 && dl < 1e-10, "energy {de:e}, momentum {dl:e}");
    let (de, dl) = tumbling(Integrator::Dop853);
    eprintln!("dop853 tumbling (tol 1e-6): energy rel {de:e}, momentum rel {dl:e}");
}

#[test]
fn bouncing_ball_energy_never_rises() {
    for solver in [Solver::Pgs, Solver::Newton] {
        bouncing_ball(solver);
    }
}

fn bouncing_ball(solver: Solver) {
    let urdf = r#"<robot name="ball"><link name="ball">
<inertial><mass value="1"/><inertia ixx="0.004" iyy="0.004" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><sphere radius="0.1"/></geometry></collision></link></robot>"#;
    let model = load_str(urdf, "ball.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        contact: ContactParams {
            restitution: 0.7,
            ..Default::default()
        },
        solver,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    q[2] = 1.0;
    let mut v = sim.v().clone();
    v[0] = 0.3; // some sliding and spin at the impacts
    v[4] = 2.0;
    sim.set_state(&q, &v).unwrap();
    let mut e_prev = sim.energy();
    let e0 = e_prev;
    let (mut impacts, mut was_contact, mut z_max_after) = (0, false, 0.0f64);
    while sim.time() < 3.0 {
        sim.step_until(3.0).unwrap();
        let e = sim.energy();
        assert!(
            e <= e_prev + 1e-12 * e0.abs(),
            "energy rose at t = {}: {e_prev} -> {e}",
            sim.time()
        );
        e_prev = e;
        let c = sim.active_contacts() > 0;
        if c && !was_contact {
            impacts += 1;
        }
        was_contact = c;
        if impacts == 1 && !c {
            z_max_after = z_max_after.max(sim.q()[2]);
        }
        assert!(sim.penetration() < 1e-3);
    }
    eprintln!("{solver:?} ball: {impacts} impacts, first rebound apex z = {z_max_after}");
    assert!(impacts >= 2, "the ball must bounce");
    assert!(z_max_after > 0.3);
}

#[test]
fn no_collision_geometry_no_contact_queries() {
    let urdf = r#"<robot name="p"><link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/></joint>
<link name="b"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#;
    let model = load_str(urdf, "p.urdf", LoadOptions::default()).unwrap();
    let mut sim = Simulation::new(model, SimOptions::default()).unwrap();
    assert!(!sim.has_contact());
    assert_eq!(sim.integrator(), Integrator::Dop853);
    while sim.time() < 0.5 {
        sim.step_until(0.5).unwrap();
    }
    assert_eq!(sim.contact_queries(), 0);
    // the lamp with the ground off: no queries either; with it on: queries
    let lamp = urdyn::load_file(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/lamp.urdf"),
        FLOAT,
    )
    .unwrap();
    let mut sim = Simulation::new(
        lamp.clone(),
        SimOptions {
            ground: None,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..10 {
        sim.step().unwrap();
    }
    assert_eq!(sim.contact_queries(), 0);
    let mut sim = Simulation::new(lamp, SimOptions::default()).unwrap();
    sim.step().unwrap();
    assert!(sim.contact_queries() > 0);
}

fn pendulum(friction: f64, limit: Option<(f64, f64)>) -> String {
    let lim = match limit {
        Some((lo, hi)) => {
            format!(r#"<limit lower="{lo}" upper="{hi}" effort="10" velocity="10"/>"#)
        }
        None => r#"<limit lower="-10" upper="10" effort="10" velocity="10"/>"#.into(),
    };
    format!(
        r#"<robot name="p"><link name="a"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>{lim}<dynamics damping="0" friction="{friction}"/></joint>
<link name="b"><inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#
    )
}

#[test]
fn joint_friction_holds_below_and_slips_above() {
    // horizontal 0.5 m arm of 1 kg: gravity torque 4.905 N m
    for (friction, moves) in [(5.0, false), (4.0, true)] {
        let model = load_str(&pendulum(friction, None), "p.urdf", LoadOptions::default()).unwrap();
        for integ in Integrator::ALL {
            let mut sim = Simulation::new(
                model.clone(),
                SimOptions {
                    integrator: Some(integ),
                    ..Default::default()
                },
            )
            .unwrap();
            while sim.time() < 1.0 {
                sim.step_until(1.0).unwrap();
            }
            let q = sim.q()[0];
            if moves {
                assert!(
                    q.abs() > 0.1,
                    "{integ:?}: friction {friction} should slip, q = {q}"
                );
            } else {
                assert!(
                    q.abs() < 1e-9,
                    "{integ:?}: friction {friction} should hold, q = {q}"
                );
            }
        }
    }
}

#[test]
fn joint_limit_is_not_passed() {
    // the arm falls (about +y, positive angle lowers it) onto a limit at 0.5 rad
    let model = load_str(
        &pendulum(0.0, Some((-0.5, 0.5))),
        "p.urdf",
        LoadOptions::default(),
    )
    .unwrap();
    for integ in Integrator::ALL {
        let mut sim = Simulation::new(
            model.clone(),
            SimOptions {
                integrator: Some(integ),
                ..Default::default()
            },
        )
        .unwrap();
        let mut qmax = f64::NEG_INFINITY;
        while sim.time() < 2.0 {
            sim.step_until(2.0).unwrap();
            qmax = qmax.max(sim.q()[0]);
        }
        assert!(qmax < 0.5 + 1e-3, "{integ:?}: passed the limit: {qmax}");
        assert!(
            (sim.q()[0] - 0.5).abs() < 1e-3,
            "{integ:?}: rests at {}",
            sim.q()[0]
        );
    }
}

#[test]
fn effort_limit_clamps_applied_torque() {
    let model = load_str(&pendulum(0.0, None), "p.urdf", LoadOptions::default()).unwrap();
    let mut model = model;
    model.gravity = Vector3::zeros();
    let mut sim = Simulation::new(
        model,
        SimOptions {
            integrator: Some(Integrator::Rk4),
            ..Default::default()
        },
    )
    .unwrap();
    sim.torques_mut()[0] = 100.0; // effort limit 10
    while sim.time() < 0.1 {
        sim.step_until(0.1).unwrap();
    }
    // I = 0.001 + 1 * 0.25 about the joint: α = 10 / 0.251
    let expect = 10.0 / 0.251 * 0.1;
    assert!(
        (sim.v()[0] - expect).abs() < 1e-9 * expect,
        "{} vs {expect}",
        sim.v()[0]
    );
}
