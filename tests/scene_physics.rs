//! Scenes in contact (scene.md, issue 22 "Must show"): a stack of three boxes
//! holds for 3 s, the lamp dropped onto a table rests on its top, and the lamp
//! dropped onto a floating table (a robot onto another) rests on it — all
//! through the scene file, its forest and the two-body contact rows.

use nalgebra::{DVector, Vector3};
use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

fn scene(json: &str) -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    Scene::from_json(json, "test.json", dir, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// A simulation of the scene at its start, with its ground and friction.
fn simulation(s: &Scene) -> Simulation {
    let mut sim = Simulation::new(s.model.clone(), SimOptions::of_scene(s)).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    sim
}

fn base(sim: &Simulation, s: &Scene, model: usize) -> (Vector3<f64>, [f64; 4]) {
    let f = &s.model.free_joints[s.model.trees[model].free.unwrap()];
    let q = sim.q();
    (
        Vector3::new(q[f.iq], q[f.iq + 1], q[f.iq + 2]),
        [q[f.iq + 3], q[f.iq + 4], q[f.iq + 5], q[f.iq + 6]],
    )
}

#[test]
fn a_stack_of_three_boxes_stays_within_a_millimetre_for_3_s() {
    let s = scene(
        r#"{"ground": {"height": 0.0},
        "models": [
          {"name": "b0", "urdf": "tests/urdf/crate_box.urdf", "base": "floating", "position": [0, 0, 0.1]},
          {"name": "b1", "urdf": "tests/urdf/crate_box.urdf", "base": "floating", "position": [0, 0, 0.3]},
          {"name": "b2", "urdf": "tests/urdf/crate_box.urdf", "base": "floating", "position": [0, 0, 0.5]}]}"#,
    );
    let mut sim = simulation(&s);
    let start: Vec<Vector3<f64>> = (0..3).map(|k| base(&sim, &s, k).0).collect();
    let mut worst = 0.0f64;
    while sim.time() < 3.0 {
        sim.step().unwrap();
        for (k, p0) in start.iter().enumerate() {
            worst = worst.max((base(&sim, &s, k).0 - p0).amax());
        }
    }
    assert!(worst < 1e-3, "a box moved {worst} m");
}

/// The lamp's base: height of its origin, and how far its z axis leans (rad).
fn lamp_pose(sim: &Simulation, s: &Scene, model: usize) -> (f64, f64) {
    let (p, [x, y, z, w]) = base(sim, s, model);
    let r = urdyn::spatial::quat_to_matrix(x, y, z, w);
    (p.z, r[(2, 2)].clamp(-1.0, 1.0).acos())
}

fn at_rest(sim: &Simulation, model: &urdyn::Model, tree: usize) -> f64 {
    let t = &model.trees[tree];
    DVector::from_column_slice(&sim.v().as_slice()[t.v.clone()]).amax()
}

#[test]
fn the_lamp_dropped_onto_the_table_rests_on_its_top() {
    let s = Scene::from_file(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/lamp_on_table.json"),
        &[],
    )
    .unwrap();
    let mut sim = simulation(&s);
    let mut deepest = 0.0f64;
    while sim.time() < 3.0 {
        sim.step().unwrap();
        if sim.time() > 0.5 {
            deepest = deepest.max(sim.penetration());
        }
    }
    let (z, lean) = lamp_pose(&sim, &s, 1);
    // the table's top face is 0.75 m up; the lamp's base frame is its bottom face
    assert!((z - 0.75).abs() < 1e-3, "lamp base at {z} m");
    assert!(lean < 0.02, "leans {lean} rad");
    assert!(deepest < 1e-3, "penetration {deepest} m");
    assert!(at_rest(&sim, &s.model, 1) < 1e-2, "still moving");
}

#[test]
fn a_robot_dropped_on_another_rests_on_it() {
    // the lamp dropped onto a floating table standing on the ground
    let s = scene(
        r#"{"ground": {"height": 0.0},
        "models": [
          {"name": "table", "urdf": "assets/table.urdf", "base": "floating", "position": [0, 0, 0.001]},
          {"name": "lamp", "urdf": "assets/lamp.urdf", "base": "floating", "position": [0.1, 0, 0.9]}]}"#,
    );
    let mut sim = simulation(&s);
    while sim.time() < 3.0 {
        sim.step().unwrap();
    }
    let (table, _) = base(&sim, &s, 0);
    let (z, lean) = lamp_pose(&sim, &s, 1);
    assert!(
        table.z.abs() < 2e-3,
        "the table stands on the ground: {}",
        table.z
    );
    assert!(
        (z - (table.z + 0.75)).abs() < 2e-3,
        "lamp base {z}, table top {}",
        table.z + 0.75
    );
    assert!(lean < 0.02, "leans {lean} rad");
    assert!(at_rest(&sim, &s.model, 1) < 1e-2 && at_rest(&sim, &s.model, 0) < 1e-2);
}
