//! Diagnostic: a lone URDF dropped as `urdyn simulate --floating-base
//! --above-ground H` drops it; prints, for the steps in [T0, T1), every
//! contact point (link, slot, gap, force, point velocity) and the largest
//! generalized speed. `cargo run --release --features tools --example rest_probe URDF [T0 T1]`
//! (package paths from `PKG`, colon-separated; `H` from `LIFT`, default 0.3).
use urdyn::sim::{SimOptions, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let urdf = args.get(1).ok_or("usage: rest_probe URDF [T0 T1]")?;
    let t0: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8.0);
    let t1: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(t0);
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    let pkgs: Vec<std::path::PathBuf> = std::env::var("PKG")
        .map(|s| s.split(':').map(std::path::PathBuf::from).collect())
        .unwrap_or_default();
    let model = urdyn::load_file(
        urdf,
        urdyn::LoadOptions {
            floating_base: true,
        },
    )?;
    let mut contact = urdyn::contact::ContactParams::default();
    if let Some(x) = env("TORSION") {
        contact.torsion = x;
    }
    if let Some(x) = env("ROLLING") {
        contact.rolling = x;
    }
    if let Some(x) = env("MARGIN") {
        contact.margin = x;
    }
    let opts = SimOptions {
        dt: env("DT").unwrap_or(1e-3),
        ground: Some(0.0),
        contact,
        package_paths: pkgs,
        sleep: true,
        ..Default::default()
    };
    let opts = SimOptions {
        solver_iterations: env("ITERS").map_or(opts.solver_iterations, |x| x as usize),
        ..opts
    };
    let mut sim = Simulation::new(model.clone(), opts)?;
    // INIT: a JSON file {"q": {"joint": value, ...}} (the sweep's start)
    if let Ok(path) = std::env::var("INIT") {
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path)?)?;
        let mut q = sim.q().clone();
        for (name, x) in model.q_names().iter().zip(q.iter_mut()) {
            if let Some(val) = v["q"][name.as_str()].as_f64() {
                *x = val;
            }
        }
        let v0 = sim.v().clone();
        sim.set_state(&q, &v0)?;
    }
    sim.lift_above_ground(env("LIFT").unwrap_or(0.3))?;
    let dur = env("DUR").unwrap_or(8.0);
    let mut asleep = None;
    let mut changes = 0;
    let mut last = Vec::new();
    while sim.time() < dur - 1e-9 {
        sim.step()?;
        let t = sim.time();
        let slots: Vec<usize> = sim.contact_points().iter().map(|p| p.slot).collect();
        if t > 3.0 && slots != last {
            changes += 1;
        }
        last = slots;
        if asleep.is_none() && sim.awake() == 0 {
            asleep = Some(t);
        }
        if t >= t0 - 1e-9 && t < t1 - 1e-9 {
            let vmax = sim.v().amax();
            println!(
                "E {:.6} pen {:.3e} active {}",
                sim.energy(),
                sim.penetration(),
                sim.active_contacts()
            );
            println!(
                "t {t:.3} vmax {vmax:.2e} v {:?}",
                sim.v()
                    .iter()
                    .map(|x| format!("{x:+.1e}"))
                    .collect::<Vec<_>>()
            );
            for p in sim.contact_points() {
                let f = sim
                    .contact_forces()
                    .iter()
                    .find(|f| f.point.slot == p.slot)
                    .map_or([0.0; 3], |f| [f.force.x, f.force.y, f.force.z]);
                println!(
                    "  {:>22} slot {:4} p [{:+.5} {:+.5} {:+.6}] gap {:+.3e} f [{:+.3e} {:+.3e} {:+.3e}] fresh {}",
                    sim.contact_link(p).unwrap_or("?"),
                    p.slot,
                    p.point.x,
                    p.point.y,
                    p.point.z,
                    p.gap,
                    f[0],
                    f[1],
                    f[2],
                    p.fresh
                );
            }
        }
    }
    println!(
        "asleep at {asleep:?}; point-set changes after 3 s: {changes}; E = {:.6}; q = {:?}",
        sim.energy(),
        sim.q()
            .iter()
            .map(|x| format!("{x:.5}"))
            .collect::<Vec<_>>()
    );
    Ok(())
}
