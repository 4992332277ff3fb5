//! The position pass (split impulse) on the solve's rows.

use super::kernels::{Dofs, Path, Runs};
use super::loop_block::BlockRows;
use super::{MassFactor, RowKind, Rows};
use crate::contact::ContactPoint;

/// A row the position pass updates: its index, where its path's dofs lie
/// (checked to lie in the table), its path's length, and whether it is a
/// loop row (bilateral: μ free).
#[derive(Clone, Copy, Debug)]
pub(super) struct PosRow {
    r: usize,
    at: At,
    pl: usize,
    bilateral: bool,
}

/// Where a [`PosRow`]'s path lies in w' ([`Path::of`] kept by value): one
/// run of six consecutive dofs from the first, two such runs (a free
/// body's path, two free bodies': the piles' rows), or the table's entries
/// from this start (gathered).
#[derive(Clone, Copy, Debug)]
enum At {
    One(usize),
    Two(usize, usize),
    Table(usize),
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
        let all = [(0, 0, n)];
        self.solve_position_runs(&all, None, dw, max_iter, tol, None)
    }

    /// [`Rows::solve_position`] on the rows of `runs` only (an island's,
    /// [`Rows::solve_runs`]), whose w' lives on `dofs` (`None`: every dof):
    /// only those entries of `dw` are zeroed and written. `warm`: each row's
    /// μ to start from (a unilateral row's, by row index; see [`pos_warm`]),
    /// else μ = 0.
    pub(crate) fn solve_position_runs(
        &mut self,
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dw: &mut [f64],
        max_iter: usize,
        tol: f64,
        warm: Option<&[f64]>,
    ) -> usize {
        let (nv, n) = (self.nv, self.n);
        if dw.len() < nv
            || self.mu.len() < n
            || runs.iter().any(|&(_, _, e)| e > n)
            || dofs.is_some_and(|d| d.iter().any(|&k| k >= nv))
        {
            return 0;
        }
        let table_v = std::mem::take(&mut self.table);
        let it = self.position_sweeps(&table_v, runs, dofs, dw, max_iter, tol, warm);
        self.table = table_v;
        it
    }

    /// [`Rows::solve_position`] on the path table `table` (taken out of the rows).
    #[allow(clippy::too_many_arguments)]
    fn position_sweeps(
        &mut self,
        table: &[usize],
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dw: &mut [f64],
        max_iter: usize,
        tol: f64,
        warm: Option<&[f64]>,
    ) -> usize {
        let (nv, st) = (self.nv, self.stride);
        let dw = &mut dw[..nv];
        match dofs {
            Some(d) => d.iter().for_each(|&k| dw[k] = 0.0),
            None => dw.iter_mut().for_each(|x| *x = 0.0),
        }
        for &(_, s, e) in runs {
            self.mu[s..e].iter_mut().for_each(|x| *x = 0.0);
        }
        // the loop rows as one exact block after each sweep (loop_block.rs):
        // J_b w = b_pos,b to rounding at the pass's end
        let view = BlockRows {
            st,
            y: &self.y,
            paths: &self.path[..self.n],
            table,
        };
        let block = self
            .sm
            .loops
            .prepare(&view, runs, &self.kind[..self.n], &self.w[..self.n]);
        // SAFETY (unchecked reads of dw below): every path lies in `table`
        // (checked here) and holds dof indices < nv (the factor's table and
        // its unions, as the velocity sweeps rely on, pgs.rs)
        let n = self.n;
        if runs.iter().any(|&(_, s, e)| {
            e > n
                || self.path[s..e]
                    .iter()
                    .any(|&(s, l)| s + l > table.len() || l > st)
        }) {
            return 0;
        }
        debug_assert!(table.iter().all(|&k| k < nv), "a dof path beyond nv");
        // the rows read-only and μ apart (no reload of the rows' fields after
        // each write of μ)
        let (kinds, w, paths) = (&self.kind[..n], &self.w[..n], &self.path[..n]);
        let (y, bpos) = (&self.y[..], &self.bpos[..n]);
        // the rows a sweep updates, listed once in sweep order: the contact
        // normals and joint limits (and the loop rows when not one block)
        // with a diagonal W above 1e-14 and their path and y in range (the
        // rows every sweep skipped are left out of the sweeps)
        let mut list = std::mem::take(&mut self.pos_rows);
        list.clear();
        for &(_, s, e) in runs {
            for r in s..e {
                let kind = kinds[r];
                let bilateral = kind == RowKind::Bilateral;
                if bilateral && block {
                    continue;
                }
                if !bilateral && !matches!(kind, RowKind::Normal | RowKind::Unilateral) {
                    continue;
                }
                if !(w[r] > 1e-14) {
                    continue;
                }
                let (ps, pl) = paths[r];
                if table.get(ps..ps + pl).is_none() || y.get(r * st..r * st + pl).is_none() {
                    continue;
                }
                // SAFETY: ps..ps + pl lies in the table (checked above)
                let at = match Path::of(unsafe { table.get_unchecked(ps..ps + pl) }) {
                    Path::One(Runs([a])) => At::One(a),
                    Path::Two(Runs([a, b])) => At::Two(a, b),
                    Path::Any(_) => At::Table(ps),
                };
                list.push(PosRow {
                    r,
                    at,
                    pl,
                    bilateral,
                });
            }
        }
        let mu = &mut self.mu[..n];
        // the warm start: μ of the unilateral rows from the last pass (by
        // contact slot and joint limit), w' = Σ μᵣ yᵣ; from there the same
        // sweeps to the same complementarity conditions
        if let Some(warm) = warm {
            for &PosRow {
                r,
                at,
                pl,
                bilateral,
            } in &list
            {
                let m = warm.get(r).copied().unwrap_or(0.0);
                if bilateral || !(m > 0.0) {
                    continue;
                }
                mu[r] = m;
                // w' += μᵣ yᵣ
                // SAFETY: as in the sweeps below (checked when listed)
                unsafe {
                    let yr = y.get_unchecked(r * st..r * st + pl);
                    on_path!(at, pl, yr, table; yr, p, n => path_add(yr, p, n, m, dw))
                };
            }
        }
        let loops = &mut self.sm.loops;
        let mut it = 0;
        while it < max_iter {
            it += 1;
            let mut change: f64 = 0.0;
            for &PosRow {
                r,
                at,
                pl,
                bilateral,
            } in &list
            {
                let (wrr, b) = (w[r], bpos[r]);
                let mur = &mut mu[r];
                // SAFETY: the row's path and y were checked to lie in
                // `table` and `y` when listed (neither changes in the pass);
                // the path's dofs are < nv = dw.len() (the factor's table
                // and its unions, as above)
                let d = unsafe {
                    let yr = y.get_unchecked(r * st..r * st + pl);
                    on_path!(at, pl, yr, table; yr, p, n => project(yr, p, n, dw, mur, b, wrr, bilateral))
                };
                if d != 0.0 {
                    change = change.max((d * wrr).abs());
                }
            }
            if block {
                let view = BlockRows {
                    st,
                    y,
                    paths,
                    table,
                };
                let moved = loops.solve(&view, None, bpos, mu, dw);
                change = change.max(moved);
            }
            if change <= tol {
                break;
            }
        }
        self.pos_rows = list;
        it
    }
}

/// `$run` with `$yr` a row's y (`$y`, at least `$pl` long) and `$p` its
/// path at `$at` (`$pl` long, in `$table`) as [`Dofs`], `$n` their length:
/// a run or two of six dofs as [`Runs`] at the fixed length 6 or 12 (the
/// loops below unrolled whole, the dofs read without the table), else the
/// table's entries. The same dofs in the same order either way. Unsafe to
/// use: the caller vouches for the lengths.
macro_rules! on_path {
    ($at:expr, $pl:expr, $y:expr, $table:expr; $yr:ident, $p:ident, $n:ident => $run:expr) => {
        match $at {
            At::One(a) => {
                let ($yr, $p, $n) = ($y.get_unchecked(..6), Runs([a]), 6);
                $run
            }
            At::Two(a, b) => {
                let ($yr, $p, $n) = ($y.get_unchecked(..12), Runs([a, b]), 12);
                $run
            }
            At::Table(ps) => {
                let ($yr, $p, $n) = (
                    $y.get_unchecked(..$pl),
                    $table.get_unchecked(ps..ps + $pl),
                    $pl,
                );
                $run
            }
        }
    };
}
use on_path;

/// One row's projection, returning Δμᵣ: uᵣ = yᵣ·w' over its path (in path
/// order from −0, as `Iterator::sum` adds), μᵣ ← max(0, μᵣ − (uᵣ −
/// b_posᵣ)/Wᵣᵣ) (a loop row's unclamped), and w' += Δμᵣ yᵣ if it moved.
///
/// # Safety
/// `yr` and `p` hold `n` entries; every dof of `p` is < `x.len()`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn project<D: Dofs>(
    yr: &[f64],
    p: D,
    n: usize,
    x: &mut [f64],
    mu: &mut f64,
    b: f64,
    wrr: f64,
    bilateral: bool,
) -> f64 {
    let mut u = -0.0;
    for j in 0..n {
        // SAFETY: the caller's
        u += yr[j] * unsafe { *x.get_unchecked(p.at(j)) };
    }
    let old = *mu;
    let z = old - (u - b) / wrr;
    let new = if bilateral { z } else { z.max(0.0) };
    let d = new - old;
    if d != 0.0 {
        *mu = new;
        // SAFETY: the caller's
        unsafe { path_add(yr, p, n, d, x) };
    }
    d
}

/// x += d yᵣ over a row's path `p` (`n` slots, in path order).
///
/// # Safety
/// `yr` and `p` hold `n` entries; every dof of `p` is < `x.len()`.
#[inline(always)]
unsafe fn path_add<D: Dofs>(yr: &[f64], p: D, n: usize, d: f64, x: &mut [f64]) {
    for j in 0..n {
        // SAFETY: the caller's
        unsafe { *x.get_unchecked_mut(p.at(j)) += d * yr[j] };
    }
}

/// The position pass's warm start (μ of the last pass): the contact
/// normals' kept by contact slot with the velocity solve's λ (the fourth
/// entry of `warm_contact` in sim/constraints.rs), the joint limits' by dof
/// (the fourth and fifth of `warm_joint`), both written and held with λ;
/// gathered by row index for [`Rows::solve_position_runs`], scaled by 1 − β.
///
/// Why 1 − β: the pass moves q by Δt w, which removes β of each violation
/// beyond the slop (b_pos = β(−φ − slop)/Δt, sim/constraints.rs), so a
/// violation held still is (1 − β) times the last one at the next step, its
/// b_pos too, and with the same active rows and W the exact μ (W_AA μ_A =
/// b_A) is (1 − β) times the last (the last μ itself starts above it). The
/// sweeps' exit test (max |Δμᵣ| Wᵣᵣ ≤ tol) and cap are the cold pass's.
#[derive(Clone, Debug)]
pub(crate) struct PosWarm {
    /// This pass's start, by row.
    start: Vec<f64>,
    /// 1 − β: how much of a violation held still is left after a pass.
    decay: f64,
}

impl PosWarm {
    /// Room for `cap` rows.
    pub fn new(cap: usize) -> Self {
        Self {
            start: Vec::with_capacity(cap),
            decay: 1.0,
        }
    }

    /// The pass removes `beta` of a violation a step (RowParams::beta): the
    /// warm start is 1 − `beta` of the last μ.
    pub fn set_beta(&mut self, beta: f64) {
        self.decay = (1.0 - beta).clamp(0.0, 1.0);
    }

    /// The entry of a dof's `warm_joint` (λ of friction, lower, upper at
    /// 0, 1, 2) that keeps the pass's μ of its limit row `which` (1 lower,
    /// 2 upper): 3 or 4.
    #[inline]
    pub fn limit_entry(which: u8) -> usize {
        2 + which as usize % 3
    }

    /// The start of this pass by row (`n` rows): contact triple c (rows 3c..)
    /// of point `row_point[c]` from its slot's entry 3 of `warm_contact`, a
    /// fresh point from 0; joint row `first_joint + k` of `joint_rows[k]` =
    /// (dof, which) from entry 2 + which of `warm_joint` (a limit's; a
    /// friction row from 0); every other row 0.
    #[allow(clippy::too_many_arguments)]
    pub fn gather(
        &mut self,
        n: usize,
        row_point: &[usize],
        points: &[ContactPoint],
        warm_contact: &[[f64; 4]],
        first_joint: usize,
        joint_rows: &[(usize, u8)],
        warm_joint: &[[f64; 5]],
    ) -> &[f64] {
        self.start.clear();
        self.start.resize(n, 0.0);
        for (c, &pi) in row_point.iter().enumerate() {
            if let (Some(pt), Some(x)) = (points.get(pi), self.start.get_mut(3 * c))
                && !pt.fresh
            {
                *x = self.decay * warm_contact.get(pt.slot).map_or(0.0, |w| w[3]);
            }
        }
        for (k, &(d, which)) in joint_rows.iter().enumerate() {
            if let (Some(w), Some(x)) = (warm_joint.get(d), self.start.get_mut(first_joint + k)) {
                *x = if which > 0 {
                    self.decay * w[PosWarm::limit_entry(which)]
                } else {
                    0.0
                };
            }
        }
        &self.start
    }
}
