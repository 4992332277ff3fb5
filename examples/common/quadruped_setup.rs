//! solo12 (assets/robots/solo12.urdf, floating base) standing with its four
//! feet held by `point` constraints (urdyn's `constraint_dynamics` as the contact
//! model, as Crocoddyl's contact models use Pinocchio's), driven by a computed-
//! torque controller through the constrained dynamics (examples/quadruped_held.rs,
//! tests/mechanism_examples/quadruped_held.rs).
//!
//! Controller, at every RK4 stage: the base's desired world acceleration
//! p̈* = p̈_ref + K_d (ṗ_ref − ṗ) + K_p (p_ref − p), its rotation held level
//! (ω̇* = −K_p log R − K_d ω); in the free base's body-frame coordinates
//! v̇_lin* = Rᵀ p̈* − ω × v_lin. The feet held (J_c q̈ + γ_c = 0, J_c = [J_b J_j],
//! J_j the 12 leg joints' 12 × 12 block) fix the joints' accelerations:
//! q̈_j = −J_j⁻¹ (γ_c + J_b a_b*). Then RNEA gives the generalized force
//! f = H q̈* + C; the base is unactuated, so its six rows must be carried by the
//! feet: J_bᵀ λ = f_b, λ the least-norm solution (pseudo-inverse: no internal
//! squeezing between the feet), and the joints' torques τ_j = f_j − J_jᵀ λ.
//! With τ = [0; τ_j] the constrained forward dynamics has the unique solution
//! (q̈*, λ), so the error obeys ë + K_d ė + K_p e = 0 exactly.

#![allow(dead_code)]

use nalgebra::{DMatrix, DVector, Matrix3, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use urdyn::dynamics_f64 as dynamics;
use urdyn::model::Constraints;
use urdyn::LoadOptions;

use super::constrained::{pinv, Constrained};

/// Position and velocity gains (critically damped, natural frequency 20 rad/s).
pub const KP: f64 = 400.0;
/// Velocity gain (N·s/m per kg).
pub const KD: f64 = 40.0;
/// Sway amplitude (m, along y) and frequency (Hz).
pub const SWAY: (f64, f64) = (0.02, 0.5);
/// Height amplitude (m, along z) and frequency (Hz).
pub const HEAVE: (f64, f64) = (0.015, 1.0);

/// The base's reference position, velocity, acceleration at t about its start p0:
/// a sideways sway and a vertical bob, both sinusoids from t = 0 (the start, at
/// rest, is off the reference's velocity: the controller catches up).
pub fn reference(p0: &Vector3<f64>, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let (ay, fy) = SWAY;
    let (az, fz) = HEAVE;
    let (wy, wz) = (2.0 * PI * fy, 2.0 * PI * fz);
    let p = p0 + Vector3::new(0.0, ay * (wy * t).sin(), az * (wz * t).sin());
    let v = Vector3::new(0.0, ay * wy * (wy * t).cos(), az * wz * (wz * t).cos());
    let a = Vector3::new(
        0.0,
        -ay * wy * wy * (wy * t).sin(),
        -az * wz * wz * (wz * t).sin(),
    );
    (p, v, a)
}

/// The held quadruped at its standing pose (example-robot-data's "standing":
/// HFE ±0.8, KFE ∓1.6), at rest: (system, q₀, v₀).
pub fn setup() -> (Constrained, DVector<f64>, DVector<f64>) {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let model = urdyn::load_file(
        root.join("assets/robots/solo12.urdf"),
        LoadOptions {
            floating_base: true,
        },
    )
    .expect("assets/robots/solo12.urdf");
    let feet: Vec<serde_json::Value> = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
        .iter()
        .map(|f| serde_json::json!({"name": f, "kind": "point", "link1": f}))
        .collect();
    let c = Constraints::from_json(&model, &feet).expect("feet constraints");
    let mut q = model.neutral();
    q[2] = 0.24;
    for (name, x) in model.q_names().iter().zip(q.iter_mut()) {
        let front = name.starts_with('F');
        if name.ends_with("_HFE") {
            *x = if front { 0.8 } else { -0.8 };
        } else if name.ends_with("_KFE") {
            *x = if front { -1.6 } else { 1.6 };
        }
    }
    let v = DVector::zeros(model.nv);
    (Constrained::new(model, c, &q), q, v)
}

/// The base's world position, rotation, world velocity of q, v.
pub fn base_state(q: &DVector<f64>, v: &DVector<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let _ = v;
    let p = Vector3::new(q[0], q[1], q[2]);
    let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[6], q[3], q[4], q[5]))
        .to_rotation_matrix()
        .into_inner();
    (p, r)
}

/// The controller's torques (module notes) at (q, v, t) about the start p0;
/// also the λ it plans (stacked feet forces, world).
pub fn control(
    sys: &mut Constrained,
    p0: &Vector3<f64>,
    q: &DVector<f64>,
    v: &DVector<f64>,
    t: f64,
) -> (DVector<f64>, DVector<f64>) {
    control_to(sys, reference(p0, t), q, v)
}

/// [`control`] for a given reference (position, velocity, acceleration).
pub fn control_to(
    sys: &mut Constrained,
    reference: (Vector3<f64>, Vector3<f64>, Vector3<f64>),
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> (DVector<f64>, DVector<f64>) {
    let nv = sys.model.nv;
    let (p, r) = base_state(q, v);
    let v_lin = Vector3::new(v[0], v[1], v[2]);
    let w = Vector3::new(v[3], v[4], v[5]);
    let (p_ref, v_ref, a_ref) = reference;
    let pd = r * v_lin;
    let a_world = a_ref + KD * (v_ref - pd) + KP * (p_ref - p);
    let a_lin = r.transpose() * a_world - w.cross(&v_lin);
    let log_r = nalgebra::Rotation3::from_matrix_unchecked(r).scaled_axis();
    let a_ang = -KP * log_r - KD * w;
    // J_c and γ_c at (q, v): the constrained dynamics with τ = 0 fills them
    let zero = DVector::zeros(nv);
    sys.qdd(q, v, &zero);
    let jc: DMatrix<f64> = sys.cd.jc.clone();
    let gamma: DVector<f64> = sys.cd.gamma.clone();
    let jb = jc.columns(0, 6).into_owned();
    let jj = jc.columns(6, nv - 6).into_owned();
    let mut ab = DVector::zeros(6);
    ab.rows_mut(0, 3).copy_from(&a_lin);
    ab.rows_mut(3, 3).copy_from(&a_ang);
    let rhs = -(&gamma + &jb * &ab);
    let qdd_j = jj.lu().solve(&rhs).expect("legs away from singular");
    let mut qdd = DVector::zeros(nv);
    qdd.rows_mut(0, 6).copy_from(&ab);
    qdd.rows_mut(6, nv - 6).copy_from(&qdd_j);
    let f = dynamics::rnea(&sys.model, &mut sys.data, q, v, &qdd, None)
        .expect("sizes")
        .clone();
    let lambda = pinv(&jb.transpose()) * f.rows(0, 6);
    let mut tau = f - jc.transpose() * &lambda;
    tau.rows_mut(0, 6).fill(0.0);
    (tau, lambda)
}

/// One sample of the run.
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// The base's position error |p − p_ref| (m).
    pub error: f64,
    /// The base's height (m) and its reference.
    pub z: (f64, f64),
    /// The base's sideways position (m) and its reference.
    pub y: (f64, f64),
    /// The four feet's normal (world z) forces from the forward dynamics (N).
    pub normal: [f64; 4],
    /// The largest joint torque (N·m).
    pub tau_max: f64,
    /// The largest feet violation (m).
    pub violation: f64,
}

/// Integrates the controlled, held quadruped to `t_end` with step h, a sample every `every` steps.
pub fn run(h: f64, t_end: f64, every: usize) -> Vec<Sample> {
    let (mut sys, mut q, mut v) = setup();
    let p0 = Vector3::new(q[0], q[1], q[2]);
    let n = (t_end / h).round() as usize;
    let mut out = Vec::new();
    let sample = |sys: &mut Constrained, q: &DVector<f64>, v: &DVector<f64>, t: f64| {
        let (tau, _) = control(sys, &p0, q, v, t);
        sys.qdd(q, v, &tau);
        let lam = sys.cd.lambda.clone();
        let (p, _) = base_state(q, v);
        let (p_ref, _, _) = reference(&p0, t);
        Sample {
            t,
            error: (p - p_ref).norm(),
            z: (p.z, p_ref.z),
            y: (p.y, p_ref.y),
            normal: [lam[2], lam[5], lam[8], lam[11]],
            tau_max: tau.amax(),
            violation: sys.violation(q),
        }
    };
    out.push(sample(&mut sys, &q, &v, 0.0));
    for k in 0..n {
        let t = k as f64 * h;
        sys.rk4_step(&mut q, &mut v, t, h, &mut |s, qs, vs, ts| {
            control(s, &p0, qs, vs, ts).0
        });
        if (k + 1) % every == 0 {
            out.push(sample(&mut sys, &q, &v, (k + 1) as f64 * h));
        }
    }
    out
}
