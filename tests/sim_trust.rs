//! Simulation you can trust: implicit damping at the rate the scheme predicts,
//! stiff damping stable in every integrator, gentle recovery from starts that
//! violate a constraint, no energy gained at impacts by any integrator, runs
//! that land exactly on their end, and a diverging passive run stopped with an
//! error.

use nalgebra::DVector;
use urdyn::sim::{Integrator, SimError, SimOptions, Simulation, Violation};
use urdyn::{load_str, LoadOptions};

const FLOAT: LoadOptions = LoadOptions {
    floating_base: true,
};

/// A rotor: one revolute joint about z (gravity along z does no work), a
/// cylinder-like body of axial inertia `izz`, viscous damping `b`.
fn rotor(izz: f64, b: f64) -> String {
    format!(
        r#"<robot name="rotor"><link name="base"/>
<link name="wheel"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="spin" type="continuous"><parent link="base"/><child link="wheel"/><axis xyz="0 0 1"/><dynamics damping="{b}"/></joint></robot>"#
    )
}

fn sim_of(urdf: &str, load: LoadOptions, opts: SimOptions) -> Simulation {
    let model = load_str(urdf, "test.urdf", load).unwrap();
    Simulation::new(model, opts).unwrap()
}

#[test]
fn damped_rotor_decays_at_the_implicit_euler_rate() {
    // (I + h b) v⁺ = I v: v_n = v_0 (I / (I + h b))ⁿ, exactly, for any b
    for (izz, b) in [(0.01, 0.05), (1e-6, 2.0)] {
        let h = 1e-3;
        let mut sim = sim_of(
            &rotor(izz, b),
            LoadOptions::default(),
            SimOptions {
                dt: h,
                ground: None,
                integrator: Some(Integrator::SemiImplicitEuler),
                ..Default::default()
            },
        );
        let q = sim.q().clone();
        sim.set_state(&q, &DVector::from_element(1, 3.0)).unwrap();
        let n = 200;
        for _ in 0..n {
            sim.step().unwrap();
        }
        let expect = 3.0 * (izz / (izz + h * b)).powi(n);
        let got = sim.v()[0];
        assert!(
            (got - expect).abs() <= 1e-12 * 3.0 + 1e-9 * expect.abs(),
            "izz {izz}, b {b}: v = {got}, implicit Euler predicts {expect}"
        );
    }
}

#[test]
fn damping_in_smooth_integrators_is_accurate_when_mild_and_stable_when_stiff() {
    // mild: v(t) = v0 exp(−b t / I) to the splitting's accuracy
    for integ in [Integrator::Rk4, Integrator::Dop853] {
        let (izz, b) = (0.01, 0.01);
        let mut sim = sim_of(
            &rotor(izz, b),
            LoadOptions::default(),
            SimOptions {
                ground: None,
                integrator: Some(integ),
                ..Default::default()
            },
        );
        let q = sim.q().clone();
        sim.set_state(&q, &DVector::from_element(1, 2.0)).unwrap();
        while sim.time() < 1.0 {
            sim.step_until(1.0).unwrap();
        }
        let expect = 2.0 * (-b / izz).exp();
        let got = sim.v()[0];
        assert!(
            ((got - expect) / expect).abs() < 1e-5,
            "{integ:?}: v(1) = {got}, exact {expect}"
        );
        // the angle is the integral of v: (1 − e^(−bt/I)) v0 I / b
        let angle = 2.0 * izz / b * (1.0 - (-b / izz).exp());
        assert!((sim.q()[0] - angle).abs() < 1e-4 * angle);
    }
    // stiff (λ = b/I = 2e6 s⁻¹): a few steps take the rotor to rest, never flipping
    for integ in Integrator::ALL {
        let mut sim = sim_of(
            &rotor(1e-6, 2.0),
            LoadOptions::default(),
            SimOptions {
                ground: None,
                integrator: Some(integ),
                ..Default::default()
            },
        );
        let q = sim.q().clone();
        sim.set_state(&q, &DVector::from_element(1, 5.0)).unwrap();
        let mut prev = 5.0f64;
        while sim.time() < 0.1 {
            sim.step_until(0.1).unwrap();
            let v = sim.v()[0];
            assert!(v.abs() <= prev.abs() + 1e-15, "{integ:?}: |v| rose to {v}");
            prev = v;
        }
        assert!(prev.abs() < 1e-6, "{integ:?}: v = {prev} after 0.1 s");
        assert!(sim.steps < 2000, "{integ:?}: {} steps for 0.1 s", sim.steps);
    }
}

/// A stiff three-finger "hand" hanging under gravity: light links, strong damping.
fn stiff_hand() -> String {
    let mut s = String::from(
        r#"<robot name="hand"><link name="palm"><inertial><mass value="0.5"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>"#,
    );
    for f in 0..3 {
        let mut parent = "palm".to_string();
        for k in 0..3 {
            let name = format!("f{f}_{k}");
            s += &format!(
                r#"<link name="{name}"><inertial><origin xyz="0 0 -0.02"/><mass value="0.01"/><inertia ixx="2e-7" iyy="2e-7" izz="1e-8" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j{f}_{k}" type="revolute"><parent link="{parent}"/><child link="{name}"/><origin xyz="{} 0 -0.04" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="5"/><dynamics damping="0.5"/></joint>"#,
                if k == 0 { 0.03 * f as f64 - 0.03 } else { 0.0 }
            );
            parent = name;
        }
    }
    s + "</robot>"
}

#[test]
fn stiff_hand_is_stable_with_every_integrator() {
    let mut finals = Vec::new();
    for integ in Integrator::ALL {
        let mut sim = sim_of(
            &stiff_hand(),
            LoadOptions::default(),
            SimOptions {
                ground: None,
                integrator: Some(integ),
                ..Default::default()
            },
        );
        let mut q = sim.q().clone();
        for k in 0..q.len() {
            q[k] = 0.3 * ((k as f64) + 1.0).sin();
        }
        let v = DVector::from_element(sim.model.nv, 1.0);
        sim.set_state(&q, &v).unwrap();
        let e0 = sim.energy();
        let mut emax = e0;
        while sim.time() < 1.0 {
            sim.step_until(1.0).unwrap();
            emax = emax.max(sim.energy());
        }
        assert!(emax <= e0 + 1e-9, "{integ:?}: energy rose {e0} -> {emax}");
        // overdamped: the fingers creep at about their gravity torque / damping
        assert!(sim.v().amax() < 0.05, "{integ:?}: {}", sim.v().amax());
        assert!(sim.steps <= 20_000, "{integ:?}: {} steps", sim.steps);
        assert_eq!(sim.time(), 1.0);
        finals.push(sim.q().clone());
    }
    // the three schemes agree on where the creeping fingers are
    for q in &finals[1..] {
        let d = (q - &finals[0]).amax();
        assert!(d < 1e-4, "integrators disagree by {d} rad");
    }
}

fn ball(r: f64) -> String {
    let i = 0.4 * r * r;
    format!(
        r#"<robot name="ball"><link name="ball"><inertial><mass value="1"/><inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><sphere radius="{r}"/></geometry></collision></link></robot>"#
    )
}

#[test]
fn start_deep_in_the_ground_is_recovered_gently() {
    let mut sim = sim_of(&ball(0.1), FLOAT, SimOptions::default());
    let mut q = sim.q().clone();
    q[2] = -0.3; // 0.4 m deep
    let v = sim.v().clone();
    sim.set_state(&q, &v).unwrap();
    let viol = sim.start_violations();
    assert!(
        matches!(viol.as_slice(), [Violation::Ground { link, depth }] if link == "ball" && (depth - 0.4).abs() < 1e-9),
        "{viol:?}"
    );
    assert!(viol[0].to_string().contains("ground"));
    let cap = sim.options().contact.max_push_speed;
    let mut z = sim.q()[2];
    let mut vmax: f64 = 0.0;
    while sim.time() < 2.0 {
        sim.step_until(2.0).unwrap();
        let dz = sim.q()[2] - z;
        assert!(
            dz <= cap * sim.dt() * (1.0 + 1e-9) + 1e-12,
            "pushed {dz} m in a step"
        );
        z = sim.q()[2];
        vmax = vmax.max(sim.v().rows(0, 3).norm());
    }
    // out of the ground, resting on it, never thrown
    assert!((z - 0.1).abs() < 1e-3, "z = {z}");
    assert!(vmax < 0.05, "base speed reached {vmax} m/s");
    assert!(sim.penetration() < 1e-3);
}

#[test]
fn start_outside_a_joint_limit_is_recovered_gently() {
    let urdf = r#"<robot name="p"><link name="a"/>
<link name="b"><inertial><origin xyz="0 0 -0.2"/><mass value="1"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="calf" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/><limit lower="-2.82" upper="-0.89" effort="30" velocity="20"/></joint></robot>"#;
    for integ in Integrator::ALL {
        let mut sim = sim_of(
            urdf,
            LoadOptions::default(),
            SimOptions {
                ground: None,
                integrator: Some(integ),
                ..Default::default()
            },
        );
        let viol = sim.start_violations();
        assert!(
            matches!(viol.as_slice(), [Violation::Limit { joint, amount, .. }] if joint == "calf" && (amount - 0.89).abs() < 1e-12),
            "{viol:?}"
        );
        assert!(viol[0].to_string().contains("limit"));
        let mut vmax: f64 = 0.0;
        while sim.time() < 3.0 {
            sim.step_until(3.0).unwrap();
            vmax = vmax.max(sim.v()[0].abs());
        }
        let q = sim.q()[0];
        assert!(
            (-2.82 - 1e-3..=-0.89 + 1e-3).contains(&q),
            "{integ:?}: q = {q}"
        );
        assert!(vmax < 20.0, "{integ:?}: joint speed reached {vmax}");
    }
}

#[test]
fn impacts_add_no_energy_with_any_integrator() {
    // a tilted box dropped from 0.3 m: energy never above its start, at rest
    let urdf = r#"<robot name="box"><link name="box"><inertial><mass value="2"/><inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.4 0.3 0.2"/></geometry></collision></link></robot>"#;
    for integ in Integrator::ALL {
        let mut sim = sim_of(
            urdf,
            FLOAT,
            SimOptions {
                integrator: Some(integ),
                ..Default::default()
            },
        );
        let mut q = sim.q().clone();
        let (s, c) = (0.2f64).sin_cos();
        q[2] = 0.6;
        q[3] = s;
        q[6] = c;
        let mut v = sim.v().clone();
        v[4] = 2.0;
        sim.set_state(&q, &v).unwrap();
        let e0 = sim.energy();
        let mut emax = e0;
        let end = 2.0005; // not a multiple of dt: the last step lands on it
        while sim.time() < end {
            sim.step_until(end).unwrap();
            emax = emax.max(sim.energy());
        }
        assert_eq!(sim.time(), end);
        assert!(emax <= e0 + 1e-6, "{integ:?}: energy rose {e0} -> {emax}");
        assert!(sim.v().amax() < 0.05, "{integ:?}: not at rest {}", sim.v());
        assert!(sim.penetration() < 1e-3);
    }
}

#[test]
fn diverging_passive_run_is_an_error() {
    // RK4 at a step far beyond its stability limit on a stiff pendulum
    let urdf = r#"<robot name="p"><link name="a"/>
<link name="b"><inertial><origin xyz="0 0 -0.01"/><mass value="1"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/></joint></robot>"#;
    let mut sim = sim_of(
        urdf,
        LoadOptions::default(),
        SimOptions {
            ground: None,
            dt: 0.2,
            integrator: Some(Integrator::Rk4),
            ..Default::default()
        },
    );
    let q = DVector::from_element(1, 0.5);
    sim.set_state(&q, &DVector::zeros(1)).unwrap();
    let err = loop {
        match sim.step_until(100.0) {
            Ok(_) if sim.time() < 100.0 => continue,
            Ok(_) => panic!("ran to the end: energy {}", sim.energy()),
            Err(e) => break e,
        }
    };
    match &err {
        SimError::Diverging {
            energy,
            reference,
            quantity,
            ..
        } => {
            assert!(energy > reference);
            assert_eq!(quantity, "v:j");
        }
        e => panic!("not a divergence: {e}"),
    }
    assert!(err.to_string().contains("diverging"));
}

#[test]
fn armature_adds_rotor_inertia() {
    // a damped rotor with armature A decays as I + A: v⁺ = v (I + A)/(I + A + h b)
    let (izz, b, a, h) = (0.01, 0.05, 0.02, 1e-3);
    let mut sim = sim_of(
        &rotor(izz, b),
        LoadOptions::default(),
        SimOptions {
            ground: None,
            dt: h,
            armature: a,
            integrator: Some(Integrator::SemiImplicitEuler),
            ..Default::default()
        },
    );
    let q = sim.q().clone();
    sim.set_state(&q, &DVector::from_element(1, 1.0)).unwrap();
    assert!((sim.energy() - 0.5 * (izz + a)).abs() < 1e-12);
    for _ in 0..100 {
        sim.step().unwrap();
    }
    let expect = ((izz + a) / (izz + a + h * b)).powi(100);
    assert!((sim.v()[0] - expect).abs() < 1e-12);
}
