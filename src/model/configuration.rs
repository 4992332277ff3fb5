//! The configuration manifold: q ⊕ h v (the free joint's unit quaternion and
//! body-frame velocity, every other joint additive) and its rate q̇(q, v).
//!
//! A free base's q is `[p (world), quaternion (x, y, z, w)]` and its v is
//! `[v_lin, ω]` in the base's own frame (Pinocchio's free flyer, docs/theory.md
//! §"Floating base"); joints after it have q̇ = v.

use super::JointKind;
use super::Model;
use crate::spatial::{axis_angle, quat_to_matrix, sin_cos, skew};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Quaternion, UnitQuaternion, Vector3};

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

/// `q ⊕ v` (Pinocchio's `integrate`): a free joint moves along SE(3)'s
/// exponential by the body-frame twist `[v_lin; ω]`, `M ← M exp(v)` (p ← p + R V(ω)
/// v_lin, quaternion ← quaternion ⊗ exp(ω/2), docs/theory.md §"Derivatives"); every
/// other joint adds. Every joint through its own coordinates (`iq`, `iv`).
pub fn integrate(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let mut out = q.clone();
    for j in model.joints.iter().skip(1) {
        match j.kind {
            JointKind::Free => {
                let (iq, iv) = (j.iq, j.iv);
                let (r0, quat0) = base_rotation(q, iq);
                let lin = Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
                let w = Vector3::new(v[iv + 3], v[iv + 4], v[iv + 5]);
                let dp = r0 * so3_left_jacobian(&w) * lin;
                let dq = UnitQuaternion::from_scaled_axis(w);
                let q1 = quat0 * dq;
                for k in 0..3 {
                    out[iq + k] = q[iq + k] + dp[k];
                }
                let c = q1.as_ref().coords;
                for k in 0..4 {
                    out[iq + 3 + k] = c[k];
                }
            }
            // a mimic joint's iq/iv are its leader's: assigning twice is harmless
            _ => out[j.iq] = q[j.iq] + v[j.iv],
        }
    }
    Ok(out)
}

/// `q₁ ⊖ q₀` (Pinocchio's `difference`): the v with [`integrate`]`(q₀, v) = q₁` — a
/// free joint's `log(M₀⁻¹ M₁)` (the shorter rotation), every other joint `q₁ − q₀`.
pub fn difference(
    model: &Model,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q0", model.nq, q0.len())?;
    DimensionError::check("q1", model.nq, q1.len())?;
    let mut v = DVector::zeros(model.nv);
    for j in model.joints.iter().skip(1) {
        match j.kind {
            JointKind::Free => {
                let (lin, w) = free_log(q0, q1, j.iq);
                for k in 0..3 {
                    v[j.iv + k] = lin[k];
                    v[j.iv + 3 + k] = w[k];
                }
            }
            _ => v[j.iv] = q1[j.iq] - q0[j.iq],
        }
    }
    Ok(v)
}

/// The Jacobians of [`integrate`] (Pinocchio's `dIntegrate`, tangent spaces on both
/// sides): `(∂(q ⊕ v)/∂q, ∂(q ⊕ v)/∂v)`, nv × nv. A free joint's blocks (linear
/// first) are `Ad(exp(v)⁻¹)` and the right Jacobian `Jexp(v)` of SE(3)
/// (docs/theory.md §"Derivatives"); every other joint's entry is 1.
pub fn integrate_jacobians(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let (mut jq, mut jv) = (
        DMatrix::zeros(model.nv, model.nv),
        DMatrix::zeros(model.nv, model.nv),
    );
    for j in model.joints.iter().skip(1) {
        match j.kind {
            JointKind::Free => {
                let iv = j.iv;
                let lin = Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
                let w = Vector3::new(v[iv + 3], v[iv + 4], v[iv + 5]);
                jq.view_mut((iv, iv), (6, 6))
                    .copy_from(&exp_ad_inverse(&lin, &w));
                jv.view_mut((iv, iv), (6, 6))
                    .copy_from(&se3_right_jacobian(&lin, &w));
            }
            _ => {
                jq[(j.iv, j.iv)] = 1.0;
                jv[(j.iv, j.iv)] = 1.0;
            }
        }
    }
    Ok((jq, jv))
}

/// The Jacobians of [`difference`] (Pinocchio's `dDifference`):
/// `(∂(q₁ ⊖ q₀)/∂q₀, ∂(q₁ ⊖ q₀)/∂q₁)`, nv × nv. A free joint's blocks, with
/// `M = M₀⁻¹ M₁`: `−Jlog(M) Ad(M⁻¹)` and `Jlog(M)`, `Jlog = Jexp(log M)⁻¹`; every
/// other joint's entries are −1 and 1.
pub fn difference_jacobians(
    model: &Model,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DimensionError> {
    DimensionError::check("q0", model.nq, q0.len())?;
    DimensionError::check("q1", model.nq, q1.len())?;
    let (mut j0, mut j1) = (
        DMatrix::zeros(model.nv, model.nv),
        DMatrix::zeros(model.nv, model.nv),
    );
    for j in model.joints.iter().skip(1) {
        match j.kind {
            JointKind::Free => {
                let iv = j.iv;
                let (lin, w) = free_log(q0, q1, j.iq);
                let jr = se3_right_jacobian(&lin, &w);
                let jlog = jr.try_inverse().unwrap_or_else(Matrix6::identity);
                let ad = exp_ad_inverse(&lin, &w);
                j0.view_mut((iv, iv), (6, 6)).copy_from(&(-jlog * ad));
                j1.view_mut((iv, iv), (6, 6)).copy_from(&jlog);
            }
            _ => {
                j0[(j.iv, j.iv)] = -1.0;
                j1[(j.iv, j.iv)] = 1.0;
            }
        }
    }
    Ok((j0, j1))
}

/// A free joint's rotation and unit quaternion from `q[iq + 3..iq + 7]` (x, y, z, w),
/// normalised.
fn base_rotation(q: &DVector<f64>, iq: usize) -> (Matrix3<f64>, UnitQuaternion<f64>) {
    let uq = UnitQuaternion::from_quaternion(Quaternion::new(
        q[iq + 6],
        q[iq + 3],
        q[iq + 4],
        q[iq + 5],
    ));
    (*uq.to_rotation_matrix().matrix(), uq)
}

/// `log(M₀⁻¹ M₁)` of two free-joint poses at `q[iq..iq + 7]`: `(v_lin, ω)`.
fn free_log(q0: &DVector<f64>, q1: &DVector<f64>, iq: usize) -> (Vector3<f64>, Vector3<f64>) {
    let (r0, u0) = base_rotation(q0, iq);
    let (_, u1) = base_rotation(q1, iq);
    let dp = r0.transpose()
        * Vector3::new(
            q1[iq] - q0[iq],
            q1[iq + 1] - q0[iq + 1],
            q1[iq + 2] - q0[iq + 2],
        );
    // the shorter rotation: d and −d are one rotation
    let mut d = u0.inverse() * u1;
    if d.w < 0.0 {
        d = UnitQuaternion::new_unchecked(-d.into_inner());
    }
    let w = d.scaled_axis();
    let lin = so3_left_jacobian(&w)
        .try_inverse()
        .unwrap_or_else(Matrix3::identity)
        * dp;
    (lin, w)
}

/// `Ad(exp(ξ)⁻¹)` for the twist `ξ = [lin; w]` (linear first): with
/// `exp(ξ) = (R, p)`, `R = Exp(w)`, `p = V(w) lin`, it is `[Rᵀ, −Rᵀ p×; 0, Rᵀ]`.
fn exp_ad_inverse(lin: &Vector3<f64>, w: &Vector3<f64>) -> Matrix6<f64> {
    let r = *UnitQuaternion::from_scaled_axis(*w)
        .to_rotation_matrix()
        .matrix();
    let p = so3_left_jacobian(w) * lin;
    let rt = r.transpose();
    let mut ad = Matrix6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&rt);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-rt * skew(&p)));
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&rt);
    ad
}

/// SO(3)'s left Jacobian `V(ω) = 1 + (1 − cos θ)/θ² ω× + (θ − sin θ)/θ³ ω×²`
/// (p = V(ω) v of SE(3)'s exponential).
fn so3_left_jacobian(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < 1e-4 {
        (
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0,
        )
    } else {
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let k = skew(w);
    Matrix3::identity() + k * a + k * k * b
}

/// SE(3)'s right Jacobian at the twist `[ρ; φ]` (linear first): `exp(ξ + δ) =
/// exp(ξ) exp(Jr δ)`, `Jr(ξ) = Jl(−ξ)` with Barfoot's left Jacobian
/// `[J(φ), Q(ρ, φ); 0, J(φ)]` (Pinocchio's `Jexp6`).
fn se3_right_jacobian(rho: &Vector3<f64>, phi: &Vector3<f64>) -> Matrix6<f64> {
    let (rho, phi) = (-rho, -phi);
    let j = so3_left_jacobian(&phi);
    let t2 = phi.norm_squared();
    let t = t2.sqrt();
    let (c1, c2, c3) = if t < 1e-3 {
        (
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0,
            1.0 / 24.0 - t2 / 720.0 + t2 * t2 / 40320.0,
            1.0 / 120.0 - t2 / 2520.0,
        )
    } else {
        let (s, c) = t.sin_cos();
        (
            (t - s) / (t2 * t),
            (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2),
            (2.0 * t - 3.0 * s + t * c) / (2.0 * t2 * t2 * t),
        )
    };
    let (p, r) = (skew(&phi), skew(&rho));
    let q = r * 0.5
        + (p * r + r * p + p * r * p) * c1
        + (p * p * r + r * p * p - p * r * p * 3.0) * c2
        + (p * r * p * p + p * p * r * p) * c3;
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&j);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&q);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&j);
    out
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
