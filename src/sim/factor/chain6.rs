//! The solves of [`MassFactor`] on a lone free body's tree (a chain of six
//! dofs, its factor one packed triangle), the only trees of a pile: on
//! fixed-size arrays, the same operations in the same order as on any path
//! (the same bits), without the path's look-ups and the per-row length tests.

use super::MassFactor;
use crate::model::Model;
use crate::spatial::ops::madd;

/// Where row i of a lone six-dof chain's packed triangle begins (i(i+1)/2):
/// L[i, 0..i], then D[i] ([`MassFactor::new`] packs each dof's path after
/// the last's).
const TRI6: [usize; 6] = [0, 1, 3, 6, 10, 15];

impl MassFactor {
    /// Keeps [`Self::lone_ranges`] only when each of its trees is a lone
    /// chain of six (dof k's parent k − 1 from a root k0) packed as one
    /// triangle ([`TRI6`]): checked once, so the solves look nothing up.
    pub(super) fn check_lone_ranges(&mut self) {
        let chain6 = |&(k0, k1): &(usize, usize)| {
            k1.checked_sub(k0) == Some(6)
                && self.root_chain.get(k1 - 1) == Some(&true)
                && self.len.get(k1 - 1) == Some(&6)
                && self.start.get(k0).map(|s| s + TRI6[5]) == self.start.get(k1 - 1).copied()
                && self
                    .start
                    .get(k0)
                    .is_some_and(|&s| s + 21 <= self.anc.len())
                && k1 <= self.dval.len()
        };
        if !self.lone_ranges.iter().all(chain6) {
            self.lone_ranges.clear();
        }
    }

    /// The dof ranges the solves work on, one tree each: every tree of a
    /// model of lone free bodies when none sleeps (not one range over them
    /// all: the trees are independent blocks, so each entry takes the same
    /// operations), else [`MassFactor::ranges`] (the awake trees').
    #[inline]
    fn solve_ranges(&self) -> &[(usize, usize)] {
        if !self.partial {
            &self.lone_ranges
        } else {
            self.ranges()
        }
    }

    /// The packed triangle of the lone chain of six from dof `k0`
    /// ([`Self::check_lone_ranges`]).
    #[inline(always)]
    fn tri6(&self, k0: usize) -> Option<&[f64; 21]> {
        let s0 = *self.start.get(k0)?;
        self.anc.get(s0..s0 + 21)?.try_into().ok()
    }

    /// [`MassFactor::solve`] (x cut to n) for a model of lone free bodies:
    /// true when done (false, nothing done, for any other model: a robot's
    /// solves keep their own loops, this function out of their way).
    #[inline(never)]
    pub(super) fn lone_solve(&self, x: &mut [f64]) -> bool {
        if self.lone_ranges.is_empty() {
            return false;
        }
        for &(k0, k1) in self.solve_ranges() {
            if let (Some(l), Some(d), Some(x)) = (
                self.tri6(k0),
                self.dval.get(k0..k1).and_then(|d| d.try_into().ok()),
                x.get_mut(k0..k1).and_then(|x| x.try_into().ok()),
            ) {
                solve(l, d, x);
            }
        }
        true
    }

    /// [`MassFactor::half_solve`] (z cut to n), as [`Self::lone_solve`].
    #[inline(never)]
    pub(super) fn lone_half_solve(&self, z: &mut [f64]) -> bool {
        if self.lone_ranges.is_empty() {
            return false;
        }
        for &(k0, k1) in self.solve_ranges() {
            if let (Some(l), Some(s), Some(z)) = (
                self.tri6(k0),
                self.inv_sqrt_d.get(k0..k1),
                z.get_mut(k0..k1),
            ) {
                half_solve(l, s, z);
            }
        }
        true
    }

    /// [`MassFactor::apply_r`] (v and out of length ≥ n), as [`Self::lone_solve`].
    #[inline(never)]
    pub(super) fn lone_apply_r(&self, v: &[f64], out: &mut [f64]) -> bool {
        if self.lone_ranges.is_empty() {
            return false;
        }
        for &(k0, k1) in self.solve_ranges() {
            if let (Some(l), Some(sd), Some(v), Some(out)) = (
                self.tri6(k0),
                self.sqrt_d.get(k0..k1),
                v.get(k0..k1),
                out.get_mut(k0..k1),
            ) {
                apply_r(l, sd, v, out);
            }
        }
        true
    }
}

/// Every tree's dof range of a model of lone free bodies (`lone`), when
/// they cover its `n` dofs in order; else none.
pub(super) fn lone_ranges(model: &Model, n: usize, lone: bool) -> Vec<(usize, usize)> {
    let r: Vec<_> = model.trees.iter().map(|t| (t.v.start, t.v.end)).collect();
    let tiled = r.iter().try_fold(0, |k, &(a, b)| (a == k).then_some(b)) == Some(n);
    if lone && tiled {
        r
    } else {
        Vec::new()
    }
}

/// [`MassFactor::solve`] on a lone chain of six (`l`: its packed triangle,
/// `d` its pivots): Lᵀ y = b two rows at a time (i and its parent i − 1, the
/// general solve's chain step: i's term reaches x[i − 1] first, then each
/// ancestor's entry takes i's term and i − 1's in turn), z = D⁻¹ y, L x = z
/// (each row's nearest ancestor first).
#[inline(always)]
fn solve(l: &[f64; 21], d: &[f64; 6], x: &mut [f64; 6]) {
    for i in [5, 3, 1] {
        let xi = x[i];
        let xp = madd(-l[TRI6[i] + i - 1], xi, x[i - 1]);
        x[i - 1] = xp;
        for k in (0..i - 1).rev() {
            x[k] = madd(-l[TRI6[i - 1] + k], xp, madd(-l[TRI6[i] + k], xi, x[k]));
        }
    }
    for (x, &d) in x.iter_mut().zip(d) {
        *x /= d;
    }
    for i in 0..6 {
        let mut acc = x[i];
        for k in (0..i).rev() {
            acc = madd(-l[TRI6[i] + k], x[k], acc);
        }
        x[i] = acc;
    }
}

/// [`MassFactor::half_solve`] on a lone chain of six (`s`: D^-½): row i is
/// z_i s_i − L[i, i−1] z_{i−1} − … − L[i, 0] z_0 (the nearest ancestor first).
#[inline(always)]
fn half_solve(l: &[f64; 21], s: &[f64], z: &mut [f64]) {
    let (Ok(s), Ok(z)) = (<&[f64; 6]>::try_from(s), <&mut [f64; 6]>::try_from(z)) else {
        return;
    };
    for i in 0..6 {
        let mut acc = z[i] * s[i];
        for k in (0..i).rev() {
            acc -= l[TRI6[i] + k] * z[k];
        }
        z[i] = acc;
    }
}

/// [`MassFactor::apply_r`] on a lone chain of six (`sd`: D^½): out_i = sd_i
/// (v_i + L[i, i−1] v_{i−1} + … + L[i, 0] v_0) (the nearest ancestor first).
#[inline(always)]
fn apply_r(l: &[f64; 21], sd: &[f64], v: &[f64], out: &mut [f64]) {
    let (Ok(sd), Ok(v), Ok(out)) = (
        <&[f64; 6]>::try_from(sd),
        <&[f64; 6]>::try_from(v),
        <&mut [f64; 6]>::try_from(out),
    ) else {
        return;
    };
    for i in 0..6 {
        let mut acc = v[i];
        for k in (0..i).rev() {
            acc += l[TRI6[i] + k] * v[k];
        }
        out[i] = sd[i] * acc;
    }
}
