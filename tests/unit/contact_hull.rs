//! The tests of `src/contact/hull.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::shape::{PolygonalFeature, PolygonalFeatureMap};
use urdyn::testing::contact::TestHull;

/// Points on a bumpy sphere (a hull of many vertices, some faces near
/// coplanar) and a box's corners repeated along its edges (collinear
/// points on the hull's edges, coplanar ones on its faces).
fn clouds() -> Vec<Vec<PVec>> {
    let mut out = Vec::new();
    let mut s = Vec::new();
    let (mut a, mut b) = (0.3_f64, 0.7_f64);
    for k in 0..600 {
        // a deterministic scatter on the sphere (golden-angle spiral)
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / 600.0;
        let phi = k as f64 * 2.399_963_229_728_653;
        let r = (1.0 - z * z).sqrt();
        a = (a * 7.3 + 0.11).fract();
        b = (b * 3.7 + 0.23).fract();
        let rad = 1.0 + 0.05 * a;
        s.push(PVec::new(
            0.3 * rad * r * phi.cos(),
            0.1 * rad * r * phi.sin() + 0.01 * b,
            0.05 * rad * z,
        ));
    }
    out.push(s);
    // a cylinder with flat caps (coplanar cap points, a ring on each)
    let mut bx = Vec::new();
    for ring in 0..5 {
        let r = 0.04 * (ring + 1) as f64 / 5.0;
        for k in 0..48 {
            let a = std::f64::consts::TAU * k as f64 / 48.0 + 0.1 * ring as f64;
            for z in [-0.03, 0.03] {
                bx.push(PVec::new(r * a.cos(), r * a.sin(), z));
            }
        }
    }
    out.push(bx);
    out
}

#[test]
fn climbed_support_is_the_scanned_maximum() {
    for pts in clouds() {
        let h = match TestHull::of_points(&pts) {
            Some(Ok(h)) => h,
            _ => panic!("a hull of many vertices"),
        };
        let verts = h.hull().points();
        let mut c = 0.123_f64;
        for _ in 0..4000 {
            let mut r = || {
                c = (c * 9.17 + 0.377).fract();
                2.0 * c - 1.0
            };
            let d = PVec::new(r(), r(), r());
            // and the axes and their mixes exactly (ties on flat faces)
            for d in [
                d,
                PVec::new(d.x.signum(), 0.0, 0.0),
                PVec::new(0.0, d.y, d.z),
            ] {
                let scan = verts.iter().map(|v| v.dot(d)).fold(f64::MIN, f64::max);
                let (_, climbed) = h.support_index(d);
                assert!(
                    (scan - climbed).abs() <= 1e-15 * (1.0 + scan.abs()),
                    "{d:?}: scan {scan}, climb {climbed}"
                );
            }
        }
    }
}

/// The climb reading its neighbours' points contiguously ends at the same
/// vertex, with the same value bit for bit, as the climb by index, for
/// random directions, axes and their mixes (ties on flat faces).
#[test]
fn climb_is_the_climb_by_index() {
    for pts in clouds() {
        let Some(Ok(h)) = TestHull::of_points(&pts) else {
            panic!("a hull of many vertices");
        };
        let mut c = 0.271_f64;
        for _ in 0..5000 {
            let mut r = || {
                c = (c * 9.17 + 0.377).fract();
                2.0 * c - 1.0
            };
            let d = PVec::new(r(), r(), r());
            for d in [
                d,
                PVec::new(d.x.signum(), 0.0, 0.0),
                PVec::new(0.0, d.y.signum(), d.z.signum()),
                PVec::new(0.0, d.y, d.z),
                PVec::new(d.x, 0.0, 0.0),
            ] {
                let (k, v) = h.support_index(d);
                let (k0, v0) = h.support_index_by_index(d);
                assert_eq!((k, v.to_bits()), (k0, v0.to_bits()), "{d:?}");
            }
        }
    }
}

#[test]
fn support_face_is_the_scanned_best_face() {
    for pts in clouds() {
        let Some(Ok(h)) = TestHull::of_points(&pts) else {
            panic!("a hull of many vertices");
        };
        let faces = h.hull().faces();
        let mut c = 0.377_f64;
        let (mut f1, mut f2) = (PolygonalFeature::default(), PolygonalFeature::default());
        for _ in 0..4000 {
            let mut r = || {
                c = (c * 9.17 + 0.123).fract();
                2.0 * c - 1.0
            };
            let d = PVec::new(r(), r(), r()).normalize();
            // cube-map cell borders (equal components, ±1/4 steps), a long
            // and a short copy, an axis
            for d in [
                d,
                PVec::new(0.0, 0.0, d.z.signum()),
                PVec::new(d.x, d.x, d.z),
                PVec::new(d.x, -d.x, -d.x),
                PVec::new(1.0, 0.25 * d.y.signum(), -0.75),
                d * 1e3,
                d * 1e-3,
            ] {
                h.support_feature(d, &mut f1);
                h.hull().local_support_feature(d, &mut f2);
                let n = |f: &PolygonalFeature| {
                    faces[f.fid.unpack().unwrap_face() as usize].normal.dot(d)
                };
                assert_eq!(f1.fid, f2.fid, "{d:?}");
                assert!(
                    (n(&f1) - n(&f2)).abs() < 1e-12,
                    "{d:?}: {} vs {}",
                    n(&f1),
                    n(&f2)
                );
            }
        }
    }
}

#[test]
fn aabb_at_a_pose_is_the_point_clouds() {
    for pts in clouds() {
        let Some(Ok(h)) = TestHull::of_points(&pts) else {
            panic!("a hull of many vertices");
        };
        let pose = Pose::from_parts(
            PVec::new(0.4, -1.0, 2.5),
            parry3d_f64::math::Rot3::from_scaled_axis(PVec::new(0.3, -0.8, 1.9)),
        );
        let (a, b) = (h.shape().compute_aabb(&pose), h.hull().aabb(&pose));
        assert!((a.mins - b.mins).abs().max_element() < 1e-14, "{a:?} {b:?}");
        assert!((a.maxs - b.maxs).abs().max_element() < 1e-14, "{a:?} {b:?}");
    }
}
