//! Gymnasium's ant at rest on its four feet stays at rest (issue 29: "each
//! lands, stays finite and ends at rest"). Not yet in every landing: at rest,
//! a twist of the whole ant (torso yaw, the four hips turning together, the
//! feet planted) grows when the landing leaves two diagonal feet pushed
//! toward the centre by friction (a self-stress the warm start keeps; a
//! compressed chain at its dead point). Round 5, with the subspace step's
//! rounding-level pivots: ×1.78 every 2 s (5.4e-3 m/s at 30 s); round 6, that
//! fixed: 2.7e-5 at 30 s, 1.7e-3 at 80 s (×1.2 a 2 s), then it settles. The
//! same ant with the speculative margin (`urdyn simulate`) lands with those
//! diagonals in tension and stays at 1e-6 for 100 s. The rate shrinks with
//! the step (none at 2 ms): the sticking rows hold the feet to first order
//! only; see benches/mjcf_results.md §"ant's twist at rest".

use std::path::Path;
use urdyn::mjcf;
use urdyn::sim::{Integrator, SimOptions, Simulation};

#[test]
#[ignore = "fails today: ant's twist mode grows at rest (benches/mjcf_results.md)"]
fn gymnasium_ant_at_rest_stays_at_rest() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/gymnasium/ant.xml");
    let (model, world) = mjcf::load_file_with_world(path).expect("loads");
    // `urdyn simulate ant.xml --no-sleep --integrator euler`, without the
    // speculative margin (see above)
    let mut opts = SimOptions {
        integrator: Integrator::from_name("euler"),
        sleep: false,
        ..SimOptions::of_mjcf_world(&world)
    };
    opts.contact.travel_factor = 0.0;
    let mut sim = Simulation::new(model, opts).expect("sim");
    // landed and still by 2 s (|v| ~ 1e-6: the solve's tolerance)
    while sim.time() < 2.0 - 1e-9 {
        sim.step().expect("step");
    }
    assert!(sim.v().amax() < 1e-5, "|v| = {} at 2 s", sim.v().amax());
    // nothing drives it after: with the hips' damping every speed decays,
    // so |v| stays at the tolerance's level (today: 1.7e-3 by 80 s)
    let mut worst: f64 = 0.0;
    while sim.time() < 90.0 - 1e-9 {
        sim.step().expect("step");
        worst = worst.max(sim.v().amax());
    }
    assert!(
        worst < 1e-4,
        "|v| reached {worst} at rest between 2 s and 90 s"
    );
    assert!(sim.active_contacts() >= 4);
}
