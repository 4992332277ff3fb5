//! The awake trees' ranges of a [`MassFactor`] (src/sim/factor.rs): the
//! trees a factor and its solves work on while some sleep.

use super::MassFactor;
use crate::model::Model;

/// A tree's dof and body ranges, `None` for a tree on the world body (never
/// listed).
pub(super) type TreeSpan = Option<((usize, usize), (usize, usize))>;

/// The ranges of `model`'s trees in order, and whether the trees cover its
/// `n` dofs and its bodies (less the world) exactly: only then may the
/// factor work on some trees alone.
pub(super) fn tree_spans(model: &Model, n: usize) -> (Vec<TreeSpan>, bool) {
    let spans = model
        .trees
        .iter()
        .map(|t| {
            (t.bodies.start >= 1).then_some(((t.v.start, t.v.end), (t.bodies.start, t.bodies.end)))
        })
        .collect();
    // Σ |dofs of a tree| = n and Σ |bodies of a tree| + 1 = nbodies
    let cover = model.trees.iter().map(|t| t.v.len()).sum::<usize>() == n
        && model.trees.iter().map(|t| t.bodies.len()).sum::<usize>() + 1 == model.nbodies;
    (spans, cover)
}

impl MassFactor {
    /// The next [`Self::factor_at`] (and the solves until the next factor)
    /// work on the trees of `model` not flagged in `asleep` (per tree;
    /// `None`: every tree): a forest's trees are independent blocks of H̃.
    pub fn set_awake(&mut self, model: &Model, asleep: Option<&[bool]>) {
        self.partial = false;
        let Some(asleep) = asleep.filter(|_| self.tree) else {
            return;
        };
        // (the lists depend on the mask alone: kept while it stands, which
        // is most steps of a pile with sleep on; an empty mask never lists)
        if asleep == &self.ranges_mask[..] && !asleep.is_empty() {
            self.partial = self.ranges_partial;
            return;
        }
        self.list_awake(model, asleep);
    }

    /// [`Self::set_awake`]'s lists of the trees not flagged in `asleep`,
    /// from the trees' ranges taken at [`Self::new`] (taken again if
    /// `model`'s trees are not those). Partial only when the mask has one
    /// flag a tree and the trees cover the model; else the lists go unused
    /// ([`Self::ranges`] gives every dof).
    #[inline(never)]
    fn list_awake(&mut self, model: &Model, asleep: &[bool]) {
        if self.spans.len() != model.trees.len() {
            (self.spans, self.spans_cover) = tree_spans(model, self.n);
        }
        self.dof_ranges.clear();
        self.body_ranges.clear();
        for (span, &a) in self.spans.iter().zip(asleep) {
            if let (Some((v, b)), false) = (span, a) {
                self.dof_ranges.push(*v);
                self.body_ranges.push(*b);
            }
        }
        self.partial = self.spans_cover && asleep.len() == self.spans.len();
        self.ranges_mask.clear();
        self.ranges_mask.extend_from_slice(asleep);
        self.ranges_partial = self.partial;
    }
}
