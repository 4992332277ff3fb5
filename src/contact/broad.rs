//! The broad phase: sweep and prune over world-aligned boxes.
//!
//! Each shape's box is its own box (in its frame) at its pose, boxed again
//! along the world axes (centre R·c + t, half extents |R|·h) and grown by the
//! detection margin, refreshed every step for the shapes that move. The shapes
//! are kept sorted by their boxes' lower x (an insertion sort: nearly sorted
//! from step to step, O(n)); a sweep along x meets each shape only the shapes
//! whose x-interval overlaps its own, and keeps the pairs that also overlap in
//! y and z and that the pair filter allows (a table of pair indices).

/// "No pair" in the pair table.
pub(crate) const NO_PAIR: u32 = u32::MAX;
/// A pair the filter allows whose state is not made yet (made when its boxes
/// first overlap: a pile of n shapes allows n²/2 pairs and ever touches O(n)).
pub(crate) const LAZY_PAIR: u32 = u32::MAX - 1;

/// The sweep's state.
#[derive(Clone, Debug, Default)]
pub(crate) struct SweepAndPrune {
    /// Lower and upper corners of each shape's box.
    pub lo: Vec<[f64; 3]>,
    /// Upper corners.
    pub hi: Vec<[f64; 3]>,
    /// The shapes by their boxes' lower x.
    order: Vec<u32>,
}

impl SweepAndPrune {
    /// Room for `n` shapes (boxes empty until set).
    pub fn new(n: usize) -> Self {
        Self {
            lo: vec![[f64::INFINITY; 3]; n],
            hi: vec![[f64::NEG_INFINITY; 3]; n],
            order: (0..n as u32).collect(),
        }
    }

    /// Sets shape `i`'s box to centre c ± half extents h.
    #[inline]
    pub fn set(&mut self, i: usize, c: [f64; 3], h: [f64; 3]) {
        self.lo[i] = [c[0] - h[0], c[1] - h[1], c[2] - h[2]];
        self.hi[i] = [c[0] + h[0], c[1] + h[1], c[2] + h[2]];
    }

    /// The overlapping pairs the table allows (`table[i·n + j]` the pair index
    /// of shapes i, j, or [`NO_PAIR`]), appended to `out`; those marked
    /// [`LAZY_PAIR`] (allowed, not made yet) as shapes (i, j) to `fresh`.
    pub fn overlaps(&mut self, table: &[u32], out: &mut Vec<u32>, fresh: &mut Vec<(u32, u32)>) {
        let n = self.order.len();
        // insertion sort by lower x
        for k in 1..n {
            let mut m = k;
            while m > 0
                && self.lo[self.order[m - 1] as usize][0] > self.lo[self.order[m] as usize][0]
            {
                self.order.swap(m - 1, m);
                m -= 1;
            }
        }
        for k in 0..n {
            let i = self.order[k] as usize;
            let (li, hi) = (self.lo[i], self.hi[i]);
            for &j in &self.order[k + 1..] {
                let j = j as usize;
                let lj = self.lo[j];
                if lj[0] > hi[0] {
                    break;
                }
                let hj = self.hi[j];
                if lj[1] > hi[1] || li[1] > hj[1] || lj[2] > hi[2] || li[2] > hj[2] {
                    continue;
                }
                match table.get(i * n + j) {
                    Some(&LAZY_PAIR) => fresh.push((i as u32, j as u32)),
                    Some(&p) if p != NO_PAIR => out.push(p),
                    _ => {}
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_exactly_the_overlapping_allowed_pairs() {
        // four unit spheres on the x axis at 0, 1.5, 3, 10: 0–1 and 1–2 overlap
        let mut s = SweepAndPrune::new(4);
        for (i, x) in [10.0, 0.0, 1.5, 3.0].into_iter().enumerate() {
            s.set(i, [x, 0.0, 0.0], [1.0; 3]);
        }
        // every pair allowed, pair index = 10·min + max
        let mut table = vec![NO_PAIR; 16];
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    table[i * 4 + j] = (10 * i.min(j) + i.max(j)) as u32;
                }
            }
        }
        let mut out = Vec::new();
        s.overlaps(&table, &mut out, &mut Vec::new());
        out.sort();
        assert_eq!(out, vec![12, 23]);
        // moved apart in z: none
        s.set(2, [1.5, 0.0, 5.0], [1.0; 3]);
        out.clear();
        s.overlaps(&table, &mut out, &mut Vec::new());
        assert!(out.is_empty(), "{out:?}");
        // a pair the filter forbids is not reported
        s.set(2, [1.5, 0.0, 0.0], [1.0; 3]);
        table[1 * 4 + 2] = NO_PAIR;
        table[2 * 4 + 1] = NO_PAIR;
        out.clear();
        s.overlaps(&table, &mut out, &mut Vec::new());
        assert_eq!(out, vec![23]);
        // a pair allowed but not made yet is reported by its shapes
        table[1 * 4 + 2] = LAZY_PAIR;
        table[2 * 4 + 1] = LAZY_PAIR;
        out.clear();
        let mut fresh = Vec::new();
        s.overlaps(&table, &mut out, &mut fresh);
        assert_eq!(out, vec![23]);
        let fresh: Vec<_> = fresh.iter().map(|&(i, j)| (i.min(j), i.max(j))).collect();
        assert_eq!(fresh, vec![(1, 2)]);
    }
}
