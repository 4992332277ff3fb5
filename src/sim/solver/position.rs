//! The position pass (split impulse) on the solve's rows.

use super::loop_block::BlockRows;
use super::{MassFactor, PosRow, RowKind, Rows};
use crate::contact::ContactPoint;

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
                list.push(PosRow {
                    r,
                    ps,
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
                ps,
                pl,
                bilateral,
            } in &list
            {
                let m = warm.get(r).copied().unwrap_or(0.0);
                if bilateral || !(m > 0.0) {
                    continue;
                }
                mu[r] = m;
                // SAFETY: as in the sweeps below (checked when listed)
                let (p, yr) = unsafe {
                    (
                        table.get_unchecked(ps..ps + pl),
                        y.get_unchecked(r * st..r * st + pl),
                    )
                };
                for (a, &k) in yr.iter().zip(p) {
                    unsafe { *dw.get_unchecked_mut(k) += m * a };
                }
            }
        }
        let loops = &mut self.sm.loops;
        let mut it = 0;
        while it < max_iter {
            it += 1;
            let mut change: f64 = 0.0;
            for &PosRow {
                r,
                ps,
                pl,
                bilateral,
            } in &list
            {
                let wrr = w[r];
                // SAFETY: the row's path and y were checked to lie in
                // `table` and `y` when listed (neither changes in the pass)
                let (p, yr) = unsafe {
                    (
                        table.get_unchecked(ps..ps + pl),
                        y.get_unchecked(r * st..r * st + pl),
                    )
                };
                // uᵣ = yᵣ·w' over the row's path
                // SAFETY: the path's dofs are < nv = dw.len() (the factor's
                // table and its unions, as above)
                let u = unsafe { path_dot(yr, p, dw) };
                let old = mu[r];
                let x = old - (u - bpos[r]) / wrr;
                let new = if bilateral { x } else { x.max(0.0) };
                let d = new - old;
                if d != 0.0 {
                    mu[r] = new;
                    // w' += Δμ yᵣ
                    // SAFETY: as for `path_dot`
                    unsafe { path_add(yr, p, d, dw) };
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

/// yᵣ·x over a row's path `p` (its y `yr`, as long), in the path's order
/// as `Iterator::sum` adds (from −0, term after term): unrolled for the
/// paths of one and two free bodies (6 and 12 dofs), the pass's rows on the
/// piles, the same additions in the same order (bit for bit the loop's).
///
/// # Safety
/// Every entry of `p` is < `x.len()`.
#[inline(always)]
unsafe fn path_dot(yr: &[f64], p: &[usize], x: &[f64]) -> f64 {
    #[inline(always)]
    unsafe fn fixed<const N: usize>(yr: &[f64; N], p: &[usize; N], x: &[f64]) -> f64 {
        let mut u = -0.0;
        for j in 0..N {
            // SAFETY: the caller's
            u += yr[j] * unsafe { *x.get_unchecked(p[j]) };
        }
        u
    }
    // SAFETY (the three): the caller's
    if let (Ok(y), Ok(q)) = (<&[f64; 12]>::try_from(yr), <&[usize; 12]>::try_from(p)) {
        return unsafe { fixed(y, q, x) };
    }
    if let (Ok(y), Ok(q)) = (<&[f64; 6]>::try_from(yr), <&[usize; 6]>::try_from(p)) {
        return unsafe { fixed(y, q, x) };
    }
    yr.iter()
        .zip(p)
        // SAFETY: the caller's
        .map(|(a, &k)| a * unsafe { *x.get_unchecked(k) })
        .sum()
}

/// x += d yᵣ over a row's path `p` ([`path_dot`]'s unrolling).
///
/// # Safety
/// Every entry of `p` is < `x.len()`.
#[inline(always)]
unsafe fn path_add(yr: &[f64], p: &[usize], d: f64, x: &mut [f64]) {
    #[inline(always)]
    unsafe fn fixed<const N: usize>(yr: &[f64; N], p: &[usize; N], d: f64, x: &mut [f64]) {
        for j in 0..N {
            // SAFETY: the caller's
            unsafe { *x.get_unchecked_mut(p[j]) += d * yr[j] };
        }
    }
    // SAFETY (the three): the caller's
    if let (Ok(y), Ok(q)) = (<&[f64; 12]>::try_from(yr), <&[usize; 12]>::try_from(p)) {
        return unsafe { fixed(y, q, d, x) };
    }
    if let (Ok(y), Ok(q)) = (<&[f64; 6]>::try_from(yr), <&[usize; 6]>::try_from(p)) {
        return unsafe { fixed(y, q, d, x) };
    }
    for (a, &k) in yr.iter().zip(p) {
        // SAFETY: the caller's
        unsafe { *x.get_unchecked_mut(k) += d * a };
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
