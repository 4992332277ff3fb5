//! The pair table of the broad phase (src/contact/broad.rs): for each pair
//! of shapes, none allowed, allowed and not made yet, or the index of the
//! pair made; and, per shape, a line of the pairs it was last looked up in.
//!
//! The table holds n² entries: a thousand shapes make it 4 MB, and the
//! sweep's pairs read it at random (a row a shape, shapes in no order in
//! memory), a cache and TLB miss each. A shape touches few shapes at a time,
//! so each shape keeps a cache line of [`WAYS`] entries (the other shape, the
//! table's entry for the pair), filled when a look-up finds neither shape's
//! line holding the pair (a line's ways replaced in turn) and emptied of a pair
//! whenever its table entry is written: a line's entry is always the table's,
//! so a look-up through the lines returns the table's entry, bit for bit.
//! An entry allowed and not made yet ([`LAZY_PAIR`]) is not kept: it is
//! written as the pair is made.

use crate::contact::fetch::prefetch;

/// "No pair" in the pair table.
pub(crate) const NO_PAIR: u32 = u32::MAX;
/// A pair the filter allows whose state is not made yet (made when its boxes
/// first overlap: a pile of n shapes allows n²/2 pairs and ever touches O(n)).
pub(crate) const LAZY_PAIR: u32 = u32::MAX - 1;

/// Entries a shape's line keeps.
const WAYS: usize = 8;
/// An empty entry's other shape (no shape's index: the table has fewer than
/// u32::MAX shapes).
const EMPTY: u32 = u32::MAX;

/// A shape's line: the other shape and the table's entry of [`WAYS`] pairs
/// of it (one cache line).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line {
    other: [u32; WAYS],
    entry: [u32; WAYS],
}

impl Line {
    const EMPTY: Line = Line {
        other: [EMPTY; WAYS],
        entry: [0; WAYS],
    };
    /// The ways holding shape `j`, as bits (at most one: a pair is kept only
    /// when its line does not hold it).
    #[inline(always)]
    fn ways_of(&self, j: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{
                __m128i, _mm_castsi128_ps, _mm_cmpeq_epi32, _mm_loadu_si128, _mm_movemask_ps,
                _mm_set1_epi32,
            };
            // SAFETY: SSE2 is part of x86_64; the two loads read the line's
            // eight `other` entries (two runs of four u32 inside the array).
            unsafe {
                let jj = _mm_set1_epi32(j as i32);
                let at = self.other.as_ptr().cast::<__m128i>();
                let lo = _mm_cmpeq_epi32(_mm_loadu_si128(at), jj);
                let hi = _mm_cmpeq_epi32(_mm_loadu_si128(at.add(1)), jj);
                (_mm_movemask_ps(_mm_castsi128_ps(lo))
                    | (_mm_movemask_ps(_mm_castsi128_ps(hi)) << 4)) as u32
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            (0..WAYS).fold(0, |m, w| m | (u32::from(self.other[w] == j) << w))
        }
    }
    /// The entry kept for the pair with shape `j`, or [`LAZY_PAIR`] (none
    /// kept; never a kept entry).
    #[inline(always)]
    fn find(&self, j: u32) -> u32 {
        let m = self.ways_of(j);
        if m == 0 {
            return LAZY_PAIR;
        }
        self.entry[m.trailing_zeros() as usize % WAYS]
    }
    /// Keeps entry `e` of the pair with shape `j` (not kept yet) in way `w`.
    #[inline]
    fn keep(&mut self, w: usize, j: u32, e: u32) {
        self.other[w % WAYS] = j;
        self.entry[w % WAYS] = e;
    }
    /// Forgets the pair with shape `j`.
    #[inline]
    fn forget(&mut self, j: u32) {
        for w in 0..WAYS {
            if self.other[w] == j {
                self.other[w] = EMPTY;
            }
        }
    }
}

/// The pairs of shapes the filter allows, and the index of those made: one
/// entry a pair of shapes (`idx[i·n + j]`: a pair index, [`LAZY_PAIR`] or
/// [`NO_PAIR`]), and each shape's line of entries (module docs).
#[derive(Clone, Debug, Default)]
pub struct PairTable {
    n: usize,
    idx: Vec<u32>,
    lines: Vec<Line>,
    /// Each line's way replaced next.
    next: Vec<u8>,
}

impl PairTable {
    /// No pair allowed among `n` shapes.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            idx: vec![NO_PAIR; n * n],
            lines: vec![Line::EMPTY; n],
            next: vec![0; n],
        }
    }
    /// Writes entry `e` of shapes i, j (both below n), and forgets the pair
    /// in their lines.
    #[inline]
    fn write(&mut self, i: usize, j: usize, e: u32) {
        self.idx[i * self.n + j] = e;
        self.idx[j * self.n + i] = e;
        if let Some(l) = self.lines.get_mut(i) {
            l.forget(j as u32);
        }
        if let Some(l) = self.lines.get_mut(j) {
            l.forget(i as u32);
        }
    }
    /// Allows the pair of shapes i, j (not made yet).
    pub(crate) fn allow(&mut self, i: usize, j: usize) {
        if i < self.n && j < self.n {
            self.write(i, j, LAZY_PAIR);
        }
    }
    /// Whether the pair of shapes i, j is allowed.
    #[inline]
    pub(crate) fn allowed(&self, i: usize, j: usize) -> bool {
        self.get(i, j) != NO_PAIR
    }
    /// The pair of shapes i, j: its index, [`LAZY_PAIR`] (allowed, not made)
    /// or [`NO_PAIR`].
    #[inline]
    pub(crate) fn get(&self, i: usize, j: usize) -> u32 {
        if i < self.n && j < self.n {
            self.idx[i * self.n + j]
        } else {
            NO_PAIR
        }
    }
    /// [`Self::get`] through the shapes' lines: i's, then j's, then the
    /// table (its entry then kept in both lines unless [`LAZY_PAIR`]).
    #[inline]
    pub(crate) fn get_kept(&mut self, i: u32, j: u32) -> u32 {
        let (a, b) = (i as usize, j as usize);
        if let (Some(la), Some(lb)) = (self.lines.get(a), self.lines.get(b)) {
            let e = la.find(j);
            if e != LAZY_PAIR {
                debug_assert_eq!(e, self.get(a, b));
                return e;
            }
            let e = lb.find(i);
            if e != LAZY_PAIR {
                debug_assert_eq!(e, self.get(a, b));
                return e;
            }
        }
        let e = self.get(a, b);
        if e != LAZY_PAIR && a < self.n && b < self.n && a != b {
            for (s, o) in [(a, j), (b, i)] {
                if let (Some(l), Some(w)) = (self.lines.get_mut(s), self.next.get_mut(s)) {
                    l.keep(usize::from(*w), o, e);
                    *w = ((usize::from(*w) + 1) % WAYS) as u8;
                }
            }
        }
        e
    }
    /// Asks the cache for the lines of shapes i, j.
    #[inline(always)]
    pub(crate) fn fetch(&self, i: u32, j: u32) {
        if let Some(l) = self.lines.get(i as usize) {
            prefetch(l);
        }
        if let Some(l) = self.lines.get(j as usize) {
            prefetch(l);
        }
    }
    /// Records pair `p` made for the allowed shapes i, j.
    pub(crate) fn set(&mut self, i: usize, j: usize, p: u32) {
        if self.allowed(i, j) {
            self.write(i, j, p);
        }
    }
}
