//! A loop constraint's residual φ (the position target's and the projection's,
//! src/sim/loops/{mod,project}.rs) and the rotation log it uses.

use crate::model::{Constraint, ConstraintKind, Data};
use nalgebra::Vector3;

/// The residual φ of a constraint's rows (world axes; its first `c.rows()`
/// entries) at the state whose forward kinematics `data.o_m_i` holds: a
/// `point`'s p₁ − p₂, a `frame`'s also the rotation error R₁R₂ᵀ's axis · angle,
/// a `joint`'s q₁ − ratio · q₂ − offset.
pub(in crate::sim) fn residual(c: &Constraint, data: &Data, q: &[f64]) -> [f64; 6] {
    let mut phi = [0.0; 6];
    match &c.kind {
        ConstraintKind::Joint {
            q1,
            second,
            ratio,
            offset,
            ..
        } => phi[0] = q[*q1] - second.map_or(0.0, |(q2, _)| ratio * q[q2]) - offset,
        kind => {
            let m1 = data.o_m_i[c.a.body].compose(&c.a.local);
            let m2 = data.o_m_i[c.b.body].compose(&c.b.local);
            let d = m1.trans - m2.trans;
            phi[..3].copy_from_slice(d.as_slice());
            if *kind == ConstraintKind::Frame {
                let e = rotation_vector(&(m1.rot * m2.rot.transpose()));
                phi[3..].copy_from_slice(e.as_slice());
            }
        }
    }
    phi
}

/// The rotation vector (axis · angle, the log) of a rotation matrix R, exact to
/// rounding near the identity, where a loop's residual lives: w = ½(R − Rᵀ)^∨ =
/// sin θ · axis, θ = atan2(|w|, (tr R − 1)/2), e = w θ / |w|. (The arc cosine of
/// (tr R − 1)/2 loses half the digits there, θ ≈ 1e-8 read as 0 or 2e-8, and is
/// NaN once rounding puts the trace above 3: a weld's angular residual read so
/// opened it by 1e-5 m a step in MJCF's `equalities.xml`.) Beyond π/2 the
/// axis is taken from nalgebra's log.
pub(in crate::sim) fn rotation_vector(r: &nalgebra::Matrix3<f64>) -> Vector3<f64> {
    let w = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * 0.5;
    let (s, c) = (w.norm(), (r.trace() - 1.0) * 0.5);
    if c > 0.0 {
        if s > 0.0 {
            w * (s.atan2(c) / s)
        } else {
            w
        }
    } else {
        nalgebra::Rotation3::from_matrix_unchecked(*r).scaled_axis()
    }
}
