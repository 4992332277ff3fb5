//! Joint servos (`Simulation::set_gains`, `set_targets`): stable at any gain
//! with every integrator, the static error under gravity, the effort limit,
//! gains 0 bit for bit no servo, bad input.

use nalgebra::DVector;
use urdyn::sim::{Integrator, SimOptions, Simulation};
use urdyn::{load_file, load_str, LoadOptions};

/// A pendulum about y: mass `m` at `l` along x from the joint (θ = 0
/// horizontal), effort limit `effort`. Gravity torque m g l cos θ.
fn pendulum(m: f64, l: f64, effort: f64) -> String {
    let i = m * 1e-4;
    format!(
        r#"<robot name="p"><link name="base"/>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
<axis xyz="0 1 0"/><limit lower="-6" upper="6" effort="{effort}" velocity="100"/></joint>
<link name="arm"><inertial><origin xyz="{l} 0 0"/><mass value="{m}"/>
<inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#
    )
}

fn sim(urdf: &str, integrator: Integrator) -> Simulation {
    let model = load_str(urdf, "p.urdf", LoadOptions::default()).unwrap();
    let opts = SimOptions {
        integrator: Some(integrator),
        ground: None,
        ..Default::default()
    };
    Simulation::new(model, opts).unwrap()
}

fn run(sim: &mut Simulation, t: f64) {
    while sim.time() < t - 1e-12 {
        let target = (sim.time() + 1e-3).min(t);
        while sim.time() < target - 1e-12 {
            sim.step_until(target).unwrap();
        }
    }
}

/// The equilibrium θ of kp (θ_ref − θ) + m g l cos θ = 0 (Newton).
fn equilibrium(kp: f64, th_ref: f64, mgl: f64) -> f64 {
    let mut th = th_ref;
    for _ in 0..50 {
        let f = kp * (th_ref - th) + mgl * th.cos();
        let df = -kp - mgl * th.sin();
        th -= f / df;
    }
    th
}

#[test]
fn static_error_is_mgl_cos_over_kp_with_every_integrator() {
    let (m, l, g) = (1.0, 0.5, 9.81);
    let (kp, kd, th_ref) = (2000.0, 40.0, 0.3);
    for integ in Integrator::ALL {
        let mut s = sim(&pendulum(m, l, 1e3), integ);
        s.set_gains_uniform(kp, kd).unwrap();
        s.set_targets(&DVector::from_element(1, th_ref), None)
            .unwrap();
        run(&mut s, 3.0);
        let th = s.q()[0];
        let th_eq = equilibrium(kp, th_ref, m * g * l);
        // first order: θ − θ_ref = m g l cos θ / kp
        let err = th - th_ref;
        let closed = m * g * l * th.cos() / kp;
        assert!(
            (err - closed).abs() < 1e-7 * closed.abs().max(1e-3),
            "{}: static error {err} vs m g l cos θ / kp = {closed}",
            integ.name()
        );
        assert!(
            (th - th_eq).abs() < 1e-9,
            "{}: {th} vs {th_eq}",
            integ.name()
        );
        assert!(s.v()[0].abs() < 1e-6);
    }
}

#[test]
fn stiff_gain_is_stable_with_every_integrator() {
    // kp = 1e6 on a light arm (I = 1e-3 kg·m²: ω = 3.2e4 rad/s, h ω = 32) and
    // on a heavy one (h ω = 2, the smooth integrators' own range)
    for (m, l) in [(0.1, 0.1), (1.0, 0.5)] {
        for kd in [0.0, 1e3] {
            for integ in Integrator::ALL {
                let mut s = sim(&pendulum(m, l, 1e9), integ);
                s.set_gains_uniform(1e6, kd).unwrap();
                s.set_targets(&DVector::from_element(1, 0.5), None).unwrap();
                let (q0, v0) = (DVector::from_element(1, 0.0), DVector::from_element(1, 3.0));
                s.set_state(&q0, &v0).unwrap();
                run(&mut s, 2.0);
                let th_eq = equilibrium(1e6, 0.5, m * 9.81 * l);
                let (th, v) = (s.q()[0], s.v()[0]);
                assert!(
                    th.is_finite() && v.is_finite(),
                    "{} m={m} kd={kd}",
                    integ.name()
                );
                // bounded by the start's energy: |θ − θ_eq| ≤ its first swing
                assert!(
                    (th - th_eq).abs() < 0.6 && v.abs() < 3.0 * (1.0 + 1e6f64.sqrt()),
                    "{} m={m} kd={kd}: θ {th} v {v}",
                    integ.name()
                );
                if kd > 0.0 {
                    assert!(
                        (th - th_eq).abs() < 1e-6 && v.abs() < 1e-4,
                        "{} m={m} kd={kd}: θ {th} (eq {th_eq}) v {v}",
                        integ.name()
                    );
                }
            }
        }
    }
}

#[test]
fn effort_limit_below_gravity_lets_it_fall() {
    let (m, l, g) = (1.0, 0.5, 9.81);
    for integ in Integrator::ALL {
        // the servo alone could hold it (kp large), the motor cannot
        let mut s = sim(&pendulum(m, l, 0.5 * m * g * l), integ);
        s.set_gains_uniform(1e4, 100.0).unwrap();
        s.set_targets(&DVector::from_element(1, 0.0), None).unwrap();
        run(&mut s, 1.0);
        assert!(s.q()[0] > 0.5, "{}: θ = {}", integ.name(), s.q()[0]);
        // with effort enough it holds within m g l / kp
        let mut s = sim(&pendulum(m, l, 2.0 * m * g * l), integ);
        s.set_gains_uniform(1e4, 100.0).unwrap();
        s.set_targets(&DVector::from_element(1, 0.0), None).unwrap();
        run(&mut s, 1.0);
        assert!(s.q()[0].abs() < 1.1 * m * g * l / 1e4, "{}", integ.name());
    }
}

#[test]
fn saturated_servo_applies_exactly_the_effort() {
    // a servo saturated at +effort against gravity: the arm falls as under a
    // constant torque +effort (the effort limit alone, τ_ff = +effort)
    let (m, l, g) = (1.0, 0.5, 9.81);
    let e = 0.5 * m * g * l;
    let mut a = sim(&pendulum(m, l, e), Integrator::SemiImplicitEuler);
    a.set_gains_uniform(1e5, 10.0).unwrap();
    a.set_targets(&DVector::from_element(1, -1.0), None)
        .unwrap();
    let mut b = sim(&pendulum(m, l, e), Integrator::SemiImplicitEuler);
    b.set_torques(&DVector::from_element(1, -10.0 * e)).unwrap();
    for _ in 0..300 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert!(
        (a.q()[0] - b.q()[0]).abs() < 1e-12,
        "{} {}",
        a.q()[0],
        b.q()[0]
    );
}

#[test]
fn gains_zero_change_nothing_bit_for_bit() {
    let model = load_file("tests/urdf/double_pendulum.urdf", LoadOptions::default()).unwrap();
    for integ in Integrator::ALL {
        let opts = SimOptions {
            integrator: Some(integ),
            ground: None,
            ..Default::default()
        };
        let mut a = Simulation::new(model.clone(), opts.clone()).unwrap();
        let mut b = Simulation::new(model.clone(), opts).unwrap();
        b.set_gains(&DVector::zeros(2), &DVector::zeros(2)).unwrap();
        b.set_targets(
            &DVector::from_vec(vec![0.4, -0.2]),
            Some(&DVector::from_vec(vec![1.0, 2.0])),
        )
        .unwrap();
        let q = DVector::from_vec(vec![0.7, -0.3]);
        let v = DVector::from_vec(vec![0.5, 1.0]);
        a.set_state(&q, &v).unwrap();
        b.set_state(&q, &v).unwrap();
        for k in 0..400 {
            let tau = DVector::from_vec(vec![(k as f64 * 0.01).sin() * 5.0, 1.0]);
            a.set_torques(&tau).unwrap();
            b.set_torques(&tau).unwrap();
            a.step().unwrap();
            b.step().unwrap();
            assert_eq!(a.q(), b.q(), "{} step {k}", integ.name());
            assert_eq!(a.v(), b.v(), "{} step {k}", integ.name());
        }
    }
}

#[test]
fn gains_and_targets_persist_across_set_state() {
    let model = load_file("tests/urdf/double_pendulum.urdf", LoadOptions::default()).unwrap();
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..Default::default()
    };
    let mut s = Simulation::new(model, opts).unwrap();
    s.set_gains_uniform(500.0, 20.0).unwrap();
    s.set_targets(&DVector::from_vec(vec![0.2, 0.1]), None)
        .unwrap();
    s.set_state(&DVector::from_vec(vec![-0.5, 0.5]), &DVector::zeros(2))
        .unwrap();
    assert_eq!(s.gains().0[1], 500.0);
    assert_eq!(s.targets().0[0], 0.2);
    for _ in 0..4000 {
        s.step().unwrap();
    }
    // held near the targets (within the gravity sag, 500 N·m/rad)
    assert!(
        (s.q()[0] - 0.2).abs() < 0.1 && (s.q()[1] - 0.1).abs() < 0.1,
        "{:?}",
        s.q()
    );
}

#[test]
fn bad_gains_and_targets_are_errors() {
    let model = load_file(
        "assets/robots/solo12.urdf",
        LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let nv = model.nv;
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut s = Simulation::new(model, opts).unwrap();
    let ok = DVector::from_element(nv, 0.0);
    let mut neg = ok.clone();
    neg[8] = -1.0;
    let mut nan = ok.clone();
    nan[9] = f64::NAN;
    let mut base = ok.clone();
    base[2] = 1.0;
    for (kp, kd, what) in [
        (&neg, &ok, "kp[8]"),
        (&ok, &nan, "kd[9]"),
        (&base, &ok, "floating-base"),
    ] {
        let e = s.set_gains(kp, kd).unwrap_err().to_string();
        assert!(e.contains(what) && !e.contains('\n'), "{e}");
    }
    let e = s
        .set_gains(&DVector::zeros(3), &ok)
        .unwrap_err()
        .to_string();
    assert!(e.contains("nv = 18"), "{e}");
    let e = s
        .set_targets(&DVector::zeros(3), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("nq = 19"), "{e}");
    let mut q = s.q().clone();
    q[10] = f64::INFINITY;
    let e = s.set_targets(&q, None).unwrap_err().to_string();
    assert!(e.contains("q_ref[10]"), "{e}");
    assert!(!s.has_servos());
}
