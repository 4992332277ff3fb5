//! A ball on a box or a cylinder in closed form: the ball's centre projected
//! on the other shape (a clamp to the box; the cylinder's radial and axial
//! clamp), the normal from the projection to the centre (reversed with the
//! centre inside), the gap the signed distance less the radius: one point.
//!
//! This is parry's own generator for these pairs
//! (`contact_manifold_convex_ball`: `project_local_point_and_get_feature`,
//! the same case rules, ties and feature ids, redone here on the engine's
//! rotation matrices) without its quaternion pose (`to_pose`), the
//! dispatcher's `dyn` downcasts, `TrackedContact` and [`super::push_points`]:
//! the same numbers up to rounding (about 1e-16 m: the centre is placed by
//! Rᵀ(c − t) here, by a quaternion's inverse there). The projection is exact,
//! so no depth bound ([`super::overlap_bound`]) is needed.

use super::super::shapes::PairShape;
use super::Raw;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::query::ContactManifold;
use parry3d_f64::shape::{FeatureId, PackedFeatureId};

/// parry's `math::DEFAULT_EPSILON` (f64::EPSILON): its tolerance for a point
/// on a box's face and for a point on a cylinder's axis.
const EPS: f64 = f64::EPSILON;

/// The shape a ball meets: a box (half extents) or a cylinder (parry's: axis
/// y; half height, radius).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Solid {
    /// A box of these half extents.
    Cuboid(Vector3<f64>),
    /// A cylinder: half height, radius.
    Cylinder(f64, f64),
}

/// `Some(ball is a)` when one shape of the pair is a ball and the other a
/// box or a cylinder (the pairs [`ball_points`] takes).
#[inline]
pub(crate) fn kind(a: &PairShape, b: &PairShape) -> Option<bool> {
    let ball = |s: &PairShape| matches!(s.round, Some((p0, p1, _)) if p0 == p1);
    let solid = |s: &PairShape| s.cuboid.is_some() || s.cylinder.is_some();
    if ball(a) && solid(b) {
        Some(true)
    } else if solid(a) && ball(b) {
        Some(false)
    } else {
        None
    }
}

/// The projection of local point `p` on `s`'s surface: whether `p` is
/// inside, the projection, and its feature (parry's
/// `project_local_point_and_get_feature` for a `Cuboid` or a `Cylinder`).
pub(crate) fn project(s: &Solid, p: &Vector3<f64>) -> (bool, Vector3<f64>, FeatureId) {
    match *s {
        Solid::Cuboid(h) => project_box(&h, p),
        Solid::Cylinder(hh, r) => {
            let (inside, q) = project_cylinder(hh, r, p);
            (inside, q, FeatureId::Unknown)
        }
    }
}

/// parry's `Aabb::project_local_point_and_get_feature` of the box [−h, h].
fn project_box(h: &Vector3<f64>, p: &Vector3<f64>) -> (bool, Vector3<f64>, FeatureId) {
    // outside: the clamp (shift = max(−h − p, 0) − max(p − h, 0))
    let shift = Vector3::from_fn(|i, _| (-h[i] - p[i]).max(0.0) - (p[i] - h[i]).max(0.0));
    let (inside, q, shift) = if shift != Vector3::zeros() {
        (false, p + shift, shift)
    } else {
        // inside: to the nearest face (ties: x, then y, then z; a zero
        // coordinate's side is its sign bit's)
        let sgn = Vector3::from_fn(|i, _| 1.0f64.copysign(p[i]));
        let diff = Vector3::from_fn(|i, _| h[i] - sgn[i] * p[i]);
        let mut shift = Vector3::zeros();
        let i = if diff.x <= diff.y && diff.x <= diff.z {
            0
        } else if diff.y <= diff.x && diff.y <= diff.z {
            1
        } else {
            2
        };
        shift[i] = diff[i] * sgn[i];
        (true, p + shift, shift)
    };
    let zero = |i: usize| shift[i] == 0.0;
    let nzero = (0..3).filter(|&i| zero(i)).count();
    let last_zero = (0..3).rev().find(|&i| zero(i)).unwrap_or(0);
    let last_not_zero = (0..3).rev().find(|&i| !zero(i)).unwrap_or(0);
    let fid = if nzero == 3 {
        // on the surface already
        let mut f = FeatureId::Unknown;
        for i in 0..3 {
            if q[i] > h[i] - EPS {
                f = FeatureId::Face(i as u32);
                break;
            }
            if q[i] <= -h[i] + EPS {
                f = FeatureId::Face(i as u32 + 3);
                break;
            }
        }
        f
    } else if nzero == 2 {
        let i = last_not_zero;
        FeatureId::Face(if q[i] < 0.0 { i + 3 } else { i } as u32)
    } else {
        let id = (0..3).fold(0u32, |id, i| id | (u32::from(q[i] < 0.0) << i));
        if nzero == 0 {
            FeatureId::Vertex(id)
        } else {
            FeatureId::Edge((id << 2) | last_zero as u32)
        }
    };
    (inside, q, fid)
}

/// parry's `Cylinder::project_local_point` (not solid) of the cylinder of
/// half height `hh` and radius `r` about y: whether `p` is inside, and its
/// projection.
fn project_cylinder(hh: f64, r: f64, p: &Vector3<f64>) -> (bool, Vector3<f64>) {
    // the radial direction (x where p is on the axis), the distance from it
    // (glam's normalize_and_length: times the reciprocal)
    let rho = (p.x * p.x + p.z * p.z).sqrt();
    let (dx, dz) = if rho <= EPS {
        (1.0, 0.0)
    } else {
        let inv = 1.0 / rho;
        (p.x * inv, p.z * inv)
    };
    let rim = |y: f64| Vector3::new(dx * r, y, dz * r);
    if p.y >= -hh && p.y <= hh && rho <= r {
        let (top, bottom, side) = (hh - p.y, p.y + hh, r - rho);
        let q = if top < bottom && top < side {
            Vector3::new(p.x, hh, p.z)
        } else if bottom < top && bottom < side {
            Vector3::new(p.x, -hh, p.z)
        } else {
            rim(p.y)
        };
        (true, q)
    } else if p.y > hh || p.y < -hh {
        // over a cap: onto the cap, or its rim
        let y = if p.y > hh { hh } else { -hh };
        let q = if rho <= r {
            Vector3::new(p.x, y, p.z)
        } else {
            rim(y)
        };
        (false, q)
    } else {
        (false, rim(p.y))
    }
}

/// The contact of a ball and a box or a cylinder (`ball_is_a`: the ball is
/// the pair's a; [`kind`]) within `margin`: its point appended to `raw` (the
/// normal from b toward a), the pair's one manifold left without points and
/// its normal (a's frame, from a toward b: the pair's axis) set, as parry's
/// generator leaves it. False (nothing touched) for another pair.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn ball_points(
    a: &PairShape,
    b: &PairShape,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    ball_is_a: bool,
    margin: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    raw: &mut Vec<Raw>,
) -> bool {
    let (ball, other, wball, wo) = if ball_is_a {
        (a, b, wa, wb)
    } else {
        (b, a, wb, wa)
    };
    let (Some((centre, _, radius)), Some(solid)) = (ball.round, solid_of(other)) else {
        return false;
    };
    raw.clear();
    if manifolds.len() != 1 {
        manifolds.clear();
        manifolds.push(ContactManifold::new());
    }
    let man = &mut manifolds[0];
    man.points.clear();
    // the centre in the other shape's frame
    let c_w = wball.act_point(&centre);
    let c = wo.inv_act_point(&c_w);
    let (inside, q, fid) = project(&solid, &c);
    let d = c - q;
    let mut dist = d.norm();
    // the normal from the surface toward the centre; a centre on the
    // surface: from the shape's origin (parry's rule), else y
    let mut n = if dist == 0.0 {
        c.try_normalize(0.0).unwrap_or_else(Vector3::y)
    } else {
        d / dist
    };
    if inside {
        n = -n;
        dist = -dist;
    }
    let n_w = wo.rot * n;
    // parry's local normal of a (from a toward b)
    let axis = if ball_is_a {
        wball.rot.transpose() * (-n_w)
    } else {
        n
    };
    man.local_n1 = super::super::shapes::to_pvec(&axis);
    let gap = dist - radius;
    if !(gap <= margin) {
        return true;
    }
    let p_other = wo.act_point(&q);
    let p_ball = c_w - n_w * radius;
    let (fo, fb) = (PackedFeatureId::from(fid).0, PackedFeatureId::face(0).0);
    // push_points' key of parry's manifold (its fid1 a's feature)
    let (f1, f2) = if ball_is_a { (fb, fo) } else { (fo, fb) };
    raw.push(Raw {
        point: (p_other + p_ball) * 0.5,
        normal: if ball_is_a { n_w } else { -n_w },
        gap,
        key: ((f1 as u64) << 20) ^ (f2 as u64),
    });
    true
}

/// The [`Solid`] of a box or a cylinder.
fn solid_of(s: &PairShape) -> Option<Solid> {
    match (s.cuboid, s.cylinder) {
        (Some(h), _) => Some(Solid::Cuboid(h)),
        (_, Some((hh, r))) => Some(Solid::Cylinder(hh, r)),
        _ => None,
    }
}
