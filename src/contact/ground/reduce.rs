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
/// The deepest pick goes first to `deep`, the slot it took last time, while
/// that point is kept and within the hold: among several kept points within
/// [`HOLD_DEEPEST`] of the deepest, the lowest slot alone could take the pick
/// from a deeper one, which then left the patch until it was deeper by the
/// hold, came back, and lost the pick again, every other step (borinot lying
/// with one point at the slop's depth, 1e-4 m, and another at 0: a limit cycle
/// that kept it awake). `deep` receives this call's pick (`usize::MAX` when
/// every point is kept unreduced: the deepest of them).
/// `dir`: [`reduce_directions`] of `maxp`.
pub(super) fn reduce(
    pts: &[ContactPoint],
    maxp: usize,
    out: &mut Vec<ContactPoint>,
    prev: &[bool],
    dir: &[(f64, f64); MAX_DIRS],
    deep: &mut usize,
) {
    if pts.len() <= maxp {
        out.extend_from_slice(pts);
        *deep = pts
            .iter()
            .fold((f64::INFINITY, usize::MAX), |a, p| {
                if p.gap < a.0 {
                    (p.gap, p.slot)
                } else {
                    a
                }
            })
            .1;
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
    // the deepest pick: last time's while it is kept and within the hold
    if let Some(i) = pts.iter().position(|p| p.slot == *deep) {
        if prev.get(*deep).copied().unwrap_or(false) && key(&pts[i], 0) >= best[0] - HOLD_DEEPEST {
            choice[0] = (false, *deep, i);
        }
    }
    *deep = pts[choice[0].2].slot;
    let start = out.len();
    for &(_, _, i) in choice.iter().take(dirs + 1) {
        if out.len() - start >= maxp {
            break;
        }
        if !out[start..].iter().any(|q| q.slot == pts[i].slot) {
            out.push(pts[i]);
        }
    }
    for p in pts {
        if prev.get(p.slot).copied().unwrap_or(false)
            && !out[start..].iter().any(|q| q.slot == p.slot)
        {
            keep_penetrating(out, start, maxp, *p);
        }
    }
}

/// A point `p` kept last time that the picks left out: while it is in the
/// ground (gap < 0) it goes back into the patch `out[start..]` (at most `maxp`
/// points), in place of the picked point highest above the ground when that
/// one does not touch (gap > 0; never the deepest pick, `out[start]`).
/// Without it a shape rocking on two opposite points, neither of them an
/// extreme of the horizontal directions, kept only the deeper one as the
/// deepest pick while points above the ground held the other picks: the
/// other sank until it was deeper, took the pick, and the first sank in turn
/// (borinot on its side, a seesaw every 7 ms that never came to rest).
pub(super) fn keep_penetrating(
    out: &mut Vec<ContactPoint>,
    start: usize,
    maxp: usize,
    p: ContactPoint,
) {
    if p.gap >= 0.0 {
        return;
    }
    if out.len() - start < maxp {
        out.push(p);
        return;
    }
    let mut high = None;
    for (i, q) in out.iter().enumerate().skip(start + 1) {
        if q.gap > 0.0 && high.map_or(true, |h: usize| q.gap > out[h].gap) {
            high = Some(i);
        }
    }
    if let Some(h) = high {
        out[h] = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A hull lying on two opposite points, neither of them an extreme of the
    /// three horizontal directions (0°, 120°, 240°), with three points above
    /// the ground that are: borinot's base as it rocked (docs/robots.md).
    fn points(gap0: f64) -> Vec<ContactPoint> {
        let p = |slot: usize, x: f64, y: f64, gap: f64| ContactPoint {
            shape: 0,
            slot,
            body: 1,
            point: Vector3::new(x, y, gap),
            gap,
            geom: 0,
            other: 0,
            other_geom: usize::MAX,
            normal: Vector3::z(),
            friction: 1.0,
            fresh: false,
            key: 0,
        };
        vec![
            p(0, -0.16, 0.02, gap0),
            p(1, 0.143, -0.124, -2.8e-4),
            p(2, 0.143, -0.128, 6e-4),
            p(3, 0.016, 0.187, 2.4e-5),
            p(4, -0.061, -0.171, 1.1e-3),
        ]
    }

    fn slots(out: &[ContactPoint]) -> Vec<usize> {
        let mut s: Vec<usize> = out.iter().map(|p| p.slot).collect();
        s.sort();
        s
    }

    /// By hand: the deepest is slot 1; the extremes along 0°, 120°, 240° are
    /// slots 1/2 (x = 0.143, within the 2 cm hold: the kept slot 2), 3
    /// (−x/2 + 0.866 y = 0.154) and 4 (−x/2 − 0.866 y = 0.179); slot 0 is
    /// none of them (0.097 and 0.063 along 120° and 240°). Kept last time
    /// and 0.15 mm in the ground, it replaces slot 4, the pick highest above
    /// it (1.1 mm); out of the ground (gap > 0) it is left out.
    #[test]
    fn a_kept_point_in_the_ground_stays_in_the_patch() {
        let dir = reduce_directions(4);
        let mut prev = vec![false; 5];
        for s in [0, 2, 3, 4] {
            prev[s] = true;
        }
        let (mut out, mut deep) = (Vec::new(), 0);
        reduce(&points(-1.5e-4), 4, &mut out, &prev, &dir, &mut deep);
        assert_eq!(slots(&out), vec![0, 1, 2, 3]);
        assert_eq!((out[0].slot, deep), (1, 1), "the deepest pick");
        let (mut out, mut deep) = (Vec::new(), 0);
        reduce(&points(1e-5), 4, &mut out, &prev, &dir, &mut deep);
        assert_eq!(slots(&out), vec![1, 2, 3, 4]);
    }

    /// The deepest pick stays with last time's point while it is kept and
    /// within HOLD_DEEPEST (1e-4 m) of the deepest: slot 0 at 0.25 mm, slot 1
    /// at 0.28 mm, both kept. Last time's pick 1 stays (the lowest slot alone,
    /// the rule before, gave 0); last time's pick 0 stays too. At 0.15 mm
    /// (0.13 mm shallower than slot 1) slot 0 loses the pick to 1.
    #[test]
    fn the_deepest_pick_holds_while_within_the_hold() {
        let dir = reduce_directions(4);
        let prev = vec![true, true, false, true, false];
        for (gap0, last, pick) in [(-2.5e-4, 1, 1), (-2.5e-4, 0, 0), (-1.5e-4, 0, 1)] {
            let (mut out, mut deep) = (Vec::new(), last);
            reduce(&points(gap0), 4, &mut out, &prev, &dir, &mut deep);
            assert_eq!(
                (out[0].slot, deep),
                (pick, pick),
                "gap0 {gap0}, last {last}"
            );
        }
    }
}
