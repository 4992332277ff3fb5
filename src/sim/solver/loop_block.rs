//! The loop rows' exact block of the impulse solve (block Gauss–Seidel,
//! docs/theory.md §"Loop block"): the bilateral rows of the rows being solved
//! (loop constraints, mechanisms.md §"Simulation") are solved together, exactly,
//! by a dense LDLᵀ of their Delassus block W_bb = Y_b Y_bᵀ, each time the
//! sweeps have updated every other row: W_bb δλ_b = b_b − u_b with the other
//! rows' impulses held. After every sweep (and so at the solve's end) the loop
//! rows' velocities are on their targets to rounding, however far the contact
//! rows are from convergence: a closed chain cannot open at an impact because a
//! capped Gauss–Seidel left its rows unconverged.

use super::dot;
use super::{RowKind, Rows};
use crate::dynamics::linalg::{ldlt_dropping, ldlt_dropping_solve};

/// Most bilateral rows solved as one block (its dense W_bb is this square);
/// a larger set of loop rows is swept row by row as the other rows are.
pub const LOOP_BLOCK_MAX: usize = 48;

/// A pivot of W_bb that keeps less than this fraction of its diagonal after
/// the earlier rows is a row dependent on them (two loops sharing a link):
/// its δλ is 0 (least-norm-like handling of redundant rows).
const DROP: f64 = 1e-10;

/// Preallocated scratch of the loop block: its rows and the factor of W_bb;
/// and, for the other rows, the loop rows' response to
/// them (the reduced Delassus matrix, [`LoopBlock::reduce`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct LoopBlock {
    /// Most rows this block takes (its `w` is this square): a field, not the
    /// `rows` vector's capacity, which a clone does not keep.
    max: usize,
    rows: Vec<usize>,
    w: Vec<f64>,
    /// Rows in the block now (0: no block; the sweeps update loop rows
    /// themselves).
    m: usize,
    /// Per row r of the solve (m entries at r·m): g_r = W_bb⁻¹ W_br, the loop
    /// impulses' response to a unit impulse of row r (zero for a row the loop
    /// rows do not see).
    g: Vec<f64>,
    /// Whether row r couples to the loop rows (W_br ≠ 0).
    coupled: Vec<bool>,
    /// The reduced Delassus diagonal W'_rr = W_rr − W_rb g_r, its inverse (0:
    /// a row the loops hold still) and a contact's reduced 3 × 3 block's
    /// off-diagonal entries.
    pub(super) wr: Vec<f64>,
    pub(super) winvr: Vec<f64>,
    pub(super) wblockr: Vec<[f64; 3]>,
}

/// The read-only rows a block solve reads: Y, the paths, the table.
pub(super) struct BlockRows<'a> {
    pub(super) st: usize,
    pub(super) y: &'a [f64],
    pub(super) paths: &'a [(usize, usize)],
    pub(super) table: &'a [usize],
}

impl BlockRows<'_> {
    fn path(&self, r: usize) -> &[usize] {
        let (s, l) = self.paths[r];
        &self.table[s..s + l]
    }
    /// yᵣ · x (x full width).
    fn dot(&self, r: usize, x: &[f64]) -> f64 {
        let p = self.path(r);
        let yr = &self.y[r * self.st..r * self.st + p.len()];
        yr.iter().zip(p).map(|(a, &k)| a * x[k]).sum()
    }
    /// x += a yᵣ.
    fn axpy(&self, r: usize, a: f64, x: &mut [f64]) {
        let p = self.path(r);
        let yr = &self.y[r * self.st..r * self.st + p.len()];
        for (v, &k) in yr.iter().zip(p) {
            x[k] += a * v;
        }
    }
    /// yᵣ · y_q, a merge of the two ascending paths.
    fn cross(&self, r: usize, q: usize) -> f64 {
        let (pr, pq) = (self.path(r), self.path(q));
        let (mut s, mut i) = (0.0, 0);
        for (t, &k) in pq.iter().enumerate() {
            while i < pr.len() && pr[i] < k {
                i += 1;
            }
            if i < pr.len() && pr[i] == k {
                s += self.y[q * self.st + t] * self.y[r * self.st + i];
            }
        }
        s
    }
}

impl LoopBlock {
    /// Room for a block of up to `cap` rows (at most [`LOOP_BLOCK_MAX`]).
    pub(super) fn new(cap: usize) -> Self {
        let m = cap.min(LOOP_BLOCK_MAX);
        Self {
            max: m,
            rows: Vec::with_capacity(m),
            w: vec![0.0; m * m],
            m: 0,
            ..Default::default()
        }
    }

    /// The rows that are not loop rows, seen through the loops (docs/theory.md
    /// §"Loop block"): with the loop rows always on their targets, a row r's
    /// impulse δλ_r moves the loop impulses by −g_r δλ_r and its own velocity
    /// by the reduced W'_rr δλ_r, W' = W − W_·b W_bb⁻¹ W_b· (the Schur
    /// complement: the Delassus matrix of the closed mechanism). Fills g, the
    /// reduced diagonal and contact blocks over the rows of `runs` (the other
    /// entries copied from `w`, `w_block`, `winv`). Call after
    /// [`LoopBlock::prepare`] returned true. The storage grows on the first
    /// solve with loops only.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn reduce(
        &mut self,
        rows: &BlockRows,
        runs: &[(usize, usize, usize)],
        kinds: &[RowKind],
        contact: &[bool],
        w: &[f64],
        w_block: &[[f64; 3]],
        winv: &[f64],
    ) {
        let (n, m) = (w.len(), self.m);
        if self.g.len() < n * m {
            self.g.resize(n * m, 0.0);
        }
        if self.wr.len() < n {
            self.wr.resize(n, 0.0);
            self.winvr.resize(n, 0.0);
            self.wblockr.resize(n, [0.0; 3]);
            self.coupled.resize(n, false);
        }
        self.wr[..n].copy_from_slice(w);
        self.winvr[..n].copy_from_slice(winv);
        self.wblockr[..n].copy_from_slice(w_block);
        let mut x = [[0.0; LOOP_BLOCK_MAX]; 3];
        for r in runs.iter().flat_map(|&(_, s, e)| s..e) {
            self.coupled[r] = false;
            if kinds[r] == RowKind::Bilateral {
                continue;
            }
            let xr = &mut x[0][..m];
            for (a, &b) in self.rows.iter().enumerate() {
                xr[a] = rows.cross(b, r);
            }
            if xr.iter().all(|v| *v == 0.0) {
                continue;
            }
            let g = &mut self.g[r * m..(r + 1) * m];
            g.copy_from_slice(xr);
            ldlt_dropping_solve(&self.w[..m * m], m, g);
            if g.iter().any(|v| !v.is_finite()) {
                g.fill(0.0);
                continue;
            }
            self.coupled[r] = true;
            let wr = w[r] - dot(xr, g);
            self.wr[r] = wr;
            // a row the loops hold (almost) still keeps its impulse at 0
            self.winvr[r] = if wr > 1e-10 * w[r] && wr > 1e-14 {
                1.0 / wr
            } else {
                0.0
            };
        }
        // a contact's reduced off-diagonal entries W'_ij = W_ij − x_i·g_j
        for r in runs.iter().flat_map(|&(_, s, e)| s..e) {
            if !contact[r] || r + 2 >= n {
                continue;
            }
            if !(self.coupled[r] || self.coupled[r + 1] || self.coupled[r + 2]) {
                continue;
            }
            for i in 0..3 {
                for (a, &b) in self.rows.iter().enumerate() {
                    x[i][a] = if self.coupled[r + i] {
                        rows.cross(b, r + i)
                    } else {
                        0.0
                    };
                }
            }
            let g = |i: usize| &self.g[(r + i) * m..(r + i + 1) * m];
            let c = |i: usize, j: usize| {
                if self.coupled[r + j] {
                    dot(&x[i][..m], g(j))
                } else {
                    0.0
                }
            };
            let [w01, w02, w12] = w_block[r];
            self.wblockr[r] = [w01 - c(0, 1), w02 - c(0, 2), w12 - c(1, 2)];
        }
    }

    /// The loop rows' response to the impulse changes `dl` of rows `r..` (one
    /// row, or a contact's three): λ_b −= Σ g_{r+i} dlᵢ, Δv' += Y_bᵀ of that,
    /// which holds the loop rows on their targets ([`LoopBlock::reduce`]).
    #[inline]
    pub(super) fn follow(
        &self,
        rows: &BlockRows,
        r: usize,
        dl: &[f64],
        lambda: &mut [f64],
        dv: &mut [f64],
    ) {
        let m = self.m;
        if m == 0 {
            return;
        }
        let live = |i: usize| dl[i] != 0.0 && self.coupled.get(r + i).copied().unwrap_or(false);
        if !(0..dl.len()).any(live) {
            return;
        }
        for (a, &b) in self.rows.iter().enumerate() {
            let mut d = 0.0;
            for (i, x) in dl.iter().enumerate() {
                if live(i) {
                    d -= self.g[(r + i) * m + a] * x;
                }
            }
            if d != 0.0 {
                lambda[b] += d;
                rows.axpy(b, d, dv);
            }
        }
    }

    /// Whether row r couples to the loop rows (its updates call
    /// [`LoopBlock::follow`]).
    #[inline]
    pub(super) fn couples(&self, r: usize) -> bool {
        self.m > 0 && self.coupled.get(r).copied().unwrap_or(false)
    }

    /// Whether a block is set up (its rows are left out of the sweeps).
    #[allow(dead_code)]
    pub(super) fn active(&self) -> bool {
        self.m > 0
    }

    /// No block: what [`LoopBlock::prepare`] leaves on rows without a loop
    /// row of nonzero diagonal (false).
    pub(super) fn clear(&mut self) -> bool {
        self.m = 0;
        self.rows.clear();
        false
    }

    /// Collects the bilateral rows of `runs` whose diagonal is not zero and
    /// factors their W_bb = Y_b Y_bᵀ (L D Lᵀ, dependent rows dropped). No
    /// block (the sweeps take the rows one by one) when there are none or
    /// more than [`LOOP_BLOCK_MAX`].
    pub(super) fn prepare(
        &mut self,
        rows: &BlockRows,
        runs: &[(usize, usize, usize)],
        kinds: &[RowKind],
        w: &[f64],
    ) -> bool {
        self.m = 0;
        self.rows.clear();
        for r in runs.iter().flat_map(|&(_, s, e)| s..e) {
            if kinds[r] == RowKind::Bilateral && w[r] > 1e-14 {
                if self.rows.len() == self.max {
                    self.rows.clear();
                    return false;
                }
                self.rows.push(r);
            }
        }
        let m = self.rows.len();
        if m == 0 {
            return false;
        }
        for a in 0..m {
            for b in 0..=a {
                let x = rows.cross(self.rows[a], self.rows[b]);
                self.w[a * m + b] = x;
                self.w[b * m + a] = x;
            }
        }
        ldlt_dropping(&mut self.w[..m * m], m, DROP);
        self.m = m;
        true
    }

    /// One exact block solve: with the other rows' impulses held (their part
    /// of `dv` = Yᵀλ), δλ_b = W_bb⁻¹ (target_b − c_b − Y_b dv); λ_b and dv
    /// updated. `target` and `c` are indexed by row (the velocity solve:
    /// b and J v*; the position pass: b_pos and `None` for c = 0). Returns the
    /// largest velocity residual the block removed (m/s or rad/s).
    pub(super) fn solve(
        &self,
        rows: &BlockRows,
        c: Option<&[f64]>,
        target: &[f64],
        lambda: &mut [f64],
        dv: &mut [f64],
    ) -> f64 {
        let m = self.m;
        if m == 0 {
            return 0.0;
        }
        let mut worst: f64 = 0.0;
        let mut rhs = [0.0; LOOP_BLOCK_MAX];
        for (a, &r) in self.rows.iter().enumerate() {
            let u = c.map_or(0.0, |c| c[r]) + rows.dot(r, dv);
            let res = target[r] - u;
            worst = worst.max(res.abs());
            rhs[a] = res;
        }
        ldlt_dropping_solve(&self.w[..m * m], m, &mut rhs[..m]);
        if rhs[..m].iter().any(|x| !x.is_finite()) {
            return 0.0;
        }
        for (a, &r) in self.rows.iter().enumerate() {
            let d = rhs[a];
            if d != 0.0 {
                lambda[r] += d;
                rows.axpy(r, d, dv);
            }
        }
        worst
    }
}

impl Rows {
    /// Puts the loop rows of `runs` back on their velocity targets exactly,
    /// the other rows' impulses held (δλ_b = W_bb⁻¹(b_b − u_b), Δv' += Y_bᵀδλ_b;
    /// `dv` = Δv' of those runs, as [`Rows::solve_runs`] leaves it). An
    /// H̃-orthogonal projection onto J_b v⁺ = b_b = 0: the kinetic energy never
    /// rises (docs/theory.md §"Loop block"). For a solve whose impulses were
    /// scaled afterwards (the energy-safe exit). Returns whether rows were
    /// projected.
    pub(crate) fn close_loops(
        &self,
        out: &mut super::pgs::IslandOut<'_>,
        runs: &[(usize, usize, usize)],
        dv: &mut [f64],
    ) -> bool {
        let (n, st) = (self.n, self.stride);
        if dv.len() < self.nv || out.lambda.len() < n || runs.iter().any(|&(_, _, e)| e > n) {
            return false;
        }
        let view = BlockRows {
            st,
            y: &self.y,
            paths: &self.path[..n],
            table: &self.table,
        };
        let lb = &mut out.sm.0.loops;
        if !lb.prepare(&view, runs, &self.kind[..n], &self.w[..n]) {
            return false;
        }
        lb.solve(
            &view,
            Some(&self.c[..n]),
            &self.b[..n],
            &mut out.lambda[..n],
            dv,
        );
        true
    }
}
