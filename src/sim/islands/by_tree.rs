//! The islands' dofs read off tree by tree (docs/theory.md §"Islands").
//!
//! An island's dofs are the union of its rows' paths, ascending. A row's path
//! lies in the trees of its first and last dof (the grouping's premise,
//! src/sim/islands.rs), and every tree's dofs are one range of its own, the
//! trees' ranges ascending with the trees: so the union, ascending, is each
//! of the island's trees in turn (ascending), and within a tree its marked
//! dofs in their order. The paths' dofs are marked and each tree tagged with
//! its island; one pass over the trees buckets them by island (a counting
//! sort, stable: ascending in each), and each island's trees' ranges are read
//! off their marks. No sort of the dofs, no test before a mark: the same
//! lists the marks-then-sort pass makes, entry for entry. Should a path
//! reach a dof outside its two trees (no model's does), the marks left
//! behind are counted, cleared, and the islands made the general way.

use super::{group_path, Islands};
use crate::model::Model;

/// A tree's flags in a grouping: some path held all its dofs; some path
/// marked dofs of it one by one.
const WHOLE: u8 = 1;
const MARKED: u8 = 2;

/// The trees' dof ranges when they are ascending and disjoint, in tree
/// order (`None`: the islands' dofs are made by the general pass).
pub(super) fn tree_ranges(model: &Model) -> Option<Vec<(usize, usize)>> {
    let ranges: Vec<(usize, usize)> = model.trees.iter().map(|t| (t.v.start, t.v.end)).collect();
    let ascending = ranges.windows(2).all(|w| w[0].1 <= w[1].0);
    let inside = ranges.iter().all(|&(s, e)| s <= e && e <= model.nv);
    (ascending && inside).then_some(ranges)
}

impl Islands {
    /// The islands of the runs whose keys are trees (a prefix of the runs,
    /// sorted by key), their dofs read off by tree; returns the runs taken
    /// (0, every island and mark undone, when some path left a dof outside
    /// its trees: the general pass then makes them all).
    pub(super) fn tree_islands(&mut self, table: &[usize], path: &[(usize, usize)]) -> usize {
        let nt = self.tree_v.len();
        let mut i = 0;
        // Σ new marks (a dof marked twice counts once)
        let mut marked = 0usize;
        while i < self.runs.len() && self.runs[i].0 < nt {
            let k = self.runs[i].0;
            let (r0, isl) = (i, self.islands.len());
            while i < self.runs.len() && self.runs[i].0 == k {
                let (_, s, e) = self.runs[i];
                for g in self.run_groups(s, e) {
                    let p = group_path(table, path, self.groups[g].0);
                    let (Some(&first), Some(&last)) = (p.first(), p.last()) else {
                        continue;
                    };
                    let tree = |d: usize| self.tree_of_dof.get(d).copied().unwrap_or(usize::MAX);
                    let (a, b) = (tree(first), tree(last));
                    let len = |t: usize| self.tree_v.get(t).map_or(usize::MAX, |&(s, e)| e - s);
                    // every dof of its trees (ascending, distinct, within
                    // them: as many as they hold): the trees whole, no mark
                    let whole = match a == b {
                        true => p.len() == len(a),
                        false => len(a).checked_add(len(b)) == Some(p.len()),
                    };
                    debug_assert!(p.iter().all(|&d| tree(d) == a || tree(d) == b));
                    if !whole {
                        for &d in p {
                            if let Some(m) = self.mark.get_mut(d) {
                                marked += usize::from(!*m);
                                *m = true;
                            }
                        }
                    }
                    let flag = if whole { WHOLE } else { MARKED };
                    for t in [a, b] {
                        if let (Some(x), Some(f)) =
                            (self.tree_isl.get_mut(t), self.tree_flag.get_mut(t))
                        {
                            *x = isl;
                            *f |= flag;
                        }
                    }
                }
                i += 1;
            }
            self.islands.push(((r0, i), (0, 0)));
            if let Some(x) = self.iof.get_mut(k) {
                *x = self.iroot.len();
            }
            self.iroot.push(k);
        }
        let n_isl = self.islands.len();
        // the tagged trees by island, ascending in each (a counting sort)
        self.tcount.clear();
        self.tcount.resize(n_isl + 1, 0);
        for &x in &self.tree_isl {
            if x < n_isl {
                self.tcount[x + 1] += 1;
            }
        }
        for b in 0..n_isl {
            self.tcount[b + 1] += self.tcount[b];
        }
        // (every entry below the count written: its old ones not cleared)
        if self.tree_buf.len() < self.tcount[n_isl] {
            self.tree_buf.resize(self.tcount[n_isl], 0);
        }
        for (t, &x) in self.tree_isl.iter().enumerate() {
            if x < n_isl {
                let at = &mut self.tcount[x];
                self.tree_buf[*at] = t;
                *at += 1;
            }
        }
        // each island's dofs: its trees' marks in order (`tcount[x]` is now
        // the end of island x's trees)
        let (mut from, mut read) = (0, 0);
        for x in 0..n_isl {
            let d0 = self.dofs.len();
            let to = self.tcount[x];
            for &t in &self.tree_buf[from..to] {
                self.tree_isl[t] = usize::MAX;
                let (s, e) = self.tree_v[t];
                let flag = std::mem::take(&mut self.tree_flag[t]);
                if flag & WHOLE != 0 {
                    // (a free body's six at one copy of known length)
                    match self.iota.get(s..e).map(<&[usize; 6]>::try_from) {
                        Some(Ok(six)) => self.dofs.extend_from_slice(six),
                        _ => self.dofs.extend_from_slice(&self.iota[s..e]),
                    }
                    if flag & MARKED != 0 {
                        // (its marks, of a path within it, counted as read)
                        for m in &mut self.mark[s..e] {
                            read += usize::from(*m);
                            *m = false;
                        }
                    }
                    continue;
                }
                for (d, m) in (s..e).zip(&mut self.mark[s..e]) {
                    if *m {
                        *m = false;
                        self.dofs.push(d);
                        read += 1;
                    }
                }
            }
            from = to;
            self.islands[x].1 = (d0, self.dofs.len());
        }
        if read == marked {
            return i;
        }
        // a mark outside the trees read: undone, the general pass instead
        self.mark.fill(false);
        self.tree_isl.fill(usize::MAX);
        self.tree_flag.fill(0);
        self.dofs.clear();
        self.islands.clear();
        self.iroot.clear();
        self.iof.fill(usize::MAX);
        0
    }
}
