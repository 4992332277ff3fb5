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
                            // the common ancestors a root's chain (a floating
                            // base): their rows one packed triangle, swept by
                            // the unrolled kernel (the same operations per entry)
                            let na = m - 2;
                            let tri = match table.get(sk).map(|&a0| start[a0]) {
                                Some(s0) if na > 0 && root_chain[table[sk + na - 1]] => {
                                    head.get_mut(s0..s0 + na * (na + 1) / 2)
                                }
                                _ => None,
                            };
                            let mr = (&mult[..na], &mult_p[..na], &mult_g[..na]);
                            let rows = (&row[..na], &row_p[..na], &row_g[..na]);
                            if let Some(tri) = tri {
                                if sweep3_packed(tri, mr, rows) {
                                    row.copy_from_slice(mult);
                                    row_p.copy_from_slice(mult_p);
                                    row_g.copy_from_slice(mult_g);
                                    k -= 2;
                                    continue;
                                }
                            }
                            for t in (0..m - 2).rev() {
                                let si = start[table[sk + t]];
                                let (a, b, c) = (mult[t], mult_p[t], mult_g[t]);
                                let (Some(row_i), Some(row_k), Some(row_q), Some(row_r)) = (
                                    head.get_mut(si..si + t + 1),
                                    row.get(..t + 1),
                                    row_p.get(..t + 1),
                                    row_g.get(..t + 1),
                                ) else {
                                    return Err(k);
                                };
                                for (((x, &hkj), &hqj), &hrj) in
                                    row_i.iter_mut().zip(row_k).zip(row_q).zip(row_r)
                                {
                                    *x = madd(-c, hrj, madd(-b, hqj, madd(-a, hkj, *x)));
                                }
                            }
                            row.copy_from_slice(mult);
                            row_p.copy_from_slice(mult_p);
                            row_g.copy_from_slice(mult_g);
                            k -= 2;
                            continue;
                        }
                        // (k − 2's pivot fails: found at its turn, as without triples)
                    }
                    for t in (0..t_pair).rev() {
                        let si = start[table[sk + t]];
                        let (a, b) = (mult[t], mult_p[t]);
                        let (Some(row_i), Some(row_k), Some(row_q)) = (
                            head.get_mut(si..si + t + 1),
                            row.get(..t + 1),
                            row_p.get(..t + 1),
                        ) else {
                            return Err(k);
                        };
                        for ((x, &hkj), &hqj) in row_i.iter_mut().zip(row_k).zip(row_q) {
                            *x = madd(-b, hqj, madd(-a, hkj, *x));
                        }
                    }
                    row.copy_from_slice(mult);
                    row_p.copy_from_slice(mult_p);
                    k -= 1;
                    continue;
                }
            }
            for t in (0..t_end).rev() {
                let si = start[table[sk + t]];
                let a = mult[t];
                let (Some(row_i), Some(row_k)) = (head.get_mut(si..si + t + 1), row.get(..t + 1))
                else {
                    return Err(k);
                };
                for (x, &hkj) in row_i.iter_mut().zip(row_k) {
                    *x = madd(-a, hkj, *x);
                }
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

/// The three-dof update of a root's chain of `na` ≤ 6 dofs (a floating base)
/// whose packed rows lie back to back (`tri`, na(na + 1)/2 entries: row t's
/// t + 1 entries from t(t + 1)/2): entry (t, j) ← x − a[t]·k[j] − b[t]·q[j] −
/// c[t]·r[j], three fused multiply-adds in that order, as the general sweep.
/// False (nothing done) for a longer chain.
#[inline(always)]
fn sweep3_packed(
    tri: &mut [f64],
    m: (&[f64], &[f64], &[f64]),
    r: (&[f64], &[f64], &[f64]),
) -> bool {
    match m.0.len() {
        1 => sweep3_n::<1>(tri, m, r),
        2 => sweep3_n::<2>(tri, m, r),
        3 => sweep3_n::<3>(tri, m, r),
        4 => sweep3_n::<4>(tri, m, r),
        5 => sweep3_n::<5>(tri, m, r),
        6 => sweep3_n::<6>(tri, m, r),
        _ => return false,
    }
    true
}

/// [`sweep3_packed`] for N dofs (constant bounds: unrolled, no bounds tests).
#[inline(always)]
fn sweep3_n<const N: usize>(
    tri: &mut [f64],
    (a, b, c): (&[f64], &[f64], &[f64]),
    (rk, rq, rr): (&[f64], &[f64], &[f64]),
) {
    let (tri, a, b, c) = (&mut tri[..N * (N + 1) / 2], &a[..N], &b[..N], &c[..N]);
    let (rk, rq, rr) = (&rk[..N], &rq[..N], &rr[..N]);
    for t in (0..N).rev() {
        let o = t * (t + 1) / 2;
        for j in 0..=t {
            // x − a k − b q − c r, one fused multiply-add each, in that order
            tri[o + j] = madd(
                -c[t],
                rr[j],
                madd(-b[t], rq[j], madd(-a[t], rk[j], tri[o + j])),
            );
        }
    }
}
