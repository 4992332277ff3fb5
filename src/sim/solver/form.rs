//! The rows' Y = J R⁻ᵀ, the Delassus diagonal and the free velocity's J v*
//! (the solve's data, formed once a step from the assembled rows).

use super::{MassFactor, RowKind, Rows};

impl Rows {
    /// Fills y with the rows of Y = J R⁻ᵀ (H̃ = RᵀR, [`MassFactor`]), each over
    /// its path, the Delassus diagonal Wᵣᵣ = jᵣ·H̃⁻¹jᵣ = ‖yᵣ‖² and c = J v* for
    /// the free velocity `vfree`; counts the step ([`Rows::begin_solve`]).
    pub fn form(&mut self, f: &MassFactor, vfree: &[f64]) {
        let (nv, n, st) = (self.nv, self.n, self.stride);
        if vfree.len() < nv || self.j.len() < n * st || self.y.len() < n * st {
            return;
        }
        // (the table is put back below: taking it moves no entry)
        let table_v = std::mem::take(&mut self.table);
        let table = &table_v[..];
        let mut r = 0;
        while r < n {
            let (ps, pl) = self.path[r];
            let Some(path) = table.get(ps..ps + pl).filter(|p| p.len() <= st) else {
                if let Some(b) = self.is_block.get_mut(r) {
                    *b = false;
                }
                r += 1;
                continue;
            };
            // a contact's three rows share the path: gathered, then transformed
            // in one pass over the factor
            let block = self.is_contact(r);
            let k = if block { 3 } else { 1 };
            for q in r..(r + k).min(self.is_block.len()) {
                self.is_block[q] = block && q == r;
            }
            if k == 3 && self.form_lanes(f, r, path, vfree) {
                r += 3;
                continue;
            }
            for q in r..r + k {
                let jr = &self.j[q * st..q * st + pl];
                let yr = &mut self.y[q * st..q * st + pl];
                let mut cq = 0.0;
                for ((yt, &d), &jk) in yr.iter_mut().zip(path).zip(jr) {
                    *yt = jk;
                    cq += jk * vfree[d];
                }
                self.c[q] = cq;
            }
            if k == 3 {
                let (a, rest) = self.y[r * st..].split_at_mut(st);
                let (b, c) = rest.split_at_mut(st);
                let (y0, y1, y2) = (&mut a[..pl], &mut b[..pl], &mut c[..pl]);
                f.row_transform3(path, y0, y1, y2);
                if let Some(yl) = self.ylanes.get_mut(r * st..r * st + pl) {
                    for (t, l) in yl.iter_mut().enumerate() {
                        *l = [y0[t], y1[t], y2[t], 0.0];
                    }
                }
                let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
                self.w[r] = dot(y0, y0);
                self.w[r + 1] = dot(y1, y1);
                self.w[r + 2] = dot(y2, y2);
                self.w_block[r] = [dot(y0, y1), dot(y0, y2), dot(y1, y2)];
            } else {
                let yr = &mut self.y[r * st..r * st + pl];
                f.row_transform(path, yr);
                self.w[r] = yr.iter().map(|x| x * x).sum();
            }
            r += k;
        }
        for (w, wi) in self.w[..n].iter().zip(self.winv.iter_mut()) {
            *wi = if *w > 1e-14 { 1.0 / w } else { 0.0 };
        }
        self.table = table_v;
        self.begin_solve();
    }

    /// A contact's three rows `r..r + 3` on `path` formed as [`Rows::form`]
    /// does, interleaved in [`Rows::lanes`] so that the three rows' operations
    /// run side by side (each row's entries get the same operations in the
    /// same order: the same bits). False (nothing done) on a dense factor.
    fn form_lanes(&mut self, f: &MassFactor, r: usize, path: &[usize], vfree: &[f64]) -> bool {
        let (st, pl) = (self.stride, path.len());
        if !f.is_tree() || pl > self.lanes.len() || self.j.len() < (r + 3) * st {
            return false;
        }
        // a chain path (one body's: every contact of a robot on the ground)
        // of up to 12 dofs: in registers, no scratch
        let done = match pl {
            2 => self.form_chain::<2>(f, r, path, vfree),
            3 => self.form_chain::<3>(f, r, path, vfree),
            4 => self.form_chain::<4>(f, r, path, vfree),
            5 => self.form_chain::<5>(f, r, path, vfree),
            6 => self.form_chain::<6>(f, r, path, vfree),
            7 => self.form_chain::<7>(f, r, path, vfree),
            8 => self.form_chain::<8>(f, r, path, vfree),
            9 => self.form_chain::<9>(f, r, path, vfree),
            10 => self.form_chain::<10>(f, r, path, vfree),
            11 => self.form_chain::<11>(f, r, path, vfree),
            12 => self.form_chain::<12>(f, r, path, vfree),
            _ => false,
        };
        if done {
            return true;
        }
        let buf = &mut self.lanes[..pl];
        let j = &self.j[r * st..(r + 3) * st];
        let (j0, j1, j2) = (&j[..pl], &j[st..st + pl], &j[2 * st..2 * st + pl]);
        // c = J v*, each row's sum from 0 in path order
        let mut c = [0.0f64; 4];
        for (t, (b, &d)) in buf.iter_mut().zip(path).enumerate() {
            *b = [j0[t], j1[t], j2[t], 0.0];
            let x = vfree[d];
            for (ci, &bi) in c.iter_mut().zip(b.iter()) {
                *ci += bi * x;
            }
        }
        f.row_transform_lanes(path, buf);
        // W's diagonal and the block's off-diagonal entries, each a sum in
        // path order from −0 (as `Iterator::sum` of f64)
        let (mut d, mut o) = ([-0.0f64; 4], [-0.0f64; 4]);
        for b in buf.iter() {
            let p = [b[0] * b[0], b[1] * b[1], b[2] * b[2], 0.0];
            let q = [b[0] * b[1], b[0] * b[2], b[1] * b[2], 0.0];
            for i in 0..4 {
                d[i] += p[i];
                o[i] += q[i];
            }
        }
        let y = &mut self.y[r * st..(r + 3) * st];
        let (y0, rest) = y.split_at_mut(st);
        let (y1, y2) = rest.split_at_mut(st);
        for (t, b) in buf.iter().enumerate() {
            y0[t] = b[0];
            y1[t] = b[1];
            y2[t] = b[2];
        }
        if let Some(yl) = self.ylanes.get_mut(r * st..r * st + pl) {
            yl.copy_from_slice(buf);
        }
        self.c[r..r + 3].copy_from_slice(&c[..3]);
        self.w[r..r + 3].copy_from_slice(&d[..3]);
        self.w_block[r] = [o[0], o[1], o[2]];
        true
    }

    /// [`Rows::form_lanes`] on a chain path of `N` dofs
    /// ([`MassFactor::chain_lanes`]): the three rows gathered straight into
    /// registers, transformed there, and Y, its lanes, W and c written from
    /// them (no scratch, no copies between): each value the same operations
    /// in the same order, the same bits. False, nothing written, where the
    /// path is not a chain of `N` (the caller's general way then).
    #[inline(always)]
    fn form_chain<const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let st = self.stride;
        let (Some(path), Some(j)) = (path.get(..N), self.j.get(r * st..(r + 3) * st)) else {
            return false;
        };
        if N > st || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let (j0, j1, j2) = (&j[..N], &j[st..st + N], &j[2 * st..2 * st + N]);
        // c = J v*, each row's sum from 0 in path order
        let mut w = [[0.0f64; 4]; N];
        let mut c = [0.0f64; 4];
        for t in 0..N {
            let b = [j0[t], j1[t], j2[t], 0.0];
            w[t] = b;
            let x = vfree[path[t]];
            for (ci, &bi) in c.iter_mut().zip(b.iter()) {
                *ci += bi * x;
            }
        }
        if !f.chain_lanes::<N>(path, &mut w) {
            return false;
        }
        // W's diagonal and the block's off-diagonal entries, each a sum in
        // path order from −0 (as `Iterator::sum` of f64)
        let (mut d, mut o) = ([-0.0f64; 4], [-0.0f64; 4]);
        for b in w.iter() {
            let p = [b[0] * b[0], b[1] * b[1], b[2] * b[2], 0.0];
            let q = [b[0] * b[1], b[0] * b[2], b[1] * b[2], 0.0];
            for i in 0..4 {
                d[i] += p[i];
                o[i] += q[i];
            }
        }
        let y = &mut self.y[r * st..(r + 3) * st];
        let (y0, rest) = y.split_at_mut(st);
        let (y1, y2) = rest.split_at_mut(st);
        let yl = self.ylanes.get_mut(r * st..r * st + N);
        for (t, b) in w.iter().enumerate() {
            y0[t] = b[0];
            y1[t] = b[1];
            y2[t] = b[2];
        }
        if let Some(yl) = yl {
            for (l, b) in yl.iter_mut().zip(w.iter()) {
                *l = *b;
            }
        }
        self.c[r..r + 3].copy_from_slice(&c[..3]);
        self.w[r..r + 3].copy_from_slice(&d[..3]);
        self.w_block[r] = [o[0], o[1], o[2]];
        true
    }

    /// Whether row r is a contact normal followed by its two tangent rows on
    /// the same path (as `sim::constraints` pushes them).
    #[inline]
    pub(super) fn is_contact(&self, r: usize) -> bool {
        r + 2 < self.n
            && self.kind[r] == RowKind::Normal
            && matches!(self.kind[r + 1], RowKind::Tangent { normal, .. } if normal == r)
            && self.kind[r + 2] == RowKind::Tangent2
            && self.path[r + 1] == self.path[r]
            && self.path[r + 2] == self.path[r]
    }
}
