//! The configuration manifold: q ⊕ h v (the free joint's unit quaternion and
//! body-frame velocity, every other joint additive) and its rate q̇(q, v).
//!
//! A free base's q is `[p (world), quaternion (x, y, z, w)]` and its v is
//! `[v_lin, ω]` in the base's own frame (Pinocchio's free flyer, docs/theory.md
//! §"Floating base"); joints after it have q̇ = v.

use super::Model;
use crate::spatial::{axis_angle, quat_to_matrix};
use nalgebra::{DVector, Vector3};

/// q ← q ⊕ h v: p += h R v_lin, quaternion ← quaternion ⊗ exp(h ω / 2)
/// (renormalised), joints += h v.
pub fn integrate_config(model: &Model, q: &mut DVector<f64>, v: &DVector<f64>, h: f64) {
    let (qo, vo) = (model.joint_q_offset(), model.joint_v_offset());
    if model.floating_base {
        let r = quat_to_matrix(q[3], q[4], q[5], q[6]);
        let dp = r * Vector3::new(v[0], v[1], v[2]) * h;
        q[0] += dp.x;
        q[1] += dp.y;
        q[2] += dp.z;
        let w = Vector3::new(v[3], v[4], v[5]) * h;
        let th = w.norm();
        let (s, c) = if th > 1e-12 {
            let (s, c) = (th / 2.0).sin_cos();
            (s / th, c)
        } else {
            (0.5 - th * th / 48.0, 1.0 - th * th / 8.0)
        };
        let (dx, dy, dz, dw) = (w.x * s, w.y * s, w.z * s, c);
        let (x, y, z, ww) = (q[3], q[4], q[5], q[6]);
        q[3] = ww * dx + x * dw + y * dz - z * dy;
        q[4] = ww * dy - x * dz + y * dw + z * dx;
        q[5] = ww * dz + x * dy - y * dx + z * dw;
        q[6] = ww * dw - x * dx - y * dy - z * dz;
        normalize_quat(q);
    }
    for d in 0..model.dofs.len() {
        q[qo + d] += h * v[vo + d];
    }
}

/// Re-expresses a free base's body-frame linear velocity after its frame turned
/// by exp(h ω) (ω = `w[3..6]`): v_lin ← exp(−h ω) v_lin. With
/// [`integrate_config`] this makes a semi-implicit step rotate the velocity
/// exactly (no energy from the frame's own rotation).
pub fn rotate_base_velocity(model: &Model, v: &mut DVector<f64>, w: &DVector<f64>, h: f64) {
    if !model.floating_base {
        return;
    }
    let wv = Vector3::new(w[3], w[4], w[5]) * h;
    let th = wv.norm();
    if th > 0.0 {
        let r = axis_angle(&(wv / th), th);
        let vl = r.transpose() * Vector3::new(v[0], v[1], v[2]);
        v[0] = vl.x;
        v[1] = vl.y;
        v[2] = vl.z;
    }
}

/// Writes q̇ into `dy[0..nq]`: ṗ = R(q̂) v_lin (q̂ = `qn`, normalised), quaternion
/// rate ½ q ⊗ (ω, 0) with q read from `y` unnormalised (the exact derivative of
/// the ODE state), joints q̇ = v.
pub fn config_rate(
    model: &Model,
    qn: &DVector<f64>,
    y: &DVector<f64>,
    v: &DVector<f64>,
    dy: &mut DVector<f64>,
) {
    let (qo, vo) = (model.joint_q_offset(), model.joint_v_offset());
    if model.floating_base {
        let r = quat_to_matrix(qn[3], qn[4], qn[5], qn[6]);
        let pd = r * Vector3::new(v[0], v[1], v[2]);
        dy[0] = pd.x;
        dy[1] = pd.y;
        dy[2] = pd.z;
        let (x, yy, z, ww) = (y[3], y[4], y[5], y[6]);
        let (wx, wy, wz) = (v[3], v[4], v[5]);
        // (q ⊗ (ω,0)): vector = w ω + qv × ω, scalar = −qv·ω
        dy[3] = 0.5 * (ww * wx + yy * wz - z * wy);
        dy[4] = 0.5 * (ww * wy + z * wx - x * wz);
        dy[5] = 0.5 * (ww * wz + x * wy - yy * wx);
        dy[6] = -0.5 * (x * wx + yy * wy + z * wz);
    }
    for d in 0..model.dofs.len() {
        dy[qo + d] = v[vo + d];
    }
}

/// Normalises a free base's quaternion `q[3..7]` in place (a zero or non-finite
/// one is left as is).
pub fn normalize_quat(q: &mut DVector<f64>) {
    if q.len() < 7 {
        return;
    }
    let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
    if n > 0.0 && n.is_finite() {
        for k in 3..7 {
            q[k] /= n;
        }
    }
}
