//! The whole contact pipeline of a simulation: the ground's fast path, then the
//! pairs (obstacles, other bodies, self-collision).

use super::filter::DroppedPair;
use super::ground::GroundContact;
use super::pairs::{PairContact, Runner};
use super::{ContactError, ContactParams, ContactPoint};
use crate::model::Model;
use crate::spatial::Se3;
use std::path::PathBuf;

/// Every shape that can touch something, and where its points go.
#[derive(Clone, Debug)]
pub struct Collision {
    /// Contact with the ground plane (`None`: no ground, or no moving shape).
    pub ground: Option<GroundContact>,
    /// Contact between pairs of shapes (`None`: no pair may touch).
    pub pairs: Option<PairContact>,
    /// The pairs dropped at the start (scene.md rule 4), as last decided.
    pub dropped: Vec<DroppedPair>,
    /// The contact parameters it was built with.
    pub params: ContactParams,
    /// Total number of slots (ground first, then pairs).
    pub nslots: usize,
}

impl Collision {
    /// The pipeline of `model` with the ground at `ground` (`None`: no
    /// ground); `None` when nothing can touch anything (no contact work).
    pub fn build(
        model: &Model,
        ground: Option<f64>,
        params: ContactParams,
        package_paths: &[PathBuf],
    ) -> Result<Option<Self>, ContactError> {
        let g = match ground {
            Some(h) => GroundContact::build(model, h, params, package_paths)?,
            None => None,
        };
        let offset = g.as_ref().map_or(0, |g| g.nslots);
        let pairs = PairContact::build(model, &params, package_paths, offset)?;
        if g.is_none() && pairs.is_none() {
            return Ok(None);
        }
        let nslots = offset + pairs.as_ref().map_or(0, |p| p.nslots);
        Ok(Some(Self {
            ground: g,
            pairs,
            dropped: Vec::new(),
            params,
            nslots,
        }))
    }

    /// The ground height, when there is a ground.
    pub fn ground_height(&self) -> Option<f64> {
        self.ground.as_ref().map(|g| g.ground)
    }

    /// Narrow-phase queries so far (ground shapes and pairs).
    pub fn queries(&self) -> u64 {
        self.ground.as_ref().map_or(0, |g| g.queries) + self.pairs.as_ref().map_or(0, |p| p.queries)
    }

    /// The largest number of points a detection returns without allocating.
    pub fn max_points(&self) -> usize {
        self.ground.as_ref().map_or(0, |g| g.max_points())
            + self.pairs.as_ref().map_or(0, |p| p.max_points())
    }

    /// The lowest point of the moving shapes (the ground path's; +∞ without).
    pub fn lowest_point(&self, o_m_i: &[Se3<f64>]) -> f64 {
        self.ground
            .as_ref()
            .map_or(f64::INFINITY, |g| g.lowest_point(o_m_i))
    }

    /// Forgets what earlier detections left (kept points, search starts,
    /// the pairs' manifolds and slot features): the next detection finds what
    /// a newly built pipeline would.
    pub fn forget_history(&mut self) {
        if let Some(g) = self.ground.as_mut() {
            g.forget_history();
        }
        if let Some(p) = self.pairs.as_mut() {
            p.forget_history();
        }
    }

    /// The next detection follows a step: the speculative margin measures
    /// each shape's travel in it, times `scale` (the next step's length over
    /// this one's), docs/theory.md §"Speculative margin".
    pub fn stepped(&mut self, scale: f64) {
        if let Some(g) = self.ground.as_mut() {
            g.stepped(scale);
        }
        if let Some(p) = self.pairs.as_mut() {
            p.stepped(scale);
        }
    }

    /// Every contact point at the body poses `o_m_i`, into `out` (cleared).
    /// Bodies flagged in `asleep` (indexed by body; empty: none) are not
    /// searched against the static world or each other (a sleeping island's
    /// contacts are frozen, `sim::sleep`).
    pub fn detect(&mut self, o_m_i: &[Se3<f64>], out: &mut Vec<ContactPoint>, asleep: &[bool]) {
        self.detect_on(o_m_i, out, asleep, None);
    }

    /// [`Self::detect`], the ground's shapes (with the pairs' broad phase
    /// beside them) and the pairs' narrow phase on `run`'s threads when it is
    /// worth it (the same points, bit for bit: src/contact/ground/team.rs,
    /// src/contact/pairs/visit.rs).
    pub(crate) fn detect_on(
        &mut self,
        o_m_i: &[Se3<f64>],
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        run: Option<&dyn Runner>,
    ) {
        out.clear();
        match (self.ground.as_mut(), self.pairs.as_mut()) {
            (Some(g), Some(p)) if run.is_some_and(|r| r.threads() > 1) => {
                // the pairs' broad phase as one item of the ground's job (the
                // two touch nothing of each other's): on a team, the two at once
                // (its member loop by ranges on every thread, its sweep on
                // this one: src/contact/pairs/members.rs)
                let broad = p.broad_team(o_m_i);
                g.detect_on(o_m_i, out, asleep, run, Some(&broad));
                drop(broad);
                p.visit_pairs(out, asleep, run);
            }
            (g, p) => {
                if let Some(g) = g {
                    g.detect_on(o_m_i, out, asleep, run, None);
                }
                if let Some(p) = p {
                    p.detect_on(o_m_i, out, asleep, run);
                }
            }
        }
    }

    /// Bounding spheres of every moving collision shape: (body, centre in the
    /// body frame, radius).
    pub fn body_spheres(&self) -> Vec<(usize, nalgebra::Vector3<f64>, f64)> {
        let mut out = Vec::new();
        if let Some(g) = &self.ground {
            for s in g.shapes.iter() {
                out.push((s.body, s.placement.trans, s.bound));
            }
        }
        if let Some(p) = &self.pairs {
            out.extend(p.member_spheres());
        }
        out
    }

    /// Decides anew which self pairs overlap at the start (scene.md rule 4)
    /// at the body poses `o_m_i`; returns them (also kept in `dropped`).
    pub fn drop_start_overlaps(&mut self, model: &Model, o_m_i: &[Se3<f64>]) -> &[DroppedPair] {
        self.dropped = match self.pairs.as_mut() {
            Some(p) => p.drop_start_overlaps(model, o_m_i),
            None => Vec::new(),
        };
        &self.dropped
    }
}
