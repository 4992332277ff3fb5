//! The face path's tests: against parry's distances, and the dense first
//! pass against the whole band (formerly `src/contact/face/tests.rs`).

use super::{reduce4, superellipsoid};
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::shape::{Cuboid, Shape, SharedShape};
use urdyn::nalgebra::{self, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{
    hull_on_face, to_pose, to_v, FaceContact, FacePoint, FaceShape, Raw, TestHull, BAND,
    EXTREME_BAND,
};

/// A rounded box hull (many vertices: the climbing kind): points on a
/// superellipsoid of half extents 0.05 × 0.03 × 0.02.
fn rounded() -> TestHull {
    superellipsoid([0.05, 0.03, 0.02], 0.4)
}

fn at(x: f64, y: f64, z: f64, roll: f64) -> Se3<f64> {
    let r = nalgebra::Rotation3::from_euler_angles(roll, 0.0, 0.0);
    Se3 {
        rot: *r.matrix(),
        trans: Vector3::new(x, y, z),
    }
}

fn run(h: &TestHull, pose: &Se3<f64>, face: FaceShape<'_>) -> (FaceContact, Vec<FacePoint>) {
    run_dense(h, pose, face, None)
}

fn run_dense(
    h: &TestHull,
    pose: &Se3<f64>,
    face: FaceShape<'_>,
    dense: Option<(f64, usize)>,
) -> (FaceContact, Vec<FacePoint>) {
    let (mut out, mut stack, mut seen) = (Vec::new(), Vec::new(), Vec::new());
    let c = hull_on_face(
        h, pose, face, 0.005, dense, &mut out, &mut stack, &mut seen, 1,
    );
    (c, out)
}

/// parry's signed distance between the hull at `pose` and `other`.
fn parry_dist(h: &TestHull, pose: &Se3<f64>, other: &dyn Shape) -> f64 {
    let p = to_pose(pose);
    parry3d_f64::query::contact(&p, h.shape(), &Pose::IDENTITY, other, 1.0)
        .ok()
        .flatten()
        .map_or(f64::INFINITY, |c| c.dist)
}

#[test]
fn a_hull_on_a_box_top_is_the_plane_contact_parry_finds() {
    let b = Cuboid::new(PVec::new(0.3, 0.2, 0.1));
    let h = rounded();
    // resting 1 mm into the top (z = 0.1), tilted 3°
    for (z, roll) in [(0.1 + 0.02 - 0.001, 0.0), (0.12, 0.05)] {
        let pose = at(0.05, -0.02, z, roll);
        let (c, pts) = run(&h, &pose, FaceShape::Cuboid(&b));
        assert_eq!(c, FaceContact::Plane(Vector3::z()));
        // every vertex within the band (2 mm above the lowest, within
        // the margin) of the top, each its height
        let height = |p: &PVec| pose.act_point(&to_v(*p)).z - 0.1;
        let low = h.points().iter().map(height).fold(f64::INFINITY, f64::min);
        let want = h
            .points()
            .iter()
            .filter(|p| height(p) <= 0.005f64.min(low + BAND))
            .count();
        assert!(want >= 3, "{want}");
        assert_eq!(pts.len(), want);
        for p in &pts {
            assert!((p.gap - (p.point.z - 0.1)).abs() < 1e-15);
        }
        // the deepest is parry's distance
        let deepest = pts.iter().map(|p| p.gap).fold(f64::INFINITY, f64::min);
        let d = parry_dist(&h, &pose, &b);
        assert!((deepest - d).abs() < 1e-9, "{deepest} vs parry {d}");
    }
}

#[test]
fn over_the_box_edge_parry_decides_and_far_above_nothing_touches() {
    let b = Cuboid::new(PVec::new(0.3, 0.2, 0.1));
    let h = rounded();
    // half over the edge x = 0.3
    let (c, _) = run(&h, &at(0.3, 0.0, 0.119, 0.0), FaceShape::Cuboid(&b));
    assert_eq!(c, FaceContact::Other);
    // beside the box, against its side face x = 0.3: that face
    let (c, pts) = run(&h, &at(0.35 - 0.001, 0.0, 0.0, 0.0), FaceShape::Cuboid(&b));
    assert_eq!(c, FaceContact::Plane(Vector3::x()));
    assert!(pts
        .iter()
        .all(|p| (p.gap - (p.point.x - 0.3)).abs() < 1e-15));
    // 1 cm above: apart, as parry says
    let pose = at(0.0, 0.0, 0.13, 0.0);
    assert_eq!(run(&h, &pose, FaceShape::Cuboid(&b)).0, FaceContact::Apart);
    assert!(parry_dist(&h, &pose, &b) > 0.005);
}

#[test]
fn a_hull_on_a_planar_height_field_is_its_plane_and_on_a_ridge_parry_decides() {
    let h = rounded();
    // parry's frame: the grid in x–z, heights along y; a 10° slope in x
    let slope = 10f64.to_radians().tan();
    let (rows, cols, size) = (9, 9, 2.0);
    let grid = |f: &dyn Fn(f64) -> f64| {
        let mut data = Vec::new();
        for j in 0..cols {
            for _ in 0..rows {
                let x = -size / 2.0 + size * j as f64 / (cols - 1) as f64;
                data.push(f(x));
            }
        }
        parry3d_f64::utils::Array2::new(rows, cols, data)
    };
    let flat = SharedShape::heightfield(grid(&|x| slope * x), PVec::new(size, 1.0, size));
    let hf = flat.as_heightfield().expect("a height field");
    // the hull's z (thin axis) along the slope's normal, 0.5 mm in
    let n = Vector3::new(-slope, 1.0, 0.0).normalize();
    let r = nalgebra::Rotation3::rotation_between(&Vector3::z(), &n).expect("a rotation");
    let c = Vector3::new(0.1, 0.1 * slope, 0.05) + n * (0.02 - 0.0005);
    let pose = Se3 {
        rot: *r.matrix(),
        trans: c,
    };
    let (found, pts) = run(&h, &pose, FaceShape::HeightField(hf));
    let FaceContact::Plane(m) = found else {
        panic!("{found:?}");
    };
    assert!((m - n).norm() < 1e-12, "{m:?} vs {n:?}");
    let deepest = pts.iter().map(|p| p.gap).fold(f64::INFINITY, f64::min);
    assert!((deepest + 0.0005).abs() < 1e-9, "{deepest}");
    assert!((deepest - parry_dist(&h, &pose, &*flat.0)).abs() < 1e-6);
    // a ridge under the hull: not one plane
    let ridge = SharedShape::heightfield(grid(&|x| -x.abs()), PVec::new(size, 1.0, size));
    let hr = ridge.as_heightfield().expect("a height field");
    let on_ridge = at(0.0, 0.019, 0.0, -std::f64::consts::FRAC_PI_2);
    assert_eq!(
        run(&h, &on_ridge, FaceShape::HeightField(hr)).0,
        FaceContact::Other
    );
}

/// What `reduce_pair` keeps of a face path's points (4 at most): vertex,
/// gap and point of each, in its order.
fn reduced(pts: &[FacePoint], n: Vector3<f64>) -> Vec<(u64, f64, Vector3<f64>)> {
    let raw: Vec<Raw> = pts
        .iter()
        .map(|p| Raw {
            point: p.point,
            normal: n,
            gap: p.gap,
            // the face path's key (`narrow::FACE_KEY`)
            key: (1 << 62) | p.vertex as u64,
        })
        .collect();
    reduce4(&raw)
        .iter()
        .map(|p| (p.key, p.gap, p.point))
        .collect()
}

#[test]
fn the_dense_first_pass_keeps_what_the_reduction_of_the_whole_band_keeps() {
    let h = rounded();
    let b = Cuboid::new(PVec::new(0.3, 0.2, 0.1));
    // a flat slab's bottom (hundreds of vertices within 2 mm) and tilted ones
    // (a few): the same four points either way, and the dense pass collects
    // fewer points when it is enough
    let mut fewer = 0;
    for (k, roll) in [0.0, 0.01, 0.05, 0.3, 1.0].into_iter().enumerate() {
        for depth in [0.0005, -0.001, -0.004] {
            let z = 0.1 + h.shape().compute_local_aabb().half_extents().z + depth;
            let pose = at(0.02 * k as f64 - 0.04, 0.01, z, roll);
            let full = run_dense(&h, &pose, FaceShape::Cuboid(&b), None);
            let dense = run_dense(&h, &pose, FaceShape::Cuboid(&b), Some((EXTREME_BAND, 5)));
            assert_eq!(full.0, dense.0, "roll {roll}, depth {depth}");
            let FaceContact::Plane(n) = full.0 else {
                continue;
            };
            assert_eq!(reduced(&full.1, n), reduced(&dense.1, n), "roll {roll}");
            assert!(dense.1.len() <= full.1.len());
            fewer += usize::from(dense.1.len() < full.1.len());
        }
    }
    assert!(fewer >= 3, "the dense pass was never shorter ({fewer})");
    // on a slope's height field: every vertex within the margin otherwise
    let slope = 10f64.to_radians().tan();
    let (rows, cols, size) = (9, 9, 2.0);
    let mut data = Vec::new();
    for j in 0..cols {
        for _ in 0..rows {
            data.push(slope * (-size / 2.0 + size * j as f64 / (cols - 1) as f64));
        }
    }
    let field = SharedShape::heightfield(
        parry3d_f64::utils::Array2::new(rows, cols, data),
        PVec::new(size, 1.0, size),
    );
    let hf = field.as_heightfield().expect("a height field");
    let n = Vector3::new(-slope, 1.0, 0.0).normalize();
    for tilt in [0.0, 0.02, 0.2] {
        let r = nalgebra::Rotation3::rotation_between(&Vector3::z(), &n).expect("a rotation")
            * nalgebra::Rotation3::from_euler_angles(tilt, 0.0, 0.0);
        let c = Vector3::new(0.1, 0.1 * slope, 0.05) + n * (0.02 - 0.0005);
        let pose = Se3 {
            rot: *r.matrix(),
            trans: c,
        };
        let full = run_dense(&h, &pose, FaceShape::HeightField(hf), None);
        let dense = run_dense(
            &h,
            &pose,
            FaceShape::HeightField(hf),
            Some((EXTREME_BAND, 5)),
        );
        assert_eq!(full.0, dense.0, "tilt {tilt}");
        if let FaceContact::Plane(m) = full.0 {
            assert_eq!(reduced(&full.1, m), reduced(&dense.1, m), "tilt {tilt}");
        }
    }
}
