//! Islands of the constraint solve (scene.md §"Large scenes: islands and
//! sleep"; docs/theory.md §"Islands").
//!
//! Two trees of the model are in one island when a row of this step acts on
//! both: a contact point between their bodies (the rows of the points within
//! the contact margin), or a loop constraint; a tree's own joint rows (friction,
//! limits) are in its island. The world, obstacles and trees without degrees
//! of freedom join nothing (a row acts on dofs only). Rows are found from
//! their dof paths: a row's path runs over the dofs of at most two trees, the
//! first and the last of its ascending path, so the trees of its first and
//! last dof are all it joins.
//!
//! The rows of an island are runs of consecutive rows (a contact's three rows
//! are one run: they share a path); the islands list their runs in row order,
//! so that an island's Gauss–Seidel sweep visits its rows in the order the
//! global sweep did, and a scene of one island is solved exactly as before.
//! Everything here is sized at construction: nothing is allocated in a step.

use super::solver::Rows;
use crate::model::Model;

mod by_tree;
mod split;

/// A group's key while it is left out of the solve (split.rs).
const LEFT: usize = usize::MAX - 1;

/// This step's islands: their row runs and their dofs.
#[derive(Clone, Debug)]
pub(crate) struct Islands {
    /// Each velocity coordinate's tree (`usize::MAX`: none).
    tree_of_dof: Vec<usize>,
    /// Union-find parents over the trees (scratch).
    parent: Vec<usize>,
    /// The rows' groups: maximal runs of consecutive rows on one path (a
    /// contact's three rows, the points of one pair), as (first row, end),
    /// and each group's island root tree (`usize::MAX`: a row on no dof).
    groups: Vec<(usize, usize)>,
    /// Per group: its rows are whole contacts' (found by the grouping).
    triples: Vec<bool>,
    /// Each group's first tree (`usize::MAX`: a row on no dof; [`LEFT`]: a
    /// contact group all left out of the solve).
    gtree: Vec<usize>,
    /// The contacts left out of this step's solve (split.rs): (normal row,
    /// group, the tree of its first dof, of its last).
    left: Vec<(usize, usize, usize, usize)>,
    /// Each row: a left-out contact's normal (split.rs); each group: some
    /// contact of it is left out.
    out: Vec<bool>,
    gpart: Vec<bool>,
    /// Δv' at the warm start (split.rs), every island's own warm start
    /// ([`Islands::warm`]), made when `warm_made`.
    warm: Vec<f64>,
    warm_made: bool,
    /// Per island: its root tree (`usize::MAX`: rows on no dof; [`LEFT`]:
    /// emptied by a join, split.rs).
    iroot: Vec<usize>,
    /// Per tree: the island it roots (`usize::MAX`: none), and whether that
    /// island's Δv' (or w') moved since the last check of the left-out
    /// contacts; every contact is checked while `check_all` (split.rs).
    iof: Vec<usize>,
    touched: Vec<bool>,
    check_all: bool,
    /// Scratch of a join (split.rs): the failed contacts (row, group, trees),
    /// and the pieces of the new islands (root, island or row).
    fails: Vec<(usize, usize, usize, usize)>,
    pieces: Vec<(usize, usize, usize)>,
    /// Per tree: the island it roots is among the pieces already (scratch
    /// of a join, split.rs; all false outside one).
    pieced: Vec<bool>,
    /// The islands to solve: every one after a grouping, the ones a join
    /// made after it.
    todo: Vec<usize>,
    /// The group starting at each row (read at runs' first rows only).
    group_at: Vec<usize>,
    /// Runs of consecutive rows of one island: (island key, first row, end).
    runs: Vec<(usize, usize, usize)>,
    /// Scratch of the runs' sort by key: the runs, and each key's count,
    /// then its place.
    sorted: Vec<(usize, usize, usize)>,
    count: Vec<usize>,
    /// Per island: its runs, a range of `runs`, and its dofs, a range of `dofs`.
    islands: Vec<((usize, usize), (usize, usize))>,
    /// The islands' dofs, island after island (ascending within one).
    dofs: Vec<usize>,
    /// Scratch: a dof already listed; a join's dofs in merging (split.rs).
    mark: Vec<bool>,
    dof_tmp: Vec<usize>,
    /// Each dof's parent on its path to the root ([`Model::dof_parent`],
    /// `usize::MAX` at a root).
    dof_parent: Vec<usize>,
    /// Each dof's path length to the root, itself included (`usize::MAX`:
    /// unknown).
    chain_len: Vec<usize>,
    /// The rows' paths of the last grouping, when they were all the factor's
    /// (no union path: `cached`): the islands are a function of them.
    last: Vec<(usize, usize)>,
    cached: bool,
    /// Each tree's dofs, a range (empty: the trees' ranges are not
    /// ascending, and the islands' dofs are sorted, by_tree.rs); per tree,
    /// the island whose path reached it in this grouping (`usize::MAX`:
    /// none); scratch of the trees by island, and each island's count.
    tree_v: Vec<(usize, usize)>,
    /// Each dof's own number (a whole tree's dofs copied from it).
    iota: Vec<usize>,
    tree_isl: Vec<usize>,
    tree_flag: Vec<u8>,
    tree_buf: Vec<usize>,
    tcount: Vec<usize>,
}

/// One island of this step: its row runs and its dofs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Island<'a> {
    /// Runs of rows, `start..end`, in row order.
    pub runs: &'a [(usize, usize, usize)],
    /// The dofs its rows act on.
    pub dofs: &'a [usize],
}

impl Island<'_> {
    /// The rows of the island.
    pub fn rows(&self) -> usize {
        self.runs.iter().map(|&(_, s, e)| e - s).sum()
    }
    /// Each row of the island, in order.
    pub fn each_row(&self) -> impl Iterator<Item = usize> + '_ {
        self.runs.iter().flat_map(|&(_, s, e)| s..e)
    }
}

/// The dof path of row `q` (`path`: the rows' (start, length) in `table`;
/// empty when out of it).
#[inline(always)]
fn group_path<'t>(table: &'t [usize], path: &[(usize, usize)], q: usize) -> &'t [usize] {
    let (ps, pl) = path[q];
    table.get(ps..ps + pl).unwrap_or(&[])
}

/// Each dof's path length to the root, itself included, along `parent`
/// (`usize::MAX` where `parent` has no entry for it or does not reach a root
/// in nv steps).
fn chain_lengths(parent: &[usize], nv: usize) -> Vec<usize> {
    (0..nv)
        .map(|k| {
            let mut x = k;
            for len in 1..=nv {
                match parent.get(x) {
                    Some(&usize::MAX) => return len,
                    Some(&p) if p < nv => x = p,
                    _ => return usize::MAX,
                }
            }
            usize::MAX
        })
        .collect()
}

impl Islands {
    /// Room for the islands of `model` with at most `rows` rows.
    pub fn new(model: &Model, rows: usize) -> Self {
        let nt = model.trees.len();
        let mut tree_of_dof = vec![usize::MAX; model.nv];
        for (t, tree) in model.trees.iter().enumerate() {
            for k in tree.v.clone() {
                if let Some(x) = tree_of_dof.get_mut(k) {
                    *x = t;
                }
            }
        }
        Self {
            tree_of_dof,
            parent: (0..nt).collect(),
            groups: Vec::with_capacity(rows),
            triples: Vec::with_capacity(rows),
            gtree: Vec::with_capacity(rows),
            left: Vec::with_capacity(rows),
            out: vec![false; rows],
            gpart: Vec::with_capacity(rows),
            warm: vec![0.0; model.nv],
            warm_made: false,
            iroot: Vec::with_capacity(rows.min(nt + 1)),
            iof: vec![usize::MAX; nt],
            touched: vec![false; nt],
            check_all: false,
            fails: Vec::with_capacity(rows),
            pieces: Vec::with_capacity(rows),
            pieced: vec![false; nt],
            todo: Vec::with_capacity(rows.min(nt + 1)),
            group_at: vec![0; rows],
            runs: Vec::with_capacity(rows),
            sorted: Vec::with_capacity(rows),
            count: Vec::with_capacity(nt + 2),
            islands: Vec::with_capacity(rows.min(nt + 1)),
            dofs: Vec::with_capacity(model.nv),
            mark: vec![false; model.nv],
            dof_tmp: Vec::with_capacity(2 * model.nv),
            dof_parent: model.dof_parent.clone(),
            chain_len: chain_lengths(&model.dof_parent, model.nv),
            last: Vec::with_capacity(rows),
            cached: false,
            iota: (0..model.nv).collect(),
            tree_isl: vec![usize::MAX; nt],
            tree_flag: vec![0; nt],
            tree_buf: Vec::with_capacity(nt),
            tcount: Vec::with_capacity(nt + 1),
            tree_v: by_tree::tree_ranges(model).unwrap_or_default(),
        }
    }

    fn find(&mut self, mut t: usize) -> usize {
        while self.parent[t] != t {
            self.parent[t] = self.parent[self.parent[t]];
            t = self.parent[t];
        }
        t
    }

    /// The tree of a row's first and last dof (`None`: a row on no dof).
    fn ends(&self, rows: &Rows, r: usize) -> Option<(usize, usize)> {
        let (s, l) = rows.path[r];
        let p = rows.table().get(s..s + l)?;
        let (first, last) = (*p.first()?, *p.last()?);
        let t = |k: usize| {
            self.tree_of_dof
                .get(k)
                .copied()
                .filter(|&t| t != usize::MAX)
        };
        Some((t(first)?, t(last)?))
    }

    /// Groups the assembled rows into islands. With the split on (split.rs),
    /// a contact group between trees whose every point is likely inactive
    /// this step joins nothing and is left out of the islands' rows, to be
    /// checked at their solution ([`Islands::join_failed`]).
    pub fn group(&mut self, rows: &Rows) {
        let n = rows.n.min(self.group_at.len());
        // (a scene of one tree is never split; nor is one whose rows all lie
        // on the factor's own paths, with no contact between two trees —
        // without the split on, every grouping of the same paths is the same)
        // (nor a step of few rows: its islands are small, and the split's
        // bookkeeping costs more than the sweeps it saves, split.rs)
        let may_split = self.parent.len() > 1 && n >= split::MIN_ROWS;
        // the same rows' paths as the last grouping, each one of the factor's
        // (fixed for the rows' life, [`Rows::set_table`]): the same islands
        let fixed = rows.unions_empty() && !may_split;
        self.warm_made = false;
        if fixed && self.cached && rows.path[..n] == self.last[..] {
            return;
        }
        self.cached = fixed && n <= self.last.capacity();
        self.last.clear();
        if self.cached {
            self.last.extend_from_slice(&rows.path[..n]);
        }
        for p in self.parent.iter_mut().enumerate() {
            *p.1 = p.0;
        }
        // rows on the same path as the row before them (a contact's tangents,
        // the points of one pair) join the same trees: one group, looked at once
        // (a contact's tangents share its normal's path: not compared; a
        // group of whole contacts is known to be one, `triples`)
        self.groups.clear();
        self.triples.clear();
        let path = &rows.path[..n];
        let mut r = 0;
        while r < n {
            let s = r;
            let mut k = rows.rows_at(r);
            let mut triples = k == 3;
            r += k;
            while r < n && path[r] == path[s] {
                k = rows.rows_at(r);
                triples &= k == 3;
                r += k;
            }
            debug_assert!(path[s..r].iter().all(|&p| p == path[s]));
            self.group_at[s] = self.groups.len();
            self.groups.push((s, r));
            self.triples.push(triples);
        }
        self.gtree.clear();
        for &(r, _, _, _) in &self.left {
            self.out[r] = false;
        }
        self.left.clear();
        self.gpart.clear();
        self.gpart.resize(self.groups.len(), false);
        self.check_all = true;
        if self.parent.len() == 1 {
            // one tree (a single robot): every row on a dof joins tree 0, no
            // union to find (the keys the general pass gives, without it)
            for g in 0..self.groups.len() {
                let k = self.ends(rows, self.groups[g].0).map_or(usize::MAX, |_| 0);
                self.gtree.push(k);
            }
        } else {
            if may_split {
                rows.warm_velocity(&mut self.warm);
            }
            self.warm_made = may_split;
            // (each group's first tree kept in `gtree`: its ends looked up once)
            for g in 0..self.groups.len() {
                let (s, e) = self.groups[g];
                let k = match self.ends(rows, s) {
                    Some((a, b)) => {
                        let kept = !may_split || self.leave_out(rows, g, s, e, a, b);
                        if kept {
                            let (ra, rb) = (self.find(a), self.find(b));
                            if ra != rb {
                                self.parent[ra.max(rb)] = ra.min(rb);
                            }
                            a
                        } else {
                            LEFT
                        }
                    }
                    None => usize::MAX,
                };
                self.gtree.push(k);
            }
        }
        self.build(rows);
    }

    /// The islands' runs and dofs from the groups' trees and the union-find.
    fn build(&mut self, rows: &Rows) {
        // runs of consecutive rows with one key (whole groups, but for the
        // contacts left out), then grouped by key (stable: row order within
        // an island); a group's key: its first tree's root
        self.runs.clear();
        let mut cur = (usize::MAX, 0, 0);
        for g in 0..self.groups.len() {
            let a = self.gtree[g];
            let k = if a < LEFT { self.find(a) } else { a };
            if k == LEFT {
                continue;
            }
            let (s, e) = self.groups[g];
            if !self.gpart[g] {
                if cur.0 == k && cur.2 == s {
                    cur.2 = e;
                } else {
                    if cur.2 > cur.1 {
                        self.runs.push(cur);
                    }
                    cur = (k, s, e);
                }
                continue;
            }
            // a group with contacts left out: its kept triples
            let mut r = s;
            while r < e {
                if !self.out[r] {
                    if cur.0 == k && cur.2 == r {
                        cur.2 = r + 3;
                    } else {
                        if cur.2 > cur.1 {
                            self.runs.push(cur);
                        }
                        // (a run starting inside a group: its group recorded)
                        self.group_at[r] = g;
                        cur = (k, r, r + 3);
                    }
                }
                r += 3;
            }
        }
        if cur.2 > cur.1 {
            self.runs.push(cur);
        }
        // (a counting sort over the keys: the runs are in row order, so each
        // key's stay in it; the trees' keys, then rows on no dof, as a sort by
        // (key, first row) puts them)
        let nk = self.parent.len() + 1;
        let bucket = |k: usize| k.min(nk - 1);
        self.count.clear();
        self.count.resize(nk + 1, 0);
        for &(k, _, _) in &self.runs {
            self.count[bucket(k) + 1] += 1;
        }
        for b in 0..nk {
            self.count[b + 1] += self.count[b];
        }
        // (every entry below the runs' count written: `sorted`'s old ones
        // not cleared, its tail cut after the swap)
        let nr = self.runs.len();
        if self.sorted.len() < nr {
            self.sorted.resize(nr, (0, 0, 0));
        }
        for &run in &self.runs {
            let at = &mut self.count[bucket(run.0)];
            self.sorted[*at] = run;
            *at += 1;
        }
        std::mem::swap(&mut self.runs, &mut self.sorted);
        self.runs.truncate(nr);
        // each island's runs and dofs
        self.islands.clear();
        // (`iof` is set only at the islands' roots: those cleared, the
        // roots of islands a join emptied by it, split.rs)
        for &k in &self.iroot {
            if let Some(x) = self.iof.get_mut(k) {
                *x = usize::MAX;
            }
        }
        debug_assert!(self.iof.iter().all(|&x| x == usize::MAX));
        self.iroot.clear();
        self.dofs.clear();
        let table = rows.table();
        let path = &rows.path[..rows.n.min(self.group_at.len())];
        // the trees' islands read off by tree (by_tree.rs), the rest here
        let mut i = match self.tree_v.is_empty() {
            true => 0,
            false => self.tree_islands(table, path),
        };
        while i < self.runs.len() {
            let k = self.runs[i].0;
            let (r0, d0) = (i, self.dofs.len());
            // the dofs marked (listed, and their range)
            let (mut lo, mut hi) = (usize::MAX, 0);
            while i < self.runs.len() && self.runs[i].0 == k {
                let (_, s, e) = self.runs[i];
                for g in self.run_groups(s, e) {
                    let p = group_path(table, path, self.groups[g].0);
                    // a path is closed under dof parents (a dof's path to the
                    // root, a union of two, or every dof), and so are the
                    // marks: a path as long as its last dof's chain is that
                    // chain, marked from its end up to the first dof marked
                    if let Some(&d) = p.last()
                        && self.chain_len.get(d) == Some(&p.len())
                    {
                        let mut x = d;
                        while let Some(m) = self.mark.get_mut(x)
                            && !*m
                        {
                            *m = true;
                            self.dofs.push(x);
                            lo = lo.min(x);
                            hi = hi.max(x);
                            x = self.dof_parent.get(x).copied().unwrap_or(usize::MAX);
                        }
                        continue;
                    }
                    for &d in p {
                        if let Some(m) = self.mark.get_mut(d)
                            && !*m
                        {
                            *m = true;
                            self.dofs.push(d);
                            lo = lo.min(d);
                            hi = hi.max(d);
                        }
                    }
                }
                i += 1;
            }
            // ascending: read off the marks where they are dense in their range
            // (one robot: no sort), else sorted
            let dofs = &mut self.dofs[d0..];
            if !dofs.is_empty() && hi - lo < 4 * dofs.len() + 32 {
                let mut w = dofs.iter_mut();
                for (d, m) in (lo..).zip(&mut self.mark[lo..=hi]) {
                    if *m {
                        *m = false;
                        if let Some(x) = w.next() {
                            *x = d;
                        }
                    }
                }
            } else {
                dofs.sort_unstable();
                for &d in dofs.iter() {
                    self.mark[d] = false;
                }
            }
            self.islands.push(((r0, i), (d0, self.dofs.len())));
            if let Some(x) = self.iof.get_mut(k) {
                *x = self.iroot.len();
            }
            self.iroot.push(k);
        }
        self.todo.clear();
        self.todo.extend(0..self.islands.len());
    }

    /// The groups of the run of rows `s..e`, one path each: a run starts a
    /// group (or a group's kept triples, the group recorded at its first row
    /// in `group_at`) and holds whole groups after it.
    fn run_groups(&self, s: usize, e: usize) -> std::ops::Range<usize> {
        let g0 = self.group_at[s];
        let mut g = g0;
        while let Some(&(q, _)) = self.groups.get(g)
            && q < e
        {
            g += 1;
        }
        g0..g
    }

    /// The islands to solve ([`Islands::join_failed`]).
    pub fn todo(&self) -> &[usize] {
        &self.todo
    }

    /// The islands of the last grouping.
    pub fn len(&self) -> usize {
        self.islands.len()
    }

    /// Island `i` of the last grouping.
    pub fn get(&self, i: usize) -> Island<'_> {
        let ((r0, r1), (d0, d1)) = self.islands[i];
        Island {
            runs: &self.runs[r0..r1],
            dofs: &self.dofs[d0..d1],
        }
    }
}
