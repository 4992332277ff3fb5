//! The climbing hulls' GJK started from the pair's last simplex
//! (src/contact/narrow/climb.rs) against parry's own start: along paths of
//! small steps (b turning, sliding and sinking into a, as talos's links do
//! against each other, 1–2 mrad and 0.1 mm a step), the query that keeps its
//! manifold and workspace finds what a fresh one (parry's start) finds.

use super::superellipsoid;
use crate::common::lcg::Lcg;
use parry3d_f64::query::{ContactManifold, ContactManifoldsWorkspace};
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{pair_shape, parry_points, PairShape, Raw};

const MARGIN: f64 = 0.005;

fn unit(g: &mut Lcg) -> Unit<Vector3<f64>> {
    Unit::new_normalize(Vector3::new(
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
    ))
}

/// A random rounded box's hull (266 points: the climbing kind).
fn hull(g: &mut Lcg) -> PairShape {
    let half = [
        g.uniform(0.02, 0.08),
        g.uniform(0.02, 0.08),
        g.uniform(0.02, 0.08),
    ];
    let h = superellipsoid(half, g.uniform(0.3, 0.8));
    pair_shape(h.shared(), Se3::identity(), true)
}

/// The points of b at `wb` on a at the identity, with the manifolds and
/// workspace given.
fn query(
    a: &PairShape,
    b: &PairShape,
    wb: &Se3<f64>,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    ws: &mut Option<ContactManifoldsWorkspace>,
) -> Vec<Raw> {
    let mut raw = Vec::new();
    parry_points(a, b, &Se3::identity(), wb, MARGIN, manifolds, ws, &mut raw);
    raw
}

fn deepest(raw: &[Raw]) -> Option<&Raw> {
    raw.iter().min_by(|p, q| p.gap.total_cmp(&q.gap))
}

/// Every point of `p` within `tol` (position and gap) of one of `q`.
fn within(p: &[Raw], q: &[Raw], tol: f64) -> bool {
    p.iter().all(|x| {
        q.iter()
            .any(|y| (x.point - y.point).norm() < tol && (x.gap - y.gap).abs() < tol)
    })
}

/// Counts of the steps compared: (with points, penetrating, the points
/// matched both ways, a warm start used).
#[derive(Default, Debug)]
struct Seen {
    touching: usize,
    deep: usize,
    matched: usize,
    warm: usize,
}

/// One path of `steps` steps: b starts `gap0` from a along a random
/// direction, sinks `sink` a step, turns `turn` rad and slides `slide` a step.
fn path(g: &mut Lcg, case: usize, steps: usize, seen: &mut Seen) {
    let (a, b) = (hull(g), hull(g));
    let u = unit(g);
    let axis = unit(g);
    let r0 = Rotation3::from_axis_angle(&unit(g), g.uniform(0.0, 3.0));
    let slide_dir = Unit::new_normalize(u.cross(&unit(g)));
    let (turn, slide, sink) = (
        g.uniform(0.0005, 0.002),
        g.uniform(0.0, 1e-4),
        g.uniform(1e-5, 4e-5),
    );
    // b's centre along u where the fresh query first finds it within 4 mm
    let place = |s: f64, k: usize| {
        let r = Rotation3::from_axis_angle(&axis, turn * k as f64) * r0;
        let t = u.into_inner() * s + slide_dir.into_inner() * (slide * k as f64);
        Se3::new(r.into_inner(), t)
    };
    let mut s = 0.3;
    while s > 0.0 {
        let raw = query(&a, &b, &place(s, 0), &mut Vec::new(), &mut None);
        if deepest(&raw).is_some_and(|p| p.gap < 0.004) {
            break;
        }
        s -= 0.001;
    }
    let (mut kept, mut ws) = (Vec::new(), None);
    for k in 0..steps {
        // in and out again: 2/3 of the path sinking, the rest rising
        let depth = if 3 * k < 2 * steps {
            sink * k as f64
        } else {
            sink * (4 * steps - 4 * k) as f64 / 2.0
        };
        let wb = place(s - depth, k);
        if !kept.is_empty() && ws.is_some() {
            seen.warm += 1;
        }
        let warm = query(&a, &b, &wb, &mut kept, &mut ws);
        let fresh = query(&a, &b, &wb, &mut Vec::new(), &mut None);
        let at = format!("case {case} step {k}");
        assert_eq!(
            warm.is_empty(),
            fresh.is_empty(),
            "{at}: {warm:?} / {fresh:?}"
        );
        let (Some(dw), Some(df)) = (deepest(&warm), deepest(&fresh)) else {
            continue;
        };
        seen.touching += 1;
        seen.deep += usize::from(df.gap < 0.0);
        // GJK's stop (a relative duality gap of 1.5·10⁻⁷ on gaps of
        // millimetres) and EPA's: the same depth to 10 nm, the same normal
        // to 10⁻⁴ rad
        assert!(
            (dw.gap - df.gap).abs() < 1e-8,
            "{at}: deepest {} / {}",
            dw.gap,
            df.gap
        );
        let cos = dw.normal.dot(&df.normal);
        assert!(
            cos > 1.0 - 5e-9,
            "{at}: normals {} / {}",
            dw.normal,
            df.normal
        );
        // the points are the support features' clip, the same features
        // unless two faces tie for the support: then within 0.1 mm
        if within(&warm, &fresh, 1e-7) && within(&fresh, &warm, 1e-7) {
            seen.matched += 1;
        } else {
            assert!(
                within(&warm, &fresh, 1e-4) && within(&fresh, &warm, 1e-4),
                "{at}: {warm:?} / {fresh:?}"
            );
        }
    }
}

#[test]
fn warm_started_gjk_finds_what_parry_finds() {
    let mut g = Lcg(0x5eed_c11b);
    let mut seen = Seen::default();
    for case in 0..24 {
        path(&mut g, case, 150, &mut seen);
    }
    // the paths touch, sink in and come out, and the warm start is used
    assert!(seen.touching > 1500 && seen.deep > 300, "{seen:?}");
    assert!(seen.warm > 1500, "{seen:?}");
    // most steps find the very points (ties of faces are rare)
    assert!(seen.matched * 10 > seen.touching * 9, "{seen:?}");
}
