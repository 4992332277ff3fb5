//! [`Former::form_pair`] and [`Former::form_lanes`] on chains of zeros
//! (factor/zeros.rs): where L is zero on the contacts' chains and their rows
//! are plain, no elimination step changes a bit and Y = J·D^-½ entry by
//! entry (docs/theory.md §"Tree-sparse LTDL"). The rows are then formed slot
//! by slot straight from J into Y and the sums, without the gather into
//! lanes and the store back: every value the lanes' form gives, each sum in
//! path order as there (`gather_six`, `store_six`; `gather_rows`,
//! `store_block`).

use super::super::MassFactor;
use super::{add_w, Former};

impl Former<'_> {
    /// Contact r's three rows (`R` = 3) or contacts r's and r + 3's six (`R`
    /// = 6) on N path slots (chains ending at `path[A − 1]` and
    /// `path[N − 1]`, one where A = N) formed where L is zero on the chains
    /// and the rows plain ([`MassFactor::zero_scale`]): Y's R rows, c = J v*,
    /// W's diagonal and each block's off-diagonal entries, each value what
    /// the lanes' form gives (`gather_rows` or `gather_six`, the chain's
    /// scale, `store_block` or `store_six`: the same operations in path
    /// order). False, nothing written, elsewhere.
    #[inline(always)]
    pub(super) fn form_zero<const A: usize, const N: usize, const R: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        debug_assert!(R == 3 || R == 6);
        let (st, j) = (self.st, self.j);
        let mut rows: [&[f64; N]; R] = [&const { [0.0f64; N] }; R];
        for (i, q) in rows.iter_mut().enumerate() {
            let Some(x) = j.get((r + i) * st..(r + i) * st + N) else {
                return false;
            };
            let Ok(x) = x.try_into() else {
                return false;
            };
            *q = x;
        }
        let Some(path) = path.get(..N).and_then(|p| <&[usize; N]>::try_from(p).ok()) else {
            return false;
        };
        if N > st || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let Some(s) = f.zero_scale::<A, N, R>(path, &rows) else {
            return false;
        };
        // Y's R rows, N slots each
        let Some(y) = self.y.get_mut(r * st..(r + R) * st) else {
            return false;
        };
        let y = y.as_mut_ptr();
        // c = J v* from 0, W's diagonal and off-diagonal sums from −0, each in
        // path order (the gather's and the store's order)
        let (mut c, mut d, mut o) = ([0.0f64; R], [-0.0f64; R], [-0.0f64; R]);
        for t in 0..N {
            let x = vfree[path[t]];
            // y = j·D^-½ (the chain's steps change no bit)
            let mut e = [0.0f64; R];
            for i in 0..R {
                let b = rows[i][t];
                c[i] += b * x;
                e[i] = b * s[t];
            }
            add_w(&mut d, &mut o, &e);
            for (i, &e) in e.iter().enumerate() {
                // SAFETY: row i's slot t, i·st + t < R·st (t < N ≤ st, tested
                // above), lies in the R·st entries `y` points at
                unsafe { *y.add(i * st + t) = e };
            }
        }
        for k in 0..R / 3 {
            let (k, q) = (3 * k, r + 3 * k);
            self.c[q..q + 3].copy_from_slice(&c[k..k + 3]);
            self.w[q..q + 3].copy_from_slice(&d[k..k + 3]);
            self.w_block[q] = [o[k], o[k + 1], o[k + 2]];
        }
        true
    }
}
