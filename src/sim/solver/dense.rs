//! The subspace step's dense LDLᵀ of W_FF (subspace.rs, stress.rs): the
//! operations of [`crate::dynamics::linalg::ldlt_dropping`] on the same
//! numbers in the same order (each entry the same bits), laid out for a
//! small m: four rows' sums carried side by side (independent chains, so
//! that one does not wait on another's latency) and no test on a dropped
//! pivot in the inner loops.
//!
//! Why the test can go: a pivot dropped at column k (D = 0) leaves its column
//! of L exactly +0 below the diagonal, so every term lᵢₖ lⱼₖ dₖ of a later
//! entry is (+0 · +0) · (+0) = +0, and x − (+0) is x for every x (−0, NaN and
//! ±∞ included): skipping the term and subtracting it agree bit for bit.

use crate::dynamics::linalg;

/// Most rows taken here (more: the library's loop, `ld` = m and `from` = 0
/// only).
const CAP: usize = 64;
const _: () = assert!(super::SUBSPACE_MAX <= CAP);

/// [`linalg::ldlt_dropping`] (the lower triangle of the m × m `a`, row i at
/// `a[i * ld..]`, factored as L D Lᵀ, a pivot below `drop` of its diagonal
/// dropped), the same bits, its rows before `from` taken as factored already.
///
/// Row i of the factor (its L entries and pivot) depends on the rows ≤ i of
/// the matrix only, and each entry is the same sum in the same order whatever
/// follows: the factor of a leading block is the leading block of the factor.
/// So rows appended to a factored block (`from` its size) are factored here
/// to the bits a factor from scratch gives them (docs/theory.md §"Constraint
/// solve": the subspace step's free rows kept across a solve's tries).
pub(crate) fn ldlt_dropping(a: &mut [f64], ld: usize, m: usize, from: usize, drop: f64) {
    let from = from.min(m);
    if m > CAP || ld < m || a.len() < m * ld {
        if ld == m && from == 0 {
            linalg::ldlt_dropping(a, m, drop);
        }
        return;
    }
    let a = &mut a[..m * ld];
    let mut d = [0.0f64; CAP];
    // the factored columns: their pivots, and their entries in rows from..
    for j in 0..from {
        d[j] = a[j * ld + j];
        let (head, tail) = a.split_at_mut((j + 1) * ld);
        let rows = &mut tail[(from - j - 1) * ld..];
        column(&head[j * ld..j * ld + j], &d[..j], d[j], rows, ld, j);
    }
    for j in from..m {
        let (head, tail) = a.split_at_mut((j + 1) * ld);
        let (rowj, diag) = {
            let r = &head[j * ld..j * ld + j + 1];
            (&r[..j], r[j])
        };
        let mut dj = diag;
        for (&l, &dk) in rowj.iter().zip(&d[..j]) {
            dj -= l * l * dk;
        }
        let dj = if dj > drop * diag && dj > 0.0 {
            dj
        } else {
            0.0
        };
        head[j * ld + j] = dj;
        d[j] = dj;
        column(&head[j * ld..j * ld + j], &d[..j], dj, tail, ld, j);
    }
}

/// Column j of L in `rows` (whole rows of `ld` entries, each with its entries
/// before j factored): lᵢⱼ = (aᵢⱼ − Σₖ lᵢₖ lⱼₖ dₖ) / dⱼ over k < j in order
/// (0 when dⱼ was dropped: no sum then), `rowj` = lⱼ.., `dk` the pivots
/// before j; four rows' sums side by side.
#[inline(always)]
fn column(rowj: &[f64], dk: &[f64], dj: f64, rows: &mut [f64], ld: usize, j: usize) {
    if dj == 0.0 {
        // a dropped pivot: the library's entry is 0 whatever its sum
        for ri in rows.chunks_exact_mut(ld) {
            ri[j] = 0.0;
        }
        return;
    }
    let fin = |s: f64| s / dj;
    let mut rest = rows;
    while rest.len() >= 4 * ld {
        let (four, more) = rest.split_at_mut(4 * ld);
        rest = more;
        let (r0, x) = four.split_at_mut(ld);
        let (r1, x) = x.split_at_mut(ld);
        let (r2, r3) = x.split_at_mut(ld);
        let (mut s0, mut s1, mut s2, mut s3) = (r0[j], r1[j], r2[j], r3[j]);
        let (r0j, r1j, r2j, r3j) = (&r0[..j], &r1[..j], &r2[..j], &r3[..j]);
        for k in 0..j {
            let (lk, dk) = (rowj[k], dk[k]);
            s0 -= r0j[k] * lk * dk;
            s1 -= r1j[k] * lk * dk;
            s2 -= r2j[k] * lk * dk;
            s3 -= r3j[k] * lk * dk;
        }
        r0[j] = fin(s0);
        r1[j] = fin(s1);
        r2[j] = fin(s2);
        r3[j] = fin(s3);
    }
    for ri in rest.chunks_exact_mut(ld) {
        let mut s = ri[j];
        for ((&x, &lk), &dk) in ri[..j].iter().zip(rowj).zip(dk) {
            s -= x * lk * dk;
        }
        ri[j] = fin(s);
    }
}

/// [`linalg::ldlt_dropping_solve`] (L D Lᵀ x = b in place, the factor of
/// [`ldlt_dropping`] in the lower triangle of the m × m `a`, row i at
/// `a[i * ld..]`, a dropped pivot's x set to 0), the same operations in the
/// same order on each entry, without the index checks of the library's loops
/// and with fewer loop steps (two rows' sums a step forward, two terms a step
/// back).
pub(crate) fn ldlt_dropping_solve(a: &[f64], ld: usize, m: usize, x: &mut [f64]) {
    if m == 0 || ld < m || a.len() < (m - 1) * ld + m || x.len() < m {
        return;
    }
    // SAFETY: every index read or written below is i·ld + k (i, k < m) in `a`,
    // at most (m − 1)·ld + m − 1 < a.len(), and i < m ≤ x.len() in `x`
    let (a, x) = (a.as_ptr(), x.as_mut_ptr());
    unsafe {
        // L z = b: row i's sum over k < i in order, rows i and i + 1 side
        // by side (two chains) over k < i, then row i + 1's term k = i
        let mut i = 1;
        while i + 1 < m {
            let (r0, r1) = (a.add(i * ld), a.add((i + 1) * ld));
            let (mut s0, mut s1) = (*x.add(i), *x.add(i + 1));
            for k in 0..i {
                let xk = *x.add(k);
                s0 -= *r0.add(k) * xk;
                s1 -= *r1.add(k) * xk;
            }
            *x.add(i) = s0;
            s1 -= *r1.add(i) * s0;
            *x.add(i + 1) = s1;
            i += 2;
        }
        if i < m {
            let row = a.add(i * ld);
            let mut s = *x.add(i);
            for k in 0..i {
                s -= *row.add(k) * *x.add(k);
            }
            *x.add(i) = s;
        }
        // z /= D
        for i in 0..m {
            let d = *a.add(i * ld + i);
            *x.add(i) = if d != 0.0 { *x.add(i) / d } else { 0.0 };
        }
        // Lᵀ x = z: entry i's sum over k > i in order, down column i of L
        for i in (0..m).rev() {
            if *a.add(i * ld + i) == 0.0 {
                *x.add(i) = 0.0;
                continue;
            }
            let mut s = *x.add(i);
            let mut k = i + 1;
            while k + 1 < m {
                s -= *a.add(k * ld + i) * *x.add(k);
                s -= *a.add((k + 1) * ld + i) * *x.add(k + 1);
                k += 2;
            }
            if k < m {
                s -= *a.add(k * ld + i) * *x.add(k);
            }
            *x.add(i) = s;
        }
    }
}
