//! The tests of `src/contact/travel.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use crate::common::lcg::Lcg;
use urdyn::nalgebra::Vector3;
use urdyn::nalgebra::{Matrix3, Rotation3, Unit};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{dropped, margin, moved};

#[test]
fn the_margin_grows_only_past_delta() {
    assert_eq!(margin(0.005, 2.0, f64::NAN), 0.005);
    assert_eq!(margin(0.005, 2.0, 0.0025), 0.005);
    assert_eq!(margin(0.005, 2.0, -1.0), 0.005);
    assert_eq!(margin(0.005, 2.0, 0.004), 0.008);
}

#[test]
fn moved_and_dropped_bound_every_point() {
    // random poses: no point within the radius moves farther (or further
    // down) than the bounds, and a point on the sphere comes close to them
    let mut lcg = Lcg(11);
    let mut rnd = || lcg.uniform(-1.0, 1.0);
    for _ in 0..200 {
        let pose = |rnd: &mut dyn FnMut() -> f64| {
            let axis = Unit::new_normalize(Vector3::new(rnd(), rnd(), rnd()));
            let r: Matrix3<f64> = Rotation3::from_axis_angle(&axis, 3.0 * rnd()).into_inner();
            Se3::new(r, Vector3::new(rnd(), rnd(), rnd()))
        };
        let (w0, w) = (pose(&mut rnd), pose(&mut rnd));
        let mid = Vector3::new(rnd(), rnd(), rnd()) * 0.3;
        let radius = 0.2;
        let m = moved(&w0, &w, &mid, radius);
        let p0 = w0.act_point(&mid);
        let p = w.act_point(&mid);
        let then = [p0.z, w0.rot[(2, 0)], w0.rot[(2, 1)], w0.rot[(2, 2)]];
        let down = dropped(
            &then,
            p.z,
            [w.rot[(2, 0)], w.rot[(2, 1)], w.rot[(2, 2)]],
            radius,
        );
        for _ in 0..400 {
            let u = Vector3::new(rnd(), rnd(), rnd());
            let x = mid + u.normalize() * radius * rnd().abs();
            let dx = w.act_point(&x) - w0.act_point(&x);
            assert!(dx.norm() <= m + 1e-12, "{} > {m}", dx.norm());
            assert!(-dx.z <= down + 1e-12, "{} > {down}", -dx.z);
        }
        // the bound on the drop is reached: at p − radius·Δr/|Δr|
        let dr = w.rot.row(2) - w0.rot.row(2);
        let x = mid - dr.transpose().normalize() * radius;
        let dx = w.act_point(&x) - w0.act_point(&x);
        assert!((-dx.z - down).abs() < 1e-12, "{} {down}", -dx.z);
    }
}
