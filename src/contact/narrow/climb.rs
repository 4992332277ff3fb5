//! Two climbing hulls' contact manifold: parry's polyhedral generator
//! (`contact_manifold_pfm_pfm`: GJK, EPA in penetration, the support
//! features clipped) with GJK started from the pair's last simplex.
//!
//! parry starts GJK from one support point along the last normal and needs
//! ~9 iterations on a 300–700-vertex hull to its stop (a relative duality
//! gap of √(10 ε)). The last query's simplex is a set of vertex pairs
//! (x₁ on a, x₂ on b, each in its own frame): at the new pose each x₁ − x₂
//! is still a point of the CSO (a − b), so they are a valid start for GJK,
//! which then converges from a simplex already at the closest features of a
//! pair that moved a little (docs/theory.md §"Warm-started GJK"). The answer
//! is GJK's, to the same stop; only the iterates differ (their rounding).

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::epa::EPA;
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, TrackedContact, TypedWorkspaceData, WorkspaceData,
};
use parry3d_f64::shape::{PackedFeatureId, PolygonalFeature, PolygonalFeatureMap};

thread_local! {
    /// EPA's polytope (its vertices, faces, silhouette and heap), kept
    /// between the calls on this thread: parry builds an `EPA::new()` at each
    /// query, and `EPA::closest_points` clears it first, so the same
    /// operations give the same points without the vectors' regrowth.
    static EPA_KEPT: std::cell::RefCell<EPA> = std::cell::RefCell::new(EPA::new());
}

/// `f` with this thread's kept EPA ([`EPA_KEPT`]): the climbing hulls' query
/// and the cylinder pairs' (`cylinder::pfm`).
#[inline(always)]
pub(crate) fn with_kept_epa<R>(f: impl FnOnce(&mut EPA) -> R) -> R {
    EPA_KEPT.with(|epa| f(&mut epa.borrow_mut()))
}

/// The vertex pairs of a pair's last GJK simplex: a's point in a's frame,
/// b's in b's (valid at any pose). Kept in the pair's parry workspace.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct WarmSimplex {
    n: usize,
    pts: [(Vector, Vector); 4],
}

impl WorkspaceData for WarmSimplex {
    fn as_typed_workspace_data(&self) -> TypedWorkspaceData<'_> {
        TypedWorkspaceData::Custom
    }

    fn clone_dyn(&self) -> Box<dyn WorkspaceData> {
        Box::new(*self)
    }
}

impl WarmSimplex {
    /// The pair's kept simplex (made empty when the workspace holds none).
    fn of(workspace: &mut Option<ContactManifoldsWorkspace>) -> Option<&mut WarmSimplex> {
        if workspace
            .as_ref()
            .is_none_or(|w| w.0.downcast_ref::<WarmSimplex>().is_none())
        {
            *workspace = Some(ContactManifoldsWorkspace::from(WarmSimplex::default()));
        }
        workspace.as_mut()?.0.downcast_mut::<WarmSimplex>()
    }

    /// Keeps `simplex`'s vertices (computed at `pos12` = a⁻¹b).
    fn keep(&mut self, simplex: &VoronoiSimplex, pos12: &Pose) {
        let n = (simplex.dimension() + 1).min(4);
        for i in 0..n {
            let p = simplex.point(i);
            self.pts[i] = (p.orig1, pos12.inverse_transform_point(p.orig2));
        }
        self.n = n;
    }

    /// `simplex` set to the kept vertices at `pos12` (false: none kept).
    fn start(&self, simplex: &mut VoronoiSimplex, pos12: &Pose) -> bool {
        let Some(&(a0, b0)) = self.pts.get(..self.n).and_then(|p| p.first()) else {
            return false;
        };
        simplex.reset(CsoPoint::new(a0, pos12 * b0));
        for &(a, b) in &self.pts[1..self.n] {
            // a vertex that became (nearly) dependent on the others is left
            // out (GJK's own test)
            simplex.add_point(CsoPoint::new(a, pos12 * b));
        }
        true
    }
}

/// The gap (m) within which two hulls touch: GJK's answer is asked from
/// parry's start ([`climb_manifold`]). GJK's relative stop (√(10 ε) ≈ 5·10⁻⁸
/// of the CSO point's length, ~1 m here) cannot be met within ~5·10⁻⁸ m of
/// contact: 0.1 µm keeps twice that (docs/theory.md §"Warm-started GJK").
const TOUCHING: f64 = 1e-7;

/// parry's `contact_manifold_pfm_pfm` for two climbing hulls (no border, no
/// normal constraint; the caller has cleared the points, so parry's reuse of
/// kept points and its impulse transfer do nothing), GJK started from the
/// simplex kept in `workspace` when the pair has a manifold (its history:
/// every reset clears the manifolds), else from parry's start.
pub(crate) fn climb_manifold<S1, S2>(
    pos12: &Pose,
    g1: &S1,
    g2: &S2,
    prediction: f64,
    manifold: &mut ContactManifold<(), ()>,
    warm: bool,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) where
    S1: PolygonalFeatureMap,
    S2: PolygonalFeatureMap,
{
    let mut simplex = VoronoiSimplex::new();
    let mut kept = WarmSimplex::of(workspace);
    let started = warm && kept.as_ref().is_some_and(|k| k.start(&mut simplex, pos12));
    let cold = |simplex: &mut VoronoiSimplex| {
        let dir = manifold
            .local_n1
            .try_normalize()
            .or_else(|| pos12.translation.try_normalize())
            .unwrap_or(Vector::X);
        simplex.reset(CsoPoint::from_shapes(pos12, g1, g2, dir));
    };
    if !started {
        cold(&mut simplex);
    }
    let mut contact = gjk::closest_points(pos12, g1, g2, prediction, true, &mut simplex);
    // touching (a gap within 0.1 µm of zero): GJK's direction there is any of
    // the contact features' normal cone, and the one it ends at depends on
    // the start; asked again from parry's start, so that the features (and
    // the points clipped from them) are those parry finds
    let touching = match contact {
        GJKResult::ClosestPoints(p1, p2_1, dir) => (p2_1 - p1).dot(dir).abs() < TOUCHING,
        _ => false,
    };
    if started && touching {
        cold(&mut simplex);
        contact = gjk::closest_points(pos12, g1, g2, prediction, true, &mut simplex);
    }
    if let Some(k) = kept.as_mut() {
        // a pair found apart starts its next query as parry does: from
        // the separating axis (its early stop, the first axis that
        // separates by more than the margin, is what `apart.rs` reuses;
        // a warm simplex stops at another, which proves less)
        match contact {
            GJKResult::NoIntersection(_) => k.n = 0,
            _ => k.keep(&simplex, pos12),
        }
    }
    if contact == GJKResult::Intersection {
        // the origin inside the CSO: EPA from GJK's simplex
        contact = match with_kept_epa(|epa| epa.closest_points(pos12, g1, g2, &simplex)) {
            Some((p1, p2, n)) => GJKResult::ClosestPoints(p1, p2, n),
            None => GJKResult::NoIntersection(Vector::X),
        };
    }
    manifold.clear();
    match contact {
        GJKResult::ClosestPoints(p1, p2_1, dir) => {
            let (local_n1, local_n2) = clip_at_closest(pos12, g1, g2, p1, p2_1, dir, manifold);
            manifold.local_n1 = local_n1;
            manifold.local_n2 = local_n2;
        }
        GJKResult::NoIntersection(dir) => manifold.local_n1 = dir,
        _ => manifold.local_n1 = Vector::ZERO,
    }
}

/// parry's `contact_manifold_pfm_pfm` at GJK's closest points `p1` (shape 1's
/// frame) and `p2_1` (shape 2's, in shape 1's frame) with normal `dir`: each
/// shape's support feature toward the normal, clipped against the other's,
/// and GJK's own point (no normal constraint moved the normal); returns the
/// normals in each shape's frame. The climbing hulls' query and the cylinder
/// pairs' (`cylinder::pfm`) both end here.
#[inline(always)]
pub(crate) fn clip_at_closest<S1, S2>(
    pos12: &Pose,
    g1: &S1,
    g2: &S2,
    p1: Vector,
    p2_1: Vector,
    dir: Vector,
    manifold: &mut ContactManifold<(), ()>,
) -> (Vector, Vector)
where
    S1: PolygonalFeatureMap + ?Sized,
    S2: PolygonalFeatureMap + ?Sized,
{
    let local_n1 = dir;
    let local_n2 = pos12.rotation.inverse() * -dir;
    let mut feature1 = PolygonalFeature::default();
    let mut feature2 = PolygonalFeature::default();
    g1.local_support_feature_toward(local_n1, p1, &mut feature1);
    g2.local_support_feature_toward(local_n2, pos12.inverse_transform_point(p2_1), &mut feature2);
    PolygonalFeature::contacts(
        pos12,
        &pos12.inverse(),
        local_n1,
        local_n2,
        &feature1,
        &feature2,
        manifold,
        false,
    );
    manifold.points.push(TrackedContact::new(
        p1,
        pos12.inverse_transform_point(p2_1),
        PackedFeatureId::UNKNOWN,
        PackedFeatureId::UNKNOWN,
        (p2_1 - p1).dot(local_n1),
    ));
    (local_n1, local_n2)
}
