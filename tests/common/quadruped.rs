//! The quadruped of tests/urdf/quadruped.urdf standing on its four feet.

use nalgebra::DVector;
use urdyn::sim::{SimOptions, Simulation};
use urdyn::{load_file, LoadOptions};

/// The quadruped of tests/urdf standing on its four feet under servos, 3 s
/// after it was set down, with the simulation options `opts`.
pub fn standing_quadruped(opts: SimOptions) -> Simulation {
    let model = load_file(
        "tests/urdf/quadruped.urdf",
        LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let names: Vec<String> = model.dofs.iter().map(|d| d.name.clone()).collect();
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut q = sim.q().clone();
    for (k, n) in names.iter().enumerate() {
        q[7 + k] = if n.ends_with("hip") { 0.6 } else { -1.2 };
    }
    q[2] = 0.4 * 0.6f64.cos() + 0.02 + 1e-3;
    sim.set_gains_uniform(60.0, 3.0).unwrap();
    sim.set_targets(&q, None).unwrap();
    let v = DVector::zeros(sim.model.nv);
    sim.set_state(&q, &v).unwrap();
    for _ in 0..3000 {
        sim.step().unwrap();
    }
    sim
}
