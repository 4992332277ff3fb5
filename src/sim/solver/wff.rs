//! W_FF = Y_F Y_Fᵀ of the subspace step's free rows (subspace.rs, stress.rs):
//! its lower triangle formed a pair of row groups at a time (a contact's
//! three rows side by side), entries kept from the solve's last W_FF copied.

use super::dot3::dot3;
use super::kernels::at_path_len;
use super::subspace::Subspace;

impl Subspace {
    /// Marks where a contact's three rows start in `self.rows` (`three`): rows
    /// r, r + 1, r + 2 in a row on one path, taken from the first row on (the
    /// groups the residuals and W_FF are summed by).
    pub(super) fn group(&mut self, paths: &[(usize, usize)]) {
        let (rows, m) = (&self.rows[..], self.rows.len());
        self.three.clear();
        let mut a = 0;
        while a < m {
            let r = rows[a];
            let t = a + 2 < m
                && rows[a + 1] == r + 1
                && rows[a + 2] == r + 2
                && paths[r + 1] == paths[r]
                && paths[r + 2] == paths[r];
            self.three.push(t);
            if t {
                self.three.extend([false, false]);
                a += 3;
            } else {
                a += 1;
            }
        }
    }

    /// The start of the group ([`Subspace::group`]) that holds free row `p`
    /// (`p` itself at or past the end).
    pub(super) fn group_start(&self, p: usize) -> usize {
        let mut a = 0;
        while a < p.min(self.three.len()) {
            let next = if self.three[a] { a + 3 } else { a + 1 };
            if next > p {
                return a;
            }
            a = next;
        }
        p
    }

    /// Where each free row was in the last factor's rows (`old`, [`NEW`]
    /// where it was not): both lists are in row order, so one merge.
    pub(super) fn map_old(&mut self) {
        self.old.clear();
        let mut o = 0;
        for &r in &self.rows {
            while o < self.factored_rows.len() && self.factored_rows[o] < r {
                o += 1;
            }
            if self.factored_rows.get(o) == Some(&r) {
                self.old.push(o);
                o += 1;
            } else {
                self.old.push(NEW);
            }
        }
    }

    /// The lower triangle of W_FF = Y_F Y_Fᵀ over `self.rows` (m of them) into
    /// `self.w` (row a at `w[a * ld..]`), and with `KEPT` into `self.wf` too,
    /// where it is kept for the solve's later tries (the rows of `wf` before
    /// `from` are this solve's last W_FF's, [`Subspace::keep_old`]), its
    /// rows from `from` on (a group's
    /// start, [`Subspace::group`], which must have been run on these rows):
    /// row r scattered onto its path's dofs in `x` (zeros elsewhere, put back
    /// after), each entry then a sum over the other row's path in its order.
    /// A dof off r's path adds y·0 = ±0, which leaves every partial sum as it
    /// was: the same bits as summing over the two paths' common dofs only,
    /// without the merge's branches (the cost follows the rows' paths, never
    /// nv). Rows `r` of `y` have room `st`; row r's dofs are
    /// `table[paths[r]]`, each < nv (the sweeps' check). `x` must hold nv
    /// entries, `w` m · ld. A contact's three rows q are summed side by side
    /// in vector lanes ([`dot3x3`], `dot3::dot3`): each the same sum in the
    /// same order. With `reuse`
    /// (`old` mapped, [`Subspace::map_old`]), an entry between two groups of
    /// rows all in the last W_FF (`wold`, [`Subspace::keep_old`]) is copied
    /// from there: the same sum, whichever group it was summed in. Returns
    /// whether it was formed (false: the scratch does not fit these rows).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn form_w_ff<const KEPT: bool>(
        &mut self,
        y: &[f64],
        st: usize,
        paths: &[(usize, usize)],
        table: &[usize],
        own_blocks: OwnBlocks,
        nv: usize,
        from: usize,
        reuse: bool,
    ) -> bool {
        let (m, ld) = (self.rows.len(), self.ld);
        if m > ld
            || self.w.len() < m * ld
            || self.wf.len() < m * ld
            || self.three.len() != m
            || self.x.len() < nv
            || self.x3.len() < nv
            || (reuse && (self.old.len() != m || self.wold.len() < m * ld))
        {
            return false;
        }
        let Self {
            rows,
            three,
            w,
            wf,
            wold,
            old,
            x,
            x3,
            ..
        } = self;
        let (rows, three, wold, old) = (&rows[..], &three[..], &wold[..], &old[..]);
        let path = |r: usize| {
            let (s, l) = paths[r];
            &table[s..s + l]
        };
        let (w, wf) = (&mut w[..m * ld], &mut wf[..m * ld]);
        let yrow = |q: usize, len: usize| &y[q * st..q * st + len];
        // SAFETY (the writes below): every (i, j) written has i < m, j ≤ i
        // (and with `KEPT` into wf, of the same length)
        let mut put = |i: usize, j: usize, v: f64| unsafe {
            *w.get_unchecked_mut(i * ld + j) = v;
            if KEPT {
                *wf.get_unchecked_mut(i * ld + j) = v;
            }
        };
        let known = |a: usize, s: usize| reuse && old[a..a + s].iter().all(|&o| o != NEW);
        // a group's own block (`OwnBlocks::own`) at (a, a): the entries
        // `Rows::form` summed as W's diagonal and a contact's w_block, from
        // −0 (an entry here is the same products in the same order from +0:
        // the same bits but for a sum of −0, which + 0.0 makes the +0 the sum
        // here gives)
        #[inline(always)]
        fn put_own(
            put: &mut impl FnMut(usize, usize, f64),
            a: usize,
            own: [[f64; 3]; 3],
            s: usize,
        ) {
            for (i, oi) in own.iter().enumerate().take(s) {
                for (j, &oij) in oi.iter().enumerate().take(i + 1) {
                    put(a + i, a + j, oij + 0.0);
                }
            }
        }
        // one contact's rows or two contacts', none in the last W_FF (a lone
        // contact's island, two contacts'): the entries the loop below
        // writes, the same sums, without its bookkeeping — each own block,
        // and the second contact's rows scattered against the first's
        if from == 0 && !reuse && (m == 3 || (m == 6 && three[3])) && three[0] {
            let r0 = rows[0];
            if let Some(o0) = own_blocks.own(r0, 3) {
                let r1 = rows[m - 3];
                let o1 = if m == 6 {
                    own_blocks.own(r1, 3)
                } else {
                    Some(o0)
                };
                if let Some(o1) = o1 {
                    put_own(&mut put, 0, o0, 3);
                    if m == 6 {
                        let (p0, p1) = (path(r0), path(r1));
                        let ys = |q: usize, l: usize| [yrow(q, l), yrow(q + 1, l), yrow(q + 2, l)];
                        scatter3(x3, p1, ys(r1, p1.len()));
                        // SAFETY: k < nv ≤ x3.len() (the sweeps' check)
                        let sum = unsafe { dot3x3(ys(r0, p0.len()), p0, x3) };
                        clear3(x3, p1);
                        for (i, si) in sum.iter().enumerate() {
                            for (j, &sij) in si.iter().enumerate() {
                                put(3 + i, j, sij);
                            }
                        }
                        put_own(&mut put, 3, o1, 3);
                    }
                    return true;
                }
            }
        }
        let mut a = 0;
        while a < m {
            let sa = if three[a] { 3 } else { 1 };
            if a < from {
                a += sa;
                continue;
            }
            let r = rows[a];
            let pa = path(r);
            let a_known = known(a, sa);
            let mut scattered = false;
            let mut bb = 0;
            while bb <= a {
                let sb = if three[bb] { 3 } else { 1 };
                if a_known && known(bb, sb) {
                    // both in the last W_FF: its entries (old places keep
                    // the order, so (a + i, bb + j) stays in its lower triangle)
                    for i in 0..sa {
                        for j in 0..sb {
                            if bb + j <= a + i {
                                put(a + i, bb + j, wold[old[a + i] * ld + old[bb + j]]);
                            }
                        }
                    }
                    bb += sb;
                    continue;
                }
                if bb == a {
                    // the group's own block
                    if let Some(own) = own_blocks.own(r, sa) {
                        put_own(&mut put, a, own, sa);
                        bb += sb;
                        continue;
                    }
                }
                if !scattered {
                    scattered = true;
                    if sa == 3 {
                        let l = pa.len();
                        scatter3(x3, pa, [yrow(r, l), yrow(r + 1, l), yrow(r + 2, l)]);
                    } else {
                        for (&yt, &k) in yrow(r, pa.len()).iter().zip(pa) {
                            x[k] = yt;
                        }
                    }
                }
                let q = rows[bb];
                let pq = path(q);
                match (sa, sb) {
                    (3, 3) => {
                        // a contact's three rows against another's: every
                        // entry (a + i, bb + j), bb + j ≤ a + i, the same sum
                        // in the same order as the single rows' below
                        let l = pq.len();
                        let zs = [yrow(q, l), yrow(q + 1, l), yrow(q + 2, l)];
                        // SAFETY: k < nv ≤ x3.len() (the sweeps' check)
                        let sum = unsafe { dot3x3(zs, pq, x3) };
                        // (below the diagonal block every entry: bb + 3 ≤ a)
                        let below = bb < a;
                        for (i, si) in sum.iter().enumerate() {
                            for (j, &sij) in si.iter().enumerate() {
                                if below || j <= i {
                                    put(a + i, bb + j, sij);
                                }
                            }
                        }
                    }
                    (3, _) => {
                        let mut sum = [0.0f64; 3];
                        for (&yt, &k) in yrow(q, pq.len()).iter().zip(pq) {
                            // SAFETY: k < nv ≤ x3.len() (the sweeps' check)
                            let xk = unsafe { *x3.get_unchecked(k) };
                            for (si, &xi) in sum.iter_mut().zip(&xk) {
                                *si += yt * xi;
                            }
                        }
                        for (i, &si) in sum.iter().enumerate() {
                            put(a + i, bb, si);
                        }
                    }
                    (_, 3) => {
                        // rows q on one path (a contact's three) summed side
                        // by side: each entry the same sum in the same order
                        let l = pq.len();
                        let ys = [yrow(q, l), yrow(q + 1, l), yrow(q + 2, l)];
                        // SAFETY: k < nv ≤ x.len() (the sweeps' check)
                        let [s0, s1, s2] = unsafe { dot3(ys, pq, x) };
                        put(a, bb, s0);
                        put(a, bb + 1, s1);
                        put(a, bb + 2, s2);
                    }
                    _ => {
                        let mut s = 0.0;
                        for (&yt, &k) in yrow(q, pq.len()).iter().zip(pq) {
                            // SAFETY: k < nv ≤ x.len() (the sweeps' check)
                            s += yt * unsafe { *x.get_unchecked(k) };
                        }
                        put(a, bb, s);
                    }
                }
                bb += sb;
            }
            if scattered {
                if sa == 3 {
                    clear3(x3, pa);
                } else {
                    for &k in pa {
                        x[k] = 0.0;
                    }
                }
            }
            a += sa;
        }
        true
    }

    /// Before a try on other free rows than the last factor's: the last
    /// W_FF (`wf`) moved to `wold`, where [`Subspace::form_w_ff`] reads
    /// the entries it copies, and its rows before `kept` (the rows this try
    /// keeps) back in `wf`.
    pub(super) fn keep_old(&mut self, kept: usize) {
        std::mem::swap(&mut self.wf, &mut self.wold);
        // whole rows in one copy (their entries past the diagonal are never
        // read: a W_FF is read by its lower triangle)
        let e = kept.min(self.ld) * self.ld;
        if let (Some(d), Some(s)) = (self.wf.get_mut(..e), self.wold.get(..e)) {
            d.copy_from_slice(s);
        }
    }
}

/// A contact's three rows `ys` (over its path `p`) scattered side by side
/// onto their dofs in `x3` (`Subspace::x3`).
#[inline(always)]
fn scatter3(x3: &mut [[f64; 3]], p: &[usize], [y0, y1, y2]: [&[f64]; 3]) {
    for (t, &k) in p.iter().enumerate() {
        x3[k] = [y0[t], y1[t], y2[t]];
    }
}

/// [`scatter3`]'s entries put back to zero (`x3` zero between uses).
#[inline(always)]
fn clear3(x3: &mut [[f64; 3]], p: &[usize]) {
    for &k in p {
        x3[k] = [0.0; 3];
    }
}

/// A free row not in the last factor ([`Subspace::map_old`]).
const NEW: usize = usize::MAX;

/// Which rows are a contact's normal (`Rows::is_block`), and W's diagonal and contact blocks
/// (`Rows::w`, `Rows::w_block`, as `Rows::form` made them: not the loop
/// block's reduced ones), for [`Subspace::form_w_ff`].
#[derive(Clone, Copy)]
pub(super) struct OwnBlocks<'a> {
    pub(super) contact: &'a [bool],
    pub(super) diag: (&'a [f64], &'a [[f64; 3]]),
}

impl<'a> OwnBlocks<'a> {
    /// W's own block of the free-row group at row `r` (`s` rows: a contact's
    /// three, or one row), lower triangle, each entry Σₜ yᵢₜ yⱼₜ over the
    /// row's path in its order from −0 (`Rows::form`: W's diagonal ‖yᵣ‖²,
    /// a contact's w_block [y₀·y₁, y₀·y₂, y₁·y₂]); `None` for three rows
    /// that are not a contact's (no w_block), or out of range.
    #[inline]
    pub(super) fn own(&self, r: usize, s: usize) -> Option<[[f64; 3]; 3]> {
        let (w, wb) = self.diag;
        match s {
            1 => Some([[*w.get(r)?, 0.0, 0.0], [0.0; 3], [0.0; 3]]),
            3 if *self.contact.get(r)? => {
                let (d, [o01, o02, o12]) = (w.get(r..r + 3)?, *wb.get(r)?);
                Some([[d[0], 0.0, 0.0], [o01, d[1], 0.0], [o02, o12, d[2]]])
            }
            _ => None,
        }
    }
}

/// The 3 × 3 block Σₜ x3[pₜ][i] zⱼₜ (i, j < 3) of two contacts' rows: `zs`
/// one contact's three rows of y over its path `p`, `x3` the other's
/// scattered to full width; each entry a sum from 0 in path order (the
/// scalar loop's). A free body's path (6 dofs) and two free bodies' (12)
/// at that fixed length, unrolled whole (as `dot3::dot3_from`): the same
/// sums.
///
/// # Safety
/// Every index of `p` is < `x3.len()` (a path's dofs are < nv).
#[inline(always)]
unsafe fn dot3x3(zs: [&[f64]; 3], p: &[usize], x3: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let [z0, z1, z2] = zs;
    let n = p.len().min(z0.len()).min(z1.len()).min(z2.len());
    // SAFETY: the caller's
    at_path_len!(n; z0, z1, z2, p => unsafe { dot3x3_run([z0, z1, z2], p, x3) })
}

/// [`dot3x3`]'s loop (over the shortest of `zs` and `p`): rows 0 and 1 side
/// by side in two SSE2 lanes (x86_64), row 2 alone; each lane the scalar
/// loop's products and sums in its order.
///
/// # Safety
/// As [`dot3x3`]'s.
#[inline(always)]
unsafe fn dot3x3_run([z0, z1, z2]: [&[f64]; 3], p: &[usize], x3: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let n = p.len().min(z0.len()).min(z1.len()).min(z2.len());
    debug_assert!(p[..n].iter().all(|&k| k < x3.len()));
    let mut s = [[0.0f64; 3]; 3];
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of x86_64; t < n ≤ every slice's length, and
        // every k < x3.len() (a path's dofs are < nv)
        unsafe {
            let mut a01 = [_mm_setzero_pd(); 3];
            let mut a2 = [0.0f64; 3];
            for t in 0..n {
                let xk = x3.get_unchecked(*p.get_unchecked(t));
                let z01 = _mm_loadh_pd(_mm_load_sd(z0.as_ptr().add(t)), z1.as_ptr().add(t));
                let z2t = *z2.get_unchecked(t);
                for i in 0..3 {
                    a01[i] = _mm_add_pd(a01[i], _mm_mul_pd(z01, _mm_set1_pd(xk[i])));
                    a2[i] += z2t * xk[i];
                }
            }
            for i in 0..3 {
                _mm_storeu_pd(s[i].as_mut_ptr(), a01[i]);
                s[i][2] = a2[i];
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    for t in 0..n {
        let (xk, zt) = (x3[p[t]], [z0[t], z1[t], z2[t]]);
        for (si, &xi) in s.iter_mut().zip(&xk) {
            for (sij, &zj) in si.iter_mut().zip(&zt) {
                *sij += zj * xi;
            }
        }
    }
    s
}
