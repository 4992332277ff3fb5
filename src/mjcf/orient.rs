//! MJCF's orientation forms (`quat`, `axisangle`, `euler`, `xyaxes`, `zaxis`) to a
//! unit quaternion, as MuJoCo's compiler resolves them (docs/theory.md §"MJCF
//! import"): w-first, normalised; angles in the compiler's unit.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// The quaternion of `[w, x, y, z]`, normalised (None for a zero one).
pub(crate) fn quat_wxyz(q: [f64; 4]) -> Option<UnitQuaternion<f64>> {
    let q = Quaternion::new(q[0], q[1], q[2], q[3]);
    let n = q.norm();
    (n > 0.0 && n.is_finite()).then(|| UnitQuaternion::new_unchecked(q / n))
}

/// Rotation by `angle` (rad) about `axis` (any length but zero): MuJoCo's
/// `mju_axisAngle2Quat`.
pub(crate) fn axis_angle(axis: Vector3<f64>, angle: f64) -> Option<UnitQuaternion<f64>> {
    let n = axis.norm();
    if !(n > 0.0 && n.is_finite()) {
        return None;
    }
    let (s, c) = (angle / 2.0).sin_cos();
    let a = axis / n * s;
    Some(UnitQuaternion::new_unchecked(Quaternion::new(
        c, a.x, a.y, a.z,
    )))
}

/// Euler angles (rad) in MuJoCo's `eulerseq`: lower-case letters rotate about the
/// moving axes (post-multiplied), upper-case about the fixed ones (pre-multiplied).
pub(crate) fn euler(angles: [f64; 3], seq: &[u8; 3]) -> UnitQuaternion<f64> {
    let mut q = Quaternion::new(1.0, 0.0, 0.0, 0.0);
    for (a, &c) in angles.iter().zip(seq) {
        let (s, co) = (a / 2.0).sin_cos();
        let r = match c.to_ascii_lowercase() {
            b'x' => Quaternion::new(co, s, 0.0, 0.0),
            b'y' => Quaternion::new(co, 0.0, s, 0.0),
            _ => Quaternion::new(co, 0.0, 0.0, s),
        };
        q = if c.is_ascii_lowercase() { q * r } else { r * q };
    }
    UnitQuaternion::new_normalize(q)
}

/// The frame whose x axis is `x` and whose y axis is `y` made orthogonal to it
/// (MuJoCo's `xyaxes`); None when degenerate.
pub(crate) fn xy_axes(x: Vector3<f64>, y: Vector3<f64>) -> Option<UnitQuaternion<f64>> {
    let x = x.try_normalize(0.0)?;
    let y = (y - x * x.dot(&y)).try_normalize(0.0)?;
    let z = x.cross(&y).try_normalize(0.0)?;
    let m = Matrix3::from_columns(&[x, y, z]);
    Some(UnitQuaternion::from_rotation_matrix(
        &nalgebra::Rotation3::from_matrix_unchecked(m),
    ))
}

/// The shortest rotation taking (0, 0, 1) to `z` (MuJoCo's `mjuu_z2quat`); None for a
/// zero vector.
pub(crate) fn z_axis(z: Vector3<f64>) -> Option<UnitQuaternion<f64>> {
    let v = z.try_normalize(0.0)?;
    let mut axis = Vector3::z().cross(&v);
    let s = axis.norm();
    if s < 1e-10 {
        axis = Vector3::x();
    } else {
        axis /= s;
    }
    let ang = s.atan2(v.z);
    axis_angle(axis, ang)
}
