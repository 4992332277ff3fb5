//! The subspace-minimisation step of projected Gauss–Seidel (PGS-SM): the
//! free rows solved exactly by a dense LDLᵀ.

use super::dense::{ldlt_dropping, ldlt_dropping_solve};
use super::dot3::dot3_from;
use super::loop_block::LoopBlock;
use super::wff::OwnBlocks;
use super::{RowKind, SUBSPACE_MAX};
use runs::by_runs;

pub(super) mod runs;

/// Preallocated scratch of [`subspace_step`]: the free rows, their dense
/// Delassus block and right-hand side, their Y rows scattered to full width.
#[derive(Clone, Debug)]
pub(super) struct Subspace {
    pub(super) rows: Vec<usize>,
    /// At a free row: a contact's three rows start there ([`Subspace::group`];
    /// the others false).
    pub(super) three: Vec<bool>,
    /// W_FF (lower triangle) or its factor, row a at `w[a * ld..]`: the
    /// stride fixed (the most rows a step takes), so that a factor's leading
    /// rows stay in place when rows are appended.
    pub(super) w: Vec<f64>,
    pub(super) ld: usize,
    pub(super) rhs: Vec<f64>,
    pub(super) lam: Vec<f64>,
    /// A row scattered to full width (nv entries, zero between uses).
    pub(super) x: Vec<f64>,
    /// A contact's three rows scattered side by side (nv entries, zero
    /// between uses).
    pub(super) x3: Vec<[f64; 3]>,
    /// At a tangent pair's first row: it lay on its cone's boundary (sliding).
    pub(super) sliding: Vec<bool>,
    /// The loop rows' exact block ([`LoopBlock`]).
    pub(super) loops: LoopBlock,
    /// W_FF's null vectors, one a column of `rows.len()` entries
    /// (stress.rs).
    pub(super) null: Vec<f64>,
    /// Their Gram matrix in the W-diagonal metric (stress.rs).
    pub(super) gram: Vec<f64>,
    /// `w` holds the LDLᵀ of W_FF over `factored_rows`, made in this solve
    /// of an island's rows (cleared when one starts, [`Subspace::forget`]),
    /// and `wf` that W_FF itself (lower triangle, row a at `wf[a * ld..]`).
    pub(super) factored: bool,
    pub(super) factored_rows: Vec<usize>,
    pub(super) wf: Vec<f64>,
    /// The W_FF before it, while a try forms its own ([`Subspace::keep_old`]).
    pub(super) wold: Vec<f64>,
    /// At a free row: its place in `factored_rows` (`usize::MAX`: not there).
    pub(super) old: Vec<usize>,
    /// Each row: the sweeps' `drift` up to which it is pinned at its bound
    /// (pgs.rs, `pinned_until`).
    pub(super) until: Vec<f64>,
}

impl Subspace {
    pub(super) fn new(nv: usize, cap: usize) -> Self {
        let m = cap.min(SUBSPACE_MAX);
        Self {
            rows: Vec::with_capacity(m),
            three: Vec::with_capacity(m),
            w: vec![0.0; m * m],
            ld: m,
            rhs: vec![0.0; m],
            lam: vec![0.0; m],
            x: vec![0.0; nv],
            x3: vec![[0.0; 3]; nv],
            sliding: vec![false; cap],
            loops: LoopBlock::new(cap),
            null: vec![0.0; m * m],
            gram: vec![0.0; m * m],
            factored: false,
            factored_rows: Vec::with_capacity(m),
            wf: vec![0.0; m * m],
            wold: vec![0.0; m * m],
            old: Vec::with_capacity(m),
            until: vec![f64::NEG_INFINITY; cap],
        }
    }

    /// Forgets the factor kept in `w` (a new solve, or `w` overwritten).
    #[inline]
    pub(super) fn forget(&mut self) {
        self.factored = false;
    }
}

/// A pivot of W_FF's LDLᵀ below this fraction of its diagonal is a row
/// dependent on earlier ones, dropped from the step: the pivot kept is the
/// squared sine of the angle (in the W metric) between the row and the span
/// of the rows before it. An exactly dependent row's pivot is its rounding,
/// which reached 7e-9 of the diagonal on Gymnasium's ant standing on four
/// feet with its ankles on their limits (16 rows on 14 dofs, the hips'
/// armature 1 against light legs): kept (the bound was 1e-10), it turned the
/// step's residual into impulses of 1e7 N·s (docs/theory.md §"Constraint
/// solve").
pub(super) const DEPENDENT: f64 = 1e-6;

/// The read-only view of the rows a subspace step needs.
pub(super) struct Solved<'a> {
    pub(super) n: usize,
    /// The island's row runs (key, start, end).
    pub(super) runs: &'a [(usize, usize, usize)],
    pub(super) nv: usize,
    /// Room of a row in `y`.
    pub(super) st: usize,
    pub(super) y: &'a [f64],
    pub(super) paths: &'a [(usize, usize)],
    pub(super) table: &'a [usize],
    pub(super) kinds: &'a [RowKind],
    pub(super) contact: &'a [bool],
    /// 1 / Wᵣᵣ (0: a row no impulse can move).
    pub(super) winv: &'a [f64],
    pub(super) c: &'a [f64],
    pub(super) b: &'a [f64],
    /// W's diagonal and contact blocks (`Rows::w`, `Rows::w_block`: Y Yᵀ's,
    /// not the loop block's reduced ones), [`OwnBlocks::diag`].
    pub(super) diag: (&'a [f64], &'a [[f64; 3]]),
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
pub(super) fn subspace_step(
    sm: &mut Subspace,
    rows: &Solved,
    lambda: &mut [f64],
    dv: &mut [f64],
) -> bool {
    let Solved {
        n,
        runs,
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
        diag,
    } = *rows;
    let path = |r: usize| {
        let (s, l) = paths[r];
        &table[s..s + l]
    };
    let inside =
        |t1: f64, t2: f64, ln: f64, mu: f64| (t1 * t1 + t2 * t2).sqrt() < mu * ln * (1.0 - 1e-9);
    // a contact that is not free (its normal not taken) and whose tangent
    // impulses are both 0 (either sign): the walk's projection leaves it as
    // it is (its norm 0, its scale 0 or 1, each impulse t·s the same bits,
    // each change +0, no Δv' update) and passes it by
    #[inline(always)]
    fn passed(lambda: &[f64], normal: bool, r: usize, e: usize) -> bool {
        !normal && r + 3 <= e && lambda[r + 1] == 0.0 && lambda[r + 2] == 0.0
    }
    // F: the free rows (`free`, and `sliding` as a slice: no reload of
    // either after the other's writes)
    let (free, sliding) = (&mut sm.rows, &mut sm.sliding[..]);
    free.clear();
    for &(_, s, e) in runs {
        let mut r = s;
        while r < e {
            let live = |q: usize| winv[q] != 0.0;
            if contact[r] {
                // (its three rows' λ and 1 / W, each read once: lambda[r + 2]
                // is read on every path through here)
                let (l, wi) = (&lambda[r..r + 3], &winv[r..r + 3]);
                let mu = match kinds[r + 1] {
                    RowKind::Tangent { mu, .. } => mu,
                    _ => 0.0,
                };
                let normal = l[0] > 0.0 && wi[0] != 0.0;
                let slides = &mut sliding[r + 1];
                // (not needed where the walk below passes the contact by)
                if !passed(lambda, normal, r, e) {
                    *slides = !inside(l[1], l[2], l[0], mu);
                }
                if normal {
                    free.push(r);
                    if !*slides && wi[1] != 0.0 && wi[2] != 0.0 {
                        free.push(r + 1);
                        free.push(r + 2);
                    }
                    if free.len() > SUBSPACE_MAX {
                        return false;
                    }
                }
                r += 3;
                continue;
            }
            match kinds[r] {
                RowKind::Tangent { normal, mu } if r + 1 < e => {
                    let ln = lambda.get(normal).copied().unwrap_or(0.0);
                    sliding[r] = !inside(lambda[r], lambda[r + 1], ln, mu);
                    if ln > 0.0 && !sliding[r] && live(r) {
                        free.push(r);
                        // a one-row cone (torsion: its partner row is empty,
                        // sim/constraints/spin.rs) is free on its own row
                        if live(r + 1) {
                            free.push(r + 1);
                        }
                    }
                    r += 2;
                    continue;
                }
                RowKind::Tangent2 | RowKind::Tangent { .. } => {}
                RowKind::Normal | RowKind::Unilateral => {
                    if lambda[r] > 0.0 && live(r) {
                        free.push(r);
                    }
                }
                RowKind::Box { limit } => {
                    if lambda[r].abs() < limit * (1.0 - 1e-9) && live(r) {
                        free.push(r);
                    }
                }
                RowKind::Bilateral => {
                    if live(r) {
                        free.push(r);
                    }
                }
            }
            r += 1;
            if free.len() > SUBSPACE_MAX {
                return false;
            }
        }
    }
    let m = sm.rows.len();
    if m == 0 || m > SUBSPACE_MAX {
        return false;
    }
    // the residuals b − u, then the lower triangle of W_FF = Y_F Y_Fᵀ
    if sm.x.len() < nv || dv.len() < nv {
        return false;
    }
    let target = |r: usize| match kinds[r] {
        RowKind::Tangent { .. } | RowKind::Tangent2 => 0.0,
        _ => b[r],
    };
    let own_blocks = OwnBlocks { contact, diag };
    // a try on the free rows of this solve's last factor: their groups are
    // the ones `three` holds from that try
    let again = sm.factored && sm.factored_rows == sm.rows;
    if !again {
        sm.group(paths);
    }
    let mut a = 0;
    while a < m {
        let r = sm.rows[a];
        let pa = path(r);
        let yr = |i: usize| &y[(r + i) * st..(r + i) * st + pa.len()];
        if sm.three[a] {
            // a contact's three rows in one pass, each sum in its order
            let (s0, ys) = ([c[r], c[r + 1], c[r + 2]], [yr(0), yr(1), yr(2)]);
            // SAFETY: a path's dofs are < nv ≤ dv.len() (checked above)
            let [u0, u1, u2] = unsafe { dot3_from(s0, ys, pa, dv) };
            sm.rhs[a] = target(r) - u0;
            sm.rhs[a + 1] = target(r + 1) - u1;
            sm.rhs[a + 2] = target(r + 2) - u2;
            a += 3;
            continue;
        }
        // SAFETY: a path's dofs are < nv ≤ dv.len() (checked above)
        let (y0, s0) = (yr(0), c[r]);
        let u = by_runs!(pa; y0; q, l => unsafe { runs::dot_from(s0, y0, q, l, dv) });
        sm.rhs[a] = target(r) - u;
        a += 1;
    }
    // W_FF = L D Lᵀ; a pivot that lost all but `DEPENDENT` of its diagonal
    // is a row dependent on earlier ones (redundant contacts): dropped (δ = 0).
    // The rows' y are fixed within a solve: a step whose free rows begin
    // with those of this solve's last factor keeps the factor's rows there
    // (a leading block's factor, the same bits, dense.rs)
    // and forms and factors the rows after them only (all of them on the same
    // free rows), their entries with rows of that W_FF copied from it
    let kept = if again {
        m
    } else if sm.factored {
        let same = sm
            .factored_rows
            .iter()
            .zip(&sm.rows)
            .take_while(|(p, q)| p == q);
        sm.group_start(same.count())
    } else {
        0
    };
    if kept < m {
        if sm.factored {
            sm.map_old();
            sm.keep_old(kept);
        }
        if !sm.form_w_ff::<true>(y, st, paths, table, own_blocks, nv, kept, sm.factored) {
            sm.forget();
            return false;
        }
        ldlt_dropping(&mut sm.w, sm.ld, m, kept, DEPENDENT);
    }
    if !again {
        sm.factored_rows.clone_from(&sm.rows);
    }
    sm.factored = true;
    ldlt_dropping_solve(&sm.w, sm.ld, m, &mut sm.rhs[..m]);
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
    // Δv' += d yᵣ over row r's path (`yr` as long as `p`)
    //
    // # Safety
    // Every dof of `p` is < `dv.len()`.
    #[inline(always)]
    unsafe fn add(p: &[usize], yr: &[f64], d: f64, dv: &mut [f64]) {
        if d != 0.0 {
            // SAFETY: the caller's
            by_runs!(p; yr; q, n => unsafe { runs::add(d, yr, q, n, dv) });
        }
    }
    let yrow = |r: usize, l: usize| &y[r * st..r * st + l];
    for (a, &r) in sm.rows.iter().enumerate() {
        let x = match kinds[r] {
            RowKind::Normal | RowKind::Unilateral => sm.lam[a].max(0.0),
            RowKind::Box { limit } => sm.lam[a].clamp(-limit, limit),
            RowKind::Bilateral => sm.lam[a],
            _ => continue,
        };
        let d = x - lambda[r];
        lambda[r] = x;
        let p = path(r);
        // SAFETY: a path's dofs are < nv ≤ dv.len() (checked above; the
        // sweeps' check of the paths)
        unsafe { add(p, yrow(r, p.len()), d, dv) };
    }
    // the free rows are a subsequence of this walk's rows (the scan above
    // took them in this order, each once): a cursor finds a row's place
    let mut next = 0;
    let mut at = |r: usize| {
        let here = sm.rows.get(next) == Some(&r);
        next += usize::from(here);
        here.then(|| next - 1)
    };
    'walk: for &(_, s, e) in runs {
        let mut r = s;
        while r < e {
            if r + 1 >= n {
                break 'walk;
            }
            // the pair's first row q (its place among the free rows) and the
            // rows this step takes: a contact's three (Normal, then its
            // tangent pair on one path, `Rows::is_block`) at once, with the
            // row-by-row walk's cursor; one not free whose tangents are 0
            // passed by
            let (q, free, step) = if contact[r] && r + 3 <= e {
                debug_assert!(
                    matches!(kinds[r + 1], RowKind::Tangent { normal, .. } if normal == r)
                );
                if at(r).is_none() && passed(lambda, false, r, e) {
                    (None, None, 3)
                } else {
                    let free = at(r + 1);
                    at(r + 2);
                    (Some(r + 1), free, 3)
                }
            } else {
                (Some(r), at(r), 1)
            };
            if let Some(r) = q
                && let RowKind::Tangent { normal, mu } = kinds[r]
            {
                let lim = mu * lambda.get(normal).copied().unwrap_or(0.0).max(0.0);
                let (t1, t2) = match free {
                    Some(a) if winv[r + 1] == 0.0 => (sm.lam[a], 0.0),
                    Some(a) if a + 1 < m => (sm.lam[a], sm.lam[a + 1]),
                    _ => (lambda[r], lambda[r + 1]),
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
                let p = path(r);
                if d1 != 0.0 && d2 != 0.0 && paths[r + 1] == paths[r] {
                    // the pair on one path (a contact's) in one pass: each entry
                    // (x + d₁y₁) + d₂y₂, the row-by-row order
                    let (y0, y1) = (yrow(r, p.len()), yrow(r + 1, p.len()));
                    // SAFETY: a path's dofs are < nv ≤ dv.len() (as above)
                    by_runs!(p; y0, y1; q, l => unsafe { runs::add2([d1, d2], y0, y1, q, l, dv) });
                } else {
                    let p2 = path(r + 1);
                    // SAFETY: as above
                    unsafe {
                        add(p, yrow(r, p.len()), d1, dv);
                        add(p2, yrow(r + 1, p2.len()), d2, dv);
                    }
                }
            }
            // (a contact's last row the last row: the row-by-row walk
            // stopped there)
            if step == 3 && r + 3 >= n {
                break 'walk;
            }
            r += step;
        }
    }
    true
}
