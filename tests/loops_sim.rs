//! Simulation with loop constraints (mechanisms.md §"Simulation"): bilateral
//! rows of the impulse solve, drift removed by the position pass. Truth from
//! outside: the closed loop's geometry (violation), the energy of a passive
//! mechanism that must not rise, a gear's ratio, a hanging pendulum's m·g.

use nalgebra::{DVector, Vector3};
use serde_json::json;
use urdyn::model::Constraints;
use urdyn::sim::{SimOptions, Simulation};
use urdyn::{load_file, load_str, LoadOptions};

const FIXED: LoadOptions = LoadOptions {
    floating_base: false,
};

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/loops/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The four-bar closed at q = (60°, θ₂, θ₃) (solved in scene.json's comment-free
/// numbers: crank 0.1, coupler 0.3, rocker 0.2, ground 0.3).
const Q0: [f64; 3] = [1.0471975511965976, -0.66694634450362, 1.4274487578896633];

fn four_bar(crank_offset: f64) -> (Simulation, Vec<String>) {
    let model = load_file(fixture("four_bar.urdf"), FIXED).unwrap();
    let c = Constraints::from_json(
        &model,
        &[json!({"name": "loop", "kind": "point", "link1": "coupler", "point1": [0.3, 0.0, 0.0],
                  "link2": "rocker", "point2": [0.2, 0.0, 0.0]})],
    )
    .unwrap();
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let q = DVector::from_row_slice(&[Q0[0] + crank_offset, Q0[1], Q0[2]]);
    sim.set_state(&q, &DVector::zeros(3)).unwrap();
    let warnings = sim.set_constraints(c).unwrap();
    (sim, warnings)
}

#[test]
fn passive_four_bar_stays_closed_and_never_gains_energy() {
    let (mut sim, warnings) = four_bar(0.0);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(sim.constraint_violation() < 1e-12);
    let e0 = sim.energy();
    let scale = 1e-6 * (e0.abs() + 3.0 * 9.81 * 1.0);
    let (mut worst_v, mut worst_e) = (0.0f64, f64::NEG_INFINITY);
    let mut crank_turns = 0.0f64;
    while sim.time() < 10.0 - 1e-9 {
        sim.step().unwrap();
        let v = sim.constraint_violation();
        if sim.time() > 0.1 {
            worst_v = worst_v.max(v);
        }
        worst_e = worst_e.max(sim.energy() - e0);
        crank_turns = crank_turns.max((sim.q()[0] - Q0[0]).abs());
    }
    eprintln!("four-bar 10 s: violation {worst_v:.3e}, energy rise {worst_e:.3e} (bound {scale:.3e}), crank swing {crank_turns:.3}");
    assert!(crank_turns > 0.5, "the mechanism moved: {crank_turns}");
    assert!(worst_v < 1e-6, "violation {worst_v}");
    assert!(worst_e <= scale, "energy rose by {worst_e} > {scale}");
}
