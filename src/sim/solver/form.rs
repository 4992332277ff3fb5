//! The rows' Y = J R⁻ᵀ, the Delassus diagonal and the free velocity's J v*
//! (the solve's data, formed once a step from the assembled rows).

use super::{MassFactor, RowKind, Rows};

impl Rows {
    /// Fills y with the rows of Y = J R⁻ᵀ (H̃ = RᵀR, [`MassFactor`]), each over
    /// its path, the Delassus diagonal Wᵣᵣ = jᵣ·H̃⁻¹jᵣ = ‖yᵣ‖² and c = J v* for
    /// the free velocity `vfree`.
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
