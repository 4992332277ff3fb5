//! The strips' width of the broad phase's sweep (src/contact/broad.rs): the
//! widest ordinary y-extent, w = max{e : e ≤ BIG · m} over the shapes' finite
//! y-extents e, m their median (the extent of rank ⌊k/2⌋ of the k finite ones,
//! ascending); +∞ when there is none or w ≤ 0.
//!
//! The median is found in a band about the last step's: one pass counts the
//! extents below the band, keeps those in it, and takes the maximum of those
//! at most BIG times the band's lower end (ordinary whatever the median in the
//! band: BIG·lower ≤ BIG·m, rounding being monotone), keeps those up to BIG
//! times its upper end (ordinary or not by the median), and leaves the rest
//! (wider than BIG·m). When the rank ⌊k/2⌋ falls in the band, the median is
//! the band's extent of rank ⌊k/2⌋ − (those below) — the same number a
//! selection over all of them gives — and w is the larger of that maximum and
//! the kept ones' at most BIG·m. Else (the first step, a jump) the selection
//! over every extent, as before. Either way the same w, bit for bit: the
//! band is a guess that only saves the selection's work.

/// The band about the last median: its lower and upper ends are the last
/// median times these.
const BAND: (f64, f64) = (1.0 - 1.0 / 128.0, 1.0 + 1.0 / 128.0);

/// The scratch of [`Width::of`] and its last median.
#[derive(Clone, Debug, Default)]
pub(super) struct Width {
    /// The last median (0: none yet).
    last: f64,
    /// The extents in the band, those between BIG times its ends, and (the
    /// selection over all) every finite extent.
    band: Vec<f64>,
    unsure: Vec<f64>,
    all: Vec<f64>,
}

impl Width {
    /// Room for `n` shapes.
    pub(super) fn new(n: usize) -> Self {
        Self {
            last: 0.0,
            band: vec![0.0; n + 1],
            unsure: vec![0.0; n + 1],
            all: Vec::with_capacity(n),
        }
    }

    /// w of the boxes `lo`, `hi` (module docs), `big` = BIG.
    pub(super) fn of(&mut self, lo: &[[f64; 3]], hi: &[[f64; 3]], big: f64) -> f64 {
        let (b0, b1) = (self.last * BAND.0, self.last * BAND.1);
        let (sure, unsure) = (big * b0, big * b1);
        // (each extent written at the lists' ends and kept by its count: no
        // branch an extent; room for every one, never cleared)
        let n = lo.len().min(hi.len());
        if self.band.len() < n + 1 {
            self.band.resize(n + 1, 0.0);
            self.unsure.resize(n + 1, 0.0);
        }
        let (band, uns) = (&mut self.band[..n + 1], &mut self.unsure[..n + 1]);
        // Σ finite, Σ below the band, max{e ≤ BIG·b0} (from +0, the fold's
        // start; a max of finite numbers: the same whatever their order, but
        // for the sign of a zero, which w ≤ 0 does not keep)
        let (mut finite, mut below, mut w) = (0usize, 0usize, 0.0f64);
        let (mut nb, mut nu) = (0usize, 0usize);
        for (l, h) in lo[..n].iter().zip(&hi[..n]) {
            let e = h[1] - l[1];
            if !e.is_finite() {
                continue;
            }
            finite += 1;
            below += usize::from(e < b0);
            band[nb] = e;
            nb += usize::from(e >= b0 && e <= b1);
            if e <= sure {
                if e > w {
                    w = e;
                }
            } else {
                uns[nu] = e;
                nu += usize::from(e <= unsure);
            }
        }
        let (band, uns) = (&mut band[..nb], &uns[..nu]);
        let mid = finite / 2;
        let med = if b0 > 0.0 && below <= mid && mid - below < band.len() {
            // the median in the band: its rank there
            *band.select_nth_unstable_by(mid - below, f64::total_cmp).1
        } else {
            // every finite extent's selection
            self.all.clear();
            self.all.extend(
                lo.iter()
                    .zip(hi)
                    .map(|(l, h)| h[1] - l[1])
                    .filter(|e| e.is_finite()),
            );
            if self.all.is_empty() {
                return f64::INFINITY;
            }
            let med = *self.all.select_nth_unstable_by(mid, f64::total_cmp).1;
            self.last = med;
            let w = (self.all.iter().copied())
                .filter(|&e| e <= big * med)
                .fold(0.0f64, f64::max);
            return if w > 0.0 { w } else { f64::INFINITY };
        };
        self.last = med;
        let cap = big * med;
        for &e in uns {
            if e <= cap && e > w {
                w = e;
            }
        }
        if w > 0.0 {
            w
        } else {
            f64::INFINITY
        }
    }
}
