//! The tests of `src/contact/narrow/ball.rs`: a ball on a box or a cylinder
//! in closed form against parry's dispatcher (`contact_manifold_convex_ball`
//! through `DefaultQueryDispatcher`, its manifold read as the narrow phase
//! reads it) on random world poses with the ball's centre apart, touching and
//! inside the other shape, both orders: the same gap, normal and point to
//! rounding, the same feature key and the same axis (the manifold's normal).

use crate::common::lcg::Lcg;
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d_f64::shape::SharedShape;
use urdyn::nalgebra::{Rotation3, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{pair_shape, parry_points, to_pose, PairShape, Raw};

use super::contact_cylinder_pfm::unit;

type Man = ContactManifold<(), ()>;

fn v(p: parry3d_f64::math::Vector) -> Vector3<f64> {
    Vector3::new(p.x, p.y, p.z)
}

/// parry's dispatcher's points of a at `wa` and b at `wb`, read as the
/// narrow phase reads a manifold (normal from b toward a, the midpoint of
/// the two surface points, parry's feature ids as the key), and the
/// manifold's normal (a's frame) when it has a point.
fn parrys(
    a: &PairShape,
    b: &PairShape,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
) -> (Vec<Raw>, Option<Vector3<f64>>) {
    let pos12 = to_pose(&wa.inverse().compose(wb));
    let mut ms: Vec<Man> = Vec::new();
    let mut ws: Option<ContactManifoldsWorkspace> = None;
    DefaultQueryDispatcher
        .contact_manifolds(&pos12, &*a.shape, &*b.shape, margin, &mut ms, &mut ws)
        .expect("parry's dispatcher takes a ball pair");
    assert_eq!(ms.len(), 1);
    let m = &ms[0];
    let n = -(wa.rot * v(m.local_n1));
    let n = n / n.norm();
    let raw = m
        .points
        .iter()
        .filter(|c| c.dist <= margin)
        .map(|c| Raw {
            point: (wa.act_point(&v(c.local_p1)) + wb.act_point(&v(c.local_p2))) * 0.5,
            normal: n,
            gap: c.dist,
            key: ((c.fid1.0 as u64) << 20) ^ (c.fid2.0 as u64),
        })
        .collect();
    // apart, parry's generator leaves the manifold's normal as it was
    (raw, (!m.points.is_empty()).then(|| v(m.local_n1)))
}

/// A random rotation.
fn rotation(g: &mut Lcg) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&unit(g), g.uniform(-3.1, 3.1))
}

/// `n` random poses of b about a (a ball of radius `r` either; centres `reach` × [0, 1.3] apart), each
/// compared; returns (poses touching, poses with the centre inside) and the
/// largest differences (gap, normal, point; the last two weighed, below).
fn run(
    a: &PairShape,
    b: &PairShape,
    reach: f64,
    r: f64,
    seed: u64,
    n: usize,
) -> (usize, usize, [f64; 3]) {
    let margin = 0.005;
    let mut g = Lcg(seed);
    let (mut touching, mut inside) = (0, 0);
    let mut worst = [0.0f64; 3];
    for k in 0..n {
        let off = Vector3::new(
            g.uniform(-2.0, 2.0),
            g.uniform(-2.0, 2.0),
            g.uniform(0.0, 1.0),
        );
        let wa = Se3::new(*rotation(&mut g).matrix(), off);
        let d = unit(&mut g).into_inner() * (reach * g.uniform(0.0, 1.3));
        let wb = Se3::new(*rotation(&mut g).matrix(), off + d);
        let (theirs, axis) = parrys(a, b, &wa, &wb, margin);
        let mut ours: Vec<Raw> = Vec::new();
        let mut ms: Vec<Man> = Vec::new();
        let mut ws: Option<ContactManifoldsWorkspace> = None;
        parry_points(a, b, &wa, &wb, margin, &mut ms, &mut ws, &mut ours);
        assert_eq!(ours.len(), theirs.len(), "pose {k}: {ours:?} vs {theirs:?}");
        assert_eq!(ms.len(), 1);
        // a normal from a radial direction (a cylinder's side or rim) is
        // off by rounding / the centre's distance ρ from the axis, and any
        // normal by rounding / the centre's distance from the surface: weighed
        // by min(1, ρ / 1 mm, distance / 1 mm)
        let near = theirs
            .first()
            .map_or(1.0, |t| ((t.gap + r).abs() / 1e-3).min(1.0));
        let weight = near
            * match b.cylinder.or(a.cylinder) {
                Some(_) => {
                    let wo = if a.cylinder.is_some() { &wa } else { &wb };
                    let wc = if a.cylinder.is_some() { &wb } else { &wa };
                    let c = wo.inv_act_point(&wc.trans);
                    (c.x.hypot(c.z) / 1e-3).min(1.0)
                }
                None => 1.0,
            };
        if let Some(axis) = axis {
            let off = (v(ms[0].local_n1) - axis).norm() * weight;
            assert!(
                off < 1e-12,
                "pose {k}: axis {:?} vs {axis:?}",
                ms[0].local_n1
            );
        }
        for (o, t) in ours.iter().zip(&theirs) {
            assert_eq!(o.key, t.key, "pose {k}: {o:?} vs {t:?}");
            let diff = [
                (o.gap - t.gap).abs(),
                (o.normal - t.normal).norm() * weight,
                (o.point - t.point).norm() * weight,
            ];
            for (w, d) in worst.iter_mut().zip(diff) {
                *w = w.max(d);
            }
            touching += 1;
            inside += usize::from(t.gap < -0.05);
        }
    }
    (touching, inside, worst)
}

#[test]
fn ball_pairs_match_parrys_generator() {
    let r = 0.05;
    let ball = pair_shape(SharedShape::ball(r), Se3::identity(), true);
    let cube = pair_shape(SharedShape::cuboid(0.05, 0.05, 0.05), Se3::identity(), true);
    let slab = pair_shape(SharedShape::cuboid(0.3, 0.05, 0.2), Se3::identity(), true);
    let cyl = pair_shape(SharedShape::cylinder(0.05, 0.05), Se3::identity(), true);
    let thin = pair_shape(SharedShape::cylinder(0.2, 0.03), Se3::identity(), true);
    let flat = pair_shape(SharedShape::cylinder(0.02, 0.2), Se3::identity(), true);
    let cases: [(&PairShape, &PairShape, f64); 8] = [
        (&ball, &cube, 0.12),
        (&cube, &ball, 0.12),
        (&slab, &ball, 0.3),
        (&ball, &slab, 0.3),
        (&ball, &cyl, 0.12),
        (&cyl, &ball, 0.12),
        (&thin, &ball, 0.25),
        (&ball, &flat, 0.25),
    ];
    for (i, (a, b, reach)) in cases.into_iter().enumerate() {
        let (touching, inside, worst) = run(a, b, reach, r, 101 + i as u64, 3000);
        // every kind of pose ran: apart, touching, centre inside
        assert!(
            (600..2900).contains(&touching) && inside >= 30,
            "case {i}: {touching} touching, {inside} inside of 3000"
        );
        // the same to rounding (poses placed by matrices here, by
        // quaternions in parry, its quaternion taken from a matrix: normals
        // to 2.2e-13 seen)
        assert!(
            worst[0] < 1e-14 && worst[1] < 1e-12 && worst[2] < 1e-13,
            "case {i}: gap, normal, point off by {worst:?}"
        );
    }
}

#[test]
fn ball_on_a_face_and_an_axis() {
    // a ball resting on a box's top face, its centre on the cylinder's axis:
    // the exact numbers
    let r = 0.05;
    let ball = pair_shape(SharedShape::ball(r), Se3::identity(), true);
    let cube = pair_shape(SharedShape::cuboid(0.1, 0.1, 0.1), Se3::identity(), true);
    let cyl = pair_shape(SharedShape::cylinder(0.1, 0.1), Se3::identity(), true);
    for other in [&cube, &cyl] {
        let wa = Se3::identity();
        let wb = Se3::new(
            Rotation3::identity().into_inner(),
            Vector3::new(0.0, 0.149, 0.0),
        );
        let mut raw: Vec<Raw> = Vec::new();
        let mut ms: Vec<Man> = Vec::new();
        let mut ws: Option<ContactManifoldsWorkspace> = None;
        parry_points(other, &ball, &wa, &wb, 0.005, &mut ms, &mut ws, &mut raw);
        assert_eq!(raw.len(), 1);
        assert!((raw[0].gap + 0.001).abs() < 1e-15);
        assert_eq!(raw[0].normal, -Vector3::y());
        assert!((raw[0].point - Vector3::new(0.0, 0.0995, 0.0)).norm() < 1e-15);
        // apart beyond the margin: no point, the axis still set (b above a)
        let wb = Se3::new(
            Rotation3::identity().into_inner(),
            Vector3::new(0.0, 0.2, 0.0),
        );
        parry_points(other, &ball, &wa, &wb, 0.005, &mut ms, &mut ws, &mut raw);
        assert!(raw.is_empty());
        assert_eq!(v(ms[0].local_n1), Vector3::y());
    }
}
