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
