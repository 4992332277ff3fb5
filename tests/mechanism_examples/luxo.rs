//! The balanced-arm desk lamp (assets/luxo.urdf, two parallelogram arms closed by
//! the `point` constraints of assets/luxo_constraints.json, start pose
//! assets/luxo_start.json), fixed and on a free base (as the simulation will drop
//! it): the constraint set builds (two loops, six rows of which two are
//! identically zero: planar loops closed by 3-D points), the start closes both
//! loops (violation < 1e-9 m), and at states with random v and τ the constrained
//! forward dynamics satisfies its defining equations: RNEA(q, v, q̈) − τ = J_cᵀλ
//! (H q̈ + C − τ = J_cᵀλ) and J_c q̈ + γ_c = 0 to 1e-9, with γ_c = J̇_c v checked
//! by central differences of J_c(q ⊕ εv) v (1e-6 relative). The random v are
//! projected onto J_c v = 0 (a moving closed lamp); at v = 1 (opening the loops
//! while swivelling) the rows are inconsistent and constraint_dynamics says so.

use nalgebra::{DMatrix, DVector};
use std::path::PathBuf;
use urdyn::dynamics_f64::{self as dynamics, ConstraintData};
use urdyn::model::configuration::integrate;
use urdyn::model::Constraints;
use urdyn::{Data, LoadOptions, Model};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(floating_base: bool) -> (Model, Constraints, DVector<f64>) {
    let model = urdyn::load_file(
        root().join("assets/luxo.urdf"),
        LoadOptions { floating_base },
    )
    .unwrap();
    let text = std::fs::read_to_string(root().join("assets/luxo_constraints.json")).unwrap();
    let c = Constraints::from_value(&model, &serde_json::from_str(&text).unwrap()).unwrap();
    let start: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("assets/luxo_start.json")).unwrap(),
    )
    .unwrap();
    let mut q = model.neutral();
    let mut set = 0;
    for (name, x) in model.q_names().iter().zip(q.iter_mut()) {
        if let Some(v) = start["q"][name.as_str()].as_f64() {
            *x = v;
            set += 1;
        }
    }
    assert_eq!(set, 7, "every joint of the lamp in luxo_start.json");
    (model, c, q)
}

/// A small deterministic generator in [−1, 1].
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn check(floating_base: bool) {
    let (model, c, q) = load(floating_base);
    assert_eq!(c.items.len(), 2);
    assert_eq!(c.rows(), 6);
    let mut data = Data::new(&model);
    let mut viol = [0.0; 2];
    dynamics::constraint_violation(&model, &mut data, &c, &q, &mut viol).unwrap();
    assert!(
        viol.iter().all(|v| *v < 1e-9),
        "start violates the loops: {viol:?}"
    );
    let mut cd = ConstraintData::new(&model, &c);
    let mut seed = 7u64;
    let mut worst = [0.0f64; 3];
    for _ in 0..5 {
        // a velocity of the closed lamp (J_c v = 0): off it, a swivelling planar loop's
        // identically zero row meets a non-zero γ, and the rows are inconsistent (an
        // error, as mechanisms.md says)
        let v0 = DVector::from_fn(model.nv, |_, _| 2.0 * lcg(&mut seed));
        let mut j0 = DMatrix::zeros(6, model.nv);
        dynamics::constraint_jacobian(&model, &mut data, &c, &q, &mut j0).unwrap();
        let jp = j0.clone().svd(true, true).pseudo_inverse(1e-10).unwrap();
        let v = &v0 - jp * (&j0 * &v0);
        let tau = DVector::from_fn(model.nv, |_, _| lcg(&mut seed));
        let qdd = dynamics::constraint_dynamics(&model, &mut data, &mut cd, &c, &q, &v, &tau, None)
            .unwrap()
            .clone();
        let (jc, gamma, lam) = (cd.jc.clone(), cd.gamma.clone(), cd.lambda.clone());
        let f = dynamics::rnea(&model, &mut data, &q, &v, &qdd, None)
            .unwrap()
            .clone();
        let r1 = (&f - &tau - jc.transpose() * &lam).amax() / f.amax().max(1.0);
        let r2 = (&jc * &qdd + &gamma).amax() / gamma.amax().max(1.0);
        assert!(r1 < 1e-9, "H qdd + C - tau - Jc^T lambda = {r1:e}");
        assert!(r2 < 1e-9, "Jc qdd + gamma = {r2:e}");
        // gamma = d/dt (J_c(q(t)) v) at fixed v, central differences along v
        let eps = 1e-6;
        let mut jp = DMatrix::zeros(6, model.nv);
        let mut jm = DMatrix::zeros(6, model.nv);
        let qp = integrate(&model, &q, &(&v * eps)).unwrap();
        let qm = integrate(&model, &q, &(&v * -eps)).unwrap();
        dynamics::constraint_jacobian(&model, &mut data, &c, &qp, &mut jp).unwrap();
        dynamics::constraint_jacobian(&model, &mut data, &c, &qm, &mut jm).unwrap();
        let fd = (jp - jm) * &v / (2.0 * eps);
        let r3 = (&fd - &gamma).amax() / gamma.amax().max(1.0);
        assert!(r3 < 1e-6, "gamma vs central differences: {r3:e}");
        worst = [worst[0].max(r1), worst[1].max(r2), worst[2].max(r3)];
    }
    eprintln!("luxo (floating base {floating_base}): violation {viol:?}, identity {:.1e}, rows {:.1e}, gamma vs FD {:.1e}", worst[0], worst[1], worst[2]);
}

#[test]
fn luxo_loops_close_and_constrained_dynamics_holds_fixed() {
    check(false);
    // off the velocity manifold the planar loops' zero rows are inconsistent: named
    let (model, c, q) = load(false);
    let mut data = Data::new(&model);
    let mut cd = ConstraintData::new(&model, &c);
    let v = DVector::from_element(model.nv, 1.0);
    let tau = DVector::zeros(model.nv);
    let e = dynamics::constraint_dynamics(&model, &mut data, &mut cd, &c, &q, &v, &tau, None);
    assert!(
        e.is_err(),
        "a swivelling, opening parallelogram must be inconsistent"
    );
}

#[test]
fn luxo_loops_close_and_constrained_dynamics_holds_floating() {
    check(true);
}

/// The Luxo with its parallelograms dropped from 0.3 m onto the table
/// (assets/luxo_on_table.json, examples/luxo_on_table.rs): it lands, falls
/// asleep under the default sleep rule within 4 s, and at rest both loops are
/// closed below 1e-6 m. (Measured with these options, which leave out the scene's
/// torsional and rolling friction: asleep at 2.12 s, violation 0 at rest.
/// The examples and tests/loops_sim.rs run the scenes with them: the table drop
/// sleeps at 1.94 s and the ground drop at 2.21 s, the loops below 1e-15 m after
/// landing and the energy never more than 1e-10 J above its lowest value so far,
/// docs/mechanisms_examples.md.)
#[test]
fn luxo_dropped_on_the_table_comes_to_rest_with_its_loops_closed() {
    use urdyn::sim::{SimOptions, Simulation};
    let scene =
        urdyn::scene::Scene::from_file(root().join("assets/luxo_on_table.json"), &[]).unwrap();
    let contact = urdyn::contact::ContactParams {
        friction: scene.ground.unwrap().friction,
        ..Default::default()
    };
    let opts = SimOptions {
        ground: scene.ground.map(|g| g.height),
        contact,
        ..Default::default()
    };
    let mut sim = Simulation::new(scene.model.clone(), opts).unwrap();
    sim.set_state(&scene.q0, &scene.v0).unwrap();
    assert!(sim
        .set_constraints(scene.constraints.clone())
        .unwrap()
        .is_empty());
    let e0 = sim.energy();
    let mut asleep_at = None;
    while sim.time() < 4.0 - 1e-9 {
        sim.step().unwrap();
        if asleep_at.is_none() && sim.awake() == 0 {
            asleep_at = Some(sim.time());
        }
    }
    let viol = sim.constraint_violation();
    let e = sim.energy();
    eprintln!("luxo on the table: asleep at {asleep_at:?} s, violation at rest {viol:.2e}, energy {e0:.4} J -> {e:.4} J");
    assert!(asleep_at.is_some_and(|t| t < 4.0), "{asleep_at:?}");
    assert!(viol < 1e-6, "{viol}");
    assert!(e < e0, "{e} >= {e0}");
}
