//! Velocity-level constraint solve of one step: ground contact (normal +
//! Coulomb cone), joint Coulomb friction (stiction) and joint position limits, by
//! projected Gauss–Seidel on the Delassus matrix W = J H⁻¹ Jᵀ.
//!
//! With the free velocity v* = v + Δt H⁻¹(τ − C(q, v)) the impulses λ make the
//! end-of-step velocity v⁺ = v* + H⁻¹ Jᵀ λ satisfy, row by row (u = J v⁺):
//! - contact normal: 0 ≤ λₙ ⊥ uₙ − bₙ ≥ 0;
//! - contact tangents (pair): ‖λₜ‖ ≤ μ λₙ, uₜ = 0 inside the cone (stick), λₜ
//!   anti-parallel to uₜ on its boundary (slip);
//! - joint friction: |λ| ≤ F Δt, u = 0 inside (a joint loaded below its
//!   friction F stays at rest);
//! - joint limit (one-sided): 0 ≤ λ ⊥ u − b ≥ 0, with b = −φ/Δt for a gap φ > 0
//!   (the joint may reach its limit, not pass it) and b = 0 when past it.
//!
//! The velocity solve never pushes a violated constraint back (b ≤ 0 for every
//! unilateral row): that would turn a position error into kinetic energy.
//! Violations are removed by a separate *position pass* ([`Rows::solve_position`],
//! split impulse / post-stabilisation): a pseudo-velocity w = H̃⁻¹Jᵀμ with
//! 0 ≤ μ ⊥ J w − b_pos ≥ 0 on the unilateral rows, b_pos = min(βφ⁻/Δt, cap),
//! moves q but never enters v.

pub(crate) mod dense;
mod dot3;
mod form;
mod kernels;
mod loop_block;
mod pgs;
mod position;
mod stress;
mod subspace;
mod wff;

pub(crate) use pgs::{IslandOut, Scratch};
use position::PosRow;
pub(crate) use position::PosWarm;

use super::factor::MassFactor;
use subspace::Subspace;

/// What a row is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowKind {
    /// Contact normal (λ ≥ 0).
    Normal,
    /// First of a contact's two tangent rows; the next row is its partner.
    /// `normal` is the row index of the contact's normal, `mu` the friction.
    Tangent {
        /// Row index of the contact's normal row.
        normal: usize,
        /// Coulomb friction coefficient μ of the contact's cone.
        mu: f64,
    },
    /// The second tangent row (handled with the first).
    Tangent2,
    /// Joint friction: |λ| ≤ limit.
    Box {
        /// Largest impulse magnitude, F·Δt (N·m·s or N·s).
        limit: f64,
    },
    /// Joint limit: λ ≥ 0.
    Unilateral,
    /// Loop constraint (mechanisms.md §"Simulation"): bilateral, λ free.
    Bilateral,
}

/// Preallocated rows: Jacobians and Y = J R⁻ᵀ (each row compact over its dof
/// path, `stride` apart), diag W, targets. Every per-row vector holds `capacity()` entries, the first `n` in use.
#[derive(Clone, Debug)]
pub struct Rows {
    /// The model's nv (the length of velocity vectors).
    pub nv: usize,
    /// Room of a row in `j` and `y`: the longest path a row can have (two
    /// bodies' paths to the root; nv for a dense factor), so that storage
    /// grows with rows × path length, never rows × nv.
    pub stride: usize,
    /// Rows in use.
    pub n: usize,
    /// Each row's kind (the first `n` entries in use).
    pub kind: Vec<RowKind>,
    /// Jacobians J, `stride` apart, each row compact over its path (entry t of
    /// row r, `j[r·stride + t]`, belongs to dof `path[t]`; J is zero elsewhere).
    pub j: Vec<f64>,
    /// Rows of Y = J R⁻ᵀ (H̃ = RᵀR), `stride` apart, each held compactly over its
    /// path (entry t belongs to dof `path[t]`); filled by [`Rows::form`].
    pub y: Vec<f64>,
    /// Delassus diagonal Wᵣᵣ = ‖yᵣ‖² (the row's velocity per unit impulse).
    pub w: Vec<f64>,
    /// 1 / Wᵣᵣ, and 0 where Wᵣᵣ ≤ 1e-14 (a row no impulse can move: its
    /// impulse stays 0).
    winv: Vec<f64>,
    /// J v* (free velocity).
    pub c: Vec<f64>,
    /// Target (b) of each row.
    pub b: Vec<f64>,
    /// Impulse of each row (N·s for contact rows, N·m·s or N·s for joint rows);
    /// the warm start on entry to [`Rows::solve`], the solution after.
    pub lambda: Vec<f64>,
    /// Position-pass target of each unilateral row (0: not violated).
    pub bpos: Vec<f64>,
    /// Position-pass multipliers.
    pub mu: Vec<f64>,
    /// Each row's dof path (start, length) in the factor's table: its Jacobian
    /// and y live there only (compact y: entry t is dof `path[t]`).
    pub path: Vec<(usize, usize)>,
    /// At a contact's normal row: the off-diagonal entries of its 3×3 block of
    /// W (n·t₁, n·t₂, t₁·t₂), so that a sweep reads the contact's path once.
    pub w_block: Vec<[f64; 3]>,
    is_block: Vec<bool>,
    /// Scratch of [`Rows::form`]: a contact's three rows interleaved (one
    /// entry per path slot, `stride` of them), one such for each thread of
    /// a form on the team (form/team.rs).
    lanes: Vec<[f64; 4]>,
    /// Each row's velocity at its update in the last sweep.
    u_prev: Vec<f64>,
    /// Scratch of the position pass: the rows it updates, in sweep order
    /// (position.rs).
    pos_rows: Vec<PosRow>,
    /// Scratch of the subspace step ([`subspace_step`]).
    sm: Subspace,
    /// The last solve took a subspace step.
    pub polished: bool,
    cap: usize,
    /// The dof paths rows live on: the factor's table ([`MassFactor::table`],
    /// every dof's path to the root, the first `static_len` entries), then the
    /// step's unions of two paths (a contact between two bodies acts on both
    /// bodies' paths: their union, ascending, is where its row and y live).
    table: Vec<usize>,
    static_len: usize,
    /// The last union made: its two paths and where it is.
    last_union: ((usize, usize), (usize, usize), (usize, usize)),
    /// Each dof: a joint's other than a free one ([`Rows::set_jointed`]).
    jointed: Vec<bool>,
    /// Some dof is jointed.
    any_jointed: bool,
    /// Some row pushed since the last [`Rows::clear`] is bilateral (a
    /// loop's): false, the sweeps look for no loop block.
    bilateral: bool,
    /// Solves so far ([`Rows::begin_solve`]).
    solves: u64,
    /// This solve sheds the self-stress of its jointed islands.
    shed_now: bool,
}

/// Every how many steps a jointed island's self-stress is shed (stress.rs).
pub const SHED_EVERY: u64 = 50;

/// Most rows a subspace step solves directly (its dense W_FF is this square).
pub const SUBSPACE_MAX: usize = 16;

impl Rows {
    /// Room for `cap` rows of width `nv`, all allocated here (none in a step).
    pub fn new(nv: usize, cap: usize, stride: usize) -> Self {
        let stride = stride.clamp(1, nv.max(1));
        Self {
            nv,
            stride,
            n: 0,
            kind: vec![RowKind::Unilateral; cap],
            j: vec![0.0; cap * stride],
            y: vec![0.0; cap * stride],
            w: vec![0.0; cap],
            winv: vec![0.0; cap],
            c: vec![0.0; cap],
            b: vec![0.0; cap],
            lambda: vec![0.0; cap],
            bpos: vec![0.0; cap],
            mu: vec![0.0; cap],
            path: vec![(0, 0); cap],
            w_block: vec![[0.0; 3]; cap],
            is_block: vec![false; cap],
            lanes: vec![[0.0; 4]; stride * form::PARTS],
            u_prev: vec![0.0; cap],
            pos_rows: Vec::with_capacity(cap),
            sm: Subspace::new(nv, cap),
            polished: false,
            cap,
            table: Vec::new(),
            static_len: 0,
            last_union: ((0, 0), (0, 0), (0, 0)),
            jointed: vec![false; nv],
            any_jointed: false,
            bilateral: false,
            solves: 0,
            shed_now: false,
        }
    }
    /// Takes the factor's path table (`base`, [`MassFactor::table`]) with room
    /// for `unions` two-body paths of at most nv entries each, allocated here.
    pub fn set_table(&mut self, base: &[usize], unions: usize) {
        self.table = Vec::with_capacity(base.len() + unions * self.stride);
        self.table.extend_from_slice(base);
        self.static_len = base.len();
    }
    /// No union path was made this step: every row's path is one of the
    /// factor's table ([`Rows::union_path`]).
    pub(crate) fn unions_empty(&self) -> bool {
        self.table.len() == self.static_len
    }
    /// The dof paths rows index ([`Rows::path`]).
    pub fn table(&self) -> &[usize] {
        &self.table
    }
    /// The path table and J, borrowed apart (to write a row's entries on
    /// its path).
    pub(crate) fn table_and_j(&mut self) -> (&[usize], &mut [f64]) {
        (&self.table, &mut self.j)
    }
    /// The path table and the per-row vectors a contact's rows are made of,
    /// borrowed apart (the team's contact rows, sim/constraints/team.rs:
    /// each contact writes its own rows, as [`Rows::push_contact`] would).
    pub(crate) fn contact_parts(&mut self) -> ContactParts<'_> {
        ContactParts {
            table: &self.table,
            j: &mut self.j,
            b: &mut self.b,
            bpos: &mut self.bpos,
            lambda: &mut self.lambda,
            kind: &mut self.kind,
            path: &mut self.path,
        }
    }
    /// A contact's three rows' place ([`Rows::push_contact`]'s, not
    /// written: see [`Rows::contact_parts`]), or `None` when fewer than
    /// three rows are left.
    pub(crate) fn reserve_contact(&mut self) -> Option<usize> {
        if self.n + 3 > self.cap {
            return None;
        }
        self.n += 3;
        Some(self.n - 3)
    }
    /// Takes the path table out (no entry moved), for a solver that mutates
    /// the rows while reading it; [`Rows::put_table`] puts it back.
    pub(crate) fn take_table(&mut self) -> Vec<usize> {
        std::mem::take(&mut self.table)
    }
    /// Puts back the table [`Rows::take_table`] took.
    pub(crate) fn put_table(&mut self, table: Vec<usize>) {
        self.table = table;
    }
    /// The path of a row acting on the dofs of two paths `a` and `b` (entries
    /// of the table): their union, ascending (appended to the table for this
    /// step; the last union is reused when asked again).
    #[inline]
    pub fn union_path(&mut self, a: (usize, usize), b: (usize, usize)) -> (usize, usize) {
        if a == b || b.1 == 0 {
            return a;
        }
        if a.1 == 0 {
            return b;
        }
        let (la, lb, at) = self.last_union;
        if la == a && lb == b && at.0 + at.1 <= self.table.len() && at.0 >= self.static_len {
            return at;
        }
        self.union_new(a, b)
    }
    /// [`Rows::union_path`]'s new union of two nonempty paths.
    #[inline(never)]
    fn union_new(&mut self, a: (usize, usize), b: (usize, usize)) -> (usize, usize) {
        let start = self.table.len();
        let (mut i, mut j) = (a.0, b.0);
        let (ea, eb) = (a.0 + a.1, b.0 + b.1);
        // two paths apart (two trees': every dof of one below every dof of
        // the other) are each other's ends: the merge's entries, copied
        if ea <= start && eb <= start {
            let (ta, tb) = (&self.table[a.0..ea], &self.table[b.0..eb]);
            let apart = match (ta.first(), ta.last(), tb.first(), tb.last()) {
                (Some(_), Some(&al), Some(&bf), Some(_)) if al < bf => Some((a, b)),
                (Some(&af), Some(_), Some(_), Some(&bl)) if bl < af => Some((b, a)),
                _ => None,
            };
            if let Some((lo, hi)) = apart {
                self.table.extend_from_within(lo.0..lo.0 + lo.1);
                self.table.extend_from_within(hi.0..hi.0 + hi.1);
                let at = (start, self.table.len() - start);
                self.last_union = (a, b, at);
                return at;
            }
        }
        while i < ea || j < eb {
            let x = if i < ea { self.table[i] } else { usize::MAX };
            let y = if j < eb { self.table[j] } else { usize::MAX };
            let k = if x <= y {
                i += 1;
                if x == y {
                    j += 1;
                }
                x
            } else {
                j += 1;
                y
            };
            self.table.push(k);
        }
        let at = (start, self.table.len() - start);
        self.last_union = (a, b, at);
        at
    }
    /// The most rows that fit.
    pub fn capacity(&self) -> usize {
        self.cap
    }
    /// Empties the rows; their Jacobian entries are zeroed here, once, so that
    /// every row pushed after starts from zeros (a row holds its path's
    /// entries only: the cost follows the rows' path lengths, never rows × nv).
    pub fn clear(&mut self) {
        self.zero_rows(0, self.n);
        self.n = 0;
        self.bilateral = false;
        self.table.truncate(self.static_len);
        self.last_union = ((0, 0), (0, 0), (0, 0));
    }
    /// Drops the last `k` rows (pushed, their Jacobian entries not yet written).
    pub fn pop(&mut self, k: usize) {
        let k = k.min(self.n);
        self.n -= k;
        self.zero_rows(self.n, self.n + k);
    }
    /// A gap of more than this many entries past a row's path is skipped
    /// by [`Rows::zero_rows`]; rows of a stride at most this are zeroed whole
    /// (without reading their paths).
    pub(crate) const GAP: usize = 16;
    /// Zeroes the Jacobian entries of rows `from..to`.
    fn zero_rows(&mut self, from: usize, to: usize) {
        let st = self.stride;
        // rows whose path fills the stride, or nearly (a pile's ground contact:
        // 6 of 12), lie back to back: one fill for a run of them, not one call
        // per row. A row's entries past its path are never written (they
        // stay 0: zeroing them again changes nothing); a gap of more than
        // `GAP` of them (a robot's short rows on a long stride) is skipped.
        // A run is cut at `CHUNK` entries (+ a stride): glibc's memset takes
        // `rep stos` above 2 KiB, one instruction a byte to callgrind.
        const CHUNK: usize = 192;
        if st <= Self::GAP {
            // (no row leaves a gap of more than `GAP`: rows from..to are one
            // run, filled without reading their paths — a pile's contact, one
            // call a contact)
            let (a, b) = (from * st, to.min(self.cap) * st);
            if let Some(j) = self.j.get_mut(a..b) {
                for c in j.chunks_mut(CHUNK) {
                    c.fill(0.0);
                }
            }
            return;
        }
        let mut run = from * st;
        for r in from..to.min(self.cap) {
            let pl = self.path[r].1.min(st);
            let gap = pl + Self::GAP < st;
            let end = r * st + if gap { pl } else { st };
            if gap || end - run >= CHUNK {
                self.j[run..end].fill(0.0);
                run = (r + 1) * st;
            }
        }
        let end = to.min(self.cap) * st;
        if run < end {
            self.j[run..end].fill(0.0);
        }
    }
    /// Adds a row (zeroed Jacobian: rows are zeroed by [`Rows::clear`]) and returns
    /// its index, or `None` when full.
    #[inline]
    pub fn push(
        &mut self,
        kind: RowKind,
        b: f64,
        warm: f64,
        path: (usize, usize),
    ) -> Option<usize> {
        if self.n >= self.cap {
            return None;
        }
        let r = self.n;
        self.n += 1;
        self.kind[r] = kind;
        self.bilateral |= kind == RowKind::Bilateral;
        self.b[r] = b;
        self.lambda[r] = warm;
        self.bpos[r] = 0.0;
        self.path[r] = path;
        Some(r)
    }
    /// A contact's three rows at once ([`Rows::push`] of a normal, its
    /// tangent pair, on one path, targets 0): the normal's index, or `None`
    /// (nothing pushed) when fewer than three rows are left.
    #[inline]
    pub fn push_contact(&mut self, mu: f64, warm: [f64; 3], path: (usize, usize)) -> Option<usize> {
        if self.n + 3 > self.cap {
            return None;
        }
        let r = self.n;
        self.n += 3;
        self.kind[r..r + 3].copy_from_slice(&[
            RowKind::Normal,
            RowKind::Tangent { normal: r, mu },
            RowKind::Tangent2,
        ]);
        self.b[r..r + 3].fill(0.0);
        self.lambda[r..r + 3].copy_from_slice(&warm);
        self.bpos[r..r + 3].fill(0.0);
        self.path[r..r + 3].fill(path);
        Some(r)
    }
    /// The rows from `r` sharing its path for certain: a formed contact's 3, or 1.
    #[inline(always)]
    pub(crate) fn rows_at(&self, r: usize) -> usize {
        1 + 2 * usize::from(r + 3 <= self.n && self.is_block.get(r) == Some(&true))
    }
    /// Rows `s..e` are contact triples.
    pub(crate) fn contacts_only(&self, s: usize, e: usize) -> bool {
        e <= self.n && (e - s) % 3 == 0 && (s..e).step_by(3).all(|r| self.is_block[r])
    }
    /// Δv' at the warm start of every row, Σ λᵣ yᵣ (`x`, nv entries, every
    /// entry written): on each island's dofs bit for bit the start its own
    /// sweeps make ([`Rows::sweeps`]: the same updates in row order, a
    /// contact's three rows in one pass when all three are nonzero; rows of
    /// other islands touch other dofs). Leaves `x` untouched if the rows are
    /// not well formed (the sweeps' checks).
    #[inline]
    pub(crate) fn warm_velocity(&self, x: &mut [f64]) {
        let (table, n, st) = (&self.table[..], self.n, self.stride);
        if x.len() < self.nv
            || self.y.len() < n * st
            || self.lambda.len() < n
            || self.path[..n]
                .iter()
                .any(|&(s, l)| s + l > table.len() || l > st)
        {
            return;
        }
        x.iter_mut().for_each(|v| *v = 0.0);
        // SAFETY: the paths and y checked above; path indices < nv ≤
        // x.len() (the sweeps' invariant)
        unsafe {
            kernels::warm_rows(
                &self.lambda[..n],
                &self.is_block[..n],
                &self.path[..n],
                table,
                &self.y,
                st,
                (0, n),
                x,
            )
        };
    }

    /// The contact triple at row `r` is not likely to push this step
    /// (src/sim/islands/split.rs): no impulse warm-started on its rows, its
    /// normal not violated (b_pos = 0), and its normal velocity both free
    /// (cᵣ) and at the warm start's Δv' (`warm`) at least `margin` above
    /// its target.
    #[inline]
    pub(crate) fn contact_idle(&self, r: usize, warm: &[f64], margin: f64) -> bool {
        let l = &self.lambda[r..r + 3];
        if !(self.c[r] >= self.b[r])
            || self.bpos[r] > 0.0
            || l[0] != 0.0
            || l[1] != 0.0
            || l[2] != 0.0
        {
            return false;
        }
        let Some(d) = self.y_dot(r, warm) else {
            return false;
        };
        self.c[r] + d >= self.b[r] + margin
    }
    /// yᵣ·x over row `r`'s path, in the path's order (None: the row's path
    /// or y out of range). A row's path holds dof indices < nv ≤ x.len()
    /// (the sweeps' invariant); a short `x` reads 0 past its end.
    #[inline]
    fn y_dot(&self, r: usize, x: &[f64]) -> Option<f64> {
        let st = self.stride;
        let (ps, pl) = *self.path.get(r)?;
        let p = self.table.get(ps..ps + pl)?;
        let y = self.y.get(r * st..r * st + pl)?;
        Some(kernels::dot_checked(y, p, x))
    }
    /// The normal of the contact at row `r` holds at λ = 0 to `tol` for the
    /// Δv' `x` (src/sim/islands/split.rs): uₙ = cₙ + yₙ·x ≥ bₙ − tol. A row
    /// no impulse moves (Wᵣᵣ = 0) holds.
    #[inline]
    pub(crate) fn contact_holds(&self, r: usize, x: &[f64], tol: f64) -> bool {
        if r >= self.n || self.winv[r] == 0.0 {
            return true;
        }
        let Some(d) = self.y_dot(r, x) else {
            return false;
        };
        self.c[r] + d >= self.b[r] - tol
    }
    /// Some row of `s..e` is violated (b_pos ≠ 0: the position pass runs
    /// on its island).
    pub(crate) fn violated(&self, s: usize, e: usize) -> bool {
        self.bpos[s..e]
            .iter()
            .fold(false, |any, &b| any | (b != 0.0))
    }
    /// Marks the dofs of joints other than free ones (`jointed[d]`, nv
    /// entries): the contacts whose rows reach one get
    /// the self-stress shedding of stress.rs.
    pub fn set_jointed(&mut self, jointed: &[bool]) {
        self.jointed = jointed.to_vec();
        self.any_jointed = jointed.iter().any(|&j| j);
    }
    /// Counts the step's solve: every [`SHED_EVERY`]-th one sheds the
    /// self-stress of jointed islands (stress.rs).
    pub fn begin_solve(&mut self) {
        self.solves = self.solves.wrapping_add(1);
        self.shed_now = self.any_jointed && self.solves % SHED_EVERY == 0;
    }
    /// Forgets the solves counted (with the warm starts: a state set anew
    /// steps as a new simulation does).
    pub fn forget_solves(&mut self) {
        self.solves = 0;
        self.shed_now = false;
    }
    /// Where dof `d` lies on row `r`'s path (`None`: off it, J is 0 there).
    fn slot_of(&self, r: usize, d: usize) -> Option<usize> {
        let (ps, pl) = self.path[r];
        self.table.get(ps..ps + pl)?.iter().position(|&k| k == d)
    }
    /// Adds `x` to J's entry of row `r` at dof `d` (on the row's path; a dof
    /// off the path is ignored: the row cannot act there).
    pub fn add_entry(&mut self, r: usize, d: usize, x: f64) {
        if let Some(t) = self.slot_of(r, d) {
            self.j[r * self.stride + t] += x;
        }
    }
    /// J's entry of row `r` at dof `d` (0 off its path).
    pub fn entry(&self, r: usize, d: usize) -> f64 {
        self.slot_of(r, d)
            .map_or(0.0, |t| self.j[r * self.stride + t])
    }
    /// Row `r` of J written from a dense row `dense` (nv entries, J's
    /// entries on the row's path; zero elsewhere), whose path entries are
    /// zeroed after (the caller's scratch is left all zeros).
    pub fn gather(&mut self, r: usize, dense: &mut [f64]) {
        let (ps, pl) = self.path[r];
        let st = self.stride;
        let Some(path) = self.table.get(ps..ps + pl) else {
            return;
        };
        for (t, &d) in path.iter().enumerate().take(st) {
            if let Some(x) = dense.get_mut(d) {
                self.j[r * st + t] = *x;
                *x = 0.0;
            }
        }
    }
    /// J's row `r` times `x` (nv entries).
    pub fn jdot(&self, r: usize, x: &[f64]) -> f64 {
        let (ps, pl) = self.path[r];
        let Some(path) = self.table.get(ps..ps + pl) else {
            return 0.0;
        };
        let jr = &self.j[r * self.stride..r * self.stride + pl.min(self.stride)];
        jr.iter()
            .zip(path)
            .map(|(a, &k)| a * x.get(k).copied().unwrap_or(0.0))
            .sum()
    }
    /// Row `r` of J as (dof, entry) pairs over its path.
    pub fn jrow(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let (ps, pl) = self.path[r];
        let path = self.table.get(ps..ps + pl).unwrap_or(&[]);
        let jr = &self.j[r * self.stride..r * self.stride + path.len().min(self.stride)];
        path.iter().copied().zip(jr.iter().copied())
    }
}

/// [`Rows::contact_parts`]: the path table and the per-row vectors.
pub(crate) struct ContactParts<'a> {
    pub table: &'a [usize],
    pub j: &'a mut [f64],
    pub b: &'a mut [f64],
    pub bpos: &'a mut [f64],
    pub lambda: &'a mut [f64],
    pub kind: &'a mut [RowKind],
    pub path: &'a mut [(usize, usize)],
}

/// `Σ aₖ bₖ` over the shorter of the two slices.
#[inline(always)]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
