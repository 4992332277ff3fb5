//! Profiling driver for the analytic step Jacobians (ur5, no contact, Euler, dt 1 ms):
//! `cargo run --release --features tools --example prof_stepjac -- N` (perf record on it).
use nalgebra::DVector;
use std::hint::black_box;
use urdyn::sim::{Integrator, JacobianMethod, SimOptions, Simulation};
use urdyn::LoadOptions;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200_000);
    let model = urdyn::load_file("assets/robots/ur5.urdf", LoadOptions::default()).expect("ur5");
    let opts = SimOptions {
        ground: None,
        integrator: Some(Integrator::SemiImplicitEuler),
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).expect("sim");
    let nv = sim.model.nv;
    let q = DVector::from_fn(nv, |i, _| 0.3 + 0.4 * i as f64);
    sim.set_state(&q, &DVector::zeros(nv)).expect("state");
    let tau = DVector::zeros(nv);
    let t0 = std::time::Instant::now();
    for _ in 0..n {
        black_box(
            sim.transition_jacobians(&tau, JacobianMethod::Analytic, 1e-6)
                .ok(),
        );
    }
    println!(
        "{:.3} us per call",
        t0.elapsed().as_secs_f64() * 1e6 / n as f64
    );
}
