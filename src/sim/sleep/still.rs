//! Sleep's per-step tests (src/sim/sleep.rs, `Sleep::after_step`): each awake
//! tree's largest point speed, its still time and its own verdicts, and the
//! islands of the step's contact points (a union–find over the trees).
//!
//! The loops here run over the awake trees and the points at every step of a
//! run with sleep on: the per-tree vectors are sliced to the tree count once,
//! so that a tree's entries are read without a bounds test each.

use super::{Sleep, WORLD};
use crate::contact::ContactPoint;
use crate::spatial::Motion;
use nalgebra::Vector3;

/// A tree's verdict bit (`Sleep::verdict`): it lets its island sleep.
pub(super) const MAY_SLEEP: u8 = 1;
/// A tree's verdict bit: it lets its island begin to doze (`super::super::doze`).
pub(super) const MAY_DOZE: u8 = 2;

/// The spheres of `spheres` (sorted by `tree`, the tree of a body) that
/// another one of the same body with the same centre holds (a radius no
/// larger; of equal ones the first is kept) left out: a body's shape seen by
/// the ground detection and by the pairs' has two spheres about one centre
/// (its origin), and the larger bounds the speed.
///
/// Exact: a sphere's bound is fl(fl(√a) + fl(fl(√w) r)) with a = |v_c|² and
/// w = |ω|² the same for one body and one centre (a centre equal in value
/// gives the same a: the signs of its zeros vanish in the squares), and each
/// rounding is monotone, so a radius no larger gives a bound no larger, and
/// the max over the spheres is the same number (a NaN bound, which the max
/// skips, comes with a NaN w, the same for both).
pub(super) fn drop_held(
    spheres: &mut Vec<(usize, Vector3<f64>, f64)>,
    tree: impl Fn(usize) -> usize,
) {
    let mut keep = vec![true; spheres.len()];
    let mut s = 0;
    while s < spheres.len() {
        // (one tree's run: a body's spheres are all in it)
        let t = tree(spheres[s].0);
        let mut e = s;
        while e < spheres.len() && tree(spheres[e].0) == t {
            e += 1;
        }
        for i in s..e {
            let (b, c, r) = spheres[i];
            keep[i] = !(s..e).any(|j| {
                let (bj, cj, rj) = spheres[j];
                j != i && bj == b && cj == c && (rj > r || (rj == r && j < i))
            });
        }
        s = e;
    }
    let mut k = keep.into_iter();
    spheres.retain(|_| k.next().unwrap_or(true));
}

/// The root of tree `t`'s island (path halving: each visited tree is hung
/// from its grandparent).
#[inline]
pub(super) fn find(parent: &mut [usize], mut t: usize) -> usize {
    while parent[t] != t {
        parent[t] = parent[parent[t]];
        t = parent[t];
    }
    t
}

impl Sleep {
    /// Each awake tree's largest point speed from the body velocities
    /// `body_v`, its still time after a step of `h` (`forced[t]`: driven
    /// now), its verdicts (`verdict`: [`MAY_SLEEP`], [`MAY_DOZE`] when
    /// `doze_on`), and its own island (`parent`); the per-root flags `may`,
    /// `may_doze` set true (an island's root is one of its awake trees).
    /// Returns how many of them doze.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn still_pass(
        &mut self,
        awake_trees: &[usize],
        h: f64,
        body_v: &[Motion<f64>],
        forced: &[bool],
        doze_on: bool,
        may: &mut [bool],
        may_doze: &mut [bool],
    ) -> usize {
        let nt = self.parent.len();
        let parent = &mut self.parent[..nt];
        let may = &mut may[..nt];
        let may_doze = &mut may_doze[..nt];
        let verdict = &mut self.verdict[..nt];
        let still = &mut self.still[..nt];
        let never = &self.never[..nt];
        let forced = &forced[..nt];
        let left = &self.doze.left[..nt];
        let ranges = &self.tree_spheres[..nt];
        let (v_tol, t_tol) = (self.v_tol, self.t_tol);
        let mut dozing = 0;
        for &t in awake_trees {
            if t >= nt {
                continue;
            }
            parent[t] = t;
            may[t] = true;
            may_doze[t] = true;
            let f = forced[t];
            if left[t] > 0 {
                // dozing: its speed is held below sleep_velocity (and it does
                // not begin to doze: it dozes)
                dozing += 1;
                still[t] = if f { 0.0 } else { still[t] + h };
                let sleep = !(never[t] || f || still[t] < t_tol);
                verdict[t] = sleep as u8 * MAY_SLEEP + !doze_on as u8 * MAY_DOZE;
                continue;
            }
            // (a max: the same whatever the order of the spheres, each ≥ +0
            // or NaN, which the max skips; a body without a sphere is one
            // of radius 0.1 m about its centre of mass)
            let mut speed = 0.0f64;
            let (s0, s1) = ranges[t];
            for &(b, c, r) in self.spheres.get(s0..s1).unwrap_or(&[]) {
                if let Some(m) = body_v.get(b) {
                    let s = (m.lin + m.ang.cross(&c)).norm() + m.ang.norm() * r;
                    speed = speed.max(s);
                }
            }
            still[t] = if speed < v_tol && !f {
                still[t] + h
            } else {
                0.0
            };
            let sleep = !(never[t] || f || still[t] < t_tol);
            let doze = !doze_on || self.doze.may_begin(t, never[t], f, still[t], speed, v_tol);
            verdict[t] = sleep as u8 * MAY_SLEEP + doze as u8 * MAY_DOZE;
        }
        dozing
    }

    /// The islands of `points` and `joins` (body pairs): the union of the
    /// trees each joins (the world and a tree with itself join nothing).
    pub(super) fn join_islands(&mut self, points: &[ContactPoint], joins: &[(usize, usize)]) {
        let tree_of = &self.tree_of_body[..];
        let parent = &mut self.parent[..];
        // (a pair's points come one after another: the repeats of the last
        // pair are skipped, a union already made; finds only shorten paths)
        let mut last = (WORLD, WORLD);
        for p in points {
            join(tree_of, parent, &mut last, p.body, p.other);
        }
        for &(a, b) in joins {
            join(tree_of, parent, &mut last, a, b);
        }
    }
}

/// One union of [`Sleep::join_islands`]: bodies `a` and `b` (a repeat of
/// `last`, the pair joined before, skipped).
#[inline(always)]
fn join(tree_of: &[usize], parent: &mut [usize], last: &mut (usize, usize), a: usize, b: usize) {
    if (a, b) == *last {
        return;
    }
    *last = (a, b);
    let tree = |b: usize| tree_of.get(b).copied().unwrap_or(WORLD);
    let (ta, tb) = (tree(a), tree(b));
    if ta == WORLD || tb == WORLD || ta == tb {
        return;
    }
    let (ra, rb) = (find(parent, ta), find(parent, tb));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}
