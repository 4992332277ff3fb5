//! A cylinder on a box's face or on another cylinder's cap, and a box on a
//! cylinder's cap ([`boxed`]), in closed form, where the face's normal is
//! the exact contact normal: parry's GJK + EPA
//! and its polygonal features' clipping (`contact_manifold_pfm_pfm`) give
//! the same plane and points (up to EPA's tolerance) at ~40 k instructions
//! a pair.
//!
//! On a cylinder: the cap of the larger separation of the four (each's two
//! against the other), its region the cap's disc (the test below with the
//! distance from the axis), its polygon for the clipping parry's square of
//! the cap, its first vertex at the azimuth of GJK's point on it (here the
//! foot of the point that stands for the contact). On a box:
//!
//! The box's face is the one of its six with the largest separation of the
//! cylinder from its plane (the box's face axes of the separating-axis
//! test): n·c − h|n·u| − r√(1 − (n·u)²) − eᵢ for the cylinder's centre c,
//! axis u, half height h and radius r in the box's frame. A separation
//! beyond the margin is no contact. Within it, the face's normal n and depth
//! d = −separation are the exact contact when a deepest point p of the
//! cylinder lies over the face at least d from its edges (and d ≤ eᵢ): the
//! ball of radius d about p is then inside the box, so every direction
//! overlaps the two shapes by at least d, and n by exactly d (the face
//! path's test, `contact::face`; apart, p over the face is the closest
//! point). Where the deepest feature is level (a side, a cap) to within
//! [`LEVEL`], its point nearest the face's centre line stands for it: the
//! depth is then exact to `LEVEL`. Otherwise parry is asked.
//!
//! The points are parry's: the cylinder's support feature along −n (a cap,
//! |n·u| ≥ ½, as parry's `Cylinder::support_feature`: the square of four rim
//! points, its first at the rim's lowest azimuth, on a level cap along the
//! cylinder's x axis; a side: the segment of the side under the axis)
//! clipped against the face as parry's `PolygonalFeature::contacts`: the
//! feature's vertices over the face, the face's corners under the square,
//! the crossings of their edges. Each within the margin is a point at the
//! midpoint of the cylinder's point and its foot on the plane, its gap its
//! height above it. (parry adds GJK's deepest point: on a tilted feature
//! its deepest vertex again, not repeated here; on a level one a point of
//! it, here the point that stands for the contact, key code 7.)

use super::Raw;
use crate::spatial::Se3;
use nalgebra::Vector3;

pub(crate) mod apart;
mod boxed;
pub(crate) mod pfm;
pub(crate) mod rim;
pub(crate) mod side;
use boxed::box_feature;
pub(crate) use boxed::box_on_cap;

/// The key bit of a cylinder-on-face point (face index and feature code
/// below it): neither parry's features (bits 0–59), the closed-form round
/// pairs' (bit 61) nor the face path's (bit 62).
pub(crate) const CYL_KEY: u64 = 1 << 60;

/// How much shallower (m) than the deepest depth a point of a level side or
/// cap may be and stand for the deepest in the exactness test, and how level
/// (rise across the cap, m) a cap's square is laid along the cylinder's own
/// x axis: EPA's tolerance (~1e-7 m). At 1e-9 (to round 35) a box's edge
/// across a cylinder's cap with a rise of 1e-9 to 1e-7 m went to EPA (~1,300
/// calls in 2 s of the 256-object mixed pile, each ~65 k instructions).
pub(crate) const LEVEL: f64 = 1e-7;

/// The most points: a square clipped by a rectangle (an octagon).
pub(crate) const MAX_PTS: usize = 8;

/// Points: (the cylinder's point in the box's frame, its height above the
/// face's plane, key), and how many.
pub(crate) type Pts = ([(Vector3<f64>, f64, u64); MAX_PTS], usize);

/// What [`cylinder_on_box`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CylBox {
    /// Apart by more than the margin along the box's face normal (box
    /// frame, out of the box).
    Apart(Vector3<f64>),
    /// The plane contact: the points were written; the face's outward
    /// normal in the box's frame.
    Plane(Vector3<f64>),
    /// Not the exact contact here: ask parry.
    Other,
}

/// The face a cylinder is tested on, in its shape's frame: the plane
/// σxᵢ = `off` (outward normal σeᵢ) over a box's rectangle (half extents
/// along axes j = i + 1, k = i + 2) or a cap's disc (radius); `f` its key code.
#[derive(Clone, Copy, Debug)]
struct Face {
    i: usize,
    s: f64,
    off: f64,
    region: Region,
    f: u64,
}

#[derive(Clone, Copy, Debug)]
enum Region {
    Rect(f64, f64),
    Disc(f64),
}

/// Whether 2-D point `p` lies in the convex quadrilateral `poly` (either
/// turn; on its edges too).
fn inside(poly: &[(f64, f64); 4], p: (f64, f64)) -> bool {
    let side = |a: usize| {
        let (q0, q1) = (poly[a], poly[(a + 1) % 4]);
        (q1.0 - q0.0) * (p.1 - q0.1) - (q1.1 - q0.1) * (p.0 - q0.0)
    };
    let sides = [side(0), side(1), side(2), side(3)];
    sides.iter().all(|&x| x >= 0.0) || sides.iter().all(|&x| x <= 0.0)
}

/// The shape set on a [`Face`]: a cylinder (parry's: axis y, half height,
/// radius) or a box (half extents).
#[derive(Clone, Copy, Debug)]
enum Other {
    Cyl(f64, f64),
    Box(Vector3<f64>),
}

/// The other shape's support feature along −n (in the face's frame): its
/// deepest point `p0`, the point that stands for the contact, the feature's
/// vertices (`m` of them), its plane (normal, a point; for a polygon) and its
/// key code (bits 5–7).
struct Feature {
    p0: Vector3<f64>,
    stand: Vector3<f64>,
    vs: [Vector3<f64>; 4],
    m: usize,
    plane: (Vector3<f64>, Vector3<f64>),
    code: u64,
}

impl Face {
    /// Whether `p` lies over the region at least `depth` from its edges.
    fn over(&self, p: &Vector3<f64>, depth: f64) -> bool {
        let (j, k) = ((self.i + 1) % 3, (self.i + 2) % 3);
        match self.region {
            Region::Rect(ej, ek) => p[j].abs() + depth <= ej && p[k].abs() + depth <= ek,
            Region::Disc(rad) => p[j].hypot(p[k]) + depth <= rad,
        }
    }
}

/// A cylinder's [`Feature`] on `face` (outward normal `n`): the lower end of
/// the axis and the rim's lowest direction across it, −(n − (n·u)u) (a level
/// cap: the cylinder's x axis); the deepest point, else (a level side or
/// cap) its point nearest the face's centre line; parry's square on the
/// lower cap or the side's segment. None when no point stands for it.
fn cylinder_feature(
    (h, r): (f64, f64),
    q_m_c: &Se3<f64>,
    face: &Face,
    n: &Vector3<f64>,
    depth: f64,
) -> Option<Feature> {
    let (j, k) = ((face.i + 1) % 3, (face.i + 2) % 3);
    let c = q_m_c.trans;
    let u: Vector3<f64> = q_m_c.rot.column(1).into();
    let un = u.dot(n);
    let t0 = if un > 0.0 { -h } else { h };
    let w = u * un - n;
    let wl = w.norm();
    let w0: Vector3<f64> = if r * wl > LEVEL {
        w / wl
    } else {
        q_m_c.rot.column(0).into()
    };
    let p0 = c + u * t0 + w0 * r;
    let stand = if face.over(&p0, depth) {
        p0
    } else if 2.0 * h * un.abs() <= LEVEL {
        // a level side's lowest line
        let a = c + w0 * r;
        let uu = u[j] * u[j] + u[k] * u[k];
        let t = if uu > 0.0 {
            (-(a[j] * u[j] + a[k] * u[k]) / uu).clamp(-h, h)
        } else {
            0.0
        };
        a + u * t
    } else if 2.0 * r * wl <= LEVEL {
        // a level cap
        let cc = c + u * t0;
        let mut v = Vector3::zeros();
        v[j] = -cc[j];
        v[k] = -cc[k];
        let v = v - u * u.dot(&v);
        let vl = v.norm();
        cc + if vl > r { v * (r / vl) } else { v }
    } else {
        return None;
    };
    let cc = c + u * t0;
    if un.abs() >= 0.5 {
        let w1 = w0.cross(&u);
        Some(Feature {
            p0,
            stand,
            vs: [cc + w0 * r, cc + w1 * r, cc - w0 * r, cc - w1 * r],
            m: 4,
            plane: (u, cc),
            code: u64::from(t0 > 0.0),
        })
    } else {
        let foot = c + w0 * r;
        let z = Vector3::zeros();
        Some(Feature {
            p0,
            stand,
            vs: [foot - u * h, foot + u * h, z, z],
            m: 2,
            plane: (u, cc),
            code: 0,
        })
    }
}

/// The contact of `other` at `q_m_c` (its frame in the face's shape's) with
/// `face`, its separation from the face's plane `sep` (≤ margin): whether
/// the plane contact is the exact one (module doc); if so its points are
/// written to `out`.
fn on_face(
    other: Other,
    q_m_c: &Se3<f64>,
    face: Face,
    sep: f64,
    margin: f64,
    out: &mut Pts,
) -> bool {
    let Face {
        i,
        s,
        off,
        region,
        f,
    } = face;
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let mut n = Vector3::zeros();
    n[i] = s;
    let depth = (-sep).max(0.0);
    if depth > off {
        return false;
    }
    let feature = match other {
        Other::Cyl(h, r) => cylinder_feature((h, r), q_m_c, &face, &n, depth),
        Other::Box(e) => box_feature(&e, q_m_c, &face, &n, depth),
    };
    let Some(Feature {
        p0,
        stand,
        vs,
        m,
        plane: (pn, pc),
        code,
    }) = feature
    else {
        return false;
    };
    if !face.over(&stand, depth) {
        return false;
    }
    // the face's polygon in (j, k): the box's rectangle, or parry's square
    // on the cap, its first vertex at GJK's point's azimuth (the stand-in's
    // foot; on the axis, the x axis: (j, k) = (z, x) of a cylinder's frame)
    let poly = match region {
        Region::Rect(ej, ek) => [(ej, ek), (-ej, ek), (-ej, -ek), (ej, -ek)],
        Region::Disc(rad) => {
            let l = stand[j].hypot(stand[k]);
            let (dj, dk) = if l > 0.0 {
                (stand[j] / l * rad, stand[k] / l * rad)
            } else {
                (0.0, rad)
            };
            // parry's (x, z) = (dk, dj), then (−dj, dk), and their opposites
            [(dj, dk), (dk, -dj), (-dj, -dk), (-dk, dj)]
        }
    };
    let key0 = CYL_KEY | f << 8 | code << 5;
    let mut push = |v: Vector3<f64>, code: u64| {
        let gap = s * v[i] - off;
        if gap <= margin && out.1 < MAX_PTS {
            out.0[out.1] = (v, gap, key0 | code);
            out.1 += 1;
        }
    };
    // the feature's vertices over the face
    for (a, v) in vs[..m].iter().enumerate() {
        if inside(&poly, (v[j], v[k])) {
            push(*v, a as u64);
        }
    }
    // the face's corners under the feature's polygon, at its plane:
    // pn·(corner + g n − pc) = 0
    if m == 4 {
        let sq = [
            (vs[0][j], vs[0][k]),
            (vs[1][j], vs[1][k]),
            (vs[2][j], vs[2][k]),
            (vs[3][j], vs[3][k]),
        ];
        let pnn = pn.dot(&n);
        for (ci, &p) in poly.iter().enumerate() {
            if inside(&sq, p) {
                let mut q = Vector3::zeros();
                q[i] = s * off;
                q[j] = p.0;
                q[k] = p.1;
                let g = pn.dot(&(pc - q)) / pnn;
                push(q + n * g, 8 + ci as u64);
            }
        }
    }
    // the crossings of the feature's edges with the face's edges (a
    // segment's one edge once: parry finds it twice, the same point)
    let edges = if m == 4 { 4 } else { 1 };
    for a in 0..edges {
        let (p, q) = (vs[a], vs[(a + 1) % m]);
        let d = (q[j] - p[j], q[k] - p[k]);
        for ci in 0..4 {
            let (c0, c1) = (poly[ci], poly[(ci + 1) % 4]);
            let g = (c1.0 - c0.0, c1.1 - c0.1);
            let den = d.0 * g.1 - d.1 * g.0;
            if den == 0.0 {
                continue;
            }
            let a0 = (c0.0 - p[j], c0.1 - p[k]);
            let t = (a0.0 * g.1 - a0.1 * g.0) / den;
            let v = (a0.0 * d.1 - a0.1 * d.0) / den;
            if t > 0.0 && t < 1.0 && v > 0.0 && v < 1.0 {
                push(p + (q - p) * t, 16 + 4 * a as u64 + ci as u64);
            }
        }
    }
    // parry's GJK point: the point that stands for the contact when it is
    // not a vertex of the feature (a level feature's)
    if stand != p0 {
        push(stand, 7);
    }
    true
}

/// The contact of a cylinder (parry's: axis y, half height `h`, radius `r`)
/// at `b_m_c` (its frame in the box's) with a box of half extents `e`,
/// within `margin`: points written to `out`.
pub(crate) fn cylinder_on_box(
    h: f64,
    r: f64,
    e: &Vector3<f64>,
    b_m_c: &Se3<f64>,
    margin: f64,
    out: &mut Pts,
) -> CylBox {
    out.1 = 0;
    let c = b_m_c.trans;
    let u: Vector3<f64> = b_m_c.rot.column(1).into();
    // separation from face f (axis i, sign σ): σcᵢ − h|uᵢ| − r√(1 − uᵢ²) − eᵢ
    let mut best = (f64::NEG_INFINITY, 0usize);
    for f in 0..6 {
        let (i, s) = (f / 2, if f % 2 == 0 { 1.0 } else { -1.0 });
        let rp = r * (1.0 - u[i] * u[i]).max(0.0).sqrt();
        let sep = s * c[i] - h * u[i].abs() - rp - e[i];
        if sep > best.0 {
            best = (sep, f);
        }
    }
    let (sep, f) = best;
    let (i, s) = (f / 2, if f % 2 == 0 { 1.0 } else { -1.0 });
    let mut n = Vector3::zeros();
    n[i] = s;
    if sep > margin {
        return CylBox::Apart(n);
    }
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let face = Face {
        i,
        s,
        off: e[i],
        region: Region::Rect(e[j], e[k]),
        f: f as u64,
    };
    if on_face(Other::Cyl(h, r), b_m_c, face, sep, margin, out) {
        CylBox::Plane(n)
    } else {
        CylBox::Other
    }
}

/// The contact of cylinders a and b (parry's: axis y, (half height,
/// radius)), b at `a_m_b` in a's frame, where one's cap is the exact plane
/// of contact: the cap of the larger separation of the four (each's caps
/// against the other), then [`on_face`]. Points written to `out` in the
/// frame of the cap's cylinder, the normal in it; true when that is a.
pub(crate) fn cylinder_on_cylinder(
    ca: (f64, f64),
    cb: (f64, f64),
    a_m_b: &Se3<f64>,
    margin: f64,
    out: &mut Pts,
) -> (CylBox, bool) {
    out.1 = 0;
    let b_m_a = a_m_b.inverse();
    // q's separation from p's nearer cap: σc_y − h_p − h_q|u_y| − r_q√(1 − u_y²)
    let cap = |p: (f64, f64), q: (f64, f64), m: &Se3<f64>| {
        let uy = m.rot[(1, 1)];
        let s = if m.trans.y >= 0.0 { 1.0 } else { -1.0 };
        let rp = q.1 * (1.0 - uy * uy).max(0.0).sqrt();
        (s * m.trans.y - p.0 - q.0 * uy.abs() - rp, s)
    };
    let (sa, sga) = cap(ca, cb, a_m_b);
    let (sb, sgb) = cap(cb, ca, &b_m_a);
    let (on_a, sep, s, p, q, m) = if sa >= sb {
        (true, sa, sga, ca, cb, a_m_b)
    } else {
        (false, sb, sgb, cb, ca, &b_m_a)
    };
    let mut n = Vector3::zeros();
    n[1] = s;
    if sep > margin {
        return (CylBox::Apart(n), on_a);
    }
    let face = Face {
        i: 1,
        s,
        off: p.0,
        region: Region::Disc(p.1),
        f: 6 + 2 * u64::from(!on_a) + u64::from(s < 0.0),
    };
    if on_face(Other::Cyl(q.0, q.1), m, face, sep, margin, out) {
        (CylBox::Plane(n), on_a)
    } else {
        (CylBox::Other, on_a)
    }
}

/// The contact points of two cylinders (half height, radius) `a` at `wa`
/// and `b` at `wb` by [`cylinder_on_cylinder`], appended to `raw` with the
/// normal from b toward a; the pair's axis (a's frame, from a toward b)
/// returned, or None when the closed form does not apply.
pub(crate) fn cylinder_cylinder_points(
    ca: (f64, f64),
    cb: (f64, f64),
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
    raw: &mut Vec<Raw>,
) -> Option<Vector3<f64>> {
    let a_m_b = wa.inverse().compose(wb);
    let mut pts: Pts = ([(Vector3::zeros(), 0.0, 0); MAX_PTS], 0);
    let (found, on_a) = cylinder_on_cylinder(ca, cb, &a_m_b, margin, &mut pts);
    let n = match found {
        CylBox::Other => return None,
        CylBox::Apart(n) | CylBox::Plane(n) => n,
    };
    // the cap's normal points out of its cylinder toward the other
    let wp = if on_a { wa } else { wb };
    Some(push_plane_points(&pts, &n, wp, !on_a, wa, raw))
}

/// The contact points of `a` at `wa` and `b` at `wb` when one is a cylinder
/// (half height, radius) and the other a box (half extents), by
/// [`cylinder_on_box`], appended to `raw` with the normal from b toward a;
/// the direction from a toward b in a's frame (the pair's axis) returned,
/// or None when the closed form does not apply (the caller asks parry).
#[allow(clippy::too_many_arguments)]
pub(crate) fn cylinder_box_points(
    cyl: (f64, f64),
    e: &Vector3<f64>,
    cyl_is_a: bool,
    wa: &Se3<f64>,
    wb: &Se3<f64>,
    margin: f64,
    raw: &mut Vec<Raw>,
) -> Option<Vector3<f64>> {
    let (wc, wx) = if cyl_is_a { (wa, wb) } else { (wb, wa) };
    let x_m_c = wx.inverse().compose(wc);
    let mut pts: Pts = ([(Vector3::zeros(), 0.0, 0); MAX_PTS], 0);
    let n = match cylinder_on_box(cyl.0, cyl.1, e, &x_m_c, margin, &mut pts) {
        CylBox::Other => {
            // the box on the cylinder's cap: the cap's normal points from
            // the cylinder toward the box
            let n = match box_on_cap(cyl.0, cyl.1, e, &x_m_c.inverse(), margin, &mut pts) {
                CylBox::Other => return None,
                CylBox::Apart(n) | CylBox::Plane(n) => n,
            };
            return Some(push_plane_points(&pts, &n, wc, !cyl_is_a, wa, raw));
        }
        CylBox::Apart(n) | CylBox::Plane(n) => n,
    };
    // the face's normal points from the box toward the cylinder
    Some(push_plane_points(&pts, &n, wx, cyl_is_a, wa, raw))
}

/// The points `pts` found on a plane of normal `n` (the frame `wp` of the
/// plane's shape, out of it) appended to `raw` with the normal from b toward
/// a (`n` in the world if the plane's shape is b, else its opposite), each at
/// the midpoint of its vertex and the vertex's foot on the plane; returned:
/// the pair's axis, a's frame, from a toward b.
fn push_plane_points(
    pts: &Pts,
    n: &Vector3<f64>,
    wp: &Se3<f64>,
    plane_is_b: bool,
    wa: &Se3<f64>,
    raw: &mut Vec<Raw>,
) -> Vector3<f64> {
    let nw = wp.rot * n;
    let normal = if plane_is_b { nw } else { -nw };
    for &(v, gap, key) in &pts.0[..pts.1] {
        let p = v - n * (0.5 * gap);
        raw.push(Raw {
            point: wp.act_point(&p),
            normal,
            gap,
            key,
        });
    }
    wa.rot.transpose() * -normal
}
