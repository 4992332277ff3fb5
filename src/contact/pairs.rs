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
use super::shapes::{from_pvec, pair_shape, to_pose, PairShape};
use super::{ContactError, ContactParams, ContactPoint};
use crate::model::Model;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
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
    friction: f64,
}

const NO_KEY: u64 = u64::MAX;

/// A raw point of a manifold before the reduction.
#[derive(Clone, Copy, Debug)]
struct Raw {
    point: Vector3<f64>,
    normal: Vector3<f64>,
    gap: f64,
    key: u64,
}

/// Contact between pairs of shapes.
#[derive(Clone)]
pub struct PairContact {
    members: Vec<Member>,
    pairs: Vec<Pair>,
    /// `table[i·n + j]`: the pair of members i, j ([`NO_PAIR`]: none).
    table: Vec<u32>,
    sap: SweepAndPrune,
    overlapping: Vec<u32>,
    /// Each member's world pose (parry's frame) at the last detection.
    poses: Vec<Se3<f64>>,
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

/// Two unit tangents completing the unit normal n to a right-handed frame
/// (t₁, t₂, n); x and y for n = +z.
#[inline]
pub fn tangents(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    if n.x == 0.0 && n.y == 0.0 && n.z > 0.0 {
        return (Vector3::x(), Vector3::y());
    }
    // the axis least aligned with n
    let e = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vector3::x()
    } else if n.y.abs() <= n.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let t1 = n.cross(&e).normalize();
    (t1, n.cross(&t1))
}

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
            overlapping: Vec::with_capacity(pairs.len()),
            poses,
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
    pub fn detect(&mut self, o_m_i: &[Se3<f64>], out: &mut Vec<ContactPoint>) {
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
        let dispatcher = DefaultQueryDispatcher;
        // (sorted: the same order every step, whatever the sweep's)
        self.overlapping.sort_unstable();
        let mut next = 0;
        for pi in 0..self.pairs.len() {
            let hit = next < self.overlapping.len() && self.overlapping[next] as usize == pi;
            if hit {
                next += 1;
            }
            let pair = &mut self.pairs[pi];
            if !hit || pair.dropped {
                if pair.keys[0] != NO_KEY || !pair.manifolds.is_empty() {
                    pair.keys.iter_mut().for_each(|k| *k = NO_KEY);
                    pair.manifolds.clear();
                }
                continue;
            }
            let (ma, mb) = (&self.members[pair.a], &self.members[pair.b]);
            let (wa, wb) = (self.poses[pair.a], self.poses[pair.b]);
            let pos12 = to_pose(&wa.inverse().compose(&wb));
            self.queries += 1;
            // the points are found anew (a generator that finds the shapes
            // apart returns without touching them; the slots, not parry's
            // contact data, carry the warm starts)
            for man in pair.manifolds.iter_mut() {
                man.points.clear();
            }
            let ok = dispatcher.contact_manifolds(
                &pos12,
                &*ma.shape.shape,
                &*mb.shape.shape,
                margin,
                &mut pair.manifolds,
                &mut pair.workspace,
            );
            self.raw.clear();
            if ok.is_ok() {
                for man in &pair.manifolds {
                    // parry's normal leaves shape a toward b: ours points from
                    // b toward a (the direction a's impulse pushes it)
                    let sub1 = man.subshape_pos1().copied();
                    let ln = match sub1 {
                        Some(s) => s.rotation * man.local_n1,
                        None => man.local_n1,
                    };
                    let n = -(wa.rot * from_pvec(ln));
                    let nn = n.norm();
                    if !(nn > 0.5) {
                        continue;
                    }
                    let n = n / nn;
                    for c in &man.points {
                        if c.dist > margin {
                            continue;
                        }
                        let p1 = match sub1 {
                            Some(s) => s * c.local_p1,
                            None => c.local_p1,
                        };
                        let p2 = match man.subshape_pos2() {
                            Some(s) => s * c.local_p2,
                            None => c.local_p2,
                        };
                        let (p1, p2) = (wa.act_point(&from_pvec(p1)), wb.act_point(&from_pvec(p2)));
                        let key = ((man.subshape2 as u64) << 40)
                            ^ ((c.fid1.0 as u64) << 20)
                            ^ (c.fid2.0 as u64)
                            ^ ((man.subshape1 as u64) << 52);
                        let point = (p1 + p2) * 0.5;
                        // parry may give one point twice (a cylinder cap's square
                        // vertex, clipped): one row a point
                        if self
                            .raw
                            .iter()
                            .any(|r| (r.point - point).norm_squared() < 1e-18)
                        {
                            continue;
                        }
                        self.raw.push(Raw {
                            point,
                            normal: n,
                            gap: c.dist,
                            key,
                        });
                    }
                }
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

/// Appends at most `maxp` of `raw` to `out` as `make` makes them: all when
/// they fit, else the deepest, then the extremes along `maxp − 1` tangent
/// directions of the deepest point's normal.
fn reduce_pair(
    raw: &[Raw],
    maxp: usize,
    out: &mut Vec<ContactPoint>,
    make: impl Fn(&Raw) -> ContactPoint,
) {
    if raw.len() <= maxp {
        out.extend(raw.iter().map(&make));
        return;
    }
    let deepest = (0..raw.len())
        .min_by(|&i, &j| {
            raw[i]
                .gap
                .total_cmp(&raw[j].gap)
                .then(raw[i].key.cmp(&raw[j].key))
        })
        .unwrap_or(0);
    let start = out.len();
    out.push(make(&raw[deepest]));
    let (t1, t2) = tangents(&raw[deepest].normal);
    let dirs = maxp - 1;
    for d in 0..dirs {
        let (s, c) = (std::f64::consts::TAU * d as f64 / dirs as f64).sin_cos();
        let dir = t1 * c + t2 * s;
        let best = (0..raw.len())
            .max_by(|&i, &j| {
                dir.dot(&raw[i].point)
                    .total_cmp(&dir.dot(&raw[j].point))
                    .then(raw[j].key.cmp(&raw[i].key))
            })
            .unwrap_or(0);
        if !out[start..].iter().any(|p| p.key == raw[best].key) {
            out.push(make(&raw[best]));
        }
    }
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
