//! The fast path of contact with the ground plane z = `ground`: each moving
//! shape's points within the margin found from its vertices' heights (a
//! plane's cheap special cases, as MuJoCo's colliders), reduced to a persistent
//! patch (see the module doc of [`super`]).

mod build;
mod patch;
mod reduce;
mod serial;
mod team;
pub(crate) use team::Side;

use super::pairs::Runner;
use super::shapes::to_pose;
use super::travel::{self, Travel};
use super::{ContactParams, ContactPoint};
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SupportMap};
use reduce::{reduce, MAX_DIRS};

#[derive(Clone, Debug)]
pub(super) enum ParryShape {
    Ball(Ball),
    Capsule(Capsule),
    Cuboid(Cuboid),
    Cylinder(Cylinder),
    Hull(ConvexPolyhedron),
    /// A degenerate (flat) mesh: its vertices only.
    Points,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Manifold {
    /// Fixed vertices in the geometry frame.
    Vertices,
    /// A sphere of this radius at the geometry origin.
    Sphere(f64),
    /// A capsule: end-sphere centres at ±half along z, radius.
    Capsule { half: f64, radius: f64 },
    /// A cylinder along z: exact lowest rim points then the sampled vertices.
    Cylinder { half: f64, radius: f64 },
}

/// One collision shape that takes part in ground contact.
#[derive(Clone, Debug)]
pub struct GroundShape {
    /// The body it moves with.
    pub body: usize,
    /// Index of its geometry in the model's collisions.
    pub geom: usize,
    /// The fields its contact points share (body, geometry, the ground's
    /// normal +z and the pair's friction, the larger of the geometry's and
    /// the ground's).
    template: ContactPoint,
    /// The URDF link it belongs to.
    pub link: String,
    /// `body_M_geom` (URDF geometry frame).
    pub placement: Se3<f64>,
    /// `placement` is exactly the identity: the geometry's pose is its
    /// body's (no compose in the detection; see [`GroundShape::pose`]).
    at_body: bool,
    /// `geom_M_parry` (parry's own shape frame).
    parry_offset: Se3<f64>,
    shape: ParryShape,
    manifold: Manifold,
    /// Manifold vertices in the geometry frame.
    verts: Vec<Vector3<f64>>,
    /// Number of slots (stable point identities) of this shape.
    pub nslots: usize,
    /// A hull's vertex graph (compressed rows: the neighbours of vertex k are
    /// `adj[adj_start[k]..adj_start[k + 1]]`), empty for small vertex sets,
    /// which are scanned whole.
    adj_start: Vec<u32>,
    adj: Vec<u32>,
    /// Radius of a sphere about the geometry origin that holds the shape: a
    /// shape whose origin is higher than this above the ground (plus the margin)
    /// cannot touch it, and is skipped without a narrow-phase query.
    pub bound: f64,
    /// A vertex shape's box in the body frame (centre, half extents): its
    /// lowest point is no lower than the box's lowest corner, a tighter test
    /// than `bound` for a long link (solo12's base and shanks stand within
    /// their spheres' reach of the ground without their boxes' reaching it).
    low_box: Option<([f64; 3], [f64; 3])>,
}

/// What the detection's first tests read of a shape (its body, geometry
/// origin, bounding sphere and box), apart from the shape: a few cache
/// lines for all of a model's shapes, where each [`GroundShape`] fills a
/// dozen (humanoid_CMU's 47 shapes did not fit the L1 cache, and most are
/// culled from these alone).
#[derive(Clone, Copy, Debug)]
pub(super) struct Cull {
    body: usize,
    /// `placement.trans`.
    origin: [f64; 3],
    bound: f64,
    /// `low_box`, when there is one.
    low_box: Option<([f64; 3], [f64; 3])>,
}

impl GroundShape {
    /// The geometry's world pose `o_m_b · placement`, its body's pose itself
    /// when the placement is the identity (the compose skipped: R·I and
    /// R·0 + t give back R and t but for the sign of a zero sum, which no
    /// point's sum of nonzero terms keeps).
    #[inline(always)]
    pub(super) fn pose(&self, o_m_b: &Se3<f64>) -> Se3<f64> {
        if self.at_body {
            *o_m_b
        } else {
            o_m_b.compose(&self.placement)
        }
    }
}

impl Cull {
    pub(super) fn of(s: &GroundShape) -> Self {
        let t = &s.placement.trans;
        Self {
            body: s.body,
            origin: [t.x, t.y, t.z],
            bound: s.bound,
            low_box: s.low_box,
        }
    }
}

/// The ground plane and every shape that can touch it.
#[derive(Clone, Debug)]
pub struct GroundContact {
    /// Every collision shape of a moving link; [`ContactPoint::shape`] indexes it.
    /// Shared, not copied, by a clone (they never change after the build: a
    /// batch of simulations cloned from one holds its hulls once).
    pub shapes: std::sync::Arc<[GroundShape]>,
    /// Each shape's [`Cull`] data, in the same order.
    cull: std::sync::Arc<[Cull]>,
    /// Ground height (the plane z = ground, normal +z).
    pub ground: f64,
    /// The contact parameters it was built with.
    pub params: ContactParams,
    /// Narrow-phase queries performed so far (one per shape per detection).
    pub queries: u64,
    slot_offset: Vec<usize>,
    /// Total number of slots.
    pub nslots: usize,
    scratch: Vec<ContactPoint>,
    /// Slots the last detection kept, as flags and as a list: a reduced
    /// manifold keeps them while they stay within the margin.
    prev_flag: Vec<bool>,
    prev_list: Vec<usize>,
    /// Per shape, its slots in `prev_list` (a range).
    prev_range: Vec<(usize, usize, usize)>,
    /// Per shape, how many of this detection's points are picks (the rest,
    /// after them: points kept from last step still in the ground); `usize::MAX`:
    /// all. Last step's picks are `prev_list[a..b]`, its extras `[b..c]` for
    /// `prev_range` (a, b, c): only picks are preferred by the picks.
    picks: Vec<usize>,
    /// The horizontal directions a reduced manifold's extremes are taken along
    /// (cos, sin), computed once ([`reduce_directions`]).
    reduce_dirs: [(f64, f64); MAX_DIRS],
    /// Per shape, the vertex where the last lowest-vertex search ended (the
    /// next one starts there); per slot, the search generation that visited it.
    last_low: Vec<usize>,
    visited: Vec<u32>,
    generation: u32,
    /// A hull searched on its graph, from its last band search: per slot, the
    /// generation of the search that found it in the band (`in_band`); in the
    /// shape's slot range, the band's vertices in search order (`band_order`,
    /// `band_len[shape]` of them) and its rim, the vertices next to the band
    /// outside it (`rim_xyz`, `rim_len[shape]`); per shape, the generation
    /// of its band (`band_gen`).
    in_band: Vec<u32>,
    /// Per slot, its place in its shape's band search order (valid where
    /// `in_band` holds the shape's `band_gen`).
    band_place: Vec<u32>,
    /// The current band's world points, in its search order ([`patch`]).
    band_pts: patch::Soa,
    /// In each shape's slot range, its band's and rim's vertices (geometry
    /// frame) in search order ([`patch`]).
    band_xyz: patch::Soa,
    rim_xyz: patch::Soa,
    band_order: Vec<u32>,
    band_len: Vec<usize>,
    rim_len: Vec<usize>,
    band_gen: Vec<u32>,
    stack: Vec<u32>,
    /// The speculative margin ([`travel`]): per shape, the height of its
    /// geometry origin and the third row of its body's rotation at the last
    /// detection, and how far down it moved in the last step.
    anchor: Vec<[f64; 4]>,
    travel: Travel,
    /// Some shape is a hull searched on its vertex graph (its search's
    /// scratch is one for all shapes: such a detection stays on one thread).
    hulls: bool,
    /// The chunks of shapes of a detection on a team ([`team`]).
    parts: Vec<team::Part>,
    /// Scratch of a detection on one thread ([`serial`]): the shapes within
    /// reach and their margins.
    reached: Vec<(usize, f64)>,
}

impl GroundShape {
    /// The radius of a shape whose ground contact point lies that far below a
    /// centre moving with the link (a sphere, a capsule's end sphere); 0 for
    /// vertex contacts (hulls, boxes, point sets) and cylinders.
    pub fn rolling_radius(&self) -> f64 {
        match self.manifold {
            Manifold::Sphere(r) => r,
            Manifold::Capsule { radius, .. } => radius,
            _ => 0.0,
        }
    }

    /// Shape `si`'s contact point at slot `slot` (in the detection's slot
    /// numbering), world point `p`, its gap above the ground at `ground`.
    #[inline]
    fn contact_at(&self, si: usize, slot: usize, p: Vector3<f64>, ground: f64) -> ContactPoint {
        ContactPoint {
            shape: si,
            slot,
            body: self.body,
            point: p,
            gap: p.z - ground,
            ..self.template
        }
    }
}

/// A large hull's patch is chosen among its vertices at most this far (m)
/// above its lowest one (and within the margin).
const BAND: f64 = 2e-3;

impl GroundContact {
    /// The lowest z of any shape (its support point toward −z), given every
    /// body's world pose; +∞ without shapes. Not counted as a query.
    pub fn lowest_point(&self, o_m_i: &[Se3<f64>]) -> f64 {
        let mut low = f64::INFINITY;
        for s in self.shapes.iter() {
            let Some(o_m_b) = o_m_i.get(s.body) else {
                continue;
            };
            let pose = to_pose(&o_m_b.compose(&s.placement).compose(&s.parry_offset));
            let dir = PVec::new(0.0, 0.0, -1.0);
            let z = match &s.shape {
                ParryShape::Ball(b) => b.support_point(&pose, dir).z,
                ParryShape::Capsule(b) => b.support_point(&pose, dir).z,
                ParryShape::Cuboid(b) => b.support_point(&pose, dir).z,
                ParryShape::Cylinder(b) => b.support_point(&pose, dir).z,
                ParryShape::Hull(b) => b.support_point(&pose, dir).z,
                ParryShape::Points => {
                    let o_m_g = o_m_b.compose(&s.placement);
                    s.verts
                        .iter()
                        .map(|v| o_m_g.act_point(v).z)
                        .fold(f64::INFINITY, f64::min)
                }
            };
            low = low.min(z);
        }
        low
    }

    /// Forgets what earlier detections left (the points kept from the last
    /// one, where each hull's search starts, its band cache): the next
    /// detection finds what a newly built one would.
    pub fn forget_history(&mut self) {
        self.prev_flag.fill(false);
        self.prev_list.clear();
        self.prev_range.fill((0, 0, 0));
        self.picks.fill(usize::MAX);
        self.last_low.fill(0);
        self.visited.fill(0);
        self.generation = 0;
        self.in_band.fill(0);
        self.band_len.fill(0);
        self.rim_len.fill(0);
        self.band_gen.fill(0);
        self.travel.forget();
    }

    /// The next detection follows a step ([`super::Collision::stepped`]).
    pub fn stepped(&mut self, scale: f64) {
        self.travel.stepped(scale);
    }

    /// The largest number of points [`detect`](Self::detect) can return.
    pub fn max_points(&self) -> usize {
        self.shapes
            .iter()
            .map(|s| {
                // a hull's patch: its picks and at most as many points kept
                // from last step that are still in the ground (`detect`)
                let maxp = self.params.max_points_per_shape.max(1);
                let hull = s.manifold == Manifold::Vertices && !s.adj.is_empty();
                s.nslots.min(if hull { 2 * maxp } else { maxp })
            })
            .sum()
    }

    /// Finds the contact points given every body's world pose `o_m_i`, appending
    /// them to `out` (cleared first). No allocation once `out` has
    /// [`max_points`](Self::max_points) capacity.
    /// Shapes of bodies flagged in `asleep` are skipped.
    pub fn detect(&mut self, o_m_i: &[Se3<f64>], out: &mut Vec<ContactPoint>, asleep: &[bool]) {
        self.detect_on(o_m_i, out, asleep, None, None);
    }

    /// [`Self::detect`], the shapes searched on `run`'s threads when there
    /// are enough of them and no hull among them (the same points in the
    /// same order, bit for bit: [`team`]); `side`, work of the caller's that
    /// touches nothing of this detection (the pairs' broad phase), run once
    /// (on a team by the calling thread, first, else after the shapes).
    pub(crate) fn detect_on(
        &mut self,
        o_m_i: &[Se3<f64>],
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        run: Option<&dyn Runner>,
        side: Option<&dyn Side>,
    ) {
        out.clear();
        let stepped = self.travel.begin();
        // (c = 0: every margin is δ, the shapes' travel is not measured)
        let measure = self.travel.measures();
        match run.filter(|r| self.team_worth(r.threads())) {
            Some(r) => self.detect_team(o_m_i, out, asleep, r, (stepped, measure), side),
            None => {
                self.detect_serial(o_m_i, out, asleep, (stepped, measure));
                if let Some(f) = side {
                    team::side_alone(f);
                }
            }
        }
        self.keep_picks(out);
    }

    /// The slots of this detection's points `out` kept for the next one
    /// (`prev_flag`, `prev_list`, `prev_range`), the picks forgotten.
    fn keep_picks(&mut self, out: &[ContactPoint]) {
        for &k in &self.prev_list {
            self.prev_flag[k] = false;
        }
        self.prev_list.clear();
        self.prev_range.fill((0, 0, 0));
        for p in out {
            if let Some(f) = self.prev_flag.get_mut(p.slot) {
                *f = true;
                // a shape's points are contiguous in `out`, its picks first
                let r = &mut self.prev_range[p.shape];
                if r.2 == 0 {
                    r.0 = self.prev_list.len();
                    r.1 = r.0;
                }
                let pick = self.prev_list.len() - r.0 < self.picks[p.shape];
                self.prev_list.push(p.slot);
                r.2 = self.prev_list.len();
                if pick {
                    r.1 = r.2;
                }
            }
        }
        self.picks.fill(usize::MAX);
    }
}

/// Shape `cu`'s test against the ground, its body at `o_m_b`: its travel
/// since the last detection measured (`step`: the travel's scale and whether
/// it is measured; `anchor`, `travel`: the shape's entries, δ and c) and
/// its margin, `None` when its bounding sphere or box is clear of the
/// ground by more than the margin.
#[inline(always)]
fn reach(
    cu: &Cull,
    o_m_b: &Se3<f64>,
    ground: f64,
    (stepped, measure): (f64, bool),
    anchor: &mut [f64; 4],
    mut travel: Option<&mut f64>,
    (delta, c): (f64, f64),
) -> Option<f64> {
    // broad phase: the bounding sphere clear of the plane (the height of
    // the geometry origin alone, before the whole pose is composed)
    let r = &o_m_b.rot;
    let pt = &cu.origin;
    let z = r[(2, 0)] * pt[0] + r[(2, 1)] * pt[1] + r[(2, 2)] * pt[2] + o_m_b.trans.z;
    // the speculative margin: max(δ, c·s), s how far down the shape
    // moved in the last step (docs/theory.md §"Speculative margin")
    let row = [r[(2, 0)], r[(2, 1)], r[(2, 2)]];
    if measure {
        if stepped > 0.0 {
            let down = travel::dropped(anchor, z, row, cu.bound);
            if let Some(x) = travel.as_deref_mut() {
                *x = down * stepped;
            }
        }
        *anchor = [z, row[0], row[1], row[2]];
    }
    let margin = travel::margin(delta, c, travel.map_or(0.0, |x| *x));
    if z - ground - cu.bound > margin {
        return None;
    }
    if let Some((c, e)) = &cu.low_box {
        let zc = row[0] * c[0] + row[1] * c[1] + row[2] * c[2] + o_m_b.trans.z;
        let reach = row[0].abs() * e[0] + row[1].abs() * e[1] + row[2].abs() * e[2];
        // (a nanometre of slack for the rounding of the two ways)
        if zc - reach - ground > margin + 1e-9 {
            return None;
        }
    }
    Some(margin)
}

/// What a shape's points read of the detection, apart from the shape.
pub(super) struct Plain<'a> {
    ground: f64,
    maxp: usize,
    slot_offset: &'a [usize],
    /// The slots the last detection kept (read only during a detection).
    prev_flag: &'a [bool],
    reduce_dirs: &'a [(f64, f64); MAX_DIRS],
}

/// A vertex set this small keeps its heights on the stack ([`plain_points`]).
const SMALL_SET: usize = 8;

/// Shape `si` (`s`, not a hull searched on its graph) at the geometry
/// pose `o_m_g`: its points within `margin` reduced into `out` (`scratch`:
/// its candidates).
#[inline(always)]
fn plain_points(
    s: &GroundShape,
    si: usize,
    o_m_g: &Se3<f64>,
    margin: f64,
    cx: &Plain<'_>,
    scratch: &mut Vec<ContactPoint>,
    out: &mut Vec<ContactPoint>,
) {
    let ground = cx.ground;
    let base = cx.slot_offset[si];
    scratch.clear();
    if s.manifold == Manifold::Vertices {
        let r = &o_m_g.rot;
        let (rx, ry, rz) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
        let tz = o_m_g.trans.z - ground;
        let height = |v: &Vector3<f64>| rx * v.x + ry * v.y + rz * v.z + tz;
        let point = |k: usize| s.contact_at(si, base + k, o_m_g.act_point(&s.verts[k]), ground);
        // a small vertex set: scanned whole (up to a box's 8 vertices, the
        // heights kept for the second pass: the same values)
        let small = s.verts.len() <= SMALL_SET;
        let mut hs = [0.0; SMALL_SET];
        let low = if small {
            for (h, v) in hs.iter_mut().zip(&s.verts) {
                *h = height(v);
            }
            hs[..s.verts.len()]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
        } else {
            s.verts.iter().map(height).fold(f64::INFINITY, f64::min)
        };
        if low > margin {
            return;
        }
        if small {
            // no more candidates than `reduce` keeps: they are its output
            // (all of them, in vertex order), made in place
            let hs = &hs[..s.verts.len()];
            if hs.iter().filter(|&&h| h <= margin).count() <= cx.maxp {
                for (k, &h) in hs.iter().enumerate() {
                    if h <= margin {
                        out.push(point(k));
                    }
                }
                return;
            }
        }
        let mut candidate = |k: usize| scratch.push(point(k));
        for (k, v) in s.verts.iter().enumerate() {
            let h = if small { hs[k % SMALL_SET] } else { height(v) };
            if h <= margin {
                candidate(k);
            }
        }
        reduce(scratch, cx.maxp, out, cx.prev_flag, cx.reduce_dirs);
        return;
    }
    // a sphere, capsule or cylinder: its manifold points are computed
    // directly (a sphere's and a capsule's lowest points, a cylinder's
    // lowest rim points, where its lowest point always lies, and its
    // rim samples); none within the margin, no contact
    let down = Vector3::new(0.0, 0.0, -1.0);
    if let Manifold::Sphere(r) = s.manifold
        && cx.maxp >= 1
    {
        // one candidate: `reduce`'s output as it stands, made in place
        let p = o_m_g.trans + down * r;
        if p.z - ground <= margin {
            out.push(s.contact_at(si, base, p, ground));
        }
        return;
    }
    let mut push = |slot: usize, p: Vector3<f64>| {
        let gap = p.z - ground;
        if gap <= margin {
            scratch.push(s.contact_at(si, base + slot, p, ground));
        }
    };
    match s.manifold {
        Manifold::Vertices => {
            for (k, v) in s.verts.iter().enumerate() {
                push(k, o_m_g.act_point(v));
            }
        }
        Manifold::Sphere(r) => push(0, o_m_g.trans + down * r),
        Manifold::Capsule { half, radius } => {
            let a = o_m_g.rot.column(2).into_owned();
            push(0, o_m_g.trans - a * half + down * radius);
            push(1, o_m_g.trans + a * half + down * radius);
        }
        Manifold::Cylinder { half, radius } => {
            let a = o_m_g.rot.column(2).into_owned();
            // lowest point of each rim: centre + r·(−z projected off the axis)
            let d = down - a * a.dot(&down);
            let dn = d.norm();
            if dn > 1e-9 {
                let d = d / dn;
                push(0, o_m_g.trans - a * half + d * radius);
                push(1, o_m_g.trans + a * half + d * radius);
            }
            for (k, v) in s.verts.iter().enumerate() {
                push(2 + k, o_m_g.act_point(v));
            }
        }
    }
    reduce(scratch, cx.maxp, out, cx.prev_flag, cx.reduce_dirs);
}
