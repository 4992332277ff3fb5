//! [`Former::form_pair`] on chains of zeros (factor/zeros.rs): where L is
//! zero on the pair's chains and its rows are plain, no elimination step
//! changes a bit and Y = J·D^-½ entry by entry (docs/theory.md §"Tree-sparse
//! LTDL"). The six rows are then formed slot by slot straight from J into Y
//! and the sums, without the gather into lanes and the store back:
//! every value the lanes' form gives, each sum in path order as there
//! (`gather_six`, `store_six`).

use super::super::MassFactor;
use super::{add_w_six, Former};

impl Former<'_> {
    /// Contacts r's and r + 3's rows (six rows of J, N path slots; chains
    /// ending at `path[A − 1]` and `path[N − 1]`) formed where L is zero on
    /// both chains and the rows plain ([`MassFactor::zero_scale`]): Y's six
    /// rows, c = J v*, W's diagonal and the blocks'
    /// off-diagonal entries. False, nothing written, elsewhere.
    #[inline(always)]
    pub(super) fn form_zero_pair<const A: usize, const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let (st, j) = (self.st, self.j);
        let row = |i: usize| -> Option<&[f64; N]> {
            j.get((r + i) * st..(r + i) * st + N)?.try_into().ok()
        };
        let (Some(j0), Some(j1), Some(j2), Some(j3), Some(j4), Some(j5)) =
            (row(0), row(1), row(2), row(3), row(4), row(5))
        else {
            return false;
        };
        let rows = [j0, j1, j2, j3, j4, j5];
        let Some(path) = path.get(..N).and_then(|p| <&[usize; N]>::try_from(p).ok()) else {
            return false;
        };
        let Some(s) = f.zero_scale::<A, N, 6>(path, &rows) else {
            return false;
        };
        // Y's six rows, N slots each
        let Some(y) = self.y.get_mut(r * st..(r + 6) * st) else {
            return false;
        };
        let mut ys = y.chunks_exact_mut(st).map(|q| &mut q[..N]);
        let (Some(y0), Some(y1), Some(y2), Some(y3), Some(y4), Some(y5)) = (
            ys.next(),
            ys.next(),
            ys.next(),
            ys.next(),
            ys.next(),
            ys.next(),
        ) else {
            return false;
        };
        // c = J v* from 0, W's diagonal and off-diagonal sums from −0, each in
        // path order (gather_six's and store_six's order)
        let (mut c, mut d, mut o) = ([0.0f64; 6], [-0.0f64; 6], [-0.0f64; 6]);
        for t in 0..N {
            let x = vfree[path[t]];
            let b = [j0[t], j1[t], j2[t], j3[t], j4[t], j5[t]];
            // y = j·D^-½ (the chain's steps change no bit)
            let mut e = [0.0f64; 6];
            for i in 0..6 {
                c[i] += b[i] * x;
                e[i] = b[i] * s[t];
            }
            add_w_six(&mut d, &mut o, &e);
            (y0[t], y1[t], y2[t]) = (e[0], e[1], e[2]);
            (y3[t], y4[t], y5[t]) = (e[3], e[4], e[5]);
        }
        for (k, q) in [(0, r), (3, r + 3)] {
            self.c[q..q + 3].copy_from_slice(&c[k..k + 3]);
            self.w[q..q + 3].copy_from_slice(&d[k..k + 3]);
            self.w_block[q] = [o[k], o[k + 1], o[k + 2]];
        }
        true
    }

    /// Contact r's three rows (N path slots; chains ending at `path[A − 1]`
    /// and `path[N − 1]`, one where A = N) formed where L is zero on the
    /// chains and the rows plain ([`MassFactor::zero_scale`]), as
    /// [`Former::form_zero_pair`] forms a pair's: Y's three rows, c = J v*,
    /// W's diagonal and the block's off-diagonal entries, each value what
    /// the lanes' form gives (`gather_rows`, the chain's scale, `store_block`:
    /// the same operations in path order). False, nothing written, elsewhere.
    #[inline(always)]
    pub(super) fn form_zero_three<const A: usize, const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let (st, j) = (self.st, self.j);
        let row = |i: usize| -> Option<&[f64; N]> {
            j.get((r + i) * st..(r + i) * st + N)?.try_into().ok()
        };
        let (Some(j0), Some(j1), Some(j2)) = (row(0), row(1), row(2)) else {
            return false;
        };
        let Some(path) = path.get(..N).and_then(|p| <&[usize; N]>::try_from(p).ok()) else {
            return false;
        };
        if N > st || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let Some(s) = f.zero_scale::<A, N, 3>(path, &[j0, j1, j2]) else {
            return false;
        };
        let Some(y) = self.y.get_mut(r * st..(r + 3) * st) else {
            return false;
        };
        let (y0, rest) = y.split_at_mut(st);
        let (y1, y2) = rest.split_at_mut(st);
        let (y0, y1, y2) = (&mut y0[..N], &mut y1[..N], &mut y2[..N]);
        // c = J v* from 0, W's diagonal and off-diagonal sums from −0, each in
        // path order (gather_rows' and store_block's order)
        let (mut c, mut d, mut o) = ([0.0f64; 3], [-0.0f64; 3], [-0.0f64; 3]);
        for t in 0..N {
            let x = vfree[path[t]];
            let b = [j0[t], j1[t], j2[t]];
            // y = j·D^-½ (the chain's steps change no bit)
            let e = [b[0] * s[t], b[1] * s[t], b[2] * s[t]];
            let q = [e[0] * e[1], e[0] * e[2], e[1] * e[2]];
            for i in 0..3 {
                c[i] += b[i] * x;
                d[i] += e[i] * e[i];
                o[i] += q[i];
            }
            (y0[t], y1[t], y2[t]) = (e[0], e[1], e[2]);
        }
        self.c[r..r + 3].copy_from_slice(&c);
        self.w[r..r + 3].copy_from_slice(&d);
        self.w_block[r] = o;
        true
    }
}
