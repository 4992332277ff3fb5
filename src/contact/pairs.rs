//! Contact between two collision shapes (two bodies, or a body and a static
//! obstacle): the shapes, the pairs the filter allows, the broad phase and the
//! narrow phase with parry's persistent contact manifolds.
//!
//! Per step: every moving shape's box is refreshed ([`super::broad`]); for
//! each allowed pair whose boxes overlap, parry computes its contact manifolds
//! (`PersistentQueryDispatcher::contact_manifolds`: convex–convex by its
//! polyhedral and GJK/EPA generators, convex–triangle mesh and convex–height
//! field triangle by triangle), kept in the pair between steps (parry matches
//! the new points to the old by their features). The points within the margin
//! are reduced to at most `max_points_per_shape` (the deepest, then the
//! extremes along tangent directions of its normal), each put in one of the
//! pair's slots: the slot of the same features last step (its impulse warm
//! starts the solve), else a free one marked fresh (no warm start).

use super::broad::{SweepAndPrune, NO_PAIR};
use super::filter::{is_self_pair, may_touch, DroppedPair, START_OVERLAP};
use super::narrow::{face_kind, face_points, parry_points, reduce_pair, FaceScratch, Raw};
use super::shapes::{from_pvec, pair_shape, to_pose, to_pvec, PairShape};
use super::{ContactError, ContactParams, ContactPoint};
use crate::model::Model;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::query::{ContactManifold, ContactManifoldsWorkspace};
use std::path::PathBuf;

/// One shape of pair contact.
#[derive(Clone, Debug)]
struct Member {
    /// Index into the model's collisions.
    geom: usize,
    body: usize,
    /// `body_M_parry`.
    placement: Se3<f64>,
    shape: PairShape,
}

/// The persistent state of one allowed pair.
#[derive(Clone)]
struct Pair {
    /// Member indices (a < b; a moves, or both do).
    a: usize,
    b: usize,
    /// The first of its slots (global).
    slot_base: usize,
    /// The features each of its slots held last step (`NO_KEY`: free).
    keys: Vec<u64>,
    manifolds: Vec<ContactManifold<(), ()>>,
    workspace: Option<ContactManifoldsWorkspace>,
    /// Dropped at the start (rule 4).
    dropped: bool,
    /// A self pair (rule 4 applies).
    self_pair: bool,
    /// A unit axis (a's frame, from a toward b) that separated the two
    /// shapes last time, or their contact normal (zero: none).
    axis: Vector3<f64>,
    /// The last time `axis` separated the shapes by more than the margin:
    /// the gap along it and both shapes' world poses then (see
    /// [`still_apart`]).
    apart: Option<(f64, Se3<f64>, Se3<f64>)>,
    /// A hull and a box or height field (`Some(true)`: the hull is a): the
    /// face path ([`hull_on_face`]) is tried first.
    face: Option<bool>,
    friction: f64,
}

const NO_KEY: u64 = u64::MAX;

/// Contact between pairs of shapes.
#[derive(Clone)]
pub struct PairContact {
    members: Vec<Member>,
    pairs: Vec<Pair>,
    /// `table[i·n + j]`: the pair of members i, j ([`NO_PAIR`]: none).
    table: Vec<u32>,
    sap: SweepAndPrune,
    overlapping: Vec<u32>,
    /// The pairs holding anything after the last detection (points, manifolds,
    /// a separating axis), ascending: with the overlapping ones, the only pairs
    /// a detection visits (never all pairs: their count is the square of the scene's).
    live: Vec<u32>,
    /// The pairs a detection visits (overlapping ∪ live), ascending.
    visit: Vec<u32>,
    /// Each member's world pose (parry's frame) at the last detection.
    poses: Vec<Se3<f64>>,
    scratch: FaceScratch,
    stamp: u32,
    raw: Vec<Raw>,
    /// Members that move (their boxes are refreshed each step).
    moving: Vec<usize>,
    /// Slots in all.
    pub nslots: usize,
    /// Narrow-phase queries performed so far (one a pair whose boxes overlap).
    pub queries: u64,
    margin: f64,
    max_points: usize,
    /// The first slot of pair contact in the whole pipeline.
    slot_offset: usize,
}

impl std::fmt::Debug for PairContact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairContact")
            .field("members", &self.members.len())
            .field("pairs", &self.pairs.len())
            .finish()
    }
}

/// World pose of a member at the body poses `o_m_i`.
#[inline]
fn world(m: &Member, o_m_i: &[Se3<f64>]) -> Se3<f64> {
    o_m_i
        .get(m.body)
        .map_or(m.placement, |o| o.compose(&m.placement))
}

/// The contact frame's tangents ([`super::frame::tangents`]), here too.
pub use super::frame::tangents;

impl PairContact {
    /// The pairs of `model`'s geometries that may touch (none: `None`, and no
    /// shape is built). `slot_offset`: the first slot number it may use.
    pub fn build(
        model: &Model,
        params: &ContactParams,
        package_paths: &[PathBuf],
        slot_offset: usize,
    ) -> Result<Option<Self>, ContactError> {
        let g = &model.collisions;
        let mut wanted = vec![false; g.len()];
        let mut any = false;
        for i in 0..g.len() {
            for j in i + 1..g.len() {
                if may_touch(model, &g[i], &g[j]) {
                    wanted[i] = true;
                    wanted[j] = true;
                    any = true;
                }
            }
        }
        if !any {
            return Ok(None);
        }
        let mut members = Vec::new();
        let mut member_of = vec![usize::MAX; g.len()];
        for (k, geom) in g.iter().enumerate() {
            if !wanted[k] {
                continue;
            }
            let Some(shape) = pair_shape(geom, model, package_paths)? else {
                continue;
            };
            member_of[k] = members.len();
            members.push(Member {
                geom: k,
                body: geom.body,
                placement: geom.placement.compose(&shape.offset),
                shape,
            });
        }
        let n = members.len();
        let maxp = params.max_points_per_shape.max(1);
        let mut table = vec![NO_PAIR; n * n];
        let mut pairs = Vec::new();
        for i in 0..g.len() {
            for j in i + 1..g.len() {
                let (a, b) = (member_of[i], member_of[j]);
                if a == usize::MAX || b == usize::MAX || !may_touch(model, &g[i], &g[j]) {
                    continue;
                }
                // a non-convex shape (a mesh obstacle, a height field) is
                // never shape a: parry is given it second
                let (a, b) = if members[a].shape.convex || !members[b].shape.convex {
                    (a, b)
                } else {
                    (b, a)
                };
                if !members[a].shape.convex {
                    continue; // two non-convex shapes (both static): never
                }
                let p = pairs.len() as u32;
                table[a * n + b] = p;
                table[b * n + a] = p;
                pairs.push(Pair {
                    a,
                    b,
                    slot_base: slot_offset + pairs.len() * maxp,
                    keys: vec![NO_KEY; maxp],
                    manifolds: Vec::new(),
                    workspace: None,
                    dropped: false,
                    self_pair: is_self_pair(&g[i], &g[j]),
                    axis: Vector3::zeros(),
                    apart: None,
                    face: face_kind(&members[a].shape, &members[b].shape),
                    friction: g[i].friction.max(g[j].friction),
                });
            }
        }
        if pairs.is_empty() {
            return Ok(None);
        }
        let mut sap = SweepAndPrune::new(n);
        let mut moving = Vec::new();
        let mut poses = Vec::with_capacity(n);
        for (k, m) in members.iter().enumerate() {
            poses.push(m.placement);
            if m.body == 0 {
                set_box(&mut sap, k, m, &m.placement, params.margin);
            } else {
                moving.push(k);
            }
        }
        Ok(Some(Self {
            nslots: pairs.len() * maxp,
            members,
            table,
            sap,
            overlapping: Vec::new(),
            live: Vec::new(),
            visit: Vec::new(),
            poses,
            scratch: FaceScratch::default(),
            stamp: 0,
            raw: Vec::new(),
            moving,
            queries: 0,
            margin: params.margin,
            max_points: maxp,
            slot_offset,
            pairs,
        }))
    }

    /// Forgets every pair's manifolds and the features its slots held: the
    /// next detection finds what a newly built one would.
    pub fn forget_history(&mut self) {
        for pair in self.pairs.iter_mut() {
            pair.keys.iter_mut().for_each(|k| *k = NO_KEY);
            pair.manifolds.clear();
            pair.workspace = None;
            pair.apart = None;
        }
    }

    /// The most points a step can report: each pair's limit, for at most 8
    /// pairs touching a moving shape at once (more are found, and cost an
    /// allocation, in crowded scenes).
    pub fn max_points(&self) -> usize {
        self.pairs.len().min(8 * self.moving.len().max(1)) * self.max_points
    }

    /// The geometry (index into the model's collisions) of member `k`.
    pub fn geoms(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.pairs
            .iter()
            .map(|p| (self.members[p.a].geom, self.members[p.b].geom))
    }

    /// Appends the contact points of every pair to `out`, given every body's
    /// world pose.
    /// Bounding spheres of the moving members: (body, centre in the body
    /// frame, radius).
    pub fn member_spheres(&self) -> impl Iterator<Item = (usize, Vector3<f64>, f64)> + '_ {
        self.members.iter().filter(|m| m.body != 0).map(|m| {
            (
                m.body,
                m.placement.act_point(&m.shape.mid),
                m.shape.half.norm(),
            )
        })
    }

    /// Pairs whose two bodies are flagged in `asleep` (or static) keep what
    /// they held and are not queried.
    pub fn detect(&mut self, o_m_i: &[Se3<f64>], out: &mut Vec<ContactPoint>, asleep: &[bool]) {
        let margin = self.margin;
        for &k in &self.moving {
            let m = &self.members[k];
            let w = world(m, o_m_i);
            set_box(&mut self.sap, k, m, &w, margin);
            self.poses[k] = w;
        }
        self.overlapping.clear();
        self.sap.overlaps(&self.table, &mut self.overlapping);
        // the pairs not overlapping forget their points
        // (sorted: the same order every step, whatever the sweep's)
        self.overlapping.sort_unstable();
        // visited: the overlapping pairs and those that held anything
        self.visit.clear();
        let (mut i, mut j) = (0, 0);
        let (ov, live) = (&self.overlapping, &self.live);
        while i < ov.len() || j < live.len() {
            let x = ov.get(i).copied().unwrap_or(u32::MAX);
            let y = live.get(j).copied().unwrap_or(u32::MAX);
            self.visit.push(x.min(y));
            i += usize::from(x <= y);
            j += usize::from(y <= x);
        }
        self.live.clear();
        let mut next = 0;
        for vi in 0..self.visit.len() {
            let pi = self.visit[vi] as usize;
            let hit = next < self.overlapping.len() && self.overlapping[next] as usize == pi;
            if hit {
                next += 1;
            }
            let Some(pair) = self.pairs.get_mut(pi) else {
                continue;
            };
            if !hit || pair.dropped {
                pair.apart = None;
                if pair.keys[0] != NO_KEY || !pair.manifolds.is_empty() {
                    pair.keys.iter_mut().for_each(|k| *k = NO_KEY);
                    pair.manifolds.clear();
                }
                continue;
            }
            self.live.push(pi as u32);
            let still = |b: usize| b == 0 || asleep.get(b) == Some(&true);
            if still(self.members[pair.a].body) && still(self.members[pair.b].body) {
                continue;
            }
            let (ma, mb) = (&self.members[pair.a], &self.members[pair.b]);
            let (wa, wb) = (self.poses[pair.a], self.poses[pair.b]);
            self.queries += 1;
            self.raw.clear();
            // a hull on a box's face or a flat height field: the plane
            // contact where it is the exact one (`face`), else parry
            let plane = match pair.face {
                Some(hull_is_a) => {
                    self.stamp = self.stamp.wrapping_add(1).max(1);
                    face_points(
                        &ma.shape,
                        &mb.shape,
                        &wa,
                        &wb,
                        hull_is_a,
                        margin,
                        self.max_points,
                        &mut self.scratch,
                        &mut self.raw,
                        self.stamp,
                    )
                }
                None => false,
            };
            // two convex shapes apart along last step's axis by more than
            // the margin: no point, no parry query
            let convex = ma.shape.convex && mb.shape.convex;
            let apart = convex
                && (still_apart(pair.apart.as_ref(), ma, mb, &wa, &wb, margin) || {
                    let gap = apart_along(&pair.axis, ma, mb, &wa, &wb);
                    pair.apart = (gap > margin).then_some((gap, wa, wb));
                    gap > margin
                });
            if !plane && !apart {
                parry_points(
                    &ma.shape,
                    &mb.shape,
                    &wa,
                    &wb,
                    margin,
                    &mut pair.manifolds,
                    &mut pair.workspace,
                    &mut self.raw,
                );
                // parry's last direction (a's frame, from a toward b): its
                // separating axis when apart, else the contact normal
                pair.axis = match pair.manifolds.first() {
                    Some(m) if convex && pair.manifolds.len() == 1 => {
                        let n = from_pvec(m.local_n1);
                        let l = n.norm();
                        if l > 0.5 && l.is_finite() {
                            n / l
                        } else {
                            Vector3::zeros()
                        }
                    }
                    _ => Vector3::zeros(),
                };
            }
            let start = out.len();
            // the moving side first: a static a (an obstacle or a fixed
            // model's welded link) against a moving b swaps sides
            let swap = ma.body == 0;
            let (first, second) = if swap { (mb, ma) } else { (ma, mb) };
            let sign = if swap { -1.0 } else { 1.0 };
            reduce_pair(&self.raw, self.max_points, out, |r| ContactPoint {
                shape: pi,
                slot: 0,
                body: first.body,
                point: r.point,
                gap: r.gap,
                geom: first.geom,
                other: second.body,
                other_geom: second.geom,
                normal: r.normal * sign,
                friction: pair.friction,
                fresh: true,
                key: r.key,
            });
            assign_slots(pair, &mut out[start..]);
        }
    }

    /// Drops the self pairs that overlap by more than [`START_OVERLAP`] at the
    /// body poses `o_m_i` (scene.md rule 4), after restoring every pair dropped
    /// before; returns them, with their links, from `model`.
    pub fn drop_start_overlaps(&mut self, model: &Model, o_m_i: &[Se3<f64>]) -> Vec<DroppedPair> {
        let mut out = Vec::new();
        for pair in &mut self.pairs {
            pair.dropped = false;
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
                    pair.dropped = true;
                    pair.manifolds.clear();
                    pair.keys.iter_mut().for_each(|k| *k = NO_KEY);
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

    /// The first slot of pair contact.
    pub fn slot_offset(&self) -> usize {
        self.slot_offset
    }

    /// Whether a pair is dropped (rule 4), by its index ([`ContactPoint::shape`]).
    pub fn is_dropped(&self, pair: usize) -> bool {
        self.pairs.get(pair).is_some_and(|p| p.dropped)
    }
}

/// The gap of convex members `a` at `wa` and `b` at `wb` along the unit
/// axis `u` (a's frame, from a toward b; zero: not known, −∞): min over b
/// of u·x − max over a of u·x (two support points), a lower bound of their
/// distance when positive.
#[inline]
fn apart_along(u: &Vector3<f64>, a: &Member, b: &Member, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
    if u.x == 0.0 && u.y == 0.0 && u.z == 0.0 {
        return f64::NEG_INFINITY;
    }
    let (Some(sa), Some(sb)) = (
        a.shape.shape.as_support_map(),
        b.shape.shape.as_support_map(),
    ) else {
        return f64::NEG_INFINITY;
    };
    // b in a's frame: x = R p + t
    let a_m_b = wa.inverse().compose(wb);
    let top_a = u.dot(&from_pvec(sa.local_support_point(to_pvec(u))));
    let d = a_m_b.rot.transpose() * (-u);
    let low_b = u.dot(&a_m_b.act_point(&from_pvec(sb.local_support_point(to_pvec(&d)))));
    low_b - top_a
}

/// Whether two shapes separated by a plane with a gap g (> the margin) at
/// the world poses `then` are still more than `margin` apart at `wa`, `wb`
/// without a support query: no point of a shape moved farther than D =
/// |w·c − w₀·c| + ‖R − R₀‖_F |h| (c, h its box's centre and half extents in
/// its frame: every point lies within |h| of c), so across that plane the
/// shapes are still g − D_a − D_b apart (conservative advancement).
fn still_apart(
    then: Option<&(f64, Se3<f64>, Se3<f64>)>,
    a: &Member,
    b: &Member,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
) -> bool {
    let Some((gap, wa0, wb0)) = then else {
        return false;
    };
    let moved = |m: &Member, w0: &Se3<f64>, w: &Se3<f64>| {
        (w.act_point(&m.shape.mid) - w0.act_point(&m.shape.mid)).norm()
            + (w.rot - w0.rot).norm() * m.shape.half.norm()
    };
    gap - moved(a, wa0, wa) - moved(b, wb0, wb) > margin
}

/// Sets member `k`'s broad-phase box: its shape's box at the world pose `w`
/// boxed along the world axes (centre R·c + t, half extents |R|·h), grown by
/// `margin`.
#[inline]
fn set_box(sap: &mut SweepAndPrune, k: usize, m: &Member, w: &Se3<f64>, margin: f64) {
    let c = w.act_point(&m.shape.mid);
    let h = &m.shape.half;
    let r = &w.rot;
    let e =
        |i: usize| r[(i, 0)].abs() * h.x + r[(i, 1)].abs() * h.y + r[(i, 2)].abs() * h.z + margin;
    sap.set(k, [c.x, c.y, c.z], [e(0), e(1), e(2)]);
}

/// Puts each of a pair's points in a slot: the one that held the same
/// features last step (not fresh), else a free one (fresh).
fn assign_slots(pair: &mut Pair, pts: &mut [ContactPoint]) {
    let maxp = pair.keys.len();
    let mut taken = [false; 64];
    let mut placed = [false; 64];
    for (k, p) in pts.iter_mut().enumerate().take(64) {
        if let Some(s) = pair.keys.iter().position(|&key| key == p.key) {
            if !taken[s] {
                taken[s] = true;
                placed[k] = true;
                p.slot = pair.slot_base + s;
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
            p.slot = pair.slot_base + s;
            p.fresh = true;
        }
    }
    for (s, key) in pair.keys.iter_mut().enumerate() {
        *key = NO_KEY;
        if let Some(p) = pts.iter().find(|p| p.slot == pair.slot_base + s) {
            *key = p.key;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3, Unit};
    use parry3d_f64::shape::SharedShape;

    fn member(half: [f64; 3]) -> Member {
        let shape = SharedShape::cuboid(half[0], half[1], half[2]);
        Member {
            geom: 0,
            body: 1,
            placement: Se3::identity(),
            shape: PairShape::new(shape, Se3::identity(), true),
        }
    }

    fn distance(a: &Member, b: &Member, wa: &Se3<f64>, wb: &Se3<f64>) -> f64 {
        let pose = |w: &Se3<f64>| super::super::shapes::to_pose(w);
        parry3d_f64::query::distance(&pose(wa), &*a.shape.shape, &pose(wb), &*b.shape.shape)
            .unwrap()
            .distance
    }

    #[test]
    fn still_apart_is_never_wrong_and_not_vacuous() {
        // a long bar beside a cube, 3 cm apart along x: turning the bar about
        // its centre swings its end into the cube with no translation at all
        let (a, b) = (member([0.02, 0.1, 0.02]), member([0.02, 0.02, 0.02]));
        let margin = 0.005;
        let wa0 = Se3::identity();
        let wb0 = Se3::new(Matrix3::identity(), Vector3::new(0.07, 0.08, 0.0));
        let gap = apart_along(&Vector3::x(), &a, &b, &wa0, &wb0);
        assert!((gap - 0.03).abs() < 1e-12, "{gap}");
        let then = (gap, wa0, wb0);
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut kept, mut asked, mut touching) = (0, 0, 0);
        for k in 0..4000 {
            // turns up to 0.6 rad about axes near z, moves up to 2 cm
            let s = (k % 10) as f64 / 10.0;
            let mut turn = |w: &Se3<f64>, by: f64| {
                let axis = Unit::new_normalize(Vector3::new(0.2 * rnd(), 0.2 * rnd(), 1.0));
                let r = Rotation3::from_axis_angle(&axis, by * s * rnd()).into_inner();
                Se3::new(
                    r * w.rot,
                    w.trans + Vector3::new(rnd(), rnd(), rnd()) * 0.02 * s * s,
                )
            };
            let (wa, wb) = (turn(&wa0, 0.6), turn(&wb0, 0.1));
            let d = distance(&a, &b, &wa, &wb);
            touching += usize::from(d <= margin);
            if still_apart(Some(&then), &a, &b, &wa, &wb, margin) {
                kept += 1;
                assert!(d > margin, "move {k}: still apart, but {d} m apart");
            } else {
                asked += 1;
            }
        }
        assert!(
            kept > 500 && asked > 500 && touching > 100,
            "{kept} {asked} {touching}"
        );
    }
}
