//! The awake trees' ranges of a [`MassFactor`] (src/sim/factor.rs): the
//! trees a factor and its solves work on while some sleep.

use super::MassFactor;
use crate::model::Model;

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

    /// [`Self::set_awake`]'s lists of the trees not flagged in `asleep`
    /// (from the trees' ranges taken once, `spans`, when they are `model`'s).
    #[inline(never)]
    fn list_awake(&mut self, model: &Model, asleep: &[bool]) {
        self.dof_ranges.clear();
        self.body_ranges.clear();
        if self.spans.len() == model.trees.len() && asleep.len() == self.spans.len() {
            for (span, &a) in self.spans.iter().zip(asleep) {
                if let (Some((v, b)), false) = (span, a) {
                    self.dof_ranges.push(*v);
                    self.body_ranges.push(*b);
                }
            }
            self.partial = self.spans_cover;
        } else {
            let (mut nv, mut nb) = (0, 0);
            for (t, tree) in model.trees.iter().enumerate() {
                nv += tree.v.len();
                nb += tree.bodies.len();
                if asleep.get(t) == Some(&true) || tree.bodies.start < 1 {
                    continue;
                }
                self.dof_ranges.push((tree.v.start, tree.v.end));
                self.body_ranges.push((tree.bodies.start, tree.bodies.end));
            }
            // the trees must cover the model exactly, else everything is done
            self.partial =
                nv == self.n && nb + 1 == model.nbodies && asleep.len() == model.trees.len();
        }
        self.ranges_mask.clear();
        self.ranges_mask.extend_from_slice(asleep);
        self.ranges_partial = self.partial;
    }
}
