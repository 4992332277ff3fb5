//! The rows' Y = J R⁻ᵀ, the Delassus diagonal and the free velocity's J v*
//! (the solve's data, formed once a step from the assembled rows; on the
//! team's threads by ranges of rows above a size: team.rs).

use super::super::parallel::Team;
use super::{MassFactor, RowKind, Rows};

mod team;
mod zero;
pub(super) use team::PARTS;

/// What [`Rows::form`] reads of the rows and writes: their fields borrowed
/// apart, so that a thread of the team forms some rows while another forms
/// others (team.rs). Each block of rows (a contact's three rows, two
/// contacts' six, one row) writes only its own rows' entries.
pub(super) struct Former<'a> {
    st: usize,
    /// The rows a block may reach: the rows in use, or the end of a team's
    /// range (a contact's rows lie below it, [`Former::is_contact`]).
    end: usize,
    kind: &'a [RowKind],
    path: &'a [(usize, usize)],
    table: &'a [usize],
    j: &'a [f64],
    y: &'a mut [f64],
    c: &'a mut [f64],
    w: &'a mut [f64],
    w_block: &'a mut [[f64; 3]],
    is_block: &'a mut [bool],
    winv: &'a mut [f64],
    /// Scratch: a contact's three rows interleaved (`stride` entries).
    lanes: &'a mut [[f64; 4]],
}

impl Rows {
    /// Fills y with the rows of Y = J R⁻ᵀ (H̃ = RᵀR, [`MassFactor`]), each over
    /// its path, the Delassus diagonal Wᵣᵣ = jᵣ·H̃⁻¹jᵣ = ‖yᵣ‖² and c = J v* for
    /// the free velocity `vfree`; counts the step ([`Rows::begin_solve`]).
    pub fn form(&mut self, f: &MassFactor, vfree: &[f64]) {
        self.form_on(f, vfree, None);
    }

    /// [`Rows::form`], by ranges of rows on the threads of `team` where the
    /// rows are many enough to pay a dispatch (team.rs): the same values,
    /// bit for bit, each block formed by the same code whichever thread.
    pub(crate) fn form_on(&mut self, f: &MassFactor, vfree: &[f64], team: Option<&Team>) {
        let (nv, n, st) = (self.nv, self.n, self.stride);
        if vfree.len() < nv || self.j.len() < n * st || self.y.len() < n * st {
            return;
        }
        let shared = team.filter(|t| t.threads() > 1 && n * st >= team::MIN_WORK);
        if !shared.is_some_and(|t| team::form(self, f, vfree, t)) {
            let mut fm = self.former();
            fm.walk(f, vfree, 0, n);
            fm.invert(0, n);
        }
        self.begin_solve();
    }

    /// The rows' fields [`Rows::form`] reads and writes, borrowed apart (the
    /// first `stride` entries of the scratch `lanes`).
    fn former(&mut self) -> Former<'_> {
        let st = self.stride;
        Former {
            st,
            end: self.n,
            kind: &self.kind,
            path: &self.path,
            table: &self.table,
            j: &self.j,
            y: &mut self.y,
            c: &mut self.c,
            w: &mut self.w,
            w_block: &mut self.w_block,
            is_block: &mut self.is_block,
            winv: &mut self.winv,
            lanes: &mut self.lanes[..st],
        }
    }
}

impl Former<'_> {
    /// Forms the blocks of rows from `start` (a block's first row) up to
    /// `end` (where a block begins, or the rows' end): each contact's three
    /// rows together, two contacts on one path of free bodies' chains
    /// together ([`Former::form_pair`]), any other row alone.
    fn walk(&mut self, f: &MassFactor, vfree: &[f64], start: usize, end: usize) {
        let st = self.st;
        self.end = end;
        let table = self.table;
        let mut r = start;
        while r < end {
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
            // (a contact's three flags in one store: its normal's alone set)
            match self.is_block.get_mut(r..r + k) {
                Some(f) if block => f.copy_from_slice(&[true, false, false]),
                Some(f) => f.fill(false),
                None => (self.is_block.iter_mut().skip(r).enumerate())
                    .for_each(|(i, f)| *f = block && i == 0),
            }
            // two contacts between the same two free bodies (6 + 6 dofs, the
            // same path): formed together, one walk of L for both
            // (the same table entries first: a pair's contacts share their union)
            let same = |q: (usize, usize)| q == (ps, pl) || table.get(q.0..q.0 + q.1) == Some(path);
            // (likewise two contacts of one free body on the ground: 6 dofs)
            if block
                && (pl == 12 || pl == 6)
                && self.is_contact(r + 3)
                && same(self.path[r + 3])
                && match pl {
                    12 => self.form_pair::<6, 12>(f, r, path, vfree),
                    _ => self.form_pair::<0, 6>(f, r, path, vfree),
                }
            {
                self.is_block[r + 3..r + 6].copy_from_slice(&[true, false, false]);
                r += 6;
                continue;
            }
            if k == 3 && self.form_lanes(f, r, path, vfree) {
                r += 3;
                continue;
            }
            if k == 1 && self.form_row(f, r, path, vfree) {
                r += 1;
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
    }

    /// Wᵣᵣ⁻¹ of rows `a..b` (0 where Wᵣᵣ ≤ 1e-14).
    fn invert(&mut self, a: usize, b: usize) {
        let (Some(w), Some(wi)) = (self.w.get(a..b), self.winv.get_mut(a..b)) else {
            return;
        };
        for (w, wi) in w.iter().zip(wi.iter_mut()) {
            *wi = if *w > 1e-14 { 1.0 / w } else { 0.0 };
        }
    }

    /// A contact's three rows `r..r + 3` on `path` formed as [`Former::walk`]
    /// does, interleaved in the scratch `lanes` so that the three rows' operations
    /// run side by side (each row's entries get the same operations in the
    /// same order: the same bits). False (nothing done) on a dense factor.
    fn form_lanes(&mut self, f: &MassFactor, r: usize, path: &[usize], vfree: &[f64]) -> bool {
        let (st, pl) = (self.st, path.len());
        if !f.is_tree() || pl > self.lanes.len() || self.j.len() < (r + 3) * st {
            return false;
        }
        // (L zero on a free body's chain, or two's, and the rows plain: Y =
        // J·D^-½ straight from J, zero.rs)
        let zero = match pl {
            6 => f.is_chain_of::<6>(path) && self.form_zero::<6, 6, 3>(f, r, path, vfree),
            12 => f.two_chains::<6, 6>(path) && self.form_zero::<6, 12, 3>(f, r, path, vfree),
            _ => false,
        };
        if zero {
            return true;
        }
        // a chain path (one body's: every contact of a robot on the ground)
        // of up to 13 dofs (a humanoid's foot): in registers, no scratch
        let done = match pl {
            2 => self.form_chain::<2, 0, 2>(f, r, path, vfree),
            3 => self.form_chain::<3, 0, 3>(f, r, path, vfree),
            4 => self.form_chain::<4, 0, 4>(f, r, path, vfree),
            5 => self.form_chain::<5, 0, 5>(f, r, path, vfree),
            6 => self.form_chain::<6, 0, 6>(f, r, path, vfree),
            7 => self.form_chain::<7, 0, 7>(f, r, path, vfree),
            8 => self.form_chain::<8, 0, 8>(f, r, path, vfree),
            9 => self.form_chain::<9, 0, 9>(f, r, path, vfree),
            10 => self.form_chain::<10, 0, 10>(f, r, path, vfree),
            11 => self.form_chain::<11, 0, 11>(f, r, path, vfree),
            12 => self.form_chain::<12, 0, 12>(f, r, path, vfree),
            13 => self.form_chain::<13, 0, 13>(f, r, path, vfree),
            _ => false,
        };
        // two free bodies' chains (6 + 6: a pile's contacts between bodies)
        if done || (pl == 12 && self.form_chain::<6, 6, 12>(f, r, path, vfree)) {
            return true;
        }
        let j = &self.j[r * st..(r + 3) * st];
        let rows = [&j[..pl], &j[st..st + pl], &j[2 * st..2 * st + pl]];
        let c = gather_rows(rows, path, vfree, &mut self.lanes[..pl]);
        f.row_transform_lanes(path, &mut self.lanes[..pl]);
        // (put back below: taking it moves no entry)
        let lanes = std::mem::take(&mut self.lanes);
        self.store_block(r, &lanes[..pl], c);
        self.lanes = lanes;
        true
    }

    /// Row r (not a contact's) on a chain path of 2–12 dofs formed as
    /// [`Former::walk`] does, in registers ([`Former::form_row_chain`]). False
    /// (nothing done) on any other path or a dense factor.
    fn form_row(&mut self, f: &MassFactor, r: usize, path: &[usize], vfree: &[f64]) -> bool {
        if !f.is_tree() {
            return false;
        }
        match path.len() {
            2 => self.form_row_chain::<2>(f, r, path, vfree),
            3 => self.form_row_chain::<3>(f, r, path, vfree),
            4 => self.form_row_chain::<4>(f, r, path, vfree),
            5 => self.form_row_chain::<5>(f, r, path, vfree),
            6 => self.form_row_chain::<6>(f, r, path, vfree),
            7 => self.form_row_chain::<7>(f, r, path, vfree),
            8 => self.form_row_chain::<8>(f, r, path, vfree),
            9 => self.form_row_chain::<9>(f, r, path, vfree),
            10 => self.form_row_chain::<10>(f, r, path, vfree),
            11 => self.form_row_chain::<11>(f, r, path, vfree),
            12 => self.form_row_chain::<12>(f, r, path, vfree),
            _ => false,
        }
    }

    /// [`Former::form_row`] on a chain of `N` dofs ([`MassFactor::chain_row`]):
    /// c = J v* (a sum from 0 in path order), y ← R⁻ᵀ j and Wᵣᵣ = ‖y‖² (a sum
    /// from −0, as `Iterator::sum`), the same operations in the same order as
    /// the general way: the same bits. False, nothing written, where the path
    /// is not the chain.
    #[inline(always)]
    fn form_row_chain<const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let st = self.st;
        let (Some(path), Some(j)) = (path.get(..N), self.j.get(r * st..r * st + N)) else {
            return false;
        };
        if N > st || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let mut y = [0.0f64; N];
        let mut cq = 0.0;
        for ((yt, &d), &jk) in y.iter_mut().zip(path).zip(j) {
            *yt = jk;
            cq += jk * vfree[d];
        }
        if !f.chain_row::<N>(path, &mut y) {
            return false;
        }
        self.c[r] = cq;
        self.y[r * st..r * st + N].copy_from_slice(&y);
        self.w[r] = y.iter().map(|x| x * x).sum();
        true
    }

    /// [`Former::form_lanes`] on a path of `N = A + B` dofs that is a chain
    /// (`B = 0`: [`MassFactor::chain_lanes`]) or two trees' chains
    /// ([`MassFactor::two_chain_lanes`]): the three rows gathered straight
    /// into registers, transformed there, and Y, W and c written
    /// from them (no scratch, no copies between): each value the same
    /// operations in the same order, the same bits. False, nothing written,
    /// where the path is not such chains (the caller's general way then).
    #[inline(always)]
    fn form_chain<const A: usize, const B: usize, const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let st = self.st;
        let (Some(path), Some(j)) = (path.get(..N), self.j.get(r * st..(r + 3) * st)) else {
            return false;
        };
        // (the shape first: a pile's 6 + 6 path is tried as a 12-dof chain
        // before it is tried as two, and its rows are not gathered twice)
        let shape = match B {
            0 => f.is_chain_of::<N>(path),
            _ => f.two_chains::<A, B>(path),
        };
        if N != A + B || N > st || !shape || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        let mut w = [[0.0f64; 4]; N];
        let c = gather_rows(
            [&j[..N], &j[st..st + N], &j[2 * st..2 * st + N]],
            path,
            vfree,
            &mut w,
        );
        let done = match B {
            0 => f.chain_lanes::<N>(path, &mut w),
            _ => f.two_chain_lanes::<A, B>(path, &mut w),
        };
        if !done {
            return false;
        }
        self.store_block(r, &w, c);
        true
    }

    /// Contacts r and r + 3 on the same path of two free bodies' chains
    /// (`B` = 6: 6 + 6 dofs) or of one free body's chain (`B` = 0: 6 dofs,
    /// two contacts of a body on the ground), `N` dofs, formed as
    /// [`Former::form_chain`] forms each ([`MassFactor::two_chain_lanes2`],
    /// [`MassFactor::chain_lanes2`]: one walk of L for both): the same
    /// operations in the same order, the same bits. False, nothing written,
    /// where `path` (contact r + 3's too: the caller's test) is not such chains.
    // (kept out of `form`: inlined there, it costs every other path's rows)
    #[inline(never)]
    fn form_pair<const B: usize, const N: usize>(
        &mut self,
        f: &MassFactor,
        r: usize,
        path: &[usize],
        vfree: &[f64],
    ) -> bool {
        let st = self.st;
        let (Some(path), Some(j)) = (path.get(..N), self.j.get(r * st..(r + 6) * st)) else {
            return false;
        };
        // (the shape first: a robot's foot, one 12-dof chain, is not two
        // chains, and its rows are not gathered twice)
        let shape = match B {
            0 => N == 6 && f.is_chain_of::<N>(path),
            _ => N == 6 + B && f.two_chains::<6, B>(path),
        };
        if N > st || !shape || path.iter().any(|&d| d >= vfree.len()) {
            return false;
        }
        // (L zero on both chains and the rows plain: Y = J·D^-½, zero.rs)
        if self.form_zero::<6, N, 6>(f, r, path, vfree) {
            return true;
        }
        if SIX {
            // the six rows in six lanes a path slot (no pad lane)
            let mut u = [[0.0f64; 6]; N];
            let Some(c) = gather_six(j, st, path, vfree, &mut u) else {
                return false;
            };
            let done = match B {
                0 => f.chain_lanes6::<N>(path, &mut u),
                _ => f.two_chain_lanes6::<6, B>(path, &mut u),
            };
            if done {
                self.store_six(r, &u, c);
            }
            return done;
        }
        let (mut w, mut v) = ([[0.0f64; 4]; N], [[0.0f64; 4]; N]);
        let c = gather_rows(
            [&j[..N], &j[st..st + N], &j[2 * st..2 * st + N]],
            path,
            vfree,
            &mut w,
        );
        let j = &j[3 * st..];
        let e = gather_rows(
            [&j[..N], &j[st..st + N], &j[2 * st..2 * st + N]],
            path,
            vfree,
            &mut v,
        );
        let done = match B {
            0 => f.chain_lanes2::<N>(path, &mut w, &mut v),
            _ => f.two_chain_lanes2::<6, B>(path, &mut w, &mut v),
        };
        if !done {
            return false;
        }
        self.store_block(r, &w, c);
        self.store_block(r + 3, &v, e);
        true
    }

    /// Contacts r's and r + 3's formed blocks from their transformed rows `b`
    /// (one [y₀ₜ … y₅ₜ] a path slot, [`Former::form_pair`]) and c = J v*, as
    /// [`Former::store_block`] stores each.
    #[inline(always)]
    fn store_six(&mut self, r: usize, b: &[[f64; 6]], c: [f64; 6]) {
        let st = self.st;
        // each sum in path order from −0, as store_block's
        let (mut d, mut o) = ([-0.0f64; 6], [-0.0f64; 6]);
        for bt in b {
            add_w(&mut d, &mut o, bt);
        }
        for (k, q) in [(0, r), (3, r + 3)] {
            let y = &mut self.y[q * st..(q + 3) * st];
            let (y0, rest) = y.split_at_mut(st);
            let (y1, y2) = rest.split_at_mut(st);
            for (((bt, a), b1), b2) in b.iter().zip(y0).zip(y1).zip(y2) {
                (*a, *b1, *b2) = (bt[k], bt[k + 1], bt[k + 2]);
            }
            self.c[q..q + 3].copy_from_slice(&c[k..k + 3]);
            self.w[q..q + 3].copy_from_slice(&d[k..k + 3]);
            self.w_block[q] = [o[k], o[k + 1], o[k + 2]];
        }
    }

    /// Contact r's formed block from its transformed rows `b` (one
    /// [y₀ₜ, y₁ₜ, y₂ₜ, 0] a path slot) and c = J v*: Y's three rows, c, W's
    /// diagonal and the block's off-diagonal entries.
    #[inline(always)]
    fn store_block(&mut self, r: usize, b: &[[f64; 4]], c: [f64; 4]) {
        let st = self.st;
        // W's diagonal and the block's off-diagonal entries, each a sum in
        // path order from −0 (as `Iterator::sum` of f64)
        let (mut d, mut o) = ([-0.0f64; 4], [-0.0f64; 4]);
        for bt in b {
            let p = [bt[0] * bt[0], bt[1] * bt[1], bt[2] * bt[2], 0.0];
            let q = [bt[0] * bt[1], bt[0] * bt[2], bt[1] * bt[2], 0.0];
            for i in 0..4 {
                d[i] += p[i];
                o[i] += q[i];
            }
        }
        let y = &mut self.y[r * st..(r + 3) * st];
        let (y0, rest) = y.split_at_mut(st);
        let (y1, y2) = rest.split_at_mut(st);
        for (((bt, a), b1), b2) in b.iter().zip(y0).zip(y1).zip(y2) {
            (*a, *b1, *b2) = (bt[0], bt[1], bt[2]);
        }
        self.c[r..r + 3].copy_from_slice(&c[..3]);
        self.w[r..r + 3].copy_from_slice(&d[..3]);
        self.w_block[r] = [o[0], o[1], o[2]];
    }

    /// Whether row r is a contact normal followed by its two tangent rows on
    /// the same path (as `sim::constraints` pushes them), below `end`.
    #[inline(always)]
    fn is_contact(&self, r: usize) -> bool {
        contact_at(self.kind, self.path, self.end, r)
    }
}

impl Rows {
    /// [`Rows::clear`] that leaves the Jacobian entries of rows `..keep` (the
    /// last assembly's contact triples, rows 3c..3c + 3) unzeroed: the caller
    /// zeroes each triple just before it writes it ([`Rows::zero_contact`])
    /// and the rest after ([`Rows::zero_stale`]), so that a row's zeros and
    /// its entries meet in the cache, not a pass over every row before (on a
    /// thousand-box pile the rows outgrow the cache between the two).
    pub(crate) fn clear_but(&mut self, keep: usize) {
        let n = self.n;
        self.zero_rows(keep.min(n), n);
        // (`clear` then zeroes nothing more: rows 0..0)
        self.n = 0;
        self.clear();
    }

    /// Zeroes what the last assembly wrote of rows `r..r + 3`, one contact's
    /// three rows on one path then (as [`Rows::clear`]'s pass would), before
    /// they are pushed again: call it with `r = self.n`, below `clear_but`'s
    /// `keep`.
    pub(crate) fn zero_contact(&mut self, r: usize) {
        self.zero_rows(r, r + 3);
    }

    /// Zeroes the rows `self.n..keep` ([`Rows::clear_but`]) not pushed again.
    pub(crate) fn zero_stale(&mut self, keep: usize) {
        let n = self.n;
        if n < keep {
            self.zero_rows(n, keep);
        }
    }

    /// Whether row r is a contact normal followed by its two tangent rows on
    /// the same path (as `sim::constraints` pushes them).
    #[inline(always)]
    pub(super) fn is_contact(&self, r: usize) -> bool {
        contact_at(&self.kind, &self.path, self.n, r)
    }
}

/// Whether row r of rows `..end` (kinds `kind`, paths `path`) is a contact
/// normal followed by its two tangent rows on the same path.
#[inline(always)]
fn contact_at(kind: &[RowKind], path: &[(usize, usize)], end: usize, r: usize) -> bool {
    r + 2 < end
        && kind[r] == RowKind::Normal
        && matches!(kind[r + 1], RowKind::Tangent { normal, .. } if normal == r)
        && kind[r + 2] == RowKind::Tangent2
        && path[r + 1] == path[r]
        && path[r + 2] == path[r]
}

/// Whether [`Former::form_pair`] holds its two contacts' six rows in six
/// lanes a path slot (SSE: three registers a slot, not four with a pad lane
/// each; with AVX the two blocks' [f64; 4] are two registers a slot either way).
const SIX: bool = cfg!(not(target_feature = "avx"));

/// One path slot's transformed rows `bt` (one contact's three, `R` = 3, or
/// two contacts' six, `R` = 6) added to W's diagonal `d` (d_i += y_i²) and
/// each block's off-diagonal entries `o` (y₀y₁, y₀y₂, y₁y₂ and y₃y₄, y₃y₅,
/// y₄y₅): the sums' next terms, in path order.
#[inline(always)]
fn add_w<const R: usize>(d: &mut [f64; R], o: &mut [f64; R], bt: &[f64; R]) {
    let mut q = [0.0f64; R];
    for k in 0..R / 3 {
        let k = 3 * k;
        (q[k], q[k + 1], q[k + 2]) = (bt[k] * bt[k + 1], bt[k] * bt[k + 2], bt[k + 1] * bt[k + 2]);
    }
    for i in 0..R {
        d[i] += bt[i] * bt[i];
        o[i] += q[i];
    }
}

/// c = J v* over two contacts' six rows (`j`, `stride` apart) on `path`
/// (each row's sum from 0 in path order, as [`gather_rows`]'), the rows
/// gathered into `out`, one [j₀ₜ … j₅ₜ] a path slot; `None` where `j` is
/// short.
#[inline(always)]
fn gather_six<const N: usize>(
    j: &[f64],
    st: usize,
    path: &[usize],
    vfree: &[f64],
    out: &mut [[f64; 6]; N],
) -> Option<[f64; 6]> {
    let row = |i: usize| -> Option<&[f64; N]> { j.get(i * st..i * st + N)?.try_into().ok() };
    let rows = [row(0)?, row(1)?, row(2)?, row(3)?, row(4)?, row(5)?];
    let mut c = [0.0f64; 6];
    for (t, (o, &d)) in out.iter_mut().zip(path).enumerate() {
        let x = vfree[d];
        for i in 0..6 {
            let b = rows[i][t];
            o[i] = b;
            c[i] += b * x;
        }
    }
    Some(c)
}

/// c = J v* over a contact's three rows `j` on `path` (each row's sum from 0
/// in path order), the rows gathered into `out`, one [j₀ₜ, j₁ₜ, j₂ₜ, 0] a
/// path slot.
#[inline(always)]
fn gather_rows(j: [&[f64]; 3], path: &[usize], vfree: &[f64], out: &mut [[f64; 4]]) -> [f64; 4] {
    let mut c = [0.0f64; 4];
    let rows = j[0].iter().zip(j[1]).zip(j[2]);
    for ((o, &d), ((&j0, &j1), &j2)) in out.iter_mut().zip(path).zip(rows) {
        let b = [j0, j1, j2, 0.0];
        *o = b;
        let x = vfree[d];
        for (ci, &bi) in c.iter_mut().zip(b.iter()) {
            *ci += bi * x;
        }
    }
    c
}
