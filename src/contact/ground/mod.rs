//! The fast path of contact with the ground plane z = `ground`: each moving
//! shape's points within the margin found from its vertices' heights (a
//! plane's cheap special cases, as MuJoCo's colliders), reduced to a persistent
//! patch (see the module doc of [`super`]).

mod build;
mod reduce;

use super::shapes::to_pose;
use super::travel::{self, Travel};
use super::{ContactParams, ContactPoint};
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SupportMap};
use reduce::{band_best, reduce, HOLD_DEEPEST, HOLD_EXTREME, MAX_DIRS};

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
}

/// The ground plane and every shape that can touch it.
#[derive(Clone, Debug)]
pub struct GroundContact {
    /// Every collision shape of a moving link; [`ContactPoint::shape`] indexes it.
    /// Shared, not copied, by a clone (they never change after the build: a
    /// batch of simulations cloned from one holds its hulls once).
    pub shapes: std::sync::Arc<[GroundShape]>,
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
    /// outside it (`band_rim`, `rim_len[shape]`); per shape, the generation
    /// of its band (`band_gen`).
    in_band: Vec<u32>,
    band_order: Vec<u32>,
    band_rim: Vec<u32>,
    band_len: Vec<usize>,
    rim_len: Vec<usize>,
    band_gen: Vec<u32>,
    stack: Vec<u32>,
    /// The speculative margin ([`travel`]): per shape, the height of its
    /// geometry origin and the third row of its body's rotation at the last
    /// detection, and how far down it moved in the last step.
    anchor: Vec<[f64; 4]>,
    travel: Travel,
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
        out.clear();
        let ground = self.ground;
        let maxp = self.params.max_points_per_shape.max(1);
        let stepped = self.travel.begin();
        for (si, s) in self.shapes.iter().enumerate() {
            let Some(o_m_b) = o_m_i.get(s.body) else {
                continue;
            };
            if asleep.get(s.body) == Some(&true) {
                continue;
            }
            // broad phase: the bounding sphere clear of the plane (the height of
            // the geometry origin alone, before the whole pose is composed)
            let r = &o_m_b.rot;
            let pt = &s.placement.trans;
            let z = r[(2, 0)] * pt.x + r[(2, 1)] * pt.y + r[(2, 2)] * pt.z + o_m_b.trans.z;
            // the speculative margin: max(δ, c·s), s how far down the shape
            // moved in the last step (docs/theory.md §"Speculative margin")
            let row = [r[(2, 0)], r[(2, 1)], r[(2, 2)]];
            if stepped > 0.0 {
                let down = travel::dropped(&self.anchor[si], z, row, s.bound);
                self.travel.set(si, down * stepped);
            }
            self.anchor[si] = [z, row[0], row[1], row[2]];
            let margin = self.travel.margin(si);
            if z - ground - s.bound > margin {
                continue;
            }
            let o_m_g = o_m_b.compose(&s.placement);
            self.queries += 1;
            // a hull or point set: its lowest vertex is its support point toward
            // −z; only the heights are needed to find it and the candidates
            // (one dot product a vertex, no parry query)
            if s.manifold == Manifold::Vertices {
                let r = &o_m_g.rot;
                let (rx, ry, rz) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
                let tz = o_m_g.trans.z - ground;
                let height = |v: &Vector3<f64>| rx * v.x + ry * v.y + rz * v.z + tz;
                let base = self.slot_offset[si];
                let scratch = &mut self.scratch;
                scratch.clear();
                let mut candidate = |k: usize| {
                    let p = o_m_g.act_point(&s.verts[k]);
                    scratch.push(ContactPoint {
                        shape: si,
                        slot: base + k,
                        body: s.body,
                        point: p,
                        gap: p.z - ground,
                        ..s.template
                    });
                };
                if s.adj.is_empty() {
                    // a small vertex set: scanned whole
                    let low = s.verts.iter().map(height).fold(f64::INFINITY, f64::min);
                    if low > margin {
                        continue;
                    }
                    for (k, v) in s.verts.iter().enumerate() {
                        if height(v) <= margin {
                            candidate(k);
                        }
                    }
                    reduce(scratch, maxp, out, &self.prev_flag, &self.reduce_dirs);
                    continue;
                }
                // a hull: descend the vertex graph from the last lowest vertex
                // (a vertex of a convex polytope with no lower neighbour is
                // the lowest), then collect the vertices within the margin,
                // a connected set on the graph
                let nbrs = |k: usize| {
                    let (a, b) = (s.adj_start[k] as usize, s.adj_start[k + 1] as usize);
                    &s.adj[a..b]
                };
                let mut k = self.last_low[si].min(s.verts.len() - 1);
                let mut zk = height(&s.verts[k]);
                loop {
                    let mut best = None;
                    for &j in nbrs(k) {
                        let zj = height(&s.verts[j as usize]);
                        if zj < zk {
                            zk = zj;
                            best = Some(j as usize);
                        }
                    }
                    match best {
                        Some(j) => k = j,
                        None => break,
                    }
                }
                self.last_low[si] = k;
                if zk > margin {
                    continue;
                }
                // the band the patch is chosen from: within BAND of the
                // lowest vertex (a face lying flat on the ground is all
                // inside it; the vertices further up a rounded edge are not
                // needed to span the patch)
                let band = margin.min(zk + BAND);
                let verts = &s.verts[..];
                let order = &mut self.band_order[base..base + verts.len()];
                let rim = &mut self.band_rim[base..base + verts.len()];
                // last step's band (in its search order) and its rim (the
                // vertices next to it outside it): from the same lowest vertex,
                // the band is the same set, searched in the same order, when
                // every band vertex is still in it and no rim vertex is (a
                // height a vertex, no graph walk: a patch at rest)
                let (bl, rl) = (self.band_len[si], self.rim_len[si]);
                let same = bl > 0
                    && order[0] as usize == k
                    && order[1..bl]
                        .iter()
                        .all(|&j| height(&verts[j as usize]) <= band)
                    && !rim[..rl]
                        .iter()
                        .any(|&j| height(&verts[j as usize]) <= band);
                if !same {
                    // the band's vertices by a search from the lowest; a
                    // vertex is marked when its height is first taken (one
                    // height a vertex, in or out of the band), the band's
                    // stamped with this search's generation
                    self.generation = self.generation.wrapping_add(1).max(1);
                    let stamp = self.generation;
                    let visited = &mut self.visited[base..base + verts.len()];
                    let in_band = &mut self.in_band[base..base + verts.len()];
                    let stack = &mut self.stack;
                    stack.clear();
                    stack.push(k as u32);
                    visited[k] = stamp;
                    let (mut bl, mut rl) = (0, 0);
                    while let Some(i) = stack.pop() {
                        order[bl] = i;
                        bl += 1;
                        in_band[i as usize] = stamp;
                        for &j in nbrs(i as usize) {
                            let j = j as usize;
                            if visited[j] != stamp {
                                visited[j] = stamp;
                                if height(&verts[j]) <= band {
                                    stack.push(j as u32);
                                } else {
                                    rim[rl] = j as u32;
                                    rl += 1;
                                }
                            }
                        }
                    }
                    self.band_len[si] = bl;
                    self.rim_len[si] = rl;
                    self.band_gen[si] = stamp;
                }
                let cand = &order[..self.band_len[si]];
                // a band vertex only gets its world point p and its criteria
                // (`reduce`: −φ, cᵢ·x + sᵢ·y), their maxima: no ContactPoint
                // until chosen
                let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
                let dir = &self.reduce_dirs;
                let key = |p: &Vector3<f64>, q: usize| -> f64 {
                    if q == 0 {
                        -(p.z - ground)
                    } else {
                        let (c, sn) = dir[q - 1];
                        c * p.x + sn * p.y
                    }
                };
                let best = match dirs {
                    3 => band_best::<3>(&o_m_g, verts, cand, ground, dir),
                    _ => band_best::<0>(&o_m_g, verts, cand, ground, dir),
                };
                let point = |k: usize| {
                    let p = o_m_g.act_point(&verts[k]);
                    ContactPoint {
                        shape: si,
                        slot: base + k,
                        body: s.body,
                        point: p,
                        gap: p.z - ground,
                        ..s.template
                    }
                };
                if cand.len() <= maxp {
                    out.extend(cand.iter().map(|&i| point(i as usize)));
                    continue;
                }
                // each criterion's choice as `reduce`'s: a point kept last step
                // (this shape's, at most maxp, looked at directly) within its
                // hold of the best, the lowest slot; else the lowest slot within
                // 1e-6 of the best (a scan of the band, only then)
                let (pa, pb, pc) = self.prev_range[si];
                let kept = &self.prev_list[pa..pb];
                let kept_all = &self.prev_list[pa..pc];
                let stamp = self.band_gen[si];
                let start = out.len();
                for (q, &bq) in best.iter().enumerate().take(dirs + 1) {
                    let hold = if q == 0 { HOLD_DEEPEST } else { HOLD_EXTREME };
                    let mut ch = usize::MAX;
                    for &slot in kept {
                        if slot < ch
                            && self.in_band[slot] == stamp
                            && key(&o_m_g.act_point(&verts[slot - base]), q) >= bq - hold
                        {
                            ch = slot;
                        }
                    }
                    let k = if ch != usize::MAX {
                        ch - base
                    } else {
                        let mut kmin = usize::MAX;
                        for &i in cand {
                            let i = i as usize;
                            if i < kmin && key(&o_m_g.act_point(&verts[i]), q) >= bq - 1e-6 {
                                kmin = i;
                            }
                        }
                        if kmin == usize::MAX {
                            cand[0] as usize
                        } else {
                            kmin
                        }
                    };
                    if out.len() - start >= maxp {
                        break;
                    }
                    if !out[start..].iter().any(|p| p.slot == base + k) {
                        out.push(point(k));
                    }
                }
                // a point kept last step and still in the ground that no
                // criterion picked stays in the patch beside the picks (never
                // in place of one: a pick above the ground may be the point
                // about to be hit), at most maxp of them: a point that
                // carries the body does not lose its row because another
                // became the deepest or an extreme (docs/theory.md §"Contact
                // geometry"; borinot's rocking, docs/robots.md)
                self.picks[si] = out.len() - start;
                let mut extra = 0;
                for &slot in kept_all {
                    if extra >= maxp {
                        break;
                    }
                    if out[start..].iter().any(|p| p.slot == slot) {
                        continue;
                    }
                    let p = point(slot - base);
                    if p.gap < 0.0 {
                        out.push(p);
                        extra += 1;
                    }
                }
                continue;
            }
            // a sphere, capsule or cylinder: its manifold points are computed
            // directly (a sphere's and a capsule's lowest points, a cylinder's
            // lowest rim points, where its lowest point always lies, and its
            // rim samples); none within the margin, no contact
            let base = self.slot_offset[si];
            let scratch = &mut self.scratch;
            scratch.clear();
            let mut push = |slot: usize, p: Vector3<f64>| {
                let gap = p.z - ground;
                if gap <= margin {
                    scratch.push(ContactPoint {
                        shape: si,
                        slot: base + slot,
                        body: s.body,
                        point: p,
                        gap,
                        ..s.template
                    });
                }
            };
            let down = Vector3::new(0.0, 0.0, -1.0);
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
            reduce(scratch, maxp, out, &self.prev_flag, &self.reduce_dirs);
        }
        for &k in &self.prev_list {
            self.prev_flag[k] = false;
        }
        self.prev_list.clear();
        self.prev_range.fill((0, 0, 0));
        for p in out.iter() {
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
