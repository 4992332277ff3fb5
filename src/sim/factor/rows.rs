//! A constraint row through the mass factor, y ← R⁻ᵀ y (docs/theory.md
//! §"Tree-sparse LTDL"): the rows of the solve held compactly over a dof path
//! (one body's chain: every contact and joint row of a robot), one, three or
//! four lanes at once.

use super::super::factor_dense::dense_forward;
use super::zeros::plain;
use super::MassFactor;
use crate::dynamics::linalg::by_size;

/// `pub fn NAME<const A: usize, const B: usize>(&self, path, w, …)`: rows on
/// a path of two trees' chains (`A` dofs then `B`), one or more right-hand
/// sides `w` (each with the names of its two halves), each chain eliminated
/// on its own by `ELIM` (one body for one and two sides).
macro_rules! two_chain_lanes {
    ($(#[$m:meta])* $name:ident, $elim:ident, $($w:ident / $wa:ident / $wb:ident),+) => {
        $(#[$m])*
        #[inline(always)]
        pub fn $name<const A: usize, const B: usize>(
            &self,
            path: &[usize],
            $($w: &mut [[f64; 4]]),+
        ) -> bool {
            if !(self.two_chains::<A, B>(path) $(&& $w.len() == A + B)+) {
                return false;
            }
            let (pa, pb) = path.split_at(A);
            $(let ($wa, $wb) = $w.split_at_mut(A);)+
            match (
                ($(<&mut [[f64; 4]; A]>::try_from($wa),)+),
                ($(<&mut [[f64; 4]; B]>::try_from($wb),)+),
            ) {
                (($(Ok($wa),)+), ($(Ok($wb),)+)) => {
                    self.$elim::<B>(pb, $($wb),+) && self.$elim::<A>(pa, $($wa),+)
                }
                _ => false,
            }
        }
    };
}

impl MassFactor {
    /// y ← R⁻ᵀ y for a row held compactly over `path` (`y[t]` is the entry of
    /// dof `path[t]`; the row is zero off the path).
    #[inline]
    pub fn row_transform(&self, path: &[usize], y: &mut [f64]) {
        let n = self.n;
        let m = self.m.as_slice();
        if !self.tree {
            // R⁻ᵀ = L⁻¹ (the path is 0..n)
            by_size!(n, N => dense_forward::<N, 1>(m, &self.inv_sqrt_d, n, [y]));
            return;
        }
        let len = path.len().min(y.len());
        // Lᵀ g = j from the leaf in: along a path the tree is a chain, the
        // ancestors of path[t] are path[..t]
        let chain = self.is_chain(&path[..len]);
        for t in (0..len).rev() {
            let yt = y[t];
            if yt == 0.0 {
                continue;
            }
            if chain {
                let s = self.start[path[t]];
                for (ys, l) in y[..t].iter_mut().zip(&self.anc[s..s + t]) {
                    *ys -= l * yt;
                }
            } else {
                match self.ancestors(path, t) {
                    Some((s0, anc)) => {
                        for (ys, l) in y[s0..t].iter_mut().zip(anc) {
                            *ys -= l * yt;
                        }
                    }
                    None => self.for_ancestors(path, t, |s, l| y[s] -= l * yt),
                }
            }
        }
        for t in 0..len {
            y[t] *= self.inv_sqrt_d[path[t]];
        }
    }

    /// [`Self::row_transform`] of three rows on one path (a contact's normal
    /// and tangents) in one pass over the factor.
    #[inline]
    pub fn row_transform3(&self, path: &[usize], y0: &mut [f64], y1: &mut [f64], y2: &mut [f64]) {
        let n = self.n;
        let m = self.m.as_slice();
        if !self.tree {
            by_size!(n, N => dense_forward::<N, 3>(m, &self.inv_sqrt_d, n, [y0, y1, y2]));
            return;
        }
        let len = path.len().min(y0.len()).min(y1.len()).min(y2.len());
        if self.is_chain(&path[..len]) {
            for t in (0..len).rev() {
                let (a0, a1, a2) = (y0[t], y1[t], y2[t]);
                let s = self.start[path[t]];
                for (s, &l) in (0..t).zip(&self.anc[s..s + t]) {
                    y0[s] -= l * a0;
                    y1[s] -= l * a1;
                    y2[s] -= l * a2;
                }
            }
        } else {
            self.row_transform3_general(path, len, y0, y1, y2);
        }
        for t in 0..len {
            let d = self.inv_sqrt_d[path[t]];
            y0[t] *= d;
            y1[t] *= d;
            y2[t] *= d;
        }
    }

    /// [`Self::row_transform3`]'s elimination on any path (before the scaling).
    #[inline]
    fn row_transform3_general(
        &self,
        path: &[usize],
        len: usize,
        y0: &mut [f64],
        y1: &mut [f64],
        y2: &mut [f64],
    ) {
        for t in (0..len).rev() {
            let (a0, a1, a2) = (y0[t], y1[t], y2[t]);
            match self.ancestors(path, t) {
                Some((s0, anc)) => {
                    for (s, &l) in (s0..t).zip(anc) {
                        y0[s] -= l * a0;
                        y1[s] -= l * a1;
                        y2[s] -= l * a2;
                    }
                }
                None => self.for_ancestors(path, t, |s, l| {
                    y0[s] -= l * a0;
                    y1[s] -= l * a1;
                    y2[s] -= l * a2;
                }),
            }
        }
    }

    /// [`Self::row_transform`] of one row held in registers, on a path of `N`
    /// dofs that is a tree factor's chain root … leaf (a joint row's, or a
    /// contact's on one body): every loop's bounds constant, each entry the
    /// same operations in the same order (a zero entry skipped, as there), so
    /// the same bits. False where the factor is dense, `path` is not that
    /// chain or L's entries are not all there; `y` is then not (or not wholly)
    /// transformed, and the caller starts again from its row.
    #[inline(always)]
    pub fn chain_row<const N: usize>(&self, path: &[usize], y: &mut [f64; N]) -> bool {
        if !(self.tree && path.len() == N && self.is_chain(path)) {
            return false;
        }
        // Lᵀ g = j from the leaf in: y[s] −= L[path[t], path[s]]·y[t], s < t
        for t in (1..N).rev() {
            let yt = y[t];
            if yt == 0.0 {
                continue;
            }
            let s = self.start[path[t]];
            let Some(anc) = self.anc.get(s..s + t) else {
                return false;
            };
            for (ys, &l) in y.iter_mut().zip(anc) {
                *ys -= l * yt;
            }
        }
        // y ← D^-½ g
        for (yt, &k) in y.iter_mut().zip(path) {
            *yt *= self.inv_sqrt_d[k];
        }
        true
    }

    /// Tree: `f(s, L[path[t], path[s]])` for each ancestor `path[s]` of
    /// `path[t]` on the path, root first (a row on two branches of one tree
    /// interleaved: [`Self::ancestors`]'s `None`). The path and each dof's
    /// ancestors (`table`, root first) both ascend, so one merge finds them;
    /// L is zero at the path's other entries, whose `y[s] −= 0·a` is skipped.
    #[inline(always)]
    fn for_ancestors(&self, path: &[usize], t: usize, mut f: impl FnMut(usize, f64)) {
        let Some(&d) = path.get(t) else {
            return;
        };
        let (s, l) = (self.start[d], self.len[d]);
        let (anc, dofs) = (&self.anc[s..s + l - 1], &self.table[s..s + l - 1]);
        let mut p = 0;
        for (&a, &j) in anc.iter().zip(dofs) {
            while p < t && path[p] < j {
                p += 1;
            }
            if p < t && path[p] == j {
                f(p, a);
                p += 1;
            }
        }
    }

    /// Tree: where the ancestors of `path[t]` lie on `path` when they are two
    /// runs, `path[..k]` and `path[p..t]` (a row on two branches of one tree:
    /// the branches' common ancestors, then `path[t]`'s own branch after the
    /// other's), with L's entries at them (`k` then `t − p`); `None` otherwise.
    #[inline(always)]
    fn ancestor_runs(&self, path: &[usize], t: usize) -> Option<(usize, usize, &[f64])> {
        let d = *path.get(t)?;
        let (s, l) = (*self.start.get(d)?, *self.len.get(d)?);
        let na = l.checked_sub(1)?;
        let dofs = self.table.get(s..s + na)?;
        // the own branch: the ancestors from the nearest back, on path[..t]'s end
        let (mut k, mut p) = (na, t);
        while k > 0 && p > 0 && dofs[k - 1] == path[p - 1] {
            k -= 1;
            p -= 1;
        }
        (k <= p && path.get(..k)? == &dofs[..k]).then(|| (k, p, &self.anc[s..s + na]))
    }

    /// [`Self::row_transform_lanes`] of rows held in registers, `w[t] = [y₀ₜ,
    /// y₁ₜ, y₂ₜ, pad]`, on a path of `N` dofs that is a tree factor's chain
    /// root … leaf (a contact's three rows on one body's path): the same
    /// operations in the same order (the same bits). False where the factor
    /// is dense or `path` is not the chain; `w` is then not (or not wholly)
    /// transformed, and the caller starts again from its rows.
    #[inline(always)]
    pub fn chain_lanes<const N: usize>(&self, path: &[usize], w: &mut [[f64; 4]; N]) -> bool {
        self.tree && path.len() == N && self.is_chain(path) && self.chain_elim::<N>(path, w)
    }

    /// [`Self::chain_lanes`] of two contacts' rows `w` and `v` on the same
    /// chain path (two contacts of a free body on the ground): one walk of L
    /// for both, each lane's entry the same operations in the same order as
    /// [`Self::chain_lanes`] alone (the same bits). False where the factor is
    /// dense or `path` is not the chain.
    #[inline(always)]
    pub fn chain_lanes2<const N: usize>(
        &self,
        path: &[usize],
        w: &mut [[f64; 4]; N],
        v: &mut [[f64; 4]; N],
    ) -> bool {
        self.tree && path.len() == N && self.is_chain(path) && self.chain_elim2::<N>(path, w, v)
    }

    /// Whether `path` is a tree factor's chain, root … leaf, of `N` dofs
    /// (what [`Self::chain_lanes`] takes).
    #[inline(always)]
    pub fn is_chain_of<const N: usize>(&self, path: &[usize]) -> bool {
        self.tree && path.len() == N && self.is_chain(path)
    }

    /// Whether `path` is two trees' chains, root … leaf each, of `A` dofs
    /// then `B` (a tree factor's; what [`Self::two_chain_lanes`] takes).
    #[inline(always)]
    pub fn two_chains<const A: usize, const B: usize>(&self, path: &[usize]) -> bool {
        self.tree && path.len() == A + B && {
            let (pa, pb) = path.split_at(A);
            self.is_chain(pa) && self.is_chain(pb)
        }
    }

    two_chain_lanes! {
        /// [`Self::row_transform_lanes`] of rows held in registers on a path
        /// of `A + B` dofs that is two trees' chains, root … leaf each (a
        /// contact's three rows between two free bodies: every contact of a
        /// pile): L is zero between the trees, so each chain is eliminated on
        /// its own, each lane's entry taking the same operations in the same
        /// order (the same bits). False where the factor is dense or `path` is
        /// not two such chains.
        two_chain_lanes, chain_elim, w / wa / wb
    }

    two_chain_lanes! {
        /// [`Self::two_chain_lanes`] of two contacts' rows on the same path
        /// (two contacts between the same two free bodies), `w` and `v`: one
        /// walk of L for both, each lane's entry taking the same operations
        /// in the same order as [`Self::two_chain_lanes`] alone (the same
        /// bits). False where the factor is dense or `path` is not two such
        /// chains.
        two_chain_lanes2, chain_elim2, w / wa / wb, v / va / vb
    }

    /// [`Self::chain_elim`] of two right-hand sides `w`, `v` on one chain path:
    /// each L entry loaded once for both, each lane's entry the same operations
    /// in the same order as [`Self::chain_elim`] (the same bits).
    #[inline(always)]
    fn chain_elim2<const N: usize>(
        &self,
        path: &[usize],
        w: &mut [[f64; 4]; N],
        v: &mut [[f64; 4]; N],
    ) -> bool {
        let Some(path) = path.get(..N) else {
            return false;
        };
        // (L zero on the chain and both sides plain: no step changes a bit, zeros.rs)
        let zero = path.last().is_some_and(|&d| self.zero_chain(d));
        let steps = if zero && plain(w.as_flattened()) && plain(v.as_flattened()) {
            1
        } else {
            N
        };
        // y[j] −= L[path[t], path[j]]·y[t] for t from the leaf in, both sides
        for t in (1..steps).rev() {
            let (a, b) = (w[t], v[t]);
            let s = self.start[path[t]];
            let Some(anc) = self.anc.get(s..s + t) else {
                return false;
            };
            for ((wj, vj), &l) in w.iter_mut().zip(v.iter_mut()).zip(anc) {
                for i in 0..4 {
                    wj[i] -= l * a[i];
                    vj[i] -= l * b[i];
                }
            }
        }
        // y[t] ← y[t]/√D[path[t]]
        for ((wt, vt), &k) in w.iter_mut().zip(v.iter_mut()).zip(path) {
            let d = self.inv_sqrt_d[k];
            for i in 0..4 {
                wt[i] *= d;
                vt[i] *= d;
            }
        }
        true
    }

    /// The elimination and scaling of [`Self::row_transform_lanes`] on a chain
    /// path of `N` dofs (`path[..N]`), in registers: every loop's bounds
    /// constant (unrolled, no bounds tests); each lane's entry takes the same
    /// operations in the same order, y[j] −= L[path[t], path[j]]·y[t] for t
    /// from the leaf in, then the scaling. False (w partly done) where L's
    /// entries are not all there.
    #[inline(always)]
    fn chain_elim<const N: usize>(&self, path: &[usize], w: &mut [[f64; 4]; N]) -> bool {
        self.chain_elim_n::<N, 4>(path, w)
    }

    /// [`Self::chain_lanes2`] of two contacts' rows held six lanes a path
    /// slot, `w[t] = [y₀ₜ, y₁ₜ, y₂ₜ, y₃ₜ, y₄ₜ, y₅ₜ]` (no pad lane: three
    /// pairs of lanes where SSE has two lanes a register, so that both
    /// blocks stay nearer the registers): each lane the same operations in
    /// the same order (the same bits). False where the factor is dense or
    /// `path` is not the chain.
    #[inline(always)]
    pub fn chain_lanes6<const N: usize>(&self, path: &[usize], w: &mut [[f64; 6]; N]) -> bool {
        self.is_chain_of::<N>(path) && self.chain_elim_n::<N, 6>(path, w)
    }

    /// [`Self::two_chain_lanes2`] in [`Self::chain_lanes6`]'s six lanes a
    /// path slot: each chain on its own, each lane the same operations in
    /// the same order (the same bits). False where the factor is dense or
    /// `path` is not two chains of `A` and `B` dofs.
    #[inline(always)]
    pub fn two_chain_lanes6<const A: usize, const B: usize>(
        &self,
        path: &[usize],
        w: &mut [[f64; 6]],
    ) -> bool {
        if !(self.two_chains::<A, B>(path) && w.len() == A + B) {
            return false;
        }
        let (pa, pb) = path.split_at(A);
        let (wa, wb) = w.split_at_mut(A);
        match (
            <&mut [[f64; 6]; A]>::try_from(wa),
            <&mut [[f64; 6]; B]>::try_from(wb),
        ) {
            (Ok(wa), Ok(wb)) => {
                self.chain_elim_n::<B, 6>(pb, wb) && self.chain_elim_n::<A, 6>(pa, wa)
            }
            _ => false,
        }
    }

    /// [`Self::chain_elim`] on `L` lanes a path slot.
    #[inline(always)]
    fn chain_elim_n<const N: usize, const L: usize>(
        &self,
        path: &[usize],
        w: &mut [[f64; L]; N],
    ) -> bool {
        let Some(path) = path.get(..N).filter(|_| N <= 16) else {
            return false;
        };
        // (L zero on the chain and the rows plain: no step changes a bit, zeros.rs)
        let zero = path.last().is_some_and(|&d| self.zero_chain(d));
        let steps = !(zero && plain(w.as_flattened()));
        // the step at each t from the leaf in, t a constant (the loop written
        // out: each step's loop over y[..t] unrolled, no loop over t)
        macro_rules! steps {
            ($($t:literal)*) => {$(
                if steps && $t < N {
                    let (Some(&a), Some(&d)) = (w.get($t), path.get($t)) else {
                        return false;
                    };
                    let s = self.start[d];
                    let Some(anc) = self.anc.get(s..s + $t) else {
                        return false;
                    };
                    for (wj, &l) in w.iter_mut().zip(anc) {
                        for (x, &ai) in wj.iter_mut().zip(&a) {
                            *x -= l * ai;
                        }
                    }
                }
            )*};
        }
        steps!(15 14 13 12 11 10 9 8 7 6 5 4 3 2 1);
        for (wt, &k) in w.iter_mut().zip(path) {
            let d = self.inv_sqrt_d[k];
            for x in wt.iter_mut() {
                *x *= d;
            }
        }
        true
    }

    /// [`Self::row_transform3`] on rows held interleaved, `y[t] = [y₀ₜ, y₁ₜ,
    /// y₂ₜ, pad]` (a contact's three rows, lane by lane): each lane takes
    /// exactly the operations of [`Self::row_transform3`] in the same order (so
    /// the same bits), four lanes at once. Tree factors only: returns false
    /// (nothing done) on a dense one.
    #[inline]
    pub fn row_transform_lanes(&self, path: &[usize], y: &mut [[f64; 4]]) -> bool {
        if !self.tree {
            return false;
        }
        let len = path.len().min(y.len());
        let (path, y) = (&path[..len], &mut y[..len]);
        // the path's shape, found once: a chain root … leaf (p = len), or two
        // branches of one tree, path[..p] a chain and the last dof's ancestors
        // path[..k] and path[p..] (a contact between two links of one robot)
        let runs = if self.is_chain(path) {
            Some((0, len))
        } else {
            self.two_branches(path)
        };
        let Some((k, p)) = runs else {
            self.lanes_general(path, y);
            return true;
        };
        // the second branch from its leaf in: path[t]'s ancestors are path[..k]
        // and path[p..t], L's entries at anc[start[path[t]]..], in that order
        // (each y[j] gets the general way's updates in the same order: t
        // descending, one a step)
        for t in (p..len).rev() {
            let a = y[t];
            let s = self.start[path[t]];
            let (la, lb) = self.anc[s..s + k + t - p].split_at(k);
            let (ya, yb) = y[..t].split_at_mut(p);
            sub_lanes(&mut ya[..k], la, a);
            sub_lanes(yb, lb, a);
        }
        // the chain path[..p]: the ancestors of path[t] are path[..t]; `next`
        // carries y[t − 1] as the step at t leaves it (held in a register, not
        // read back from the store just made: the leaf-to-root chain is the
        // form's latency)
        if p > 0 {
            let mut next = y[p - 1];
            for t in (1..p).rev() {
                let a = next;
                let s = self.start[path[t]];
                let anc = &self.anc[s..s + t];
                let (ys, last) = y[..t].split_at_mut(t - 1);
                sub_lanes(ys, anc, a);
                let mut v = last[0];
                sub_lanes(std::slice::from_mut(&mut v), &anc[t - 1..], a);
                last[0] = v;
                next = v;
            }
        }
        for (yt, &k) in y.iter_mut().zip(path) {
            let d = self.inv_sqrt_d[k];
            for x in yt.iter_mut() {
                *x *= d;
            }
        }
        true
    }

    /// Tree: `(k, p)` where `path` is two branches of one tree, `path[..p]`
    /// a chain root … `path[p − 1]` and the last dof's ancestors `path[..k]`
    /// (the branches' common ones) then `path[p..]` (its own branch, p > k);
    /// `None` for any other path.
    #[inline]
    fn two_branches(&self, path: &[usize]) -> Option<(usize, usize)> {
        let (k, p, _) = self.ancestor_runs(path, path.len().checked_sub(1)?)?;
        (k < p && self.is_chain(&path[..p])).then_some((k, p))
    }

    /// [`Self::row_transform_lanes`]'s elimination (before the scaling) on a
    /// path that is neither a chain nor two branches: each dof's ancestors
    /// found on the path at each step.
    fn lanes_general(&self, path: &[usize], y: &mut [[f64; 4]]) {
        for t in (0..path.len().min(y.len())).rev() {
            let a = y[t];
            match self.ancestors(path, t) {
                Some((s0, anc)) => sub_lanes(&mut y[s0..t], anc, a),
                None => match self.ancestor_runs(path, t) {
                    // two runs: the branches' common ancestors path[..k]
                    // and path[t]'s own branch path[p..t]
                    Some((k, p, anc)) => {
                        let (ya, yb) = y[..t].split_at_mut(p);
                        let (la, lb) = anc.split_at(k);
                        sub_lanes(&mut ya[..k], la, a);
                        sub_lanes(yb, lb, a);
                    }
                    None => self.for_ancestors(path, t, |s, l| {
                        sub_lanes(std::slice::from_mut(&mut y[s]), &[l], a)
                    }),
                },
            }
        }
    }
}

/// y[j] −= l[j]·a, lane by lane, for each j: each lane one product and one
/// difference, each rounded (the scalar operations' bits), the four lanes
/// as one vector (written out: left to itself the compiler vectorises over
/// j, two entries at a time, with shuffles that cost more than they save).
#[inline(always)]
fn sub_lanes(ys: &mut [[f64; 4]], ls: &[f64], a: [f64; 4]) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{
            _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
        };
        // SAFETY: AVX is enabled for this build (the cfg); each load and
        // store is of one [f64; 4]
        unsafe {
            let av = _mm256_loadu_pd(a.as_ptr());
            for (yj, &l) in ys.iter_mut().zip(ls) {
                let y = _mm256_loadu_pd(yj.as_ptr());
                let p = _mm256_mul_pd(_mm256_set1_pd(l), av);
                _mm256_storeu_pd(yj.as_mut_ptr(), _mm256_sub_pd(y, p));
            }
        }
    }
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx")))]
    {
        use std::arch::x86_64::{_mm_loadu_pd, _mm_mul_pd, _mm_set1_pd, _mm_storeu_pd, _mm_sub_pd};
        // SAFETY: SSE2 is every x86_64's; each load and store is of two f64
        // of one [f64; 4]
        unsafe {
            let (a0, a1) = (_mm_loadu_pd(a.as_ptr()), _mm_loadu_pd(a[2..].as_ptr()));
            for (yj, &l) in ys.iter_mut().zip(ls) {
                let lv = _mm_set1_pd(l);
                let (lo, hi) = yj.split_at_mut(2);
                let y0 = _mm_sub_pd(_mm_loadu_pd(lo.as_ptr()), _mm_mul_pd(lv, a0));
                let y1 = _mm_sub_pd(_mm_loadu_pd(hi.as_ptr()), _mm_mul_pd(lv, a1));
                _mm_storeu_pd(lo.as_mut_ptr(), y0);
                _mm_storeu_pd(hi.as_mut_ptr(), y1);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    for (yj, &l) in ys.iter_mut().zip(ls) {
        for (x, &ai) in yj.iter_mut().zip(&a) {
            *x -= l * ai;
        }
    }
}
