//! Diagnostic: Gymnasium's ant at rest on its plane (`urdyn simulate ant.xml
//! --no-sleep --integrator euler`); prints every `EVERY`-th step from T0 to T1:
//! time, largest |v|, sweeps of the step, contacts, penetration, root yaw rate.
//! `cargo run --release --features tools --example ant_probe [T0 T1]`
//! (env: DT, ITERS, TOL, RELAX, SLOP, BAUM, PUSH, MARGIN, MU, ARM, TRAVEL (the
//! speculative margin's factor; `urdyn simulate` uses 1.5), EVERY; FORCES=1
//! also prints each contact's force and |f_t|/f_n). `SCENE=FILE.json` runs a
//! scene instead (sleep off, `WINDOW` s windows, default 0.25): per window
//! the solve's work a step (rows × sweeps, `Simulation::solve_work`), the
//! most sweeps a step, contacts and largest |v|, and the totals at the end.
use urdyn::mjcf;
use urdyn::scene::Scene;
use urdyn::sim::{Integrator, SimOptions, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let t0: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    let t1: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(40.0);
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    if let Ok(scene) = std::env::var("SCENE") {
        return scene_probe(&scene, t0, t1, env("WINDOW").unwrap_or(0.25));
    }
    // MODEL: another fixture under tests/fixtures/mjcf (e.g. dm_control/dog)
    let name = std::env::var("MODEL").unwrap_or_else(|_| "gymnasium/ant".into());
    let path = format!(
        "{}/tests/fixtures/mjcf/{name}.xml",
        env!("CARGO_MANIFEST_DIR")
    );
    let (model, world) = mjcf::load_file_with_world(&path)?;
    // `urdyn simulate MODEL.xml --no-sleep --integrator euler` (TRAVEL: 0
    // unless given)
    let world_opts = SimOptions::of_mjcf_world(&world);
    let mut opts = SimOptions {
        dt: env("DT").unwrap_or(world_opts.dt),
        integrator: Integrator::from_name("euler"),
        sleep: false,
        ..world_opts
    };
    opts.contact.travel_factor = 0.0;
    if let Some(x) = env("ITERS") {
        opts.solver_iterations = x as usize;
    }
    if let Some(x) = env("TOL") {
        opts.solver_tol = x;
    }
    if let Some(x) = env("RELAX") {
        opts.solver_relaxation = x;
    }
    if let Some(x) = env("SLOP") {
        opts.contact.slop = x;
    }
    if let Some(x) = env("BAUM") {
        opts.contact.baumgarte = x;
    }
    if let Some(x) = env("PUSH") {
        opts.limit_push_speed = x;
    }
    if let Some(x) = env("MARGIN") {
        opts.contact.margin = x;
    }
    if let Some(x) = env("MU") {
        opts.contact.friction = x;
    }
    if let Some(x) = env("TRAVEL") {
        opts.contact.travel_factor = x;
    }
    if let Some(x) = env("ARM") {
        opts.armature = x;
    }
    let every = env("EVERY").unwrap_or(100.0) as u64;
    let mut sim = Simulation::new(model, opts)?;
    let mut k = 0u64;
    while sim.time() < t1 - 1e-9 {
        let s0 = sim.pgs_sweeps;
        sim.step()?;
        k += 1;
        if let Some(d) = env("DEEP") {
            // every step with a contact deeper than DEEP metres: that contact
            let deepest = sim
                .contact_points()
                .iter()
                .max_by(|a, b| (-a.gap).total_cmp(&-b.gap));
            if let Some(p) = deepest.filter(|p| -p.gap > d) {
                println!(
                    "DEEP t {:.3} sweeps {} contacts {} gap {:.3e} body {} link {} geom {} other {} slot {} fresh {} n ({:.3},{:.3},{:.3}) p ({:.4},{:.4},{:.4})",
                    sim.time(),
                    sim.pgs_sweeps - s0,
                    sim.active_contacts(),
                    p.gap,
                    p.body,
                    sim.contact_link(p).unwrap_or("?"),
                    p.geom,
                    p.other,
                    p.slot,
                    p.fresh,
                    p.normal.x,
                    p.normal.y,
                    p.normal.z,
                    p.point.x,
                    p.point.y,
                    p.point.z
                );
            }
        }
        if sim.time() >= t0 - 1e-9 && k % every == 0 {
            println!(
                "t {:.2} vmax {:.3e} sweeps {} contacts {} pen {:.2e} wz {:.3e}",
                sim.time(),
                sim.v().amax(),
                sim.pgs_sweeps - s0,
                sim.active_contacts(),
                sim.penetration(),
                sim.v()[5]
            );
            if std::env::var_os("FORCES").is_some() {
                for f in sim.contact_forces() {
                    let ft = (f.force.x * f.force.x + f.force.y * f.force.y).sqrt();
                    println!(
                        "   body {} p ({:.4},{:.4},{:.4}) F ({:.4},{:.4},{:.4}) ratio {:.6}",
                        f.point.body,
                        f.point.point.x,
                        f.point.point.y,
                        f.point.point.z,
                        f.force.x,
                        f.force.y,
                        f.force.z,
                        ft / f.force.z
                    );
                }
            }
        }
    }
    Ok(())
}

/// `SCENE=FILE.json`: per window of `w` s from 0 to `t1` (sleep off), the
/// solve's work a step, the most sweeps of a step, contacts and |v|max.
fn scene_probe(file: &str, t0: f64, t1: f64, w: f64) -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::from_file(file, &[])?;
    let opts = SimOptions {
        sleep: false,
        ..SimOptions::of_scene(&scene)
    };
    let mut sim = Simulation::new_at(scene.model.clone(), opts, &scene.q0, &scene.v0)?;
    let (mut work0, mut steps, mut most) = (sim.solve_work(), 0u64, 0u64);
    let mut next = w;
    let start = std::time::Instant::now();
    while sim.time() < t1 - 1e-9 {
        let s0 = sim.pgs_sweeps;
        sim.step()?;
        steps += 1;
        most = most.max(sim.pgs_sweeps - s0);
        if sim.time() >= next - 1e-9 {
            if sim.time() >= t0 - 1e-9 {
                println!(
                    "t {:.2} work/step {:.1} max sweeps {} contacts {} vmax {:.3e}",
                    sim.time(),
                    (sim.solve_work() - work0) as f64 / steps as f64,
                    most,
                    sim.active_contacts(),
                    sim.v().amax()
                );
            }
            work0 = sim.solve_work();
            steps = 0;
            most = 0;
            next += w;
        }
    }
    println!(
        "total work {} sweeps {} wall {:.3} s",
        sim.solve_work(),
        sim.pgs_sweeps,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
