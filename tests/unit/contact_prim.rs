//! The tests of `src/contact/narrow/prim.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use crate::common::lcg::Lcg;
use parry3d_f64::shape::SharedShape;
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{pair_shape, round_of, round_points, PairShape};

fn ball(r: f64) -> PairShape {
    pair_shape(SharedShape::ball(r), Se3::identity(), true)
}

fn capsule(half: f64, r: f64) -> PairShape {
    pair_shape(SharedShape::capsule_z(half, r), Se3::identity(), true)
}

/// The gap of two spheres or capsules by brute force: the distance of
/// their axes minimised by nested ternary searches (the distance from a
/// point moving along one segment to the other segment is convex in
/// its parameter), less both radii.
fn reference_gap(a: &PairShape, b: &PairShape, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
    let (ra, rb) = (round_of(a, wa).unwrap(), round_of(b, wb).unwrap());
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
    let wa = Se3::new(
        urdyn::nalgebra::Matrix3::identity(),
        Vector3::new(0.0, 0.0, 0.29),
    );
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
    let far = Se3::new(
        urdyn::nalgebra::Matrix3::identity(),
        Vector3::new(0.0, 0.31, 0.0),
    );
    assert!(round_points(&a, &b, &far, &wb, 0.005, &mut raw));
    assert!(raw.is_empty());
}

#[test]
fn gaps_and_normals_agree_with_brute_force_at_random_poses() {
    let shapes = [ball(0.05), capsule(0.1, 0.03), capsule(0.2, 0.05)];
    let mut lcg = Lcg(11);
    let mut rnd = || lcg.uniform(-1.0, 1.0);
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
    let along_x =
        Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2).into_inner();
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
