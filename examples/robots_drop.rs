//! Five real robots from example-robot-data simulated for 3 s with ground
//! contact at the default settings (semi-implicit Euler, dt = 1 ms, μ = 1):
//! solo12, anymal and talos_reduced with a floating base, dropped with their
//! lowest collision point 0.3 m above the ground; ur5 and panda on a fixed base,
//! released at rest from their neutral pose. Prints steps per second, real-time
//! factor, final penetration, deepest penetration and the largest final speed.
//!
//! `cargo run --release --features tools --example robots_drop -- PACKAGE_ROOT` where PACKAGE_ROOT
//! holds `example-robot-data/robots/...` (the meshes), e.g.
//! `.../site-packages/cmeel.prefix/share`.

use std::path::PathBuf;
use std::time::Instant;
use urdyn::sim::{SimOptions, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let pkg: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    println!("| robot | base | nv | shapes | steps/s | real-time factor | final penetration (m) | deepest (m) | max final speed | contacts | initial penetration (m) |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (name, floating) in [
        ("solo12", true),
        ("anymal", true),
        ("talos_reduced", true),
        ("ur5", false),
        ("panda", false),
    ] {
        let model = urdyn::load_file(
            root.join(format!("assets/robots/{name}.urdf")),
            urdyn::LoadOptions {
                floating_base: floating,
            },
        )?;
        let opts = SimOptions {
            package_paths: pkg.clone(),
            ..Default::default()
        };
        let mut sim = Simulation::new(model.clone(), opts)?;
        let nshapes = model.collisions.iter().filter(|c| c.body != 0).count();
        if floating {
            let low = sim.lowest_point();
            let mut q = sim.q().clone();
            q[2] += 0.3 - low;
            let v = sim.v().clone();
            sim.set_state(&q, &v)?;
        }
        // a link that starts inside the ground shows here, before any step
        let initial = sim.penetration();
        let mut deepest: f64 = 0.0;
        let start = Instant::now();
        while sim.time() < 3.0 {
            sim.step_until(3.0)?;
            deepest = deepest.max(sim.penetration());
        }
        let wall = start.elapsed().as_secs_f64();
        let vmax = sim.v().amax();
        println!(
            "| {name} | {} | {} | {nshapes} | {:.0} | {:.1} | {:.2e} | {:.2e} | {:.2e} | {} | {:.2e} |",
            if floating { "floating" } else { "fixed" },
            model.nv,
            sim.steps as f64 / wall,
            3.0 / wall,
            sim.penetration(),
            deepest,
            vmax,
            sim.active_contacts(),
            initial
        );
    }
    Ok(())
}
