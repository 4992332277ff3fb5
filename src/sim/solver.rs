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

use crate::dynamics::linalg::by_size;

/// What a row is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowKind {
    /// Contact normal (λ ≥ 0).
    Normal,
    /// First of a contact's two tangent rows; the next row is its partner.
    /// `normal` is the row index of the contact's normal, `mu` the friction.
    Tangent { normal: usize, mu: f64 },
    /// The second tangent row (handled with the first).
    Tangent2,
    /// Joint friction: |λ| ≤ limit.
    Box { limit: f64 },
    /// Joint limit: λ ≥ 0.
    Unilateral,
}

/// Preallocated rows: Jacobians (row-major, `nv` wide), H⁻¹Jᵀ, diag W, targets.
#[derive(Clone, Debug)]
pub struct Rows {
    pub nv: usize,
    pub n: usize,
    pub kind: Vec<RowKind>,
    pub j: Vec<f64>,
    pub y: Vec<f64>,
    pub w: Vec<f64>,
    /// J v* (free velocity).
    pub c: Vec<f64>,
    /// Target (b) of each row.
    pub b: Vec<f64>,
    pub lambda: Vec<f64>,
    /// Position-pass target of each unilateral row (0: not violated).
    pub bpos: Vec<f64>,
    /// Position-pass multipliers.
    pub mu: Vec<f64>,
    cap: usize,
}

impl Rows {
    pub fn new(nv: usize, cap: usize) -> Self {
        Self {
            nv,
            n: 0,
            kind: Vec::with_capacity(cap),
            j: vec![0.0; cap * nv],
            y: vec![0.0; cap * nv],
            w: vec![0.0; cap],
            c: vec![0.0; cap],
            b: vec![0.0; cap],
            lambda: vec![0.0; cap],
            bpos: vec![0.0; cap],
            mu: vec![0.0; cap],
            cap,
        }
    }
    pub fn capacity(&self) -> usize {
        self.cap
    }
    /// Empties the rows; their Jacobian entries are zeroed here, once, so that
    /// every row pushed after starts from zeros.
    pub fn clear(&mut self) {
        let used = (self.n * self.nv).min(self.j.len());
        self.j[..used].fill(0.0);
        self.n = 0;
        self.kind.clear();
    }
    /// Drops the last `k` rows (pushed, their Jacobian entries not yet written).
    pub fn pop(&mut self, k: usize) {
        let k = k.min(self.n);
        self.n -= k;
        self.kind.truncate(self.n);
        let from = (self.n * self.nv).min(self.j.len());
        let to = ((self.n + k) * self.nv).min(self.j.len());
        self.j[from..to].fill(0.0);
    }
    /// Adds a row (zeroed Jacobian: rows are zeroed by [`Rows::clear`]) and returns
    /// its index, or `None` when full.
    pub fn push(&mut self, kind: RowKind, b: f64, warm: f64) -> Option<usize> {
        if self.n >= self.cap {
            return None;
        }
        let r = self.n;
        self.n += 1;
        self.kind.push(kind);
        self.b[r] = b;
        self.lambda[r] = warm;
        self.bpos[r] = 0.0;
        Some(r)
    }
    pub fn jrow_mut(&mut self, r: usize) -> &mut [f64] {
        &mut self.j[r * self.nv..(r + 1) * self.nv]
    }
    pub fn jrow(&self, r: usize) -> &[f64] {
        &self.j[r * self.nv..(r + 1) * self.nv]
    }
    pub fn yrow(&self, r: usize) -> &[f64] {
        &self.y[r * self.nv..(r + 1) * self.nv]
    }

    /// Fills `y` with the rows of Y = J L⁻ᵀ (yᵣ = L⁻¹ jᵣ, one forward substitution
    /// a row) for the lower Cholesky factor `l` of H (column-major, nv × nv), the
    /// Delassus diagonal Wᵣᵣ = jᵣ·H⁻¹jᵣ = ‖yᵣ‖² and c = J v* for the free velocity
    /// `vfree`.
    pub fn form_factored(&mut self, l: &[f64], vfree: &[f64]) {
        let (nv, n) = (self.nv, self.n);
        if l.len() < nv * nv
            || vfree.len() < nv
            || self.j.len() < n * nv
            || self.y.len() < n * nv
            || self.w.len() < n
            || self.c.len() < n
        {
            return;
        }
        by_size!(nv, N => self.form_n::<N>(l, vfree))
    }

    /// [`Rows::form_factored`] with rows `N` long (`N = 0`: `self.nv`); the
    /// caller checked the lengths.
    #[inline(always)]
    fn form_n<const N: usize>(&mut self, l: &[f64], vfree: &[f64]) {
        let nv = if N == 0 { self.nv } else { N };
        let n = self.n;
        let (j, y) = (&self.j[..n * nv], &mut self.y[..n * nv]);
        let (w, c) = (&mut self.w[..n], &mut self.c[..n]);
        let (l, vfree) = (&l[..nv * nv], &vfree[..nv]);
        // SAFETY: r < n, k, i < nv; j and y are n·nv long, l nv·nv, vfree nv,
        // w and c n (sliced above).
        unsafe {
            for r in 0..n {
                let mut cr = -0.0;
                let mut wr = -0.0;
                for k in 0..nv {
                    let jk = *j.get_unchecked(r * nv + k);
                    cr += jk * *vfree.get_unchecked(k);
                    *y.get_unchecked_mut(r * nv + k) = jk;
                }
                for k in 0..nv {
                    let xk = *y.get_unchecked(r * nv + k) / *l.get_unchecked(k * nv + k);
                    *y.get_unchecked_mut(r * nv + k) = xk;
                    wr += xk * xk;
                    for i in k + 1..nv {
                        *y.get_unchecked_mut(r * nv + i) -= *l.get_unchecked(k * nv + i) * xk;
                    }
                }
                *c.get_unchecked_mut(r) = cr;
                *w.get_unchecked_mut(r) = wr;
            }
        }
    }

    /// Projected Gauss–Seidel on W = J H⁻¹ Jᵀ = Y Yᵀ (Y = J L⁻ᵀ, H = L Lᵀ), kept
    /// implicit: Δv' = Lᵀ Δv = Yᵀλ is carried along (in `dv`, length nv) so that
    /// a row's velocity is uᵣ = cᵣ + yᵣ·Δv', O(nv) a row; the caller recovers
    /// Δv = L⁻ᵀ Δv'. Stops when no row's velocity
    /// changes by more than `tol` (m/s or rad/s) in a sweep, or after `max_iter`
    /// sweeps; returns the sweeps. Rows with a (numerically) zero diagonal stay at 0.
    /// After three plain sweeps, the scalar rows (contact normals, joint friction
    /// and limits) are over-relaxed by `relax` ∈ (0, 2) (projected SOR, convergent
    /// for the positive semi-definite W in that range; 1 is plain Gauss–Seidel)
    /// until converged, then one plain sweep ends the solve; the tangent pairs,
    /// projected onto the friction disc, are never over-relaxed. A solve still
    /// unconverged after half of `max_iter` sweeps goes on with plain sweeps: an
    /// over-relaxed iterate left by the sweep limit can add energy (talos_reduced
    /// standing on its feet did not come to rest that way), a Gauss–Seidel one
    /// does not in practice.
    pub fn solve(&mut self, dv: &mut [f64], max_iter: usize, tol: f64, relax: f64) -> usize {
        // the row length known at compile time for common sizes: the short dot
        // products and updates are unrolled (same arithmetic, same order)
        by_size!(self.nv, N => self.solve_n::<N>(dv, max_iter, tol, relax))
    }

    /// [`Rows::solve`] with rows `N` long (`N = 0`: `self.nv`).
    #[inline]
    fn solve_n<const N: usize>(
        &mut self,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> usize {
        let nv = if N == 0 { self.nv } else { N };
        if N != 0 && (dv.len() < N || self.nv != N) {
            return self.solve_n::<0>(dv, max_iter, tol, relax);
        }
        let n = self.n;
        if dv.len() < nv
            || self.j.len() < n * nv
            || self.y.len() < n * nv
            || self.kind.len() < n
            || self.w.len() < n
            || self.c.len() < n
            || self.b.len() < n
            || self.lambda.len() < n
        {
            return 0;
        }
        let dv = &mut dv[..nv];
        let y = &self.y[..n * nv];
        let (kinds, w, c, b) = (&self.kind[..n], &self.w[..n], &self.c[..n], &self.b[..n]);
        let lambda = &mut self.lambda[..n];
        // SAFETY (all unchecked reads below): r < n, k < nv, the slices above are
        // n·nv and n long, dv is nv long.
        #[inline(always)]
        fn rdot<const N: usize>(nv: usize, m: &[f64], r: usize, x: &[f64]) -> f64 {
            let nv = if N == 0 { nv } else { N };
            let mut s = -0.0;
            for k in 0..nv {
                s += unsafe { m.get_unchecked(r * nv + k) * x.get_unchecked(k) };
            }
            s
        }
        #[inline(always)]
        fn raxpy<const N: usize>(nv: usize, a: f64, m: &[f64], r: usize, x: &mut [f64]) {
            let nv = if N == 0 { nv } else { N };
            for k in 0..nv {
                unsafe { *x.get_unchecked_mut(k) += a * m.get_unchecked(r * nv + k) };
            }
        }
        // Δv from the warm start
        dv.iter_mut().for_each(|x| *x = 0.0);
        for r in 0..n {
            let l = lambda[r];
            if l != 0.0 {
                raxpy::<N>(nv, l, y, r, dv);
            }
        }
        let mut it = 0;
        // plain sweeps first; a problem not solved in `PLAIN` sweeps is
        // over-relaxed, and once that has converged one plain sweep finishes it
        // (every row then leaves its own residual exactly 0 or projected, as
        // Gauss–Seidel does)
        const PLAIN: usize = 3;
        let mut finishing = false;
        while it < max_iter {
            it += 1;
            let plain = it <= PLAIN || finishing || 2 * it > max_iter || relax == 1.0;
            let relax = if plain { 1.0 } else { relax };
            // (comparisons in place of f64::max: the same result, NaN included)
            let mut change: f64 = 0.0;
            let mut r = 0;
            while r < n {
                let kind = unsafe { *kinds.get_unchecked(r) };
                match kind {
                    RowKind::Tangent { normal, mu } if r + 1 < n => {
                        let (w11, w22) = unsafe { (*w.get_unchecked(r), *w.get_unchecked(r + 1)) };
                        let u1 = unsafe { *c.get_unchecked(r) } + rdot::<N>(nv, y, r, dv);
                        let u2 = unsafe { *c.get_unchecked(r + 1) } + rdot::<N>(nv, y, r + 1, dv);
                        let (o1, o2) =
                            unsafe { (*lambda.get_unchecked(r), *lambda.get_unchecked(r + 1)) };
                        let mut t1 = if w11 > 1e-14 { o1 - u1 / w11 } else { 0.0 };
                        let mut t2 = if w22 > 1e-14 { o2 - u2 / w22 } else { 0.0 };
                        let ln = lambda.get(normal).copied().unwrap_or(0.0);
                        let lim = mu * if ln > 0.0 { ln } else { 0.0 };
                        let m = (t1 * t1 + t2 * t2).sqrt();
                        if m > lim {
                            let s = if m > 0.0 { lim / m } else { 0.0 };
                            t1 *= s;
                            t2 *= s;
                        }
                        unsafe {
                            *lambda.get_unchecked_mut(r) = t1;
                            *lambda.get_unchecked_mut(r + 1) = t2;
                        }
                        let (d1, d2) = (t1 - o1, t2 - o2);
                        if d1 != 0.0 {
                            raxpy::<N>(nv, d1, y, r, dv);
                        }
                        if d2 != 0.0 {
                            raxpy::<N>(nv, d2, y, r + 1, dv);
                        }
                        let a1 = (d1 * w11).abs();
                        if a1 > change {
                            change = a1;
                        }
                        let a2 = (d2 * w22).abs();
                        if a2 > change {
                            change = a2;
                        }
                        r += 2;
                        continue;
                    }
                    RowKind::Tangent2 | RowKind::Tangent { .. } => {
                        r += 1;
                        continue;
                    }
                    _ => {}
                }
                let wrr = unsafe { *w.get_unchecked(r) };
                let old = unsafe { *lambda.get_unchecked(r) };
                let new = if wrr > 1e-14 {
                    let u = unsafe { *c.get_unchecked(r) } + rdot::<N>(nv, y, r, dv);
                    let x = old - relax * (u - unsafe { *b.get_unchecked(r) }) / wrr;
                    match kind {
                        RowKind::Box { limit } => {
                            if x < -limit {
                                -limit
                            } else if x > limit {
                                limit
                            } else {
                                x
                            }
                        }
                        _ => {
                            if x > 0.0 {
                                x
                            } else {
                                0.0
                            }
                        }
                    }
                } else {
                    0.0
                };
                unsafe { *lambda.get_unchecked_mut(r) = new };
                let d = new - old;
                if d != 0.0 {
                    raxpy::<N>(nv, d, y, r, dv);
                }
                let a = (d * wrr).abs();
                if a > change {
                    change = a;
                }
                r += 1;
            }
            if finishing || (change <= tol && plain) {
                break;
            }
            if change <= tol {
                finishing = true;
            }
        }
        it
    }
}

impl Rows {
    /// The position pass (split impulse): projected Gauss–Seidel on the same
    /// W = Y Yᵀ over the unilateral rows (contact normals, joint limits) only,
    /// from μ = 0, for 0 ≤ μᵣ ⊥ yᵣ·w' − b_posᵣ ≥ 0; the pseudo-velocity is
    /// w = L⁻ᵀ w' (`dw` receives w' = Yᵀμ; the caller back-substitutes). Rows
    /// that are not violated (b_pos = 0) take part so that pushing one point out
    /// never pushes another in. Returns the sweeps.
    pub fn solve_position(&mut self, dw: &mut [f64], max_iter: usize, tol: f64) -> usize {
        let (nv, n) = (self.nv, self.n);
        if dw.len() < nv || self.y.len() < n * nv || self.mu.len() < n || self.bpos.len() < n {
            return 0;
        }
        let dw = &mut dw[..nv];
        dw.iter_mut().for_each(|x| *x = 0.0);
        let y = &self.y[..n * nv];
        let mu = &mut self.mu[..n];
        mu.iter_mut().for_each(|x| *x = 0.0);
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
                let yr = &y[r * nv..(r + 1) * nv];
                let u = dot(yr, dw);
                let old = mu[r];
                let new = (old - (u - self.bpos[r]) / wrr).max(0.0);
                let d = new - old;
                if d != 0.0 {
                    mu[r] = new;
                    for (x, yk) in dw.iter_mut().zip(yr) {
                        *x += d * yk;
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

#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
