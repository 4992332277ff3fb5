//! The tests of `src/contact/pairs/apart.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use crate::common::lcg::Lcg;
use parry3d_f64::shape::SharedShape;
use urdyn::nalgebra::Vector3;
use urdyn::nalgebra::{Matrix3, Rotation3, Unit};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{apart_along, pair_shape, still_apart, to_pose, Member};

fn member(half: [f64; 3]) -> Member {
    let shape = SharedShape::cuboid(half[0], half[1], half[2]);
    Member {
        geom: 0,
        body: 1,
        placement: Se3::identity(),
        shape: pair_shape(shape, Se3::identity(), true),
    }
}

fn distance(a: &Member, b: &Member, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
    let pose = |w: &Se3<f64>| to_pose(w);
    parry3d_f64::query::distance(&pose(wa), &*a.shape.shape, &pose(wb), &*b.shape.shape)
        .unwrap()
        .distance
}

#[test]
fn still_apart_is_never_wrong_and_not_vacuous() {
    // a long bar beside a cube, 3 cm apart along x: turning the bar about
    // its centre swings its end into the cube with no translation at all
    let (a, b) = (member([0.02, 0.1, 0.02]), member([0.02, 0.02, 0.02]));
    let margin = 0.005;
    let wa0 = Se3::identity();
    let wb0 = Se3::new(Matrix3::identity(), Vector3::new(0.07, 0.08, 0.0));
    let gap = apart_along(&Vector3::x(), &a, &b, &wa0, &wb0);
    assert!((gap - 0.03).abs() < 1e-12, "{gap}");
    let then = (gap, wa0, wb0);
    let mut lcg = Lcg(7);
    let mut rnd = || lcg.uniform(-1.0, 1.0);
    let (mut kept, mut asked, mut touching) = (0, 0, 0);
    for k in 0..4000 {
        // turns up to 0.6 rad about axes near z, moves up to 2 cm
        let s = (k % 10) as f64 / 10.0;
        let mut turn = |w: &Se3<f64>, by: f64| {
            let axis = Unit::new_normalize(Vector3::new(0.2 * rnd(), 0.2 * rnd(), 1.0));
            let r = Rotation3::from_axis_angle(&axis, by * s * rnd()).into_inner();
            Se3::new(
                r * w.rot,
                w.trans + Vector3::new(rnd(), rnd(), rnd()) * 0.02 * s * s,
            )
        };
        let (wa, wb) = (turn(&wa0, 0.6), turn(&wb0, 0.1));
        let d = distance(&a, &b, &wa, &wb);
        touching += usize::from(d <= margin);
        if still_apart(Some(&then), &a, &b, &wa, &wb, margin) {
            kept += 1;
            assert!(d > margin, "move {k}: still apart, but {d} m apart");
        } else {
            asked += 1;
        }
    }
    assert!(
        kept > 500 && asked > 500 && touching > 100,
        "{kept} {asked} {touching}"
    );
}

#[test]
fn apart_along_is_parrys_support_gap_bit_for_bit() {
    // the gap from the numbers kept beside the shapes (a box's half
    // extents, a cylinder's and a ball's sizes) must be the one from parry's
    // support points, bit for bit, axes with ±0 components too
    use parry3d_f64::math::Vector as PVec;
    let to_pvec = |v: &Vector3<f64>| PVec::new(v.x, v.y, v.z);
    let from_pvec = |v: PVec| Vector3::new(v.x, v.y, v.z);
    let mut lcg = Lcg(31);
    let mut rnd = |a: f64, b: f64| lcg.uniform(a, b);
    for k in 0..3000 {
        // boxes, cylinders and balls (each kind against each)
        let mut shape = |kind: usize| {
            let s = match kind % 3 {
                0 => SharedShape::cuboid(rnd(0.01, 0.3), rnd(0.01, 0.3), rnd(0.01, 0.3)),
                1 => SharedShape::cylinder(rnd(0.01, 0.3), rnd(0.01, 0.3)),
                _ => SharedShape::ball(rnd(0.01, 0.3)),
            };
            Member {
                geom: 0,
                body: 1,
                placement: Se3::identity(),
                shape: pair_shape(s, Se3::identity(), true),
            }
        };
        let (a, b) = (shape(k), shape(k / 3));
        let pose = |r: &mut dyn FnMut(f64, f64) -> f64| {
            let axis = Unit::new_normalize(Vector3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)));
            let rot = Rotation3::from_axis_angle(&axis, r(-3.0, 3.0)).into_inner();
            Se3::new(rot, Vector3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)))
        };
        let (wa, wb) = (pose(&mut rnd), pose(&mut rnd));
        let mut u = Vector3::new(rnd(-1.0, 1.0), rnd(-1.0, 1.0), rnd(-1.0, 1.0)).normalize();
        // some components exactly ±0 (the sign picks the corner; a
        // cylinder's axis: no radial direction)
        match (k / 9) % 5 {
            1 => u.x = 0.0,
            2 => u.y = -0.0,
            3 => (u.x, u.z) = (-0.0, 0.0),
            4 => (u.x, u.z) = (0.0, -0.0),
            _ => {}
        }
        let gap = apart_along(&u, &a, &b, &wa, &wb);
        let (sa, sb) = (
            a.shape.shape.as_support_map().unwrap(),
            b.shape.shape.as_support_map().unwrap(),
        );
        let a_m_b = wa.inverse().compose(&wb);
        let top_a = u.dot(&from_pvec(sa.local_support_point(to_pvec(&u))));
        let d = a_m_b.rot.transpose() * (-u);
        let low_b = u.dot(&a_m_b.act_point(&from_pvec(sb.local_support_point(to_pvec(&d)))));
        let want = low_b - top_a;
        assert_eq!(gap.to_bits(), want.to_bits(), "case {k}: {gap} vs {want}");
    }
}
