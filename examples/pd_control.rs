//! A PD controller with gravity compensation holding the UR5 arm
//! (`assets/robots/ur5.urdf`) at a pose under gravity, written against the
//! step-by-step library API: read the state, set the joint torques, step, read
//! the energy and the contact forces.
//!
//! τ = Kp (q* − q) − Kd v + g(q) (diagonal gains), with g(q) = C(q, 0) from RNEA
//! (docs/theory.md §"Bias forces"); the
//! torques are held over each 1 ms step (zero-order hold, RK4) and clamped by the
//! engine to the URDF effort limits. The arm starts at rest 0.3 rad away from q*
//! on every joint. Run: `cargo run --release --example pd_control`.

use nalgebra::DVector;
use urdyn::sim::{Integrator, SimOptions, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let model = urdyn::load_file(root.join("assets/robots/ur5.urdf"), Default::default())?;
    let target = DVector::from_vec(vec![0.0, -1.2, 1.4, -0.4, 1.2, 0.0]);
    // gains per joint: the wrist's small inertia (~0.01 kg m²) needs a small Kd
    // for the sampled controller to stay stable (Kd·Δt/I well below 2)
    let kp = DVector::from_vec(vec![400.0, 400.0, 400.0, 50.0, 50.0, 50.0]);
    let kd = DVector::from_vec(vec![40.0, 40.0, 40.0, 2.0, 2.0, 2.0]);
    let opts = SimOptions {
        integrator: Some(Integrator::Rk4),
        dt: 1e-3,
        // the arm's links never reach the floor in this motion: no ground, so the
        // collision meshes are not needed
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model.clone(), opts)?;
    let start = target.map(|x| x + 0.3);
    sim.set_state(&start, &DVector::zeros(model.nv))?;
    let mut data = urdyn::Data::new(&model);
    let zero = DVector::zeros(model.nv);
    println!("   t (s)   max |q - q*| (rad)   max |v| (rad/s)   energy (J)");
    while sim.time() < 3.0 - 1e-12 {
        let (q, v) = (sim.q().clone(), sim.v().clone());
        let g = urdyn::dynamics_f64::bias(&model, &mut data, &q, &zero, None)?.clone();
        let tau = (&target - &q).component_mul(&kp) - v.component_mul(&kd) + g;
        sim.torques_mut().copy_from(&tau);
        sim.step_until(3.0)?;
        let k = (sim.time() * 1000.0).round() as u64;
        if k % 500 == 0 {
            let err = (sim.q() - &target).amax();
            let e = sim.energy();
            println!(
                "{:8.3}   {:18.3e}   {:15.3e}   {:10.4}",
                sim.time(),
                err,
                sim.v().amax(),
                e
            );
        }
    }
    let err = (sim.q() - &target).amax();
    println!(
        "held: final error {err:.2e} rad, contact forces on {} links",
        sim.contact_forces().len()
    );
    assert!(err < 1e-3, "the PD controller must hold the pose");
    Ok(())
}
