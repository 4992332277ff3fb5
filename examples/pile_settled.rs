//! Issue 30's "a settled 256-box pile ≥ 20× faster than while it falls",
//! measured: the pile (benches/scenes/pile_boxes_N.json, sleep on) is run to
//! `T` s untimed, then 2000 steps of it are timed from that saved state (a
//! clone of the simulation, the best of 5), against 500 steps from the drop
//! (the best of 3). Prints steps/s of each, the awake count at `T` and the
//! ratio. Wall time: run it on a quiet machine; the best of several takes the
//! least disturbed run.
//!
//! `cargo run --release --features tools --example pile_settled [N] [T]`
//! (N = 256, T = 4 s).

use std::path::PathBuf;
use std::time::Instant;
use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

fn best(sim: &Simulation, steps: usize, reps: usize) -> Result<f64, Box<dyn std::error::Error>> {
    let mut t_best = f64::INFINITY;
    for _ in 0..reps {
        let mut s = sim.clone();
        let t0 = Instant::now();
        for _ in 0..steps {
            s.step()?;
        }
        t_best = t_best.min(t0.elapsed().as_secs_f64());
    }
    Ok(steps as f64 / t_best)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(256), |s| s.parse())?;
    let t_settle: f64 = args.next().map_or(Ok(4.0), |s| s.parse())?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let path = root.join(format!("benches/scenes/pile_boxes_{n}.json"));
    let scene = Scene::from_file(&path, &[])?;
    let opts = SimOptions::of_scene(&scene);
    let mut sim = Simulation::new(scene.model.clone(), opts)?;
    sim.set_state(&scene.q0, &scene.v0)?;
    let falling = best(&sim, 500, 3)?;
    while sim.time() < t_settle {
        sim.step()?;
    }
    let awake = sim.awake();
    let settled = best(&sim, 2000, 5)?;
    println!(
        "pile_boxes_{n}: falling (first 500 steps) {falling:.0} steps/s; settled (2000 steps from {t_settle} s, {awake} awake) {settled:.0} steps/s; ratio {:.1}",
        settled / falling
    );
    Ok(())
}
