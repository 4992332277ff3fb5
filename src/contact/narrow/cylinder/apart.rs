//! A cylinder and a box apart, their distance and closest points in closed
//! form where the box's nearest point lies on an edge or a vertex: the
//! pairs the face forms decline (a rim or side near a box's edge or
//! corner) and parry's `contact_manifold_pfm_pfm` sends to GJK only to
//! learn they are apart within the prediction (~26 k instructions a call).
//!
//! The distance of a point p from the solid cylinder (axis y, half height
//! h, radius r; its frame) is closed: its projection q clamps the height to
//! [−h, h] and the distance from the axis to r. Along a box edge
//! p(s) = a + s d, s ∈ [0, 1], f(s) = |p(s) − q(p(s))| is convex (the
//! distance to a convex set) and, outside the cylinder, differentiable with
//! f' = d·(p − q)/f (the distance's gradient is the unit vector from the
//! projection): its least is at an end where f' does not change sign, else
//! at the root of g(s) = d·(p − q), found by Newton kept inside the bracket
//! (g' = |d|² on a cap's region, (dₓ² + d_z²)(1 − r/ρ) + (dₓx + d_z z)² r/ρ³
//! on the side's, their sum on the rim's). An edge is skipped when the two
//! end tangents' lower bound on f (convexity: f ≥ each tangent) is not
//! below the best so far.
//!
//! The least over the box's 12 edges is the distance when the box's
//! nearest point is on an edge (the face forms take the faces' insides).
//! That is checked, not assumed: the pair p, q bounds the distance from
//! above (|p − q|) and the separation of the shapes along n = (p − q)/|p − q|
//! (the two support functions, closed) from below; the answer is taken only
//! when they agree to [`CERTIFY`]. Else (a box point inside the cylinder, a
//! face's inside nearest, the bounds apart) None: GJK's path.

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::gjk::GJKResult;
use parry3d_f64::shape::{Cuboid, Cylinder};

/// How far (m) the separation along the found normal may fall short of the
/// found points' distance for them to be taken: far below GJK's own
/// tolerance and above the rounding of either bound (~1e-16 m at the
/// piles' scale).
const CERTIFY: f64 = 1e-12;

/// The normal n = (p − q)/|p − q| carries p − q's error (the edge's
/// parameter to ~1e-15 of its length, the corners' rounding: ~1e-16 m) over
/// |p − q|, its separation that times the shapes' reach (up to ~0.6 m):
/// `CERTIFY_NORMAL`/|p − q| more (8.6e-11 m seen at 2.2 µm on a 0.6 m slab
/// in the tests; 1e-9 m allowed at 1 µm). Under [`MIN_GAP`] the pair is
/// left to GJK (touching).
const CERTIFY_NORMAL: f64 = 1e-15;
const MIN_GAP: f64 = 1e-7;

/// Newton's stop on an edge's parameter (a step below it), and its most
/// steps (bisection alone reaches 1e-15 in 50).
const STEP_TOL: f64 = 1e-15;
const MAX_STEPS: usize = 100;

/// The cylinder's projection of `p` (its frame): (q, p − q).
#[inline]
fn project(p: Vector, (h, r): (f64, f64)) -> (Vector, Vector) {
    let rho = p.x.hypot(p.z);
    let y = p.y.clamp(-h, h);
    let (x, z) = if rho > r {
        (p.x * (r / rho), p.z * (r / rho))
    } else {
        (p.x, p.z)
    };
    let q = Vector::new(x, y, z);
    (q, p - q)
}

/// g(s) = d·(p − q) at p and its slope g' (module doc).
#[inline]
fn slope(p: Vector, d: Vector, (h, r): (f64, f64)) -> (f64, f64) {
    let rho = p.x.hypot(p.z);
    let (mut g, mut g1) = (0.0, 0.0);
    if rho > r {
        let dx = d.x * p.x + d.z * p.z;
        let k = 1.0 - r / rho;
        g += dx * k;
        g1 += (d.x * d.x + d.z * d.z) * k + dx * dx * r / (rho * rho * rho);
    }
    if p.y > h {
        g += d.y * (p.y - h);
        g1 += d.y * d.y;
    } else if p.y < -h {
        g += d.y * (p.y + h);
        g1 += d.y * d.y;
    }
    (g, g1)
}

/// The least of f on the edge a + s d, s ∈ (0, 1), where f'(0) < 0 < f'(1),
/// from `s0`: the parameter s.
fn least_on_edge(a: Vector, d: Vector, hr: (f64, f64), s0: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut s = s0.clamp(0.0, 1.0);
    for _ in 0..MAX_STEPS {
        let (g, gp) = slope(a + d * s, d, hr);
        if g < 0.0 {
            lo = s;
        } else if g > 0.0 {
            hi = s;
        } else {
            return s;
        }
        // Newton inside the bracket, else its middle (near a small gap g
        // is a steep sigmoid: Newton's step from its flanks overshoots)
        let next = if gp > 0.0 { s - g / gp } else { f64::NAN };
        let next = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if (next - s).abs() <= STEP_TOL || hi - lo <= STEP_TOL {
            return next;
        }
        s = next;
    }
    s
}

/// The separation along unit `n` (cylinder's frame, from the cylinder
/// toward the box) of the cylinder (`hr`) and the box of half extents `e`
/// at `c_m_b` (its frame in the cylinder's): the box's least n·x less the
/// cylinder's most.
fn separation(n: Vector, c_m_b: &Pose, e: Vector, (h, r): (f64, f64)) -> f64 {
    let nb = c_m_b.rotation.inverse() * n;
    let low = n.dot(c_m_b.translation) - nb.abs().dot(e);
    let top = h * n.y.abs() + r * (1.0 - n.y * n.y).max(0.0).sqrt();
    low - top
}

/// The closest points of a cylinder and a box apart (module doc), the
/// cylinder's frame: (q on the cylinder, p on the box, distance), or None.
/// `c_m_b`: the box's frame in the cylinder's. The box's point as the
/// lerp of its edge's corners in the box's own frame too (`p_box`).
#[allow(clippy::type_complexity)]
fn closest(cyl: &Cylinder, cub: &Cuboid, c_m_b: &Pose) -> Option<(Vector, Vector, Vector, f64)> {
    let hr = (cyl.half_height, cyl.radius);
    let e = cub.half_extents;
    let corner = |v: usize| {
        Vector::new(
            if v & 1 == 0 { e.x } else { -e.x },
            if v & 2 == 0 { e.y } else { -e.y },
            if v & 4 == 0 { e.z } else { -e.z },
        )
    };
    // the corners, their projections and distances
    let mut ps = [Vector::ZERO; 8];
    let mut ws = [Vector::ZERO; 8];
    let mut fs = [0.0; 8];
    // the best: (distance, corner a, corner b, s)
    let mut best = (f64::INFINITY, 0usize, 0usize, 0.0f64);
    for v in 0..8 {
        let p = c_m_b.transform_point(corner(v));
        let (_, w) = project(p, hr);
        let f = w.length();
        if !(f > 0.0) {
            return None;
        }
        ps[v] = p;
        ws[v] = w;
        fs[v] = f;
        if f < best.0 {
            best = (f, v, v, 0.0);
        }
    }
    // the edges: corners v and v with bit l flipped
    for v in 0..8usize {
        for l in 0..3 {
            let b = v | 1 << l;
            if b == v {
                continue;
            }
            let d = ps[b] - ps[v];
            let (g0, g1) = (d.dot(ws[v]), d.dot(ws[b]));
            if !(g0 < 0.0 && g1 > 0.0) {
                continue;
            }
            // the end tangents f0 + s f0', f1 + (s − 1) f1' meet at s*
            let (f0, f1) = (fs[v], fs[b]);
            let (t0, t1) = (g0 / f0, g1 / f1);
            let s = (f1 - t1 - f0) / (t0 - t1);
            if f0 + s * t0 >= best.0 {
                continue;
            }
            let s = least_on_edge(ps[v], d, hr, s);
            let (_, w) = project(ps[v] + d * s, hr);
            let f = w.length();
            if !(f > 0.0) {
                return None;
            }
            if f < best.0 {
                best = (f, v, b, s);
            }
        }
    }
    let (f, v, b, s) = best;
    let p = ps[v] + (ps[b] - ps[v]) * s;
    let (q, w) = project(p, hr);
    let (cv, cb) = (corner(v), corner(b));
    let p_box = cv + (cb - cv) * s;
    // certified: the separation along n as the points' distance (n's
    // digits: p − q's rounding over f)
    let n = w / f;
    if !(f >= MIN_GAP && separation(n, c_m_b, e, hr) >= f - CERTIFY - CERTIFY_NORMAL / f) {
        return None;
    }
    Some((q, p, p_box, f))
}

/// The pair apart as GJK's answer to parry's `contact_manifold_pfm_pfm`
/// (`ClosestPoints` in shape 1's frame, the normal from shape 1 toward 2,
/// within `max_dist`; beyond it `NoIntersection` along that normal), the
/// cylinder shape 1 (`cyl_first`) or 2 of `pos12`; None: GJK's path.
pub fn as_gjk(
    cyl: &Cylinder,
    cub: &Cuboid,
    pos12: &Pose,
    cyl_first: bool,
    max_dist: f64,
) -> Option<GJKResult> {
    if cyl_first {
        let (q, p, _, f) = closest(cyl, cub, pos12)?;
        let n = (p - q) / f;
        if f > max_dist {
            return Some(GJKResult::NoIntersection(n));
        }
        Some(GJKResult::ClosestPoints(q, p, n))
    } else {
        let b_m_c = pos12;
        let c_m_b = b_m_c.inverse();
        let (q, p, p_box, f) = closest(cyl, cub, &c_m_b)?;
        let n = b_m_c.rotation * ((q - p) / f);
        if f > max_dist {
            return Some(GJKResult::NoIntersection(n));
        }
        Some(GJKResult::ClosestPoints(p_box, b_m_c.transform_point(q), n))
    }
}
