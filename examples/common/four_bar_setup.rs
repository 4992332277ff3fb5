//! The four-bar of assets/four_bar.urdf + assets/four_bar_constraints.json
//! (examples/four_bar.rs, tests/mechanism_examples/four_bar.rs): the model, its loop, and the start
//! configuration on the loop's upper branch for a crank angle θ₀ (closed form:
//! the coupler's tip B is where the circles of radius l₂ about the crank's tip A
//! and l₃ about the rocker's pivot meet; in the xz plane a rotation by a about
//! +y takes (1, 0, 0) to (cos a, 0, −sin a)).

#![allow(dead_code)]

use nalgebra::DVector;
use std::path::PathBuf;
use urdyn::model::Constraints;
use urdyn::LoadOptions;

use super::constrained::Constrained;

/// The crank's start angle (rad), released at rest; tests/oracle/four_bar_reference.py's THETA0.
pub const THETA0: f64 = -1.0;
/// Crank, coupler, rocker lengths and the ground link (m), as the URDF and the JSON.
pub const L1: f64 = 0.10;
/// Coupler length (m).
pub const L2: f64 = 0.30;
/// Rocker length (m).
pub const L3: f64 = 0.25;
/// Rocker pivot's distance from the crank pivot (m).
pub const D: f64 = 0.30;

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// (q_crank, q_coupler, q_rocker) closing the loop at crank angle θ, upper branch (z > 0).
pub fn closed_q(theta: f64) -> [f64; 3] {
    // planar coordinates (x, w = −z): angle a is (cos a, sin a)
    let a = [L1 * theta.cos(), L1 * theta.sin()];
    let dv = [D - a[0], -a[1]];
    let dist = dv[0].hypot(dv[1]);
    let x = (L2 * L2 - L3 * L3 + dist * dist) / (2.0 * dist);
    let h = (L2 * L2 - x * x).sqrt();
    let u = [dv[0] / dist, dv[1] / dist];
    let n = [-u[1], u[0]];
    let b1 = [a[0] + x * u[0] + h * n[0], a[1] + x * u[1] + h * n[1]];
    let b2 = [a[0] + x * u[0] - h * n[0], a[1] + x * u[1] - h * n[1]];
    let b = if b1[1] < b2[1] { b1 } else { b2 };
    let phi2 = (b[1] - a[1]).atan2(b[0] - a[0]);
    let phi3 = b[1].atan2(b[0] - D);
    [theta, phi2 - theta, phi3]
}

/// The model with its loop, at rest at θ₀: (system, q₀, v₀).
pub fn setup() -> (Constrained, DVector<f64>, DVector<f64>) {
    let model = urdyn::load_file(root().join("assets/four_bar.urdf"), LoadOptions::default())
        .expect("assets/four_bar.urdf");
    let text = std::fs::read_to_string(root().join("assets/four_bar_constraints.json"))
        .expect("assets/four_bar_constraints.json");
    let json: serde_json::Value = serde_json::from_str(&text).expect("constraints JSON");
    let c = Constraints::from_value(&model, &json).expect("the loop builds");
    let names = model.q_names();
    assert_eq!(names, ["crank_joint", "coupler_joint", "rocker_joint"]);
    let q = DVector::from_row_slice(&closed_q(THETA0));
    let v = DVector::zeros(3);
    (Constrained::new(model, c, &q), q, v)
}

/// One sample of the run.
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// q.
    pub q: DVector<f64>,
    /// Energy (J).
    pub energy: f64,
    /// The loop's violation (m).
    pub violation: f64,
}

/// Integrates from rest at θ₀ to `t_end` with step h, a sample every `every` steps.
pub fn run(h: f64, t_end: f64, every: usize) -> Vec<Sample> {
    let (mut sys, mut q, mut v) = setup();
    let n = (t_end / h).round() as usize;
    let zero = DVector::zeros(3);
    let mut out = Vec::with_capacity(n / every + 1);
    let sample = |sys: &mut Constrained, q: &DVector<f64>, v: &DVector<f64>, t| Sample {
        t,
        q: q.clone(),
        energy: sys.energy(q, v),
        violation: sys.violation(q),
    };
    out.push(sample(&mut sys, &q, &v, 0.0));
    for k in 0..n {
        let t = k as f64 * h;
        sys.rk4_step(&mut q, &mut v, t, h, &mut |_, _, _, _| zero.clone());
        if (k + 1) % every == 0 {
            out.push(sample(&mut sys, &q, &v, (k + 1) as f64 * h));
        }
    }
    out
}
