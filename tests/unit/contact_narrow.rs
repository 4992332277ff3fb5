//! The tests of `src/contact/narrow.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use super::superellipsoid;
use parry3d_f64::query::ContactManifold;
use urdyn::nalgebra::{Rotation3, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{pair_shape, parry_points, PairShape, Raw};

/// A rounded slab's hull (the climbing kind: hundreds of vertices).
fn slab() -> PairShape {
    let h = superellipsoid([0.05, 0.04, 0.02], 0.3);
    pair_shape(h.shared(), Se3::identity(), true)
}

fn pose(angle: f64, t: Vector3<f64>) -> Se3<f64> {
    let r = Rotation3::from_axis_angle(&Vector3::x_axis(), angle)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), 0.5 * angle);
    Se3::new(r.into_inner(), t)
}

/// The points of b at `wb` on a: from scratch, and with the manifolds
/// `kept` from earlier queries.
fn points(
    a: &PairShape,
    b: &PairShape,
    wb: &Se3<f64>,
    kept: Option<&mut Vec<ContactManifold<(), ()>>>,
) -> Vec<Raw> {
    let wa = Se3::identity();
    let mut fresh = Vec::new();
    let manifolds = kept.unwrap_or(&mut fresh);
    let (mut ws, mut raw) = (None, Vec::new());
    parry_points(a, b, &wa, wb, 0.005, manifolds, &mut ws, &mut raw);
    raw
}

fn deepest(raw: &[Raw]) -> f64 {
    raw.iter().map(|r| r.gap).fold(f64::INFINITY, f64::min)
}

#[test]
fn kept_points_measure_the_gaps_a_fresh_query_finds() {
    let (a, b) = (slab(), slab());
    // b lies on a, tilted a little: it touches with a corner region
    let w0 = pose(0.03, Vector3::new(0.004, -0.002, 0.0399));
    let mut kept = Vec::new();
    let first = points(&a, &b, &w0, Some(&mut kept));
    assert!(!first.is_empty() && deepest(&first) < 0.0, "{first:?}");
    // moved well within the kept points' tolerance (µm and 10⁻⁶ rad):
    // the points stand, the gaps are this pose's
    for k in 1..=5 {
        let s = k as f64;
        let w = pose(
            0.03 + 1e-6 * s,
            Vector3::new(0.004 + 1e-6 * s, -0.002, 0.0399 - 2e-6 * s),
        );
        let again = points(&a, &b, &w, Some(&mut kept));
        let fresh = points(&a, &b, &w, None);
        let keys = |r: &[Raw]| r.iter().map(|p| p.key).collect::<Vec<_>>();
        assert_eq!(keys(&again), keys(&first), "kept points, same features");
        let (d1, d2) = (deepest(&again), deepest(&fresh));
        assert!((d1 - d2).abs() < 1e-9, "step {k}: kept {d1}, fresh {d2}");
        assert!((d1 - deepest(&first)).abs() > 1e-6, "the gaps moved with b");
    }
    // moved by a millimetre and tilted by 0.02 rad: found anew, as a
    // fresh query finds them
    let w = pose(0.05, Vector3::new(0.005, -0.002, 0.0399));
    let again = points(&a, &b, &w, Some(&mut kept));
    let fresh = points(&a, &b, &w, None);
    assert!((deepest(&again) - deepest(&fresh)).abs() < 1e-9);
}
