//! Closed-form contact of spheres and capsules (the pairs of MuJoCo's
//! models' limbs): sphere–sphere, sphere–capsule and capsule–capsule by the
//! closest points of their centres and axes, then one sphere–sphere test,
//! as MuJoCo's `mjraw_CapsuleCapsule` (docs/theory.md §"Closed-form
//! sphere and capsule pairs"). No GJK, no quaternion: parry's generic
//! manifolds cost about ten times as much on these shapes.

use super::super::shapes::PairShape;
use super::Raw;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// The key bit of a closed-form point (its index below it): neither a key
/// of parry's features (bits 0–59) nor of the face path (bit 62).
pub(crate) const PRIM_KEY: u64 = 1 << 61;

/// Axes closer to parallel than this (sin² of their angle) touch also at
/// the ends of their common stretch, besides their closest pair: a capsule
/// lying along another stands on both ends, not on whichever end the
/// rounding picks (MuJoCo adds them only at exactly parallel axes).
const PARALLEL_SIN2: f64 = 1e-6;

/// A sphere or capsule in the world: its axis' ends (equal for a sphere)
/// and radius.
#[derive(Clone, Copy, Debug)]
pub struct Round {
    /// One end of the axis (world, m).
    pub p0: Vector3<f64>,
    /// The other end (= `p0` for a sphere).
    pub p1: Vector3<f64>,
    /// The radius (m).
    pub r: f64,
    /// The axis' length |p1 − p0| (0 for a sphere).
    pub len: f64,
}

impl Round {
    /// The sphere or capsule `s` placed at `w`; None for another shape.
    pub(crate) fn of(s: &PairShape, w: &Se3<f64>) -> Option<Self> {
        let (p0, p1, r) = s.round?;
        let (p0, p1) = (w.act_point(&p0), w.act_point(&p1));
        Some(Self {
            p0,
            p1,
            r,
            len: (p1 - p0).norm_squared().sqrt(),
        })
    }
}

/// The contact points of `a` at `wa` and `b` at `wb` within `margin` when
/// both are spheres or capsules (`raw` cleared, then filled; true), else
/// false and `raw` untouched.
pub(crate) fn round_points(
    a: &PairShape,
    b: &PairShape,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
    raw: &mut Vec<Raw>,
) -> bool {
    let (Some(ra), Some(rb)) = (Round::of(a, wa), Round::of(b, wb)) else {
        return false;
    };
    round_points_at(&ra, &rb, margin, raw);
    true
}

/// The contact points of the spheres or capsules `ra` and `rb` (placed)
/// within `margin` (`raw` cleared, then filled): [`round_points`] of shapes
/// already placed (a pair's members placed once a detection, not once a pair).
pub(crate) fn round_points_at(ra: &Round, rb: &Round, margin: f64, raw: &mut Vec<Raw>) {
    raw.clear();
    // their bounding spheres (about the axes' middles) apart by more than
    // the margin: no point (no division)
    let reach = 0.5 * (ra.len + rb.len) + ra.r + rb.r + margin;
    if (ra.p0 + ra.p1 - rb.p0 - rb.p1).norm_squared() > 4.0 * reach * reach {
        return;
    }
    let (da, db) = (ra.p1 - ra.p0, rb.p1 - rb.p0);
    let (aa, bb, ab) = (da.norm_squared(), db.norm_squared(), da.dot(&db));
    let (pa, pb) = closest(&ra.p0, &da, aa, &rb.p0, &db, bb, ab);
    spheres(&pa, ra.r, &pb, rb.r, margin, PRIM_KEY, raw);
    let cross2 = aa * bb - ab * ab;
    if aa > 0.0 && bb > 0.0 && cross2 <= PARALLEL_SIN2 * aa * bb {
        // (nearly) parallel axes: also the ends of their common stretch
        // along a (the closest pair, found above, may lie between them)
        let t = |p: &Vector3<f64>| (p - ra.p0).dot(&da) / aa;
        let (t0, t1) = (t(&rb.p0), t(&rb.p1));
        let (lo, hi) = (t0.min(t1).max(0.0), t0.max(t1).min(1.0));
        if hi > lo {
            for (k, s) in [lo, hi].into_iter().enumerate() {
                let ea = ra.p0 + da * s;
                if (ea - pa).norm_squared() < 1e-18 {
                    continue;
                }
                let eb = on_segment(&rb.p0, &db, bb, &ea);
                spheres(&ea, ra.r, &eb, rb.r, margin, PRIM_KEY | (k as u64 + 1), raw);
            }
        }
    }
}

/// The point of segment p0 + s d (s in [0, 1], |d|² = `dd`) nearest `x`.
fn on_segment(p0: &Vector3<f64>, d: &Vector3<f64>, dd: f64, x: &Vector3<f64>) -> Vector3<f64> {
    if dd <= 0.0 {
        return *p0;
    }
    p0 + d * ((x - p0).dot(d) / dd).clamp(0.0, 1.0)
}

/// The closest points of segments p + s d and q + t e (s, t in [0, 1];
/// `dd` = |d|², `ee` = |e|², `de` = d·e), Ericson's clamped solution
/// (Real-Time Collision Detection §5.1.9).
fn closest(
    p: &Vector3<f64>,
    d: &Vector3<f64>,
    dd: f64,
    q: &Vector3<f64>,
    e: &Vector3<f64>,
    ee: f64,
    de: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let r = p - q;
    let f = e.dot(&r);
    let (s, t);
    if dd <= 0.0 && ee <= 0.0 {
        return (*p, *q);
    }
    if dd <= 0.0 {
        s = 0.0;
        t = (f / ee).clamp(0.0, 1.0);
    } else {
        let c = d.dot(&r);
        if ee <= 0.0 {
            t = 0.0;
            s = (-c / dd).clamp(0.0, 1.0);
        } else {
            let denom = dd * ee - de * de;
            let s0 = if denom > 0.0 {
                ((de * f - c * ee) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (de * s0 + f) / ee;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / dd).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((de - c) / dd).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    (p + d * s, q + e * t)
}

/// The contact of spheres (centre `ca`, radius `ra`) of a and (`cb`, `rb`)
/// of b, pushed to `raw` when within `margin`: the normal from b toward a,
/// the point midway between the two surfaces along it.
fn spheres(
    ca: &Vector3<f64>,
    ra: f64,
    cb: &Vector3<f64>,
    rb: f64,
    margin: f64,
    key: u64,
    raw: &mut Vec<Raw>,
) {
    let d = ca - cb;
    let dist = d.norm();
    let gap = dist - ra - rb;
    if !(gap <= margin) {
        return;
    }
    // coincident centres: any direction is a normal (MuJoCo takes x)
    let normal = if dist > 1e-12 { d / dist } else { Vector3::z() };
    let point = (ca - normal * ra + cb + normal * rb) * 0.5;
    raw.push(Raw {
        point,
        normal,
        gap,
        key,
    });
}
