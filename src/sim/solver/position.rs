//! The position pass (split impulse) on the solve's rows.

use super::loop_block::BlockRows;
use super::{MassFactor, PosRow, RowKind, Rows};

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
        self.solve_position_runs(&all, None, dw, max_iter, tol)
    }

    /// [`Rows::solve_position`] on the rows of `runs` only (an island's,
    /// [`Rows::solve_runs`]), whose w' lives on `dofs` (`None`: every dof):
    /// only those entries of `dw` are zeroed and written.
    pub(crate) fn solve_position_runs(
        &mut self,
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dw: &mut [f64],
        max_iter: usize,
        tol: f64,
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
        let it = self.position_sweeps(&table_v, runs, dofs, dw, max_iter, tol);
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
                let u: f64 = yr
                    .iter()
                    .zip(p)
                    .map(|(a, &k)| a * unsafe { *dw.get_unchecked(k) })
                    .sum();
                let old = mu[r];
                let x = old - (u - bpos[r]) / wrr;
                let new = if bilateral { x } else { x.max(0.0) };
                let d = new - old;
                if d != 0.0 {
                    mu[r] = new;
                    // w' += Δμ yᵣ
                    for (a, &k) in yr.iter().zip(p) {
                        unsafe { *dw.get_unchecked_mut(k) += d * a };
                    }
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
