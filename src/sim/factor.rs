//! The factor of the step's mass matrix H̃ = H + A + h·D, written H̃ = RᵀR, and
//! the four things the step does with it (docs/theory.md §"Constraint solve"):
//! solve H̃ x = b, turn a constraint row j into y = R⁻ᵀ j (so that the Delassus
//! matrix is W = J H̃⁻¹ Jᵀ = Y Yᵀ), map back Δv = R⁻¹ Δv', and apply R (the
//! kinetic energy is ½‖R v‖²).
//!
//! On a tree (no mimic joint) H̃ is factored as Lᵀ D L by the tree-sparse LTDL
//! ([`crate::dynamics::ltdl`], no fill), so R = D^½ L. A row whose Jacobian
//! lives on the path of a body to the root (every contact and joint row) then
//! gives y on that same path: R⁻ᵀ = D^-½ L⁻ᵀ only moves entries toward the root.
//! Along a path the tree is a chain, so y is formed in O(depth²) and each solver
//! sweep reads O(depth) entries a row instead of O(nv²) and O(nv) (MuJoCo's
//! tree-sparse `mj_factorI` / `mj_solveM` idea). With mimic joints H̃ is not
//! tree-shaped: a dense Cholesky H̃ = L Lᵀ (R = Lᵀ) and full-length rows.

mod awake;
mod chain6;
mod elim;
mod rows;
mod unroll;
mod zeros;

use super::factor_dense::{dense_backward, dense_forward};
use crate::dynamics::linalg::{by_size, cholesky_fast};
use crate::dynamics::{crba_packed, same_bits};
use crate::model::{Data, JointKind, Model};
use crate::spatial::ops::madd;
use crate::spatial::CompositeInertia;
use nalgebra::{DMatrix, DVector};
use unroll::{fold_n, scatter_row};

const NONE: usize = usize::MAX;

/// `x[j]` for a dof `j` read from [`MassFactor::table`], without a bounds
/// test: every entry of the table is a dof below `n` ([`MassFactor::new`]
/// builds it so: each entry but `0..n`'s indexes `dof_parent`, of length
/// `n`, when pushed), and the solves cut `x` to `n` first.
#[inline(always)]
fn at(x: &[f64], j: usize) -> f64 {
    debug_assert!(j < x.len());
    // SAFETY: j < n ≤ x.len() (the table's invariant above)
    unsafe { *x.get_unchecked(j) }
}

/// [`at`], mutable.
#[inline(always)]
fn at_mut(x: &mut [f64], j: usize) -> &mut f64 {
    debug_assert!(j < x.len());
    // SAFETY: as [`at`]'s
    unsafe { x.get_unchecked_mut(j) }
}

/// H̃ factored, with the dof paths rows live on.
#[derive(Clone, Debug)]
pub struct MassFactor {
    tree: bool,
    n: usize,
    /// Dense: L (lower, column-major). Tree: empty (the factor is `anc`).
    m: DMatrix<f64>,
    /// Tree: D^½. Dense: unused.
    sqrt_d: Vec<f64>,
    /// Tree: D^-½. Dense: 1 / Lₖₖ (the substitutions multiply, never divide:
    /// a division costs a dozen multiplies, and a step does hundreds).
    inv_sqrt_d: Vec<f64>,
    /// Tree: the whole LTDL factor packed along [`Self::table`]
    /// (`anc[start[k] + s]` = L[k, path_k[s]] for the dof's path root … k,
    /// the last entry D[k]); before the elimination, H̃'s entries there. No
    /// nv × nv matrix: a large scene's nv is in the thousands (docs/theory.md
    /// §"Tree-sparse LTDL", "Packed storage").
    anc: Vec<f64>,
    /// Tree: H̃'s diagonal before the elimination (the pivot test's scale).
    hdiag: Vec<f64>,
    /// Tree: the dof ranges `[k0, k1)` factored and solved (whole trees),
    /// and their bodies: every tree's, or the awake ones' when some sleep
    /// ([`Self::set_awake`]). A sleeping tree's entries keep their last
    /// values and its dofs are left alone: no row reaches them, and the step
    /// holds them.
    dof_ranges: Vec<(usize, usize)>,
    body_ranges: Vec<(usize, usize)>,
    partial: bool,
    /// The mask the ranges were listed for and the `partial` it gave
    /// ([`Self::set_awake`]: the lists are made again only when it changes).
    ranges_mask: Vec<bool>,
    ranges_partial: bool,
    /// Per tree of the model (in order), its dof and body ranges, for the
    /// lists (`None`: a tree on the world body, never listed); `spans_cover`:
    /// the trees cover the model's dofs and bodies exactly.
    spans: Vec<awake::TreeSpan>,
    spans_cover: bool,
    /// Tree, lone free bodies: every tree's dof range (the solves' ranges
    /// when none sleeps, `chain6`); else empty.
    lone_ranges: Vec<(usize, usize)>,
    all: (usize, usize),
    /// Every dof's path (root … dof, ascending) back to back, then `0..n`.
    table: Vec<usize>,
    start: Vec<usize>,
    len: Vec<usize>,
    x: DVector<f64>,
    /// Tree: D (the pivots), contiguous (the solve divides in vector lanes).
    dval: Vec<f64>,
    /// Tree: scratch of the elimination, a dof's multipliers L[k, ·] (and
    /// its parent's and grandparent's beside them: 3 nv).
    mult: Vec<f64>,
    /// Tree: per dof, whether its path is a root's chain of consecutive dofs
    /// (root, root + 1, …, the dof: a floating base's six), whose packed rows
    /// then lie back to back as one triangle.
    root_chain: Vec<bool>,
    /// Tree, lone free bodies: per dof, L's row and its ancestors' rows are
    /// all zeros (either sign): the chain eliminations skip their steps on
    /// plain rows (zeros.rs). False on every other model.
    zero_l: Vec<bool>,
    /// Tree: every body a lone free body on the world (each tree one body).
    /// H is then each body's spatial inertia in its body frame (the free
    /// joint's S = 1, docs/theory.md §"Floating base"), the same numbers at
    /// every q: H̃ and its factor change only with the diagonal A + h D and
    /// the inertias.
    lone_free: bool,
    /// The factor in place is [`Self::factor_at`]'s of every tree of such a
    /// model with `held_diag` added to H's diagonal and the bodies' inertias
    /// `held_inertia` (false: not known to be).
    held: bool,
    held_diag: Vec<f64>,
    held_inertia: Vec<CompositeInertia<f64>>,
    /// The caller's scratch for H̃'s diagonal additions (n entries), filled
    /// in one pass over slices before [`Self::factor_at`] reads it
    /// (`Simulation::factor_mass`).
    pub(crate) diag_buf: Vec<f64>,
}

impl MassFactor {
    /// The factor's storage and dof paths for `model` (nv × nv), chosen once:
    /// tree-sparse LTDL on a tree, dense Cholesky with mimic joints or on a
    /// chain of at most 18 dofs (its H has no zeros for LTDL to skip).
    pub fn new(model: &Model) -> Self {
        let n = model.nv;
        let chain = model
            .dof_parent
            .iter()
            .enumerate()
            .all(|(k, &p)| p == k.wrapping_sub(1));
        let tree = !model.has_mimic && model.dof_parent.len() == n && !(chain && n <= 18);
        let mut table = Vec::new();
        let (mut start, mut len) = (Vec::with_capacity(n + 1), Vec::with_capacity(n + 1));
        for k in 0..n {
            let s = table.len();
            if tree {
                let mut i = k;
                while i != NONE {
                    table.push(i);
                    i = model.dof_parent[i];
                }
                table[s..].reverse();
            }
            start.push(s);
            len.push(table.len() - s);
        }
        start.push(table.len());
        len.push(n);
        table.extend(0..n);
        let mut root_chain = vec![false; n];
        for k in 0..n {
            let p = model.dof_parent.get(k).copied();
            root_chain[k] =
                tree && (p == Some(NONE) || (k > 0 && p == Some(k - 1) && root_chain[k - 1]));
        }
        let nb = model.nbodies;
        let lone_free = tree
            && nb > 1
            && model.parent.len() == nb
            && model.joints.len() == nb
            && (1..nb).all(|i| model.parent[i] == 0 && model.joints[i].kind == JointKind::Free);
        let (spans, spans_cover) = awake::tree_spans(model, n);
        let mut f = Self {
            tree,
            n,
            lone_free,
            held: false,
            held_diag: vec![0.0; if lone_free { n } else { 0 }],
            held_inertia: Vec::with_capacity(if lone_free { nb } else { 0 }),
            diag_buf: vec![0.0; n],
            m: if tree {
                DMatrix::zeros(0, 0)
            } else {
                DMatrix::zeros(n, n)
            },
            sqrt_d: vec![1.0; n],
            inv_sqrt_d: vec![1.0; n],
            anc: if tree {
                vec![0.0; table.len()]
            } else {
                Vec::new()
            },
            hdiag: vec![0.0; if tree { n } else { 0 }],
            dof_ranges: Vec::with_capacity(model.trees.len()),
            body_ranges: Vec::with_capacity(model.trees.len()),
            partial: false,
            ranges_mask: Vec::new(),
            ranges_partial: false,
            spans,
            spans_cover,
            lone_ranges: chain6::lone_ranges(model, n, lone_free),
            all: (0, n),
            table,
            start,
            len,
            x: DVector::zeros(n),
            dval: vec![1.0; if tree { n } else { 0 }],
            mult: vec![0.0; if tree { 3 * n } else { 0 }],
            root_chain,
            zero_l: vec![false; n],
        };
        f.check_lone_ranges();
        f
    }

    /// The path of a row acting on dofs up to `dof` (its body's last dof, or a
    /// joint row's own): (start, length) in [`Self::table`]. A dense factor's
    /// rows are all full length.
    pub fn path_of(&self, dof: usize) -> (usize, usize) {
        let k = if self.tree { dof.min(self.n) } else { self.n };
        (self.start[k], self.len[k])
    }

    /// Whether H̃ is factored tree-sparse (reading its upper triangle only) or
    /// dense (reading its lower triangle).
    pub fn is_tree(&self) -> bool {
        self.tree
    }

    /// Every dof's path to the root (root first) back to back, then `0..nv`
    /// (the full-length path); [`MassFactor::path_of`] gives a row's slice.
    pub fn table(&self) -> &[usize] {
        &self.table
    }

    /// Factors `h` (H̃, full symmetric storage; on a tree only the pattern of
    /// its upper triangle is read). Fails with the index of a pivot that is
    /// not positive.
    pub fn factor(&mut self, h: &DMatrix<f64>) -> Result<(), usize> {
        self.partial = false;
        self.held = false;
        if self.tree {
            for k in 0..self.n {
                let (s, l) = (self.start[k], self.len[k]);
                for (a, &i) in self.anc[s..s + l].iter_mut().zip(&self.table[s..s + l]) {
                    *a = h[(i, k)];
                }
            }
            self.factor_packed()
        } else {
            cholesky_fast(h, &mut self.m)?;
            for k in 0..self.n {
                self.inv_sqrt_d[k] = 1.0 / self.m[(k, k)];
            }
            Ok(())
        }
    }

    /// Factors H̃ = H(q) + diag(`diag`) formed straight into the packed tree
    /// storage (the local-frame CRBA, [`crba_packed`]: no nv × nv matrix is
    /// touched; `data.h` is left as it was). `placed`: `data.li_m_i` holds the
    /// joint placements at `q`. `None` where that does not apply (a dense
    /// factor, mimic joints, a long chain): the caller forms H in `data.h`
    /// and calls [`Self::factor`].
    pub fn factor_at(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        placed: bool,
        diag: impl Fn(usize) -> f64,
    ) -> Option<Result<(), usize>> {
        // lone free bodies: H̃ at this q is H̃ at the last one; with the same
        // diagonal and inertias the factor in place is the one this would
        // compute, bit for bit (`placed`: nor are the placements to be stored)
        if placed && self.held && self.holds(model, &diag) {
            return Some(Ok(()));
        }
        self.held = false;
        let bodies = self.partial.then_some(&self.body_ranges[..]);
        let (anc, start, len) = (&mut self.anc, &self.start, &self.len);
        if !self.tree || !crba_packed(model, data, q, placed, anc, start, len, bodies) {
            self.partial = false;
            return None;
        }
        for r in 0..self.ranges().len() {
            let (k0, k1) = self.ranges()[r];
            for k in k0..k1 {
                if let Some(x) = self.anc.get_mut(self.start[k] + self.len[k] - 1) {
                    *x += diag(k);
                }
            }
        }
        let r = self.factor_packed();
        // every tree factored (none asleep): the factor may be held
        let covered: usize = self.ranges().iter().map(|&(k0, k1)| k1 - k0).sum();
        if r.is_ok() && self.lone_free && covered == self.n {
            self.hold(model, &diag);
        }
        Some(r)
    }

    /// Whether H̃'s diagonal additions and the bodies' inertias are, bit for
    /// bit, those of the held factor: each entry's bits xor-ed with the held
    /// one's, or-ed (zero iff every entry is the same), with no early exit
    /// (vector lanes, no iterator call an entry; the same verdict).
    fn holds(&self, model: &Model, diag: &impl Fn(usize) -> f64) -> bool {
        let inertias = &model.inertias_origin;
        if self.held_diag.len() != self.n || inertias.len() != self.held_inertia.len() {
            return false;
        }
        let d = (self.held_diag.iter().enumerate())
            .fold(0u64, |acc, (k, h)| acc | (diag(k).to_bits() ^ h.to_bits()));
        let i =
            (inertias.iter().zip(&self.held_inertia)).fold(true, |s, (a, b)| s & same_bits(a, b));
        d == 0 && i
    }

    /// Records the diagonal additions and inertias of the factor just made.
    fn hold(&mut self, model: &Model, diag: &impl Fn(usize) -> f64) {
        for (k, x) in self.held_diag.iter_mut().enumerate() {
            *x = diag(k);
        }
        self.held_inertia.clear();
        self.held_inertia.extend_from_slice(&model.inertias_origin);
        self.held = self.held_diag.len() == self.n;
    }

    /// The dof ranges worked on: every dof, or the awake trees'.
    #[inline]
    fn ranges(&self) -> &[(usize, usize)] {
        if self.partial {
            &self.dof_ranges
        } else {
            std::slice::from_ref(&self.all)
        }
    }

    /// The tree-sparse LTDL elimination (docs/theory.md §"Tree-sparse LTDL")
    /// in place on `anc` (holding H̃'s pattern): the arithmetic of
    /// [`crate::dynamics::ltdl::ltdl`], entry for entry, on each dof's packed
    /// path (the path of an ancestor i of k is the start of k's path, so
    /// H̃[j, i] for j ancestor-or-self of i sits at `start[i] + depth(j)`).
    fn factor_packed(&mut self) -> Result<(), usize> {
        let tiny = 64.0 * f64::EPSILON;
        for r in 0..self.ranges().len() {
            let (k0, k1) = self.ranges()[r];
            let r = self.factor_range(k0, k1, tiny);
            self.mark_zeros(k0, k1, r.is_ok());
            r?;
        }
        Ok(())
    }

    /// Tree: where the ancestors of `path[t]` lie on `path` when they are
    /// exactly `path[s0..t]` (a row on one body's path, or on two bodies'
    /// paths in two trees: each a run of the path), with L's entries at them
    /// ([`Self::anc`]); `None` otherwise (two branches of one tree
    /// interleaved). L is zero between a dof and a non-ancestor, so the
    /// entries skipped (the other tree's) are zeros.
    #[inline(always)]
    fn ancestors(&self, path: &[usize], t: usize) -> Option<(usize, &[f64])> {
        let d = *path.get(t)?;
        let (s, l) = (*self.start.get(d)?, *self.len.get(d)?);
        // the union is ascending and holds every ancestor of d (its root
        // the least): the l entries ending at t are them iff they start at d's root
        let s0 = (t + 1).checked_sub(l)?;
        (path.get(s0)? == self.table.get(s)?).then(|| (s0, &self.anc[s..s + l - 1]))
    }

    /// Tree: whether `path` is exactly the chain root … its last dof (a row on
    /// one body's path, every contact's and joint row's in a robot): then the
    /// ancestors of `path[t]` are `path[..t]` and their entries of L lie at
    /// `anc[start[path[t]]..][..t]` (what [`Self::ancestors`] finds, without
    /// its look-ups at every t). A path holds every ancestor of its last dof,
    /// so one of the chain's length is the chain.
    #[inline(always)]
    fn is_chain(&self, path: &[usize]) -> bool {
        match path.last() {
            Some(&d) => {
                self.len.get(d) == Some(&path.len())
                    && self.start.get(d).and_then(|&s| self.table.get(s)) == path.first()
            }
            None => false,
        }
    }

    /// Tree: `f(…f(f(init, a, j)…)` over row i's multipliers a = L[i, j]
    /// beside their dofs j, from the nearest ancestor to the root (one at a time: the same operations in the
    /// same order); a row of up to 11 unrolled (constant bounds).
    #[inline(always)]
    fn fold_row<T>(&self, i: usize, init: T, f: impl Fn(T, f64, usize) -> T) -> T {
        let (s, l) = (self.start[i], self.len[i]);
        let (a, j) = (&self.anc[s..s + l - 1], &self.table[s..s + l - 1]);
        match a.len() {
            0 => init,
            1 => fold_n::<1, T>(a, j, init, f),
            2 => fold_n::<2, T>(a, j, init, f),
            3 => fold_n::<3, T>(a, j, init, f),
            4 => fold_n::<4, T>(a, j, init, f),
            5 => fold_n::<5, T>(a, j, init, f),
            6 => fold_n::<6, T>(a, j, init, f),
            7 => fold_n::<7, T>(a, j, init, f),
            8 => fold_n::<8, T>(a, j, init, f),
            9 => fold_n::<9, T>(a, j, init, f),
            10 => fold_n::<10, T>(a, j, init, f),
            11 => fold_n::<11, T>(a, j, init, f),
            _ => a
                .iter()
                .zip(j)
                .rev()
                .fold(init, |acc, (&a, &j)| f(acc, a, j)),
        }
    }

    /// x ← H̃⁻¹ x.
    pub fn solve(&self, x: &mut DVector<f64>) {
        if self.tree {
            // Lᵀ y = b (leaves inwards), z = D⁻¹ y, L x = z (root outwards):
            // [`crate::dynamics::ltdl::ltdl_solve`] on the packed factor
            let x = &mut x.as_mut_slice()[..self.n];
            if self.lone_solve(x) {
                return;
            }
            for &(k0, k1) in self.ranges() {
                let mut i = k1;
                while i > k0 {
                    i -= 1;
                    let xi = x[i];
                    let (s, l) = (self.start[i], self.len[i]);
                    // i − 1 is i's parent (a chain): i's term reaches x[i − 1]
                    // first, then each common ancestor's entry takes i's term and
                    // i − 1's in turn, in registers (the same two fused
                    // multiply-adds in the same order: the same bits)
                    if l >= 2 && i > k0 && self.table[s + l - 2] == i - 1 {
                        let xp = madd(-self.anc[s + l - 2], xi, x[i - 1]);
                        x[i - 1] = xp;
                        let sp = self.start[i - 1];
                        let (a, ap, js) = (
                            &self.anc[s..s + l - 2],
                            &self.anc[sp..sp + l - 2],
                            &self.table[s..s + l - 2],
                        );
                        scatter_row(a, js, |t, xj| {
                            *at_mut(x, xj) = madd(-ap[t], xp, madd(-a[t], xi, at(x, xj)))
                        });
                        i -= 1;
                        continue;
                    }
                    let (a, js) = (&self.anc[s..s + l - 1], &self.table[s..s + l - 1]);
                    scatter_row(a, js, |t, xj| *at_mut(x, xj) = madd(-a[t], xi, at(x, xj)));
                }
                if let (Some(x), Some(d)) = (x.get_mut(k0..k1), self.dval.get(k0..k1)) {
                    for (x, &d) in x.iter_mut().zip(d) {
                        *x /= d;
                    }
                }
                for i in k0..k1 {
                    x[i] = self.fold_row(i, x[i], |acc, a, j| madd(-a, at(x, j), acc));
                }
            }
        } else {
            let (l, inv, x) = (self.m.as_slice(), &self.inv_sqrt_d[..], x.as_mut_slice());
            by_size!(self.n, N => {
                dense_forward::<N, 1>(l, inv, self.n, [x]);
                dense_backward::<N>(l, inv, self.n, x)
            })
        }
    }

    /// z ← R⁻¹ z (full length).
    pub fn half_solve(&self, z: &mut [f64]) {
        let n = self.n;
        if !self.tree {
            by_size!(n, N => dense_backward::<N>(self.m.as_slice(), &self.inv_sqrt_d, n, z));
            return;
        }
        // L x = D^-½ z, root outwards
        if z.len() < n {
            return;
        }
        let z = &mut z[..n];
        if self.lone_half_solve(z) {
            return;
        }
        for &(k0, k1) in self.ranges() {
            for i in k0..k1 {
                let z0 = z[i] * self.inv_sqrt_d[i];
                z[i] = self.fold_row(i, z0, |acc, a, j| acc - a * at(z, j));
            }
        }
    }

    /// z ← R⁻¹ z and w ← R⁻¹ w (full length) in one pass over the factor: each
    /// vector's entries the operations of [`Self::half_solve`] in its order
    /// (the same bits).
    pub fn half_solve2(&self, z: &mut [f64], w: &mut [f64]) {
        let n = self.n;
        if !self.tree || z.len() < n || w.len() < n {
            self.half_solve(z);
            self.half_solve(w);
            return;
        }
        // L x = D^-½ z, root outwards, both at once
        let (z, w) = (&mut z[..n], &mut w[..n]);
        if self.lone_half_solve(z) && self.lone_half_solve(w) {
            return;
        }
        for &(k0, k1) in self.ranges() {
            for i in k0..k1 {
                let s = self.inv_sqrt_d[i];
                let init = (z[i] * s, w[i] * s);
                let (zi, wi) = self.fold_row(i, init, |(az, aw), a, j| {
                    (az - a * at(z, j), aw - a * at(w, j))
                });
                z[i] = zi;
                w[i] = wi;
            }
        }
    }

    /// out ← R v.
    pub fn apply_r(&self, v: &[f64], out: &mut [f64]) {
        let n = self.n;
        if !self.tree {
            // Lᵀ v: a_k = Σ_{i≥k} L[i,k] v_i (column k of L)
            let l = self.m.as_slice();
            for k in 0..n {
                let mut a = 0.0;
                for i in k..n {
                    a += l[k * n + i] * v[i];
                }
                out[k] = a;
            }
            return;
        }
        if v.len() < n || out.len() < n {
            return;
        }
        let v = &v[..n];
        if self.lone_apply_r(v, out) {
            return;
        }
        for &(k0, k1) in self.ranges() {
            for i in k0..k1 {
                let acc = self.fold_row(i, v[i], |acc, a, j| acc + a * at(v, j));
                out[i] = self.sqrt_d[i] * acc;
            }
        }
    }

    /// (H̃⁻¹)ₖₖ = ‖R⁻ᵀ eₖ‖².
    pub fn inverse_diagonal(&mut self, k: usize) -> f64 {
        let (s, l) = self.path_of(k);
        let mut x = std::mem::replace(&mut self.x, DVector::zeros(0));
        x.fill(0.0);
        let path = &self.table[s..s + l];
        // e_k is the last entry of its own path (dense: index k)
        let at = if self.tree { l - 1 } else { k };
        x[at] = 1.0;
        self.row_transform(path, &mut x.as_mut_slice()[..l]);
        let r = x.rows(0, l).norm_squared();
        self.x = x;
        r
    }
}
