//! A link mesh's convex hull for pair contact, with a support map that climbs
//! the hull's vertex graph instead of scanning every vertex.
//!
//! parry's `ConvexPolyhedron` finds its support point s(d) = argmax_v d·v by
//! a scan of all its vertices (a robot's link hull has 300–700): GJK and EPA
//! ask for it at every iteration, and a height field's manifold asks for the
//! shape's whole AABB first (another scan). On a convex polytope's
//! triangulated surface, a vertex no neighbour of which has a larger d·v is a
//! maximum of d·v over the whole polytope (the linear function's local
//! maximum on a convex surface is global), so a steepest ascent on the
//! triangulation's edges from a good start ends at the support point: the
//! start is the hull's extreme vertex toward the centre of d's cell in a cube
//! map of directions (`CELLS`), and a climb then takes a step or two. The
//! AABB at a pose is six such support values. The support face (the face
//! whose normal is best aligned with d) is parry's, found among the few
//! faces that can be best for a direction of d's cell in a finer cube map
//! (`FACE_CELLS`), listed from the cell's cone on its first use (a climb
//! over faces is not exact: the best normal is not always reached by
//! improving neighbours). Point and ray queries are the wrapped
//! `ConvexPolyhedron`'s.

use parry3d_f64::bounding_volume::{Aabb, BoundingSphere};
use parry3d_f64::mass_properties::MassProperties;
use parry3d_f64::math::{Pose, Real, Vector as PVec};
use parry3d_f64::query::{PointProjection, PointQuery, Ray, RayCast, RayIntersection};
use parry3d_f64::shape::{
    ConvexPolyhedron, FeatureId, PackedFeatureId, PolygonalFeature, PolygonalFeatureMap, Shape,
    ShapeType, SupportMap, TypedShape,
};
use std::sync::OnceLock;

/// Hulls with at most this many vertices are scanned whole (parry's own
/// shape): a climb's start costs about as much.
pub(crate) const CLIMB_MIN_VERTICES: usize = 32;

/// The climb's starts: a cube map of directions, `CELLS`² cells on each of
/// the cube's 6 faces; a direction's cell is found from its largest
/// component and the other two's ratios to it, and the cell's seed is the
/// hull's extreme vertex toward the cell's centre direction. 16 (1,536
/// seeds, 6 KB a hull; 4 before): talos' hull–hull supports cost ~0.7 of
/// what they did; where vertices tie, the climb may end at another of them.
const CELLS: usize = 16;

/// The cube-map cell of direction d (any length, not zero).
#[inline]
fn cell(d: PVec) -> usize {
    cell_in(d, CELLS)
}

/// The cell of direction d in a cube map of `cells`² cells a cube face.
#[inline]
fn cell_in(d: PVec, cells: usize) -> usize {
    let a = d.abs();
    // the dominant axis and the two others (u, v) in a fixed order
    let (axis, u, v, m) = if a.x >= a.y && a.x >= a.z {
        (0, d.y, d.z, d.x)
    } else if a.y >= a.z {
        (1, d.z, d.x, d.y)
    } else {
        (2, d.x, d.y, d.z)
    };
    let face = 2 * axis + usize::from(m < 0.0);
    let inv = 1.0 / m.abs();
    // (u/|m| + 1)/2 ∈ [0, 1] → a cell index (NaN → 0)
    let idx = |w: f64| (((w * inv + 1.0) * 0.5 * cells as f64) as usize).min(cells - 1);
    (face * cells + idx(u)) * cells + idx(v)
}

/// The point (u, v) of cube face `face` (u, v ∈ [−1, 1]), as a direction.
fn face_point(face: usize, u: f64, v: f64) -> PVec {
    let m = if face % 2 == 0 { 1.0 } else { -1.0 };
    match face / 2 {
        0 => PVec::new(m, u, v),
        1 => PVec::new(v, m, u),
        _ => PVec::new(u, v, m),
    }
}

/// The centre direction of cube-map cell `c`.
fn cell_centre(c: usize) -> PVec {
    let (face, rest) = (c / (CELLS * CELLS), c % (CELLS * CELLS));
    let w = |i: usize| 2.0 * (i as f64 + 0.5) / CELLS as f64 - 1.0;
    face_point(face, w(rest / CELLS), w(rest % CELLS))
}

/// The faces' cube map: `FACE_CELLS`² cells a cube face (their cones are
/// narrower than the climb's seeds', so fewer faces are candidates of one).
const FACE_CELLS: usize = 16;

/// The angle (rad) between directions a and b (any length), accurate near 0.
fn angle(a: PVec, b: PVec) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The faces of cell `cell` of the faces' cube map that may be the best
/// aligned with a direction in it, in index order (`normal` gives face f's
/// unit normal). A cell's directions lie within r of its centre c (r: the
/// angle to its farthest corner); with θ_f = ∠(n_f, c) and θ₀ = min θ_f, a
/// direction d of the cell has ∠(n_f, d) ≥ θ_f − r and ∠(n₀, d) ≤ θ₀ + r, so
/// only faces with θ_f ≤ θ₀ + 2r can be best; a 10⁻⁶ rad slack keeps every
/// face whose rounded n·d may tie the best (docs/theory.md §"Support face by
/// cells"). The angles are compared as cosines (one product a face).
fn cell_faces(cell: usize, faces: usize, normal: impl Fn(usize) -> PVec) -> Box<[u32]> {
    const SLACK: f64 = 1e-6;
    let n = FACE_CELLS;
    let (face, i, j) = (cell / (n * n), cell / n % n, cell % n);
    let w = |i: usize| 2.0 * i as f64 / n as f64 - 1.0;
    let (u0, u1, v0, v1) = (w(i), w(i + 1), w(j), w(j + 1));
    let c = face_point(face, 0.5 * (u0 + u1), 0.5 * (v0 + v1)).normalize();
    let r = [(u0, v0), (u0, v1), (u1, v0), (u1, v1)]
        .iter()
        .map(|&(u, v)| angle(face_point(face, u, v), c))
        .fold(0.0, f64::max);
    let cosine: Vec<f64> = (0..faces).map(|f| normal(f).dot(c)).collect();
    let best = cosine.iter().copied().fold(-1.0f64, f64::max);
    // cos(θ₀ + 2r + slack), θ₀ from the best cosine
    let reach = (best.clamp(-1.0, 1.0).acos() + 2.0 * r + SLACK).min(std::f64::consts::PI);
    let floor = reach.cos();
    (0..faces)
        .filter(|&f| cosine[f] >= floor)
        .map(|f| f as u32)
        .collect()
}

/// A convex hull with a graph-climbing support map (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct ClimbHull {
    /// parry's hull of the points.
    pub(crate) hull: ConvexPolyhedron,
    /// The triangulation's vertex graph, compressed rows: the neighbours of
    /// vertex k are `adj[adj_start[k]..adj_start[k + 1]]`.
    adj_start: Vec<u32>,
    adj: Vec<u32>,
    /// The neighbours' points, `adj`'s entries' vertices copied in the same
    /// order (the climb reads them contiguously, with no index to follow).
    adj_pts: Vec<PVec>,
    /// Per cube-map cell, the extreme vertex toward its centre (one with
    /// neighbours).
    seeds: Vec<u32>,
    /// The faces' normals, component by component (a scan that vectorises).
    normal_x: Vec<f64>,
    normal_y: Vec<f64>,
    normal_z: Vec<f64>,
    /// Per cell of the faces' cube map, its candidate faces ([`cell_faces`]),
    /// found the first time a direction of the cell is asked (a robot's
    /// pair asks few of the 1,536 cells).
    cells: Box<[OnceLock<Box<[u32]>>]>,
    /// The mean of the vertices (a point inside the hull).
    centre: PVec,
    /// The box of the vertices in the hull's frame.
    local_box: Aabb,
}

/// The compressed vertex graph of `n` vertices from triangles.
pub(crate) fn triangle_graph(n: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    compressed_graph(
        n,
        triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]),
    )
}

/// The compressed rows (start, neighbours) of the undirected graph of `n`
/// vertices with `edges` (out-of-range ends and loops ignored, duplicates
/// merged): the neighbours of k are `adj[start[k]..start[k + 1]]`, sorted.
pub(crate) fn compressed_graph(
    n: usize,
    edges: impl Iterator<Item = (u32, u32)>,
) -> (Vec<u32>, Vec<u32>) {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (a, b) in edges {
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

impl ClimbHull {
    /// The hull of `points` (`None`: flat or too few points); `Ok(hull)` is
    /// parry's plain hull when it has at most [`CLIMB_MIN_VERTICES`] vertices.
    pub fn of_points(points: &[PVec]) -> Option<Result<Self, ConvexPolyhedron>> {
        let (verts, tris) = parry3d_f64::transformation::try_convex_hull(points).ok()?;
        let n = verts.len();
        let hull = ConvexPolyhedron::from_convex_mesh(verts, &tris)?;
        if n <= CLIMB_MIN_VERTICES || hull.points().len() != n {
            return Some(Err(hull));
        }
        let (adj_start, adj) = triangle_graph(n, &tris);
        let pts = hull.points();
        let mut seeds: Vec<u32> = Vec::with_capacity(6 * CELLS * CELLS);
        for c in 0..6 * CELLS * CELLS {
            let d = cell_centre(c);
            let mut best = usize::MAX;
            let mut bv = f64::NEG_INFINITY;
            for (k, p) in pts.iter().enumerate() {
                let v = p.dot(d);
                if v > bv && adj_start[k + 1] > adj_start[k] {
                    bv = v;
                    best = k;
                }
            }
            if best == usize::MAX {
                return Some(Err(hull));
            }
            seeds.push(best as u32);
        }
        let adj_pts = adj.iter().map(|&j| pts[j as usize]).collect();
        let normal = |c: usize| hull.faces().iter().map(|f| f.normal[c]).collect();
        let centre = pts.iter().fold(PVec::ZERO, |s, p| s + *p) / n as f64;
        Some(Ok(Self {
            cells: (0..6 * FACE_CELLS * FACE_CELLS)
                .map(|_| OnceLock::new())
                .collect(),
            centre,
            local_box: hull.local_aabb(),
            normal_x: normal(0),
            normal_y: normal(1),
            normal_z: normal(2),
            hull,
            adj_start,
            adj,
            adj_pts,
            seeds,
        }))
    }

    /// The hull's vertices.
    pub fn points(&self) -> &[PVec] {
        self.hull.points()
    }

    /// A point inside the hull (the mean of its vertices).
    pub fn centre(&self) -> PVec {
        self.centre
    }

    /// The neighbours of vertex `k` on the triangulation's vertex graph.
    #[inline]
    pub fn neighbours(&self, k: usize) -> &[u32] {
        &self.adj[self.adj_start[k] as usize..self.adj_start[k + 1] as usize]
    }

    /// The index of a vertex maximising d·v, and d·v there: a steepest
    /// ascent from d's cell's seed, to the first best neighbour while it is
    /// better (the neighbours' points read from `adj_pts`, the same products).
    #[inline]
    pub fn support_index(&self, d: PVec) -> (usize, f64) {
        let pts = self.hull.points();
        let mut k = self.seeds[cell(d)] as usize;
        let mut best = pts[k].dot(d);
        loop {
            let (a, b) = (self.adj_start[k] as usize, self.adj_start[k + 1] as usize);
            let mut next = usize::MAX;
            for (i, p) in self.adj_pts[a..b].iter().enumerate() {
                let v = p.dot(d);
                if v > best {
                    best = v;
                    next = i;
                }
            }
            if next == usize::MAX {
                return (k, best);
            }
            k = self.adj[a + next] as usize;
        }
    }

    /// The climb as it was before `adj_pts` (each neighbour's point read
    /// through its index), kept as the reference [`Self::support_index`]
    /// must match index for index (tests/unit/contact_hull.rs).
    pub(crate) fn support_index_by_index(&self, d: PVec) -> (usize, f64) {
        let pts = self.hull.points();
        let mut k = self.seeds[cell(d)] as usize;
        let mut best = pts[k].dot(d);
        loop {
            let mut next = k;
            for &j in self.neighbours(k) {
                let v = pts[j as usize].dot(d);
                if v > best {
                    best = v;
                    next = j as usize;
                }
            }
            if next == k {
                return (k, best);
            }
            k = next;
        }
    }
}

/// A test hull of the climbing kind: points on the superellipsoid of half
/// extents `half` and exponent `power` (24 × 11 rings and both poles).
impl SupportMap for ClimbHull {
    #[inline]
    fn local_support_point(&self, dir: PVec) -> PVec {
        self.hull.points()[self.support_index(dir).0]
    }
}

impl ClimbHull {
    /// The face whose normal is best aligned with `dir` (the first of the
    /// best, as parry's scan): among the candidates of `dir`'s cell of the
    /// faces' cube map (see [`cell_faces`]), which hold every face that
    /// can reach the best value, in index order, so that the first of the
    /// best among them is the scan's (the same products, bit for bit); a
    /// direction with no cell (zero, tiny, not finite) is scanned whole.
    #[inline]
    fn best_face(&self, dir: PVec) -> usize {
        let (nx, ny, nz) = (&self.normal_x, &self.normal_y, &self.normal_z);
        let dot = |i: usize| nx[i] * dir.x + ny[i] * dir.y + nz[i] * dir.z;
        let big = dir.abs().max_element();
        if !(big > 1e-100 && big < 1e100) {
            return self.scan_face(dir);
        }
        let c = cell_in(dir, FACE_CELLS);
        let list = self.cells[c]
            .get_or_init(|| cell_faces(c, nx.len(), |f| PVec::new(nx[f], ny[f], nz[f])));
        let mut best = f64::NEG_INFINITY;
        let mut face = 0;
        for &k in list.iter() {
            let v = dot(k as usize);
            if v > best {
                best = v;
                face = k as usize;
            }
        }
        face
    }

    /// [`Self::best_face`] by a scan of every face normal, kept as three
    /// arrays: the best value first (four lanes at a time), then its first
    /// face (the same products, bit for bit).
    fn scan_face(&self, dir: PVec) -> usize {
        let (nx, ny, nz) = (&self.normal_x, &self.normal_y, &self.normal_z);
        let dot = |i: usize| nx[i] * dir.x + ny[i] * dir.y + nz[i] * dir.z;
        let n = nx.len();
        let mut m = [f64::NEG_INFINITY; 4];
        let mut i = 0;
        while i + 4 <= n {
            for (l, ml) in m.iter_mut().enumerate() {
                let v = dot(i + l);
                if v > *ml {
                    *ml = v;
                }
            }
            i += 4;
        }
        let mut best = m[0].max(m[1]).max(m[2].max(m[3]));
        for k in i..n {
            let v = dot(k);
            if v > best {
                best = v;
            }
        }
        (0..n).find(|&k| dot(k) == best).unwrap_or(0)
    }
}

impl PolygonalFeatureMap for ClimbHull {
    /// parry's support face (the face whose normal is best aligned with
    /// `dir`, its first 4 vertices and edges), by [`ClimbHull::best_face`].
    fn local_support_feature(&self, dir: PVec, out_feature: &mut PolygonalFeature) {
        let h = &self.hull;
        let best = self.best_face(dir);
        let face = &h.faces()[best];
        let i1 = face.first_vertex_or_edge as usize;
        let nv = (face.num_vertices_or_edges as usize).min(4);
        let (vaf, eaf, pts) = (h.vertices_adj_to_face(), h.edges_adj_to_face(), h.points());
        for i in 0..nv {
            let (vid, eid) = (vaf[i1 + i], eaf[i1 + i]);
            out_feature.vertices[i] = pts[vid as usize];
            out_feature.vids[i] = PackedFeatureId::vertex(vid);
            out_feature.eids[i] = PackedFeatureId::edge(eid);
        }
        out_feature.fid = PackedFeatureId::face(best as u32);
        out_feature.num_vertices = nv;
    }

    fn is_convex_polyhedron(&self) -> bool {
        true
    }
}

impl PointQuery for ClimbHull {
    fn project_local_point(&self, pt: PVec, solid: bool) -> PointProjection {
        self.hull.project_local_point(pt, solid)
    }

    fn project_local_point_and_get_feature(&self, pt: PVec) -> (PointProjection, FeatureId) {
        self.hull.project_local_point_and_get_feature(pt)
    }
}

impl RayCast for ClimbHull {
    fn cast_local_ray_and_get_normal(
        &self,
        ray: &Ray,
        max_time_of_impact: Real,
        solid: bool,
    ) -> Option<RayIntersection> {
        self.hull
            .cast_local_ray_and_get_normal(ray, max_time_of_impact, solid)
    }
}

impl Shape for ClimbHull {
    fn compute_local_aabb(&self) -> Aabb {
        self.local_box
    }

    fn compute_local_bounding_sphere(&self) -> BoundingSphere {
        self.hull.local_bounding_sphere()
    }

    fn clone_dyn(&self) -> Box<dyn Shape> {
        Box::new(self.clone())
    }

    fn scale_dyn(&self, scale: PVec, num_subdivisions: u32) -> Option<Box<dyn Shape>> {
        self.hull.scale_dyn(scale, num_subdivisions)
    }

    /// Six support values: world axis i's extent is t_i ± max ±(Rᵀeᵢ)·v.
    fn compute_aabb(&self, position: &Pose) -> Aabb {
        let inv = position.rotation.inverse();
        let t = position.translation;
        let mut mins = PVec::ZERO;
        let mut maxs = PVec::ZERO;
        for (i, e) in [PVec::X, PVec::Y, PVec::Z].into_iter().enumerate() {
            let d = inv * e;
            maxs[i] = t[i] + self.support_index(d).1;
            mins[i] = t[i] - self.support_index(-d).1;
        }
        Aabb::new(mins, maxs)
    }

    fn mass_properties(&self, density: Real) -> MassProperties {
        self.hull.mass_properties(density)
    }

    fn is_convex(&self) -> bool {
        true
    }

    fn shape_type(&self) -> ShapeType {
        ShapeType::Custom
    }

    fn as_typed_shape(&self) -> TypedShape<'_> {
        TypedShape::Custom(self)
    }

    fn ccd_thickness(&self) -> Real {
        self.hull.ccd_thickness()
    }

    fn ccd_angular_thickness(&self) -> Real {
        self.hull.ccd_angular_thickness()
    }

    fn as_support_map(&self) -> Option<&dyn SupportMap> {
        Some(self as &dyn SupportMap)
    }

    fn as_polygonal_feature_map(&self) -> Option<(&dyn PolygonalFeatureMap, Real)> {
        Some((self as &dyn PolygonalFeatureMap, 0.0))
    }
}
