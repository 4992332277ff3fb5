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

use super::broad::{PairMasks, PairTable, SweepAndPrune, LAZY_PAIR};
use super::filter::{is_self_pair, may_touch};
use super::narrow::prim::Round;
use super::shapes::{pair_shape, PairShape};
use super::travel::Travel;
use super::{ContactError, ContactParams, ContactPoint};
use crate::model::Model;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::query::{ContactManifold, ContactManifoldsWorkspace};
use std::path::PathBuf;

pub(crate) mod apart;
mod make;
mod members;
mod order;
mod start;
pub(crate) mod visit;
use apart::Apart;
pub(crate) use visit::{spin_until, Runner};

/// One shape of pair contact.
#[derive(Clone, Debug)]
pub struct Member {
    /// Index into the model's collisions.
    pub geom: usize,
    /// Its body.
    pub body: usize,
    /// `body_M_parry`.
    pub placement: Se3<f64>,
    /// The shape (parry's, and its sphere/capsule form).
    pub shape: PairShape,
}

/// The persistent state of one allowed pair, made when its boxes first
/// overlap (self pairs: at the start, for rule 4).
#[derive(Clone)]
struct Pair {
    /// Member indices (a < b; a moves, or both do).
    a: usize,
    b: usize,
    /// The first of its slots (global).
    slot_base: usize,
    manifolds: Vec<ContactManifold<(), ()>>,
    workspace: Option<ContactManifoldsWorkspace>,
    /// A self pair (rule 4 applies).
    self_pair: bool,
    /// A unit axis (a's frame, from a toward b) that separated the two
    /// shapes last time, or their contact normal (zero: none).
    axis: Vector3<f64>,
    /// The last time `axis` separated the shapes by more than the margin:
    /// the gap along it and both shapes' box centres and rotations then
    /// (see [`still_apart_at`]).
    apart: Option<Apart>,
    /// A hull and a box or height field (`Some(true)`: the hull is a): the
    /// face path ([`hull_on_face`]) is tried first.
    face: Option<bool>,
    friction: f64,
}

const NO_KEY: u64 = u64::MAX;

/// Raw points a query's scratch holds from the start (parry's manifolds of
/// one pair, the closed forms' two or three).
const RAW_ROOM: usize = 64;

/// Contact between pairs of shapes.
#[derive(Clone)]
pub struct PairContact {
    members: Vec<Member>,
    /// The pairs made so far (in the order they were made).
    pairs: Vec<Pair>,
    /// Each pair's place in the visiting order: (lower geometry index)·G +
    /// higher (G geometries), the order of the pairs of geometries i < j,
    /// whatever order the pairs were made in. Apart from the pairs (sorted
    /// by every step: a pair's whole state need not be loaded for that).
    ords: Vec<u64>,
    /// The features each pair's slots held last step (`NO_KEY`: free),
    /// `max_points` a pair (pair p's at `p·max_points`): apart from the
    /// pairs, in one array (no heap block of its own a pair).
    keys: Vec<u64>,
    /// Each pair dropped at the start (rule 4), apart from its state: the
    /// visit tests it before loading the pair.
    dropped: Vec<bool>,
    /// Pairs made since they were last put in visiting order ([`order`]).
    made_since_sort: usize,
    /// Pairs `0..ranked` are numbered in visiting order (their `ords`
    /// ascend); the pairs made since follow ([`order`]).
    ranked: usize,
    /// Scratch of [`Self::by_ord`]: the ranked pairs overlapping, a bit each,
    /// and the others as (ord, pair).
    seen: Vec<u64>,
    tail: Vec<(u64, u32)>,
    /// The pair of members i, j (`table.get(i, j)`: none allowed, allowed
    /// and not made yet, or its index).
    table: PairTable,
    /// Pairs the filter allows (made or not).
    allowed: usize,
    /// The friction of each member's geometry, and whether two members are
    /// of one model (a self pair), for the pairs made later.
    friction: Vec<f64>,
    model_of: Vec<Option<usize>>,
    /// Geometries in the model (the `ord` base).
    ngeoms: u64,
    sap: SweepAndPrune,
    /// Once every allowed pair is made and the shapes are fewer than
    /// [`STRIPS_FROM`] (one robot's self pairs), the broad phase by
    /// [`PairMasks`] (the same pairs as the sweep's, and in visiting order:
    /// no sort).
    listed: Option<PairMasks>,
    /// The overlapping pairs of this detection as (ord, pair).
    overlapping: Vec<(u64, u32)>,
    /// Scratch: the broad phase's pair indices.
    sap_ids: Vec<u32>,
    /// Member pairs allowed and overlapping whose pair is not made yet.
    fresh: Vec<(u32, u32)>,
    /// The pairs holding anything after the last detection (points, manifolds,
    /// a separating axis), by `ord`: with the overlapping ones, the only pairs
    /// a detection visits (never all pairs: their count is the square of the scene's).
    live: Vec<(u64, u32)>,
    /// The pairs a detection visits (overlapping ∪ live), by `ord`.
    visit: Vec<(u64, u32)>,
    /// Each member's world pose (parry's frame) at the last detection.
    poses: Vec<Se3<f64>>,
    /// Each member's box centre (world) at the last detection, and the
    /// radius of a sphere about it that holds the box (|half extents|).
    centres: Vec<Vector3<f64>>,
    radii: Vec<f64>,
    /// Each member's placement is the identity ([`world_at`]).
    at_body: Vec<bool>,
    /// A sphere or capsule member placed at the last detection (its closed
    /// form's input, once a member, not once a pair).
    rounds: Vec<Option<Round>>,
    /// Each visited pair's boxes overlap (with `visit`).
    hits: Vec<bool>,
    /// Each thread's query scratch (the calling thread's first).
    queries_scratch: Vec<visit::Query>,
    /// Each chunk's output of a visit on several threads ([`visit`]).
    chunks: Vec<visit::ChunkOut>,
    /// Members that move (their boxes are refreshed each step).
    moving: Vec<usize>,
    /// Slots in all.
    pub nslots: usize,
    /// Narrow-phase queries performed so far (one a pair whose boxes overlap).
    pub queries: u64,
    /// Each member's travel in the last step: the speculative margin.
    travel: Travel,
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

/// [`world`] of a member whose placement is the identity when `at_body`
/// (`PairContact::at_body`): its body's pose itself where every entry of it
/// is finite and nonzero (`o · I` is then `o` bit for bit,
/// [`crate::dynamics::plain_pose`]).
#[inline(always)]
fn world_at(m: &Member, o_m_i: &[Se3<f64>], at_body: bool) -> Se3<f64> {
    match o_m_i.get(m.body) {
        Some(o) if at_body && crate::dynamics::plain_pose(o) => *o,
        Some(o) => o.compose(&m.placement),
        None => m.placement,
    }
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
        let mut table = PairTable::new(n);
        let mut allowed = 0;
        let friction: Vec<f64> = members.iter().map(|m| g[m.geom].friction).collect();
        let model_of: Vec<Option<usize>> = members
            .iter()
            .map(|m| {
                let x = &g[m.geom];
                is_self_pair(x, x).then_some(x.model)
            })
            .collect();
        for i in 0..g.len() {
            for j in i + 1..g.len() {
                let (a, b) = (member_of[i], member_of[j]);
                if a == usize::MAX || b == usize::MAX || !may_touch(model, &g[i], &g[j]) {
                    continue;
                }
                if !members[a].shape.convex && !members[b].shape.convex {
                    continue; // two non-convex shapes (both static): never
                }
                allowed += 1;
                table.allow(a, b);
            }
        }
        let mut made = Self {
            nslots: allowed * maxp,
            members,
            table,
            allowed,
            friction,
            model_of,
            ngeoms: g.len() as u64,
            sap: SweepAndPrune::new(n),
            listed: None,
            overlapping: Vec::new(),
            sap_ids: Vec::new(),
            fresh: Vec::new(),
            live: Vec::new(),
            visit: Vec::new(),
            poses: Vec::with_capacity(n),
            centres: Vec::with_capacity(n),
            radii: Vec::with_capacity(n),
            at_body: Vec::with_capacity(n),
            rounds: Vec::with_capacity(n),
            hits: Vec::new(),
            queries_scratch: Vec::new(),
            chunks: Vec::new(),
            moving: Vec::new(),
            queries: 0,
            travel: Travel::new(params, Vec::new()),
            max_points: maxp,
            slot_offset,
            pairs: Vec::new(),
            ords: Vec::new(),
            keys: Vec::new(),
            dropped: Vec::new(),
            made_since_sort: 0,
            ranked: 0,
            seen: Vec::new(),
            tail: Vec::new(),
        };
        // self pairs now (rule 4 looks at them before the first step)
        for a in 0..n {
            for b in a + 1..n {
                let self_pair = made.model_of[a].is_some() && made.model_of[a] == made.model_of[b];
                if self_pair && made.table.get(a, b) == LAZY_PAIR {
                    made.make_pair(a, b);
                }
            }
        }
        if allowed == 0 {
            return Ok(None);
        }
        // a detection's lists sized here, not grown in a step: every allowed
        // pair (a model's own pairs, all made above), at most 8 a member for
        // a scene's (a pile's count is the square of its bodies'), and a
        // query's raw points
        let room = allowed.min(8 * n);
        made.overlapping.reserve(room);
        made.live.reserve(room);
        made.visit.reserve(2 * room);
        made.hits.reserve(2 * room);
        made.queries_scratch.push(visit::Query::with_room(RAW_ROOM));
        let fixed = made.members.iter().map(|m| m.body == 0).collect();
        made.travel = Travel::new(params, fixed);
        for (k, m) in made.members.iter().enumerate() {
            made.poses.push(m.placement);
            let c = m.placement.act_point(&m.shape.mid);
            made.centres.push(c);
            made.radii.push(m.shape.half.norm());
            let p = &m.placement;
            made.at_body
                .push(p.rot == nalgebra::Matrix3::identity() && p.trans == Vector3::zeros());
            made.rounds.push(Round::of(&m.shape, &m.placement));
            if m.body == 0 {
                set_box(&mut made.sap, k, m, &m.placement, &c, params.margin);
            } else {
                made.moving.push(k);
            }
        }
        Ok(Some(made))
    }

    /// Forgets every pair's manifolds and the features its slots held: the
    /// next detection finds what a newly built one would.
    pub fn forget_history(&mut self) {
        self.keys.fill(NO_KEY);
        for pair in self.pairs.iter_mut() {
            pair.manifolds.clear();
            pair.workspace = None;
            pair.apart = None;
        }
        self.travel.forget();
    }

    /// The next detection follows a step ([`super::Collision::stepped`]).
    pub fn stepped(&mut self, scale: f64) {
        self.travel.stepped(scale);
    }

    /// The most points a step can report: each pair's limit, for at most 8
    /// pairs touching a moving shape at once (more are found, and cost an
    /// allocation, in crowded scenes).
    pub fn max_points(&self) -> usize {
        self.allowed.min(8 * self.moving.len().max(1)) * self.max_points
    }

    /// The geometry (index into the model's collisions) of member `k`.
    pub fn geoms(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.members.len();
        (0..n * n)
            .filter(move |&k| k / n < k % n && self.table.allowed(k / n, k % n))
            .map(move |k| (self.members[k / n].geom, self.members[k % n].geom))
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
        self.detect_on(o_m_i, out, asleep, None);
    }

    /// [`Self::detect`], its narrow phase on `run`'s threads when there are
    /// enough pairs (the same points, bit for bit: [`visit`]).
    pub(crate) fn detect_on(
        &mut self,
        o_m_i: &[Se3<f64>],
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        run: Option<&dyn Runner>,
    ) {
        self.broad(o_m_i);
        self.visit_pairs(out, asleep, run);
    }

    /// The broad phase of [`Self::detect_on`] at the body poses `o_m_i`: the
    /// members' boxes, the overlapping pairs and the pairs to visit
    /// (`visit_pairs`, the narrow phase, follows).
    pub(crate) fn broad(&mut self, o_m_i: &[Se3<f64>]) {
        let step = self.broad_begin();
        self.broad_members(o_m_i, step);
        self.broad_rest();
    }

    /// What precedes the broad phase's member loop: the travel's scale (0:
    /// none) and whether it is measured.
    pub(crate) fn broad_begin(&mut self) -> (f64, bool) {
        let stepped = self.travel.begin();
        // (c = 0: every margin is δ, the members' travel is not measured)
        let measure = self.travel.measures();
        self.keep_in_order();
        (stepped, measure)
    }

    /// The broad phase's member loop on this thread ([`members::place`]).
    pub(crate) fn broad_members(&mut self, o_m_i: &[Se3<f64>], step: (f64, bool)) {
        let (ts, delta, factor) = self.travel.split();
        for &k in &self.moving {
            let (Some(m), Some(&radius), Some(&at_body)) =
                (self.members.get(k), self.radii.get(k), self.at_body.get(k))
            else {
                continue;
            };
            let (Some(travel), Some(lo), Some(hi), Some(round), Some(pose), Some(centre)) = (
                ts.get_mut(k),
                self.sap.lo.get_mut(k),
                self.sap.hi.get_mut(k),
                self.rounds.get_mut(k),
                self.poses.get_mut(k),
                self.centres.get_mut(k),
            ) else {
                continue;
            };
            let out = members::Placed {
                travel,
                lo,
                hi,
                round,
                pose,
                centre,
            };
            members::place(m, o_m_i, step, (delta, factor), (radius, at_body), out);
        }
    }

    /// The broad phase after the member loop: the overlapping pairs and
    /// the pairs to visit.
    pub(crate) fn broad_rest(&mut self) {
        self.overlapping.clear();
        self.list_pairs();
        if let Some(masks) = self.listed.as_mut() {
            // every pair made: by l, then h, i.e. by `ord` (members are in
            // geometry order)
            let (table, ords, ov) = (&self.table, &self.ords, &mut self.overlapping);
            masks.overlaps(&self.sap, |l, h| {
                let p = table.get(l, h);
                if let Some(&ord) = ords.get(p as usize) {
                    ov.push((ord, p));
                }
            });
        } else {
            self.fresh.clear();
            let mut ids = std::mem::take(&mut self.sap_ids);
            ids.clear();
            self.sap
                .overlaps(&mut self.table, &mut ids, &mut self.fresh);
            for f in 0..self.fresh.len() {
                let (i, j) = self.fresh[f];
                ids.push(self.make_pair(i as usize, j as usize));
            }
            // the pairs not overlapping forget their points
            // (by ord: the same order every step, whatever the sweep's or the
            // order the pairs were made in)
            self.by_ord(&ids);
            self.sap_ids = ids;
        }
        // visited: the overlapping pairs and those that held anything
        self.visit.clear();
        self.hits.clear();
        let (mut i, mut j) = (0, 0);
        let (ov, live) = (&self.overlapping, &self.live);
        while i < ov.len() || j < live.len() {
            let x = ov.get(i).copied().unwrap_or((u64::MAX, u32::MAX));
            let y = live.get(j).copied().unwrap_or((u64::MAX, u32::MAX));
            self.visit.push(x.min(y));
            self.hits.push(x <= y);
            i += usize::from(x <= y);
            j += usize::from(y <= x);
        }
    }

    /// The first slot of pair contact.
    pub fn slot_offset(&self) -> usize {
        self.slot_offset
    }

    /// Whether a pair is dropped (rule 4), by its index ([`ContactPoint::shape`]).
    pub fn is_dropped(&self, pair: usize) -> bool {
        self.dropped.get(pair).copied().unwrap_or(false)
    }
}

/// Sets member `k`'s broad-phase box: its shape's box at the world pose `w`
/// boxed along the world axes (centre `c` = R·c₀ + t, half extents |R|·h),
/// grown by `margin`.
#[inline]
fn set_box(
    sap: &mut SweepAndPrune,
    k: usize,
    m: &Member,
    w: &Se3<f64>,
    c: &Vector3<f64>,
    margin: f64,
) {
    let (lo, hi) = box_of(m, w, c, margin);
    sap.lo[k] = lo;
    sap.hi[k] = hi;
}

/// [`set_box`]'s box: its lower and upper corners.
#[inline(always)]
fn box_of(m: &Member, w: &Se3<f64>, c: &Vector3<f64>, margin: f64) -> ([f64; 3], [f64; 3]) {
    let h = &m.shape.half;
    let r = &w.rot;
    let e =
        |i: usize| r[(i, 0)].abs() * h.x + r[(i, 1)].abs() * h.y + r[(i, 2)].abs() * h.z + margin;
    let (c, h) = ([c.x, c.y, c.z], [e(0), e(1), e(2)]);
    (
        [c[0] - h[0], c[1] - h[1], c[2] - h[2]],
        [c[0] + h[0], c[1] + h[1], c[2] + h[2]],
    )
}
