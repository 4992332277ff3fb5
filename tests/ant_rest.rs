//! Gymnasium's ant at rest on its four feet stays at rest (issue 29: "each
//! lands, stays finite and ends at rest"). Until round 7 a twist of the whole
//! ant (torso yaw, the four hips turning together, the feet planted) grew at
//! rest (×1.9 every 5 s, 1.5e-2 m/s by 90 s): the landing left two diagonal
//! feet pushed toward the centre by friction, a self-stress (Jᵀλ = 0) the
//! warm start kept, on a chain at its dead point. The solve now sheds the
//! self-stress of jointed islands (the least-norm impulses, docs/theory.md
//! §"Self-stress of a sticking stance"), so the stance is the symmetric one:
//! each foot carries a quarter of the weight.

use std::path::Path;
use urdyn::mjcf;
use urdyn::sim::{Integrator, SimOptions, Simulation};

#[test]
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
    let weight = model.total_mass() * model.gravity.norm();
    let mut sim = Simulation::new(model, opts).expect("sim");
    // landed and still by 2 s (|v| ~ 1e-6: the solve's tolerance)
    while sim.time() < 2.0 - 1e-9 {
        sim.step().expect("step");
    }
    assert!(sim.v().amax() < 1e-5, "|v| = {} at 2 s", sim.v().amax());
    // nothing drives it after: with the hips' damping every speed decays,
    // so |v| stays at the tolerance's level (1.5e-2 by 90 s before round 7)
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
    // the ant is symmetric under quarter turns about z and at rest: its four
    // feet share the weight equally (the least-norm stance; a self-stress
    // loaded one diagonal with 3.90 N and the other with 0.57 N)
    let fz: Vec<f64> = sim.contact_forces().iter().map(|c| c.force.z).collect();
    assert_eq!(fz.len(), 4, "four feet: {fz:?}");
    for f in &fz {
        assert!(
            (f - weight / 4.0).abs() < 1e-3 * weight,
            "foot loads {fz:?}, weight/4 = {}",
            weight / 4.0
        );
    }
}
