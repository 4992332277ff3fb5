//! Diagnostic: which contacts hold the Luxo lamp and how fast each point moves.
//! `cargo run --release --features tools --example luxo_probe [SCENE] [T...]`
use nalgebra::DVector;
use urdyn::sim::{SimOptions, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = env!("CARGO_MANIFEST_DIR");
    let args: Vec<String> = std::env::args().collect();
    let scene_path = args
        .get(1)
        .cloned()
        .unwrap_or(format!("{root}/assets/luxo_drop.json"));
    let times: Vec<f64> = args.iter().skip(2).filter_map(|s| s.parse().ok()).collect();
    let pkgs: Vec<std::path::PathBuf> = std::env::var("PKG")
        .map(|s| s.split(':').map(std::path::PathBuf::from).collect())
        .unwrap_or_default();
    let scene = urdyn::scene::Scene::from_file(&scene_path, &pkgs)?;
    let ground = scene.ground.unwrap_or(urdyn::scene::Ground {
        height: 0.0,
        friction: 1.0,
        torsion: None,
        rolling: None,
    });
    let mut contact = urdyn::contact::ContactParams::of_scene_ground(Some(&ground));
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    if let Some(x) = env("TORSION") {
        contact.torsion = x;
    }
    if let Some(x) = env("ROLLING") {
        contact.rolling = x;
    }
    let iters = env("ITERS").map(|x| x as usize);
    let opts = SimOptions {
        dt: 1e-3,
        ground: Some(ground.height),
        contact,
        sleep: true,
        ..Default::default()
    };
    let opts = SimOptions {
        solver_iterations: iters.unwrap_or(opts.solver_iterations),
        ..opts
    };
    let mut sim = Simulation::new(scene.model.clone(), opts)?;
    sim.set_state(&scene.q0, &scene.v0)?;
    sim.set_constraints(scene.constraints.clone())?;
    let model = scene.model.clone();
    let mut data = urdyn::model::Data::new(&model);
    if times.is_empty() {
        let mut asleep = None;
        let mut sweeps_max = 0;
        let mut pen: f64 = 0.0;
        let dur = env("DUR").unwrap_or(8.0);
        while sim.time() < dur - 1e-9 {
            let s0 = sim.pgs_sweeps;
            sim.step()?;
            pen = pen.max(sim.penetration());
            sweeps_max = sweeps_max.max(sim.pgs_sweeps - s0);
            if asleep.is_none() && sim.awake() == 0 {
                asleep = Some(sim.time());
            }
        }
        println!(
            "asleep at {asleep:?}, E = {:.6}, most sweeps in a step {sweeps_max}, deepest {pen:.3e}",
            sim.energy()
        );
    }
    for &t in &times {
        while sim.time() < t - 1e-9 {
            sim.step()?;
        }
        let (q, v) = (sim.q().clone(), sim.v().clone());
        let a = DVector::zeros(model.nv);
        urdyn::dynamics_f64::forward_kinematics_second_order(&model, &mut data, &q, &v, &a)?;
        println!(
            "t = {:.3}  E = {:.6}  awake {}",
            sim.time(),
            sim.energy(),
            sim.awake()
        );
        for b in 1..model.nbodies {
            let o = data.o_m_i[b];
            let w = o.rot * data.v[b].ang;
            let vl = o.rot * data.v[b].lin;
            println!(
                "  body {b} {:>10} pos [{:+.4} {:+.4} {:+.4}] v [{:+.2e} {:+.2e} {:+.2e}] w [{:+.2e} {:+.2e} {:+.2e}]",
                model.body_link_names[b], o.trans.x, o.trans.y, o.trans.z, vl.x, vl.y, vl.z, w.x, w.y, w.z
            );
        }
        for f in sim.contact_forces() {
            let p = f.point;
            let o = data.o_m_i[p.body];
            let w = o.rot * data.v[p.body].ang;
            let vl = o.rot * data.v[p.body].lin;
            let vp = vl + w.cross(&(p.point - o.trans));
            println!(
                "  contact {:>10} slot {:3} p [{:+.4} {:+.4} {:+.4}] gap {:+.2e} f [{:+.3} {:+.3} {:+.3}] vpt [{:+.2e} {:+.2e} {:+.2e}] |ft|/fn {:.3} fresh {}",
                sim.contact_link(&p).unwrap_or("?"), p.slot, p.point.x, p.point.y, p.point.z, p.gap,
                f.force.x, f.force.y, f.force.z, vp.x, vp.y, vp.z,
                (f.force.x.hypot(f.force.y)) / f.force.z.max(1e-12),
                p.fresh
            );
        }
    }
    Ok(())
}
