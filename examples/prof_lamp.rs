//! Profiling aid: the lamp drop of the README (floating base, 0.5 m, 10° about x)
//! without any output. `prof_lamp [DURATION] [SOLVER_TOL] [REPEATS]` prints the
//! solver's sweeps per step (a histogram), the resting state one second later,
//! and the fastest of REPEATS runs of DURATION simulated seconds. TILT (degrees,
//! default 5) rotates the start about x by twice that angle (the README's lamp
//! is TILT=5).
use urdyn::sim::{SimOptions, Simulation};

fn setup(tol: Option<f64>) -> Simulation {
    let path = std::env::var("LAMP").unwrap_or_else(|_| "assets/lamp.urdf".into());
    let model = urdyn::load_file(
        std::path::Path::new(&path),
        urdyn::LoadOptions {
            floating_base: true,
        },
    )
    .expect("lamp loads");
    let mut o = SimOptions::default();
    if let Ok(p) = std::env::var("PKG") {
        o.package_paths = vec![p.into()];
    }
    if let Some(t) = tol {
        o.solver_tol = t;
    }
    if let Some(n) = std::env::var("ITERS").ok().and_then(|s| s.parse().ok()) {
        o.solver_iterations = n;
    }
    if let Some(sv) = std::env::var("SOLVER")
        .ok()
        .and_then(|s| urdyn::sim::Solver::from_name(&s))
    {
        o.solver = sv;
    }
    if let Some(w) = std::env::var("RELAX").ok().and_then(|s| s.parse().ok()) {
        o.solver_relaxation = w;
    }
    let mut sim = Simulation::new(model, o).expect("simulation");
    let mut q = sim.q().clone();
    let low = sim.lowest_point();
    q[2] += if std::env::var("LAMP").is_ok() {
        0.3 - low
    } else {
        0.5
    };
    let tilt: f64 = std::env::var("TILT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5.0);
    q[3] = (tilt).to_radians().sin();
    q[6] = (tilt).to_radians().cos();
    let v = sim.v().clone();
    sim.set_state(&q, &v).expect("state");
    sim
}

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|s| s.parse::<f64>().ok());
    let dur = arg(1).unwrap_or(3.0);
    let tol = arg(2);
    let reps = arg(3).unwrap_or(20.0) as usize;
    let mut sim = setup(tol);
    {
        let mut cold = setup(tol);
        let t = std::time::Instant::now();
        while cold.time() < dur {
            cold.step_until(dur).expect("step");
        }
        let w = t.elapsed().as_secs_f64();
        println!(
            "first run in this process: {:.2} ms, real-time factor {:.0}",
            w * 1e3,
            dur / w
        );
    }
    // TRACE=1: one line a step on standard error (t, sweeps, rows so far,
    // active contacts, µs)
    let trace = std::env::var("TRACE").is_ok();
    let mut hist = [0u64; 8];
    let mut tsum = [0f64; 8];
    let mut prev = 0;
    while sim.time() < dur {
        let t0 = std::time::Instant::now();
        sim.step_until(dur).expect("step");
        let el = t0.elapsed().as_secs_f64();
        let sw = sim.pgs_sweeps - prev;
        prev = sim.pgs_sweeps;
        let b = match sw {
            0 => 0,
            1 => 1,
            2..=3 => 2,
            4..=7 => 3,
            8..=15 => 4,
            16..=31 => 5,
            32..=59 => 6,
            _ => 7,
        };
        hist[b] += 1;
        tsum[b] += el;
        if trace {
            eprintln!(
                "{:.3} {} {} {} {:.2}",
                sim.time(),
                sw,
                sim.rows_total,
                sim.active_contacts(),
                el * 1e6
            );
        }
    }
    println!(
        "time per bucket (ms): {:?}",
        tsum.iter()
            .map(|x| (x * 1e5).round() / 100.0)
            .collect::<Vec<_>>()
    );
    println!("sweeps per step [0, 1, 2-3, 4-7, 8-15, 16-31, 32-59, 60+]: {hist:?}");
    println!(
        "mean sweeps/step {:.2}, rows/step {:.1}, queries {}",
        sim.pgs_sweeps as f64 / sim.steps as f64,
        sim.rows_total as f64 / sim.steps as f64,
        sim.contact_queries()
    );
    while sim.time() < dur + 1.0 {
        sim.step_until(dur + 1.0).expect("step");
    }
    println!(
        "1 s later: penetration {:.3e} m, max |v| {:.2e}, energy {:.6} J",
        sim.penetration(),
        sim.v().amax(),
        sim.energy()
    );
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let mut sim = setup(tol);
        let t = std::time::Instant::now();
        while sim.time() < dur {
            sim.step_until(dur).expect("step");
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!(
        "fastest of {reps}: {:.2} ms for {dur} s, {:.2} us/step, real-time factor {:.0}",
        best * 1e3,
        best / (dur / 1e-3) * 1e6,
        dur / best
    );
}
