//! Velocity-level constraint solve of one step: ground contact (normal +
//! Coulomb cone), joint Coulomb friction (stiction) and joint position limits, by
//! projected Gauss–Seidel on the Delassus matrix W = J H⁻¹ Jᵀ.
//!
//! With the free velocity v* = v + Δt H⁻¹(τ − C(q, v)) the impulses λ make the
//! end-of-step velocity v⁺ = v* + H⁻¹ Jᵀ λ satisfy, row by row (u = J v⁺):
//! - contact normal: 0 ≤ λₙ ⊥ uₙ − bₙ ≥ 0;
//! - contact tangents (pair): ‖λₜ‖ ≤ μ λₙ, uₜ = 0 inside the cone (stick), λₜ
//!   anti-parallel to uₜ on its boundary (slip);
//! - joint friction: |λ| ≤ F Δt, u = 0 inside (a joint loaded below its
//!   friction F stays at rest);
//! - joint limit (one-sided): 0 ≤ λ ⊥ u − b ≥ 0, with b = −φ/Δt for a gap φ > 0
//!   (the joint may reach its limit, not pass it) and b = 0 when past it.
//!
//! The velocity solve never pushes a violated constraint back (b ≤ 0 for every
//! unilateral row): that would turn a position error into kinetic energy.
//! Violations are removed by a separate *position pass* ([`Rows::solve_position`],
//! split impulse / post-stabilisation): a pseudo-velocity w = H̃⁻¹Jᵀμ with
//! 0 ≤ μ ⊥ J w − b_pos ≥ 0 on the unilateral rows, b_pos = min(βφ⁻/Δt, cap),
//! moves q but never enters v.

use super::factor::MassFactor;
use crate::dynamics::linalg::{ldlt_dropping, ldlt_dropping_solve};

/// What a row is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowKind {
    /// Contact normal (λ ≥ 0).
    Normal,
    /// First of a contact's two tangent rows; the next row is its partner.
    /// `normal` is the row index of the contact's normal, `mu` the friction.
    Tangent {
        /// Row index of the contact's normal row.
        normal: usize,
        /// Coulomb friction coefficient μ of the contact's cone.
        mu: f64,
    },
    /// The second tangent row (handled with the first).
    Tangent2,
    /// Joint friction: |λ| ≤ limit.
    Box {
        /// Largest impulse magnitude, F·Δt (N·m·s or N·s).
        limit: f64,
    },
    /// Joint limit: λ ≥ 0.
    Unilateral,
}

/// Preallocated rows: Jacobians and Y = J R⁻ᵀ (each row compact over its dof
/// path, `stride` apart), diag W, targets. Every per-row vector holds `capacity()` entries, the first `n` in use.
#[derive(Clone, Debug)]
pub struct Rows {
    /// The model's nv (the length of velocity vectors).
    pub nv: usize,
    /// Room of a row in `j` and `y`: the longest path a row can have (two
    /// bodies' paths to the root; nv for a dense factor), so that storage
    /// grows with rows × path length, never rows × nv.
    pub stride: usize,
    /// Rows in use.
    pub n: usize,
    /// Each row's kind (the first `n` entries in use).
    pub kind: Vec<RowKind>,
    /// Jacobians J, `stride` apart, each row compact over its path (entry t of
    /// row r, `j[r·stride + t]`, belongs to dof `path[t]`; J is zero elsewhere).
    pub j: Vec<f64>,
    /// Rows of Y = J R⁻ᵀ (H̃ = RᵀR), `stride` apart, each held compactly over its
    /// path (entry t belongs to dof `path[t]`); filled by [`Rows::form`].
    pub y: Vec<f64>,
    /// Delassus diagonal Wᵣᵣ = ‖yᵣ‖² (the row's velocity per unit impulse).
    pub w: Vec<f64>,
    /// 1 / Wᵣᵣ, and 0 where Wᵣᵣ ≤ 1e-14 (a row no impulse can move: its
    /// impulse stays 0).
    winv: Vec<f64>,
    /// J v* (free velocity).
    pub c: Vec<f64>,
    /// Target (b) of each row.
    pub b: Vec<f64>,
    /// Impulse of each row (N·s for contact rows, N·m·s or N·s for joint rows);
    /// the warm start on entry to [`Rows::solve`], the solution after.
    pub lambda: Vec<f64>,
    /// Position-pass target of each unilateral row (0: not violated).
    pub bpos: Vec<f64>,
    /// Position-pass multipliers.
    pub mu: Vec<f64>,
    /// Each row's dof path (start, length) in the factor's table: its Jacobian
    /// and y live there only (compact y: entry t is dof `path[t]`).
    pub path: Vec<(usize, usize)>,
    /// At a contact's normal row: the off-diagonal entries of its 3×3 block of
    /// W (n·t₁, n·t₂, t₁·t₂), so that a sweep reads the contact's path once.
    pub w_block: Vec<[f64; 3]>,
    is_block: Vec<bool>,
    /// Each row's velocity at its update in the last sweep.
    u_prev: Vec<f64>,
    /// Scratch of the subspace step ([`subspace_step`]).
    sm: Subspace,
    /// The last solve took a subspace step.
    pub polished: bool,
    cap: usize,
    /// The dof paths rows live on: the factor's table ([`MassFactor::table`],
    /// every dof's path to the root, the first `static_len` entries), then the
    /// step's unions of two paths (a contact between two bodies acts on both
    /// bodies' paths: their union, ascending, is where its row and y live).
    table: Vec<usize>,
    static_len: usize,
    /// The last union made: its two paths and where it is.
    last_union: ((usize, usize), (usize, usize), (usize, usize)),
}

/// Most rows a subspace step solves directly (its dense W_FF is this square).
pub const SUBSPACE_MAX: usize = 16;

/// Preallocated scratch of [`subspace_step`]: the free rows, their dense
/// Delassus block and right-hand side, their Y rows scattered to full width.
#[derive(Clone, Debug)]
struct Subspace {
    rows: Vec<usize>,
    w: Vec<f64>,
    rhs: Vec<f64>,
    dense: Vec<f64>,
    lam: Vec<f64>,
    /// At a tangent pair's first row: it lay on its cone's boundary (sliding).
    sliding: Vec<bool>,
}

impl Subspace {
    fn new(nv: usize, cap: usize) -> Self {
        let m = cap.min(SUBSPACE_MAX);
        Self {
            rows: Vec::with_capacity(m),
            w: vec![0.0; m * m],
            rhs: vec![0.0; m],
            dense: vec![0.0; m * nv],
            lam: vec![0.0; m],
            sliding: vec![false; cap],
        }
    }
}

impl Rows {
    /// Room for `cap` rows of width `nv`, all allocated here (none in a step).
    pub fn new(nv: usize, cap: usize, stride: usize) -> Self {
        let stride = stride.clamp(1, nv.max(1));
        Self {
            nv,
            stride,
            n: 0,
            kind: vec![RowKind::Unilateral; cap],
            j: vec![0.0; cap * stride],
            y: vec![0.0; cap * stride],
            w: vec![0.0; cap],
            winv: vec![0.0; cap],
            c: vec![0.0; cap],
            b: vec![0.0; cap],
            lambda: vec![0.0; cap],
            bpos: vec![0.0; cap],
            mu: vec![0.0; cap],
            path: vec![(0, 0); cap],
            w_block: vec![[0.0; 3]; cap],
            is_block: vec![false; cap],
            u_prev: vec![0.0; cap],
            sm: Subspace::new(nv, cap),
            polished: false,
            cap,
            table: Vec::new(),
            static_len: 0,
            last_union: ((0, 0), (0, 0), (0, 0)),
        }
    }
    /// Takes the factor's path table (`base`, [`MassFactor::table`]) with room
    /// for `unions` two-body paths of at most nv entries each, allocated here.
    pub fn set_table(&mut self, base: &[usize], unions: usize) {
        self.table = Vec::with_capacity(base.len() + unions * self.stride);
        self.table.extend_from_slice(base);
        self.static_len = base.len();
    }
    /// The dof paths rows index ([`Rows::path`]).
    pub fn table(&self) -> &[usize] {
        &self.table
    }
    /// Takes the path table out (no entry moved), for a solver that mutates
    /// the rows while reading it; [`Rows::put_table`] puts it back.
    pub(crate) fn take_table(&mut self) -> Vec<usize> {
        std::mem::take(&mut self.table)
    }
    /// Puts back the table [`Rows::take_table`] took.
    pub(crate) fn put_table(&mut self, table: Vec<usize>) {
        self.table = table;
    }
    /// The path of a row acting on the dofs of two paths `a` and `b` (entries
    /// of the table): their union, ascending (appended to the table for this
    /// step; the last union is reused when asked again).
    pub fn union_path(&mut self, a: (usize, usize), b: (usize, usize)) -> (usize, usize) {
        if a == b || b.1 == 0 {
            return a;
        }
        if a.1 == 0 {
            return b;
        }
        let (la, lb, at) = self.last_union;
        if la == a && lb == b && at.0 + at.1 <= self.table.len() && at.0 >= self.static_len {
            return at;
        }
        let start = self.table.len();
        let (mut i, mut j) = (a.0, b.0);
        let (ea, eb) = (a.0 + a.1, b.0 + b.1);
        while i < ea || j < eb {
            let x = if i < ea { self.table[i] } else { usize::MAX };
            let y = if j < eb { self.table[j] } else { usize::MAX };
            let k = if x <= y {
                i += 1;
                if x == y {
                    j += 1;
                }
                x
            } else {
                j += 1;
                y
            };
            self.table.push(k);
        }
        let at = (start, self.table.len() - start);
        self.last_union = (a, b, at);
        at
    }
    /// The most rows that fit.
    pub fn capacity(&self) -> usize {
        self.cap
    }
    /// Empties the rows; their Jacobian entries are zeroed here, once, so that
    /// every row pushed after starts from zeros (a row holds its path's
    /// entries only: the cost follows the rows' path lengths, never rows × nv).
    pub fn clear(&mut self) {
        self.zero_rows(0, self.n);
        self.n = 0;
        self.table.truncate(self.static_len);
        self.last_union = ((0, 0), (0, 0), (0, 0));
    }
    /// Drops the last `k` rows (pushed, their Jacobian entries not yet written).
    pub fn pop(&mut self, k: usize) {
        let k = k.min(self.n);
        self.n -= k;
        self.zero_rows(self.n, self.n + k);
    }
    /// Zeroes the Jacobian entries of rows `from..to`.
    fn zero_rows(&mut self, from: usize, to: usize) {
        let st = self.stride;
        for r in from..to.min(self.cap) {
            let pl = self.path[r].1.min(st);
            self.j[r * st..r * st + pl].fill(0.0);
        }
    }
    /// Adds a row (zeroed Jacobian: rows are zeroed by [`Rows::clear`]) and returns
    /// its index, or `None` when full.
    #[inline]
    pub fn push(
        &mut self,
        kind: RowKind,
        b: f64,
        warm: f64,
        path: (usize, usize),
    ) -> Option<usize> {
        if self.n >= self.cap {
            return None;
        }
        let r = self.n;
        self.n += 1;
        self.kind[r] = kind;
        self.b[r] = b;
        self.lambda[r] = warm;
        self.bpos[r] = 0.0;
        self.path[r] = path;
        Some(r)
    }
    /// Where dof `d` lies on row `r`'s path (`None`: off it, J is 0 there).
    fn slot_of(&self, r: usize, d: usize) -> Option<usize> {
        let (ps, pl) = self.path[r];
        self.table.get(ps..ps + pl)?.iter().position(|&k| k == d)
    }
    /// Adds `x` to J's entry of row `r` at dof `d` (on the row's path; a dof
    /// off the path is ignored: the row cannot act there).
    pub fn add_entry(&mut self, r: usize, d: usize, x: f64) {
        if let Some(t) = self.slot_of(r, d) {
            self.j[r * self.stride + t] += x;
        }
    }
    /// J's entry of row `r` at dof `d` (0 off its path).
    pub fn entry(&self, r: usize, d: usize) -> f64 {
        self.slot_of(r, d)
            .map_or(0.0, |t| self.j[r * self.stride + t])
    }
    /// Row `r` of J written from a dense row `dense` (nv entries, J's
    /// entries on the row's path; zero elsewhere), whose path entries are
    /// zeroed after (the caller's scratch is left all zeros).
    pub fn gather(&mut self, r: usize, dense: &mut [f64]) {
        let (ps, pl) = self.path[r];
        let st = self.stride;
        let Some(path) = self.table.get(ps..ps + pl) else {
            return;
        };
        for (t, &d) in path.iter().enumerate().take(st) {
            if let Some(x) = dense.get_mut(d) {
                self.j[r * st + t] = *x;
                *x = 0.0;
            }
        }
    }
    /// J's row `r` times `x` (nv entries).
    pub fn jdot(&self, r: usize, x: &[f64]) -> f64 {
        let (ps, pl) = self.path[r];
        let Some(path) = self.table.get(ps..ps + pl) else {
            return 0.0;
        };
        let jr = &self.j[r * self.stride..r * self.stride + pl.min(self.stride)];
        jr.iter()
            .zip(path)
            .map(|(a, &k)| a * x.get(k).copied().unwrap_or(0.0))
            .sum()
    }
    /// Row `r` of J as (dof, entry) pairs over its path.
    pub fn jrow(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (ps, pl) = self.path[r];
        let path = self.table.get(ps..ps + pl).unwrap_or(&[]);
        let jr = &self.j[r * self.stride..r * self.stride + path.len().min(self.stride)];
        path.iter().copied().zip(jr.iter().copied())
    }
    /// Fills y with the rows of Y = J R⁻ᵀ (H̃ = RᵀR, [`MassFactor`]), each over
    /// its path, the Delassus diagonal Wᵣᵣ = jᵣ·H̃⁻¹jᵣ = ‖yᵣ‖² and c = J v* for
    /// the free velocity `vfree`.
    pub fn form(&mut self, f: &MassFactor, vfree: &[f64]) {
        let (nv, n, st) = (self.nv, self.n, self.stride);
        if vfree.len() < nv || self.j.len() < n * st || self.y.len() < n * st {
            return;
        }
        // (the table is put back below: taking it moves no entry)
        let table_v = std::mem::take(&mut self.table);
        let table = &table_v[..];
        let mut r = 0;
        while r < n {
            let (ps, pl) = self.path[r];
            let Some(path) = table.get(ps..ps + pl).filter(|p| p.len() <= st) else {
                if let Some(b) = self.is_block.get_mut(r) {
                    *b = false;
                }
                r += 1;
                continue;
            };
            // a contact's three rows share the path: gathered, then transformed
            // in one pass over the factor
            let block = self.is_contact(r);
            let k = if block { 3 } else { 1 };
            for q in r..(r + k).min(self.is_block.len()) {
                self.is_block[q] = block && q == r;
            }
            for q in r..r + k {
                let jr = &self.j[q * st..q * st + pl];
                let yr = &mut self.y[q * st..q * st + pl];
                let mut cq = 0.0;
                for ((yt, &d), &jk) in yr.iter_mut().zip(path).zip(jr) {
                    *yt = jk;
                    cq += jk * vfree[d];
                }
                self.c[q] = cq;
            }
            if k == 3 {
                let (a, rest) = self.y[r * st..].split_at_mut(st);
                let (b, c) = rest.split_at_mut(st);
                let (y0, y1, y2) = (&mut a[..pl], &mut b[..pl], &mut c[..pl]);
                f.row_transform3(path, y0, y1, y2);
                let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
                self.w[r] = dot(y0, y0);
                self.w[r + 1] = dot(y1, y1);
                self.w[r + 2] = dot(y2, y2);
                self.w_block[r] = [dot(y0, y1), dot(y0, y2), dot(y1, y2)];
            } else {
                let yr = &mut self.y[r * st..r * st + pl];
                f.row_transform(path, yr);
                self.w[r] = yr.iter().map(|x| x * x).sum();
            }
            r += k;
        }
        for (w, wi) in self.w[..n].iter().zip(self.winv.iter_mut()) {
            *wi = if *w > 1e-14 { 1.0 / w } else { 0.0 };
        }
        self.table = table_v;
    }

    /// Whether row r is a contact normal followed by its two tangent rows on
    /// the same path (as `sim::constraints` pushes them).
    #[inline]
    fn is_contact(&self, r: usize) -> bool {
        r + 2 < self.n
            && self.kind[r] == RowKind::Normal
            && matches!(self.kind[r + 1], RowKind::Tangent { normal, .. } if normal == r)
            && self.kind[r + 2] == RowKind::Tangent2
            && self.path[r + 1] == self.path[r]
            && self.path[r + 2] == self.path[r]
    }

    /// Projected Gauss–Seidel on W = Y Yᵀ, kept implicit: Δv' = Yᵀλ is carried
    /// along (in `dv`, length nv) so that a row's velocity is uᵣ = cᵣ + yᵣ·Δv',
    /// O(path length) a row; the caller recovers Δv = R⁻¹ Δv'. Stops when no
    /// row's velocity changes by more than `tol` (m/s or rad/s) in a sweep, or
    /// after `max_iter` sweeps; returns the sweeps. Rows with a (numerically)
    /// zero diagonal stay at 0. After three plain sweeps, the scalar rows
    /// (contact normals, joint friction and limits) are over-relaxed by `relax`
    /// ∈ (0, 2) (projected SOR, convergent for the positive semi-definite W in
    /// that range; 1 is plain Gauss–Seidel) until converged, then one plain
    /// sweep ends the solve; the tangent pairs, projected onto the friction
    /// disc, are never over-relaxed. A solve still unconverged after half of
    /// `max_iter` sweeps goes on with plain sweeps.
    pub fn solve(
        &mut self,
        f: &MassFactor,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> usize {
        self.polished = false;
        let _ = f;
        let table_v = std::mem::take(&mut self.table);
        let it = self.sweeps(&table_v, dv, max_iter, tol, relax);
        self.table = table_v;
        it
    }

    /// [`Rows::solve`] on the path table `table` (taken out of the rows).
    fn sweeps(
        &mut self,
        table: &[usize],
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> usize {
        let (nv, n, st) = (self.nv, self.n, self.stride);
        if dv.len() < nv
            || self.y.len() < n * st
            || self.kind.len() < n
            || self
                .path
                .iter()
                .take(n)
                .any(|&(s, l)| s + l > table.len() || l > st)
        {
            return 0;
        }
        let dv = &mut dv[..nv];
        let (y, paths) = (&self.y[..], &self.path[..n]);
        let (kinds, w, c, b) = (&self.kind[..n], &self.w[..n], &self.c[..n], &self.b[..n]);
        let contact = &self.is_block[..n];
        let w_block = &self.w_block[..n];
        let winv = &self.winv[..n];
        // a row no impulse can move keeps 0
        let live = |r: usize| if winv[r] != 0.0 { 1.0 } else { 0.0 };
        let u_prev = &mut self.u_prev[..n];
        // a row's convergence measure: its own residual |Δλ|·Wᵣᵣ, or, when
        // smaller, how much its velocity moved since the last sweep (redundant
        // contacts can trade impulse among themselves for many sweeps while no
        // velocity changes: that is converged)
        #[inline(always)]
        fn measure(first: bool, residual: f64, u: f64, prev: &mut f64) -> f64 {
            let moved = (u - *prev).abs();
            *prev = u;
            if first {
                residual
            } else {
                residual.min(moved)
            }
        }
        let lambda = &mut self.lambda[..n];
        // SAFETY (unchecked reads in rdot/raxpy): every path lies in `table`
        // (checked above) and holds dof indices < nv; y holds n·stride entries and
        // a path is at most stride long.
        #[inline(always)]
        fn rdot(y: &[f64], r: usize, st: usize, p: &[usize], x: &[f64]) -> f64 {
            let mut s = 0.0;
            for (t, &k) in p.iter().enumerate() {
                s += unsafe { y.get_unchecked(r * st + t) * x.get_unchecked(k) };
            }
            s
        }
        #[inline(always)]
        fn raxpy(a: f64, y: &[f64], r: usize, st: usize, p: &[usize], x: &mut [f64]) {
            for (t, &k) in p.iter().enumerate() {
                unsafe { *x.get_unchecked_mut(k) += a * y.get_unchecked(r * st + t) };
            }
        }
        let path = |r: usize| {
            let (s, l) = paths[r];
            &table[s..s + l]
        };
        // Δv' from the warm start
        dv.iter_mut().for_each(|x| *x = 0.0);
        for r in 0..n {
            let l = lambda[r];
            if l != 0.0 {
                raxpy(l, y, r, st, path(r), dv);
            }
        }
        let mut it = 0;
        // plain sweeps first; a problem not solved in `PLAIN` sweeps is
        // over-relaxed, and once that has converged one plain sweep finishes it
        // (every row then leaves its own residual exactly 0 or projected, as
        // Gauss–Seidel does)
        const PLAIN: usize = 3;
        let mut finishing = false;
        let mut attempts = 0;
        let mut polished = false;
        while it < max_iter {
            it += 1;
            let plain = it <= PLAIN || finishing || polished || 2 * it > max_iter || relax == 1.0;
            let relax = if plain { 1.0 } else { relax };
            let first = it == 1;
            let mut change: f64 = 0.0;
            let mut r = 0;
            while r < n {
                let kind = kinds[r];
                if contact[r] {
                    // a contact's three rows in one pass over its path: the
                    // normal, then the tangent pair from the velocity the
                    // normal's change left (through the block's entries)
                    let p = path(r);
                    let (mut dn, mut d1, mut d2) = (0.0, 0.0, 0.0);
                    for (t, &k) in p.iter().enumerate() {
                        let x = unsafe { *dv.get_unchecked(k) };
                        unsafe {
                            dn += y.get_unchecked(r * st + t) * x;
                            d1 += y.get_unchecked((r + 1) * st + t) * x;
                            d2 += y.get_unchecked((r + 2) * st + t) * x;
                        }
                    }
                    let [wn1, wn2, w12] = w_block[r];
                    let (wnn, w11, w22) = (w[r], w[r + 1], w[r + 2]);
                    let on = lambda[r];
                    let un = c[r] + dn;
                    let nn = (on - relax * (un - b[r]) * winv[r]).max(0.0) * live(r);
                    let dln = nn - on;
                    lambda[r] = nn;
                    let mu = match kinds[r + 1] {
                        RowKind::Tangent { mu, .. } => mu,
                        _ => 0.0,
                    };
                    let (o1, o2) = (lambda[r + 1], lambda[r + 2]);
                    let u1 = c[r + 1] + d1 + dln * wn1;
                    let u2 = c[r + 2] + d2 + dln * wn2;
                    let mut t1 = (o1 - u1 * winv[r + 1]) * live(r + 1);
                    let mut t2 = (o2 - u2 * winv[r + 2]) * live(r + 2);
                    let lim = mu * nn;
                    if t1 * t1 + t2 * t2 > lim * lim {
                        // w̄ = (W₁₁ + W₂₂)/2 + √(((W₁₁ − W₂₂)/2)² + W₁₂²)
                        let half = 0.5 * (w11 - w22);
                        let wbar = 0.5 * (w11 + w22) + (half * half + w12 * w12).sqrt();
                        (t1, t2) = slide_onto_cone(o1, o2, u1, u2, wbar, lim);
                        t1 *= live(r + 1);
                        t2 *= live(r + 2);
                    }
                    lambda[r + 1] = t1;
                    lambda[r + 2] = t2;
                    let (dl1, dl2) = (t1 - o1, t2 - o2);
                    if dln != 0.0 || dl1 != 0.0 || dl2 != 0.0 {
                        for (t, &k) in p.iter().enumerate() {
                            unsafe {
                                *dv.get_unchecked_mut(k) += dln * y.get_unchecked(r * st + t)
                                    + dl1 * y.get_unchecked((r + 1) * st + t)
                                    + dl2 * y.get_unchecked((r + 2) * st + t);
                            }
                        }
                    }
                    change = change
                        .max(measure(first, (dln * wnn).abs(), un, &mut u_prev[r]))
                        .max(measure(first, (dl1 * w11).abs(), u1, &mut u_prev[r + 1]))
                        .max(measure(first, (dl2 * w22).abs(), u2, &mut u_prev[r + 2]));
                    r += 3;
                    continue;
                }
                match kind {
                    RowKind::Tangent { normal, mu } if r + 1 < n => {
                        let (p1, p2) = (path(r), path(r + 1));
                        let (w11, w22) = (w[r], w[r + 1]);
                        let u1 = c[r] + rdot(y, r, st, p1, dv);
                        let u2 = c[r + 1] + rdot(y, r + 1, st, p2, dv);
                        let (o1, o2) = (lambda[r], lambda[r + 1]);
                        let mut t1 = if w11 > 1e-14 { o1 - u1 / w11 } else { 0.0 };
                        let mut t2 = if w22 > 1e-14 { o2 - u2 / w22 } else { 0.0 };
                        let ln = lambda.get(normal).copied().unwrap_or(0.0);
                        let lim = mu * if ln > 0.0 { ln } else { 0.0 };
                        if t1 * t1 + t2 * t2 > lim * lim {
                            // the block's largest eigenvalue ≤ its trace
                            (t1, t2) = slide_onto_cone(o1, o2, u1, u2, w11 + w22, lim);
                        }
                        lambda[r] = t1;
                        lambda[r + 1] = t2;
                        let (d1, d2) = (t1 - o1, t2 - o2);
                        if d1 != 0.0 {
                            raxpy(d1, y, r, st, p1, dv);
                        }
                        if d2 != 0.0 {
                            raxpy(d2, y, r + 1, st, p2, dv);
                        }
                        change = change
                            .max(measure(first, (d1 * w11).abs(), u1, &mut u_prev[r]))
                            .max(measure(first, (d2 * w22).abs(), u2, &mut u_prev[r + 1]));
                        r += 2;
                        continue;
                    }
                    RowKind::Tangent2 | RowKind::Tangent { .. } => {
                        r += 1;
                        continue;
                    }
                    _ => {}
                }
                let wrr = w[r];
                let old = lambda[r];
                let p = path(r);
                let mut u = 0.0;
                let new = if winv[r] != 0.0 {
                    u = c[r] + rdot(y, r, st, p, dv);
                    let x = old - relax * (u - b[r]) * winv[r];
                    match kind {
                        RowKind::Box { limit } => x.clamp(-limit, limit),
                        _ => x.max(0.0),
                    }
                } else {
                    0.0
                };
                lambda[r] = new;
                let d = new - old;
                if d != 0.0 {
                    raxpy(d, y, r, st, p, dv);
                }
                change = change.max(measure(first, (d * wrr).abs(), u, &mut u_prev[r]));
                r += 1;
            }
            if finishing || (change <= tol && plain) {
                break;
            }
            if change <= tol {
                finishing = true;
            } else if it >= SUBSPACE_AFTER && attempts < SUBSPACE_TRIES && it + 1 < max_iter {
                // slow linear convergence (coupled rows): solve the rows
                // the sweeps left free exactly, then let plain sweeps check
                attempts += 1;
                let rows = Solved {
                    n,
                    nv,
                    st,
                    y,
                    paths,
                    table,
                    kinds,
                    contact,
                    winv,
                    c,
                    b,
                };
                if subspace_step(&mut self.sm, &rows, lambda, dv) {
                    polished = true;
                }
            }
        }
        self.polished = polished;
        it
    }
}

/// Sweeps before the first subspace step, and the most a solve takes.
const SUBSPACE_AFTER: usize = 2;
const SUBSPACE_TRIES: usize = 3;

/// The read-only view of the rows a subspace step needs.
struct Solved<'a> {
    n: usize,
    nv: usize,
    /// Room of a row in `y`.
    st: usize,
    y: &'a [f64],
    paths: &'a [(usize, usize)],
    table: &'a [usize],
    kinds: &'a [RowKind],
    contact: &'a [bool],
    /// 1 / Wᵣᵣ (0: a row no impulse can move).
    winv: &'a [f64],
    c: &'a [f64],
    b: &'a [f64],
}

/// One subspace-minimisation step of projected Gauss–Seidel (PGS-SM,
/// docs/theory.md §"Constraint solve"): the rows the sweeps left strictly
/// inside their sets — positive normals and limits, sticking tangent pairs,
/// joint friction below its bound — are solved exactly as equalities
/// (W_FF δ = b_F − u_F, the other rows held), by a dense LDLᵀ of W_FF that
/// drops rows dependent on earlier ones (redundant contacts). The result is
/// projected onto the sets (normals and limits ≥ 0, friction in its box, a
/// sticking pair into its cone) and a sliding pair, held in the solve, is put
/// back on its cone's boundary at the new normal impulse; the sweeps that
/// follow check it (exact when the sweeps had found the active set). Gauss–
/// Seidel converges linearly, at a rate that coupled rows (a light arm on a
/// base resting on several points) make slow. Returns whether a step was taken
/// (λ and Δv' = Yᵀλ updated).
fn subspace_step(sm: &mut Subspace, rows: &Solved, lambda: &mut [f64], dv: &mut [f64]) -> bool {
    let Solved {
        n,
        nv,
        st,
        y,
        paths,
        table,
        kinds,
        contact,
        winv,
        c,
        b,
    } = *rows;
    let path = |r: usize| {
        let (s, l) = paths[r];
        &table[s..s + l]
    };
    let inside =
        |t1: f64, t2: f64, ln: f64, mu: f64| (t1 * t1 + t2 * t2).sqrt() < mu * ln * (1.0 - 1e-9);
    // F: the free rows
    sm.rows.clear();
    let mut r = 0;
    while r < n {
        let live = |q: usize| winv[q] != 0.0;
        if contact[r] {
            let mu = match kinds[r + 1] {
                RowKind::Tangent { mu, .. } => mu,
                _ => 0.0,
            };
            sm.sliding[r + 1] = !inside(lambda[r + 1], lambda[r + 2], lambda[r], mu);
            if lambda[r] > 0.0 && live(r) {
                sm.rows.push(r);
                if !sm.sliding[r + 1] && live(r + 1) && live(r + 2) {
                    sm.rows.push(r + 1);
                    sm.rows.push(r + 2);
                }
            }
            r += 3;
            continue;
        }
        match kinds[r] {
            RowKind::Tangent { normal, mu } if r + 1 < n => {
                let ln = lambda.get(normal).copied().unwrap_or(0.0);
                sm.sliding[r] = !inside(lambda[r], lambda[r + 1], ln, mu);
                if ln > 0.0 && !sm.sliding[r] && live(r) && live(r + 1) {
                    sm.rows.push(r);
                    sm.rows.push(r + 1);
                }
                r += 2;
                continue;
            }
            RowKind::Tangent2 | RowKind::Tangent { .. } => {}
            RowKind::Normal | RowKind::Unilateral => {
                if lambda[r] > 0.0 && live(r) {
                    sm.rows.push(r);
                }
            }
            RowKind::Box { limit } => {
                if lambda[r].abs() < limit * (1.0 - 1e-9) && live(r) {
                    sm.rows.push(r);
                }
            }
        }
        r += 1;
        if sm.rows.len() > SUBSPACE_MAX {
            return false;
        }
    }
    let m = sm.rows.len();
    if m == 0 || m > SUBSPACE_MAX || sm.dense.len() < m * nv {
        return false;
    }
    // the free rows of Y at full width, the residuals b − u, and the lower
    // triangle of W_FF = Y_F Y_Fᵀ
    for (a, &r) in sm.rows.iter().enumerate() {
        let d = &mut sm.dense[a * nv..(a + 1) * nv];
        d.fill(0.0);
        let mut u = c[r];
        for (t, &k) in path(r).iter().enumerate() {
            let yt = y[r * st + t];
            d[k] = yt;
            u += yt * dv[k];
        }
        let target = match kinds[r] {
            RowKind::Tangent { .. } | RowKind::Tangent2 => 0.0,
            _ => b[r],
        };
        sm.rhs[a] = target - u;
        for (bb, &q) in sm.rows.iter().enumerate().take(a + 1) {
            let mut s = 0.0;
            for (t, &k) in path(q).iter().enumerate() {
                s += y[q * st + t] * d[k];
            }
            sm.w[a * m + bb] = s;
        }
    }
    // W_FF = L D Lᵀ; a pivot that lost all but 1e-10 of its diagonal is a
    // row dependent on earlier ones (redundant contacts): dropped (δ = 0)
    ldlt_dropping(&mut sm.w[..m * m], m, 1e-10);
    ldlt_dropping_solve(&sm.w[..m * m], m, &mut sm.rhs[..m]);
    // the new impulses (none taken if one is not finite)
    for (a, &r) in sm.rows.iter().enumerate() {
        let x = lambda[r] + sm.rhs[a];
        if !x.is_finite() {
            return false;
        }
        sm.lam[a] = x;
    }
    // projected onto the sets (the step is exact when nothing moves here):
    // normals and limits ≥ 0, friction in its box; then the tangent pairs, a
    // sticking pair into the cone of its new normal, a sliding one (held in
    // the solve) along its direction onto that cone's boundary, μλₙ
    let add = |r: usize, d: f64, dv: &mut [f64]| {
        if d != 0.0 {
            for (t, &k) in path(r).iter().enumerate() {
                dv[k] += d * y[r * st + t];
            }
        }
    };
    for (a, &r) in sm.rows.iter().enumerate() {
        let x = match kinds[r] {
            RowKind::Normal | RowKind::Unilateral => sm.lam[a].max(0.0),
            RowKind::Box { limit } => sm.lam[a].clamp(-limit, limit),
            _ => continue,
        };
        let d = x - lambda[r];
        lambda[r] = x;
        add(r, d, dv);
    }
    let mut r = 0;
    while r + 1 < n {
        let RowKind::Tangent { normal, mu } = kinds[r] else {
            r += 1;
            continue;
        };
        let lim = mu * lambda.get(normal).copied().unwrap_or(0.0).max(0.0);
        let free = sm.rows.iter().position(|&q| q == r).filter(|&a| a + 1 < m);
        let (t1, t2) = match free {
            Some(a) => (sm.lam[a], sm.lam[a + 1]),
            None => (lambda[r], lambda[r + 1]),
        };
        let norm = (t1 * t1 + t2 * t2).sqrt();
        let s = if norm > lim || (free.is_none() && sm.sliding[r]) {
            if norm > 0.0 {
                lim / norm
            } else {
                0.0
            }
        } else {
            1.0
        };
        let (n1, n2) = (t1 * s, t2 * s);
        let (d1, d2) = (n1 - lambda[r], n2 - lambda[r + 1]);
        lambda[r] = n1;
        lambda[r + 1] = n2;
        add(r, d1, dv);
        add(r + 1, d2, dv);
        r += 2;
    }
    true
}

impl Rows {
    /// The position pass (split impulse): projected Gauss–Seidel on the same
    /// W = Y Yᵀ over the unilateral rows (contact normals, joint limits) only,
    /// from μ = 0, for 0 ≤ μᵣ ⊥ yᵣ·w' − b_posᵣ ≥ 0; the pseudo-velocity is
    /// w = L⁻ᵀ w' (`dw` receives w' = Yᵀμ; the caller back-substitutes). Rows
    /// that are not violated (b_pos = 0) take part so that pushing one point out
    /// never pushes another in. Returns the sweeps.
    pub fn solve_position(
        &mut self,
        f: &MassFactor,
        dw: &mut [f64],
        max_iter: usize,
        tol: f64,
    ) -> usize {
        let (nv, n) = (self.nv, self.n);
        let _ = f;
        if dw.len() < nv
            || self.y.len() < n * self.stride
            || self.mu.len() < n
            || self.bpos.len() < n
        {
            return 0;
        }
        let table_v = std::mem::take(&mut self.table);
        let it = self.position_sweeps(&table_v, dw, max_iter, tol);
        self.table = table_v;
        it
    }

    /// [`Rows::solve_position`] on the path table `table` (taken out of the rows).
    fn position_sweeps(
        &mut self,
        table: &[usize],
        dw: &mut [f64],
        max_iter: usize,
        tol: f64,
    ) -> usize {
        let (nv, n, st) = (self.nv, self.n, self.stride);
        let dw = &mut dw[..nv];
        dw.iter_mut().for_each(|x| *x = 0.0);
        self.mu[..n].iter_mut().for_each(|x| *x = 0.0);
        let mut it = 0;
        while it < max_iter {
            it += 1;
            let mut change: f64 = 0.0;
            for r in 0..n {
                if !matches!(self.kind[r], RowKind::Normal | RowKind::Unilateral) {
                    continue;
                }
                let wrr = self.w[r];
                if !(wrr > 1e-14) {
                    continue;
                }
                let (ps, pl) = self.path[r];
                let (Some(p), Some(yr)) = (table.get(ps..ps + pl), self.y.get(r * st..r * st + pl))
                else {
                    continue;
                };
                let u: f64 = yr.iter().zip(p).map(|(a, &k)| a * dw[k]).sum();
                let old = self.mu[r];
                let new = (old - (u - self.bpos[r]) / wrr).max(0.0);
                let d = new - old;
                if d != 0.0 {
                    self.mu[r] = new;
                    for (a, &k) in yr.iter().zip(p) {
                        dw[k] += d * a;
                    }
                    change = change.max((d * wrr).abs());
                }
            }
            if change <= tol {
                break;
            }
        }
        it
    }
}

/// `Σ aₖ bₖ` over the shorter of the two slices.
#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A tangent pair's update when its Gauss–Seidel step leaves the cone (the
/// point slides): one isotropic step, λₜ − uₜ/w̄ with `wbar` = w̄ at least the
/// largest eigenvalue of the pair's 2 × 2 Delassus block, projected onto the disc
/// of radius `lim`. A fixed point of it is the exact Coulomb law: λₜ = s (λₜ − uₜ/w̄)
/// with s < 1 makes λₜ anti-parallel to the slip uₜ, ‖λₜ‖ = μλₙ (maximal
/// dissipation; the per-row diagonal step would leave λₜ anti-parallel to
/// D⁻¹uₜ instead, off by the block's anisotropy: docs/theory.md §"Constraint
/// solve"). Inside the cone (sticking) the diagonal step is kept.
#[inline]
fn slide_onto_cone(o1: f64, o2: f64, u1: f64, u2: f64, wbar: f64, lim: f64) -> (f64, f64) {
    if !(wbar > 1e-14) {
        return (0.0, 0.0);
    }
    let (t1, t2) = (o1 - u1 / wbar, o2 - u2 / wbar);
    let m = (t1 * t1 + t2 * t2).sqrt();
    if m > lim {
        let s = if m > 0.0 { lim / m } else { 0.0 };
        (t1 * s, t2 * s)
    } else {
        (t1, t2)
    }
}
