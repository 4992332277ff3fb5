//! Whether two convex members of a pair are apart without asking parry: the
//! gap along last step's separating axis, and the conservative advancement
//! from the last time that gap was known (src/contact/pairs/mod.rs).

use super::super::shapes::{from_pvec, to_pvec};
use super::Member;
use crate::spatial::Se3;
use nalgebra::{Matrix3, Vector3};

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
    // (a shape that is not a support map: not known)
    let Some(sa) = support(a, u) else {
        return f64::NEG_INFINITY;
    };
    // b in a's frame: x = R p + t
    let a_m_b = wa.inverse().compose(wb);
    let d = a_m_b.rot.transpose() * (-u);
    let Some(sb) = support(b, &d) else {
        return f64::NEG_INFINITY;
    };
    let top_a = u.dot(&sa);
    let low_b = u.dot(&a_m_b.act_point(&sb));
    low_b - top_a
}

/// Member `m`'s support point along `v` (its frame; None: not a support
/// map) from the numbers kept beside it, not the shape behind its pointer
/// (a cache miss): parry's `local_support_point`s, the same operations in
/// the same order (glam's normalize: v · (1 / √((x² + y²) + z²))):
/// - a box, half extents h: sign(v) ⊙ h (h_i with v_i's sign);
/// - a cylinder along y, half height e, radius r: (x, 0, z) normalized
///   (zero when that is not finite and positive) times r, y = ±e by v_y;
/// - a ball of radius r: v normalized times r;
///
/// else parry's.
#[inline(always)]
fn support(m: &Member, v: &Vector3<f64>) -> Option<Vector3<f64>> {
    if let Some(h) = &m.shape.cuboid {
        return Some(Vector3::new(
            h.x.copysign(v.x),
            h.y.copysign(v.y),
            h.z.copysign(v.z),
        ));
    }
    // 1 / |(x, y, z)|, as glam's length_recip
    let recip = |x: f64, y: f64, z: f64| 1.0 / ((x * x + y * y) + z * z).sqrt();
    if let Some((e, r)) = m.shape.cylinder {
        let k = recip(v.x, 0.0, v.z);
        let (x, z) = if k.is_finite() && k > 0.0 {
            (v.x * k, v.z * k)
        } else {
            (0.0, 0.0)
        };
        return Some(Vector3::new(x * r, e.copysign(v.y), z * r));
    }
    if let Some((_, _, r)) = m.shape.round {
        if m.shape.shape.as_ball().is_some() {
            let k = recip(v.x, v.y, v.z);
            return Some(Vector3::new((v.x * k) * r, (v.y * k) * r, (v.z * k) * r));
        }
    }
    let s = m.shape.shape.as_support_map()?;
    Some(from_pvec(s.local_support_point(to_pvec(v))))
}

/// A pair found apart by more than the margin: the gap g along the
/// separating plane, and each member's box centre (world) and rotation then.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Apart {
    pub(crate) gap: f64,
    pub(crate) ca: Vector3<f64>,
    pub(crate) ra: Matrix3<f64>,
    pub(crate) cb: Vector3<f64>,
    pub(crate) rb: Matrix3<f64>,
}

/// A member now: its box centre `c` (world; w·c₀ for its box's centre c₀ in
/// its frame), its pose `w` and its box's |h| (half extents).
pub(crate) type Now<'a> = (&'a Vector3<f64>, &'a Se3<f64>, f64);

/// Whether two shapes separated by a plane with a gap g (> the margin) at
/// the poses of `then` are still more than `margin` apart now (`a`, `b`)
/// without a support query: no point of a shape moved farther than D =
/// |w·c₀ − w₀·c₀| + ‖R − R₀‖_F |h| (c₀, h its box's centre and half extents
/// in its frame: every point lies within |h| of c₀), so across that plane the
/// shapes are still g − D_a − D_b apart (conservative advancement).
#[inline(always)]
pub(crate) fn still_apart_at(then: Option<&Apart>, a: Now, b: Now, margin: f64) -> bool {
    let Some(t) = then else {
        return false;
    };
    let moved = |(c, w, h): Now, c0: &Vector3<f64>, r0: &Matrix3<f64>| {
        (c - c0).norm() + (w.rot - r0).norm() * h
    };
    t.gap - moved(a, &t.ca, &t.ra) - moved(b, &t.cb, &t.rb) > margin
}

/// [`still_apart_at`] of members `a`, `b` at the world poses `wa`, `wb`,
/// apart by `then` = (g, their poses then) (its box centres computed here).
pub(crate) fn still_apart(
    then: Option<&(f64, Se3<f64>, Se3<f64>)>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
) -> bool {
    let then = then.map(|(gap, wa0, wb0)| Apart {
        gap: *gap,
        ca: wa0.act_point(&a.shape.mid),
        ra: wa0.rot,
        cb: wb0.act_point(&b.shape.mid),
        rb: wb0.rot,
    });
    let (ca, cb) = (wa.act_point(&a.shape.mid), wb.act_point(&b.shape.mid));
    let now_a = (&ca, wa, a.shape.half.norm());
    let now_b = (&cb, wb, b.shape.half.norm());
    still_apart_at(then.as_ref(), now_a, now_b, margin)
}
