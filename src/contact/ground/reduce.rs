//! The reduction of a shape's ground points to a persistent patch.

use super::patch::Soa;
use super::ContactPoint;

/// The maxima of `reduce`'s criteria (−φ, then cᵢ·x + sᵢ·y for the
/// directions `dir`) over the first `n` world points of `pts` (φ = z − ground); `D`: the
/// number of directions when it is known at compile time (the default 3), else
/// 0 and every direction of `dir` is taken (the unused ones are (0, 0): their
/// maxima are not looked at).
#[inline(always)]
pub(super) fn band_best<const D: usize>(
    pts: &Soa,
    n: usize,
    ground: f64,
    dir: &[(f64, f64); MAX_DIRS],
) -> [f64; MAX_DIRS + 1] {
    let nd = if D == 0 { MAX_DIRS } else { D };
    let mut best = [f64::NEG_INFINITY; MAX_DIRS + 1];
    let (xs, ys, zs) = (&pts.x[..n], &pts.y[..n], &pts.z[..n]);
    best[0] = lane_max(zs, zs, |z, _| -(z - ground));
    for q in 0..nd {
        let (c, sn) = dir[q];
        best[q + 1] = lane_max(xs, ys, |x, y| c * x + sn * y);
    }
    best
}

/// The maximum of `key(a[i], b[i])` over i (−∞ for none; a NaN key ignored):
/// four running maxima, point i in lane i mod 4 (vector lanes), then the
/// lanes' maximum. The same maximum of the same keys as one running maximum
/// over the points in order, up to the sign of a zero, which the maxima's one
/// use (`best − hold`, `best − 1e-6`: [`super::GroundContact::hull_patch`])
/// does not see.
#[inline(always)]
fn lane_max(a: &[f64], b: &[f64], key: impl Fn(f64, f64) -> f64) -> f64 {
    // max(m, k) as `if k > m { k } else { m }`: one instruction (maxpd),
    // a NaN k ignored as `reduce` does
    let up = |m: f64, k: f64| if k > m { k } else { m };
    let mut acc = [f64::NEG_INFINITY; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (a4, b4) in ac.zip(bc) {
        for l in 0..4 {
            acc[l] = up(acc[l], key(a4[l], b4[l]));
        }
    }
    let mut best = f64::NEG_INFINITY;
    for k in acc {
        best = up(best, k);
    }
    for (&x, &y) in ar.iter().zip(br) {
        best = up(best, key(x, y));
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
