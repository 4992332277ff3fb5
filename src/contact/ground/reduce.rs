//! The reduction of a shape's ground points to a persistent patch.

use super::ContactPoint;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// The maxima of `reduce`'s criteria (−φ, then cᵢ·x + sᵢ·y for the
/// directions `dir`) over the vertices `verts[i]`, i in `cand`, placed by `m`
/// (φ = z − ground); `D`: the number of directions when it is known at compile
/// time (the default 3), else 0 and every direction of `dir` is taken (the
/// unused ones are (0, 0): their maxima are not looked at).
#[inline(always)]
pub(super) fn band_best<const D: usize>(
    m: &Se3<f64>,
    verts: &[Vector3<f64>],
    cand: &[u32],
    ground: f64,
    dir: &[(f64, f64); MAX_DIRS],
) -> [f64; MAX_DIRS + 1] {
    // max(b, k) as `if k > b { k } else { b }`: one instruction (maxsd),
    // a NaN k ignored as `reduce` does
    let up = |b: f64, k: f64| if k > b { k } else { b };
    let nd = if D == 0 { MAX_DIRS } else { D };
    let mut best = [f64::NEG_INFINITY; MAX_DIRS + 1];
    for &i in cand {
        let p = m.act_point(&verts[i as usize]);
        best[0] = up(best[0], -(p.z - ground));
        for q in 0..nd {
            let (c, sn) = dir[q];
            best[q + 1] = up(best[q + 1], c * p.x + sn * p.y);
        }
    }
    best
}

/// How much shallower (m) a point kept last step may be than the deepest and
/// still be chosen as the deepest.
pub(super) const HOLD_DEEPEST: f64 = 1e-4;
/// How much less far out (m) a point kept last step may be than a direction's
/// extreme and still be chosen for it: 2 cm (a foot's size) keeps a patch while
/// the contact lasts; 1 mm left solo12 with 2× the sweeps (its patches changed
/// every few steps).
pub(super) const HOLD_EXTREME: f64 = 2e-2;

/// Most horizontal directions a reduced manifold uses.
pub(super) const MAX_DIRS: usize = 8;

/// The `maxp − 1` (1 to [`MAX_DIRS`]) evenly spread horizontal directions
/// (cos, sin) of [`reduce`].
pub(super) fn reduce_directions(maxp: usize) -> [(f64, f64); MAX_DIRS] {
    let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
    let mut dir = [(0.0, 0.0); MAX_DIRS];
    for (d, x) in dir.iter_mut().enumerate().take(dirs) {
        let (sn, c) = (std::f64::consts::TAU * d as f64 / dirs as f64).sin_cos();
        *x = (c, sn);
    }
    dir
}

/// Appends `pts` to `out`, reduced to at most `maxp` points when there are
/// more: the deepest point, then the extremes in `maxp − 1` evenly spaced
/// horizontal directions (a patch spanning the support polygon: a cylinder
/// lying flat keeps three rim points 120° apart, not a cluster). Each choice
/// prefers a point kept last time (`prev`, by slot) when it is within
/// [`HOLD_DEEPEST`] or [`HOLD_EXTREME`] of the best, then the lowest slot: the set stays the same from step to step while the contact does, so
/// warm starts keep working (a deepest point that flipped between near-equal
/// corners kept solo8's base rocking in a 6 ms cycle).
/// `dir`: [`reduce_directions`] of `maxp`.
pub(super) fn reduce(
    pts: &[ContactPoint],
    maxp: usize,
    out: &mut Vec<ContactPoint>,
    prev: &[bool],
    dir: &[(f64, f64); MAX_DIRS],
) {
    if pts.len() <= maxp {
        out.extend_from_slice(pts);
        return;
    }
    let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
    // criterion 0: depth; 1..=dirs: how far out along a direction
    let key = |p: &ContactPoint, q: usize| -> f64 {
        if q == 0 {
            -p.gap
        } else {
            let (c, sn) = dir[q - 1];
            c * p.point.x + sn * p.point.y
        }
    };
    // one pass for every criterion's best value
    let mut best = [f64::NEG_INFINITY; MAX_DIRS + 1];
    for p in pts {
        for (q, b) in best.iter_mut().enumerate().take(dirs + 1) {
            let k = key(p, q);
            if k > *b {
                *b = k;
            }
        }
    }
    // one pass for each criterion's choice: within its hold of the best a point
    // kept last time first, then the lowest slot
    let mut choice = [(true, usize::MAX, 0usize); MAX_DIRS + 1];
    for (i, p) in pts.iter().enumerate() {
        let was = prev.get(p.slot).copied().unwrap_or(false);
        for (q, ch) in choice.iter_mut().enumerate().take(dirs + 1) {
            let hold = match (was, q) {
                (false, _) => 1e-6,
                (true, 0) => HOLD_DEEPEST,
                (true, _) => HOLD_EXTREME,
            };
            if key(p, q) >= best[q] - hold && (!was, p.slot) < (ch.0, ch.1) {
                *ch = (!was, p.slot, i);
            }
        }
    }
    let start = out.len();
    for &(_, _, i) in choice.iter().take(dirs + 1) {
        if out.len() - start >= maxp {
            break;
        }
        if !out[start..].iter().any(|q| q.slot == pts[i].slot) {
            out.push(pts[i]);
        }
    }
}

/// The slope (height along the normal over the distance across it) above
/// which a point of a pair's patch is hidden by a deeper point of the same
/// patch (see [`cull_hidden`]): 0.05, a tilt of 2.9° about the deeper point,
/// which a body turning at 10 rad/s takes 5 steps of 1 ms to go through.
pub(crate) const HIDDEN_SLOPE: f64 = 0.05;

/// The slope above which a ground point is hidden by a deeper point of the
/// same body less than [`TINY_PATCH`] of its shape's radius away (a
/// rounded foot's ring of hull vertices: 0.1–0.5 mm up, 2–7 mm across).
pub(crate) const HIDDEN_SLOPE_TINY: f64 = 0.02;

/// A ground patch is tiny when its points are less than this fraction of
/// their shape's bounding radius apart.
pub(crate) const TINY_PATCH: f64 = 0.5;

/// `Some((h, d))`: `p` lies `h` > 0 above `q` along `q`'s normal, `d` across it.
#[inline]
pub(crate) fn above(p: &ContactPoint, q: &ContactPoint) -> Option<(f64, f64)> {
    let h = p.gap - q.gap;
    if !(h > 0.0) {
        return None;
    }
    let d = p.point - q.point;
    let across = d - q.normal * d.dot(&q.normal);
    Some((h, across.norm()))
}

/// Drops from `out[start..]` every point `p` that `hidden(p, q)` says a
/// deeper point `q` of the same body in the same run of `out` hides (a
/// body's shapes' points are contiguous). The callers' rule: `p` lies above
/// `q` more steeply than a slope, so it cannot reach the other side before
/// `q` unless the body turns about `q` through that slope within the step
/// (a translation keeps it above `q`), and when it does, the next detection
/// finds it; meanwhile it would carry no force, only rows. A rounded foot's
/// ring of vertices a fraction of a millimetre above its lowest one, and a
/// lower leg's copy of the foot millimetres up, are hidden; the corners of a
/// face lying flat (equal heights) are not (docs/theory.md §"Contact points
/// hidden by deeper ones").
pub(crate) fn cull_hidden(
    out: &mut Vec<ContactPoint>,
    start: usize,
    hidden: impl Fn(&ContactPoint, &ContactPoint) -> bool,
) {
    let n = out.len();
    let mut w = start;
    let mut a = start;
    while a < n {
        let body = out[a].body;
        let mut b = a + 1;
        while b < n && out[b].body == body {
            b += 1;
        }
        // a run's verdicts first (a bit a point), then the kept ones moved down
        let mut hide = 0u64;
        if b - a > 1 && b - a <= 64 {
            for i in a..b {
                if (a..b).any(|j| j != i && hidden(&out[i], &out[j])) {
                    hide |= 1 << (i - a);
                }
            }
        }
        for i in a..b {
            if hide & (1 << (i - a)) == 0 {
                out[w] = out[i];
                w += 1;
            }
        }
        a = b;
    }
    out.truncate(w);
}
