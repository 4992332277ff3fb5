//! λ = K⁻¹ r for a K with a block-diagonal part and a low-rank shared part
//! (docs/theory.md §"Constrained dynamics", "K from its blocks"): when the
//! rows split into disjoint groups (a foot's 3 rows, a sole's 6) that only the
//! coordinates of their own branch reach, besides a few coordinates shared by
//! all rows (a free base's six), the elimination gives
//!
//! ```text
//! K = A + Bᵀ D_B⁻¹ B,   A block-diagonal,   B = the shared rows of W = L⁻ᵀ J_cᵀ,
//! K⁻¹ = A⁻¹ − A⁻¹ Bᵀ S⁻¹ B A⁻¹,   S = D_B + B A⁻¹ Bᵀ   (Woodbury),
//! ```
//!
//! so the dense m × m factor of K and its g rank-1 updates give way to the
//! blocks' small factors and a g × g one (g the shared count). Used when each
//! block is well inside full rank (then so is K); otherwise the caller forms
//! K and takes the least-norm route (`kkt.rs`).

use super::kkt::add_rank1;
use super::ConstraintData;
use crate::spatial::ops::madd;

/// At most this many shared coordinates (a free base and two more), and rows
/// in a block: the width of the solve's fixed-size rows.
pub(crate) const MAX_SHARED: usize = 8;
const W: usize = MAX_SHARED;
/// A block's Cholesky pivot at most this fraction of its diagonal entry sends
/// the call to the dense route (an ill-conditioned block would cost digits).
const BLOCK_TOL: f64 = 1e-4;

/// From the rows' spans per coordinate (`lo..hi`, empty when lo ≥ hi): the
/// disjoint blocks that tile `0..m` (every span not the whole `0..m` is one of
/// them, of at most [`MAX_SHARED`] rows) into `blocks`, and the number of
/// coordinates spanning all rows. None when the spans have no such structure
/// (fewer than two blocks, spans that overlap without being equal, rows in no
/// block, too many shared).
pub(crate) fn structure(
    span: &[(usize, usize)],
    m: usize,
    blocks: &mut Vec<(usize, usize)>,
) -> Option<usize> {
    blocks.clear();
    let mut shared = 0;
    for &(lo, hi) in span {
        let (lo, hi) = (lo.min(m), hi.min(m));
        if lo >= hi {
            continue;
        }
        if (lo, hi) == (0, m) {
            shared += 1;
            continue;
        }
        if hi - lo > W {
            return None;
        }
        if !blocks.contains(&(lo, hi)) {
            blocks.push((lo, hi));
        }
    }
    if blocks.len() < 2 || shared == 0 || shared > MAX_SHARED {
        return None;
    }
    blocks.sort_unstable();
    // disjoint and covering 0..m
    let mut end = 0;
    for &(lo, hi) in blocks.iter() {
        if lo != end {
            return None;
        }
        end = hi;
    }
    (end == m).then_some(shared)
}

/// Whether `cd`'s rows (their spans over the first `n` coordinates, `cd.span`)
/// have the block structure of [`structure`], into `cd.blocks`; the structure
/// is the constraints' and the model's, found again only when the spans change.
pub(crate) fn blocked(cd: &mut ConstraintData, n: usize) -> bool {
    if cd.blocks_span[..n] != cd.span[..n] {
        cd.blocks_span[..n].copy_from_slice(&cd.span[..n]);
        cd.blocked = structure(&cd.span[..n], cd.rows, &mut cd.blocks).is_some();
    }
    cd.blocked
}

/// With `cd.k` holding A's blocks, the g shared rows and pivots in `cd.brows`,
/// `cd.bd`, `cd.r` = −J_c q̈₀ and `cd.gamma`: `cd.lambda` = K⁻¹ (−γ_c − J_c q̈₀)
/// by [`solve`] (true), else (false) `cd.k`'s upper triangle completed to K
/// (its g rank-1 updates, as the elimination would have added them) for the
/// dense route.
pub(crate) fn solve_or_form(cd: &mut ConstraintData, g: usize) -> bool {
    let m = cd.rows;
    let r2 = cd.r2.as_mut_slice();
    for ((x, &a), &c) in r2.iter_mut().zip(cd.r.as_slice()).zip(cd.gamma.as_slice()) {
        *x = a - c;
    }
    let args = (
        m,
        &cd.k.as_slice()[..m * m],
        &cd.blocks[..],
        &cd.brows[..g * m],
        &cd.bd[..g],
        &*r2,
    );
    if solve(
        args,
        cd.lambda.as_mut_slice(),
        &mut cd.lf,
        &mut cd.ld,
        &mut cd.z,
    ) {
        return true;
    }
    // K = A + Σ D⁻¹ₖ W[k, :]ᵀ W[k, :] over the rows kept aside
    let k = &mut cd.k.as_mut_slice()[..m * m];
    for (row, &d) in cd.brows[..g * m].chunks_exact(m).zip(&cd.bd[..g]) {
        add_rank1(k, m, 0, row, 1.0 / d);
    }
    false
}

/// `lambda = K⁻¹ r` with K = A + Bᵀ D_B⁻¹ B; `args`: m, `a` (m × m, column-major) holding A's
/// blocks (`blocks`, the entries outside them are not read), `brows` the g
/// shared rows of W (row j at `j m`), `bd` their pivots D_B. Scratch: `lf`
/// (m × [`MAX_SHARED`]: row i of a block's unit factor L, A = L D Lᵀ), `ld`
/// (m: D⁻¹), `z` (m × [`MAX_SHARED`]: row i of Z = L⁻¹ Bᵀ). False, with
/// `lambda` unset, when a block's pivot is at most [`BLOCK_TOL`] of its
/// diagonal entry (or not finite).
fn solve(args: Args, lambda: &mut [f64], lf: &mut [f64], ld: &mut [f64], z: &mut [f64]) -> bool {
    // the block size known at compile time when all are 3 (feet) or 6 (soles)
    let blocks = args.2;
    let b0 = blocks[0].1 - blocks[0].0;
    let uniform = blocks.iter().all(|&(lo, hi)| hi - lo == b0);
    match (uniform, b0) {
        (true, 3) => solve_n::<3>(args, lambda, lf, ld, z),
        (true, 6) => solve_n::<6>(args, lambda, lf, ld, z),
        _ => solve_n::<0>(args, lambda, lf, ld, z),
    }
}

/// The operands of [`solve`]: m, A, the blocks, B's rows, D_B, r.
type Args<'a> = (
    usize,
    &'a [f64],
    &'a [(usize, usize)],
    &'a [f64],
    &'a [f64],
    &'a [f64],
);

/// [`solve`] with every block `N` rows (0: the blocks' own sizes).
#[inline(always)]
fn solve_n<const N: usize>(
    (m, a, blocks, brows, bd, r): Args,
    lambda: &mut [f64],
    lf: &mut [f64],
    ld: &mut [f64],
    z: &mut [f64],
) -> bool {
    let g = bd.len();
    let (a, lf, ld, z) = (&a[..m * m], &mut lf[..m * W], &mut ld[..m], &mut z[..m * W]);
    let size = |lo: usize, hi: usize| if N == 0 { (hi - lo).min(W) } else { N };
    for &(lo, hi) in blocks {
        let bs = size(lo, hi);
        // A's block = L D Lᵀ, row by row: L[i, j] D[j] = A[i, j] − Σₚ L[i, p] D[p] L[j, p]
        // (the products L[i, p] D[p] kept in e)
        for t in 0..bs {
            let i = lo + t;
            let (done, rest) = lf.split_at_mut(i * W);
            let li = &mut rest[..W];
            let mut e = [0.0; W];
            for u in 0..t {
                let j = lo + u;
                let lj = &done[j * W..j * W + W];
                let mut x = a[i + j * m];
                for p in 0..u {
                    x = madd(-e[p], lj[p], x);
                }
                e[u] = x;
                li[u] = x * ld[j];
            }
            let mut d = a[i + i * m];
            for p in 0..t {
                d = madd(-e[p], li[p], d);
            }
            if !(d > BLOCK_TOL * a[i + i * m].abs()) || !d.is_finite() {
                return false;
            }
            ld[i] = 1.0 / d;
            // row i of Z = L⁻¹ Bᵀ: Bᵀ[i, :] − Σₚ L[i, p] Z[p, :]
            let (zd, zr) = z.split_at_mut(i * W);
            let mut zi = [0.0; W];
            for c in 0..g {
                zi[c] = brows[c * m + i];
            }
            for p in 0..t {
                let l = li[p];
                let zp = &zd[(lo + p) * W..(lo + p) * W + W];
                for c in 0..W {
                    zi[c] = madd(-l, zp[c], zi[c]);
                }
            }
            zr[..W].copy_from_slice(&zi);
        }
    }
    // S = D_B + Zᵀ D⁻¹ Z (g × g), then S = Lₛ Dₛ Lₛᵀ (rows; Dₛ⁻¹ in sd)
    let mut s = [[0.0; W]; W];
    for c in 0..g {
        s[c][c] = bd[c];
    }
    for (zi, &di) in z.chunks_exact(W).zip(ld.iter()) {
        for c in 0..g {
            let x = zi[c] * di;
            for e in 0..W {
                s[c][e] = madd(x, zi[e], s[c][e]);
            }
        }
    }
    let mut sd = [0.0; W];
    for i in 0..g {
        let mut e = [0.0; W];
        for j in 0..i {
            let mut x = s[i][j];
            for p in 0..j {
                x = madd(-e[p], s[j][p], x);
            }
            e[j] = x;
            s[i][j] = x * sd[j];
        }
        let mut d = s[i][i];
        for p in 0..i {
            d = madd(-e[p], s[i][p], d);
        }
        if !(d > 0.0) || !d.is_finite() {
            return false;
        }
        sd[i] = 1.0 / d;
    }
    // y = L⁻¹ r
    let y = &mut lambda[..m];
    y.copy_from_slice(&r[..m]);
    for &(lo, hi) in blocks {
        for t in 0..size(lo, hi) {
            let i = lo + t;
            let li = &lf[i * W..i * W + W];
            let mut v = y[i];
            for p in 0..t {
                v = madd(-li[p], y[lo + p], v);
            }
            y[i] = v;
        }
    }
    // u = S⁻¹ Zᵀ D⁻¹ y
    let mut u = [0.0; W];
    for ((zi, &yi), &di) in z.chunks_exact(W).zip(y.iter()).zip(ld.iter()) {
        let x = yi * di;
        for c in 0..W {
            u[c] = madd(zi[c], x, u[c]);
        }
    }
    for i in 0..g {
        let mut x = u[i];
        for p in 0..i {
            x = madd(-s[i][p], u[p], x);
        }
        u[i] = x;
    }
    for i in (0..g).rev() {
        let mut x = u[i] * sd[i];
        for p in i + 1..g {
            x = madd(-s[p][i], u[p], x);
        }
        u[i] = x;
    }
    // y ← D⁻¹ (y − Z u), then λ = L⁻ᵀ y
    for ((zi, yi), &di) in z.chunks_exact(W).zip(y.iter_mut()).zip(ld.iter()) {
        let mut x = *yi;
        for c in 0..g {
            x = madd(-zi[c], u[c], x);
        }
        *yi = x * di;
    }
    for &(lo, hi) in blocks {
        let bs = size(lo, hi);
        for t in (0..bs).rev() {
            let i = lo + t;
            let mut v = y[i];
            for p in t + 1..bs {
                v = madd(-lf[(lo + p) * W + t], y[lo + p], v);
            }
            y[i] = v;
        }
    }
    true
}
