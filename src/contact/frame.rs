//! A contact point's frame: the tangents of its normal (shared by the narrow
//! phase, the pair pipeline and the constraint rows).

use nalgebra::Vector3;

/// Two unit tangents completing the unit normal n to a right-handed frame
/// (t₁, t₂, n); x and y for n = +z. (Always inlined: the contact rows' hot
/// loops, whose inlining otherwise follows the crate's codegen split.)
#[inline(always)]
pub fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    if n.x == 0.0 && n.y == 0.0 && n.z > 0.0 {
        return (Vector3::x(), Vector3::y());
    }
    // the axis least aligned with n
    let e = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vector3::x()
    } else if n.y.abs() <= n.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let t1 = n.cross(&e).normalize();
    (t1, n.cross(&t1))
}
