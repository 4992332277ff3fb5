//! Whether two convex members of a pair are apart without asking parry: the
//! gap along last step's separating axis, and the conservative advancement
//! from the last time that gap was known (src/contact/pairs/mod.rs).

use super::super::shapes::{from_pvec, to_pvec};
use super::Member;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// The gap of convex members `a` at `wa` and `b` at `wb` along the unit
/// axis `u` (a's frame, from a toward b; zero: not known, −∞): min over b
/// of u·x − max over a of u·x (two support points), a lower bound of their
/// distance when positive.
#[inline]
pub(crate) fn apart_along(
    u: &Vector3<f64>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
) -> f64 {
    if u.x == 0.0 && u.y == 0.0 && u.z == 0.0 {
        return f64::NEG_INFINITY;
    }
    let (Some(sa), Some(sb)) = (
        a.shape.shape.as_support_map(),
        b.shape.shape.as_support_map(),
    ) else {
        return f64::NEG_INFINITY;
    };
    // b in a's frame: x = R p + t
    let a_m_b = wa.inverse().compose(wb);
    let top_a = u.dot(&from_pvec(sa.local_support_point(to_pvec(u))));
    let d = a_m_b.rot.transpose() * (-u);
    let low_b = u.dot(&a_m_b.act_point(&from_pvec(sb.local_support_point(to_pvec(&d)))));
    low_b - top_a
}

/// Whether two shapes separated by a plane with a gap g (> the margin) at
/// the world poses `then` are still more than `margin` apart at `wa`, `wb`
/// without a support query: no point of a shape moved farther than D =
/// |w·c − w₀·c| + ‖R − R₀‖_F |h| (c, h its box's centre and half extents in
/// its frame: every point lies within |h| of c), so across that plane the
/// shapes are still g − D_a − D_b apart (conservative advancement).
pub(crate) fn still_apart(
    then: Option<&(f64, Se3<f64>, Se3<f64>)>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
) -> bool {
    let Some((gap, wa0, wb0)) = then else {
        return false;
    };
    let moved = |m: &Member, w0: &Se3<f64>, w: &Se3<f64>| {
        (w.act_point(&m.shape.mid) - w0.act_point(&m.shape.mid)).norm()
            + (w.rot - w0.rot).norm() * m.shape.half.norm()
    };
    gap - moved(a, wa0, wa) - moved(b, wb0, wb) > margin
}
