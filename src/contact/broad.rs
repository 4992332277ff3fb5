//! The broad phase: sweep and prune over world-aligned boxes.
//!
//! Each shape's box is its own box (in its frame) at its pose, boxed again
//! along the world axes (centre R·c + t, half extents |R|·h) and grown by the
//! detection margin, refreshed every step for the shapes that move.
//!
//! Few shapes (fewer than [`STRIPS_FROM`]): the shapes are kept sorted by their
//! boxes' lower x (an insertion sort: nearly sorted from step to step, O(n));
//! a sweep along x meets each shape only the shapes whose x-interval overlaps
//! its own, and keeps the pairs that also overlap in y and z and that the
//! pair filter allows (a table of pair indices).
//!
//! Many shapes: one sweep along x meets, for each shape, every shape of its
//! x-slab, O(n^1.5) for shapes spread over a square floor (a pile in a bin).
//! The floor is cut into strips along y, each as wide as the widest y-extent
//! of the ordinary shapes (those at most [`BIG`] times the median y-extent):
//! two boxes that overlap in y then lie in one strip or in two neighbouring
//! ones (by their lower y). The shapes are kept sorted by (strip, lower x)
//! (the same insertion sort), and strip s is swept along x merged with strip
//! s + 1, keeping the pairs with a member in s: each overlapping pair once,
//! and a shape meets only the shapes of its slab in two strips (O(n) for a
//! floor that grows with the pile). The few shapes wider than the strips (the
//! walls of a bin, a long obstacle) are tested against every shape. Either
//! way the pairs reported are exactly those whose boxes overlap (in another
//! order: the caller sorts them).

mod table;
mod width;
pub use table::PairTable;
pub(crate) use table::{LAZY_PAIR, NO_PAIR};
use width::Width;

/// The sweep's state.
#[derive(Clone, Debug, Default)]
pub struct SweepAndPrune {
    /// Lower and upper corners of each shape's box.
    pub lo: Vec<[f64; 3]>,
    /// Upper corners.
    pub hi: Vec<[f64; 3]>,
    /// The shapes by their boxes' lower x (with strips: the ordinary shapes
    /// by (strip, lower x)).
    order: Vec<u32>,
    /// Each shape's strip (strips only), and whether it is wider than a strip.
    strip: Vec<i64>,
    big: Vec<bool>,
    /// The strips' width's scratch (width.rs); the shapes wider than a
    /// strip, and two strips merged by lower x (lower x, shape, [`LOWER`]
    /// or the lower strip's shapes before it).
    width: Width,
    wide: Vec<u32>,
    merged: Vec<(f64, u32, u32)>,
    /// The y and z intervals (lower y, upper y, lower z, upper z) of the
    /// sorted shapes, in their order, and of the merged list's, in its
    /// order: a sweep reads them in turn, not through the shapes' indices.
    yz: Vec<[f64; 4]>,
    merged_yz: Vec<[f64; 4]>,
    /// The sweep's pairs whose boxes overlap, in the sweep's order, before
    /// the table is read (then read a few ahead of use).
    cand: Vec<(u32, u32)>,
    /// Scratch of the one sweep: the lower x of `order`'s shapes, in its
    /// order (sorted with it, read by the sweep without a gather).
    xs: Vec<f64>,
    /// Scratch of the strips' sort: (strip, lower x) in `order`'s order.
    keys: Vec<(i64, f64)>,
}

/// Shapes from which the floor is cut into strips.
pub(crate) const STRIPS_FROM: usize = 64;
/// A shape whose y-extent is above this many times the median is tested
/// against every shape (not put in a strip).
const BIG: f64 = 4.0;

impl SweepAndPrune {
    /// Room for `n` shapes (boxes empty until set).
    pub(crate) fn new(n: usize) -> Self {
        Self {
            lo: vec![[f64::INFINITY; 3]; n],
            hi: vec![[f64::NEG_INFINITY; 3]; n],
            order: (0..n as u32).collect(),
            strip: vec![0; n],
            big: vec![false; n],
            width: Width::new(n),
            wide: Vec::with_capacity(n),
            merged: Vec::with_capacity(n),
            yz: Vec::with_capacity(n),
            merged_yz: Vec::with_capacity(n),
            cand: Vec::new(),
            xs: Vec::with_capacity(n),
            keys: Vec::with_capacity(n),
        }
    }

    /// Sets shape `i`'s box to centre c ± half extents h.
    #[inline]
    pub(crate) fn set(&mut self, i: usize, c: [f64; 3], h: [f64; 3]) {
        self.lo[i] = [c[0] - h[0], c[1] - h[1], c[2] - h[2]];
        self.hi[i] = [c[0] + h[0], c[1] + h[1], c[2] + h[2]];
    }

    /// The overlapping pairs the table allows (`table.get(i, j)` the pair
    /// index of shapes i, j, or [`NO_PAIR`]), appended to `out`; those marked
    /// [`LAZY_PAIR`] (allowed, not made yet) as shapes (i, j) to `fresh`.
    pub(crate) fn overlaps(
        &mut self,
        table: &mut PairTable,
        out: &mut Vec<u32>,
        fresh: &mut Vec<(u32, u32)>,
    ) {
        let n = self.lo.len();
        let mut cand = std::mem::take(&mut self.cand);
        let found = if n < STRIPS_FROM {
            cand.clear();
            self.sweep_x(&mut cand);
            cand.len()
        } else {
            self.sweep_strips(&mut cand)
        };
        let cand_all = cand;
        let cand = &cand_all[..found.min(cand_all.len())];
        // the table read through the shapes' lines (table.rs) in the
        // sweep's order, the lines of eight pairs ahead fetched
        const AHEAD: usize = 8;
        for k in 0..cand.len() {
            if let Some(&(i, j)) = cand.get(k + AHEAD) {
                table.fetch(i, j);
            }
            let (i, j) = cand[k];
            match table.get_kept(i, j) {
                LAZY_PAIR => fresh.push((i, j)),
                NO_PAIR => {}
                p => out.push(p),
            }
        }
        self.cand = cand_all;
    }

    /// One sweep along x over every shape.
    fn sweep_x(&mut self, cand: &mut Vec<(u32, u32)>) {
        let n = self.order.len();
        // the lower x in last step's order, then an insertion sort by it
        // (the same comparisons, so the same order, as one on the boxes)
        let mut buf = std::mem::take(&mut self.xs);
        buf.clear();
        buf.extend(self.order.iter().map(|&i| self.lo[i as usize][0]));
        {
            let order = &mut self.order[..n];
            let xs = &mut buf[..n];
            for k in 1..n {
                let mut m = k;
                while m > 0 && xs[m - 1] > xs[m] {
                    xs.swap(m - 1, m);
                    order.swap(m - 1, m);
                    m -= 1;
                }
            }
        }
        for k in 0..n {
            let i = self.order[k] as usize;
            // (i's box read once for the shapes it meets)
            let (li, hi) = (self.lo[i], self.hi[i]);
            let hx = hi[0];
            for (&x, &j) in buf[k + 1..n].iter().zip(&self.order[k + 1..]) {
                if x > hx {
                    break;
                }
                let j = j as usize;
                if meet_yz(&li, &hi, &self.lo[j], &self.hi[j]) {
                    cand.push((i as u32, j as u32));
                }
            }
        }
        self.xs = buf;
    }

    /// Strips along y, each swept along x with the next (module docs): the
    /// pairs written to `cand` from its start, how many returned (the rest of
    /// `cand` is stale).
    fn sweep_strips(&mut self, cand: &mut Vec<(u32, u32)>) -> usize {
        let mut cand = Found { buf: cand, len: 0 };
        let n = self.lo.len();
        // the strips' width: the widest ordinary y-extent (width.rs)
        let w = self.width.of(&self.lo, &self.hi, BIG);
        self.wide.clear();
        // (the boxes, flags and strips read as one pass of slices, no index
        // tests: every per-shape vector holds n entries)
        let boxes = self.lo.iter().zip(&self.hi);
        let flags = self.big.iter_mut().zip(self.strip.iter_mut());
        for (i, ((l, h), (big, strip))) in boxes.zip(flags).enumerate() {
            let e = h[1] - l[1];
            let ly = l[1];
            // a shape with no box (never set) or no finite strip: with the wide ones
            let s = (ly / w).floor();
            let ordinary = e <= w && s.is_finite() && s.abs() <= 1e15;
            *big = !ordinary;
            *strip = if ordinary { s as i64 } else { 0 };
            if !ordinary {
                self.wide.push(i as u32);
            }
        }
        // the ordinary shapes by (strip, lower x): last step's order, the
        // wide ones out, then an insertion sort (nearly sorted); the sort's
        // keys, (strip, lower x), gathered in the same pass and sorted with
        // it (the same compares, the same swaps)
        let mut keys = std::mem::take(&mut self.keys);
        // (written in place, as many as the order holds, then cut)
        if keys.len() < self.order.len() {
            keys.resize(self.order.len(), (0, 0.0));
        }
        // (a NaN lower x: the strips may not be sorted by it)
        let mut nan = false;
        {
            let (big, strip, lo) = (&self.big[..n], &self.strip[..n], &self.lo[..n]);
            let mut kept = 0;
            for x in 0..self.order.len() {
                let i = self.order[x] as usize;
                if let (Some(false), Some(&s), Some(l)) =
                    (big.get(i).copied(), strip.get(i), lo.get(i))
                {
                    self.order[kept] = i as u32;
                    keys[kept] = (s, l[0]);
                    nan |= l[0].is_nan();
                    kept += 1;
                }
            }
            self.order.truncate(kept);
            keys.truncate(kept);
        }
        if self.order.len() + self.wide.len() < n {
            // a shape wide last step and ordinary now (or at the start)
            let mut seen = vec![false; n];
            for &i in &self.order {
                seen[i as usize] = true;
            }
            for (i, (&seen, &big)) in seen.iter().zip(&self.big).enumerate() {
                if !seen && !big {
                    self.order.push(i as u32);
                    keys.push((self.strip[i], self.lo[i][0]));
                    nan |= self.lo[i][0].is_nan();
                }
            }
        }
        let len = self.order.len();
        {
            let (order, keys) = (&mut self.order[..len], &mut keys[..len]);
            for k in 1..len {
                let mut m = k;
                while m > 0
                    && (keys[m - 1].0 > keys[m].0
                        || (keys[m - 1].0 == keys[m].0 && keys[m - 1].1 > keys[m].1))
                {
                    keys.swap(m - 1, m);
                    order.swap(m - 1, m);
                    m -= 1;
                }
            }
        }
        // the sorted shapes' y and z intervals in their order (each box
        // read once here, not once a shape it meets)
        let mut yz = std::mem::take(&mut self.yz);
        yz.clear();
        yz.extend(self.order.iter().map(|&i| {
            let (l, h) = (&self.lo[i as usize], &self.hi[i as usize]);
            [l[1], h[1], l[2], h[2]]
        }));
        // each strip merged with the next by lower x, swept
        let mut merged = std::mem::take(&mut self.merged);
        let mut merged_yz = std::mem::take(&mut self.merged_yz);
        let (order, ks, yz_all) = (&self.order[..len], &keys[..len], &yz[..len]);
        // (the end of strip s, found once: the next strip's start)
        let run_end = |a: usize| a + ks[a..].iter().take_while(|k| k.0 == ks[a].0).count();
        let mut a = 0;
        let mut b = if len > 0 { run_end(0) } else { 0 };
        while a < len {
            let s = ks[a].0;
            let c = if b < len && ks[b].0 == s + 1 {
                run_end(b)
            } else {
                b
            };
            let lower = (&ks[a..b], &order[a..b], &yz_all[a..b]);
            let upper = (&ks[b..c], &order[b..c], &yz_all[b..c]);
            let (merged, merged_yz) = merge_strips(lower, upper, (&mut merged, &mut merged_yz));
            for (k, (&(_, i, from), yi)) in merged.iter().zip(merged_yz).enumerate() {
                let i = i as usize;
                // (i's upper x read once for the shapes it meets)
                let hx = self.hi[i][0];
                if from != LOWER && !nan {
                    // i of strip s + 1 meets strip s's shapes only: those
                    // after it by lower x, strip s's from `from` on (sorted:
                    // the first past hx is the merged list's first of s past
                    // it, and the pairs in the merged list's order)
                    let (xs, js, yzs) = lower;
                    let from = from as usize;
                    let rest = (xs.get(from..), js.get(from..), yzs.get(from..));
                    let (Some(xs), Some(js), Some(yzs)) = rest else {
                        continue;
                    };
                    for ((&(_, x), &j), yj) in xs.iter().zip(js).zip(yzs) {
                        if x > hx {
                            break;
                        }
                        cand.put(i, j as usize, meet4(yi, yj));
                    }
                    continue;
                }
                let in_s = from == LOWER;
                let rest = merged[k + 1..].iter().zip(&merged_yz[k + 1..]);
                for (&(x, j, jfrom), yj) in rest {
                    if x > hx {
                        break;
                    }
                    cand.put(i, j as usize, (in_s | (jfrom == LOWER)) & meet4(yi, yj));
                }
            }
            a = b;
            b = if c > b || b >= len { c } else { run_end(b) };
        }
        self.merged = merged;
        self.merged_yz = merged_yz;
        self.keys = keys;
        self.yz = yz;
        // the wide shapes against every shape (a pair of two wide ones once)
        for wi in 0..self.wide.len() {
            let i = self.wide[wi] as usize;
            let (li, hi) = (self.lo[i], self.hi[i]);
            let shapes = self.lo.iter().zip(&self.hi).zip(&self.big).enumerate();
            for (j, ((lj, hj), &bj)) in shapes {
                if j == i || (bj && j < i) {
                    continue;
                }
                if lj[0] > hi[0] || li[0] > hj[0] {
                    continue;
                }
                cand.put(i, j, meet_yz(&li, &hi, lj, hj));
            }
        }
        cand.len
    }
}

/// The strips' sweep's pairs, written without a branch on the test: each
/// pair tested is written after those kept, and kept (counted) when its
/// boxes overlap.
struct Found<'a> {
    buf: &'a mut Vec<(u32, u32)>,
    len: usize,
}

impl Found<'_> {
    /// Writes shapes (i, j) after the pairs kept, kept when `keep`.
    #[inline(always)]
    fn put(&mut self, i: usize, j: usize, keep: bool) {
        if self.len >= self.buf.len() {
            let room = 2 * self.buf.len() + 64;
            self.buf.resize(room, (0, 0));
        }
        if let Some(x) = self.buf.get_mut(self.len) {
            *x = (i as u32, j as u32);
        }
        self.len += usize::from(keep);
    }
}

/// A merged entry of strip s ([`merge_strips`]).
const LOWER: u32 = u32::MAX;

/// A strip: its shapes' (strip, lower x) keys, shapes and y and z
/// intervals, by lower x.
type Strip<'a> = (&'a [(i64, f64)], &'a [u32], &'a [[f64; 4]]);

/// Strips `l` and `u` merged by lower x into `out` as (lower x, shape,
/// [`LOWER`] for one of `l`, else how many of `l` precede it), and their y
/// and z intervals beside: one of `l` first unless its lower x is greater
/// (as the sort: `l` before `u` on a tie).
#[inline(always)]
fn merge_strips<'m>(
    (lk, lo, lyz): Strip,
    (uk, uo, uyz): Strip,
    (out, out_yz): (&'m mut Vec<(f64, u32, u32)>, &'m mut Vec<[f64; 4]>),
) -> (&'m [(f64, u32, u32)], &'m [[f64; 4]]) {
    let nl = lk.len().min(lo.len()).min(lyz.len());
    let nu = uk.len().min(uo.len()).min(uyz.len());
    let (lk, lo, lyz) = (&lk[..nl], &lo[..nl], &lyz[..nl]);
    let (uk, uo, uyz) = (&uk[..nu], &uo[..nu], &uyz[..nu]);
    // (written in place: room for both, kept from step to step)
    if out.len() < nl + nu {
        out.resize(nl + nu, (0.0, 0, 0));
    }
    if out_yz.len() < nl + nu {
        out_yz.resize(nl + nu, [0.0; 4]);
    }
    let (out, out_yz) = (&mut out[..nl + nu], &mut out_yz[..nl + nu]);
    let (mut i, mut j) = (0, 0);
    while i < nl && j < nu {
        let (x, y) = (lk[i].1, uk[j].1);
        if x > y {
            out[i + j] = (y, uo[j], i as u32);
            out_yz[i + j] = uyz[j];
            j += 1;
        } else {
            out[i + j] = (x, lo[i], LOWER);
            out_yz[i + j] = lyz[i];
            i += 1;
        }
    }
    // (the rest of the one not used up)
    let rest = lk[i..].iter().zip(&lo[i..]).zip(&lyz[i..]);
    for ((o, oyz), ((&(_, x), &s), yz)) in
        out[i + j..].iter_mut().zip(&mut out_yz[i + j..]).zip(rest)
    {
        *o = (x, s, LOWER);
        *oyz = *yz;
    }
    let at = (nl + j).min(nl + nu);
    let rest = uk[j..].iter().zip(&uo[j..]).zip(&uyz[j..]);
    for ((o, oyz), ((&(_, x), &s), yz)) in out[at..].iter_mut().zip(&mut out_yz[at..]).zip(rest) {
        *o = (x, s, nl as u32);
        *oyz = *yz;
    }
    (out, out_yz)
}

/// Two boxes (lower, upper corners; known to overlap in x) overlap in y and z.
#[inline(always)]
fn meet_yz(li: &[f64; 3], hi: &[f64; 3], lj: &[f64; 3], hj: &[f64; 3]) -> bool {
    !(lj[1] > hi[1] || li[1] > hj[1] || lj[2] > hi[2] || li[2] > hj[2])
}

/// [`meet_yz`] of two boxes' y and z intervals (lower y, upper y, lower z,
/// upper z): the same four comparisons, all made (no branch).
#[inline(always)]
fn meet4(i: &[f64; 4], j: &[f64; 4]) -> bool {
    !((j[0] > i[1]) | (i[0] > j[1]) | (j[2] > i[3]) | (i[2] > j[3]))
}

/// The broad phase of fewer than 64 shapes whose allowed pairs are all
/// known (one robot's self pairs): for each shape l, the shapes h > l whose
/// boxes overlap l's as the bits of a mask (a branch-free test of every h,
/// which vectorises; under [`DENSE_FROM`] shapes, a test of each allowed
/// pair), kept where the pair is allowed. A robot's link boxes
/// meet along x for most pairs, so a sweep along x tests nearly every pair
/// anyway, with a branch and a table look-up each. The pairs reported are
/// the sweeps': exactly the allowed ones whose boxes overlap.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairMasks {
    /// Per shape l, the allowed shapes h > l, as bits.
    allowed: Vec<u64>,
    /// Scratch: the boxes' lower and upper corners (x, y, z, then x, y, z)
    /// of shapes 4b to 4b + 3 in block b, a lane a shape (the last block
    /// padded: never allowed).
    quads: Vec<[[f64; 4]; 6]>,
}

/// Shapes from which [`PairMasks`] tests every shape h > l at once (fewer:
/// each allowed pair, as a scalar test).
const DENSE_FROM: usize = 16;

impl PairMasks {
    /// The masks of `n` shapes with the allowed pairs `pairs` (`None`: more
    /// than 64 shapes).
    pub(crate) fn new(n: usize, pairs: impl Iterator<Item = (usize, usize)>) -> Option<Self> {
        if n > 64 {
            return None;
        }
        let mut allowed = vec![0u64; n];
        for (i, j) in pairs {
            let (l, h) = (i.min(j), i.max(j));
            if h < n && l < h {
                allowed[l] |= 1 << h;
            }
        }
        Some(Self {
            allowed,
            quads: vec![[[0.0; 4]; 6]; n.div_ceil(4)],
        })
    }

    /// Calls `found(l, h)` for each allowed pair l < h whose boxes in `sap`
    /// overlap, by l, then h.
    #[inline]
    pub(crate) fn overlaps(&mut self, sap: &SweepAndPrune, mut found: impl FnMut(usize, usize)) {
        let n = self.allowed.len().min(sap.lo.len()).min(sap.hi.len());
        if n < DENSE_FROM {
            // few shapes: each allowed pair tested (x first, one branch)
            for (l, &allowed) in self.allowed.iter().enumerate().take(n) {
                let (li, hi) = (&sap.lo[l], &sap.hi[l]);
                let mut mask = allowed;
                while mask != 0 {
                    let h = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let (Some(lj), Some(hj)) = (sap.lo.get(h), sap.hi.get(h)) else {
                        continue;
                    };
                    let apart = lj[0] > hi[0]
                        || li[0] > hj[0]
                        || lj[1] > hi[1]
                        || li[1] > hj[1]
                        || lj[2] > hi[2]
                        || li[2] > hj[2];
                    if !apart {
                        found(l, h);
                    }
                }
            }
            return;
        }
        for k in 0..n {
            let q = &mut self.quads[k / 4];
            for a in 0..3 {
                q[a][k % 4] = sap.lo[k][a];
                q[a + 3][k % 4] = sap.hi[k][a];
            }
        }
        for l in 0..n {
            let allowed = self.allowed[l];
            if allowed == 0 {
                continue;
            }
            let (q, i) = (&self.quads[l / 4], l % 4);
            let lbox = [q[0][i], q[1][i], q[2][i], q[3][i], q[4][i], q[5][i]];
            // bit h: boxes l and h overlap (apart: one's lower corner above
            // the other's upper one along an axis), 4 shapes h at a time
            let mut mask = 0u64;
            let first = (l + 1) / 4;
            for (b, hbox) in self.quads.iter().enumerate().skip(first) {
                mask |= overlap4(&lbox, hbox) << (4 * b);
            }
            mask &= allowed;
            while mask != 0 {
                let h = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                found(l, h);
            }
        }
    }
}

/// The bits (0–3) of the 4 boxes `h` (lower x, y, z, upper x, y, z, a lane
/// each) that overlap box `l` (lower x, y, z, upper x, y, z): none apart
/// along an axis (the same comparisons whatever the path: exact).
#[inline]
fn overlap4(l: &[f64; 6], h: &[[f64; 4]; 6]) -> u64 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{
            _mm256_broadcast_sd, _mm256_cmp_pd, _mm256_loadu_pd, _mm256_movemask_pd, _mm256_or_pd,
            _CMP_GT_OQ,
        };
        // SAFETY: AVX is enabled for this build (the cfg); the loads read
        // the 4 lanes of arrays of 4 f64 and the broadcasts one f64.
        unsafe {
            let gt = |a, b| _mm256_cmp_pd::<_CMP_GT_OQ>(a, b);
            let lane = |k: usize| _mm256_loadu_pd(h[k].as_ptr());
            let one = |k: usize| _mm256_broadcast_sd(&l[k]);
            // lo_h > hi_l or lo_l > hi_h, along x, y, z
            let x = _mm256_or_pd(gt(lane(0), one(3)), gt(one(0), lane(3)));
            let y = _mm256_or_pd(gt(lane(1), one(4)), gt(one(1), lane(4)));
            let z = _mm256_or_pd(gt(lane(2), one(5)), gt(one(2), lane(5)));
            let apart = _mm256_movemask_pd(_mm256_or_pd(x, _mm256_or_pd(y, z)));
            u64::from(!(apart as u32) & 0xF)
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let mut bits = 0u64;
        for i in 0..4 {
            let apart = (h[0][i] > l[3])
                | (l[0] > h[3][i])
                | (h[1][i] > l[4])
                | (l[1] > h[4][i])
                | (h[2][i] > l[5])
                | (l[2] > h[5][i]);
            bits |= u64::from(!apart) << i;
        }
        bits
    }
}
