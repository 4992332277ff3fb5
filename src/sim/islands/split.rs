//! The solve's islands split by the contacts likely active (issue #30;
//! docs/theory.md §"Islands").
//!
//! A contact's rows are made for every point within the contact margin and
//! the speculative margin, and most of a pile's points there carry no
//! impulse: a third to two fifths of a big island's contacts stay at λ = 0
//! through its whole solve. Joining trees through them makes islands larger
//! than the impulses couple, and projected Gauss–Seidel's rate falls with an
//! island's size. So a contact joins its two trees for the solve only when
//! it is likely to push this step, and each contact (its three rows) is
//! left out on its own, at λ = 0, when none of these holds: its normal's
//! free velocity closes the gap this step (cᵣ < bᵣ), it was warm-started
//! with an impulse (last step's λ ≠ 0 on one of its rows), its position is
//! violated (b_pos > 0), or the warm start's Δv' (every row's λ_warm yᵣ,
//! [`Rows::warm_velocity`], made once and taken by each island as its own
//! start) leaves its normal less than [`MARGIN`] above its target. Steps of
//! fewer than [`MIN_ROWS`] rows are not split.
//!
//! λ = 0 on a left-out point is its solution exactly when uₙ ≥ bₙ at the
//! solved velocities (its tangents are then held at 0 by the cone of radius
//! μλₙ = 0): that is checked for every left-out point once the islands are
//! solved, to the solve's tolerance (a row's own residual, the measure the
//! sweeps stop on). Where it fails, the contact joins its trees, the islands
//! of those trees are merged into one new island (nothing else rebuilt), and
//! it is solved again, warm from the split solution; the rest stand (their
//! rows and dofs are untouched by it), and only the left-out points on a
//! re-solved island are checked again. The end is a solution of
//! the whole rows' conditions, to the same tolerance as one solve of them.
//! The position pass runs on the islands of every contact: before it, the
//! left-out contacts on an island it pushes join it ([`Islands::join_pushed`]).
//!
//! The sleep islands (src/sim/sleep.rs) are not these: they join trees by
//! every point, as before.

use super::{Islands, LEFT};
use crate::sim::solver::Rows;

/// A contact is left out only when the warm start leaves its normal this
/// much above its target (m/s).
const MARGIN: f64 = 1e-3;

/// A step is split only with at least this many rows (64 contacts): below
/// it the warm start and the checks cost more than the sweeps saved (mixed
/// 16 pile, 81 rows a solve at the median: +3.7 % instructions of split
/// bookkeeping against −2 % of sweeps; boxes 64, 330 rows: −6.4 % in all).
pub(super) const MIN_ROWS: usize = 192;

impl Islands {
    /// Marks the contacts of group `g` (rows `s..e`, on trees `a` and `b`)
    /// left out of the solve: contact triples none likely to push this step
    /// ([`Rows::contact_idle`]). Returns whether the group keeps a row (it
    /// joins its trees).
    pub(super) fn leave_out(
        &mut self,
        rows: &Rows,
        g: usize,
        s: usize,
        e: usize,
        a: usize,
        b: usize,
    ) -> bool {
        if !self.triples[g] && !rows.contacts_only(s, e) {
            return true;
        }
        let (mut kept, mut part) = (false, false);
        let mut r = s;
        while r < e {
            if rows.contact_idle(r, &self.warm, MARGIN) {
                self.out[r] = true;
                self.left.push((r, g, a, b));
                part = true;
            } else {
                kept = true;
            }
            r += 3;
        }
        self.gpart[g] = part;
        kept
    }

    /// Checks the left-out contacts at the solved Δv' `x`, to `tol`: after a
    /// grouping every one, then only those on a tree of an island solved
    /// since the last check (the others' velocities have not moved). Each
    /// that fails joins its two trees and leaves the left-out list; the
    /// islands it joins are merged into one new island (their runs and the
    /// contact's rows, in row order; their dofs and its path's, ascending),
    /// the old ones emptied, and the new ones are the islands to solve
    /// ([`Islands::todo`]). Returns whether any joined.
    pub fn join_failed(&mut self, rows: &Rows, x: &[f64], tol: f64) -> bool {
        self.fails.clear();
        let mut keep = 0;
        for i in 0..self.left.len() {
            let (r, g, a, b) = self.left[i];
            let moved = self.check_all || {
                let (ra, rb) = (self.find(a), self.find(b));
                self.touched[ra] || self.touched[rb]
            };
            if !moved || rows.contact_holds(r, x, tol) {
                self.left[keep] = self.left[i];
                keep += 1;
                continue;
            }
            self.fails.push((r, g, a, b));
        }
        self.left.truncate(keep);
        self.check_all = false;
        self.touched.fill(false);
        if self.fails.is_empty() {
            return false;
        }
        // the pieces of the new islands: the islands of the failed contacts'
        // trees (before their unions), and the contacts' rows
        self.pieces.clear();
        for i in 0..self.fails.len() {
            let (r, _, a, b) = self.fails[i];
            for t in [a, b] {
                let ri = self.find(t);
                self.piece_island(t, ri);
            }
            self.pieces.push((a, 1, r));
        }
        self.unpiece();
        for i in 0..self.fails.len() {
            let (r, g, a, b) = self.fails[i];
            let (ra, rb) = (self.find(a), self.find(b));
            if ra != rb {
                self.parent[ra.max(rb)] = ra.min(rb);
            }
            self.out[r] = false;
            if self.gtree[g] == LEFT {
                self.gtree[g] = a;
            }
        }
        self.merge(rows, true);
        true
    }

    /// Lists the island rooted at `root` (if any) among the join's pieces as
    /// (`t`, 0, island), once: a second listing maps to the same root in
    /// [`Islands::merge`] and would be dropped there as a duplicate.
    fn piece_island(&mut self, t: usize, root: usize) {
        let k = self.iof[root];
        if k != usize::MAX && !self.pieced[root] {
            self.pieced[root] = true;
            self.pieces.push((t, 0, k));
        }
    }

    /// Clears the pieces' marks (`pieced`, at their islands' roots).
    fn unpiece(&mut self) {
        for &(_, kind, k) in &self.pieces {
            if kind == 0 {
                self.pieced[self.iroot[k]] = false;
            }
        }
        debug_assert!(self.pieced.iter().all(|&p| !p));
    }

    /// The new islands of a join from its `pieces` (tree, 0, an island of
    /// its root before the join) and (tree, 1, a joined contact's first
    /// row): per root (after the join's unions) one new island, its runs
    /// those of its pieces' islands and the contacts' rows in row order
    /// (adjacent runs one), its dofs theirs and the contacts' paths',
    /// ascending, once each; the merged islands emptied. The new ones are
    /// the islands to solve ([`Islands::todo`]), their roots `touched`.
    /// Without `sort_dofs`, the dofs are listed once each in no order.
    fn merge(&mut self, rows: &Rows, sort_dofs: bool) {
        for i in 0..self.pieces.len() {
            let t = self.pieces[i].0;
            self.pieces[i].0 = self.find(t);
        }
        // (sorted as a merge of its ascending stretches: a join's rows are
        // listed in row order, pass by pass, mostly onto one root)
        merge_stretches(&mut self.pieces, &mut self.sorted, |&p| p);
        self.pieces.dedup();
        self.todo.clear();
        let (table, path) = (rows.table(), &rows.path[..]);
        let mut i = 0;
        while i < self.pieces.len() {
            let root = self.pieces[i].0;
            let (r0, d0) = (self.runs.len(), self.dofs.len());
            while i < self.pieces.len() && self.pieces[i].0 == root {
                let (_, kind, k) = self.pieces[i];
                i += 1;
                if kind == 0 {
                    // an island merged: its runs and dofs moved, it emptied
                    let ((s0, s1), (e0, e1)) = self.islands[k];
                    for j in s0..s1 {
                        let (_, s, e) = self.runs[j];
                        self.runs.push((root, s, e));
                    }
                    for j in e0..e1 {
                        let d = self.dofs[j];
                        if let Some(m) = self.mark.get_mut(d) {
                            *m = true;
                        }
                        self.dofs.push(d);
                    }
                    self.islands[k] = ((s0, s0), (e0, e0));
                    // (its root's entry cleared: it may root no island now)
                    if let Some(x) = self.iof.get_mut(self.iroot[k])
                        && *x == k
                    {
                        *x = usize::MAX;
                    }
                    self.iroot[k] = LEFT;
                } else {
                    self.runs.push((root, k, k + 3));
                    let (ps, pl) = path.get(k).copied().unwrap_or((0, 0));
                    // (a path's dofs are mostly its trees' islands' already)
                    for &d in table.get(ps..ps + pl).unwrap_or(&[]) {
                        if let Some(m) = self.mark.get_mut(d)
                            && !*m
                        {
                            *m = true;
                            self.dofs.push(d);
                        }
                    }
                }
            }
            // row order, adjacent runs one
            // (each piece's runs in order already: their stretches merged,
            // not sorted anew — a sort of the pile's big islands cost more
            // than the rebuild this replaces, round 29)
            let runs = &mut self.runs[r0..];
            merge_stretches(runs, &mut self.sorted, |run| run.1);
            let mut w = 0;
            for j in 0..runs.len() {
                if w > 0 && runs[w - 1].2 == runs[j].1 {
                    runs[w - 1].2 = runs[j].2;
                } else {
                    runs[w] = runs[j];
                    w += 1;
                }
            }
            self.runs.truncate(r0 + w);
            // once each (the marks cleared), ascending with `sort_dofs`
            let dofs = &mut self.dofs[d0..];
            for &d in dofs.iter() {
                if let Some(m) = self.mark.get_mut(d) {
                    *m = false;
                }
            }
            if sort_dofs {
                merge_stretches(dofs, &mut self.dof_tmp, |&d| d);
            }
            let ni = self.islands.len();
            self.islands
                .push(((r0, self.runs.len()), (d0, self.dofs.len())));
            self.iroot.push(root);
            self.iof[root] = ni;
            self.touched[root] = true;
            self.todo.push(ni);
        }
    }

    /// The position pass's islands: every left-out contact on an island
    /// with a violated row (b_pos ≠ 0, the islands the pass pushes) joins
    /// it, and so on from the islands so grown; the islands so joined are
    /// merged as [`Islands::join_failed`] merges (the same rows in row order
    /// and the same dofs as a new grouping gives, the others untouched: a
    /// rebuild of every island cost twice this on the mixed piles). The
    /// pushed islands are then those of every contact (the sleep
    /// islands' rows, in row order); the rest are not pushed (w' = 0 on
    /// them), so every contact still left out holds (yₙ·w' = 0 ≥ b_pos = 0)
    /// and none is checked. (Left out, a point the pass pushes in would be
    /// found only after the pass, and its island pushed again: mixed 256,
    /// 22.7 such joins a solve in 1.7 rounds, docs/theory.md §"Islands".)
    pub fn join_pushed(&mut self, rows: &Rows) {
        if self.left.is_empty() {
            return;
        }
        // the pushed islands' roots
        self.touched.fill(false);
        for i in 0..self.islands.len() {
            let ((r0, r1), _) = self.islands[i];
            let pushed = self.runs[r0..r1]
                .iter()
                .any(|&(_, s, e)| rows.violated(s, e));
            if pushed && let Some(t) = self.touched.get_mut(self.iroot[i]) {
                *t = true;
            }
        }
        let mut any = false;
        self.pieces.clear();
        loop {
            let (mut more, mut keep) = (false, 0);
            for i in 0..self.left.len() {
                let (r, g, a, b) = self.left[i];
                let (ra, rb) = (self.find(a), self.find(b));
                if !(self.touched[ra] || self.touched[rb]) {
                    self.left[keep] = self.left[i];
                    keep += 1;
                    continue;
                }
                // the pieces of the new islands (`merge`): the islands of its
                // trees' roots (each a root before the join: a union's root
                // is one of its two) and its rows
                for t in [ra, rb] {
                    self.piece_island(t, t);
                }
                self.pieces.push((a, 1, r));
                // (the touched trees grow when one side was not: else no
                // contact skipped in this pass joins in the next)
                more |= !(self.touched[ra] && self.touched[rb]);
                if ra != rb {
                    self.parent[ra.max(rb)] = ra.min(rb);
                    self.touched[ra.min(rb)] = true;
                }
                self.out[r] = false;
                if self.gtree[g] == LEFT {
                    self.gtree[g] = a;
                }
                any = true;
            }
            self.left.truncate(keep);
            if !more {
                break;
            }
        }
        self.unpiece();
        if any {
            // (the pass reads a pushed island's dofs only to zero its w'
            // there: listed once each, not sorted)
            self.merge(rows, false);
        }
        self.touched.fill(false);
    }

    /// Δv' at the warm start of every island of the last grouping, if made
    /// (split.rs; bit for bit each island's own: [`Rows::warm_velocity`]).
    pub fn warm(&self) -> Option<&[f64]> {
        self.warm_made.then_some(&self.warm[..])
    }
}

/// Sorts `v` by `key` as a merge of its ascending stretches (a join's
/// pieces, each in order already): neighbouring stretches merged pairwise
/// into `tmp` until one is left, O(n log m) for m stretches; nothing is
/// allocated while `tmp` holds `v.len()` (the islands' scratch is sized
/// for every row and dof). Equal keys keep their order.
fn merge_stretches<T: Copy, K: Ord>(v: &mut [T], tmp: &mut Vec<T>, key: impl Fn(&T) -> K) {
    let n = v.len();
    if n < 2 {
        return;
    }
    loop {
        tmp.clear();
        let mut i = 0;
        while i < n {
            let a = i;
            i += 1;
            while i < n && key(&v[i - 1]) <= key(&v[i]) {
                i += 1;
            }
            let m = i;
            if m == n {
                if a == 0 {
                    // one stretch: in order
                    return;
                }
                tmp.extend_from_slice(&v[a..]);
                break;
            }
            i += 1;
            while i < n && key(&v[i - 1]) <= key(&v[i]) {
                i += 1;
            }
            let (mut x, mut y) = (a, m);
            while x < m && y < i {
                if key(&v[y]) < key(&v[x]) {
                    tmp.push(v[y]);
                    y += 1;
                } else {
                    tmp.push(v[x]);
                    x += 1;
                }
            }
            tmp.extend_from_slice(&v[x..m]);
            tmp.extend_from_slice(&v[y..i]);
        }
        v.copy_from_slice(tmp);
    }
}
