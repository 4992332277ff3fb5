//! The step loop allocates nothing (counting global allocator), for each
//! integrator, with contact and joint friction (the lamp) and without (a chain).

use urdyn::sim::{Integrator, SimOptions, Simulation};

use crate::common::counting_alloc::{allocations, measure_this_thread};

#[test]
fn step_loop_does_not_allocate() {
    measure_this_thread();
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let lamp = urdyn::load_file(
        root.join("assets/lamp.urdf"),
        urdyn::LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let chain = urdyn::load_file(
        root.join("tests/urdf/chain20_hanging.urdf"),
        Default::default(),
    )
    .unwrap();
    for (model, z) in [(lamp, 0.2), (chain, 0.0)] {
        for integ in Integrator::ALL {
            let mut sim = Simulation::new(
                model.clone(),
                SimOptions {
                    integrator: Some(integ),
                    ..Default::default()
                },
            )
            .unwrap();
            let mut q = sim.q().clone();
            if model.floating_base {
                q[2] = z;
            } else {
                q[0] = 0.5;
            }
            let v = sim.v().clone();
            sim.set_state(&q, &v).unwrap();
            for _ in 0..5 {
                sim.step().unwrap();
            }
            let before = allocations();
            for _ in 0..400 {
                sim.step().unwrap();
                std::hint::black_box(sim.energy());
                std::hint::black_box(sim.penetration());
            }
            let n = allocations() - before;
            assert_eq!(
                n, 0,
                "{} / {:?}: {n} allocations in 400 steps",
                model.name, integ
            );
        }
    }
}
