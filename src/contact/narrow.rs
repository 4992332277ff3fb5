//! The narrow phase of one pair of shapes: a hull on a flat face by the face
//! path ([`super::face`]), two spheres or capsules in closed form
//! ([`prim`]), a ball on a box or a cylinder by parry's generator in closed
//! form ([`ball`]), two boxes by parry's box–box manifold redone without parry
//! ([`boxes`]), everything else by parry's contact manifolds, and
//! the reduction of the points found to a persistent patch of at most
//! `max_points_per_shape`.

use super::face::{hull_on_face, FaceContact, FacePoint, FaceShape, HullRef};
use super::frame::tangents;
use super::hull::ClimbHull;
use super::shapes::{from_pvec, to_pose, PairShape};
use super::ContactPoint;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::math::Pose;
use parry3d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d_f64::shape::ShapeType;

pub(crate) mod ball;
pub(crate) mod boxes;
pub(crate) mod climb;
pub(crate) mod cylinder;
pub(crate) mod prim;

/// The key bit of a face-path point (its vertex index below it): never a key
/// of parry's features (those fill at most bits 0–59).
pub(super) const FACE_KEY: u64 = 1 << 62;

/// Scratch of the face path.
#[derive(Clone, Debug, Default)]
pub(super) struct FaceScratch {
    points: Vec<FacePoint>,
    stack: Vec<u32>,
    seen: Vec<u32>,
}

/// `Some(hull is a)` when one shape is a hull and the other a box or a
/// height field.
pub(super) fn face_kind(a: &PairShape, b: &PairShape) -> Option<bool> {
    let hull = |s: &PairShape| HullRef::of(&*s.shape).is_some();
    let face = |s: &PairShape| FaceShape::of(&*s.shape).is_some();
    if hull(a) && face(b) {
        Some(true)
    } else if face(a) && hull(b) {
        Some(false)
    } else {
        None
    }
}

/// A raw point of a manifold before the reduction.
#[derive(Clone, Copy, Debug)]
pub struct Raw {
    /// The contact point (world, m).
    pub point: Vector3<f64>,
    /// The unit normal from b toward a (world).
    pub normal: Vector3<f64>,
    /// The signed distance (m, negative in penetration).
    pub gap: f64,
    /// The point's features, the same from step to step.
    pub key: u64,
}

/// The contact points of shapes `a` at `wa` and `b` at `wb` by parry's
/// contact manifolds (`manifolds` and `workspace` kept between steps),
/// appended to `raw`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn parry_points(
    a: &PairShape,
    b: &PairShape,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
    raw: &mut Vec<Raw>,
) {
    // two spheres or capsules: their closed form (no manifold kept)
    if prim::round_points(a, b, wa, wb, margin, raw) {
        manifolds.clear();
        *workspace = None;
        return;
    }
    // a ball on a box or a cylinder: parry's generator in closed form
    if let Some(ball_is_a) = ball::kind(a, b) {
        if ball::ball_points(a, b, wa, wb, ball_is_a, margin, manifolds, raw) {
            return;
        }
    }
    // two boxes: the closed form (`boxes`), parry's manifold without parry
    if let (Some(ha), Some(hb)) = (&a.cuboid, &b.cuboid) {
        // b in a's frame: (R, t) = wa⁻¹ wb
        let a_m_b = wa.inverse().compose(wb);
        let (r, t) = (&a_m_b.rot, &a_m_b.trans);
        raw.clear();
        if manifolds.len() != 1 {
            manifolds.clear();
            manifolds.push(ContactManifold::new());
            *workspace = None;
        }
        let man = &mut manifolds[0];
        // a resting pair keeps its points (as parry's reuse below), else
        // the separating axes and the faces' clip
        if boxes::reuse(man, r, t, REUSE_COS, REUSE_SLIDE * REUSE_SLIDE)
            || boxes::box_box(ha, hb, r, t, margin, man)
        {
            push_points(&manifolds[..], wa, wb, margin, f64::INFINITY, raw);
        }
        return;
    }
    // a cylinder on a box's face or on a cylinder's cap: the closed form
    // where that plane is the exact contact (`cylinder`), else parry below
    let closed = match (a.cylinder, &a.cuboid, b.cylinder, &b.cuboid) {
        (Some(cy), _, _, Some(e)) => {
            raw.clear();
            cylinder::cylinder_box_points(cy, e, true, wa, wb, margin, raw)
        }
        (_, Some(e), Some(cy), _) => {
            raw.clear();
            cylinder::cylinder_box_points(cy, e, false, wa, wb, margin, raw)
        }
        (Some(ca), _, Some(cb), _) => {
            raw.clear();
            cylinder::cylinder_cylinder_points(ca, cb, wa, wb, margin, raw)
        }
        _ => None,
    };
    if let Some(axis) = closed {
        // one manifold without points: its normal is the pair's axis
        if manifolds.len() != 1 {
            manifolds.clear();
            manifolds.push(ContactManifold::new());
            *workspace = None;
        }
        manifolds[0].points.clear();
        manifolds[0].local_n1 = super::shapes::to_pvec(&axis);
        return;
    }
    raw.clear();
    let dispatcher = DefaultQueryDispatcher;
    let pos12 = to_pose(&wa.inverse().compose(wb));
    let climbs = (
        a.shape.as_shape::<ClimbHull>(),
        b.shape.as_shape::<ClimbHull>(),
    );
    let query = |manifolds: &mut Vec<ContactManifold<(), ()>>,
                 workspace: &mut Option<ContactManifoldsWorkspace>| {
        // the points are found anew (a generator that finds the shapes
        // apart returns without touching them; the slots, not parry's
        // contact data, carry the warm starts)
        for man in manifolds.iter_mut() {
            man.points.clear();
        }
        if let (Some(ha), Some(hb)) = climbs {
            climb_manifolds(&pos12, ha, hb, margin, manifolds, workspace);
            return Ok(());
        }
        if cylinder::pfm::takes(a, b) && cylinder::pfm::manifold(&pos12, a, b, margin, manifolds) {
            return Ok(());
        }
        dispatcher.contact_manifolds(&pos12, &*a.shape, &*b.shape, margin, manifolds, workspace)
    };
    // a convex pair that has barely moved since parry found its points
    // keeps them, their gaps measured anew at this pose (exact for a vertex
    // on a face: the face's plane is fixed in a's frame): no GJK, no clipping
    let convex = a.convex && b.convex;
    if convex
        && manifolds.len() == 1
        && polyhedral(a)
        && polyhedral(b)
        && manifolds[0].try_update_contacts_eps(&pos12, REUSE_COS, REUSE_SLIDE * REUSE_SLIDE)
    {
        raw.clear();
        push_points(&manifolds[..], wa, wb, margin, f64::INFINITY, raw);
        return;
    }
    let mut ok = query(manifolds, workspace);
    // a convex pair's depth is at most the shapes' overlap along its normal:
    // deeper, the penetration solver (EPA) has failed; asked again from
    // scratch (no cached direction), and what is still deeper is dropped
    let mut bound = f64::INFINITY;
    if convex && manifolds.len() == 1 {
        bound = overlap_bound(a, b, &pos12, &manifolds[0]);
        if too_deep(&manifolds[0], bound) {
            manifolds.clear();
            *workspace = None;
            ok = query(manifolds, workspace);
            bound = manifolds
                .first()
                .map_or(f64::INFINITY, |m| overlap_bound(a, b, &pos12, m));
        }
    }
    raw.clear();
    if ok.is_ok() {
        push_points(&manifolds[..], wa, wb, margin, bound, raw);
    }
}

/// The dispatcher's generator for two climbing hulls (one manifold, parry's
/// polyhedral one, no border, no normal constraint) with their own type:
/// GJK's supports inlined, not called through `dyn`, and GJK started from
/// the pair's last simplex ([`climb::climb_manifold`]). Out of line: in
/// [`parry_points`] it grew the pair visit past what the inliner keeps whole.
#[inline(never)]
fn climb_manifolds(
    pos12: &Pose,
    ha: &ClimbHull,
    hb: &ClimbHull,
    margin: f64,
    manifolds: &mut Vec<ContactManifold<(), ()>>,
    workspace: &mut Option<ContactManifoldsWorkspace>,
) {
    // a pair with a manifold has a history (every reset clears them)
    let warm = !manifolds.is_empty();
    if manifolds.is_empty() {
        manifolds.push(ContactManifold::new());
    }
    climb::climb_manifold(pos12, ha, hb, margin, &mut manifolds[0], warm, workspace);
}

/// How far (m) a kept point may slide along the contact plane, and how far
/// the normals may tilt (the cosine of 10⁻⁴ rad), since parry found the
/// points, for them to stand (see [`parry_points`]).
const REUSE_SLIDE: f64 = 1e-5;
const REUSE_COS: f64 = 1.0 - 5e-9;

/// Whether parry's manifold of a pair with this shape keeps its points in
/// the pair's own order (a's points as `local_p1`, at pos12 = a⁻¹b), as
/// its polyhedral generators do (two polygonal feature maps, two boxes);
/// a ball's, a capsule's, a half-space's and a triangle's may store theirs
/// flipped.
fn polyhedral(s: &PairShape) -> bool {
    !matches!(
        s.shape.shape_type(),
        ShapeType::Ball | ShapeType::Capsule | ShapeType::HalfSpace | ShapeType::Triangle
    )
}

/// The points of `manifolds` (a at `wa`) within `margin` and no deeper than
/// `bound`, appended to `raw` with the normal from b toward a.
fn push_points(
    manifolds: &[ContactManifold<(), ()>],
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
    bound: f64,
    raw: &mut Vec<Raw>,
) {
    {
        for man in manifolds.iter() {
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
                if c.dist > margin || -c.dist > bound {
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
                // (|Δ|² ≥ Δx² with terms ≥ 0: Δx² ≥ 1e-18 decides "apart")
                let near = |r: &Raw| {
                    let dx = r.point.x - point.x;
                    dx * dx < 1e-18 && (r.point - point).norm_squared() < 1e-18
                };
                if raw.iter().any(near) {
                    continue;
                }
                raw.push(Raw {
                    point,
                    normal: n,
                    gap: c.dist,
                    key,
                });
            }
        }
    }
}

/// How deep (m) a convex pair may be along `man`'s normal ν (a's frame,
/// from a toward b): their overlap along it, max_a ν·x − min_b ν·x (two
/// support points), with a 1 µm tolerance; +∞ when it cannot be told (a
/// shallow manifold needs no check).
fn overlap_bound(a: &PairShape, b: &PairShape, pos12: &Pose, man: &ContactManifold<(), ()>) -> f64 {
    let deepest = man.points.iter().map(|c| c.dist).fold(0.0, f64::min);
    let (Some(sa), Some(sb)) = (a.shape.as_support_map(), b.shape.as_support_map()) else {
        return f64::INFINITY;
    };
    let Some(nu) = man.local_n1.try_normalize() else {
        return f64::INFINITY;
    };
    if deepest > -1e-3 {
        return f64::INFINITY;
    }
    let top_a = nu.dot(sa.local_support_point(nu));
    let low_b = nu.dot(sb.support_point(pos12, -nu));
    top_a - low_b + 1e-6
}

/// Whether a point of `man` is deeper than `bound`.
fn too_deep(man: &ContactManifold<(), ()>, bound: f64) -> bool {
    man.points.iter().any(|c| -c.dist > bound)
}

/// The contact points of a hull on a face shape (`hull_is_a`: the hull is
/// the pair's a) by [`hull_on_face`], appended to `raw` with the normal from
/// b toward a; false when the plane contact is not the exact one (the caller
/// asks parry). `maxp`: what [`reduce_pair`] will be given (of more points
/// than that, only those it looks at are collected when they are enough).
#[allow(clippy::too_many_arguments)]
pub(super) fn face_points(
    ma: &PairShape,
    mb: &PairShape,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    hull_is_a: bool,
    margin: f64,
    maxp: usize,
    scratch: &mut FaceScratch,
    raw: &mut Vec<Raw>,
    stamp: u32,
) -> bool {
    let (mh, mf, wh, wf) = if hull_is_a {
        (ma, mb, wa, wb)
    } else {
        (mb, ma, wb, wa)
    };
    let (Some(hull), Some(face)) = (HullRef::of(&*mh.shape), FaceShape::of(&*mf.shape)) else {
        return false;
    };
    let f_m_h = wf.inverse().compose(wh);
    let found = hull_on_face(
        hull,
        &f_m_h,
        face,
        margin,
        // more than `maxp` points: `reduce_pair` looks only at those within
        // EXTREME_BAND of the deepest
        Some((EXTREME_BAND, maxp + 1)),
        &mut scratch.points,
        &mut scratch.stack,
        &mut scratch.seen,
        stamp,
    );
    match found {
        FaceContact::Other => false,
        FaceContact::Apart => true,
        FaceContact::Plane(n) => {
            // the face's normal points toward the hull
            let sign = if hull_is_a { 1.0 } else { -1.0 };
            let normal = wf.rot * n * sign;
            for fp in &scratch.points {
                // the midpoint of the vertex and its foot on the plane
                let p = fp.point - n * (0.5 * fp.gap);
                raw.push(Raw {
                    point: wf.act_point(&p),
                    normal,
                    gap: fp.gap,
                    key: FACE_KEY | fp.vertex as u64,
                });
            }
            true
        }
    }
}

/// The extremes of [`reduce_pair`] are chosen among the points at most this
/// far (m) above the deepest: the points that bear the load. Chosen among
/// every point within the margin, they were the patch's far rim, millimetres
/// up, and a shin lying on solo12's 10° slope stood on one of its two level
/// vertices at a time, swapping every few steps, and crept down the slope
/// at 0.05 rad/s; within 0.3 mm both are kept and it rests (v = 0 by 0.7 s).
/// (2 mm, the ground's band, still left it creeping.)
pub(crate) const EXTREME_BAND: f64 = 3e-4;

/// (sin, cos) of direction `d` of `dirs` evenly spread ones.
fn direction(d: usize, dirs: usize) -> (f64, f64) {
    (std::f64::consts::TAU * d as f64 / dirs as f64).sin_cos()
}

/// The most directions [`directions`] keeps a table for.
const TABLE_DIRS: usize = 8;

/// The [`direction`]s of `dirs` (1 to [`TABLE_DIRS`]), computed once: the
/// same numbers, without a sine and a cosine a direction a pair a step.
fn directions(dirs: usize) -> Option<&'static [(f64, f64)]> {
    static TABLE: std::sync::OnceLock<[[(f64, f64); TABLE_DIRS]; TABLE_DIRS + 1]> =
        std::sync::OnceLock::new();
    let t = TABLE.get_or_init(|| {
        let mut t = [[(0.0, 0.0); TABLE_DIRS]; TABLE_DIRS + 1];
        for (n, row) in t.iter_mut().enumerate().skip(1) {
            for (d, x) in row.iter_mut().enumerate().take(n) {
                *x = direction(d, n);
            }
        }
        t
    });
    t.get(dirs).map(|row| &row[..dirs])
}

/// Appends at most `maxp` of `raw` to `out` as `make` makes them: all when
/// they fit, else the deepest, then the extremes along `maxp − 1` tangent
/// directions of the deepest point's normal among the points within
/// [`EXTREME_BAND`] of it, then, while slots are left, the nearest of the
/// others (not the face path's, [`FACE_KEY`]). (Preferring last step's points
/// within a hold of the best, as the ground's reduction does, left points
/// deeper than the kept ones unchosen: solo12 landing on the box step sank
/// 2 mm instead of 0.06.)
pub(crate) fn reduce_pair(
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
    let band = raw[deepest].gap + EXTREME_BAND;
    let start = out.len();
    out.push(make(&raw[deepest]));
    let (t1, t2) = tangents(&raw[deepest].normal);
    let dirs = maxp - 1;
    let table = directions(dirs);
    for d in 0..dirs {
        let (s, c) = match table {
            Some(t) => t[d],
            None => direction(d, dirs),
        };
        let dir = t1 * c + t2 * s;
        let best = (0..raw.len())
            .filter(|&i| raw[i].gap <= band)
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
    // the slots the extremes left free (they repeat a point: one or two
    // within the band, the rest above it) go to the other points, nearest
    // first: a corner closing on the pair is in the rows within the margin,
    // not first found inside (docs/theory.md §"Speculative margin"). Not to
    // the face path's: it collects above the band only some of the points
    // (`face_points`)
    while out.len() - start < maxp {
        let next = (0..raw.len())
            .filter(|&i| raw[i].key & FACE_KEY == 0)
            .filter(|&i| !out[start..].iter().any(|p| p.key == raw[i].key))
            .min_by(|&i, &j| {
                raw[i]
                    .gap
                    .total_cmp(&raw[j].gap)
                    .then(raw[i].key.cmp(&raw[j].key))
            });
        match next {
            Some(i) => out.push(make(&raw[i])),
            None => break,
        }
    }
}
