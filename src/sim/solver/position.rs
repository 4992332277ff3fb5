//! The position pass (split impulse) on the solve's rows.

use super::kernels::{Dofs, Path, Runs};
use super::loop_block::BlockRows;
use super::subspace::runs::{add, dot_from};
use super::{MassFactor, RowKind, Rows};
use crate::contact::ContactPoint;

/// A row the position pass updates, with what its sweeps read of it: where
/// its path's dofs lie (checked to lie in the table) and its length, where
/// its y starts (checked to lie in `y`), Wᵣᵣ and b_posᵣ, its μᵣ through the
/// sweeps (written back by row index at the pass's end), its index, and
/// whether it is a loop row (bilateral: μ free).
#[derive(Clone, Copy, Debug)]
pub(super) struct PosRow {
    at: At,
    pl: usize,
    y0: usize,
    wrr: f64,
    b: f64,
    mu: f64,
    r: usize,
    bilateral: bool,
}

/// Where a [`PosRow`]'s path lies in w' ([`Path::of`] kept by value): one
/// run of six consecutive dofs from the first, two such runs (a free body's
/// path, two free bodies': the piles' rows), or the table's entries from
/// this start (gathered).
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
        let n = self.n;
        // the rows read-only and μ apart (no reload of the rows' fields after
        // each write of μ)
        let (kinds, w, paths) = (&self.kind[..n], &self.w[..n], &self.path[..n]);
        let (y, bpos) = (&self.y[..], &self.bpos[..n]);
        let view = BlockRows {
            st,
            y,
            paths,
            table,
        };
        // the rows a sweep updates, listed once in sweep order: the contact
        // normals and joint limits and the loop rows (left out below when
        // they are one block) with a diagonal W above 1e-14 and their path
        // and y in range (the rows every sweep skipped are left out of the
        // sweeps); and whether every path lies in `table` within a row's
        // room, which the unchecked reads of dw below rely on
        let mut list = std::mem::take(&mut self.pos_rows);
        list.clear();
        let (mut inside, mut loop_rows) = (true, false);
        'rows: for &(_, s, e) in runs {
            for r in s..e {
                let (ps, pl) = paths[r];
                if ps + pl > table.len() || pl > st {
                    inside = false;
                    break 'rows;
                }
                let kind = kinds[r];
                let bilateral = kind == RowKind::Bilateral;
                if !bilateral && !matches!(kind, RowKind::Normal | RowKind::Unilateral) {
                    continue;
                }
                if !(w[r] > 1e-14) {
                    continue;
                }
                // (a loop row LoopBlock::prepare collects)
                loop_rows |= bilateral;
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
                    at,
                    pl,
                    y0: r * st,
                    wrr: w[r],
                    b: bpos[r],
                    mu: 0.0,
                    r,
                    bilateral,
                });
            }
        }
        // the loop rows as one exact block after each sweep (loop_block.rs):
        // J_b w = b_pos,b to rounding at the pass's end (without loop rows
        // none: what prepare would find)
        let loops = &mut self.sm.loops;
        let block = match loop_rows || !inside {
            true => loops.prepare(&view, runs, kinds, w),
            false => loops.clear(),
        };
        // SAFETY (unchecked reads of dw below): every path lies in `table`
        // (checked above) and holds dof indices < nv (the factor's table and
        // its unions, as the velocity sweeps rely on, pgs.rs)
        if !inside {
            self.pos_rows = list;
            return 0;
        }
        debug_assert!(table.iter().all(|&k| k < nv), "a dof path beyond nv");
        if block {
            list.retain(|p| !p.bilateral);
        }
        // the warm start: μ of the unilateral rows from the last pass (by
        // contact slot and joint limit), w' = Σ μᵣ yᵣ; from there the same
        // sweeps to the same complementarity conditions
        if let Some(warm) = warm {
            for row in list.iter_mut() {
                let PosRow {
                    at,
                    pl,
                    y0,
                    r,
                    bilateral,
                    ..
                } = *row;
                let m = warm.get(r).copied().unwrap_or(0.0);
                if bilateral || !(m > 0.0) {
                    continue;
                }
                row.mu = m;
                // w' += μᵣ yᵣ
                // SAFETY: as in the sweeps below (checked when listed)
                unsafe {
                    let yr = y.get_unchecked(y0..y0 + pl);
                    on_path!(at, pl, yr, table; yr, p, n => add(m, yr, p, n, dw))
                };
            }
        }
        let mu = &mut self.mu[..n];
        let free = !block && list.iter().any(|p| p.bilateral);
        let mut it = 0;
        while it < max_iter {
            it += 1;
            // SAFETY: each row's path and y were checked to lie in `table`
            // and `y` when listed (neither changes in the pass); the paths'
            // dofs are < nv = dw.len() (the factor's table and its unions)
            let mut change = unsafe {
                match free {
                    true => sweep::<true>(&mut list, y, table, dw),
                    false => sweep::<false>(&mut list, y, table, dw),
                }
            };
            if block {
                // (the block's rows are not listed: their μ is `mu`'s)
                let moved = loops.solve(&view, None, bpos, mu, dw);
                change = change.max(moved);
            }
            if change <= tol {
                break;
            }
        }
        for p in &list {
            mu[p.r] = p.mu;
        }
        self.pos_rows = list;
        it
    }
}

/// One sweep of the position pass over `list` (in order): each row's
/// [`project`] with its μ kept in its entry; returns the largest |Δμᵣ| Wᵣᵣ
/// of the rows that moved (0 if none; as `change.max(x)` over them, a NaN
/// never taken). `BILATERAL`: some row is a loop row (else every μ is
/// clamped at 0 without the test).
///
/// # Safety
/// Each row's y (`y0..y0 + pl`) lies in `y` and its path in `table` (an
/// `At::Table` path at `ps..ps + pl`); every dof of a path is < `dw.len()`.
#[inline(always)]
unsafe fn sweep<const BILATERAL: bool>(
    list: &mut [PosRow],
    y: &[f64],
    table: &[usize],
    dw: &mut [f64],
) -> f64 {
    let mut change: f64 = 0.0;
    for row in list.iter_mut() {
        let PosRow {
            at,
            pl,
            y0,
            wrr,
            b,
            bilateral,
            ..
        } = *row;
        let bilateral = BILATERAL && bilateral;
        let mur = &mut row.mu;
        // SAFETY: the caller's
        let d = unsafe {
            let yr = y.get_unchecked(y0..y0 + pl);
            on_path!(at, pl, yr, table; yr, p, n => project(yr, p, n, dw, mur, b, wrr, bilateral))
        };
        // (|d Wᵣᵣ| > change is false for d = 0 and for a NaN)
        let x = (d * wrr).abs();
        if x > change {
            change = x;
        }
    }
    change
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
    // SAFETY: the caller's
    let u = unsafe { dot_from(-0.0, yr, p, n, x) };
    let old = *mu;
    let z = old - (u - b) / wrr;
    let new = if bilateral { z } else { z.max(0.0) };
    let d = new - old;
    if d != 0.0 {
        *mu = new;
        // SAFETY: the caller's
        unsafe { add(d, yr, p, n, x) };
    }
    d
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
        // the contacts' rows (3c, 3c + 1, 3c + 2 of contact c < n / 3) in one
        // pass, each (μ of its normal, 0, 0), then the other rows 0: no fill
        // of zeros written over
        let (start, decay) = (&mut self.start, self.decay);
        start.clear();
        start.reserve(n);
        for &pi in row_point.iter().take(n.div_ceil(3)) {
            let mu = match points.get(pi) {
                Some(pt) if !pt.fresh => decay * warm_contact.get(pt.slot).map_or(0.0, |w| w[3]),
                _ => 0.0,
            };
            start.extend_from_slice(&[mu, 0.0, 0.0]);
        }
        start.resize(n, 0.0);
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
