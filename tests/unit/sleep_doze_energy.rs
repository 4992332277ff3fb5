//! src/sim/sleep.rs with src/sim/state.rs (issue #30): while some boxes of a
//! pile sleep and others move, the energy the step's guard computes (the
//! sleeping trees' bodies left out of the bias pass it runs, every body's
//! pose from the step's forward kinematics) is the energy of the state
//! computed afresh, at every step.

use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

#[test]
fn a_pile_with_sleeping_and_moving_boxes_has_the_energy_of_its_state_at_every_step() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = Scene::from_file(&root.join("benches/scenes/pile_boxes_16.json"), &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(s.model.clone(), SimOptions::of_scene(&s)).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    let boxes = sim.model.free_joints.len();
    let mut checked = 0;
    while sim.time() < 2.0 {
        sim.step().unwrap();
        let awake = sim.awake();
        if awake == 0 || awake == boxes {
            continue;
        }
        let (ke, pe) = urdyn::dynamics::energies(&sim.model, sim.q(), sim.v()).unwrap();
        let e = sim.energy();
        assert!(
            (e - (ke + pe)).abs() <= 1e-9 * (1.0 + pe.abs()),
            "t = {} s, {awake} awake: energy {e} J, of the state {} J",
            sim.time(),
            ke + pe
        );
        checked += 1;
    }
    // (boxes sleep from ~0.7 s, the last after ~1.2 s)
    assert!(checked > 100, "{checked} steps with boxes asleep and awake");
}
