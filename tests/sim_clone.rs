//! A cloned `Simulation` is the same simulation: stepped side by side with the
//! original it stays bit for bit equal (Python's `reset()` and every rollout
//! start from a clone). Found broken once: the loop block read its size limit
//! from a vector's capacity, which a clone does not keep, so a clone solved its
//! loop rows one by one and drifted from the original by 1e-14 in one step.

use urdyn::sim::{SimOptions, Simulation};

#[test]
fn a_clone_of_a_simulation_with_loops_steps_bit_for_bit_as_the_original() {
    let file = format!(
        "{}/tests/fixtures/loops/scene.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = urdyn::scene::Scene::from_file(file, &[]).unwrap();
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(scene.model.clone(), opts).unwrap();
    sim.set_state(&scene.q0, &scene.v0).unwrap();
    assert!(sim
        .set_constraints(scene.constraints.clone())
        .unwrap()
        .is_empty());
    let mut copy = sim.clone();
    for k in 0..300 {
        sim.step().unwrap();
        copy.step().unwrap();
        assert_eq!(sim.q().as_slice(), copy.q().as_slice(), "q at step {k}");
        assert_eq!(sim.v().as_slice(), copy.v().as_slice(), "v at step {k}");
    }
    // and it moved: the four-bar falls under gravity from rest
    assert!((sim.q() - &scene.q0).norm() > 1e-2);
}
