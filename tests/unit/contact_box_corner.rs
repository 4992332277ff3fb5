//! A box turning onto another: the corner that closes is among the pair's
//! points while its gap is within the margin (`narrow::reduce_pair` gives
//! the slots its extremes leave free to the nearest other points).
//!
//! Round 26's boxes 1024 pile went 2.76 mm deep when a box resting on a
//! corner of another turned onto it at 2.5 m/s: the manifold (parry's
//! box–box clip) held the closing corner, but with more than four points the
//! reduction kept only those within `EXTREME_BAND` of the deepest, the
//! touching one, and the corner entered the rows already 1.5 mm in.

use super::reduce4;
use parry3d_f64::shape::SharedShape;
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{pair_shape, parry_points, Raw};

const MARGIN: f64 = 0.005;
const H: f64 = 0.05;

fn cube() -> urdyn::testing::contact::PairShape {
    pair_shape(SharedShape::cuboid(H, H, H), Se3::identity(), true)
}

/// b (a 0.1 m cube) turned by `yaw` about z, then by `phi` about a
/// horizontal axis, its lowest corner `clear` above a's top face, its centre
/// moved by (`dx`, `dy`): the two squares' outlines cross at eight points.
fn pose(phi: f64, yaw: f64, axis: Vector3<f64>, dx: f64, dy: f64, clear: f64) -> Se3<f64> {
    let r = Rotation3::from_axis_angle(&Unit::new_normalize(axis), phi)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
    // the lowest corner's height relative to the centre
    let low = (0..8)
        .map(|k| {
            let c = Vector3::new(
                if k & 1 == 0 { H } else { -H },
                if k & 2 == 0 { H } else { -H },
                if k & 4 == 0 { H } else { -H },
            );
            (r * c).z
        })
        .fold(f64::INFINITY, f64::min);
    Se3::new(r.into_inner(), Vector3::new(dx, dy, H + clear - low))
}

#[test]
fn a_closing_corner_is_kept_while_within_the_margin() {
    let (a, b) = (cube(), cube());
    let wa = Se3::identity();
    let mut cases = 0;
    let mut crowded = 0;
    for (yaw, axis, dx, dy) in [
        (0.5, Vector3::new(1.0, 0.3, 0.0), 0.01, 0.005),
        (0.6, Vector3::new(0.2, 1.0, 0.0), -0.008, 0.004),
        (0.45, Vector3::new(1.0, -0.7, 0.0), 0.006, -0.01),
        (0.7, Vector3::new(-0.4, 1.0, 0.0), 0.0, 0.008),
    ] {
        // b turns down onto a, one step of 1 mrad at a time, its lowest
        // corner 0.1 mm above a's top face (beside a: the points are the
        // outlines' crossings, gaps from 0.1 mm up)
        let mut manifolds = Vec::new();
        let mut ws = None;
        for k in 0..=60 {
            let phi = 0.06 - 0.001 * k as f64;
            let wb = pose(phi, yaw, axis, dx, dy, 1e-4);
            let mut raw = Vec::new();
            parry_points(&a, &b, &wa, &wb, MARGIN, &mut manifolds, &mut ws, &mut raw);
            let out = reduce4(&raw);
            cases += 1;
            assert_eq!(out.len(), raw.len().min(4), "phi {phi}: {raw:?}");
            if raw.len() > 4 {
                crowded += 1;
            }
            // the points left out are no nearer than any kept above the band
            // (the extremes' band: the load-bearing points)
            let deepest = raw.iter().map(|r| r.gap).fold(f64::INFINITY, f64::min);
            let band = deepest + urdyn::testing::contact::EXTREME_BAND;
            let far_kept = out
                .iter()
                .filter(|c| c.gap > band)
                .map(|c| c.gap)
                .fold(f64::NEG_INFINITY, f64::max);
            for r in &raw {
                if !out.iter().any(|c| c.key == r.key) {
                    assert!(r.gap >= far_kept, "phi {phi}: left out {r:?}, kept {out:?}");
                    assert!(r.gap > band || out.len() == 4, "phi {phi}: {r:?}");
                }
            }
            // the nearest point above the band (the corner that closes
            // next) is kept while within the margin
            // (when the band holds fewer points than the slots)
            let in_band = raw.iter().filter(|r| r.gap <= band).count();
            if let Some(next) = raw
                .iter()
                .filter(|r| in_band < 4 && r.gap > band && r.gap < MARGIN)
                .min_by(|x, y| x.gap.total_cmp(&y.gap))
            {
                assert!(
                    out.iter().any(|c| c.key == next.key),
                    "phi {phi}: the corner at {} m left out: {out:?}",
                    next.gap
                );
            }
        }
    }
    assert!(
        crowded >= 10,
        "{crowded} of {cases} poses had more than 4 points"
    );
}

#[test]
fn the_extremes_of_the_band_come_first() {
    // four points within the band and two above: the band's extremes fill
    // the slots, the points above get none
    let n = Vector3::z();
    let p = |x: f64, y: f64, gap: f64, key: u64| Raw {
        point: Vector3::new(x, y, 0.0),
        normal: n,
        gap,
        key,
    };
    let raw = [
        p(0.0, 0.0, -1e-4, 1),
        p(0.1, 0.0, -1e-4, 2),
        p(0.1, 0.1, -1e-4, 3),
        p(0.0, 0.1, -1e-4, 4),
        p(0.05, 0.2, 1e-3, 5),
        p(0.2, 0.05, 2e-3, 6),
    ];
    let out = reduce4(&raw);
    let mut keys: Vec<u64> = out.iter().map(|c| c.key).collect();
    keys.sort();
    assert_eq!(keys, [1, 2, 3, 4]);
    // one point in the band: it, then the two above, nearest first
    let raw = [
        p(0.0, 0.0, -1e-4, 1),
        p(0.2, 0.05, 2e-3, 6),
        p(0.05, 0.2, 1e-3, 5),
        p(0.1, 0.1, 3e-3, 7),
        p(0.3, 0.1, 4e-3, 8),
    ];
    let keys: Vec<u64> = reduce4(&raw).iter().map(|c| c.key).collect();
    assert_eq!(keys, [1, 5, 6, 7]);
}
