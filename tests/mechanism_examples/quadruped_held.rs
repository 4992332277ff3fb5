//! examples/quadruped_held.rs: solo12 with its feet held by `point` constraints
//! under computed torque through the constrained dynamics.
//! - At rest at the standing pose (v = 0, the reference its position, no
//!   acceleration), the controller's joint torques, fed to urdyn's forward
//!   `constraint_dynamics`, give q̈ = 0 and feet forces whose normal (world z)
//!   components sum to the weight M g (closed form: the base is unactuated, so
//!   the feet carry everything) within 1e-6 relative, each positive.
//! - Tracking: the exact computed torque makes the base's error obey
//!   ë + 40 ė + 400 e = 0; from the start's velocity mismatch (the sway starts at
//!   6.3 cm/s) it decays as e^{−20 t}·(1 + 20 t) ≈ 2e-7 of its scale at 1 s, so
//!   after 1 s the error is what RK4 at 1 ms leaves (measured 2.3e-10 m);
//!   asserted below 1e-6 m, and below 5 mm while catching up (measured 2.1 mm).
//!   A wrong λ (not carrying the base) or a wrong γ_c breaks both by far.
//! - The feet push on the ground throughout (normal forces > 0).

use super::quadruped_setup;

use nalgebra::Vector3;

#[test]
fn held_quadruped_carries_its_weight_at_rest() {
    let (mut sys, q, v) = quadruped_setup::setup();
    let p = Vector3::new(q[0], q[1], q[2]);
    let (tau, _) =
        quadruped_setup::control_to(&mut sys, (p, Vector3::zeros(), Vector3::zeros()), &q, &v);
    assert!(tau.rows(0, 6).amax() == 0.0, "the base is unactuated");
    let qdd = sys.qdd(&q, &v, &tau);
    assert!(qdd.amax() < 1e-9, "at rest: qdd {qdd}");
    let lam = sys.cd.lambda.clone();
    let weight = sys.model.total_mass() * -sys.model.gravity.z;
    let sum: f64 = (0..4).map(|k| lam[3 * k + 2]).sum();
    assert!(
        (sum - weight).abs() < 1e-6 * weight,
        "feet carry {sum} N, weight {weight} N"
    );
    for k in 0..4 {
        assert!(lam[3 * k + 2] > 0.0, "foot {k} pulls: {lam}");
    }
    // horizontal components: the least-norm λ leaves no net horizontal force
    let fx: f64 = (0..4).map(|k| lam[3 * k]).sum();
    let fy: f64 = (0..4).map(|k| lam[3 * k + 1]).sum();
    assert!(
        fx.abs() < 1e-9 * weight && fy.abs() < 1e-9 * weight,
        "net horizontal {fx}, {fy}"
    );
    eprintln!("quadruped_held at rest: feet carry {sum:.9} N, weight {weight:.9} N");
}

#[test]
fn held_quadruped_tracks_sway_and_height() {
    let s = quadruped_setup::run(1e-3, 3.0, 5);
    let late = s
        .iter()
        .filter(|x| x.t >= 1.0)
        .map(|x| x.error)
        .fold(0.0, f64::max);
    let all = s.iter().map(|x| x.error).fold(0.0, f64::max);
    let fmin = s
        .iter()
        .flat_map(|x| x.normal)
        .fold(f64::INFINITY, f64::min);
    let viol = s.iter().map(|x| x.violation).fold(0.0, f64::max);
    assert!(
        all > 1e-4,
        "the start's mismatch shows ({all:e} m): the test can see an error"
    );
    assert!(all < 5e-3, "catching up: error {all:e} m");
    assert!(late < 1e-6, "after 1 s: error {late:e} m");
    assert!(fmin > 0.0, "a foot pulls on the ground: {fmin} N");
    assert!(viol < 1e-12, "feet drift {viol:e} m");
    eprintln!(
        "quadruped_held: error {all:.2e} m, after 1 s {late:.2e} m, normal forces >= {fmin:.3} N"
    );
}
