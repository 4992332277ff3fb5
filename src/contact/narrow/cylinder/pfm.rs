//! The cylinder pairs the closed forms decline (a rim on a box's edge, a
//! rim on another cylinder's side, ...), by parry's own generator
//! `contact_manifold_pfm_pfm` (GJK, EPA when GJK finds the shapes
//! overlapping, the support features clipped) redone here step for step
//! with one difference: EPA's polytope (its vertices, faces, silhouette and
//! heap) is kept between calls on this thread (`climb::with_kept_epa`, shared
//! with the climbing hulls' query) instead of allocated anew at
//! each (parry's `contact_support_map_support_map_with_params` builds an
//! `EPA::new()` every time; `EPA::closest_points` clears it first, so the
//! same operations give the same points). On the mixed piles EPA runs on
//! about half of these pairs and its vectors' growth (`grow_one`, `realloc`)
//! was ~1.5 % of the step. GJK and EPA are called on the shapes' own types
//! (`Cylinder`, `Cuboid`) where parry's dispatcher passes `dyn`
//! `PolygonalFeatureMap`s: the same support functions, inlined.

use super::super::super::shapes::PairShape;
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::epa::EPA;
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::query::ContactManifold;
use parry3d_f64::shape::{Cuboid, Cylinder, PolygonalFeatureMap};

use super::{apart, rim, side};

/// parry's `utils::COS_1_DEGREES` (crate-private there): the normal's tilt
/// under which its generator keeps a manifold's points.
const COS_1_DEGREES: f64 = 0.99984769515;

/// Whether [`manifold`] takes the pair: a cylinder and a cylinder or a box,
/// the pairs for which parry's dispatcher calls `contact_manifold_pfm_pfm`.
pub(crate) fn takes(a: &PairShape, b: &PairShape) -> bool {
    let cyl_or_box = |s: &PairShape| s.cylinder.is_some() || s.cuboid.is_some();
    (a.cylinder.is_some() && cyl_or_box(b)) || (cyl_or_box(a) && b.cylinder.is_some())
}

/// parry's `DefaultQueryDispatcher::contact_manifolds` of a pair that
/// [`takes`] (both convex, neither composite: the dispatcher's first
/// manifold, made if there is none, by `contact_manifold_pfm_pfm` with no
/// normal constraints), with EPA's polytope kept (module doc). False (and
/// nothing touched) when a shape has no polygonal feature map. Out of
/// line: inlined, it grew [`super::super::parry_points`] and the pair visit
/// past what the inliner keeps whole (talos_fall +0.25 %).
#[inline(never)]
pub(crate) fn manifold(
    pos12: &Pose,
    a: &PairShape,
    b: &PairShape,
    prediction: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
) -> bool {
    manifold_with(pos12, a, b, prediction, manifolds, true)
}

/// [`manifold`], a cylinder's rim on a box's edge ([`rim::rim_on_edge`]) or
/// in another cylinder's side ([`side::rim_in_side`]), in place of GJK and
/// EPA, and a cylinder apart from a box's edge or corner ([`apart`], in
/// place of GJK) in closed form when `closed`.
pub(crate) fn manifold_with(
    pos12: &Pose,
    a: &PairShape,
    b: &PairShape,
    prediction: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    closed: bool,
) -> bool {
    let (Some((_, border_radius1)), Some((_, border_radius2))) = (
        a.shape.as_polygonal_feature_map(),
        b.shape.as_polygonal_feature_map(),
    ) else {
        return false;
    };
    let radii = (border_radius1, border_radius2);
    let (sa, sb) = (&*a.shape, &*b.shape);
    // the shapes' own types: GJK's and EPA's support calls inlined, not
    // through `dyn` (the same functions, so the same arithmetic)
    match (
        sa.as_cylinder(),
        sa.as_cuboid(),
        sb.as_cylinder(),
        sb.as_cuboid(),
    ) {
        (Some(c1), _, Some(c2), _) => {
            let rim = |_| {
                closed
                    .then(|| side::as_epa(c1, c2, pos12))
                    .flatten()
                    .map(|(p1, p2, n)| GJKResult::ClosestPoints(p1, p2, n))
            };
            run(pos12, c1, c2, radii, prediction, manifolds, rim)
        }
        (Some(c1), _, _, Some(c2)) => {
            let rim = |max| {
                closed
                    .then(|| closed_form(c1, c2, pos12, true, max))
                    .flatten()
            };
            run(pos12, c1, c2, radii, prediction, manifolds, rim)
        }
        (_, Some(c1), Some(c2), _) => {
            let rim = |max| {
                closed
                    .then(|| closed_form(c2, c1, pos12, false, max))
                    .flatten()
            };
            run(pos12, c1, c2, radii, prediction, manifolds, rim)
        }
        _ => return false,
    }
    true
}

/// GJK's (or EPA's) answer for a cylinder and a box in closed form: the
/// rim on an edge ([`rim::as_epa`]), else the pair apart near an edge or a
/// corner ([`apart::as_gjk`], within `max_dist`); None: GJK's path.
fn closed_form(
    cyl: &Cylinder,
    cub: &Cuboid,
    pos12: &Pose,
    cyl_first: bool,
    max_dist: f64,
) -> Option<GJKResult> {
    if let Some((p1, p2, n)) = rim::as_epa(cyl, cub, pos12, cyl_first) {
        return Some(GJKResult::ClosestPoints(p1, p2, n));
    }
    apart::as_gjk(cyl, cub, pos12, cyl_first, max_dist)
}

/// [`manifold`] of shapes `pfm1`, `pfm2` (border radii `radii`), GJK's or
/// EPA's answer from `rim` (given the prediction) when it gives one.
fn run<S1: PolygonalFeatureMap, S2: PolygonalFeatureMap>(
    pos12: &Pose,
    pfm1: &S1,
    pfm2: &S2,
    (border_radius1, border_radius2): (f64, f64),
    prediction: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    rim: impl FnOnce(f64) -> Option<GJKResult>,
) {
    if manifolds.is_empty() {
        manifolds.push(ContactManifold::new());
    }
    let manifold = &mut manifolds[0];
    // contact_manifold_pfm_pfm, its lines in its order
    if manifold.try_update_contacts_eps(pos12, COS_1_DEGREES, 1.0e-6) {
        return;
    }
    let init_dir = manifold.local_n1.try_normalize();
    let total_prediction = prediction + border_radius1 + border_radius2;
    // a rim on an edge, or the pair apart: EPA's or GJK's answer in
    // closed form (`rim`)
    let contact = if let Some(found) = rim(total_prediction) {
        found
    } else {
        super::super::climb::with_kept_epa(|epa| {
            with_params(
                pos12,
                pfm1,
                pfm2,
                total_prediction,
                &mut VoronoiSimplex::new(),
                init_dir,
                epa,
            )
        })
    };
    let old_manifold_points = manifold.points.clone();
    manifold.clear();
    match contact {
        GJKResult::ClosestPoints(p1, p2_1, dir) => {
            let (local_n1, local_n2) =
                super::super::climb::clip_at_closest(pos12, pfm1, pfm2, p1, p2_1, dir, manifold);
            if border_radius1 != 0.0 || border_radius2 != 0.0 {
                for contact in &mut manifold.points {
                    contact.local_p1 += local_n1 * border_radius1;
                    contact.local_p2 += local_n2 * border_radius2;
                    contact.dist -= border_radius1 + border_radius2;
                }
            }
            manifold.local_n1 = local_n1;
            manifold.local_n2 = local_n2;
        }
        GJKResult::NoIntersection(dir) => {
            manifold.local_n1 = dir;
        }
        _ => {
            manifold.local_n1 = Vector::ZERO;
        }
    }
    manifold.match_contacts(&old_manifold_points);
}

/// parry's `contact_support_map_support_map_with_params` with EPA's
/// polytope `epa` kept by the caller.
fn with_params<S1: PolygonalFeatureMap, S2: PolygonalFeatureMap>(
    pos12: &Pose,
    g1: &S1,
    g2: &S2,
    prediction: f64,
    simplex: &mut VoronoiSimplex,
    init_dir: Option<Vector>,
    epa: &mut EPA,
) -> GJKResult {
    let dir = if let Some(init_dir) = init_dir {
        init_dir
    } else if let Some(init_dir) = (pos12.translation).try_normalize() {
        init_dir
    } else {
        Vector::X
    };
    simplex.reset(CsoPoint::from_shapes(pos12, g1, g2, dir));
    let cpts = gjk::closest_points(pos12, g1, g2, prediction, true, simplex);
    if cpts != GJKResult::Intersection {
        return cpts;
    }
    if let Some((p1, p2, n)) = epa.closest_points(pos12, g1, g2, simplex) {
        return GJKResult::ClosestPoints(p1, p2, n);
    }
    GJKResult::NoIntersection(Vector::X)
}
