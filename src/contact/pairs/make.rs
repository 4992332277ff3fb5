//! Making a pair of members (its state, slots and place in the table) and,
//! once every allowed pair is made among few shapes, the masks that replace the
//! sweep ([`PairMasks`]): [`PairContact`]'s bookkeeping, beside its detection.

use super::{Pair, PairContact, NO_KEY};
use crate::contact::broad::{PairMasks, STRIPS_FROM};
use crate::contact::narrow::face_kind;
use nalgebra::Vector3;

impl PairContact {
    /// Makes the pair of members `i` and `j` (allowed, not made yet): its
    /// state, its slots (the next `max_points`), its place in the table.
    pub(super) fn make_pair(&mut self, i: usize, j: usize) -> u32 {
        // members are in geometry order: the lower one first, as the filter
        // enumerated them (the sweep meets them in either order)
        let (i, j) = (i.min(j), i.max(j));
        let (mi, mj) = (&self.members[i], &self.members[j]);
        // a non-convex shape (a mesh obstacle, a height field) is never shape
        // a: parry is given it second
        let (a, b) = if mi.shape.convex || !mj.shape.convex {
            (i, j)
        } else {
            (j, i)
        };
        let (ga, gb) = (self.members[a].geom as u64, self.members[b].geom as u64);
        let p = self.pairs.len() as u32;
        self.table.set(a, b, p);
        let maxp = self.max_points;
        let self_pair = self.model_of[a].is_some() && self.model_of[a] == self.model_of[b];
        let ord = ga.min(gb) * self.ngeoms + ga.max(gb);
        // (still numbered in visiting order: ranked with those before it)
        if self.ranked == self.ords.len() && self.ords.last().is_none_or(|&l| l <= ord) {
            self.ranked += 1;
        }
        self.ords.push(ord);
        self.keys.extend(std::iter::repeat_n(NO_KEY, maxp));
        self.dropped.push(false);
        self.made_since_sort += 1;
        self.pairs.push(Pair {
            a,
            b,
            slot_base: self.slot_offset + p as usize * maxp,
            manifolds: Vec::new(),
            workspace: None,
            self_pair,
            axis: Vector3::zeros(),
            apart: None,
            face: face_kind(&self.members[a].shape, &self.members[b].shape),
            friction: self.friction[a].max(self.friction[b]),
        });
        p
    }

    /// Sets up the broad phase by masks ([`Self::listed`]) once every
    /// allowed pair is made among fewer than [`STRIPS_FROM`] shapes (after
    /// that no pair is made: the allowed pairs stay those).
    pub(super) fn list_pairs(&mut self) {
        if self.listed.is_some()
            || self.pairs.len() != self.allowed
            || self.members.len() >= STRIPS_FROM
        {
            return;
        }
        let pairs = self.pairs.iter().map(|p| (p.a, p.b));
        self.listed = PairMasks::new(self.members.len(), pairs);
    }
}
