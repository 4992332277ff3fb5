//! The configuration manifold: q ⊕ h v (the free joint's unit quaternion and
//! body-frame velocity, every other joint additive) and its rate q̇(q, v).
//!
//! A free base's q is `[p (world), quaternion (x, y, z, w)]` and its v is
//! `[v_lin, ω]` in the base's own frame (Pinocchio's free flyer, docs/theory.md
//! §"Floating base"); joints after it have q̇ = v.

use super::Model;
use crate::spatial::{axis_angle, quat_to_matrix, sin_cos};
use nalgebra::{DVector, Vector3};

/// q ← q ⊕ h v: p += h R v_lin, quaternion ← quaternion ⊗ exp(h ω / 2)
/// (renormalised), joints += h v.
pub fn integrate_config(model: &Model, q: &mut DVector<f64>, v: &DVector<f64>, h: f64) {
    for f in &model.free_joints {
        integrate_free(q, v, h, f.iq, f.iv);
    }
    for t in &model.trees {
        let (qo, vo) = (t.joint_q(), t.joint_v());
        for k in 0..t.dofs.len() {
            q[qo + k] += h * v[vo + k];
        }
    }
}

/// One free joint's q ⊕ h v, its q at `iq..iq + 7`, its v at `iv..iv + 6`.
fn integrate_free(q: &mut DVector<f64>, v: &DVector<f64>, h: f64, iq: usize, iv: usize) {
    let r = quat_to_matrix(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]);
    let dp = r * Vector3::new(v[iv], v[iv + 1], v[iv + 2]) * h;
    q[iq] += dp.x;
    q[iq + 1] += dp.y;
    q[iq + 2] += dp.z;
    let w = Vector3::new(v[iv + 3], v[iv + 4], v[iv + 5]) * h;
    let th = w.norm();
    let (s, c) = if th > 1e-12 {
        let (s, c) = sin_cos(th / 2.0);
        (s / th, c)
    } else {
        (0.5 - th * th / 48.0, 1.0 - th * th / 8.0)
    };
    let (dx, dy, dz, dw) = (w.x * s, w.y * s, w.z * s, c);
    let (x, y, z, ww) = (q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]);
    q[iq + 3] = ww * dx + x * dw + y * dz - z * dy;
    q[iq + 4] = ww * dy - x * dz + y * dw + z * dx;
    q[iq + 5] = ww * dz + x * dy - y * dx + z * dw;
    q[iq + 6] = ww * dw - x * dx - y * dy - z * dz;
    normalize_quat_at(q, iq + 3);
}

/// Re-expresses a free base's body-frame linear velocity after its frame turned
/// by exp(h ω) (ω = `w[3..6]`): v_lin ← exp(−h ω) v_lin. With
/// [`integrate_config`] this makes a semi-implicit step rotate the velocity
/// exactly (no energy from the frame's own rotation).
pub fn rotate_base_velocity(model: &Model, v: &mut DVector<f64>, w: &DVector<f64>, h: f64) {
    for f in &model.free_joints {
        let iv = f.iv;
        let wv = Vector3::new(w[iv + 3], w[iv + 4], w[iv + 5]) * h;
        let th = wv.norm();
        if th > 0.0 {
            let r = axis_angle(&(wv / th), th);
            let vl = r.transpose() * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
            v[iv] = vl.x;
            v[iv + 1] = vl.y;
            v[iv + 2] = vl.z;
        }
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
    for f in &model.free_joints {
        let (iq, iv) = (f.iq, f.iv);
        let r = quat_to_matrix(qn[iq + 3], qn[iq + 4], qn[iq + 5], qn[iq + 6]);
        let pd = r * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
        dy[iq] = pd.x;
        dy[iq + 1] = pd.y;
        dy[iq + 2] = pd.z;
        let (x, yy, z, ww) = (y[iq + 3], y[iq + 4], y[iq + 5], y[iq + 6]);
        let (wx, wy, wz) = (v[iv + 3], v[iv + 4], v[iv + 5]);
        // (q ⊗ (ω,0)): vector = w ω + qv × ω, scalar = −qv·ω
        dy[iq + 3] = 0.5 * (ww * wx + yy * wz - z * wy);
        dy[iq + 4] = 0.5 * (ww * wy + z * wx - x * wz);
        dy[iq + 5] = 0.5 * (ww * wz + x * wy - yy * wx);
        dy[iq + 6] = -0.5 * (x * wx + yy * wy + z * wz);
    }
    for t in &model.trees {
        let (qo, vo) = (t.joint_q(), t.joint_v());
        for k in 0..t.dofs.len() {
            dy[qo + k] = v[vo + k];
        }
    }
}

/// Normalises a free base's quaternion `q[3..7]` in place (a zero or non-finite
/// one is left as is).
pub fn normalize_quat(q: &mut DVector<f64>) {
    if q.len() < 7 {
        return;
    }
    normalize_quat_at(q, 3);
}

/// Normalises every free joint's quaternion in place (as [`normalize_quat`]).
pub fn normalize_quats(model: &Model, q: &mut DVector<f64>) {
    for f in &model.free_joints {
        normalize_quat_at(q, f.iq + 3);
    }
}

/// Normalises the quaternion `q[at..at + 4]` (a zero or non-finite one is left as is).
fn normalize_quat_at(q: &mut DVector<f64>, at: usize) {
    let n = (q[at] * q[at] + q[at + 1] * q[at + 1] + q[at + 2] * q[at + 2] + q[at + 3] * q[at + 3])
        .sqrt();
    if n > 0.0 && n.is_finite() {
        for k in at..at + 4 {
            q[k] /= n;
        }
    }
}

// ---------------------------------------------------------------------------
// The manifold for tools: q ⊕ v, q₁ ⊖ q₀, neutral and random configurations,
// configurations by joint name (sizes checked, no panic).

use super::{DimensionError, NameError};

/// `q ⊕ v`: the configuration reached from `q` by the velocity `v` held for one
/// unit of time, as the simulator steps ([`integrate_config`] with h = 1): a free
/// base moves by `R(q) v_lin` (world) and turns by `exp(ω)` (body frame); every
/// other joint adds. (Pinocchio's `integrate` moves a free base along the SE(3)
/// exponential instead; the two agree to first order.)
pub fn integrate(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let mut out = q.clone();
    integrate_config(model, &mut out, v, 1.0);
    Ok(out)
}

/// `q₁ ⊖ q₀`: the velocity `v` with [`integrate`]`(q₀, v) = q₁` — a free base's
/// `v_lin = R(q₀)ᵀ (p₁ − p₀)` and `ω = log(q₀⁻¹ ⊗ q₁)` (the shorter rotation),
/// every other joint `q₁ − q₀`.
pub fn difference(
    model: &Model,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q0", model.nq, q0.len())?;
    DimensionError::check("q1", model.nq, q1.len())?;
    let mut v = DVector::zeros(model.nv);
    for f in &model.free_joints {
        difference_free(q0, q1, &mut v, f.iq, f.iv);
    }
    for (_, iq, iv) in model.dof_indices() {
        v[iv] = q1[iq] - q0[iq];
    }
    Ok(v)
}

/// One free joint's part of q₁ ⊖ q₀ (q at `iq..iq + 7`, v at `iv..iv + 6`).
fn difference_free(
    q0: &DVector<f64>,
    q1: &DVector<f64>,
    v: &mut DVector<f64>,
    iq: usize,
    iv: usize,
) {
    let quat = |q: &DVector<f64>| {
        let n = (q[iq + 3] * q[iq + 3]
            + q[iq + 4] * q[iq + 4]
            + q[iq + 5] * q[iq + 5]
            + q[iq + 6] * q[iq + 6])
            .sqrt();
        (q[iq + 3] / n, q[iq + 4] / n, q[iq + 5] / n, q[iq + 6] / n)
    };
    let (x0, y0, z0, w0) = quat(q0);
    let (x1, y1, z1, w1) = quat(q1);
    let r0 = quat_to_matrix(x0, y0, z0, w0);
    let dp = r0.transpose()
        * Vector3::new(
            q1[iq] - q0[iq],
            q1[iq + 1] - q0[iq + 1],
            q1[iq + 2] - q0[iq + 2],
        );
    // d = conj(q0) ⊗ q1
    let mut dw = w0 * w1 + x0 * x1 + y0 * y1 + z0 * z1;
    let mut dv = Vector3::new(
        w0 * x1 - x0 * w1 - y0 * z1 + z0 * y1,
        w0 * y1 + x0 * z1 - y0 * w1 - z0 * x1,
        w0 * z1 - x0 * y1 + y0 * x1 - z0 * w1,
    );
    if dw < 0.0 {
        dw = -dw;
        dv = -dv;
    }
    let s = dv.norm();
    // ω = 2 atan2(|d_v|, d_w) d_v / |d_v|
    let w = if s > 1e-12 {
        dv * (2.0 * s.atan2(dw) / s)
    } else {
        dv * (2.0 / dw)
    };
    for k in 0..3 {
        v[iv + k] = dp[k];
        v[iv + 3 + k] = w[k];
    }
}

/// A random configuration inside the joint limits (uniform; a continuous joint,
/// or one without limits, in [−π, π]; a free base at the origin with a uniformly
/// random orientation), reproducible from `seed`.
pub fn random_configuration(model: &Model, seed: u64) -> DVector<f64> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    // splitmix64: a uniform number in [0, 1)
    let mut unit = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut q = model.neutral();
    for f in &model.free_joints {
        // Shoemake's uniform unit quaternion
        let (u1, u2, u3) = (unit(), unit(), unit());
        let tau = 2.0 * std::f64::consts::PI;
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        q[f.iq + 3] = a * (tau * u2).sin();
        q[f.iq + 4] = a * (tau * u2).cos();
        q[f.iq + 5] = b * (tau * u3).sin();
        q[f.iq + 6] = b * (tau * u3).cos();
    }
    for (d, iq, _) in model.dof_indices() {
        let dof = &model.dofs[d];
        let (lo, hi) = match (dof.limits.lower, dof.limits.upper) {
            (Some(lo), Some(hi)) if lo < hi && !dof.continuous => (lo, hi),
            _ => (-std::f64::consts::PI, std::f64::consts::PI),
        };
        q[iq] = lo + (hi - lo) * unit();
    }
    q
}

impl Model {
    /// The configuration with the named joints at the given positions and every
    /// other at [`Model::neutral`]. Keys are degrees of freedom (movable, non-mimic
    /// joints); an unknown name is an error naming it and the nearest known one.
    pub fn configuration_from_names<'a>(
        &self,
        values: impl IntoIterator<Item = (&'a str, f64)>,
    ) -> Result<DVector<f64>, NameError> {
        let mut q = self.neutral();
        for (name, x) in values {
            q[self.q_index(name)?] = x;
        }
        Ok(q)
    }
    /// Every degree of freedom's position in `q` by joint name, in engine order.
    pub fn positions_by_name(&self, q: &DVector<f64>) -> Result<Vec<(&str, f64)>, DimensionError> {
        DimensionError::check("q", self.nq, q.len())?;
        Ok(self
            .dof_indices()
            .map(|(d, iq, _)| (self.dofs[d].name.as_str(), q[iq]))
            .collect())
    }
}
