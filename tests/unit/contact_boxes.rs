//! The tests of `src/contact/narrow/boxes.rs`: the closed-form box–box
//! manifold against parry's `contact_manifold_cuboid_cuboid`, point by point.

use crate::common::lcg::Lcg;
use parry3d_f64::query::details::contact_manifold_cuboid_cuboid;
use parry3d_f64::query::ContactManifold;
use parry3d_f64::shape::Cuboid;
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{box_box, to_pose, to_v};

fn random_rotation(g: &mut Lcg) -> Rotation3<f64> {
    let axis = Vector3::new(
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
    );
    Rotation3::from_axis_angle(&Unit::new_normalize(axis), g.uniform(-3.1, 3.1))
}

/// parry's manifold of the same pair (from scratch).
fn parry(
    ha: &Vector3<f64>,
    hb: &Vector3<f64>,
    a_m_b: &Se3<f64>,
    margin: f64,
) -> ContactManifold<(), ()> {
    let (ca, cb) = (
        Cuboid::new(parry3d_f64::math::Vector::new(ha.x, ha.y, ha.z)),
        Cuboid::new(parry3d_f64::math::Vector::new(hb.x, hb.y, hb.z)),
    );
    let mut man = ContactManifold::new();
    contact_manifold_cuboid_cuboid(&to_pose(a_m_b), &ca, &cb, margin, &mut man);
    man
}

/// Compares the two manifolds of one pose: the same points (features, gaps,
/// positions) and normals.
fn same(
    ours: &ContactManifold<(), ()>,
    theirs: &ContactManifold<(), ()>,
    found: bool,
    case: usize,
) {
    assert_eq!(
        ours.points.len(),
        theirs.points.len(),
        "case {case}: points"
    );
    if !found || theirs.points.is_empty() {
        return;
    }
    let (n, m) = (to_v(ours.local_n1), to_v(theirs.local_n1));
    assert!((n - m).norm() < 1e-9, "case {case}: normal {n:?} vs {m:?}");
    assert!((to_v(ours.local_n2) - to_v(theirs.local_n2)).norm() < 1e-9);
    assert_eq!(
        ours.points.len(),
        theirs.points.len(),
        "case {case}: points"
    );
    for (p, q) in ours.points.iter().zip(&theirs.points) {
        assert_eq!((p.fid1, p.fid2), (q.fid1, q.fid2), "case {case}: features");
        assert!(
            (p.dist - q.dist).abs() < 1e-9,
            "case {case}: gap {} vs {}",
            p.dist,
            q.dist
        );
        assert!(
            (to_v(p.local_p1) - to_v(q.local_p1)).norm() < 1e-9,
            "case {case}: p1"
        );
        assert!(
            (to_v(p.local_p2) - to_v(q.local_p2)).norm() < 1e-9,
            "case {case}: p2"
        );
    }
}

#[test]
fn random_box_pairs_match_parrys_manifold() {
    let mut g = Lcg(7);
    let margin = 0.005;
    let (mut touching, mut compared) = (0, 0);
    for case in 0..20000 {
        let ha = Vector3::new(
            g.uniform(0.02, 0.3),
            g.uniform(0.02, 0.3),
            g.uniform(0.02, 0.3),
        );
        let hb = Vector3::new(
            g.uniform(0.02, 0.3),
            g.uniform(0.02, 0.3),
            g.uniform(0.02, 0.3),
        );
        let r = random_rotation(&mut g);
        // b's centre about the sum of the boxes' sizes away: near contact
        let dir = Unit::new_normalize(Vector3::new(
            g.uniform(-1.0, 1.0),
            g.uniform(-1.0, 1.0),
            g.uniform(-1.0, 1.0),
        ));
        let reach = g.uniform(0.2, 1.0) * (ha.norm() + hb.norm());
        let a_m_b = Se3::new(r.into_inner(), dir.into_inner() * reach);
        let theirs = parry(&ha, &hb, &a_m_b, margin);
        let mut ours = ContactManifold::new();
        let found = box_box(&ha, &hb, &a_m_b, margin, &mut ours);
        compared += 1;
        touching += usize::from(found);
        same(&ours, &theirs, found, case);
    }
    assert!(touching > 2000 && compared == 20000, "{touching} touching");
}

#[test]
fn resting_and_aligned_boxes_match_parrys_manifold() {
    // a box on a box, axis-aligned and turned about z, resting within
    // micrometres, penetrating and hovering in the margin
    let (ha, hb) = (Vector3::new(0.1, 0.1, 0.1), Vector3::new(0.1, 0.1, 0.1));
    for (case, (angle, dz, dx)) in [
        (0.0, 0.2, 0.0),
        (0.0, 0.2 - 1e-6, 0.03),
        (0.0, 0.2 + 0.003, 0.0),
        (0.3, 0.199, 0.01),
        (0.785, 0.1995, -0.02),
        (1e-7, 0.2 - 2e-6, 0.0),
    ]
    .into_iter()
    .enumerate()
    {
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
        let a_m_b = Se3::new(r.into_inner(), Vector3::new(dx, 0.0, dz));
        let theirs = parry(&ha, &hb, &a_m_b, 0.005);
        let mut ours = ContactManifold::new();
        let found = box_box(&ha, &hb, &a_m_b, 0.005, &mut ours);
        same(&ours, &theirs, found, case);
    }
}
