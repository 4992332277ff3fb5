//! The penetration of a cylinder and a box in closed form where it is a
//! cylinder's rim on a box's edge: the pairs the face forms decline, which
//! parry's `contact_manifold_pfm_pfm` sends to EPA (~100 k instructions a
//! call on the mixed piles).
//!
//! Both shapes convex, their penetration depth is the least overlap
//! h(n) = h_C(n) + h_B(−n) over the unit directions n (h_C the cylinder's
//! support function, h_B the box's: the Minkowski difference C − B's support
//! function, whose least value is the origin's distance to its boundary).
//! At the least n the nearest boundary
//! point of C − B is a smooth one (the ball of that radius about the origin
//! lies inside and touches there, so the support plane there is unique):
//! the pair of features meeting there has one common normal. For a cylinder
//! (caps, side lines, rim points) and a box (faces, edges, vertices) that
//! leaves, in the box's frame:
//!
//! - a box face's normal (six), a cap's normal (two);
//! - a side line on a box vertex: n radial from the axis through the vertex;
//! - a side line or a rim point on a box edge: n on the edge's normal arc,
//!   n = −(cos φ σⱼeⱼ + sin φ σₖeₖ), φ ∈ [0, π/2], where
//!   h(φ) = A cos φ + B sin φ + h|t| + r√(1 − t²), A = eⱼ − σⱼcⱼ,
//!   B = eₖ − σₖcₖ, t = σⱼuⱼ cos φ + σₖuₖ sin φ (c, u the cylinder's centre
//!   and axis, h, r its half height and radius): a side line at t = 0 (a
//!   kink), a rim point elsewhere (a stationary point, Newton on φ).
//!
//! Every h(n) evaluated is exact (an upper bound on the depth); the least of
//! all these candidates is the depth, its n the normal. An edge's arc is
//! skipped when its lower bound (the least of A cos φ + B sin φ on the arc,
//! plus the least of h|t| + r√(1 − t²), concave in |t|, at the ends of the
//! range of |t| on the arc) is not below the best so far. The
//! answer is taken only when the least is a rim point's stationary point
//! inside the arc with the rim point over the edge, or the kink (the side
//! line crossing the edge, seen along n = ±u × eᵢ: a parallelogram face of
//! C − B, `side_on_edge`), and that point lies in the box (the shapes
//! overlap: parry's GJK would find them so and run EPA); else None
//! (parry's path). The points are then parry's own: its
//! clip of the two support features at this normal
//! (`climb::clip_at_closest`), with the rim point and its foot on the edge
//! as EPA's pair.

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{Cuboid, Cylinder};

/// How far off the kink (|n·u|, a side line on the edge: no one rim point)
/// the rim's stationary point must lie to be taken.
pub(super) const OFF_SIDE: f64 = 1e-6;

/// How far off the cap's normal (1 − |n·u|): nearer, the rim point's
/// azimuth (n's part across the axis, normalised) loses its digits.
pub(super) const OFF_CAP: f64 = 1e-12;

/// The φ recorded for the kink (the side line on the edge): none of the
/// arc's, which lie in [0, π/2].
const KINK: f64 = -1.0;

/// |u × eᵢ| under which a side line on an edge is declined (a segment of
/// contact, the crossing ill-conditioned): ~0.06°.
const MIN_CROSS: f64 = 1e-3;

/// Whether the pairs take the side line on an edge in closed form
/// (`rim_on_edge`'s `side`): on. Built and tested against EPA in round 24
/// (tests/unit/contact_cylinder_rim.rs) and left off then (the 256-object
/// mixed pile slept later on that engine); on today's, mean awake over 10
/// perturbed copies of that pile is 217.58 off, 217.56 on, and the form
/// takes about half of the cylinder–box pairs EPA was asked for there.
const SIDE_ON_EDGE: bool = true;

/// The samples of each edge's arc before Newton: φ = mπ/32 (the overlap
/// on an arc may have two local leasts, ~30° apart in the tests).
pub(super) const SAMPLES: usize = 17;

/// (sin φ, cos φ) of the samples, φ = m (π/2)/16 (`f64::sin_cos` of those
/// φ, written out: no sine at each sample; bit for bit, so at π/4 the sine
/// is one ulp below `FRAC_1_SQRT_2`, which clippy's `approx_constant` flags).
#[allow(clippy::approx_constant)]
const SIN_COS: [(f64, f64); SAMPLES] = [
    (0.0, 1.0),
    (0.0980171403295606, 0.9951847266721969),
    (0.19509032201612825, 0.9807852804032304),
    (0.29028467725446233, 0.9569403357322088),
    (0.3826834323650898, 0.9238795325112867),
    (0.47139673682599764, 0.881921264348355),
    (0.5555702330196022, 0.8314696123025452),
    (0.6343932841636455, 0.773010453362737),
    (0.7071067811865475, 0.7071067811865476),
    (0.773010453362737, 0.6343932841636455),
    (0.8314696123025452, 0.5555702330196023),
    (0.8819212643483549, 0.4713967368259978),
    (0.9238795325112867, 0.38268343236508984),
    (0.9569403357322089, 0.29028467725446233),
    (0.9807852804032304, 0.19509032201612833),
    (0.9951847266721968, 0.09801714032956077),
    (1.0, 6.123233995736766e-17),
];

/// The rim-on-edge contact in the box's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RimEdge {
    /// From the cylinder into the box (unit).
    pub n: Vector,
    /// The penetration depth (≥ 0).
    pub depth: f64,
    /// The cylinder's deepest point along n: its rim's, or its side
    /// line's crossing of the edge (the kink).
    pub rim: Vector,
    /// Its foot on the box's edge: rim − depth n.
    pub edge: Vector,
}

/// The overlap along n of a cylinder (centre c, axis u, half height h,
/// radius r) and a box of half extents e at the origin (the box's frame).
#[inline]
fn overlap(n: Vector, c: Vector, u: Vector, (h, r): (f64, f64), e: Vector) -> f64 {
    let nu = n.dot(u);
    n.dot(c) + h * nu.abs() + r * (1.0 - nu * nu).max(0.0).sqrt() + n.abs().dot(e)
}

/// The value, slope and curvature of h(φ) (module doc) on an edge's arc.
#[inline]
fn arc(phi: f64, k: &[f64; 4], hr: (f64, f64)) -> (f64, f64, f64) {
    arc_at(phi.sin_cos(), k, hr)
}

/// [`arc`] at (sin φ, cos φ).
#[inline]
fn arc_at((s, c): (f64, f64), k: &[f64; 4], (h, r): (f64, f64)) -> (f64, f64, f64) {
    let [a, b, al, be] = *k;
    let t = al * c + be * s;
    let tp = -al * s + be * c;
    let ss = (1.0 - t * t).max(1e-300);
    let sq = ss.sqrt();
    let sg = if t >= 0.0 { 1.0 } else { -1.0 };
    let g = a * c + b * s + h * t.abs() + r * sq;
    let g1 = -a * s + b * c + h * sg * tp - r * t * tp / sq;
    let g2 =
        -a * c - b * s - h * t.abs() - r * ((tp * tp - t * t) / sq + t * t * tp * tp / (ss * sq));
    (g, g1, g2)
}

/// h(φ) and h'(φ) ([`arc_at`]) at each of the arc's samples ([`SIN_COS`]),
/// in one pass with no exit: the samples run in vector lanes (each lane the
/// same operations as [`arc_at`] alone, so the same values).
#[inline]
pub(super) fn at_samples(k: &[f64; 4], hr: (f64, f64)) -> ([f64; SAMPLES], [f64; SAMPLES]) {
    let (mut g, mut g1) = ([0.0; SAMPLES], [0.0; SAMPLES]);
    for (m, &sc) in SIN_COS.iter().enumerate() {
        (g[m], g1[m], _) = arc_at(sc, k, hr);
    }
    (g, g1)
}

/// The local least of h in the samples' interval (m − 1, m), where h' turns
/// from falling to rising ([`at_samples`]): Newton there ([`newton`]), as
/// (h(φ*), φ*, (sin φ*, cos φ*)).
#[inline]
pub(super) fn least_in(m: usize, k: &[f64; 4], hr: (f64, f64)) -> (f64, f64, (f64, f64)) {
    let step = std::f64::consts::FRAC_PI_2 / (SAMPLES - 1) as f64;
    let phi = m as f64 * step;
    let phi = newton(phi - step, phi, k, hr);
    let sc = phi.sin_cos();
    (arc_at(sc, k, hr).0, phi, sc)
}

/// The least of h|t| + r√(1 − t²) over the arc, t = α cos φ + β sin φ,
/// φ ∈ [0, π/2]: concave in |t|, so at an end of the range of |t|.
#[inline]
fn floor(al: f64, be: f64, (h, r): (f64, f64)) -> f64 {
    // t's range: the ends, and its extreme inside when α, β share a sign
    // (|(α, β)| only then: no hypot on the other arcs)
    let lo = if al <= 0.0 && be <= 0.0 {
        -al.hypot(be)
    } else {
        al.min(be)
    };
    let hi = if al >= 0.0 && be >= 0.0 {
        al.hypot(be)
    } else {
        al.max(be)
    };
    let (x0, x1) = if lo <= 0.0 && hi >= 0.0 {
        (0.0, hi.max(-lo))
    } else {
        (lo.abs().min(hi.abs()), lo.abs().max(hi.abs()))
    };
    let f = |x: f64| h * x + r * (1.0 - x * x).max(0.0).sqrt();
    f(x0).min(f(x1))
}

/// The least of h on [lo, hi] where h' < 0 at lo and > 0 at hi: Newton
/// kept inside the bracket, else bisection. Returns φ.
#[inline]
fn newton(mut lo: f64, mut hi: f64, k: &[f64; 4], hr: (f64, f64)) -> f64 {
    let mut phi = 0.5 * (lo + hi);
    for _ in 0..60 {
        let (_, g1, g2) = arc(phi, k, hr);
        if g1 < 0.0 {
            lo = phi;
        } else {
            hi = phi;
        }
        let step = if g2 > 0.0 { g1 / g2 } else { f64::NAN };
        let next = phi - step;
        let next = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if (next - phi).abs() <= 1e-15 || hi - lo <= 1e-15 {
            return next;
        }
        phi = next;
    }
    phi
}

/// The rim-on-edge contact of a cylinder `cyl` at `b_m_c` (its frame in the
/// box's) with a box `cub`, when that is the penetration (module doc); with
/// `side`, also the side line on an edge (the kink).
pub fn rim_on_edge(cyl: &Cylinder, cub: &Cuboid, b_m_c: &Pose, side: bool) -> Option<RimEdge> {
    let hr = (cyl.half_height, cyl.radius);
    let (h, r) = hr;
    let e = cub.half_extents;
    let c = b_m_c.translation;
    let u = b_m_c.rotation * Vector::Y;
    // faces, caps, side lines on vertices: the best so far
    let mut best = f64::INFINITY;
    for l in 0..3 {
        let mut n = Vector::ZERO;
        n[l] = 1.0;
        best = best
            .min(overlap(n, c, u, hr, e))
            .min(overlap(-n, c, u, hr, e));
    }
    best = best
        .min(overlap(u, c, u, hr, e))
        .min(overlap(-u, c, u, hr, e));
    for v in 0..8 {
        let corner = Vector::new(
            if v & 1 == 0 { e.x } else { -e.x },
            if v & 2 == 0 { e.y } else { -e.y },
            if v & 4 == 0 { e.z } else { -e.z },
        );
        let w = corner - c;
        let w = w - u * w.dot(u);
        if let Some(n) = w.try_normalize() {
            best = best.min(overlap(n, c, u, hr, e));
        }
    }
    // apart along one of these (GJK's case, no rim in the box)
    if best < 0.0 {
        return None;
    }
    // edges: along axis i at (σⱼeⱼ, σₖeₖ)
    // the least's (depth, axis, signs, φ, (sin φ, cos φ))
    let mut found: Option<(f64, usize, f64, f64, f64, (f64, f64))> = None;
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        for sg in 0..4 {
            let sj = if sg & 1 == 0 { 1.0 } else { -1.0 };
            let sk = if sg & 2 == 0 { 1.0 } else { -1.0 };
            let a = e[j] - sj * c[j];
            let b = e[k] - sk * c[k];
            let least = if a < 0.0 && b < 0.0 {
                -a.hypot(b)
            } else {
                a.min(b)
            };
            let (al, be) = (sj * u[j], sk * u[k]);
            if least + floor(al, be, hr) >= best {
                continue;
            }
            let kk = [a, b, al, be];
            // the samples, then Newton in each interval where h' turns
            // from falling to rising (each local least the samples part)
            let (g, g1) = at_samples(&kk, hr);
            for m in 0..SAMPLES {
                best = best.min(g[m]);
                // apart along a sample (best < 0): the answer is None
                // whatever follows (best only falls, and a found depth is
                // ≥ 0 only if it is the best), so the rest of the arcs is
                // not looked at
                if best < 0.0 {
                    return None;
                }
                if m > 0 && g1[m - 1] < 0.0 && g1[m] > 0.0 {
                    let (g, phi, sc) = least_in(m, &kk, hr);
                    if g <= best {
                        best = g;
                        found = Some((g, i, sj, sk, phi, sc));
                    }
                }
            }
            // the side line on the edge: the kink t = 0, inside the arc
            // when α, β have opposite signs (n = ±u × eᵢ; after the
            // samples: a tie goes to the kink, Newton's bisection there
            // would give it to a point beside it)
            if side && al * be < 0.0 {
                let q = al.hypot(be);
                let sc = (al.abs() / q, be.abs() / q);
                let g = a * sc.1 + b * sc.0 + r;
                if g <= best {
                    best = g;
                    found = Some((g, i, sj, sk, KINK, sc));
                }
            }
        }
    }
    let (depth, i, sj, sk, phi, (s, co)) = found?;
    if depth > best || !(depth >= 0.0) {
        return None;
    }
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let mut n = Vector::ZERO;
    n[j] = -co * sj;
    n[k] = -s * sk;
    if phi == KINK {
        return side_on_edge(n, depth, i, (sj * e[j], sk * e[k]), (c, u), hr, e);
    }
    if !(phi > 0.0 && phi < std::f64::consts::FRAC_PI_2) {
        return None;
    }
    let nu = n.dot(u);
    if !(nu.abs() > OFF_SIDE && nu.abs() < 1.0 - OFF_CAP) {
        return None;
    }
    let w = (n - u * nu) / (1.0 - nu * nu).sqrt();
    let rim = c + u * h.copysign(nu) + w * r;
    // over the edge and in the box: the shapes overlap
    if !(rim.abs().cmple(e).all()) {
        return None;
    }
    Some(RimEdge {
        n,
        depth,
        rim,
        edge: rim - n * depth,
    })
}

/// The contact of the cylinder's side line on the box's edge along axis
/// `i` through (eⱼ, eₖ) = `ejk`, at the kink's normal `n` (⊥ u and the
/// edge) and depth: the side line c + r n + s u and the edge E + x eᵢ
/// cross when seen along n, where (plane ⊥ n, spanned by u and eᵢ)
/// s = (dᵢuᵢ − d·u) / (1 − uᵢ²), x = dᵢ + s uᵢ, d = c + r n − E. None
/// when the crossing is off either segment, the side line is within
/// [`MIN_CROSS`] of parallel to the edge (a segment of contact, no one
/// crossing), or the side's point is outside the box.
fn side_on_edge(
    n: Vector,
    depth: f64,
    i: usize,
    ejk: (f64, f64),
    (c, u): (Vector, Vector),
    (h, r): (f64, f64),
    e: Vector,
) -> Option<RimEdge> {
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let across = 1.0 - u[i] * u[i];
    if !(across > MIN_CROSS * MIN_CROSS) {
        return None;
    }
    let mut corner = Vector::ZERO;
    corner[j] = ejk.0;
    corner[k] = ejk.1;
    let d = c + n * r - corner;
    let s = (d[i] * u[i] - d.dot(u)) / across;
    let x = d[i] + s * u[i];
    if !(s.abs() <= h && x.abs() <= e[i]) {
        return None;
    }
    let side = c + n * r + u * s;
    if !(side.abs().cmple(e).all()) {
        return None;
    }
    Some(RimEdge {
        n,
        depth,
        rim: side,
        edge: side - n * depth,
    })
}

/// [`rim_on_edge`] as EPA's answer to parry's `contact_manifold_pfm_pfm`
/// (points in shape 1's frame, the normal from shape 1 toward 2), the
/// cylinder shape 1 (`cyl_first`) or 2 of `pos12`.
pub fn as_epa(
    cyl: &Cylinder,
    cub: &Cuboid,
    pos12: &Pose,
    cyl_first: bool,
) -> Option<(Vector, Vector, Vector)> {
    if cyl_first {
        let b_m_c = pos12.inverse();
        let re = rim_on_edge(cyl, cub, &b_m_c, SIDE_ON_EDGE)?;
        Some((
            pos12.transform_point(re.rim),
            pos12.transform_point(re.edge),
            pos12.rotation * re.n,
        ))
    } else {
        let re = rim_on_edge(cyl, cub, pos12, SIDE_ON_EDGE)?;
        Some((re.edge, re.rim, -re.n))
    }
}
