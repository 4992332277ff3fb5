//! Whether two convex members of a pair are apart without asking parry: the
//! gap along last step's separating axis, and the conservative advancement
//! from the last time that gap was known (src/contact/pairs/mod.rs).

use super::super::shapes::{from_pvec, to_pvec};
use super::Member;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// The gap of convex members `a` at `wa` and `b` at `wb` along the unit
/// axis `u` (a's frame, from a toward b; zero: not known, −∞): min over b
/// of u·x − max over a of u·x (two support points), a lower bound of their
/// distance when positive.
#[inline]
pub(super) fn apart_along(
    u: &Vector3<f64>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
) -> f64 {
    if u.x == 0.0 && u.y == 0.0 && u.z == 0.0 {
        return f64::NEG_INFINITY;
    }
    let (Some(sa), Some(sb)) = (
        a.shape.shape.as_support_map(),
        b.shape.shape.as_support_map(),
    ) else {
        return f64::NEG_INFINITY;
    };
    // b in a's frame: x = R p + t
    let a_m_b = wa.inverse().compose(wb);
    let top_a = u.dot(&from_pvec(sa.local_support_point(to_pvec(u))));
    let d = a_m_b.rot.transpose() * (-u);
    let low_b = u.dot(&a_m_b.act_point(&from_pvec(sb.local_support_point(to_pvec(&d)))));
    low_b - top_a
}

/// Whether two shapes separated by a plane with a gap g (> the margin) at
/// the world poses `then` are still more than `margin` apart at `wa`, `wb`
/// without a support query: no point of a shape moved farther than D =
/// |w·c − w₀·c| + ‖R − R₀‖_F |h| (c, h its box's centre and half extents in
/// its frame: every point lies within |h| of c), so across that plane the
/// shapes are still g − D_a − D_b apart (conservative advancement).
pub(super) fn still_apart(
    then: Option<&(f64, Se3<f64>, Se3<f64>)>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
) -> bool {
    let Some((gap, wa0, wb0)) = then else {
        return false;
    };
    let moved = |m: &Member, w0: &Se3<f64>, w: &Se3<f64>| {
        (w.act_point(&m.shape.mid) - w0.act_point(&m.shape.mid)).norm()
            + (w.rot - w0.rot).norm() * m.shape.half.norm()
    };
    gap - moved(a, wa0, wa) - moved(b, wb0, wb) > margin
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::shapes::PairShape;
    use crate::spatial::Se3;
    use nalgebra::{Matrix3, Rotation3, Unit};
    use parry3d_f64::shape::SharedShape;

    fn member(half: [f64; 3]) -> Member {
        let shape = SharedShape::cuboid(half[0], half[1], half[2]);
        Member {
            geom: 0,
            body: 1,
            placement: Se3::identity(),
            shape: PairShape::new(shape, Se3::identity(), true),
        }
    }

    fn distance(a: &Member, b: &Member, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
        let pose = |w: &Se3<f64>| crate::contact::shapes::to_pose(w);
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
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
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
}
