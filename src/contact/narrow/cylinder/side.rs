//! The penetration of two cylinders in closed form where it is one's rim
//! in the other's side: the commonest cylinder pair that parry's
//! `contact_manifold_pfm_pfm` sends to EPA on the mixed piles (~70 k
//! instructions a call there).
//!
//! In B's frame (axis y, half height h_B, radius r_B), A's centre c and axis
//! u (half height h, radius r): for a unit m across B's axis, m(φ) =
//! cos φ d₀ + sin φ d₁ (d₀, d₁ ⊥ y), the overlap of the shapes along
//! n = −m (from A into B) is
//! h(φ) = r_B − m·c + h|t| + r√(1 − t²), t = m·u:
//! B's support along m is its side at r_B, A's along −m its rim point
//! p = c − h sgn(t) u + r w, w = (n − (n·u)u)/√(1 − t²). That is
//! `rim`'s arc function (A = −d₀·c, B = −d₁·c, α = d₀·u, β = d₁·u) plus
//! r_B: the same samples and Newton on the two quarters about the
//! direction from B's axis to c give a least φ*, depth d = h(φ*).
//!
//! Taken when p lies in B with the ball of radius d about it inside B
//! (its distance from B's axis ρ + d ≤ r_B, its height |p_y| + d ≤ h_B):
//! then A − B holds that ball about the origin (p ∈ A), so every direction
//! overlaps the shapes by at least d, and n by d: d is the penetration depth
//! and n its normal (the ball argument of `contact::face` and the cylinder
//! on a face), whatever the other features (rims, caps) do. The rim point
//! must be one (|n·u| off 0 and 1 as in `rim`). The points are then
//! parry's own, its clip of the two support features at n, with p and its
//! foot p − d n on B's side as EPA's pair.

use super::rim::{at_samples, least_in, RimEdge, OFF_CAP, OFF_SIDE, SAMPLES};
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::Cylinder;

/// How far (m) the ball about the rim point may reach past B's side for
/// the answer to be taken: the rounding of ρ + d (~1e-17 m at the piles'
/// scale), far below EPA's tolerance (~1e-7 m).
const BALL_SLACK: f64 = 1e-12;

/// The rim-in-side contact of cylinder `a` at `b_m_a` (its frame in b's)
/// with cylinder `b` (module doc), b's frame: n from a into b, the depth,
/// a's rim point and its foot on b's side (`edge`).
pub fn rim_in_side(a: &Cylinder, b: &Cylinder, b_m_a: &Pose) -> Option<RimEdge> {
    look(a, b, b_m_a).ok().flatten()
}

/// The shapes apart along a sampled direction (a negative overlap): no
/// penetration, neither way round.
struct Apart;

/// [`rim_in_side`], or [`Apart`] when a sample found the shapes apart.
fn look(a: &Cylinder, b: &Cylinder, b_m_a: &Pose) -> Result<Option<RimEdge>, Apart> {
    let hr = (a.half_height, a.radius);
    let c = b_m_a.translation;
    let u = b_m_a.rotation * Vector::Y;
    let rho_c = c.x.hypot(c.z);
    if !(rho_c > 0.0) {
        return Ok(None);
    }
    // m toward c across b's axis, and the quarters either side of it
    let (x0, z0) = (c.x / rho_c, c.z / rho_c);
    // the least's (depth, φ, (sin φ, cos φ), d₀, d₁)
    let mut found: Option<(f64, f64, (f64, f64), Vector, Vector)> = None;
    for (d0, d1) in [
        (Vector::new(z0, 0.0, -x0), Vector::new(x0, 0.0, z0)),
        (Vector::new(x0, 0.0, z0), Vector::new(-z0, 0.0, x0)),
    ] {
        let kk = [-d0.dot(c), -d1.dot(c), d0.dot(u), d1.dot(u)];
        let (g, g1) = at_samples(&kk, hr);
        for m in 1..SAMPLES {
            // apart along a sample: GJK's case
            if g[m - 1] + b.radius < 0.0 {
                return Err(Apart);
            }
            if g1[m - 1] < 0.0 && g1[m] > 0.0 {
                let (g, phi, sc) = least_in(m, &kk, hr);
                let depth = g + b.radius;
                if found.is_none_or(|f| depth < f.0) {
                    found = Some((depth, phi, sc, d0, d1));
                }
            }
        }
    }
    let Some((depth, phi, (s, co), d0, d1)) = found else {
        return Ok(None);
    };
    if !(depth > 0.0 && phi > 0.0 && phi < std::f64::consts::FRAC_PI_2) {
        return Ok(None);
    }
    // n = −m; the rim point p = c + h sgn(n·u) u + r w
    let n = -(d0 * co + d1 * s);
    let nu = n.dot(u);
    if !(nu.abs() > OFF_SIDE && nu.abs() < 1.0 - OFF_CAP) {
        return Ok(None);
    }
    let w = (n - u * nu) / (1.0 - nu * nu).sqrt();
    let rim = c + u * hr.0.copysign(nu) + w * hr.1;
    // the ball of radius d about p inside b
    let rho = rim.x.hypot(rim.z);
    if !(rho + depth <= b.radius + BALL_SLACK && rim.y.abs() + depth <= b.half_height) {
        return Ok(None);
    }
    Ok(Some(RimEdge {
        n,
        depth,
        rim,
        edge: rim - n * depth,
    }))
}

/// [`rim_in_side`] as EPA's answer to parry's `contact_manifold_pfm_pfm`
/// (points in shape 1's frame, the normal from shape 1 toward 2): shape 1's
/// rim in shape 2's side, else shape 2's in shape 1's (not looked for when
/// the first found the shapes apart).
pub fn as_epa(c1: &Cylinder, c2: &Cylinder, pos12: &Pose) -> Option<(Vector, Vector, Vector)> {
    if let Some(re) = look(c1, c2, &pos12.inverse()).ok()? {
        return Some((
            pos12.transform_point(re.rim),
            pos12.transform_point(re.edge),
            pos12.rotation * re.n,
        ));
    }
    let re = rim_in_side(c2, c1, pos12)?;
    Some((re.edge, re.rim, -re.n))
}
