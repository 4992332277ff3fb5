//! The pair filter of scene.md "Who touches whom": which pairs of collision
//! geometries may ever touch (decided once, from the model), and the self pairs
//! dropped because they already overlap at the start.

use crate::model::{CollisionGeom, Model, OBSTACLE};

/// Whether the geometries `a` and `b` of `model` may touch (rules 1–3 of
/// scene.md "Who touches whom"; rule 4, overlaps at the start, is
/// [`DroppedPair`]'s):
/// 1. not on the same body, not both welded to the world (body 0);
/// 2. not a body and its parent body within one model (the parent possibly the
///    model's links welded to the world: the same model on body 0);
/// 3. not of one model whose self-collision is off, not an excluded link pair.
pub(crate) fn may_touch(model: &Model, a: &CollisionGeom, b: &CollisionGeom) -> bool {
    if a.body == b.body {
        return false;
    }
    let filter = &model.collision_filter;
    if a.model == b.model && a.model != OBSTACLE {
        if !filter.self_collides(a.model) {
            return false;
        }
        let parent = |i: usize| model.parent.get(i).copied().unwrap_or(0);
        if parent(a.body) == b.body || parent(b.body) == a.body {
            return false;
        }
    }
    !filter.is_excluded(&a.link, &b.link)
}

/// Whether a pair is a self pair (two links of one model), the kind rule 4
/// drops when it overlaps at the start.
pub(crate) fn is_self_pair(a: &CollisionGeom, b: &CollisionGeom) -> bool {
    a.model == b.model && a.model != OBSTACLE
}

/// Start overlaps deeper than this (m) drop a self pair (scene.md rule 4).
pub const START_OVERLAP: f64 = 1e-3;

/// A self pair dropped because its shapes overlapped by more than
/// [`START_OVERLAP`] at the start (real URDFs' coarse collision meshes often
/// overlap at rest): it never touches in this run.
#[derive(Clone, Debug, PartialEq)]
pub struct DroppedPair {
    /// One side's link.
    pub a: String,
    /// The other side's link.
    pub b: String,
    /// The overlap found (m, positive).
    pub depth: f64,
}

impl std::fmt::Display for DroppedPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "links \"{}\" and \"{}\" overlap by {:.4} m at the start: that pair is not in contact",
            self.a, self.b, self.depth
        )
    }
}
