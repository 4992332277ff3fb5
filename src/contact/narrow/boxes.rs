//! Closed-form box–box contact: parry's cuboid–cuboid manifold
//! (`contact_manifold_cuboid_cuboid`: the separating-axis test over a's
//! faces, b's faces and the nine edge pairs, then the two support faces
//! clipped against each other) redone in a's frame with b's rotation as a
//! matrix, and parry's reuse of a resting pair's points
//! (`try_update_contacts_eps`) with it: no quaternion (parry's pose), no
//! dispatch, no manifold copy. The same axes, faces, points, depths and
//! feature keys as parry's, to rounding (tests/unit/contact_boxes.rs
//! compares them on random pairs).

use super::super::shapes::{from_pvec, to_pvec};
use nalgebra::{Matrix3, Vector2, Vector3};
use parry3d_f64::query::{ContactManifold, TrackedContact};
use parry3d_f64::shape::PackedFeatureId;

/// `h` with the signs of `d` (a box's support point along `d`).
#[inline]
fn support(h: &Vector3<f64>, d: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(h.x.copysign(d.x), h.y.copysign(d.y), h.z.copysign(d.z))
}

/// The largest separation of box `h2` at (`r`, `t`) from box `h1` along
/// h1's face normals (h1's frame, from h1 toward h2): parry's
/// `cuboid_cuboid_find_local_separating_normal_oneway`, which, when two or
/// more faces separate, measures along their separations' sum instead.
fn face_separation(
    h1: &Vector3<f64>,
    h2: &Vector3<f64>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (f64, Vector3<f64>) {
    let mut best = -f64::MAX;
    let mut best_dir = Vector3::zeros();
    let mut acc = Vector3::zeros();
    let mut positive = 0;
    for i in 0..3 {
        // axis s·eᵢ toward h2; h2's lowest point along it: its support along
        // −s·Rᵀeᵢ; separation s·(R p + t)ᵢ − h1ᵢ
        let s = 1.0f64.copysign(t[i]);
        let d2 = Vector3::new(-s * r[(i, 0)], -s * r[(i, 1)], -s * r[(i, 2)]);
        let p2 = support(h2, &d2);
        let x = r[(i, 0)] * p2.x + r[(i, 1)] * p2.y + r[(i, 2)] * p2.z + t[i];
        let sep = x * s - h1[i];
        if sep > best {
            best = sep;
            best_dir = Vector3::zeros();
            best_dir[i] = s;
        }
        if sep >= 0.0 {
            acc[i] += s * sep.max(f64::EPSILON);
            positive += 1;
        }
    }
    if positive > 1 {
        // the separations' sum as the axis: gap (x₂ − x₁)·u of the support points
        let u = acc.normalize();
        let p1 = support(h1, &u);
        let p2 = r * support(h2, &(r.tr_mul(&(-u)))) + t;
        ((p2 - p1).dot(&u), u)
    } else {
        (best, best_dir)
    }
}

/// The largest separation along the nine edge directions eᵢ × R eⱼ (h1's
/// frame, oriented along t): parry's
/// `cuboid_cuboid_find_local_separating_edge_twoway`.
fn edge_separation(
    h1: &Vector3<f64>,
    h2: &Vector3<f64>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> (f64, Vector3<f64>) {
    let mut best = -f64::MAX;
    let mut best_dir = Vector3::zeros();
    for j in 0..3 {
        let c = r.column(j);
        let axes = [
            Vector3::new(0.0, -c.z, c.y),
            Vector3::new(c.z, 0.0, -c.x),
            Vector3::new(-c.y, c.x, 0.0),
        ];
        for axis in &axes {
            let l = axis.norm();
            if l > f64::EPSILON {
                // u = ±axis/|axis| toward t; the support points' gap
                // (R p₂ + t − p₁)·u = |t·u| − Σ h1ₖ|uₖ| − Σ h2ₖ|(Rᵀu)ₖ|
                let u = axis / l;
                let tu = t.dot(&u);
                let s = 1.0f64.copysign(tu);
                let w = r.tr_mul(&u);
                let sep = tu * s
                    - (h1.x * u.x.abs() + h1.y * u.y.abs() + h1.z * u.z.abs())
                    - (h2.x * w.x.abs() + h2.y * w.y.abs() + h2.z * w.z.abs());
                if sep > best {
                    best = sep;
                    best_dir = u * s;
                }
            }
        }
    }
    (best, best_dir)
}

/// A box's face most along `d` (its frame): the four corners, their and
/// its edges' feature ids and the face's, as parry's `Cuboid::support_face`.
struct Face {
    v: [Vector3<f64>; 4],
    vids: [u32; 4],
    eids: [u32; 4],
    fid: u32,
}

/// parry's `PackedFeatureId` headers: vertex, edge, face.
const VERTEX: u32 = 0b01 << 30;
const EDGE: u32 = 0b10 << 30;
const FACE: u32 = 0b11 << 30;

fn support_face(h: &Vector3<f64>, d: &Vector3<f64>) -> Face {
    let a = d.abs();
    let mut imax = 0;
    let mut m = a.x;
    if a.y > m {
        m = a.y;
        imax = 1;
    }
    if a.z > m {
        imax = 2;
    }
    let s = 1.0f64.copysign(d[imax]);
    let si = ((s as isize + 1) / 2) as u32;
    let (v, vids, eids) = match imax {
        0 => {
            let sb = si << 2;
            let eb = (si << 2) | (si << 5);
            (
                [
                    Vector3::new(h.x * s, h.y, h.z),
                    Vector3::new(h.x * s, -h.y, h.z),
                    Vector3::new(h.x * s, -h.y, -h.z),
                    Vector3::new(h.x * s, h.y, -h.z),
                ],
                [sb, 0b010 | sb, 0b011 | sb, 0b001 | sb],
                [
                    0b11_010_000 | eb,
                    0b11_011_010 | eb,
                    0b11_011_001 | eb,
                    0b11_001_000 | eb,
                ],
            )
        }
        1 => {
            let sb = si << 1;
            let eb = (si << 1) | (si << 4);
            (
                [
                    Vector3::new(h.x, h.y * s, h.z),
                    Vector3::new(-h.x, h.y * s, h.z),
                    Vector3::new(-h.x, h.y * s, -h.z),
                    Vector3::new(h.x, h.y * s, -h.z),
                ],
                [sb, 0b100 | sb, 0b101 | sb, 0b001 | sb],
                [
                    0b11_100_000 | eb,
                    0b11_101_100 | eb,
                    0b11_101_001 | eb,
                    0b11_001_000 | eb,
                ],
            )
        }
        _ => {
            let sb = si;
            let eb = si | (si << 3);
            (
                [
                    Vector3::new(h.x, h.y, h.z * s),
                    Vector3::new(h.x, -h.y, h.z * s),
                    Vector3::new(-h.x, -h.y, h.z * s),
                    Vector3::new(-h.x, h.y, h.z * s),
                ],
                [sb, 0b010 | sb, 0b110 | sb, 0b100 | sb],
                [
                    0b11_010_000 | eb,
                    0b11_110_010 | eb,
                    0b11_110_100 | eb,
                    0b11_100_000 | eb,
                ],
            )
        }
    };
    Face {
        v,
        vids: vids.map(|i| VERTEX | (i * 2)),
        eids: eids.map(|i| EDGE | i),
        fid: FACE | (imax as u32 + si * 3 + 10),
    }
}

/// Two unit vectors completing `n` to an orthonormal basis (Duff et al.,
/// as parry's `orthonormal_basis`).
fn basis(n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let s = 1.0f64.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    [
        Vector3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vector3::new(b, s + n.y * n.y * a, -n.y),
    ]
}

/// Whether `a` and `b` are equal within f64::EPSILON or 4 ulps (approx's
/// `ulps_eq!` with its defaults).
fn ulps_eq(a: f64, b: f64) -> bool {
    if (a - b).abs() <= f64::EPSILON {
        return true;
    }
    if a.is_sign_positive() != b.is_sign_positive() {
        return false;
    }
    (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs() <= 4
}

/// Where two 2-D lines cross, as the fractions along each edge (parry's
/// `closest_points_line2d`); `None` when parallel.
fn cross_lines(e1: [Vector2<f64>; 2], e2: [Vector2<f64>; 2]) -> Option<(f64, f64)> {
    let eps = f64::EPSILON;
    let d1 = e1[1] - e1[0];
    let d2 = e2[1] - e2[0];
    let r = e1[0] - e2[0];
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    if a <= eps && e <= eps {
        Some((0.0, 0.0))
    } else if a <= eps {
        Some((0.0, f / e))
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            Some((-c / a, 0.0))
        } else {
            // s = (b f − c e)/(a e − b²), t = (b s + f)/e
            let b = d1.dot(&d2);
            let ae = a * e;
            let bb = b * b;
            let denom = ae - bb;
            if denom <= eps || ulps_eq(ae, bb) {
                None
            } else {
                let s = (b * f - c * e) / denom;
                Some((s, (b * s + f) / e))
            }
        }
    }
}

/// The sides of the points `p` to the edges of the quadrilateral `q`:
/// `s[i][j]` = (q[j+1] − q[j]) × (p[i] − q[j]) (2-D cross product), the
/// numbers parry's inside test computes.
fn sides(q: &[Vector2<f64>; 4], p: &[Vector2<f64>; 4]) -> [[f64; 4]; 4] {
    // (the edges e = q[j+1] − q[j]; e × (x − q[j]) = eₓ (x − q[j])_y −
    // e_y (x − q[j])ₓ, a point at a time, edges 0, 1 and 2, 3 in two lanes)
    let (mut qx, mut qy, mut ex, mut ey) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
    for j in 0..4 {
        let k = (j + 1) % 4;
        (qx[j], qy[j]) = (q[j].x, q[j].y);
        (ex[j], ey[j]) = (q[k].x - q[j].x, q[k].y - q[j].y);
    }
    let mut s = [[0.0; 4]; 4];
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_loadu_pd, _mm_mul_pd, _mm_set1_pd, _mm_storeu_pd, _mm_sub_pd};
        // SAFETY: SSE2 is part of x86_64; each load and store is two
        // entries at 0 or 2 of a local [f64; 4]
        unsafe {
            let half = |a: &[f64; 4], h: usize| _mm_loadu_pd(a.as_ptr().add(2 * h));
            let lanes = [0, 1].map(|h| (half(&qx, h), half(&qy, h), half(&ex, h), half(&ey, h)));
            for (si, pi) in s.iter_mut().zip(p) {
                let (px, py) = (_mm_set1_pd(pi.x), _mm_set1_pd(pi.y));
                for (h, &(qx, qy, ex, ey)) in lanes.iter().enumerate() {
                    let a = _mm_mul_pd(ex, _mm_sub_pd(py, qy));
                    let b = _mm_mul_pd(ey, _mm_sub_pd(px, qx));
                    _mm_storeu_pd(si.as_mut_ptr().add(2 * h), _mm_sub_pd(a, b));
                }
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    for (si, pi) in s.iter_mut().zip(p) {
        for j in 0..4 {
            si[j] = ex[j] * (pi.y - qy[j]) - ey[j] * (pi.x - qx[j]);
        }
    }
    s
}

/// Whether a point whose sides to a quadrilateral's edges are `s` lies in
/// it: every side of one sign, zeros ignored, taken in parry's order (the
/// last edge first).
fn inside(s: &[f64; 4]) -> bool {
    let mut sign = s[3];
    for &new in &s[..3] {
        if sign == 0.0 {
            sign = new;
        } else if sign * new < 0.0 {
            return false;
        }
    }
    true
}

/// The contact manifold of box `ha` and box `hb` at `a_M_b` = (`r`, `t`)
/// (half extents; b's pose in a's frame): its points (a's as `local_p1`,
/// b's as `local_p2`, every one of the clip, as parry keeps them, also those
/// beyond `margin`) and normals (`local_n1` from a toward b, `local_n2` its
/// opposite in b's frame) written into `man`. False when an axis separates
/// them by more than `margin`: `man` then holds no point and `local_n1` is
/// that axis.
pub(crate) fn box_box(
    ha: &Vector3<f64>,
    hb: &Vector3<f64>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    margin: f64,
    man: &mut ContactManifold<(), ()>,
) -> bool {
    man.points.clear();
    // a's faces, then b's (b at (Rᵀ, −Rᵀt) in a), then the edge pairs;
    // the first beyond the margin separates them
    let sep1 = face_separation(ha, hb, r, t);
    if sep1.0 > margin {
        man.local_n1 = to_pvec(&sep1.1);
        return false;
    }
    let rt = r.transpose();
    let t21 = -(rt * t);
    let sep2 = face_separation(hb, ha, &rt, &t21);
    if sep2.0 > margin {
        man.local_n1 = to_pvec(&(r * (-sep2.1)));
        return false;
    }
    let sep3 = edge_separation(ha, hb, r, t);
    if sep3.0 > margin {
        man.local_n1 = to_pvec(&sep3.1);
        return false;
    }
    // the least overlap: a's face, b's face (its normal turned into a's
    // frame, from a toward b), an edge pair only when strictly beyond a's
    let n1 = if sep2.0 > sep1.0 && sep2.0 > sep3.0 {
        r * (-sep2.1)
    } else if sep3.0 > sep1.0 {
        sep3.1
    } else {
        sep1.1
    };
    let n2 = rt * (-n1);
    let f1 = support_face(ha, &n1);
    let f2 = support_face(hb, &n2);
    clip_faces(r, t, &n1, &f1, &f2, man);
    man.local_n1 = to_pvec(&n1);
    man.local_n2 = to_pvec(&n2);
    true
}

/// The points of faces `f1` (a's) and `f2` (b's, at (`r`, `t`)) along `n`
/// (a's frame, from a toward b), parry's `contacts_face_face`: each face's
/// corners inside the other's outline (both projected on the plane ⟂ n),
/// with their gap along n to the other face's plane, and the crossings of
/// the two outlines' edges.
fn clip_faces(
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    n: &Vector3<f64>,
    f1: &Face,
    f2: &Face,
    man: &mut ContactManifold<(), ()>,
) {
    let [u, w] = basis(n);
    let flat = |p: &Vector3<f64>| Vector2::new(p.dot(&u), p.dot(&w));
    let v2: [Vector3<f64>; 4] = f2.v.map(|p| r * p + t);
    let q1 = f1.v.map(|p| flat(&p));
    let q2 = v2.map(|p| flat(&p));
    // each face's corners against the other's edges (inside tests and
    // crossings share them)
    let s12 = sides(&q2, &q1);
    let s21 = sides(&q1, &q2);
    // b's point x (a's frame) in b's frame: Rᵀ(x − t)
    let to_b = |x: Vector3<f64>| r.tr_mul(&(x - t));
    let mut push = |p1: Vector3<f64>, p2_1: Vector3<f64>, fid1: u32, fid2: u32, dist: f64| {
        man.points.push(TrackedContact::new(
            to_pvec(&p1),
            to_pvec(&to_b(p2_1)),
            PackedFeatureId(fid1),
            PackedFeatureId(fid2),
            dist,
        ));
    };
    // a's corners over b's face: gap to its plane, (v₂ − p)·m / (m·n)
    let m2 = (v2[2] - v2[1]).cross(&(v2[0] - v2[1]));
    let den2 = m2.dot(n);
    if den2.abs() > f64::EPSILON {
        for i in 0..4 {
            if inside(&s12[i]) {
                let dist = (v2[0] - f1.v[i]).dot(&m2) / den2;
                push(f1.v[i], f1.v[i] + n * dist, f1.vids[i], f2.fid, dist);
            }
        }
    }
    // b's corners over a's face: gap (v₁ − p)·m / (−m·n)
    let m1 = (f1.v[2] - f1.v[1]).cross(&(f1.v[0] - f1.v[1]));
    let den1 = -m1.dot(n);
    if den1.abs() > f64::EPSILON {
        for i in 0..4 {
            if inside(&s21[i]) {
                let dist = (f1.v[0] - v2[i]).dot(&m1) / den1;
                push(v2[i] - n * dist, v2[i], f1.fid, f2.vids[i], dist);
            }
        }
    }
    // the outlines' edge crossings: gap (x₂ − x₁)·n; only edges whose ends
    // lie strictly on either side of the other's line can cross within
    // both (others: parry's fractions fall outside (0, 1), or, a corner on
    // a line to rounding, at a point already found)
    // (bit 4j + i: b's edge j and a's edge i straddle each other's lines,
    // the tests in lanes; then the pairs in that order, j then i)
    let mut straddle = 0u32;
    for j in 0..4 {
        let j1 = (j + 1) % 4;
        for i in 0..4 {
            let i1 = (i + 1) % 4;
            let b_on = s21[j][i] * s21[j1][i] < 0.0;
            let a_on = s12[i][j] * s12[i1][j] < 0.0;
            straddle |= u32::from(b_on & a_on) << (4 * j + i);
        }
    }
    while straddle != 0 {
        let bit = straddle.trailing_zeros() as usize;
        straddle &= straddle - 1;
        let (j, i) = (bit / 4, bit % 4);
        let (j1, i1) = ((j + 1) % 4, (i + 1) % 4);
        if let Some((s, k)) = cross_lines([q1[i], q1[i1]], [q2[j], q2[j1]]) {
            if s > 0.0 && s < 1.0 && k > 0.0 && k < 1.0 {
                let x1 = f1.v[i] * (1.0 - s) + f1.v[i1] * s;
                let x2 = v2[j] * (1.0 - k) + v2[j1] * k;
                let dist = (x2 - x1).dot(n);
                push(x1, x2, f1.eids[i], f2.eids[j], dist);
            }
        }
    }
}

/// parry's `try_update_contacts_eps` at b's pose (`r`, `t`) in a's frame: when
/// the normals have turned less than `cos` and no point has slid more than
/// √`slide2` along a's face (nor crossed between touching and apart), the
/// points stand and their gaps are measured anew (true).
pub(crate) fn reuse(
    man: &mut ContactManifold<(), ()>,
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
    cos: f64,
    slide2: f64,
) -> bool {
    if man.points.is_empty() {
        return false;
    }
    let n1 = from_pvec(man.local_n1);
    let n2 = r * from_pvec(man.local_n2);
    if -n1.dot(&n2) < cos {
        return false;
    }
    // (the gaps the test measures are the new ones: kept, not measured
    // again, for the first `KEPT`, a box pair's most points)
    let mut gaps = [0.0; KEPT];
    for (k, c) in man.points.iter().enumerate() {
        // p₂ in a's frame; its gap along n₁; the foot p₂ − gap·n₁ near p₁
        let p2 = r * from_pvec(c.local_p2) + t;
        let p1 = from_pvec(c.local_p1);
        let dist = (p2 - p1).dot(&n1);
        if dist * c.dist < 0.0 {
            return false;
        }
        if (p1 - (p2 - n1 * dist)).norm_squared() > slide2 {
            return false;
        }
        if let Some(g) = gaps.get_mut(k) {
            *g = dist;
        }
    }
    for (k, c) in man.points.iter_mut().enumerate() {
        c.dist = match gaps.get(k) {
            Some(&g) => g,
            None => (r * from_pvec(c.local_p2) + t - from_pvec(c.local_p1)).dot(&n1),
        };
    }
    true
}

/// The most points [`reuse`] keeps its gaps of (a box pair's clip finds at
/// most 16: each face's four corners and eight edge crossings).
const KEPT: usize = 16;
