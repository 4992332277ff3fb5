//! Transition Jacobians of a step (`Simulation::transition_jacobians`): the
//! analytic A, B against central finite differences of the step on an arm, a
//! damped chain, a quadruped standing (sticking), a box sliding, with servos;
//! the finite-difference modes against each other; the call changes nothing.

use nalgebra::{DMatrix, DVector, Vector3};
use urdyn::contact::ContactParams;
use urdyn::sim::{Integrator, JacobianMethod, SimOptions, Simulation, TransitionJacobians};
use urdyn::{load_file, load_str, LoadOptions};

const FLOAT: LoadOptions = LoadOptions {
    floating_base: true,
};

fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).norm() / b.norm().max(1e-300)
}

fn jac(sim: &Simulation, tau: &DVector<f64>, m: JacobianMethod) -> TransitionJacobians {
    sim.transition_jacobians(tau, m, 1e-6).unwrap()
}

/// Analytic against central within `tol` (Frobenius, relative), forward
/// against central within `ftol`; returns (err A, err B).
fn check(sim: &Simulation, tau: &DVector<f64>, tol: f64, ftol: f64, what: &str) -> (f64, f64) {
    let an = jac(sim, tau, JacobianMethod::Analytic);
    let ce = jac(sim, tau, JacobianMethod::Central);
    let fw = jac(sim, tau, JacobianMethod::Forward);
    let (ea, eb) = (rel(&an.a, &ce.a), rel(&an.b, &ce.b));
    eprintln!(
        "{what}: analytic vs central A {ea:.2e} B {eb:.2e}; forward vs central A {:.2e} B {:.2e}",
        rel(&fw.a, &ce.a),
        rel(&fw.b, &ce.b)
    );
    assert!(ea < tol && eb < tol, "{what}: A {ea:.3e}, B {eb:.3e}");
    assert!(
        rel(&fw.a, &ce.a) < ftol && rel(&fw.b, &ce.b) < ftol,
        "{what}: forward vs central"
    );
    (ea, eb)
}

/// A converged contact solve: the finite differences then see the step's
/// derivative, not the solver's stopping tolerance (1e-6 m/s by default,
/// against perturbations of 1e-6).
fn tight() -> SimOptions {
    SimOptions {
        solver_tol: 1e-13,
        solver_iterations: 400,
        ..Default::default()
    }
}

/// The state lowered by 50 µm: every contact inside its slop (1e-4 m), off
/// the kink φ = 0 of the speculative target b = −max(φ, 0)/h where a resting
/// contact sits (docs/theory.md §"Transition Jacobians": a mode boundary).
fn pressed(sim: &mut Simulation) {
    let (mut q, v) = (sim.q().clone(), sim.v().clone());
    q[2] -= 5e-5;
    sim.set_state(&q, &v).unwrap();
}

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

#[test]
fn arm_without_contact() {
    let model = load_file("assets/robots/ur5.urdf", LoadOptions::default()).unwrap();
    let nv = model.nv;
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut s = 7;
    let q = DVector::from_fn(nv, |_, _| lcg(&mut s));
    let v = DVector::from_fn(nv, |_, _| 2.0 * lcg(&mut s));
    let tau = DVector::from_fn(nv, |_, _| 5.0 * lcg(&mut s));
    sim.set_state(&q, &v).unwrap();
    check(&sim, &tau, 1e-5, 1e-3, "ur5 euler");
    // the identity part: ∂q'/∂τ = h ∂v'/∂τ on a fixed base
    let an = jac(&sim, &tau, JacobianMethod::Analytic);
    let h = sim.dt();
    let top = an.b.rows(0, nv).into_owned();
    let bottom = an.b.rows(nv, nv).into_owned() * h;
    assert!(rel(&top, &bottom) < 1e-12);
}

#[test]
fn damped_chain() {
    let text = std::fs::read_to_string("tests/urdf/chain20_hanging.urdf")
        .unwrap()
        .replace("</joint>", "<dynamics damping=\"0.02\"/></joint>");
    let model = load_str(&text, "chain20_damped.urdf", LoadOptions::default()).unwrap();
    let nv = model.nv;
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut s = 3;
    let q = DVector::from_fn(nv, |_, _| 0.5 * lcg(&mut s));
    let v = DVector::from_fn(nv, |_, _| lcg(&mut s));
    sim.set_state(&q, &v).unwrap();
    let tau = DVector::from_fn(nv, |_, _| 0.1 * lcg(&mut s));
    check(&sim, &tau, 1e-5, 1e-3, "damped chain");
}

#[path = "common/quadruped.rs"]
mod quadruped;

#[test]
fn quadruped_standing_with_servos() {
    let mut sim = quadruped::standing_quadruped(tight());
    assert_eq!(sim.active_contacts(), 4);
    pressed(&mut sim);
    let nv = sim.model.nv;
    let tau = DVector::zeros(nv);
    check(&sim, &tau, 1e-5, 1e-2, "quadruped standing");
    // sticking feet: the feet's positions are not moved by τ, and a step from
    // rest stays at rest: A's velocity block maps the rest state's velocities
    let an = jac(&sim, &tau, JacobianMethod::Analytic);
    assert!(an.a.iter().all(|x| x.is_finite()));
}

fn box_urdf() -> &'static str {
    r#"<robot name="box"><link name="box">
<inertial><mass value="1"/><inertia ixx="0.0042" iyy="0.0042" izz="0.0067" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link></robot>"#
}

#[test]
fn box_sliding_on_the_ground() {
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        contact: ContactParams {
            friction: 0.3,
            ..Default::default()
        },
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.05;
    sim.set_state(&q, &DVector::zeros(6)).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    // sliding along x (no spin): every corner slides the same way
    let (q, mut v) = (sim.q().clone(), sim.v().clone());
    v[0] = 1.0;
    sim.set_state(&q, &v).unwrap();
    pressed(&mut sim);
    check(&sim, &DVector::zeros(6), 1e-5, 1e-2, "box sliding");
}

#[test]
fn box_spinning_in_flight_by_euler() {
    // the time-stepping step's base update (rotation of v_lin by Exp(h ω)) alone
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let q = sim.q().clone();
    let v = DVector::from_column_slice(&[1.0, 0.2, -0.3, 0.4, -0.5, 3.0]);
    sim.set_state(&q, &v).unwrap();
    check(
        &sim,
        &DVector::zeros(6),
        1e-5,
        1e-2,
        "box spinning in flight",
    );
}

#[test]
fn box_sliding_while_spinning() {
    // corners slipping in different directions: each corner's friction impulse
    // anti-parallel to its own slip (the exact cone at the solve's fixed point)
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        contact: ContactParams {
            friction: 0.3,
            ..Default::default()
        },
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.05;
    sim.set_state(&q, &DVector::zeros(6)).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let (q, mut v) = (sim.q().clone(), sim.v().clone());
    v[0] = 1.0;
    v[5] = 3.0;
    sim.set_state(&q, &v).unwrap();
    pressed(&mut sim);
    let before = sim.clone();
    // after a step, every sliding corner's impulse is anti-parallel to its slip
    sim.step().unwrap();
    let vb = sim.v().clone();
    let (w, vl) = (
        Vector3::new(vb[3], vb[4], vb[5]),
        Vector3::new(vb[0], vb[1], vb[2]),
    );
    let qq = sim.q().clone();
    let r = urdyn::spatial::quat_to_matrix(qq[3], qq[4], qq[5], qq[6]);
    let o = Vector3::new(qq[0], qq[1], qq[2]);
    let mut n = 0;
    for f in sim.contact_forces() {
        // the point's world velocity: R (v + ω × Rᵀ(p − o))
        let p_b = r.transpose() * (f.point.point - o);
        let slip = r * (vl + w.cross(&p_b));
        let (st, ft) = (
            Vector3::new(slip.x, slip.y, 0.0),
            Vector3::new(f.force.x, f.force.y, 0.0),
        );
        if st.norm() > 1e-3 && ft.norm() > 1e-9 {
            let cos = st.dot(&ft) / (st.norm() * ft.norm());
            // (the end state's slip: the step's own, at its start pose, is
            // h ω = 3 mrad away)
            assert!(cos < -0.9999, "impulse at cos {cos} to the slip");
            n += 1;
        }
    }
    assert!(n >= 2, "{n} sliding corners");
    // 9.8e-4 here (was 1.4e-2 before the solve's exact sliding law): the four
    // corners are redundant (three fix the box's normal motion), and which
    // split of their normal impulses the solve returns moves the friction of
    // corners slipping different ways; the derivative takes the least-norm
    // split's, the step the solve's own (docs/theory.md §"Transition
    // Jacobians"). Three corners slipping alike but determined:
    // tetrahedron_sliding_while_spinning, within 1e-5
    check(
        &before,
        &DVector::zeros(6),
        2e-3,
        1e-2,
        "box sliding while spinning",
    );
}

#[test]
fn tetrahedron_sliding_while_spinning() {
    // a tetrahedron on a face: three corners, each slipping its own way, none
    // redundant (the box's four leave the split of their normal impulses to
    // the solve: box_sliding_while_spinning)
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("tetra.obj");
    std::fs::write(
        &obj,
        "v 0.1 0 -0.04\nv -0.05 0.0866 -0.04\nv -0.05 -0.0866 -0.04\nv 0 0 0.06\n\
         f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    let urdf = format!(
        r#"<robot name="tetra"><link name="tetra">
<inertial><mass value="1"/><inertia ixx="0.0042" iyy="0.0042" izz="0.0067" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><geometry><mesh filename="{}"/></geometry></collision></link></robot>"#,
        obj.display()
    );
    let model = load_str(&urdf, "tetra.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        contact: ContactParams {
            friction: 0.3,
            ..Default::default()
        },
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.05;
    sim.set_state(&q, &DVector::zeros(6)).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    assert_eq!(sim.active_contacts(), 3);
    let (q, mut v) = (sim.q().clone(), sim.v().clone());
    v[0] = 1.0;
    v[5] = 3.0;
    sim.set_state(&q, &v).unwrap();
    pressed(&mut sim);
    check(
        &sim,
        &DVector::zeros(6),
        1e-5,
        1e-2,
        "tetrahedron sliding while spinning",
    );
}

#[test]
fn the_call_changes_nothing() {
    let a0 = quadruped::standing_quadruped(tight());
    let mut a = a0.clone();
    let mut b = a0.clone();
    let tau = DVector::from_element(a.model.nv, 0.1);
    a.set_torques(&tau).unwrap();
    b.set_torques(&tau).unwrap();
    for k in 0..30 {
        if k % 10 == 0 {
            for m in JacobianMethod::ALL {
                let _ = a.transition_jacobians(&tau, m, 1e-6).unwrap();
            }
        }
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(a.q(), b.q());
        assert_eq!(a.v(), b.v());
    }
}

#[test]
fn a_kept_workspace_answers_as_a_fresh_copy() {
    // the simulation keeps the copy it computes in between calls; a clone
    // starts without one: both answer bit for bit alike after the state, the
    // gains and targets and the model changed
    let mut sim = quadruped::standing_quadruped(tight());
    let nv = sim.model.nv;
    let tau = DVector::from_element(nv, 0.05);
    let same = |sim: &Simulation, what: &str| {
        for m in JacobianMethod::ALL {
            let kept = jac(sim, &tau, m);
            let fresh = jac(&sim.clone(), &tau, m);
            assert_eq!(kept, fresh, "{what}: {}", m.name());
        }
    };
    same(&sim, "first call");
    for _ in 0..7 {
        sim.step().unwrap();
    }
    same(&sim, "later state");
    let mut kp = DVector::from_element(nv, 80.0);
    kp.rows_mut(0, 6).fill(0.0);
    sim.set_gains(&kp, &(&kp * 0.1)).unwrap();
    let mut target = sim.q().clone();
    target[8] += 0.1;
    sim.set_targets(&target, None).unwrap();
    same(&sim, "new gains and targets");
    std::sync::Arc::make_mut(&mut sim.model).gravity.z = -5.0;
    let moon = jac(&sim, &tau, JacobianMethod::Analytic);
    same(&sim, "new gravity");
    sim.set_gains_uniform(0.0, 0.0).unwrap();
    assert_ne!(moon, jac(&sim, &tau, JacobianMethod::Analytic), "gains off");
}

#[test]
fn a_kept_workspace_answers_as_a_fresh_copy_in_a_scene() {
    // the lamp dropped onto the table: an obstacle and the lamp's own pairs,
    // whose start overlaps are decided at each state set before the first step
    let s = urdyn::scene::Scene::from_file(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/lamp_on_table.json"),
        &[],
    )
    .unwrap();
    let opts = SimOptions {
        ground: s.ground.map(|g| g.height),
        ..tight()
    };
    let mut sim = Simulation::new(s.model.clone(), opts).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    let tau = DVector::zeros(sim.model.nv);
    let same = |sim: &Simulation, what: &str| {
        for m in JacobianMethod::ALL {
            let kept = jac(sim, &tau, m);
            let fresh = jac(&sim.clone(), &tau, m);
            assert_eq!(kept, fresh, "{what}: {}", m.name());
        }
    };
    same(&sim, "at the start");
    let mut q = s.q0.clone();
    q[2] -= 0.2;
    sim.set_state(&q, &s.v0).unwrap();
    same(&sim, "another start");
    while sim.time() < 0.6 {
        sim.step().unwrap();
    }
    assert!(sim.active_contacts() > 0, "the lamp on the table");
    same(&sim, "on the table");
}

#[test]
fn jacobians_depend_on_the_state_alone() {
    // the same (q, v) after different pasts: the same A, B
    let a = quadruped::standing_quadruped(tight());
    let mut b = a.clone();
    for _ in 0..5 {
        b.step().unwrap();
    }
    let (q, v) = (a.q().clone(), a.v().clone());
    b.set_state(&q, &v).unwrap();
    let tau = DVector::zeros(a.model.nv);
    for m in JacobianMethod::ALL {
        let ja = a.transition_jacobians(&tau, m, 1e-6).unwrap();
        let jb = b.transition_jacobians(&tau, m, 1e-6).unwrap();
        assert_eq!(ja, jb, "{}", m.name());
    }
}

#[test]
fn bad_input_is_an_error() {
    let model = load_file("assets/robots/ur5.urdf", LoadOptions::default()).unwrap();
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let sim = Simulation::new(model, opts).unwrap();
    let e = sim
        .transition_jacobians(&DVector::zeros(3), JacobianMethod::Analytic, 1e-6)
        .unwrap_err()
        .to_string();
    assert!(e.contains("nv = 6") && !e.contains('\n'), "{e}");
    let e = sim
        .transition_jacobians(&DVector::zeros(6), JacobianMethod::Central, 0.0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("eps"), "{e}");
    let mut tau = DVector::zeros(6);
    tau[2] = f64::NAN;
    assert!(sim
        .transition_jacobians(&tau, JacobianMethod::Forward, 1e-6)
        .is_err());
    assert_eq!(
        JacobianMethod::from_name("central"),
        Some(JacobianMethod::Central)
    );
    assert_eq!(JacobianMethod::from_name("backward"), None);
}

#[test]
fn smooth_integrators_by_the_runge_kutta_chain_rule() {
    // ur5 without contact, with servos, by rk4 and dop853 (their own smooth
    // steps: no contact, no limit within reach, mild gains)
    let model = load_file("assets/robots/ur5.urdf", LoadOptions::default()).unwrap();
    let nv = model.nv;
    for integ in [Integrator::Rk4, Integrator::Dop853] {
        let opts = SimOptions {
            ground: None,
            integrator: Some(integ),
            ..Default::default()
        };
        let mut sim = Simulation::new(model.clone(), opts).unwrap();
        let mut s = 11;
        let q = DVector::from_fn(nv, |_, _| lcg(&mut s));
        let v = DVector::from_fn(nv, |_, _| lcg(&mut s));
        sim.set_state(&q, &v).unwrap();
        sim.set_gains_uniform(20.0, 0.5).unwrap();
        sim.set_targets(&DVector::zeros(nv), None).unwrap();
        let tau = DVector::from_fn(nv, |_, _| lcg(&mut s));
        check(
            &sim,
            &tau,
            1e-5,
            1e-3,
            &format!("ur5 servos {}", integ.name()),
        );
    }
    // a free body spinning in flight (the quaternion inside the ODE)
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    for integ in Integrator::ALL {
        let opts = SimOptions {
            ground: None,
            integrator: Some(integ),
            ..Default::default()
        };
        let mut sim = Simulation::new(model.clone(), opts).unwrap();
        let mut q = sim.q().clone();
        let (s, c) = (0.3f64.sin(), 0.3f64.cos());
        q[3] = s;
        q[6] = c;
        let v = DVector::from_vec(vec![0.4, -0.2, 1.0, 3.0, -2.0, 5.0]);
        sim.set_state(&q, &v).unwrap();
        check(
            &sim,
            &DVector::zeros(6),
            1e-5,
            1e-3,
            &format!("free box {}", integ.name()),
        );
    }
}

/// Richardson-extrapolated central differences of the step: (4 D(ε/2) − D(ε))/3.
fn richardson(sim: &Simulation, tau: &DVector<f64>, eps: f64) -> TransitionJacobians {
    let d1 = sim
        .transition_jacobians(tau, JacobianMethod::Central, eps)
        .unwrap();
    let d2 = sim
        .transition_jacobians(tau, JacobianMethod::Central, eps / 2.0)
        .unwrap();
    TransitionJacobians {
        a: (&d2.a * 4.0 - &d1.a) / 3.0,
        b: (&d2.b * 4.0 - &d1.b) / 3.0,
    }
}

fn maxabs(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax()
}

/// The sliding box of `box_sliding_on_the_ground` at friction 0.5, moving at
/// (vx, 0, 0) and spinning at wz, pressed into its slop.
fn sliding_box(vx: f64, wz: f64) -> Simulation {
    let model = load_str(box_urdf(), "box.urdf", FLOAT).unwrap();
    let opts = SimOptions {
        contact: ContactParams {
            friction: 0.5,
            ..Default::default()
        },
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.05;
    sim.set_state(&q, &DVector::zeros(6)).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let (q, mut v) = (sim.q().clone(), sim.v().clone());
    v[0] = vx;
    v[5] = wz;
    sim.set_state(&q, &v).unwrap();
    pressed(&mut sim);
    assert_eq!(sim.active_contacts(), 4, "four corners");
    sim
}

/// The analytic A, B against Richardson-extrapolated central differences of
/// the step (ε = `eps`, ε/2): the largest entry's error, asserted ≤ 1e-6.
fn against_richardson(sim: &Simulation, tau: &DVector<f64>, eps: f64, what: &str) -> (f64, f64) {
    let an = jac(sim, tau, JacobianMethod::Analytic);
    let r = richardson(sim, tau, eps);
    let (ea, eb) = (maxabs(&an.a, &r.a), maxabs(&an.b, &r.b));
    eprintln!(
        "{what}: analytic vs Richardson FD: A {ea:.2e} (relative {:.2e}), B {eb:.2e} (relative {:.2e}); |A| {:.2e}, |B| {:.2e}",
        rel(&an.a, &r.a),
        rel(&an.b, &r.b),
        r.a.amax(),
        r.b.amax()
    );
    assert!(ea < 1e-6 && eb < 1e-6, "{what}: A {ea:.3e}, B {eb:.3e}");
    (ea, eb)
}

#[test]
fn box_sliding_on_four_corners_against_richardson() {
    // every corner slipping the same way: the four corners are redundant (three
    // fix the normal motion) but the velocity the solve produces is the same
    // for every split of their normal impulses, and so is its derivative
    let sim = sliding_box(1.0, 0.0);
    let tau = DVector::zeros(6);
    against_richardson(&sim, &tau, 1e-5, "box sliding on four corners, mu 0.5");
    // by the analytic route (not its finite-difference fallback)
    let an = jac(&sim, &tau, JacobianMethod::Analytic);
    assert_ne!(an, jac(&sim, &tau, JacobianMethod::Central));
}

#[test]
fn box_sliding_and_spinning_on_four_corners_against_richardson() {
    // corners slipping different ways: the split of the normal impulses moves
    // the friction and so v⁺ (the four-legged table's indeterminacy); the
    // step's v⁺ is the solve's own pick among a family of solutions, which no
    // linearisation of its conditions gives (docs/theory.md §"Step Jacobians
    // with redundant rows"). The analytic method detects it and takes central
    // differences of the step
    let sim = sliding_box(1.0, 3.0);
    let tau = DVector::zeros(6);
    against_richardson(&sim, &tau, 1e-5, "box sliding and spinning, mu 0.5");
    let an = jac(&sim, &tau, JacobianMethod::Analytic);
    assert_eq!(an, jac(&sim, &tau, JacobianMethod::Central));
}

/// The four-bar's crank, coupler and rocker angles closing the loop at crank
/// angle θ (examples/common/four_bar_setup.rs).
fn four_bar_closed_q(theta: f64) -> [f64; 3] {
    let (l1, l2, l3, d) = (0.10, 0.30, 0.25, 0.30);
    let a = [l1 * theta.cos(), l1 * theta.sin()];
    let dv = [d - a[0], -a[1]];
    let dist = dv[0].hypot(dv[1]);
    let x = (l2 * l2 - l3 * l3 + dist * dist) / (2.0 * dist);
    let h = (l2 * l2 - x * x).sqrt();
    let u = [dv[0] / dist, dv[1] / dist];
    let n = [-u[1], u[0]];
    let b1 = [a[0] + x * u[0] + h * n[0], a[1] + x * u[1] + h * n[1]];
    let b2 = [a[0] + x * u[0] - h * n[0], a[1] + x * u[1] - h * n[1]];
    let b = if b1[1] < b2[1] { b1 } else { b2 };
    let phi2 = (b[1] - a[1]).atan2(b[0] - a[0]);
    let phi3 = b[1].atan2(b[0] - d);
    [theta, phi2 - theta, phi3]
}

#[test]
fn four_bar_driven_by_a_servo_against_richardson() {
    // assets/four_bar.urdf closed by assets/four_bar_constraints.json (a 3-D
    // point on a planar mechanism: three bilateral rows of rank two), the crank
    // driven by a servo toward a target 1 rad ahead; moving when differentiated,
    // so the position pass's drift target −½hγ acts in the step
    let model = load_file("assets/four_bar.urdf", LoadOptions::default()).unwrap();
    let text = std::fs::read_to_string("assets/four_bar_constraints.json").unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let c = urdyn::model::Constraints::from_value(&model, &json).unwrap();
    let opts = SimOptions {
        ground: None,
        ..tight()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let q = DVector::from_row_slice(&four_bar_closed_q(-1.0));
    sim.set_state(&q, &DVector::zeros(3)).unwrap();
    assert!(sim.set_constraints(c).unwrap().is_empty());
    let kp = DVector::from_vec(vec![20.0, 0.0, 0.0]);
    let kd = DVector::from_vec(vec![0.5, 0.0, 0.0]);
    sim.set_gains(&kp, &kd).unwrap();
    let mut target = q.clone();
    target[0] += 1.0;
    sim.set_targets(&target, None).unwrap();
    for _ in 0..150 {
        sim.step().unwrap();
    }
    assert!(sim.v()[0].abs() > 0.1, "the crank turns: {}", sim.v());
    assert!(sim.constraint_violation() < 1e-6);
    let tau = DVector::from_vec(vec![0.05, -0.02, 0.01]);
    against_richardson(&sim, &tau, 1e-5, "four-bar driven by a servo");
    let an = jac(&sim, &tau, JacobianMethod::Analytic);
    assert_ne!(an, jac(&sim, &tau, JacobianMethod::Central));
}
