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
pub(super) fn ldlt_dropping(a: &mut [f64], ld: usize, m: usize, from: usize, drop: f64) {
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
/// (0 when dⱼ was dropped), `rowj` = lⱼ.., `dk` the pivots before j; four
/// rows' sums side by side.
#[inline(always)]
fn column(rowj: &[f64], dk: &[f64], dj: f64, rows: &mut [f64], ld: usize, j: usize) {
    let fin = |s: f64| if dj != 0.0 { s / dj } else { 0.0 };
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
/// same order on each entry, without the index checks of the library's loops.
pub(super) fn ldlt_dropping_solve(a: &[f64], ld: usize, m: usize, x: &mut [f64]) {
    if m == 0 || ld < m || a.len() < (m - 1) * ld + m || x.len() < m {
        return;
    }
    // SAFETY: every index read or written below is i·ld + k (i, k < m) in `a`,
    // at most (m − 1)·ld + m − 1 < a.len(), and i < m ≤ x.len() in `x`
    let (a, x) = (a.as_ptr(), x.as_mut_ptr());
    unsafe {
        // L z = b: row i's sum over k < i in order
        for i in 1..m {
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
            for k in i + 1..m {
                s -= *a.add(k * ld + i) * *x.add(k);
            }
            *x.add(i) = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// W = Y Yᵀ (m × m, row i at `i * ld`) of a pseudo-random m × k `Y`;
    /// k < m gives rows dependent on earlier ones (pivots dropped).
    fn gram(m: usize, k: usize, ld: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let y: Vec<f64> = (0..m * k).map(|_| next()).collect();
        let mut w = vec![f64::NAN; ld * ld];
        for i in 0..m {
            for j in 0..=i {
                let mut s = 0.0;
                for t in 0..k {
                    s += y[i * k + t] * y[j * k + t];
                }
                w[i * ld + j] = s;
            }
        }
        w
    }

    fn lower(a: &[f64], ld: usize, m: usize) -> Vec<u64> {
        (0..m)
            .flat_map(|i| (0..=i).map(move |j| a[i * ld + j].to_bits()))
            .collect()
    }

    /// The strided factor (from scratch, and with a factored leading block
    /// kept) and its solve give the library's bits, dropped pivots included.
    #[test]
    fn strided_and_appended_factor_match_the_library_bits() {
        let ld = 16;
        let mut drops = 0;
        for (m, k, seed) in [(16, 16, 1), (16, 11, 2), (13, 9, 3), (9, 12, 4), (16, 5, 5)] {
            let w = gram(m, k, ld, seed);
            // the library on the packed copy
            let mut packed = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..=i {
                    packed[i * m + j] = w[i * ld + j];
                }
            }
            linalg::ldlt_dropping(&mut packed, m, DROP);
            let want = lower(&packed, m, m);
            drops += (0..m).filter(|&i| packed[i * m + i] == 0.0).count();
            let mut full = w.clone();
            ldlt_dropping(&mut full, ld, m, 0, DROP);
            assert_eq!(lower(&full, ld, m), want, "m {m} k {k}");
            for p in [1, 3, m / 2, m - 1] {
                // rows p.. appended to the factor of the leading p
                let mut grown = w.clone();
                ldlt_dropping(&mut grown, ld, p, 0, DROP);
                ldlt_dropping(&mut grown, ld, m, p, DROP);
                assert_eq!(lower(&grown, ld, m), want, "m {m} k {k} p {p}");
            }
            let b: Vec<f64> = (0..m).map(|i| (i as f64 * 0.37).sin()).collect();
            let (mut x, mut xl) = (b.clone(), b);
            ldlt_dropping_solve(&full, ld, m, &mut x);
            linalg::ldlt_dropping_solve(&packed, m, &mut xl);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&xl), "m {m} k {k}");
        }
        // the cases hold dependent rows, whose pivots were dropped
        assert!(drops >= 10, "{drops}");
    }

    const DROP: f64 = 1e-6;
}
