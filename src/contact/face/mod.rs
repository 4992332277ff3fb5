//! The fast path of a convex hull against a flat face: a box's face, or a
//! height field whose cells under the hull all lie in one plane (a slope, a
//! flat stretch). Where it applies, the contact is the ground path's (the
//! hull's vertices within the margin of the face's plane, each with the
//! face's normal and its height above the plane as the gap) instead of
//! parry's GJK/EPA and polygon clipping, triangle by triangle.
//!
//! On a box's face, as on the ground, a large hull's points are its vertices
//! within 2 mm of its lowest one (and within the margin): the patch is
//! chosen among them; on a height field, every vertex within the margin.
//!
//! It applies only where the plane contact is the exact one: every hull
//! vertex within the margin of the plane lies over the face, and a
//! penetrating one is nearer the face than any other of the box's faces
//! (its depth below the face at most its distance to the face's edges and
//! to the opposite face); on a height field the hull's box (grown by the
//! margin) covers only whole cells of the grid, none removed, all of whose
//! triangles lie in one plane, and no vertex is deeper than the margin.
//! Elsewhere (a foot over the box's edge, a ridge of the height field) the
//! caller asks parry. A box's face is the one of its six with the largest
//! separation of the hull from its plane (the box's face axes of the
//! separating-axis test); a separation beyond the margin, there or below a
//! flat height field, is no contact at all.

use super::hull::ClimbHull;
use crate::spatial::Se3;
use nalgebra::Vector3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::{ConvexPolyhedron, Cuboid, HeightField, Shape};

/// A hull's vertices, and its vertex graph when it is large.
#[derive(Clone, Copy)]
pub(crate) enum HullRef<'a> {
    /// A large hull: support points and candidates on its graph.
    Climb(&'a ClimbHull),
    /// A small hull: scanned whole.
    Small(&'a ConvexPolyhedron),
}

impl<'a> HullRef<'a> {
    /// The hull of a parry shape, if it is one.
    pub fn of(shape: &'a dyn Shape) -> Option<Self> {
        if let Some(h) = shape.as_shape::<ClimbHull>() {
            Some(Self::Climb(h))
        } else {
            shape.as_convex_polyhedron().map(Self::Small)
        }
    }

    fn points(&self) -> &'a [PVec] {
        match self {
            Self::Climb(h) => h.points(),
            Self::Small(h) => h.points(),
        }
    }

    /// A point inside the hull (no vertex is lower along any direction).
    fn inner(&self) -> PVec {
        match self {
            Self::Climb(h) => h.centre(),
            Self::Small(h) => h.points()[0],
        }
    }

    /// The box of the vertices in the hull's frame.
    fn local_box(&self) -> Aabb {
        match self {
            Self::Climb(h) => h.compute_local_aabb(),
            Self::Small(h) => h.local_aabb(),
        }
    }

    /// A vertex minimising d·v (its index) and that minimum.
    fn lowest(&self, d: PVec) -> (usize, f64) {
        match self {
            Self::Climb(h) => {
                let (k, v) = h.support_index(-d);
                (k, -v)
            }
            Self::Small(h) => {
                let mut best = (0, f64::INFINITY);
                for (k, p) in h.points().iter().enumerate() {
                    let v = p.dot(d);
                    if v < best.1 {
                        best = (k, v);
                    }
                }
                best
            }
        }
    }
}

/// The face a hull may rest on, in the other shape's frame.
#[derive(Clone, Copy)]
pub enum FaceShape<'a> {
    /// A box (half extents).
    Cuboid(&'a Cuboid),
    /// A height field (parry's: its grid in its x–z plane, heights along y).
    HeightField(&'a HeightField),
}

impl<'a> FaceShape<'a> {
    /// The face shape of a parry shape, if it is one.
    pub(crate) fn of(shape: &'a dyn Shape) -> Option<Self> {
        if let Some(c) = shape.as_cuboid() {
            Some(Self::Cuboid(c))
        } else {
            shape.as_heightfield().map(Self::HeightField)
        }
    }
}

/// A point of a hull on a face: its vertex, the vertex's height above the
/// face's plane (negative: below) and the plane's unit normal, all in the
/// face shape's frame.
#[derive(Clone, Copy, Debug)]
pub struct FacePoint {
    /// The hull's vertex index.
    pub vertex: usize,
    /// The vertex in the face shape's frame.
    pub point: Vector3<f64>,
    /// Its height above the plane.
    pub gap: f64,
}

/// The points are the vertices at most this far (m) above the lowest one
/// (and within the margin), as the ground path's patch (`BAND` there).
pub(crate) const BAND: f64 = 2e-3;

/// What the fast path found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaceContact {
    /// The plane contact applies: the points (within the margin) were
    /// appended; the plane's unit normal in the face shape's frame.
    Plane(Vector3<f64>),
    /// Apart by more than the margin: no point.
    Apart,
    /// The plane contact is not the exact one here: ask parry.
    Other,
}

/// parry's vector as nalgebra's.
#[inline]
pub(crate) fn to_v(p: PVec) -> Vector3<f64> {
    Vector3::new(p.x, p.y, p.z)
}

#[inline]
fn to_p(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

/// Face `f` (0–5) of a box: its axis i = f / 2 and outward normal ±eᵢ
/// (+ for even f).
fn box_face(f: usize) -> (usize, Vector3<f64>) {
    let mut n = Vector3::zeros();
    n[f / 2] = if f.is_multiple_of(2) { 1.0 } else { -1.0 };
    (f / 2, n)
}

/// The contact of `hull` placed at `b_m_a` (its frame in the face shape's)
/// with `face`, within `margin`; the points go to `out` (cleared) with
/// `stack`/`seen` as scratch (`seen` as long as the hull has vertices).
///
/// `dense = Some((inner, enough))`: the caller keeps, of more than `enough`
/// − 1 points, only those within `inner` of the deepest (see
/// [`crate::contact::narrow`]'s `reduce_pair`). The vertices within `inner`
/// of the lowest are then collected first; when they are `enough` or more,
/// they are the answer (a rounded foot's ring of a few vertices, not the
/// hundred a 5 mm band holds); else the band's climb stops at `enough`
/// points, and the answer is the near ones and the farther ones it found
/// (the caller reduces them to the same points as the whole band), or the
/// whole band when it holds fewer. The band's vertices not climbed are not
/// checked: on a height field they could not fail the check (it bounds
/// depth only, and they are shallower than the deepest), on a box's face
/// one hanging over the face's edge (above its plane, beside the box) no
/// longer sends the pair to parry, whose manifold would be the same face's
/// points.
#[allow(clippy::too_many_arguments)]
pub(crate) fn hull_on_face(
    hull: HullRef<'_>,
    b_m_a: &Se3<f64>,
    face: FaceShape<'_>,
    margin: f64,
    dense: Option<(f64, usize)>,
    out: &mut Vec<FacePoint>,
    stack: &mut Vec<u32>,
    seen: &mut Vec<u32>,
    stamp: u32,
) -> FaceContact {
    out.clear();
    let r = &b_m_a.rot;
    let t = &b_m_a.trans;
    // the hull's lowest value of n·q (q = R p + t) over its vertices: n·t +
    // min_p (Rᵀn)·p
    let lowest = |n: &Vector3<f64>| -> (usize, f64) {
        let d = r.transpose() * n;
        let (k, v) = hull.lowest(to_p(&d));
        (k, v + n.dot(t))
    };
    match face {
        FaceShape::Cuboid(c) => {
            let e = to_v(c.half_extents);
            // the face of largest separation: min_q n·q − e_i (the first of
            // the largest in the order i = 0, 1, 2, + before −). The lowest
            // vertex is no higher than a point inside, so n·q_in − e_i bounds
            // a face's separation from above: the faces are tried by that
            // bound, and those whose bound is below the best found so far
            // are not climbed (a foot on a box's top: one climb, not six)
            let q_in = b_m_a.act_point(&to_v(hull.inner()));
            let mut faces = [(0.0, 0usize); 6];
            for (f, face) in faces.iter_mut().enumerate() {
                let (i, n) = box_face(f);
                *face = (n[i] * q_in[i] - e[i], f);
            }
            faces.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let mut best = (f64::NEG_INFINITY, usize::MAX, 0usize);
            for &(bound, f) in &faces {
                if bound < best.0 {
                    break;
                }
                let (i, n) = box_face(f);
                let (k, low) = lowest(&n);
                let sep = low - e[i];
                if sep > best.0 || (sep == best.0 && f < best.1) {
                    best = (sep, f, k);
                }
            }
            let (sep, f, k0) = best;
            if sep > margin {
                return FaceContact::Apart;
            }
            let (i, n) = box_face(f);
            let (j1, j2) = ((i + 1) % 3, (i + 2) % 3);
            let band = margin.min(sep + BAND);
            let valid = |q: &Vector3<f64>, gap: f64| {
                let depth = (-gap).max(0.0);
                depth <= e[i] && q[j1].abs() + depth <= e[j1] && q[j2].abs() + depth <= e[j2]
            };
            let mut scratch = (out, stack, seen, stamp);
            let ok = collect_dense(
                hull,
                b_m_a,
                &n,
                e[i],
                k0,
                sep,
                band,
                dense,
                &mut scratch,
                valid,
            );
            if ok {
                FaceContact::Plane(n)
            } else {
                FaceContact::Other
            }
        }
        FaceShape::HeightField(hf) => {
            // a box holding the hull in the field's frame, grown by the
            // margin: the hull's own box turned, c = R c_h + t, half
            // extents |R| h (no climbs; a little larger than the hull's
            // tight box, so at most a few more cells are checked)
            let lb = hull.local_box();
            let c = b_m_a.act_point(&to_v(lb.center()));
            let he = to_v(lb.half_extents());
            let half = r.abs() * he + Vector3::repeat(margin);
            let aabb = Aabb::new(to_p(&(c - half)), to_p(&(c + half)));
            let (rows, cols) = hf.unclamped_elements_range_in_local_aabb(&aabb);
            let (nr, nc) = hf.num_cells_ij();
            if rows.start < 0
                || cols.start < 0
                || rows.end > nr as isize
                || cols.end > nc as isize
                || rows.is_empty()
                || cols.is_empty()
            {
                return FaceContact::Other;
            }
            // every triangle of every cell under the box in one plane n·q = h
            let mut plane: Option<(Vector3<f64>, f64)> = None;
            for ci in rows {
                for cj in cols.clone() {
                    let (t1, t2) = hf.triangles_at(ci as usize, cj as usize);
                    for tri in [t1, t2] {
                        let Some(tri) = tri else {
                            return FaceContact::Other;
                        };
                        let Some(nt) = tri.normal() else {
                            return FaceContact::Other;
                        };
                        let mut nt = to_v(nt);
                        if nt.y < 0.0 {
                            nt = -nt;
                        }
                        let h = nt.dot(&to_v(tri.a));
                        match plane {
                            None => plane = Some((nt, h)),
                            Some((n0, h0)) => {
                                if (nt - n0).amax() > 1e-9 || (h - h0).abs() > 1e-9 {
                                    return FaceContact::Other;
                                }
                            }
                        }
                    }
                }
            }
            let Some((n, h)) = plane else {
                return FaceContact::Other;
            };
            let (k0, low) = lowest(&n);
            if low - h > margin {
                return FaceContact::Apart;
            }
            // (every vertex within the margin: with the band's smaller
            // set, solo12 on the 10° slope kept rocking, 0.14 rad/s at 3 s)
            let band = margin;
            let mut scratch = (out, stack, seen, stamp);
            let ok = collect_dense(
                hull,
                b_m_a,
                &n,
                h,
                k0,
                low - h,
                band,
                dense,
                &mut scratch,
                |_, gap| gap >= -margin,
            );
            if ok {
                FaceContact::Plane(n)
            } else {
                FaceContact::Other
            }
        }
    }
}

/// Slack (m) added to a dense first pass's band: the lowest vertex's height
/// is computed two ways (support query, placed vertex) that may differ in
/// the last bits; the pass keeps a little more, never less, than the
/// caller's choice looks at.
const DENSE_SLACK: f64 = 1e-9;

/// The output and scratch of [`collect`]: points, stack, seen marks, stamp.
type Scratch<'s> = (
    &'s mut Vec<FacePoint>,
    &'s mut Vec<u32>,
    &'s mut Vec<u32>,
    u32,
);

/// [`collect`] within `band` of the plane, or, with `dense` (see
/// [`hull_on_face`]), first within its `inner` of the lowest height `low`
/// (kept when that gives `enough` points or fails the check).
#[allow(clippy::too_many_arguments)]
fn collect_dense(
    hull: HullRef<'_>,
    b_m_a: &Se3<f64>,
    n: &Vector3<f64>,
    h: f64,
    k0: usize,
    low: f64,
    band: f64,
    dense: Option<(f64, usize)>,
    scratch: &mut Scratch<'_>,
    valid: impl Fn(&Vector3<f64>, f64) -> bool,
) -> bool {
    let (out, stack, seen, stamp) = scratch;
    let all = usize::MAX;
    let Some((inner, enough)) = dense else {
        return collect(
            hull, b_m_a, n, h, k0, band, all, out, stack, seen, *stamp, &valid,
        );
    };
    let near = band.min(low + inner + DENSE_SLACK);
    if near >= band {
        return collect(
            hull, b_m_a, n, h, k0, band, all, out, stack, seen, *stamp, &valid,
        );
    }
    let ok = collect(
        hull, b_m_a, n, h, k0, near, all, out, stack, seen, *stamp, &valid,
    );
    // a failure inside `near` fails the whole band too
    if !ok || out.len() >= enough {
        return ok;
    }
    // fewer than `enough` near the lowest: the band's climb, after them in
    // `out`, stopped as soon as it has `enough` points (then the caller's
    // reduction looks at the near ones only, and any farther ones make it
    // reduce), its marks undone first (the points and the rim around them)
    if let HullRef::Climb(c) = hull {
        for p in out.iter() {
            seen[p.vertex] = 0;
            for &j in c.neighbours(p.vertex) {
                seen[j as usize] = 0;
            }
        }
    }
    let m = out.len();
    let ok = collect(
        hull,
        b_m_a,
        n,
        h,
        k0,
        band,
        m + enough,
        out,
        stack,
        seen,
        *stamp,
        &valid,
    );
    if !ok {
        return false;
    }
    if out.len() < m + enough {
        // the whole band, fewer than `enough` points: they are the answer,
        // in the order of its climb
        out.drain(..m);
    } else {
        // the near points, then the band's farther ones
        let mut w = m;
        for r in m..out.len() {
            if out[r].gap > near {
                out[w] = out[r];
                w += 1;
            }
        }
        out.truncate(w);
    }
    true
}

/// Appends the hull's vertices within `margin` (the band) of the plane n·q = h (q the
/// vertex in the face shape's frame) to `out`, from the lowest `k0` (on the
/// vertex graph of a large hull: the vertices below a plane are connected on
/// it); false as soon as one fails `valid(q, gap)`; stops (true) once `out`
/// holds `limit` points.
#[allow(clippy::too_many_arguments)]
fn collect(
    hull: HullRef<'_>,
    b_m_a: &Se3<f64>,
    n: &Vector3<f64>,
    h: f64,
    k0: usize,
    margin: f64,
    limit: usize,
    out: &mut Vec<FacePoint>,
    stack: &mut Vec<u32>,
    seen: &mut Vec<u32>,
    stamp: u32,
    valid: &impl Fn(&Vector3<f64>, f64) -> bool,
) -> bool {
    let pts = hull.points();
    // a vertex placed in the face shape's frame, and its height n·q − h
    let at = |k: usize| {
        let q = b_m_a.act_point(&to_v(pts[k]));
        (q, n.dot(&q) - h)
    };
    // its height from the hull's frame, d·p + c (d = Rᵀn, c = n·t − h): the
    // same number up to rounding, so a vertex it puts clearly above the band
    // is skipped without being placed (most of a climb's rim)
    let d = b_m_a.rot.transpose() * n;
    let c = n.dot(&b_m_a.trans) - h;
    let skip = margin + DENSE_SLACK;
    let above = |k: usize| {
        let p = &pts[k];
        d.x * p.x + d.y * p.y + d.z * p.z + c > skip
    };
    match hull {
        HullRef::Small(_) => {
            for k in 0..pts.len() {
                if above(k) {
                    continue;
                }
                let (q, gap) = at(k);
                if gap <= margin {
                    if !valid(&q, gap) {
                        return false;
                    }
                    out.push(FacePoint {
                        vertex: k,
                        point: q,
                        gap,
                    });
                    if out.len() >= limit {
                        return true;
                    }
                }
            }
            true
        }
        HullRef::Climb(c) => {
            if seen.len() < pts.len() {
                seen.resize(pts.len(), 0);
            }
            stack.clear();
            stack.push(k0 as u32);
            seen[k0] = stamp;
            while let Some(k) = stack.pop() {
                let k = k as usize;
                if above(k) {
                    continue;
                }
                let (q, gap) = at(k);
                if gap > margin {
                    continue;
                }
                if !valid(&q, gap) {
                    return false;
                }
                out.push(FacePoint {
                    vertex: k,
                    point: q,
                    gap,
                });
                if out.len() >= limit {
                    return true;
                }
                for &j in c.neighbours(k) {
                    if seen[j as usize] != stamp {
                        seen[j as usize] = stamp;
                        stack.push(j);
                    }
                }
            }
            true
        }
    }
}
