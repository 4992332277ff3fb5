//! SE(3) and SO(3) maps behind [`super::configuration`]: exponential,
//! logarithm, their Jacobians, and every multi-coordinate joint seen as a
//! subgroup of SE(3) (docs/theory.md §"Spherical, planar and floating joints").
//!
//! A free joint is SE(3) itself (tangent `[v; ω]`, linear first); a spherical
//! joint is SO(3) (tangent ω: rows 3..6 of SE(3)'s); a planar joint is SE(2),
//! the rotations about z and translations in xy (tangent `[vx, vy, ω]`: rows
//! 0, 1, 5). Each subgroup is closed under SE(3)'s exponential, logarithm and
//! adjoint, so its maps are SE(3)'s restricted to its rows and columns.

use super::JointKind;
use crate::spatial::skew;
use nalgebra::{DVector, Matrix3, Matrix6, Quaternion, UnitQuaternion, Vector3, Vector6};

/// A joint's rows of SE(3)'s tangent `[v; ω]` (linear first), `None` for a 1-DoF joint.
pub(crate) fn tangent_rows(kind: &JointKind) -> Option<&'static [usize]> {
    match kind {
        JointKind::Free => Some(&[0, 1, 2, 3, 4, 5]),
        JointKind::Spherical => Some(&[3, 4, 5]),
        JointKind::Planar => Some(&[0, 1, 5]),
        _ => None,
    }
}

/// A multi-coordinate joint's q at `q[iq..]` as an SE(3) element (position, unit
/// quaternion; the quaternion normalised).
pub(crate) fn joint_pose(
    kind: &JointKind,
    q: &DVector<f64>,
    iq: usize,
) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let quat = |at: usize| {
        UnitQuaternion::from_quaternion(Quaternion::new(
            q[at + 3],
            q[at],
            q[at + 1],
            q[at + 2],
        ))
    };
    match kind {
        JointKind::Free => (Vector3::new(q[iq], q[iq + 1], q[iq + 2]), quat(iq + 3)),
        JointKind::Spherical => (Vector3::zeros(), quat(iq)),
        _ => (
            Vector3::new(q[iq], q[iq + 1], 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[iq + 2]),
        ),
    }
}

/// A joint's tangent `v[iv..]` as SE(3)'s `(v, ω)`.
pub(crate) fn joint_twist(
    kind: &JointKind,
    v: &DVector<f64>,
    iv: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let mut x = Vector6::zeros();
    for (k, &r) in tangent_rows(kind).unwrap_or(&[]).iter().enumerate() {
        x[r] = v[iv + k];
    }
    (x.fixed_rows::<3>(0).into(), x.fixed_rows::<3>(3).into())
}

/// `M exp([lin; w])` for M = (p, u): `(p + R V(w) lin, u ⊗ exp(w/2))`.
pub(crate) fn se3_integrate(
    p: &Vector3<f64>,
    u: &UnitQuaternion<f64>,
    lin: &Vector3<f64>,
    w: &Vector3<f64>,
) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let dp = u * (so3_left_jacobian(w) * lin);
    (p + dp, u * UnitQuaternion::from_scaled_axis(*w))
}

/// `log(M₀⁻¹ M₁)`: `(v_lin, ω)`, the shorter rotation.
pub(crate) fn se3_log(
    p0: &Vector3<f64>,
    u0: &UnitQuaternion<f64>,
    p1: &Vector3<f64>,
    u1: &UnitQuaternion<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let dp = u0.inverse() * (p1 - p0);
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
pub(crate) fn exp_ad_inverse(lin: &Vector3<f64>, w: &Vector3<f64>) -> Matrix6<f64> {
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
pub(crate) fn so3_left_jacobian(w: &Vector3<f64>) -> Matrix3<f64> {
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
pub(crate) fn se3_right_jacobian(rho: &Vector3<f64>, phi: &Vector3<f64>) -> Matrix6<f64> {
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
