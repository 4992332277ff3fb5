//! The tests of `src/contact/narrow/cylinder/pfm.rs`: the cylinder pairs'
//! manifold with EPA's polytope kept between calls equals parry's
//! dispatcher's (`contact_manifold_pfm_pfm`, a new EPA every call) bit for
//! bit: normals, points, gaps and feature ids, on random poses of a
//! cylinder with a box (both orders) and with a cylinder, overlapping (EPA),
//! touching and apart, each pair carried along a short path with its
//! manifold kept from call to call as the narrow phase keeps it (the points
//! cleared, the normal kept as GJK's first direction). The rim-on-edge
//! closed form is off here (`contact_cylinder_rim.rs` tests it).

use crate::common::lcg::Lcg;
use parry3d_f64::math::Pose;
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d_f64::shape::SharedShape;
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{
    cylinder_pfm_manifold, cylinder_pfm_manifold_with, pair_shape, to_pose, PairShape,
};

type Man = ContactManifold<(), ()>;

/// A random unit vector (not uniform on the sphere: a cube's directions).
pub(super) fn unit(g: &mut Lcg) -> Unit<Vector3<f64>> {
    Unit::new_normalize(Vector3::new(
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
    ))
}

/// Whether two manifold lists are the same bit for bit.
fn same(a: &[Man], b: &[Man]) -> bool {
    let bits = |v: parry3d_f64::math::Vector| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    a.len() == b.len()
        && a.iter().zip(b).all(|(m, n)| {
            bits(m.local_n1) == bits(n.local_n1)
                && bits(m.local_n2) == bits(n.local_n2)
                && m.points.len() == n.points.len()
                && m.points.iter().zip(&n.points).all(|(p, q)| {
                    bits(p.local_p1) == bits(q.local_p1)
                        && bits(p.local_p2) == bits(q.local_p2)
                        && p.dist.to_bits() == q.dist.to_bits()
                        && p.fid1 == q.fid1
                        && p.fid2 == q.fid2
                })
        })
}

/// One call of each narrow phase (margin 5 mm) on a pair at `pos12` (b's
/// frame in a's): ours (the cylinder pairs' `pfm`, the rim-on-edge closed form on or off
/// by `rim`) into `ours`, parry's dispatcher into `theirs` with its
/// `workspace`; the manifolds kept as the caller left them.
pub(super) fn both(
    pos12: &Pose,
    (a, b): (&PairShape, &PairShape),
    (ours, theirs): (&mut Vec<Man>, &mut Vec<Man>),
    workspace: &mut Option<ContactManifoldsWorkspace>,
    rim: bool,
) {
    let margin = 0.005;
    assert!(cylinder_pfm_manifold_with(pos12, a, b, margin, ours, rim));
    DefaultQueryDispatcher
        .contact_manifolds(pos12, &*a.shape, &*b.shape, margin, theirs, workspace)
        .expect("parry's dispatcher takes a cylinder pair");
}

/// Runs `paths` random paths of `steps` poses of b about a (centres `reach`
/// apart ± 20 %, turning), both manifolds kept along each; returns the
/// number of calls whose deepest point overlaps.
fn run(a: &PairShape, b: &PairShape, reach: f64, seed: u64, paths: usize, steps: usize) -> usize {
    let mut g = Lcg(seed);
    let mut overlapping = 0;
    for path in 0..paths {
        let dir = unit(&mut g);
        let axis = unit(&mut g);
        let (angle, spin) = (g.uniform(-3.1, 3.1), g.uniform(-0.05, 0.05));
        let dist = reach * g.uniform(0.8, 1.2);
        let drift = Vector3::new(
            g.uniform(-1e-3, 1e-3),
            g.uniform(-1e-3, 1e-3),
            g.uniform(-1e-3, 1e-3),
        );
        let (mut ours, mut theirs): (Vec<Man>, Vec<Man>) = (Vec::new(), Vec::new());
        let mut workspace: Option<ContactManifoldsWorkspace> = None;
        for k in 0..steps {
            let rot = Rotation3::from_axis_angle(&axis, angle + spin * k as f64);
            let a_m_b = Se3::new(*rot.matrix(), dir.into_inner() * dist + drift * k as f64);
            let pos12 = to_pose(&a_m_b);
            for m in ours.iter_mut().chain(theirs.iter_mut()) {
                m.points.clear();
            }
            both(
                &pos12,
                (a, b),
                (&mut ours, &mut theirs),
                &mut workspace,
                false,
            );
            assert!(
                same(&ours, &theirs),
                "path {path} step {k}: {ours:?} vs {theirs:?}"
            );
            if theirs.iter().flat_map(|m| &m.points).any(|p| p.dist < 0.0) {
                overlapping += 1;
            }
        }
    }
    overlapping
}

#[test]
fn cylinder_pairs_match_parrys_manifold_bit_for_bit() {
    let cyl = pair_shape(SharedShape::cylinder(0.05, 0.05), Se3::identity(), true);
    let thin = pair_shape(SharedShape::cylinder(0.2, 0.03), Se3::identity(), true);
    let cube = pair_shape(SharedShape::cuboid(0.05, 0.05, 0.05), Se3::identity(), true);
    let slab = pair_shape(SharedShape::cuboid(0.3, 0.05, 0.2), Se3::identity(), true);
    // centres about the sum of the inner radii apart: every kind of touch
    let cases: [(&PairShape, &PairShape, f64); 5] = [
        (&cyl, &cube, 0.09),
        (&cube, &cyl, 0.09),
        (&cyl, &cyl, 0.09),
        (&thin, &cyl, 0.12),
        (&slab, &thin, 0.12),
    ];
    for (i, (a, b, reach)) in cases.into_iter().enumerate() {
        let overlapping = run(a, b, reach, 7 + i as u64, 60, 8);
        // EPA ran (GJK finds overlapping shapes only there)
        assert!(
            overlapping >= 40,
            "case {i}: only {overlapping} overlapping calls"
        );
    }
}

#[test]
fn other_pairs_are_not_taken() {
    let ball = pair_shape(SharedShape::ball(0.05), Se3::identity(), true);
    let cube = pair_shape(SharedShape::cuboid(0.05, 0.05, 0.05), Se3::identity(), true);
    let cyl = pair_shape(SharedShape::cylinder(0.05, 0.05), Se3::identity(), true);
    let pos12 = to_pose(&Se3::from_translation(Vector3::new(0.0, 0.09, 0.0)));
    let mut ms: Vec<Man> = Vec::new();
    for (a, b) in [(&ball, &cyl), (&cyl, &ball), (&cube, &cube), (&ball, &cube)] {
        assert!(!cylinder_pfm_manifold(&pos12, a, b, 0.005, &mut ms));
        assert!(ms.is_empty());
    }
}
