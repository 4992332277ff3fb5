//! The self-stress of a sticking stance shed: the part of the impulses
//! that moves nothing, chosen least-norm
//! (docs/theory.md §"Self-stress of a sticking stance").

use super::dense::{ldlt_dropping, ldlt_dropping_solve};
use super::subspace::{Subspace, DEPENDENT};
use super::wff::OwnBlocks;
use super::{RowKind, Rows, SUBSPACE_MAX};

impl Rows {
    /// Whether this step's solve of the island on `dofs` (`None`: every dof)
    /// sheds its self-stress: every [`super::SHED_EVERY`]-th step, on an
    /// island with a dof of a joint other than a free one.
    pub(super) fn sheds(&self, dofs: Option<&[usize]>) -> bool {
        self.shed_now
            && match dofs {
                Some(d) => d.iter().any(|&k| self.jointed.get(k) == Some(&true)),
                None => self.any_jointed,
            }
    }

    /// Sheds the self-stress of a solved island (rows `runs`, impulses
    /// `lambda`, Δv' = Yᵀλ in `dv`): F, the rows strictly inside their sets
    /// (positive normals and limits, sticking tangent pairs of a sticking
    /// contact, joint friction below its bound), at most [`SUBSPACE_MAX`]; the
    /// null vectors of W_FF (each row its LDLᵀ drops as dependent on earlier
    /// ones: n = L⁻ᵀ eⱼ, W_FF n = 0); λ_F ← λ_F + α N z with z minimising
    /// Σ Wᵣᵣ (λᵣ + (N z)ᵣ)² (the least-norm impulses in the metric of W's
    /// diagonal, those MuJoCo's regularised solve tends to), α ≤ 1 halved
    /// until every row stays in its set and every sticking pair strictly
    /// inside its cone. A null step changes no row's velocity; rows only
    /// nearly dependent (within the drop bound) make it move some: α is
    /// scaled so that no row of the island moves by more than `tol`/1000.
    /// Δv' follows the step exactly. Returns whether a step was taken.
    pub(super) fn shed_self_stress(
        &self,
        sm: &mut Subspace,
        runs: &[(usize, usize, usize)],
        lambda: &mut [f64],
        dv: &mut [f64],
        tol: f64,
    ) -> bool {
        let (n, st, nv) = (self.n, self.stride, self.nv);
        let table = &self.table[..];
        if lambda.len() < n || dv.len() < nv || sm.x.len() < nv {
            return false;
        }
        let path = |r: usize| {
            let (s, l) = self.path[r];
            table.get(s..s + l).unwrap_or(&[])
        };
        let live = |r: usize| self.winv[r] != 0.0;
        let inside = |t1: f64, t2: f64, ln: f64, mu: f64| {
            (t1 * t1 + t2 * t2).sqrt() < mu * ln * (1.0 - 1e-9)
        };
        // F
        sm.rows.clear();
        for &(_, s, e) in runs {
            let mut r = s;
            while r < e.min(n) {
                if sm.rows.len() > SUBSPACE_MAX {
                    return false;
                }
                if self.is_block[r] && r + 2 < n {
                    let mu = match self.kind[r + 1] {
                        RowKind::Tangent { mu, .. } => mu,
                        _ => 0.0,
                    };
                    let all_live = live(r) && live(r + 1) && live(r + 2);
                    if lambda[r] > 0.0
                        && all_live
                        && inside(lambda[r + 1], lambda[r + 2], lambda[r], mu)
                    {
                        sm.rows.extend_from_slice(&[r, r + 1, r + 2]);
                    }
                    r += 3;
                    continue;
                }
                match self.kind[r] {
                    RowKind::Tangent { normal, mu } if r + 1 < e => {
                        let ln = lambda.get(normal).copied().unwrap_or(0.0);
                        if ln > 0.0 && live(r) && inside(lambda[r], lambda[r + 1], ln, mu) {
                            sm.rows.push(r);
                            if live(r + 1) {
                                sm.rows.push(r + 1);
                            }
                        }
                        r += 2;
                        continue;
                    }
                    RowKind::Normal => {
                        // a contact formed row by row: its normal only with
                        // its pair sticking (a sliding pair follows μλₙ)
                        let sticking = match self.kind.get(r + 1) {
                            Some(&RowKind::Tangent { normal, mu }) if normal == r && r + 2 < n => {
                                inside(lambda[r + 1], lambda[r + 2], lambda[r], mu)
                            }
                            _ => true,
                        };
                        if lambda[r] > 0.0 && live(r) && sticking {
                            sm.rows.push(r);
                        }
                    }
                    RowKind::Unilateral => {
                        if lambda[r] > 0.0 && live(r) {
                            sm.rows.push(r);
                        }
                    }
                    RowKind::Box { limit } => {
                        if lambda[r].abs() < limit * (1.0 - 1e-9) && live(r) {
                            sm.rows.push(r);
                        }
                    }
                    // loop rows: their block keeps them exact (loop_block.rs)
                    RowKind::Bilateral => return false,
                    RowKind::Tangent2 | RowKind::Tangent { .. } => {}
                }
                r += 1;
            }
        }
        let m = sm.rows.len();
        let ld = sm.ld;
        if m < 2 || m > SUBSPACE_MAX || m > ld || sm.null.len() < m * m {
            return false;
        }
        // W_FF's lower triangle (as the subspace step forms it)
        sm.forget();
        let own_blocks = OwnBlocks {
            contact: &self.is_block,
            diag: (&self.w, &self.w_block),
        };
        sm.group(&self.path);
        if !sm.form_w_ff::<false>(
            &self.y, st, &self.path, table, own_blocks, self.nv, 0, false,
        ) {
            return false;
        }
        ldlt_dropping(&mut sm.w, ld, m, 0, DEPENDENT);
        // null vectors n = L⁻ᵀ eⱼ of the dropped rows j (L unit lower, a
        // dropped row's column below zero: n lives on j and the kept rows
        // before it)
        let mut d = 0;
        for j in 0..m {
            if sm.w[j * ld + j] != 0.0 {
                continue;
            }
            let col = &mut sm.null[d * m..(d + 1) * m];
            col.fill(0.0);
            col[j] = 1.0;
            for i in (0..j).rev() {
                let mut s = 0.0;
                for k in i + 1..=j {
                    s -= sm.w[k * ld + i] * col[k];
                }
                col[i] = s;
            }
            d += 1;
        }
        if d == 0 || sm.gram.len() < d * d {
            return false;
        }
        // G z = −g: G = Nᵀ D N, g = Nᵀ D λ_F, D = W's diagonal on F
        for a in 0..d {
            let na = &sm.null[a * m..(a + 1) * m];
            let mut g = 0.0;
            for (i, &r) in sm.rows.iter().enumerate() {
                g += self.w[r] * na[i] * lambda[r];
            }
            sm.lam[a] = -g;
            for b in 0..=a {
                let nb = &sm.null[b * m..(b + 1) * m];
                let mut s = 0.0;
                for (i, &r) in sm.rows.iter().enumerate() {
                    s += self.w[r] * na[i] * nb[i];
                }
                sm.gram[a * d + b] = s;
            }
        }
        ldlt_dropping(&mut sm.gram[..d * d], d, d, 0, 1e-12);
        ldlt_dropping_solve(&sm.gram[..d * d], d, d, &mut sm.lam[..d]);
        // the step N z (into rhs), the old impulses kept in x's first m
        // entries would clash with its use as a dof scratch: kept in `w`
        // (W_FF's factor is done with)
        for i in 0..m {
            let mut s = 0.0;
            for a in 0..d {
                s += sm.null[a * m + i] * sm.lam[a];
            }
            sm.rhs[i] = s;
            sm.w[i] = lambda[sm.rows[i]];
        }
        if sm.rhs[..m].iter().any(|x| !x.is_finite()) {
            return false;
        }
        // what the step does to the island's velocities: nothing for exactly
        // dependent rows, a little for nearly dependent ones; held to a
        // thousandth of the solve's tolerance (α scaled down to that)
        for (i, &r) in sm.rows.iter().enumerate() {
            for (t, &k) in path(r).iter().enumerate() {
                sm.x[k] += sm.rhs[i] * self.y[r * st + t];
            }
        }
        let mut moved: f64 = 0.0;
        for &(_, s, e) in runs {
            for r in s..e.min(n) {
                let mut u = 0.0;
                for (t, &k) in path(r).iter().enumerate() {
                    u += self.y[r * st + t] * sm.x[k];
                }
                moved = moved.max(u.abs());
            }
        }
        for &r in &sm.rows {
            for &k in path(r) {
                sm.x[k] = 0.0;
            }
        }
        let bound = 1e-3 * tol;
        let mut alpha = if moved > bound { bound / moved } else { 1.0 };
        if !(alpha > 0.0) {
            return false;
        }
        let mut ok = false;
        for _ in 0..8 {
            for (i, &r) in sm.rows.iter().enumerate() {
                lambda[r] = sm.w[i] + alpha * sm.rhs[i];
            }
            if self.in_sets(runs, lambda, &sm.rows) {
                ok = true;
                break;
            }
            alpha *= 0.5;
        }
        for (i, &r) in sm.rows.iter().enumerate() {
            if !ok {
                lambda[r] = sm.w[i];
                continue;
            }
            let dl = lambda[r] - sm.w[i];
            if dl != 0.0 {
                for (t, &k) in path(r).iter().enumerate() {
                    dv[k] += dl * self.y[r * st + t];
                }
            }
        }
        ok
    }

    /// Every row of `runs` in its set: normals and limits ≥ 0, joint
    /// friction in its box, each tangent pair in its cone, strictly when its
    /// first row is in `free` (it stays sticking).
    fn in_sets(&self, runs: &[(usize, usize, usize)], lambda: &[f64], free: &[usize]) -> bool {
        for &(_, s, e) in runs {
            for r in s..e.min(self.n) {
                let ok = match self.kind[r] {
                    RowKind::Normal | RowKind::Unilateral => lambda[r] >= 0.0,
                    RowKind::Box { limit } => lambda[r].abs() <= limit,
                    RowKind::Tangent { normal, mu } if r + 1 < e => {
                        let ln = lambda.get(normal).copied().unwrap_or(0.0).max(0.0);
                        let t = lambda[r].hypot(lambda[r + 1]);
                        let shrink = if free.contains(&r) {
                            1.0 - 1e-9
                        } else {
                            1.0 + 1e-9
                        };
                        t <= mu * ln * shrink
                    }
                    _ => true,
                };
                if !ok {
                    return false;
                }
            }
        }
        true
    }
}
