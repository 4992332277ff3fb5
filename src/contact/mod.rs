//! Ground contact: the URDF's collision geometry against the plane z = `ground`.
//!
//! # Geometry
//! Each `<collision>` element of a link that moves (links welded to the world take
//! no part) becomes a `parry3d-f64` shape: box → `Cuboid`, sphere → `Ball`,
//! cylinder → `Cylinder` (parry's axis is y, the URDF's z: a fixed x-rotation of
//! +90° is folded into the placement), capsule → `Capsule` (z axis), mesh →
//! `ConvexPolyhedron`, the convex hull of the file's vertices (STL, OBJ, DAE; see
//! [`mesh`]). Meshes are read only here, i.e. only when contact is on; a missing or
//! unreadable mesh file is an error naming the file and the link.
//! There is no self-collision: contact is between links and the ground only.
//!
//! # Detection
//! Per step, a shape whose bounding sphere is clear of the plane by more than
//! the margin `δ` (5 mm) is skipped from its origin's height alone. Otherwise
//! (one query, counted in [`GroundContact::queries`]) its contact *manifold* is
//! its points within `δ` of the plane, found without a general support query
//! (a plane's cheap special cases, as MuJoCo's colliders): a box's corners, a hull's vertices, a
//! cylinder's lowest rim points plus 6 samples on each rim, a sphere's lowest
//! point, a capsule's two end-sphere lowest points (a hull's candidates from its
//! vertices' heights, on its vertex graph when it is large). More than 4 such
//! points are reduced to 4: the deepest and the extremes in 3 horizontal
//! directions, each preferring a point kept last step (a persistent patch that
//! spans the support polygon, see `reduce`). Each
//! point keeps a stable *slot* (shape, feature) so the solver can warm-start.
//!
//! # Forces (solved in [`crate::sim`], docs/theory.md §"Constraint rows")
//! Contact is a velocity-level, time-stepping (Stewart–Trinkle / Anitescu) impulse
//! model: for a point with normal n = +z, signed gap φ (negative = penetration)
//! and Jacobian J (ṗ = J q̇), the step's impulse λ = (λₙ, λₜ₁, λₜ₂) satisfies
//!
//! - 0 ≤ λₙ ⊥ (uₙ − bₙ) ≥ 0 with uₙ = n·ṗ after the step and
//!   bₙ = −φ/Δt when φ > 0 (speculative: the gap may close, not overshoot) and
//!   bₙ = 0 when φ ≤ 0, or with restitution e > 0 and an approaching point,
//!   bₙ = max(bₙ, −e uₙ⁻);
//! - Coulomb's cone ‖λₜ‖ ≤ μ λₙ with maximal dissipation: λₜ opposes the tangential
//!   velocity, and the point sticks (uₜ = 0) while inside the cone — static
//!   friction is exact, not regularised;
//!
//! solved by projected Gauss–Seidel on the Delassus matrix W = J H̃⁻¹ Jᵀ
//! (H̃ = H + A + Δt·D, damping implicit), kept implicit as W = Y Yᵀ with
//! Y = J R⁻¹ (H̃ = RᵀR, tree-sparse: each row lives on its body's path to the
//! root, `crate::sim::factor`; the solver carries R Δv), warm-started from the last step's impulses (stable point slots), to
//! 1e-6 m/s (or rad/s) change per sweep, at most 20 sweeps; sweeps 4–10
//! over-relax the scalar rows by 1.3 (projected SOR) and a plain sweep ends the
//! solve (`crate::sim::solver`; a solve stopped by the cap is made
//! energy-safe). Penetration is removed by the position pass (split impulse):
//! a pseudo-velocity that moves q, never v, at β = 0.2 of the depth per step
//! and at most [`ContactParams::max_push_speed`] (0.5 m/s). The impulse is
//! turned into a world-frame spatial force per body, f̂ = Σ (p × F, F) with
//! F = (λₙ n + λₜ₁ t₁ + λₜ₂ t₂)/Δt (docs/theory.md §"External forces"). With
//! zero restitution the model never adds energy at an impact; it is
//! unconditionally stable at any step (no stiffness).

pub mod mesh;
mod paths;

use crate::model::{Model, Shape};
use crate::spatial::Se3;
use nalgebra::{Matrix3, Vector3};
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SupportMap};
pub use paths::resolve_mesh_path;
use std::path::PathBuf;

/// Contact parameters (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Coulomb friction coefficient μ between links and the ground.
    pub friction: f64,
    /// Newton restitution coefficient e (0: perfectly inelastic).
    pub restitution: f64,
    /// Baumgarte factor β: the fraction of a penetration removed per step by
    /// the position pass (never through the velocity).
    pub baumgarte: f64,
    /// The fastest the position pass pushes a penetrating point out (m/s): a
    /// start deep in the ground comes out slowly, never thrown.
    pub max_push_speed: f64,
    /// Penetration left alone (m): below it nothing is pushed.
    pub slop: f64,
    /// Detection margin δ (m): points closer than this to the plane are candidates.
    pub margin: f64,
    /// The most contact points a shape gives (MuJoCo gives a hull on a plane at
    /// most 3, a box 4): the deepest, then the extremes in this many minus one
    /// horizontal directions, each preferring last step's points. 4 with that
    /// persistent patch settles every robot of the sweep (without persistence, 4
    /// left solo12 rocking on its mesh links and needed 8).
    pub max_points_per_shape: usize,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            friction: 1.0,
            restitution: 0.0,
            baumgarte: 0.2,
            max_push_speed: 0.5,
            slop: 1e-4,
            margin: 0.005,
            max_points_per_shape: 4,
        }
    }
}

/// Why ground contact could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A collision mesh file that no package root or path resolves to.
    #[error("link \"{link}\": collision mesh \"{file}\" not found (give its package root with --package-path or ROS_PACKAGE_PATH, or run with --no-ground)")]
    MissingMesh {
        /// The URDF link whose `<collision>` names the mesh.
        link: String,
        /// The mesh filename as the URDF gives it.
        file: String,
    },
    /// A collision mesh file that was found but could not be read (unreadable,
    /// malformed, empty, or with non-finite coordinates).
    #[error("link \"{link}\": {source}")]
    Mesh {
        /// The URDF link whose `<collision>` names the mesh.
        link: String,
        /// What went wrong with the file.
        #[source]
        source: mesh::MeshError,
    },
    /// A collision primitive with a non-finite or negative dimension.
    #[error("link \"{link}\": collision {kind} has a non-finite or negative size")]
    BadSize {
        /// The URDF link the primitive belongs to.
        link: String,
        /// The primitive: `box`, `sphere`, `cylinder` or `capsule`.
        kind: &'static str,
    },
}

#[derive(Clone, Debug)]
enum ParryShape {
    Ball(Ball),
    Capsule(Capsule),
    Cuboid(Cuboid),
    Cylinder(Cylinder),
    Hull(ConvexPolyhedron),
    /// A degenerate (flat) mesh: its vertices only.
    Points,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Manifold {
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

/// A contact point found by [`GroundContact::detect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// Index of the shape in [`GroundContact::shapes`].
    pub shape: usize,
    /// A stable identity of the point across steps (global slot index).
    pub slot: usize,
    /// The body the shape moves with (index into the model's bodies).
    pub body: usize,
    /// The point on the shape, world frame.
    pub point: Vector3<f64>,
    /// Signed distance to the plane (negative: penetration depth).
    pub gap: f64,
}

/// The ground plane and every shape that can touch it.
#[derive(Clone, Debug)]
pub struct GroundContact {
    /// Every collision shape of a moving link; [`ContactPoint::shape`] indexes it.
    pub shapes: Vec<GroundShape>,
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
    prev_range: Vec<(usize, usize)>,
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
}

/// A large hull's patch is chosen among its vertices at most this far (m)
/// above its lowest one (and within the margin).
const BAND: f64 = 2e-3;

/// Hulls with more vertices than this are searched on their vertex graph
/// instead of scanned whole.
const GRAPH_SEARCH_MIN: usize = 24;

/// The compressed adjacency of a hull's vertex graph from its edges.
fn hull_adjacency(h: &ConvexPolyhedron) -> (Vec<u32>, Vec<u32>) {
    let n = h.points().len();
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    for e in h.edges() {
        let [a, b] = e.vertices;
        if (a as usize) < n && (b as usize) < n && a != b {
            nb[a as usize].push(b);
            nb[b as usize].push(a);
        }
    }
    let mut start = Vec::with_capacity(n + 1);
    let mut adj = Vec::new();
    for list in &mut nb {
        list.sort_unstable();
        list.dedup();
        start.push(adj.len() as u32);
        adj.extend_from_slice(list);
    }
    start.push(adj.len() as u32);
    (start, adj)
}

const CYL_SAMPLES: usize = 6;

fn to_pose(m: &Se3<f64>) -> Pose {
    let r = &m.rot;
    let mat = parry3d_f64::math::Mat3::from_cols_array(&[
        r[(0, 0)],
        r[(1, 0)],
        r[(2, 0)],
        r[(0, 1)],
        r[(1, 1)],
        r[(2, 1)],
        r[(0, 2)],
        r[(1, 2)],
        r[(2, 2)],
    ]);
    let q = parry3d_f64::math::Rot3::from_mat3(&mat).normalize();
    Pose::from_parts(PVec::new(m.trans.x, m.trans.y, m.trans.z), q)
}

fn rot_x90() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
}

impl GroundContact {
    /// Builds the contact shapes of `model` (meshes are read here). Returns `None`
    /// when no moving link has collision geometry: such a scene does no contact work.
    pub fn build(
        model: &Model,
        ground: f64,
        params: ContactParams,
        package_paths: &[PathBuf],
    ) -> Result<Option<Self>, ContactError> {
        let mut shapes = Vec::new();
        for g in &model.collisions {
            if g.body == 0 {
                continue; // welded to the world
            }
            let link = g.link.clone();
            let bad = |kind| ContactError::BadSize {
                link: link.clone(),
                kind,
            };
            let pos = |x: f64| x.is_finite() && x >= 0.0;
            let mut graph = (Vec::new(), Vec::new());
            let (shape, manifold, verts, parry_offset) = match &g.shape {
                Shape::Box { size } => {
                    if !size.iter().all(|&s| pos(s)) {
                        return Err(bad("box"));
                    }
                    let h = Vector3::new(size[0] / 2.0, size[1] / 2.0, size[2] / 2.0);
                    let mut v = Vec::with_capacity(8);
                    for k in 0..8 {
                        let sx = if k & 1 == 0 { -1.0 } else { 1.0 };
                        let sy = if k & 2 == 0 { -1.0 } else { 1.0 };
                        let sz = if k & 4 == 0 { -1.0 } else { 1.0 };
                        v.push(Vector3::new(sx * h.x, sy * h.y, sz * h.z));
                    }
                    (
                        ParryShape::Cuboid(Cuboid::new(PVec::new(h.x, h.y, h.z))),
                        Manifold::Vertices,
                        v,
                        Se3::identity(),
                    )
                }
                Shape::Sphere { radius } => {
                    if !pos(*radius) {
                        return Err(bad("sphere"));
                    }
                    (
                        ParryShape::Ball(Ball::new(*radius)),
                        Manifold::Sphere(*radius),
                        Vec::new(),
                        Se3::identity(),
                    )
                }
                Shape::Capsule { radius, length } => {
                    if !pos(*radius) || !pos(*length) {
                        return Err(bad("capsule"));
                    }
                    (
                        ParryShape::Capsule(Capsule::new_z(length / 2.0, *radius)),
                        Manifold::Capsule {
                            half: length / 2.0,
                            radius: *radius,
                        },
                        Vec::new(),
                        Se3::identity(),
                    )
                }
                Shape::Cylinder { radius, length } => {
                    if !pos(*radius) || !pos(*length) {
                        return Err(bad("cylinder"));
                    }
                    let half = length / 2.0;
                    let mut v = Vec::with_capacity(2 * CYL_SAMPLES);
                    for s in [-1.0, 1.0] {
                        for k in 0..CYL_SAMPLES {
                            let a = std::f64::consts::TAU * (k as f64) / (CYL_SAMPLES as f64);
                            v.push(Vector3::new(radius * a.cos(), radius * a.sin(), s * half));
                        }
                    }
                    (
                        ParryShape::Cylinder(Cylinder::new(half, *radius)),
                        Manifold::Cylinder {
                            half,
                            radius: *radius,
                        },
                        v,
                        Se3::from_rotation(rot_x90()),
                    )
                }
                Shape::Mesh { filename, scale } => {
                    let path = resolve_mesh_path(filename, model.source.as_deref(), package_paths)
                        .ok_or_else(|| ContactError::MissingMesh {
                            link: link.clone(),
                            file: filename.clone(),
                        })?;
                    let pts = mesh::load_vertices(&path, *scale).map_err(|source| {
                        ContactError::Mesh {
                            link: link.clone(),
                            source,
                        }
                    })?;
                    let pv: Vec<PVec> = pts.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
                    match ConvexPolyhedron::from_convex_hull(&pv) {
                        Some(h) => {
                            let v: Vec<_> = h
                                .points()
                                .iter()
                                .map(|p| Vector3::new(p.x, p.y, p.z))
                                .collect();
                            if v.len() > GRAPH_SEARCH_MIN {
                                graph = hull_adjacency(&h);
                            }
                            (ParryShape::Hull(h), Manifold::Vertices, v, Se3::identity())
                        }
                        None => {
                            let mut v = pts;
                            v.dedup();
                            (ParryShape::Points, Manifold::Vertices, v, Se3::identity())
                        }
                    }
                }
                // (a scene's terrain is welded to the world: never a moving link's)
                Shape::HeightField { .. } => continue,
            };
            let nslots = match manifold {
                Manifold::Vertices => verts.len(),
                Manifold::Sphere(_) => 1,
                Manifold::Capsule { .. } => 2,
                Manifold::Cylinder { .. } => 2 + verts.len(),
            };
            let bound = match manifold {
                Manifold::Vertices => verts.iter().map(|v| v.norm()).fold(0.0, f64::max),
                Manifold::Sphere(r) => r,
                Manifold::Capsule { half, radius } => half + radius,
                Manifold::Cylinder { half, radius } => half.hypot(radius),
            };
            shapes.push(GroundShape {
                body: g.body,
                link,
                placement: g.placement,
                parry_offset,
                shape,
                manifold,
                verts,
                adj_start: graph.0,
                adj: graph.1,
                nslots,
                bound,
            });
        }
        if shapes.is_empty() {
            return Ok(None);
        }
        let mut slot_offset = Vec::with_capacity(shapes.len());
        let mut n = 0;
        for s in &shapes {
            slot_offset.push(n);
            n += s.nslots;
        }
        let cap = shapes.iter().map(|s| s.nslots).max().unwrap_or(0);
        let nshapes = shapes.len();
        Ok(Some(Self {
            shapes,
            ground,
            params,
            queries: 0,
            slot_offset,
            nslots: n,
            scratch: Vec::with_capacity(cap),
            prev_flag: vec![false; n],
            prev_list: Vec::with_capacity(n),
            prev_range: vec![(0, 0); nshapes],
            reduce_dirs: reduce_directions(params.max_points_per_shape),
            last_low: vec![0; nshapes],
            visited: vec![0; n],
            generation: 0,
            in_band: vec![0; n],
            band_order: vec![0; n],
            band_rim: vec![0; n],
            band_len: vec![0; nshapes],
            rim_len: vec![0; nshapes],
            band_gen: vec![0; nshapes],
            stack: Vec::with_capacity(n),
        }))
    }

    /// The lowest z of any shape (its support point toward −z), given every
    /// body's world pose; +∞ without shapes. Not counted as a query.
    pub fn lowest_point(&self, o_m_i: &[Se3<f64>]) -> f64 {
        let mut low = f64::INFINITY;
        for s in &self.shapes {
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

    /// The largest number of points [`detect`](Self::detect) can return.
    pub fn max_points(&self) -> usize {
        self.shapes
            .iter()
            .map(|s| s.nslots.min(self.params.max_points_per_shape.max(1)))
            .sum()
    }

    /// Finds the contact points given every body's world pose `o_m_i`, appending
    /// them to `out` (cleared first). No allocation once `out` has
    /// [`max_points`](Self::max_points) capacity.
    pub fn detect(&mut self, o_m_i: &[Se3<f64>], out: &mut Vec<ContactPoint>) {
        out.clear();
        let ground = self.ground;
        let margin = self.params.margin;
        let maxp = self.params.max_points_per_shape.max(1);
        for (si, s) in self.shapes.iter().enumerate() {
            let Some(o_m_b) = o_m_i.get(s.body) else {
                continue;
            };
            // broad phase: the bounding sphere clear of the plane (the height of
            // the geometry origin alone, before the whole pose is composed)
            let r = &o_m_b.rot;
            let pt = &s.placement.trans;
            let z = r[(2, 0)] * pt.x + r[(2, 1)] * pt.y + r[(2, 2)] * pt.z + o_m_b.trans.z;
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
                    let gen = self.generation;
                    let visited = &mut self.visited[base..base + verts.len()];
                    let in_band = &mut self.in_band[base..base + verts.len()];
                    let stack = &mut self.stack;
                    stack.clear();
                    stack.push(k as u32);
                    visited[k] = gen;
                    let (mut bl, mut rl) = (0, 0);
                    while let Some(i) = stack.pop() {
                        order[bl] = i;
                        bl += 1;
                        in_band[i as usize] = gen;
                        for &j in nbrs(i as usize) {
                            let j = j as usize;
                            if visited[j] != gen {
                                visited[j] = gen;
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
                    self.band_gen[si] = gen;
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
                let (pa, pb) = self.prev_range[si];
                let kept = &self.prev_list[pa..pb];
                let gen = self.band_gen[si];
                let start = out.len();
                for (q, &bq) in best.iter().enumerate().take(dirs + 1) {
                    let hold = if q == 0 { HOLD_DEEPEST } else { HOLD_EXTREME };
                    let mut ch = usize::MAX;
                    for &slot in kept {
                        if slot < ch
                            && self.in_band[slot] == gen
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
        self.prev_range.fill((0, 0));
        for p in out.iter() {
            if let Some(f) = self.prev_flag.get_mut(p.slot) {
                *f = true;
                // a shape's points are contiguous in `out`
                let r = &mut self.prev_range[p.shape];
                if r.1 == 0 {
                    r.0 = self.prev_list.len();
                }
                self.prev_list.push(p.slot);
                r.1 = self.prev_list.len();
            }
        }
    }
}

/// The maxima of `reduce`'s criteria (−φ, then cᵢ·x + sᵢ·y for the
/// directions `dir`) over the vertices `verts[i]`, i in `cand`, placed by `m`
/// (φ = z − ground); `D`: the number of directions when it is known at compile
/// time (the default 3), else 0 and every direction of `dir` is taken (the
/// unused ones are (0, 0): their maxima are not looked at).
#[inline(always)]
fn band_best<const D: usize>(
    m: &Se3<f64>,
    verts: &[Vector3<f64>],
    cand: &[u32],
    ground: f64,
    dir: &[(f64, f64); MAX_DIRS],
) -> [f64; MAX_DIRS + 1] {
    // max(b, k) as `if k > b { k } else { b }`: one instruction (maxsd),
    // a NaN k ignored as `reduce` does
    let up = |b: f64, k: f64| if k > b { k } else { b };
    let nd = if D == 0 { MAX_DIRS } else { D };
    let mut best = [f64::NEG_INFINITY; MAX_DIRS + 1];
    for &i in cand {
        let p = m.act_point(&verts[i as usize]);
        best[0] = up(best[0], -(p.z - ground));
        for q in 0..nd {
            let (c, sn) = dir[q];
            best[q + 1] = up(best[q + 1], c * p.x + sn * p.y);
        }
    }
    best
}

/// How much shallower (m) a point kept last step may be than the deepest and
/// still be chosen as the deepest.
const HOLD_DEEPEST: f64 = 1e-4;
/// How much less far out (m) a point kept last step may be than a direction's
/// extreme and still be chosen for it: 2 cm (a foot's size) keeps a patch while
/// the contact lasts; 1 mm left solo12 with 2× the sweeps (its patches changed
/// every few steps).
const HOLD_EXTREME: f64 = 2e-2;

/// Most horizontal directions a reduced manifold uses.
const MAX_DIRS: usize = 8;

/// The `maxp − 1` (1 to [`MAX_DIRS`]) evenly spread horizontal directions
/// (cos, sin) of [`reduce`].
fn reduce_directions(maxp: usize) -> [(f64, f64); MAX_DIRS] {
    let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
    let mut dir = [(0.0, 0.0); MAX_DIRS];
    for (d, x) in dir.iter_mut().enumerate().take(dirs) {
        let (sn, c) = (std::f64::consts::TAU * d as f64 / dirs as f64).sin_cos();
        *x = (c, sn);
    }
    dir
}

/// Appends `pts` to `out`, reduced to at most `maxp` points when there are
/// more: the deepest point, then the extremes in `maxp − 1` evenly spaced
/// horizontal directions (a patch spanning the support polygon: a cylinder
/// lying flat keeps three rim points 120° apart, not a cluster). Each choice
/// prefers a point kept last time (`prev`, by slot) when it is within
/// [`HOLD_DEEPEST`] or [`HOLD_EXTREME`] of the best, then the lowest slot: the set stays the same from step to step while the contact does, so
/// warm starts keep working (a deepest point that flipped between near-equal
/// corners kept solo8's base rocking in a 6 ms cycle).
/// `dir`: [`reduce_directions`] of `maxp`.
fn reduce(
    pts: &[ContactPoint],
    maxp: usize,
    out: &mut Vec<ContactPoint>,
    prev: &[bool],
    dir: &[(f64, f64); MAX_DIRS],
) {
    if pts.len() <= maxp {
        out.extend_from_slice(pts);
        return;
    }
    let dirs = maxp.saturating_sub(1).clamp(1, MAX_DIRS);
    // criterion 0: depth; 1..=dirs: how far out along a direction
    let key = |p: &ContactPoint, q: usize| -> f64 {
        if q == 0 {
            -p.gap
        } else {
            let (c, sn) = dir[q - 1];
            c * p.point.x + sn * p.point.y
        }
    };
    // one pass for every criterion's best value
    let mut best = [f64::NEG_INFINITY; MAX_DIRS + 1];
    for p in pts {
        for (q, b) in best.iter_mut().enumerate().take(dirs + 1) {
            let k = key(p, q);
            if k > *b {
                *b = k;
            }
        }
    }
    // one pass for each criterion's choice: within its hold of the best a point
    // kept last time first, then the lowest slot
    let mut choice = [(true, usize::MAX, 0usize); MAX_DIRS + 1];
    for (i, p) in pts.iter().enumerate() {
        let was = prev.get(p.slot).copied().unwrap_or(false);
        for (q, ch) in choice.iter_mut().enumerate().take(dirs + 1) {
            let hold = match (was, q) {
                (false, _) => 1e-6,
                (true, 0) => HOLD_DEEPEST,
                (true, _) => HOLD_EXTREME,
            };
            if key(p, q) >= best[q] - hold && (!was, p.slot) < (ch.0, ch.1) {
                *ch = (!was, p.slot, i);
            }
        }
    }
    let start = out.len();
    for &(_, _, i) in choice.iter().take(dirs + 1) {
        if out.len() - start >= maxp {
            break;
        }
        if !out[start..].iter().any(|q| q.slot == pts[i].slot) {
            out.push(pts[i]);
        }
    }
}
