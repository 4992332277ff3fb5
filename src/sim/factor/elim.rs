//! The tree-sparse LTDL elimination of [`MassFactor`] on one range of dofs
//! (docs/theory.md §"Tree-sparse LTDL"), a dof with its parent (and its
//! grandparent) at once where they form a chain.

use super::MassFactor;
use crate::spatial::ops::madd;

impl MassFactor {
    /// [`Self::factor_packed`] on the dofs `[k0, k1)` (whole trees).
    ///
    /// Where dof k − 1 is k's parent (a chain: most dofs), k and k − 1 are
    /// eliminated together: k's update of row k − 1 (its first) comes first,
    /// then k − 1's multipliers, then one sweep over their common ancestors'
    /// rows applies k's update and k − 1's to each entry in turn — each
    /// entry gets the same two fused multiply-adds in the same order as one
    /// dof after the other (the same bits), with half the loads, stores and
    /// loop set-ups. Where k − 2 is k − 1's parent as well (a robot's leg
    /// of three, a floating base's six), the three go together the same way.
    pub(super) fn factor_range(&mut self, k0: usize, k1: usize, tiny: f64) -> Result<(), usize> {
        for k in k0..k1 {
            self.hdiag[k] = self.anc[self.start[k] + self.len[k] - 1];
        }
        let (anc, table, start, len) = (&mut self.anc, &self.table, &self.start, &self.len);
        let root_chain = &self.root_chain;
        let (hdiag, mult_all) = (&self.hdiag, &mut self.mult);
        // the pivot test of dof k, D[k] = d
        let pivot_ok = |k: usize, d: f64| d > tiny * hdiag[k].abs() && d.is_finite();
        let mut k = k1;
        while k > k0 {
            k -= 1;
            let (sk, lk) = (start[k], len[k]);
            let d = anc[sk + lk - 1];
            if !pivot_ok(k, d) {
                return Err(k);
            }
            // eliminate k from its ancestors i = path_k[t], t = depth(i): i's
            // packed path (t + 1 entries, ending at D[i]) lies before k's (i < k),
            // so the two are disjoint slices and each entry's update, one fused
            // multiply-add independent of the others, runs in vector lanes
            // (the same operation per entry as one at a time: the same bits)
            let (head, tail) = anc.split_at_mut(sk);
            let m = lk - 1;
            let (Some(row), Some(mult)) = (tail.get_mut(..m), mult_all.get_mut(..m)) else {
                return Err(k);
            };
            // the multipliers L[k, i] = H̃[k, i] / D[k] first, all at once: the
            // divisions are independent (vector lanes, each the correctly
            // rounded quotient it was one at a time), and no update below
            // waits on a division's latency
            for (a, &x) in mult.iter_mut().zip(row.iter()) {
                *a = x / d;
            }
            // k − 1 is k's parent (and in the range): the pair
            let pair = m >= 1 && k > k0 && table[sk + m - 1] == k - 1;
            let mut t_end = m;
            if pair {
                // k's update of row k − 1 (t = m − 1), D[k − 1] included
                let sp = start[k - 1];
                let Some(row_p) = head.get_mut(sp..sp + m) else {
                    return Err(k);
                };
                let a = mult[m - 1];
                for (x, &hkj) in row_p.iter_mut().zip(row.iter()) {
                    *x = madd(-a, hkj, *x);
                }
                t_end = m - 1;
                let dp = row_p[m - 1];
                if pivot_ok(k - 1, dp) {
                    // row k − 1's entries off its diagonal (read below, then
                    // replaced by its multipliers), apart from its ancestors' rows
                    let (head, rest) = head.split_at_mut(sp);
                    let row_p = &mut rest[..m - 1];
                    // k − 1's multipliers L[k − 1, i] = H̃'[k − 1, i] / D[k − 1]
                    // (`mult` holds 3 nv: k's, k − 1's and k − 2's side by side)
                    let (ml, mh) = mult_all.split_at_mut(m);
                    let (mult, (mult_p, mult_g)) = (&ml[..m], mh.split_at_mut(m - 1));
                    for (a, &x) in mult_p.iter_mut().zip(row_p.iter()) {
                        *a = x / dp;
                    }
                    // k − 2 is k − 1's parent (and in the range): a triple. Its
                    // row (t = m − 2) takes k's and k − 1's updates first, then
                    // its multipliers, then one sweep over the three's common
                    // ancestors' rows applies k's, k − 1's and k − 2's updates
                    // to each entry in turn (the same fused multiply-adds in
                    // the same order as the pairs and singles: the same bits)
                    let mut t_pair = m - 1;
                    if m >= 2 && k - 1 > k0 && table[sk + m - 2] == k - 2 {
                        let sg = start[k - 2];
                        let (head, rest) = head.split_at_mut(sg);
                        let (Some(row_g), Some(row_k), Some(row_q)) =
                            (rest.get_mut(..m - 1), row.get(..m - 1), row_p.get(..m - 1))
                        else {
                            return Err(k);
                        };
                        let (a, b) = (mult[m - 2], mult_p[m - 2]);
                        for ((x, &hkj), &hqj) in row_g.iter_mut().zip(row_k).zip(row_q) {
                            *x = madd(-b, hqj, madd(-a, hkj, *x));
                        }
                        t_pair = m - 2;
                        let dg = row_g[m - 2];
                        if pivot_ok(k - 2, dg) {
                            let (row_g, mult_g) = (&mut row_g[..m - 2], &mut mult_g[..m - 2]);
                            for (c, &x) in mult_g.iter_mut().zip(row_g.iter()) {
                                *c = x / dg;
                            }
                            // the three's updates of their common ancestors' rows
                            let na = m - 2;
                            let mr = [&mult[..na], &mult_p[..na], &mult_g[..na]];
                            let rows = [&row[..na], &row_p[..na], &row_g[..na]];
                            if sweep_common(head, table, start, root_chain, sk, mr, rows).is_none()
                            {
                                return Err(k);
                            }
                            row.copy_from_slice(mult);
                            row_p.copy_from_slice(mult_p);
                            row_g.copy_from_slice(mult_g);
                            k -= 2;
                            continue;
                        }
                        // (k − 2's pivot fails: found at its turn, as without triples)
                    }
                    // the pair's updates of their common ancestors' rows
                    let na = t_pair;
                    let (Some(rk), Some(rq)) = (row.get(..na), row_p.get(..na)) else {
                        return Err(k);
                    };
                    let mr = [&mult[..na], &mult_p[..na]];
                    if sweep_common(head, table, start, root_chain, sk, mr, [rk, rq]).is_none() {
                        return Err(k);
                    }
                    row.copy_from_slice(mult);
                    row_p.copy_from_slice(mult_p);
                    k -= 1;
                    continue;
                }
            }
            // k's update of its ancestors' rows
            let (Some(rk), Some(mk)) = (row.get(..t_end), mult.get(..t_end)) else {
                return Err(k);
            };
            if sweep_common(head, table, start, root_chain, sk, [mk], [rk]).is_none() {
                return Err(k);
            }
            row.copy_from_slice(mult);
            if pair {
                // k − 1's pivot failed the test
                return Err(k - 1);
            }
        }
        for k in k0..k1 {
            let d = self.anc[self.start[k] + self.len[k] - 1];
            self.dval[k] = d;
            self.sqrt_d[k] = d.sqrt();
            self.inv_sqrt_d[k] = 1.0 / self.sqrt_d[k];
        }
        Ok(())
    }
}

/// The update of R eliminated dofs (k, k − 1, k − 2: `m[0]`, `m[1]`, `m[2]`,
/// their multipliers L[·, i], and `r`, their rows H̃'[·, j] before the
/// multipliers replaced them) on the rows of their `na` common ancestors
/// i = path_k[t], t < na (`table[sk..sk + na]`, root first; na = the length of
/// every slice): entry (t, j ≤ t) of row i ← x − m[0][t] r[0][j] − m[1][t]
/// r[1][j] − …, one fused multiply-add each in that order. The entries are
/// independent, so any order of rows gives the same bits. The ancestors
/// that are a root's chain (a floating base's six, a trunk's joints after
/// them: [`MassFactor`]'s `root_chain`, a prefix of the path) have their packed
/// rows back to back, one triangle swept without look-ups; the rest row by
/// row. `None`: a row out of `anc`'s range (not on a factor's own tables).
#[inline(always)]
fn sweep_common<const R: usize>(
    head: &mut [f64],
    table: &[usize],
    start: &[usize],
    root_chain: &[bool],
    sk: usize,
    m: [&[f64]; R],
    r: [&[f64]; R],
) -> Option<()> {
    let na = m[0].len();
    // the root's-chain prefix: path_k[..p] (a prefix: a dof's path is its
    // ancestors' paths extended)
    let mut p = na;
    while p > 0 && !root_chain.get(*table.get(sk + p - 1)?).copied()? {
        p -= 1;
    }
    for t in (p..na).rev() {
        let si = *start.get(*table.get(sk + t)?)?;
        let row_i = head.get_mut(si..si + t + 1)?;
        row_update(row_i, t, m, r);
    }
    if p > 0 {
        let s0 = *start.get(*table.get(sk)?)?;
        let tri = head.get_mut(s0..s0 + p * (p + 1) / 2)?;
        match p {
            1 => sweep_n::<1, R>(tri, m, r),
            2 => sweep_n::<2, R>(tri, m, r),
            3 => sweep_n::<3, R>(tri, m, r),
            4 => sweep_n::<4, R>(tri, m, r),
            5 => sweep_n::<5, R>(tri, m, r),
            6 => sweep_n::<6, R>(tri, m, r),
            7 => sweep_n::<7, R>(tri, m, r),
            8 => sweep_n::<8, R>(tri, m, r),
            9 => sweep_n::<9, R>(tri, m, r),
            10 => sweep_n::<10, R>(tri, m, r),
            11 => sweep_n::<11, R>(tri, m, r),
            12 => sweep_n::<12, R>(tri, m, r),
            _ => sweep_rt::<R>(tri, p, m, r),
        }
    }
    Some(())
}

/// [`sweep_common`]'s triangle of N ≤ 12 rows (a floating base's six, a
/// humanoid's trunk and hip after them; constant bounds: unrolled, no bounds
/// tests).
#[inline(always)]
fn sweep_n<const N: usize, const R: usize>(tri: &mut [f64], m: [&[f64]; R], r: [&[f64]; R]) {
    let tri = &mut tri[..N * (N + 1) / 2];
    for q in 0..R {
        assert!(m[q].len() >= N && r[q].len() >= N);
    }
    for t in (0..N).rev() {
        let o = t * (t + 1) / 2;
        for j in 0..=t {
            let mut y = tri[o + j];
            for q in 0..R {
                y = madd(-m[q][t], r[q][j], y);
            }
            tri[o + j] = y;
        }
    }
}

/// [`sweep_common`]'s triangle of `p` rows (any number), row by row.
#[inline(always)]
fn sweep_rt<const R: usize>(tri: &mut [f64], p: usize, m: [&[f64]; R], r: [&[f64]; R]) {
    for q in 0..R {
        assert!(m[q].len() >= p && r[q].len() >= p);
    }
    let mut rest = tri;
    for t in 0..p {
        let (row_i, tail) = std::mem::take(&mut rest).split_at_mut(t + 1);
        rest = tail;
        row_update(row_i, t, m, r);
    }
}

/// One row of [`sweep_common`]: `row_i[j] ← x − m[0][t] r[0][j] − …` for j
/// < row_i.len() (R ≤ 3; zipped slices: vector lanes, no bounds tests).
#[inline(always)]
fn row_update<const R: usize>(row_i: &mut [f64], t: usize, m: [&[f64]; R], r: [&[f64]; R]) {
    let n = row_i.len();
    if R == 1 {
        let (a, ra) = (m[0][t], &r[0][..n]);
        for (x, &u) in row_i.iter_mut().zip(ra) {
            *x = madd(-a, u, *x);
        }
    } else if R == 2 {
        let (a, b, ra, rb) = (m[0][t], m[1][t], &r[0][..n], &r[1][..n]);
        for ((x, &u), &w) in row_i.iter_mut().zip(ra).zip(rb) {
            *x = madd(-b, w, madd(-a, u, *x));
        }
    } else {
        let (a, b, c) = (m[0][t], m[1][t], m[2][t]);
        let (ra, rb, rc) = (&r[0][..n], &r[1][..n], &r[2][..n]);
        for (((x, &u), &w), &y) in row_i.iter_mut().zip(ra).zip(rb).zip(rc) {
            *x = madd(-c, y, madd(-b, w, madd(-a, u, *x)));
        }
    }
}
