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
struct Round {
    p0: Vector3<f64>,
    p1: Vector3<f64>,
    r: f64,
}

impl Round {
    fn of(s: &PairShape, w: &Se3<f64>) -> Option<Self> {
        let (p0, p1, r) = s.round?;
        Some(Self {
            p0: w.act_point(&p0),
            p1: w.act_point(&p1),
            r,
        })
    }
}

/// The contact points of `a` at `wa` and `b` at `wb` within `margin` when
/// both are spheres or capsules (`raw` cleared, then filled; true), else
/// false and `raw` untouched.
pub(super) fn round_points(
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
    raw.clear();
    let (da, db) = (ra.p1 - ra.p0, rb.p1 - rb.p0);
    let (aa, bb, ab) = (da.norm_squared(), db.norm_squared(), da.dot(&db));
    // their bounding spheres (about the axes' middles) apart by more than
    // the margin: no point (no division, no root)
    let reach = 0.5 * (aa.sqrt() + bb.sqrt()) + ra.r + rb.r + margin;
    if (ra.p0 + ra.p1 - rb.p0 - rb.p1).norm_squared() > 4.0 * reach * reach {
        return true;
    }
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
    true
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit};
    use parry3d_f64::shape::SharedShape;

    fn ball(r: f64) -> PairShape {
        PairShape::new(SharedShape::ball(r), Se3::identity(), true)
    }

    fn capsule(half: f64, r: f64) -> PairShape {
        PairShape::new(SharedShape::capsule_z(half, r), Se3::identity(), true)
    }

    /// The gap of two spheres or capsules by brute force: the distance of
    /// their axes minimised by nested ternary searches (the distance from a
    /// point moving along one segment to the other segment is convex in
    /// its parameter), less both radii.
    fn reference_gap(a: &PairShape, b: &PairShape, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
        let (ra, rb) = (Round::of(a, wa).unwrap(), Round::of(b, wb).unwrap());
        let ternary = |f: &dyn Fn(f64) -> f64| {
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for _ in 0..100 {
                let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
                if f(m1) <= f(m2) {
                    hi = m2;
                } else {
                    lo = m1;
                }
            }
            f(0.5 * (lo + hi))
        };
        let to_b = |s: f64| {
            let x = ra.p0 + (ra.p1 - ra.p0) * s;
            ternary(&|t: f64| (x - (rb.p0 + (rb.p1 - rb.p0) * t)).norm())
        };
        ternary(&to_b) - ra.r - rb.r
    }

    #[test]
    fn sphere_sphere_is_the_closed_form() {
        let (a, b) = (ball(0.1), ball(0.2));
        let wa = Se3::new(nalgebra::Matrix3::identity(), Vector3::new(0.0, 0.0, 0.29));
        let wb = Se3::identity();
        let mut raw = Vec::new();
        assert!(round_points(&a, &b, &wa, &wb, 0.005, &mut raw));
        assert_eq!(raw.len(), 1);
        let r = raw[0];
        assert!((r.gap + 0.01).abs() < 1e-15, "{}", r.gap);
        assert!((r.normal - Vector3::z()).norm() < 1e-15);
        // midway between a's lowest point (0.19) and b's top (0.2)
        assert!((r.point - Vector3::new(0.0, 0.0, 0.195)).norm() < 1e-15);
        // apart by more than the margin: nothing
        let far = Se3::new(nalgebra::Matrix3::identity(), Vector3::new(0.0, 0.31, 0.0));
        assert!(round_points(&a, &b, &far, &wb, 0.005, &mut raw));
        assert!(raw.is_empty());
    }

    #[test]
    fn gaps_and_normals_agree_with_brute_force_at_random_poses() {
        let shapes = [ball(0.05), capsule(0.1, 0.03), capsule(0.2, 0.05)];
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut checked = 0;
        for k in 0..3000 {
            let (a, b) = (&shapes[k % 3], &shapes[(k / 3) % 3]);
            let mut pose = |spread: f64| {
                let axis = Unit::new_normalize(Vector3::new(rnd(), rnd(), rnd() + 1e-3));
                let r = Rotation3::from_axis_angle(&axis, 3.0 * rnd()).into_inner();
                Se3::new(r, Vector3::new(rnd(), rnd(), rnd()) * spread)
            };
            let (wa, wb) = (pose(0.15), pose(0.15));
            let mut raw = Vec::new();
            assert!(round_points(a, b, &wa, &wb, 0.01, &mut raw));
            let want = reference_gap(a, b, &wa, &wb);
            if raw.is_empty() {
                assert!(want > 0.01 - 1e-9, "pose {k}: none found, GJK {want}");
                continue;
            }
            let deepest = raw.iter().map(|r| r.gap).fold(f64::INFINITY, f64::min);
            assert!(
                (deepest - want).abs() < 1e-9,
                "pose {k}: {deepest} vs {want}"
            );
            for r in &raw {
                // the normal from b toward a: moving a along it by −gap
                // (plus a hair) clears the shapes
                let shift = Se3::new(wa.rot, wa.trans + r.normal * (1e-7 - r.gap));
                let after = reference_gap(a, b, &shift, &wb);
                assert!(after > -1e-8 || raw.len() > 1, "pose {k}: {after}");
                assert!((r.normal.norm() - 1.0).abs() < 1e-12);
            }
            checked += 1;
        }
        assert!(checked > 300, "{checked}");
    }

    #[test]
    fn parallel_capsules_touch_at_both_ends_of_their_overlap() {
        let (a, b) = (capsule(0.1, 0.02), capsule(0.2, 0.03));
        // a lies along x on b (also along x), shifted by 0.05 along it
        let along_x = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2)
            .into_inner();
        let wa = Se3::new(along_x, Vector3::new(0.15, 0.0, 0.049));
        let wb = Se3::new(along_x, Vector3::zeros());
        let mut raw = Vec::new();
        assert!(round_points(&a, &b, &wa, &wb, 0.005, &mut raw));
        assert_eq!(raw.len(), 2, "{raw:?}");
        let mut xs: Vec<f64> = raw.iter().map(|r| r.point.x).collect();
        xs.sort_by(f64::total_cmp);
        // the common stretch of a's axis [0.05, 0.25] and b's [-0.2, 0.2]
        assert!(
            (xs[0] - 0.05).abs() < 1e-12 && (xs[1] - 0.2).abs() < 1e-12,
            "{xs:?}"
        );
        for r in &raw {
            assert!((r.gap + 0.001).abs() < 1e-12, "{}", r.gap);
            assert!((r.normal - Vector3::z()).norm() < 1e-12);
        }
    }
}
