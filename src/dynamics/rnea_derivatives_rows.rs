//! The loops over rows of [`super::rnea_derivatives`]'s sweep on long patterns
//! (`Data::deriv_by_cols`, e.g. a 100-link chain): ∂τ/∂x's entries of a column
//! against a run of its ancestors' rows and of its subtree's rows, each entry the
//! operations of the 6-term dots they replace, in their order (docs/theory.md
//! §"Derivatives"). Beside the sweep so that it stays one algorithm a file.

use crate::spatial::ops::madd;
use crate::spatial::{Force, Motion, Scalar};

/// `x = mᵀ f` for the 6-vectors `m` (angular first) and the force `f`, as
/// [`Motion::dot`] takes it (the same operations in the same order).
#[inline(always)]
pub(super) fn dot6<T: Scalar>(m: &[T; 6], f: [T; 6]) -> T {
    madd(
        m[5],
        f[5],
        madd(
            m[4],
            f[4],
            madd(m[3], f[3], madd(m[2], f[2], madd(m[1], f[1], m[0] * f[0]))),
        ),
    )
}

/// A motion's 6 components, angular first.
#[inline(always)]
pub(super) fn m6<T: Scalar>(m: &Motion<T>) -> [T; 6] {
    [m.ang.x, m.ang.y, m.ang.z, m.lin.x, m.lin.y, m.lin.z]
}

/// A force's 6 components, angular first.
#[inline(always)]
pub(super) fn f6<T: Scalar>(f: &Force<T>) -> [T; 6] {
    [f.ang.x, f.ang.y, f.ang.z, f.lin.x, f.lin.y, f.lin.z]
}

/// Rows `k0..k0 + R` of the columns' components (`Data::deriv_cols`, stride
/// `nc`), each cut to `[lo, lo + len)`.
#[inline(always)]
pub(super) fn comps<T, const R: usize>(
    cs: &[T],
    nc: usize,
    k0: usize,
    lo: usize,
    len: usize,
) -> [&[T]; R] {
    let mut out: [&[T]; R] = [&[]; R];
    for (k, o) in out.iter_mut().enumerate() {
        let at = (k0 + k) * nc + lo;
        *o = &cs[at..at + len];
    }
    out
}

/// One column of this joint (at `col` in the column-major results `x`) against
/// a run `[lo, hi)` of its strict ancestors' rows r: `x_q[r] = Jᵣᵀ ∂F/∂q`,
/// `x_v[r] = Jᵣᵀ ∂F/∂v` and without `K` `x_a[r] = Jᵣᵀ Y J` (`f`: the column's
/// ∂F/∂q, ∂F/∂v, ∂F/∂a), Jᵣ read by components from `cols.0`
/// (`Data::deriv_cols`, stride `cols.1`): a loop over rows that vectorises, each
/// entry the operations of `Jᵣ.dot(f)`.
#[inline(always)]
pub(super) fn ancestor_rows<T: Scalar, const K: bool>(
    f: [&Force<T>; 3],
    cols: (&[T], usize),
    x: &mut [&mut [T]; 3],
    col: usize,
    (lo, hi): (usize, usize),
) {
    let [xq, xv, xa] = x;
    let len = hi - lo;
    let xq = &mut xq[col + lo..col + hi];
    let (xv, xa) = (&mut xv[col + lo..col + hi], &mut xa[col + lo..col + hi]);
    let j: [&[T]; 6] = comps(cols.0, cols.1, 0, lo, len);
    let (fq, fv, fa) = (f6(f[0]), f6(f[1]), f6(f[2]));
    for r in 0..len {
        let m = [j[0][r], j[1][r], j[2][r], j[3][r], j[4][r], j[5][r]];
        xq[r] = dot6(&m, fq);
        xv[r] = dot6(&m, fv);
        if !K {
            xa[r] = dot6(&m, fa);
        }
    }
}

/// One column r of this joint against its strict subtree's rows c (from `rows.2`
/// on): `x_q[c] = ∂aᵣᵀ/∂q Y J_c + ∂vᵣ/∂qᵀ (Ẏᵀ J)_c` (no second term at a `ROOT`;
/// with `F`, `+ ωᵣ · e_c`), `x_v[c] = ∂aᵣ/∂vᵀ Y J_c + Jᵣᵀ (Ẏᵀ J)_c` and without
/// `K` `x_a[c] = Jᵣᵀ Y J_c` (`m`: row r's ∂a/∂q, ∂v/∂q, ∂a/∂v, J), the columns c
/// read by components from `rows.0` (`Data::deriv_cols`): a loop over rows that
/// vectorises, each entry the operations of the `Motion::dot`s it replaces
/// (`(Ẏᵀ J).lin` = 0 and e.lin = 0 included as such).
#[inline(always)]
pub(super) fn subtree_rows<T: Scalar, const F: bool, const K: bool, const ROOT: bool>(
    m: [&Motion<T>; 4],
    rows: (&[T], usize, usize),
    x: [&mut [T]; 3],
) {
    let [xq, xv, xa] = x;
    let len = xq.len();
    let (xv, xa) = (&mut xv[..len], &mut xa[..len]);
    let (cs, nc, lo) = rows;
    let y: [&[T]; 6] = comps(cs, nc, 6, lo, len);
    let t: [&[T]; 3] = comps(cs, nc, 12, lo, len);
    let e: [&[T]; 3] = if F {
        comps(cs, nc, 15, lo, len)
    } else {
        [&[]; 3]
    };
    let (aq, dv, av, jr) = (m6(m[0]), m6(m[1]), m6(m[2]), m6(m[3]));
    let z = T::zero();
    for c in 0..len {
        let yc = [y[0][c], y[1][c], y[2][c], y[3][c], y[4][c], y[5][c]];
        let tc = [t[0][c], t[1][c], t[2][c], z, z, z];
        let mut q = if ROOT {
            dot6(&aq, yc)
        } else {
            dot6(&aq, yc) + dot6(&dv, tc)
        };
        if F {
            // ωᵣ · e_c
            q += madd(jr[2], e[2][c], madd(jr[1], e[1][c], jr[0] * e[0][c]));
        }
        xq[c] = q;
        xv[c] = dot6(&av, yc) + dot6(&jr, tc);
        if !K {
            xa[c] = dot6(&jr, yc);
        }
    }
}
