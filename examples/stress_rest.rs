//! The long-run stress of issue 6: a floating robot resting on the ground for many
//! steps (default 1e6) in the engine's default contact integrator. Checks that every
//! state stays finite and that the energy (kinetic + potential) is never above the
//! start by more than 1e-6 relative; prints steps, wall time, the largest energy
//! excess and the final/deepest penetration.
//!
//! `cargo run --release --features tools --example stress_rest [URDF] [STEPS] [PACKAGE_PATH]`
//! (URDF defaults to `assets/lamp.urdf`, whose collision shapes are primitives).
//! The robot starts at its neutral configuration, at rest, its lowest collision
//! point placed on the ground (z = 0). Exit status 1 if a check fails.

use std::path::PathBuf;
use std::time::Instant;
use urdyn::sim::{SimOptions, Simulation};
use urdyn::LoadOptions;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args().skip(1);
    let urdf = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("assets/lamp.urdf"));
    let steps: u64 = match args.next() {
        Some(s) => s.parse::<f64>()? as u64,
        None => 1_000_000,
    };
    let package_paths: Vec<PathBuf> = args.map(PathBuf::from).collect();
    let model = urdyn::load_file(
        &urdf,
        LoadOptions {
            floating_base: true,
        },
    )?;
    let opts = SimOptions {
        package_paths,
        ..SimOptions::default()
    };
    let mut sim = Simulation::new(model, opts)?;
    // Put the lowest collision point on the ground.
    let low = sim.lowest_point();
    let mut q = sim.q().clone();
    let v = sim.v().clone();
    q[2] -= low;
    sim.set_state(&q, &v)?;
    let e0 = sim.energy();
    let mut max_excess = 0.0f64; // (E − E0) / |E0|, largest over all steps
    let mut max_pen = sim.penetration();
    let mut e_min = e0;
    let start = Instant::now();
    for k in 0..steps {
        sim.step()?;
        let e = sim.energy();
        if !e.is_finite() || !sim.q().iter().chain(sim.v().iter()).all(|x| x.is_finite()) {
            eprintln!("non-finite state at step {k}");
            std::process::exit(1);
        }
        max_excess = max_excess.max((e - e0) / e0.abs());
        e_min = e_min.min(e);
        max_pen = max_pen.max(sim.penetration());
    }
    let wall = start.elapsed().as_secs_f64();
    let e1 = sim.energy();
    println!(
        "{}: {} steps ({}, dt {} s, {} s simulated) in {:.1} s wall ({:.2} µs/step); \
         energy {:.9e} J -> {:.9e} J (min {:.9e}); max energy excess {:.2e} relative; \
         final penetration {:.3e} m, deepest {:.3e} m; final |v|∞ {:.2e}; final base z {:.6e} m",
        urdf.display(),
        steps,
        sim.integrator().name(),
        sim.dt(),
        sim.time(),
        wall,
        wall / steps.max(1) as f64 * 1e6,
        e0,
        e1,
        e_min,
        max_excess,
        sim.penetration(),
        max_pen,
        sim.v().amax(),
        sim.q()[2],
    );
    if max_excess > 1e-6 {
        eprintln!("energy rose above the start by {max_excess:e} relative (> 1e-6)");
        std::process::exit(1);
    }
    Ok(())
}
