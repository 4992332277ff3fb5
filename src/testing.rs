//! Internals that the tests under `tests/unit/` exercise: not part of the API (hidden
//! from the documentation, no stability promised). These tests were `#[cfg(test)]`
//! modules in `src/`; out here, `cargo test --release` no longer compiles the whole
//! library a second time as a test harness (`[lib] test = false` in Cargo.toml, README
//! §"Two commands").
//!
//! Only thin wrappers are exported: each `pub fn` here calls a `pub(crate)` function
//! of the engine, which keeps its crate-internal linkage (rustc exports only what is
//! reachable from outside the crate; an internal function can be internalised and
//! inlined at its call sites as before). So the wrappers are neither generic nor
//! `#[inline]` (either would make what they call reachable), types may be `pub` (a
//! type's visibility does not change its code), but their methods that the engine
//! calls stay `pub(crate)`, called here; a type with trait impls on the engine's hot
//! path (the climbing hull's support map) stays `pub(crate)` behind a newtype. A new
//! test of an internal goes under `tests/unit/` and, if it needs one, a wrapper here.

/// Mesh files: the COLLADA reader and the cache of made meshes.
pub mod mesh {
    pub use crate::mesh::dae::DaeMesh;
    use std::path::Path;
    use std::sync::Arc;

    /// `mesh::dae::read_dae_colored`.
    pub fn read_dae_colored(text: &str) -> Result<DaeMesh, String> {
        crate::mesh::dae::read_dae_colored(text)
    }

    /// `mesh::cache::cached` for a text made by `make`.
    pub fn cached_text(
        kind: &'static str,
        path: &Path,
        scale: [f64; 3],
        make: &dyn Fn() -> Result<String, String>,
    ) -> Result<Arc<String>, String> {
        crate::mesh::cache::cached(kind, path, scale, make)
    }
}

/// Contact: the hull that climbs to its support point, the face path, the
/// narrow phase's points, the pairs' "still apart" test and the travel bounds.
pub mod contact {
    use crate::contact::face::HullRef;
    use crate::contact::hull::ClimbHull;
    use crate::spatial::Se3;
    use nalgebra::Vector3;
    use parry3d_f64::math::{Pose, Vector as PVec};
    use parry3d_f64::query::{ContactManifold, ContactManifoldsWorkspace};
    use parry3d_f64::shape::{
        ConvexPolyhedron, PolygonalFeature, PolygonalFeatureMap, Shape, SharedShape,
    };

    pub use crate::contact::broad::{PairTable, SweepAndPrune};
    pub use crate::contact::face::{FaceContact, FacePoint, FaceShape};
    pub use crate::contact::narrow::prim::Round;
    pub use crate::contact::narrow::Raw;
    pub use crate::contact::pairs::Member;
    pub use crate::contact::shapes::PairShape;
    pub use crate::contact::ContactPoint;

    /// `contact::face::BAND`.
    pub const BAND: f64 = crate::contact::face::BAND;
    /// `contact::narrow::EXTREME_BAND`.
    pub const EXTREME_BAND: f64 = crate::contact::narrow::EXTREME_BAND;

    /// A climbing hull (`contact::hull::ClimbHull`, which stays crate-internal with
    /// its parry trait impls).
    #[derive(Clone, Debug)]
    pub struct TestHull(ClimbHull);

    impl TestHull {
        /// `ClimbHull::of_points`.
        pub fn of_points(points: &[PVec]) -> Option<Result<Self, ConvexPolyhedron>> {
            ClimbHull::of_points(points).map(|r| r.map(Self))
        }
        /// `ClimbHull::support_index`.
        pub fn support_index(&self, d: PVec) -> (usize, f64) {
            self.0.support_index(d)
        }
        /// `ClimbHull::support_index_by_index` (the climb's reference).
        pub fn support_index_by_index(&self, d: PVec) -> (usize, f64) {
            self.0.support_index_by_index(d)
        }
        /// `ClimbHull::points`.
        pub fn points(&self) -> &[PVec] {
            self.0.points()
        }
        /// Its parry hull of the points.
        pub fn hull(&self) -> &ConvexPolyhedron {
            &self.0.hull
        }
        /// `ClimbHull`'s `PolygonalFeatureMap::local_support_feature`.
        pub fn support_feature(&self, d: PVec, out: &mut PolygonalFeature) {
            self.0.local_support_feature(d, out)
        }
        /// The hull as a parry shape (its own trait impls, through their vtable).
        pub fn shape(&self) -> &dyn Shape {
            &self.0
        }
        /// The hull as a shared parry shape.
        pub fn shared(self) -> SharedShape {
            SharedShape::new(self.0)
        }
    }

    /// `contact::face::hull_on_face` of a climbing hull.
    #[allow(clippy::too_many_arguments)]
    pub fn hull_on_face(
        hull: &TestHull,
        b_m_a: &Se3<f64>,
        face: FaceShape<'_>,
        margin: f64,
        dense: Option<(f64, usize)>,
        out: &mut Vec<FacePoint>,
        stack: &mut Vec<u32>,
        seen: &mut Vec<u32>,
        stamp: u32,
    ) -> FaceContact {
        crate::contact::face::hull_on_face(
            HullRef::Climb(&hull.0),
            b_m_a,
            face,
            margin,
            dense,
            out,
            stack,
            seen,
            stamp,
        )
    }

    /// `contact::face::to_v`.
    pub fn to_v(p: PVec) -> Vector3<f64> {
        crate::contact::face::to_v(p)
    }

    /// `contact::shapes::to_pose`.
    pub fn to_pose(m: &Se3<f64>) -> Pose {
        crate::contact::shapes::to_pose(m)
    }

    /// `PairShape::new`.
    pub fn pair_shape(shape: SharedShape, offset: Se3<f64>, convex: bool) -> PairShape {
        PairShape::new(shape, offset, convex)
    }

    /// `contact::narrow::reduce_pair`, each kept point made by `make`.
    pub fn reduce_pair(
        raw: &[Raw],
        maxp: usize,
        out: &mut Vec<ContactPoint>,
        make: &dyn Fn(&Raw) -> ContactPoint,
    ) {
        crate::contact::narrow::reduce_pair(raw, maxp, out, make)
    }

    /// `contact::narrow::parry_points`.
    #[allow(clippy::too_many_arguments)]
    pub fn parry_points(
        a: &PairShape,
        b: &PairShape,
        wa: &Se3<f64>,
        wb: &Se3<f64>,
        margin: f64,
        manifolds: &mut Vec<ContactManifold<(), ()>>,
        workspace: &mut Option<ContactManifoldsWorkspace>,
        raw: &mut Vec<Raw>,
    ) {
        crate::contact::narrow::parry_points(a, b, wa, wb, margin, manifolds, workspace, raw)
    }

    /// `contact::narrow::boxes::box_box`: the closed-form manifold of boxes
    /// of half extents `ha`, `hb`, b at `a_m_b` in a's frame.
    pub fn box_box(
        ha: &Vector3<f64>,
        hb: &Vector3<f64>,
        a_m_b: &Se3<f64>,
        margin: f64,
        man: &mut ContactManifold<(), ()>,
    ) -> bool {
        crate::contact::narrow::boxes::box_box(ha, hb, &a_m_b.rot, &a_m_b.trans, margin, man)
    }

    /// `contact::narrow::cylinder::cylinder_on_box`: a cylinder (parry's,
    /// half height `h`, radius `r`) at `b_m_c` in the frame of a box of half
    /// extents `e`: None where the closed form declines, else the face's
    /// normal (box frame) and the points (the cylinder's point in the box's
    /// frame, its gap, key), none when apart (`apart` true).
    #[allow(clippy::type_complexity)]
    pub fn cylinder_on_box(
        h: f64,
        r: f64,
        e: &Vector3<f64>,
        b_m_c: &Se3<f64>,
        margin: f64,
    ) -> Option<(Vector3<f64>, bool, Vec<(Vector3<f64>, f64, u64)>)> {
        use crate::contact::narrow::cylinder::{cylinder_on_box, CylBox, Pts, MAX_PTS};
        let mut pts: Pts = ([(Vector3::zeros(), 0.0, 0); MAX_PTS], 0);
        match cylinder_on_box(h, r, e, b_m_c, margin, &mut pts) {
            CylBox::Other => None,
            CylBox::Apart(n) => Some((n, true, Vec::new())),
            CylBox::Plane(n) => Some((n, false, pts.0[..pts.1].to_vec())),
        }
    }

    /// `contact::narrow::cylinder::box_on_cap`: a box of half extents `e` at
    /// `c_m_b` in the frame of a cylinder (parry's, half height `h`, radius
    /// `r`): None where the closed form declines, else the cap's normal and
    /// the points in the cylinder's frame (as [`cylinder_on_box`]).
    #[allow(clippy::type_complexity)]
    pub fn box_on_cap(
        h: f64,
        r: f64,
        e: &Vector3<f64>,
        c_m_b: &Se3<f64>,
        margin: f64,
    ) -> Option<(Vector3<f64>, bool, Vec<(Vector3<f64>, f64, u64)>)> {
        use crate::contact::narrow::cylinder::{box_on_cap, CylBox, Pts, MAX_PTS};
        let mut pts: Pts = ([(Vector3::zeros(), 0.0, 0); MAX_PTS], 0);
        match box_on_cap(h, r, e, c_m_b, margin, &mut pts) {
            CylBox::Other => None,
            CylBox::Apart(n) => Some((n, true, Vec::new())),
            CylBox::Plane(n) => Some((n, false, pts.0[..pts.1].to_vec())),
        }
    }

    /// `contact::narrow::cylinder::cylinder_on_cylinder`: cylinders (half
    /// height, radius) a and b, b at `a_m_b` in a's frame: None where the
    /// closed form declines, else whether the cap is a's, the normal and the
    /// points in that cylinder's frame (as [`cylinder_on_box`]), none when
    /// apart.
    #[allow(clippy::type_complexity)]
    pub fn cylinder_on_cylinder(
        ca: (f64, f64),
        cb: (f64, f64),
        a_m_b: &Se3<f64>,
        margin: f64,
    ) -> Option<(bool, Vector3<f64>, bool, Vec<(Vector3<f64>, f64, u64)>)> {
        use crate::contact::narrow::cylinder::{cylinder_on_cylinder, CylBox, Pts, MAX_PTS};
        let mut pts: Pts = ([(Vector3::zeros(), 0.0, 0); MAX_PTS], 0);
        match cylinder_on_cylinder(ca, cb, a_m_b, margin, &mut pts) {
            (CylBox::Other, _) => None,
            (CylBox::Apart(n), on_a) => Some((on_a, n, true, Vec::new())),
            (CylBox::Plane(n), on_a) => Some((on_a, n, false, pts.0[..pts.1].to_vec())),
        }
    }

    /// `contact::narrow::cylinder::pfm`: whether it takes the pair, and if so
    /// (and it ran) true with `manifolds` written as parry's dispatcher would.
    pub fn cylinder_pfm_manifold(
        pos12: &Pose,
        a: &PairShape,
        b: &PairShape,
        margin: f64,
        manifolds: &mut Vec<ContactManifold<(), ()>>,
    ) -> bool {
        use crate::contact::narrow::cylinder::pfm;
        pfm::takes(a, b) && pfm::manifold(pos12, a, b, margin, manifolds)
    }

    /// `contact::narrow::cylinder::pfm::manifold_with`: [`cylinder_pfm_manifold`]
    /// with the rim-on-edge closed form on (`closed`) or off (parry's GJK and
    /// EPA throughout).
    pub fn cylinder_pfm_manifold_with(
        pos12: &Pose,
        a: &PairShape,
        b: &PairShape,
        margin: f64,
        manifolds: &mut Vec<ContactManifold<(), ()>>,
        closed: bool,
    ) -> bool {
        use crate::contact::narrow::cylinder::pfm;
        pfm::takes(a, b) && pfm::manifold_with(pos12, a, b, margin, manifolds, closed)
    }

    /// `contact::narrow::cylinder::rim::rim_on_edge` of a cylinder at `b_m_c`
    /// (its frame in the box's; the side line on an edge too with `side`):
    /// (normal from the cylinder into the box, depth, rim point, its foot
    /// on the edge), the box's frame.
    pub fn cylinder_rim_on_edge(
        cyl: &parry3d_f64::shape::Cylinder,
        cub: &parry3d_f64::shape::Cuboid,
        b_m_c: &Pose,
        side: bool,
    ) -> Option<(PVec, f64, PVec, PVec)> {
        crate::contact::narrow::cylinder::rim::rim_on_edge(cyl, cub, b_m_c, side)
            .map(|r| (r.n, r.depth, r.rim, r.edge))
    }

    /// `contact::narrow::cylinder::side::rim_in_side` of cylinder `a` at
    /// `b_m_a` (its frame in b's) in cylinder `b`'s side: (normal from a into
    /// b, depth, a's rim point, its foot on b's side), b's frame.
    pub fn cylinder_rim_in_side(
        a: &parry3d_f64::shape::Cylinder,
        b: &parry3d_f64::shape::Cylinder,
        b_m_a: &Pose,
    ) -> Option<(PVec, f64, PVec, PVec)> {
        crate::contact::narrow::cylinder::side::rim_in_side(a, b, b_m_a)
            .map(|r| (r.n, r.depth, r.rim, r.edge))
    }

    /// `contact::narrow::cylinder::apart::as_gjk`: a cylinder and a box apart
    /// near an edge or a corner as GJK's answer (shape 1's frame, the
    /// cylinder shape 1 when `cyl_first`), or None.
    pub fn cylinder_box_apart(
        cyl: &parry3d_f64::shape::Cylinder,
        cub: &parry3d_f64::shape::Cuboid,
        pos12: &Pose,
        cyl_first: bool,
        max_dist: f64,
    ) -> Option<parry3d_f64::query::gjk::GJKResult> {
        crate::contact::narrow::cylinder::apart::as_gjk(cyl, cub, pos12, cyl_first, max_dist)
    }

    /// `Round::of`.
    pub fn round_of(s: &PairShape, w: &Se3<f64>) -> Option<Round> {
        Round::of(s, w)
    }

    /// `contact::narrow::prim::round_points`.
    pub fn round_points(
        a: &PairShape,
        b: &PairShape,
        wa: &Se3<f64>,
        wb: &Se3<f64>,
        margin: f64,
        raw: &mut Vec<Raw>,
    ) -> bool {
        crate::contact::narrow::prim::round_points(a, b, wa, wb, margin, raw)
    }

    /// `contact::pairs::apart::apart_along`.
    pub fn apart_along(
        u: &Vector3<f64>,
        a: &Member,
        b: &Member,
        wa: &Se3<f64>,
        wb: &Se3<f64>,
    ) -> f64 {
        crate::contact::pairs::apart::apart_along(u, a, b, wa, wb)
    }

    /// `contact::pairs::apart::still_apart`.
    pub fn still_apart(
        then: Option<&(f64, Se3<f64>, Se3<f64>)>,
        a: &Member,
        b: &Member,
        wa: &Se3<f64>,
        wb: &Se3<f64>,
        margin: f64,
    ) -> bool {
        crate::contact::pairs::apart::still_apart(then, a, b, wa, wb, margin)
    }

    /// `contact::travel::margin`.
    pub fn margin(delta: f64, c: f64, s: f64) -> f64 {
        crate::contact::travel::margin(delta, c, s)
    }

    /// `contact::travel::moved`.
    pub fn moved(w0: &Se3<f64>, w: &Se3<f64>, mid: &Vector3<f64>, radius: f64) -> f64 {
        crate::contact::travel::moved(w0, w, mid, radius)
    }

    /// `contact::travel::dropped`.
    pub fn dropped(then: &[f64; 4], z: f64, r: [f64; 3], radius: f64) -> f64 {
        crate::contact::travel::dropped(then, z, r, radius)
    }

    /// `PairTable::new`.
    pub fn table_new(n: usize) -> PairTable {
        PairTable::new(n)
    }

    /// `PairTable::allow`.
    pub fn table_allow(t: &mut PairTable, i: usize, j: usize) {
        t.allow(i, j)
    }

    /// `PairTable::allowed`.
    pub fn table_allowed(t: &PairTable, i: usize, j: usize) -> bool {
        t.allowed(i, j)
    }

    /// `PairTable::set`.
    pub fn table_set(t: &mut PairTable, i: usize, j: usize, p: u32) {
        t.set(i, j, p)
    }

    /// `SweepAndPrune::new`.
    pub fn sap_new(n: usize) -> SweepAndPrune {
        SweepAndPrune::new(n)
    }

    /// `SweepAndPrune::set`.
    pub fn sap_set(s: &mut SweepAndPrune, i: usize, c: [f64; 3], h: [f64; 3]) {
        s.set(i, c, h)
    }

    /// `PairMasks::new` on `n` shapes and `pairs`, then `PairMasks::overlaps`
    /// on the boxes of `s`: the pairs found, in the order found (`None`: more
    /// than 64 shapes).
    pub fn mask_pairs(
        n: usize,
        pairs: &[(usize, usize)],
        s: &SweepAndPrune,
    ) -> Option<Vec<(usize, usize)>> {
        let mut m = crate::contact::broad::PairMasks::new(n, pairs.iter().copied())?;
        let mut out = Vec::new();
        m.overlaps(s, |l, h| out.push((l, h)));
        Some(out)
    }

    /// `SweepAndPrune::overlaps`.
    pub fn sap_overlaps(
        s: &mut SweepAndPrune,
        table: &mut PairTable,
        out: &mut Vec<u32>,
        fresh: &mut Vec<(u32, u32)>,
    ) {
        s.overlaps(table, out, fresh)
    }
}

/// The replay page's pieces (the `cli` feature).
#[cfg(feature = "cli")]
pub mod view {
    pub use crate::cli::view::visuals::{Drawables, LinkPieces, Piece};
    use crate::mesh::TriMesh;
    use crate::scene::HeightFieldSpec;
    use nalgebra::Vector3;

    /// `cli::view::geometry::DEFAULT_RGBA`.
    pub const DEFAULT_RGBA: [f64; 4] = crate::cli::view::geometry::DEFAULT_RGBA;

    /// `cli::view::geometry::triangle_limit`.
    pub fn triangle_limit(counts: &[usize], per_mesh: usize, total: usize) -> usize {
        crate::cli::view::geometry::triangle_limit(counts, per_mesh, total)
    }

    /// `cli::view::geometry::bounds`.
    pub fn bounds(m: &TriMesh) -> (Vector3<f64>, Vector3<f64>) {
        crate::cli::view::geometry::bounds(m)
    }

    /// `cli::view::page::base64`.
    pub fn base64(bytes: &[u8]) -> String {
        crate::cli::view::page::base64(bytes)
    }

    /// `cli::view::scene::height_field_mesh`.
    pub fn height_field_mesh(h: &HeightFieldSpec) -> TriMesh {
        crate::cli::view::scene::height_field_mesh(h)
    }

    /// `cli::view::visuals::read`.
    pub fn read_visuals(text: &str) -> Result<Drawables, String> {
        crate::cli::view::visuals::read(text)
    }
}

/// Row forming (sim/constraints.rs, constraints/tables.rs).
pub mod constraints {
    use crate::spatial::Motion;
    use nalgebra::Vector3;

    /// `sim::constraints::tables::add_body` for a body of world columns `cols`
    /// from dof `iv` on the row path `path` (from `hi`): the three rows (each
    /// `row(vp)` where the path holds the column's dof, else 0) and where the
    /// body's first dof lies.
    pub fn add_body_rows(
        path: &[usize],
        hi: usize,
        iv: usize,
        cols: &[Motion],
        p: &Vector3<f64>,
        row: &dyn Fn(Vector3<f64>) -> [f64; 3],
    ) -> ([Vec<f64>; 3], usize) {
        crate::sim::constraints::add_body_rows(path, hi, iv, cols, p, row)
    }

    /// `sim::constraints::free::write`: a contact's three rows (12 entries
    /// each) at `p` along `normal` on a root free body of world columns `a`
    /// (dofs 0..6) against the ground (`b` None, `normal` +z) or a second of
    /// columns `b` (dofs 6..12), written over rows all `stale`; None where the
    /// free rows' plan declines.
    pub fn free_rows(
        a: &[Motion; 6],
        b: Option<&[Motion; 6]>,
        p: &Vector3<f64>,
        normal: &Vector3<f64>,
        stale: f64,
    ) -> Option<[Vec<f64>; 3]> {
        crate::sim::constraints::free_rows(a, b, p, normal, stale)
    }
}

/// The subspace step's dense LDLᵀ of W_FF (sim/solver/dense.rs).
pub mod solver {
    /// `sim::solver::dense::ldlt_dropping` (row i at `a[i * ld..]`, rows
    /// before `from` factored already).
    pub fn ldlt_dropping(a: &mut [f64], ld: usize, m: usize, from: usize, drop: f64) {
        crate::sim::solver::dense::ldlt_dropping(a, ld, m, from, drop)
    }

    /// `sim::solver::dense::ldlt_dropping_solve`.
    pub fn ldlt_dropping_solve(a: &[f64], ld: usize, m: usize, x: &mut [f64]) {
        crate::sim::solver::dense::ldlt_dropping_solve(a, ld, m, x)
    }
}

/// The island solve's team of threads (`sim::parallel`).
pub mod parallel {
    /// `sim::parallel::Team`.
    pub struct Team(crate::sim::parallel::Team);

    impl Team {
        /// `Team::new`.
        pub fn new(threads: usize) -> Option<Self> {
            crate::sim::parallel::Team::new(threads).map(Team)
        }
        /// `Team::threads`.
        pub fn threads(&self) -> usize {
            self.0.threads()
        }
        /// `Team::run`.
        pub fn run(&self, f: &(dyn Fn(usize) + Sync)) {
            self.0.run(f)
        }
    }

    /// `sim::parallel::cut` of `sizes`.
    pub fn cut(
        sizes: &[usize],
        parts: usize,
        min_gain: usize,
        order: &mut Vec<(usize, usize)>,
    ) -> bool {
        crate::sim::parallel::cut(sizes.iter().copied(), parts, min_gain, order)
    }
}
