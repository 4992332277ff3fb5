//! The ground detection on the calling thread, in two passes: every shape's
//! reach first ([`reach`]: its travel, its margin, culled or not, from the
//! small [`Cull`] records alone), then the narrow phase of the shapes within
//! reach, in shape order, each shape's record and vertices fetched into the
//! cache a few shapes ahead of its search (a shape's [`GroundShape`] and its
//! vertex block lie apart in memory: two cache misses a shape otherwise). A
//! shape's reach writes only its own anchor and travel, and its search reads
//! neither, so the points are those of one pass, bit for bit, in the same
//! order.

use super::{plain_points, reach, GroundContact, GroundShape, Manifold, Plain};
use crate::contact::fetch::fetch_lines;
use crate::contact::ContactPoint;
use crate::spatial::Se3;

/// Shapes within reach ahead of the search whose record is fetched, and
/// (half as far) whose vertices are (read from the record fetched before).
const AHEAD: usize = 6;

/// The most cache lines of a shape's vertices fetched ahead (a box's eight
/// vertices fill three; a hull's search reads only a few of its own).
const VERT_LINES: usize = 4;

/// The lines of shape `s`'s record its search reads fetched into the cache
/// (its pose's, its kind's, its vertices' and its points' template; not the
/// whole record, a dozen lines: fetched a shape, they pushed the broad
/// phase's arrays, read next, out of the cache).
#[inline(always)]
fn fetch_shape(s: &GroundShape) {
    fetch_lines(&s.template, std::mem::size_of::<ContactPoint>());
    fetch_lines(&s.at_body, 1);
    fetch_lines(&s.manifold, 1);
    fetch_lines(&s.verts, 1);
    fetch_lines(&s.adj, 1);
}

/// Shape `s`'s first vertices fetched into the cache (its record read).
#[inline(always)]
fn fetch_verts(s: &GroundShape) {
    let bytes = std::mem::size_of_val(&s.verts[..]).min(64 * VERT_LINES);
    fetch_lines(&s.verts[..], bytes);
}

impl GroundContact {
    /// The search of every shape on this thread, its points into `out`.
    pub(super) fn detect_serial(
        &mut self,
        o_m_i: &[Se3<f64>],
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        step: (f64, bool),
    ) {
        let ground = self.ground;
        let maxp = self.params.max_points_per_shape.max(1);
        // (the shapes never change: held apart from `self`, which the search mutates)
        let shapes = std::sync::Arc::clone(&self.shapes);
        let cull = std::sync::Arc::clone(&self.cull);
        // the first pass: each shape's reach, the shapes within it kept
        let mut reached = std::mem::take(&mut self.reached);
        reached.clear();
        for (si, cu) in cull.iter().enumerate() {
            let Some(o_m_b) = o_m_i.get(cu.body) else {
                continue;
            };
            if asleep.get(cu.body) == Some(&true) {
                continue;
            }
            let (ts, delta, c) = self.travel.split();
            let anchor = &mut self.anchor[si];
            if let Some(margin) = reach(cu, o_m_b, ground, step, anchor, ts.get_mut(si), (delta, c))
            {
                reached.push((si, margin));
            }
        }
        // the second pass: the search of the shapes within reach
        for (j, &(si, margin)) in reached.iter().enumerate() {
            if let Some(&(ahead, _)) = reached.get(j + AHEAD) {
                fetch_shape(&shapes[ahead]);
            }
            if let Some(&(ahead, _)) = reached.get(j + AHEAD / 2) {
                fetch_verts(&shapes[ahead]);
            }
            let (Some(s), Some(o_m_b)) = (
                shapes.get(si),
                cull.get(si).and_then(|cu| o_m_i.get(cu.body)),
            ) else {
                continue;
            };
            let o_m_g = s.pose(o_m_b);
            self.queries += 1;
            // a hull or point set: its lowest vertex is its support point toward
            // −z; only the heights are needed to find it and the candidates
            // (one dot product a vertex, no parry query)
            if s.manifold == Manifold::Vertices && !s.adj.is_empty() {
                // a hull: its patch from its vertex graph ([`super::patch`])
                self.hull_patch(si, s, &o_m_g, margin, maxp, out);
                continue;
            }
            let cx = Plain {
                ground,
                maxp,
                slot_offset: &self.slot_offset,
                prev_flag: &self.prev_flag,
                reduce_dirs: &self.reduce_dirs,
            };
            plain_points(s, si, &o_m_g, margin, &cx, &mut self.scratch, out);
        }
        self.reached = reached;
    }
}
