//! The pairs kept in visiting order, and each point put in its pair's slot.
//!
//! A detection visits the live pairs by `ord` (geometry pair order), while
//! pairs are made in the order boxes first meet: in a pile of a thousand
//! boxes a visit was a cache miss on each pair's state. Once an eighth of the
//! pairs are new, the pairs (their state, slot keys and flags) are sorted by
//! `ord` and the indices that name them renumbered; slots stay with their
//! pair (`slot_base`), so nothing a step computes changes. The overlapping
//! pairs of a step are put in that order by their numbers ([`PairContact::by_ord`]).

use super::{ContactPoint, PairContact, NO_KEY};

impl PairContact {
    /// Sorts the pairs by `ord` when more than an eighth were made since the
    /// last sort (module docs).
    pub(super) fn keep_in_order(&mut self) {
        let np = self.pairs.len();
        if self.made_since_sort * 8 <= np {
            return;
        }
        self.made_since_sort = 0;
        self.ranked = np;
        if self.ords.windows(2).all(|w| w[0] <= w[1]) {
            return;
        }
        let maxp = self.max_points;
        let mut z: Vec<_> = std::mem::take(&mut self.pairs)
            .into_iter()
            .enumerate()
            .map(|(k, p)| (self.ords[k], k, p))
            .collect();
        z.sort_unstable_by_key(|e| e.0);
        let mut inv = vec![0u32; np];
        let (mut keys, mut dropped) = (Vec::with_capacity(self.keys.len()), Vec::with_capacity(np));
        self.ords.clear();
        for (new, (ord, old, p)) in z.into_iter().enumerate() {
            inv[old] = new as u32;
            self.ords.push(ord);
            keys.extend_from_slice(self.keys.get(old * maxp..(old + 1) * maxp).unwrap_or(&[]));
            dropped.push(self.dropped.get(old).copied().unwrap_or(false));
            self.table.set(p.a, p.b, new as u32);
            self.pairs.push(p);
        }
        self.keys = keys;
        self.dropped = dropped;
        for e in self.live.iter_mut() {
            e.1 = inv.get(e.1 as usize).copied().unwrap_or(e.1);
        }
    }
}

/// Overlapping pairs up to which [`PairContact::by_ord`] sorts them.
const FEW: usize = 4;

impl PairContact {
    /// This detection's overlapping pairs `ids` (each once, in any order) as
    /// (ord, pair) by ord into `overlapping`: those numbered in visiting order
    /// (below `ranked`) marked a bit each and read off the bits in order, no
    /// sort; the few made since sorted and merged in. The order of a sort of
    /// them all by (ord, pair).
    pub(super) fn by_ord(&mut self, ids: &[u32]) {
        if ids.len() <= FEW {
            // (few: a sort of them is cheaper than the bits' bookkeeping)
            let ords = &self.ords;
            self.overlapping
                .extend(ids.iter().map(|&p| (ords[p as usize], p)));
            self.overlapping.sort_unstable();
            return;
        }
        let start = self.overlapping.len();
        let ranked = self.ranked.min(self.ords.len());
        let words = ranked.div_ceil(64);
        if self.seen.len() < words {
            self.seen.resize(words, 0);
        }
        self.tail.clear();
        for &p in ids {
            let k = p as usize;
            if k < ranked {
                self.seen[k / 64] |= 1 << (k % 64);
            } else if let Some(&o) = self.ords.get(k) {
                self.tail.push((o, p));
            }
        }
        // the bits read in order (and cleared: none set outside this call),
        // the made ones merged in as their turn comes
        self.tail.sort_unstable();
        let (ords, tail, ov) = (&self.ords, &self.tail, &mut self.overlapping);
        ov.reserve(ids.len());
        const END: (u64, u32) = (u64::MAX, u32::MAX);
        let mut t = 0;
        let mut next = tail.first().copied().unwrap_or(END);
        for (w, bits) in self.seen[..words].iter_mut().enumerate() {
            let mut b = std::mem::take(bits);
            while b != 0 {
                let k = w * 64 + b.trailing_zeros() as usize;
                b &= b - 1;
                let x = (ords[k], k as u32);
                while next < x {
                    ov.push(next);
                    t += 1;
                    next = tail.get(t).copied().unwrap_or(END);
                }
                ov.push(x);
            }
        }
        ov.extend_from_slice(tail.get(t..).unwrap_or(&[]));
        // (each pair once: as many as given, none lost to a shared bit)
        debug_assert_eq!(ov.len(), start + ids.len());
    }
}

/// Puts each of a pair's points in a slot: the one that held the same
/// features last step (not fresh), else a free one (fresh).
pub(super) fn assign_slots(slot_base: usize, keys: &mut [u64], pts: &mut [ContactPoint]) {
    let maxp = keys.len();
    let mut taken = [false; 64];
    let mut placed = [false; 64];
    for (k, p) in pts.iter_mut().enumerate().take(64) {
        if let Some(s) = keys.iter().position(|&key| key == p.key) {
            if !taken[s] {
                taken[s] = true;
                placed[k] = true;
                p.slot = slot_base + s;
                p.fresh = false;
            }
        }
    }
    for (k, p) in pts.iter_mut().enumerate().take(64) {
        if placed[k] {
            continue;
        }
        if let Some(s) = (0..maxp.min(64)).find(|&s| !taken[s]) {
            taken[s] = true;
            p.slot = slot_base + s;
            p.fresh = true;
        }
    }
    for (s, key) in keys.iter_mut().enumerate() {
        *key = NO_KEY;
        if let Some(p) = pts.iter().find(|p| p.slot == slot_base + s) {
            *key = p.key;
        }
    }
}
