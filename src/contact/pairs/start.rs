//! Scene.md rule 4 for the pairs: the self pairs that overlap at the start
//! are dropped (src/contact/pairs/mod.rs).

use super::super::filter::{DroppedPair, START_OVERLAP};
use super::super::shapes::to_pose;
use super::{world, Member, PairContact, NO_KEY};
use crate::model::Model;
use crate::spatial::Se3;

impl PairContact {
    /// Drops the self pairs that overlap by more than [`START_OVERLAP`] at the
    /// body poses `o_m_i` (scene.md rule 4), after restoring every pair dropped
    /// before; returns them, with their links, from `model`.
    pub fn drop_start_overlaps(&mut self, model: &Model, o_m_i: &[Se3<f64>]) -> Vec<DroppedPair> {
        let mut out = Vec::new();
        self.dropped.fill(false);
        for (pi, pair) in self.pairs.iter_mut().enumerate() {
            if !pair.self_pair {
                continue;
            }
            let (ma, mb) = (&self.members[pair.a], &self.members[pair.b]);
            let (wa, wb) = (world(ma, o_m_i), world(mb, o_m_i));
            let c = parry3d_f64::query::contact(
                &to_pose(&wa),
                &*ma.shape.shape,
                &to_pose(&wb),
                &*mb.shape.shape,
                0.0,
            );
            if let Ok(Some(c)) = c {
                if c.dist < -START_OVERLAP {
                    self.dropped[pi] = true;
                    pair.manifolds.clear();
                    let maxp = self.max_points;
                    if let Some(k) = self.keys.get_mut(pi * maxp..(pi + 1) * maxp) {
                        k.fill(NO_KEY);
                    }
                    let link = |m: &Member| {
                        model
                            .collisions
                            .get(m.geom)
                            .map_or(String::new(), |g| g.link.clone())
                    };
                    out.push(DroppedPair {
                        a: link(ma),
                        b: link(mb),
                        depth: -c.dist,
                    });
                }
            }
        }
        out
    }
}
