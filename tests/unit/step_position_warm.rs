//! src/sim/solver/position.rs: the position pass, warm-started by contact slot
//! (μ of the last pass times 1 − β). A box held 1.1 mm into the ground at rest
//! is pushed out along the closed form of the split impulse: each step removes
//! β of the depth beyond the slop, d_k − slop = (1 − β)^k (d₀ − slop), with
//! no velocity left in v, from the first (cold) pass through the warm ones.

use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

#[test]
fn a_box_held_into_the_ground_is_pushed_out_by_beta_of_its_excess_depth_each_step() {
    let (d0, half) = (1.1e-3, 0.1);
    let json = format!(
        r#"{{"ground": {{"height": 0.0}}, "models": [{{"name": "m", "urdf": "tests/urdf/crate_box.urdf", "base": "floating", "position": [0, 0, {}]}}]}}"#,
        half - d0
    );
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = Scene::from_json(&json, "push.json", root, &[]).unwrap_or_else(|e| panic!("{e}"));
    let opts = SimOptions::of_scene(&s);
    let (beta, slop, cap) = (
        opts.contact.baumgarte,
        opts.contact.slop,
        opts.contact.max_push_speed,
    );
    // the closed form holds below the push cap
    assert!(beta * (d0 - slop) / opts.dt < cap);
    let mut sim = Simulation::new(s.model.clone(), opts).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    for k in 1..=30 {
        sim.step().unwrap();
        let depth = half - sim.q()[2];
        let want = slop + (1.0 - beta).powi(k) * (d0 - slop);
        assert!(
            (depth - want).abs() < 1e-9,
            "step {k}: depth {depth:e} m, closed form {want:e} m"
        );
        let v = sim.v().amax();
        assert!(v < 1e-9, "step {k}: |v| {v:e}");
    }
}
