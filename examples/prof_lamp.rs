use urdyn::sim::{SimOptions, Simulation};
fn main() {
    let model = urdyn::load_file(
        std::path::Path::new(std::env::var("LAMP").as_deref().unwrap_or("assets/lamp.urdf")),
        urdyn::LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let mut o = SimOptions::default();
    if let Some(t) = std::env::args().nth(2).and_then(|s| s.parse().ok()) { o.solver_tol = t; }
    let mut sim = Simulation::new(model, o).unwrap();
    let mut q = sim.q().clone();
    q[2] = 0.5;
    q[3] = (5f64).to_radians().sin();
    q[6] = (5f64).to_radians().cos();
    let v = sim.v().clone();
    sim.set_state(&q, &v).unwrap();
    let t = std::time::Instant::now();
    let dur: f64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(30.0);
    let mut hist = [0u64; 8];
    let mut prev = 0;
    while sim.time() < dur {
        sim.step_until(dur).unwrap();
        let sw = sim.pgs_sweeps - prev;
        prev = sim.pgs_sweeps;
        let b = match sw { 0 => 0, 1 => 1, 2..=3 => 2, 4..=7 => 3, 8..=15 => 4, 16..=31 => 5, 32..=59 => 6, _ => 7 };
        hist[b] += 1;
        if std::env::var("TRACE").is_ok() && sim.steps % 10 == 0 { println!("t {:.3} sweeps {} pts {} rows {}", sim.time(), sw, sim.contact_points().len(), sim.rows_total); }
    }
    println!("sweeps hist [0,1,2-3,4-7,8-15,16-31,32-59,60+]: {hist:?}");
    let w = t.elapsed().as_secs_f64();
    let (s0, r0, n0) = (sim.pgs_sweeps, sim.rows_total, sim.steps);
    while sim.time() < dur + 1.0 {
        sim.step_until(dur + 1.0).unwrap();
    }
    println!("last 1 s: sweeps/step {:.1} rows/step {:.1} pen {:.3e} v {:.2e} E {:.6}",
        (sim.pgs_sweeps - s0) as f64 / (sim.steps - n0) as f64,
        (sim.rows_total - r0) as f64 / (sim.steps - n0) as f64,
        sim.penetration(), sim.v().amax(), sim.energy());
    println!(
        "wall {w:.4} steps {} sweeps/step {:.1} rows/step {:.1} queries {}",
        sim.steps,
        sim.pgs_sweeps as f64 / sim.steps as f64,
        sim.rows_total as f64 / sim.steps as f64,
        sim.contact_queries()
    );
    let t = std::time::Instant::now();
    let mut e = 0.0f64;
    for _ in 0..3000 {
        e += sim.energy();
    }
    println!("{e}");
    println!("energy x3000 {:.4}", t.elapsed().as_secs_f64());
}
#[allow(dead_code)]
fn hist() {}
