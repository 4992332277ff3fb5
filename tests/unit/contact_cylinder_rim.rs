//! The tests of `src/contact/narrow/cylinder/rim.rs`: a cylinder's rim on a
//! box's edge in closed form against parry's GJK + EPA (`query::contact`)
//! on random poses with a rim point near a box edge, and the cylinder pairs'
//! manifold with the closed form against parry's dispatcher.

use crate::common::lcg::Lcg;
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::query::{self, ContactManifold, ContactManifoldsWorkspace};
use parry3d_f64::shape::{Cuboid, Cylinder, SharedShape, SupportMap};
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{cylinder_rim_on_edge, pair_shape, to_pose};

use super::contact_cylinder_pfm::{both, unit};

type Man = ContactManifold<(), ()>;

/// A random point q on a random edge (along axis i) of the box of half
/// extents `e`, and n, a random direction of that edge's normal arc (in the
/// plane across the edge, between its two faces' normals) negated: n
/// points into the box. Returns (i, q, n); the draws in a fixed order.
fn on_edge(g: &mut Lcg, e: PVec) -> (usize, Vector3<f64>, Vector3<f64>) {
    let i = (g.uniform(0.0, 3.0) as usize).min(2);
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let mut sign = || {
        if g.uniform(-1.0, 1.0) < 0.0 {
            -1.0
        } else {
            1.0
        }
    };
    let (sj, sk) = (sign(), sign());
    let phi = g.uniform(0.0, std::f64::consts::FRAC_PI_2);
    let mut q = Vector3::zeros();
    q[i] = g.uniform(-e[i], e[i]);
    q[j] = sj * e[j];
    q[k] = sk * e[k];
    let mut n = Vector3::zeros();
    n[j] = -phi.cos() * sj;
    n[k] = -phi.sin() * sk;
    (i, q, n)
}

/// A pose (the cylinder's frame in the box's) with a rim point `depth` past
/// a random point of a random edge of the box along a random direction of
/// the edge's normal arc.
fn near_edge(g: &mut Lcg, cyl: &Cylinder, e: PVec, depth: f64) -> Se3<f64> {
    let mut rot = Rotation3::from_axis_angle(&unit(g), g.uniform(-3.2, 3.2));
    let (_, q, n) = on_edge(g, e);
    // a third with the cap nearly square to n (a cap pressed on the edge
    // near its rim: n within 0.1° of the axis)
    if g.uniform(0.0, 3.0) < 1.0 {
        let tilt = unit(g).into_inner() * g.uniform(0.0, 1.7e-3);
        let axis = Unit::new_normalize(-n + tilt - n * n.dot(&tilt));
        let spin = Rotation3::from_axis_angle(&Vector3::y_axis(), g.uniform(-3.2, 3.2));
        rot = Rotation3::rotation_between(&Vector3::y(), &axis).unwrap_or(spin) * spin;
    }
    let u = rot.matrix().column(1).into_owned();
    let nu = n.dot(&u);
    let w = (n - u * nu).normalize();
    let support = u * cyl.half_height.copysign(nu) + w * cyl.radius;
    Se3::new(*rot.matrix(), q + n * depth - support)
}

/// A pose (the cylinder's frame in the box's) with its side line crossing
/// a random edge of the box, `depth` past it along n = ±u × eᵢ (the
/// kink of the edge's normal arc), the axis at a random angle to the edge
/// (≥ 0.5°), the crossing at a random height of the side.
fn side_on_edge(g: &mut Lcg, cyl: &Cylinder, e: PVec, depth: f64) -> Se3<f64> {
    let (i, q, n) = on_edge(g, e);
    let mut ei = Vector3::zeros();
    ei[i] = 1.0;
    let psi = g.uniform(0.01, std::f64::consts::PI - 0.01);
    let u = ei * psi.cos() + n.cross(&ei) * psi.sin();
    let spin = Rotation3::from_axis_angle(&Vector3::y_axis(), g.uniform(-3.2, 3.2));
    let rot = Rotation3::rotation_between(&Vector3::y(), &u).unwrap_or(spin) * spin;
    let s = g.uniform(-0.9, 0.9) * cyl.half_height;
    Se3::new(*rot.matrix(), q + n * depth - n * cyl.radius - u * s)
}

/// How many of `tries` random poses from `pose` the closed form takes, and
/// how many of those are the side line's kink (n ⊥ the axis); each taken
/// one against parry's GJK + EPA from scratch: normal, depth and the pair
/// of points within EPA's tolerance.
fn against_epa(
    cyl: &Cylinder,
    cub: &Cuboid,
    seed: u64,
    tries: usize,
    pose: fn(&mut Lcg, &Cylinder, PVec, f64) -> Se3<f64>,
    side: bool,
) -> (usize, usize) {
    let mut g = Lcg(seed);
    let (mut taken, mut kinks) = (0, 0);
    let (mut dn, mut dd, mut dp, mut df) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for t in 0..tries {
        let depth = g.uniform(-2e-4, 2e-3);
        let b_m_c = to_pose(&pose(&mut g, cyl, cub.half_extents, depth));
        let Some((n, d, rim, edge)) = cylinder_rim_on_edge(cyl, cub, &b_m_c, side) else {
            continue;
        };
        taken += 1;
        let c = query::contact(&b_m_c, cyl, &Pose::IDENTITY, cub, 0.0)
            .expect("parry takes a cylinder and a box")
            .expect("parry finds the overlapping shapes in contact");
        // parry's normal1 leaves the cylinder toward the box, as ours. EPA's
        // depth is good to ~1e-10 here but its normal only to ~1e-4 (the
        // overlap is flat about its least: h(φ*) + ½h''Δφ², h'' ~ 1e-2 m):
        // the depths agree, ours is no deeper than the overlap along EPA's
        // normal (ours is the least), the normals and points roughly agree
        let along = |m: PVec| m.dot(cyl.support_point(&b_m_c, m)) + m.abs().dot(cub.half_extents);
        dn = dn.max((c.normal1 - n).length());
        dd = dd.max((-c.dist - d).abs());
        dp = dp
            .max((c.point1 - rim).length())
            .max((c.point2 - edge).length());
        assert!(
            d <= along(c.normal1) + 1e-12,
            "try {t}: ({n:?}, {d}) vs parry's ({:?}, {}): {} along it",
            c.normal1,
            -c.dist,
            along(c.normal1)
        );
        // and no sampled direction (300 within ~3° of ours, 300 anywhere)
        // has a smaller overlap: ours is the least, not only EPA's match
        let mut gs = Lcg(seed ^ (t as u64 + 1) << 20);
        for m in 0..600 {
            let v = unit(&mut gs).into_inner();
            let v = if m < 300 {
                n + PVec::new(v.x, v.y, v.z) * 0.05
            } else {
                PVec::new(v.x, v.y, v.z)
            };
            let v = v.normalize();
            assert!(
                along(v) >= d - 1e-12,
                "try {t}: ({n:?}, {d}), but {} along {v:?}",
                along(v)
            );
        }
        // EPA's depth: within its tolerance of ours, and (its polytope
        // inside C − B) not deeper; at the kink its stop leaves it up to
        // ~3e-6 short where the rim's is 1.5e-8 (a flat face of C − B
        // whose support points along n are a whole parallelogram)
        let tol = if side { 1e-5 } else { 1e-7 };
        assert!(
            (-c.dist - d).abs() < tol && -c.dist <= d + 1e-9,
            "try {t}: ({n:?}, {d}) vs parry's ({:?}, {})",
            c.normal1,
            -c.dist
        );
        // the closed form's pair: the rim point over the edge, depth apart
        assert!(((rim - edge).dot(n) - d).abs() < 1e-12 && (rim - edge - n * d).length() < 1e-12);
        // the points on their features: the cylinder's on its rim or
        // side, the box's on an edge, to 1 µm (the rim point's direction
        // across the axis, w = (n − u n·u)/√(1 − (n·u)²), loses its norm's
        // digits where the cap is near square to n: up to ~1e-16/(1 − (n·u)²)
        // relative, ≤ 3.3e-8 m off the rim seen here; the foot is off the
        // edge line by ~3e-11, Newton's φ)
        let pc = b_m_c.inverse_transform_point(rim);
        let radial = (pc.x * pc.x + pc.z * pc.z).sqrt();
        let off_rim = (pc.y.abs() - cyl.half_height).abs();
        let off_side = (radial - cyl.radius).abs();
        let in_cyl = (pc.y.abs() - cyl.half_height).max(radial - cyl.radius);
        let at_face = (edge.abs() - cub.half_extents).abs();
        let mut at = [at_face.x, at_face.y, at_face.z];
        at.sort_by(f64::total_cmp);
        let off_edge = at[1].max((edge.abs() - cub.half_extents).max_element());
        // a rim point on the cap's plane and the side, a kink's on the side
        let kink = n.dot(b_m_c.rotation * PVec::Y).abs() < 1e-9;
        kinks += kink as usize;
        let off = if kink {
            off_side
        } else {
            off_rim.max(off_side)
        };
        df = df.max(off.max(in_cyl)).max(off_edge);
        assert!(
            off < 1e-6 && in_cyl < 1e-6 && off_edge < 1e-6,
            "try {t}: {pc:?} (cylinder's frame) or {edge:?} (box's) off their features"
        );
        // EPA's points where its depth converged (to 1e-7): at the kink
        // with the side near parallel to the edge its pair slides along
        // the edge (a thin parallelogram face, its polytope short of it)
        if (-c.dist - d).abs() >= 1e-7 {
            continue;
        }
        assert!(
            (c.normal1 - n).length() < 1e-2
                && (c.point1 - rim).length() < 5e-4
                && (c.point2 - edge).length() < 5e-4,
            "try {t}: ({n:?}, {rim:?}, {edge:?}) vs parry's ({:?}, {:?}, {:?})",
            c.normal1,
            c.point1,
            c.point2
        );
    }
    eprintln!(
        "taken {taken} ({kinks} kinks) of {tries}: |Δn| ≤ {dn:e}, |Δdepth| ≤ {dd:e}, |Δp| ≤ {dp:e}, off features ≤ {df:e}"
    );
    (taken, kinks)
}

/// The four cylinder–box pairs the rim and side tests run on: a cube and a
/// long slab, each against a squat and a thin wide cylinder.
pub(super) fn cases() -> [(Cylinder, Cuboid); 4] {
    let cube = Cuboid::new(PVec::new(0.05, 0.05, 0.05));
    let slab = Cuboid::new(PVec::new(0.3, 0.05, 0.2));
    let cyl = Cylinder::new(0.05, 0.05);
    let thin = Cylinder::new(0.2, 0.03);
    [(cyl, cube), (thin, cube), (cyl, slab), (thin, slab)]
}

#[test]
fn rim_on_edge_matches_epa() {
    for (i, (c, b)) in cases().iter().enumerate() {
        let (taken, _) = against_epa(c, b, 11 + i as u64, 400, near_edge, false);
        assert!(taken >= 100, "case {i}: only {taken} of 400 taken");
    }
}

/// The side line on an edge (the kink of the edge's arc, n = ±u × eᵢ: a
/// parallelogram face of C − B) against EPA, as the rim above.
#[test]
fn side_on_edge_matches_epa() {
    for (i, (c, b)) in cases().iter().enumerate() {
        let (taken, kinks) = against_epa(c, b, 41 + i as u64, 400, side_on_edge, true);
        assert!(
            kinks >= 100,
            "case {i}: only {kinks} kinks of {taken} taken of 400"
        );
    }
}

/// The manifolds of cylinder–box pairs (both orders) along random paths,
/// parry's kept from call to call and ours started from a copy of it at
/// each call: where ours differs (the closed form took the call), the
/// same points (feature ids) and normal to EPA's tolerance, the gaps to
/// 1e-9, in all but the calls where a feature parry clips flips with the
/// normal's last digits (a box face's choice at 45°, a point on a clip's
/// boundary); returns (calls taken, calls matched).
pub(super) fn manifolds(
    a: &urdyn::testing::contact::PairShape,
    b: &urdyn::testing::contact::PairShape,
    seed: u64,
) -> (usize, usize) {
    let mut g = Lcg(seed);
    let (mut taken, mut matched) = (0, 0);
    for _ in 0..200 {
        let dir = unit(&mut g);
        let axis = unit(&mut g);
        let (angle, spin) = (g.uniform(-3.1, 3.1), g.uniform(-0.05, 0.05));
        let dist = 0.09 * g.uniform(0.8, 1.2);
        let mut theirs: Vec<Man> = Vec::new();
        let mut workspace: Option<ContactManifoldsWorkspace> = None;
        for k in 0..8 {
            let rot = Rotation3::from_axis_angle(&axis, angle + spin * k as f64);
            let pos12 = to_pose(&Se3::new(*rot.matrix(), dir.into_inner() * dist));
            for m in theirs.iter_mut() {
                m.points.clear();
            }
            let mut ours = theirs.clone();
            both(
                &pos12,
                (a, b),
                (&mut ours, &mut theirs),
                &mut workspace,
                true,
            );
            let (m, n) = (&ours[0], &theirs[0]);
            let bits = |v: PVec| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
            if bits(m.local_n1) == bits(n.local_n1) {
                continue;
            }
            taken += 1;
            // the points as places: the midpoints of the pairs in a's frame,
            // one within 1 µm (parry's clip may give a point twice or three
            // times: a cap's vertex on the face's edge, the crossing of that
            // edge there, GJK's point; which of them, and so the feature
            // ids, follows the normal's last digits, and EPA's copies lie
            // up to ~1e-8 apart)
            let places = |m: &Man| {
                let mut v: Vec<(PVec, f64)> = Vec::new();
                for p in &m.points {
                    let x = (p.local_p1 + pos12.transform_point(p.local_p2)) * 0.5;
                    if !v.iter().any(|(y, _)| (x - *y).length() < 1e-6) {
                        v.push((x, p.dist));
                    }
                }
                v
            };
            let (pm, pn) = (places(m), places(n));
            let deepest = |v: &[(PVec, f64)]| v.iter().map(|p| p.1).fold(0.0, f64::min);
            let close = (m.local_n1 - n.local_n1).length() < 1e-3
                && pm.len() == pn.len()
                && pm.iter().all(|(x, d)| {
                    pn.iter()
                        .any(|(y, e)| (*x - *y).length() < 1e-4 && (d - e).abs() < 1e-4)
                })
                && (deepest(&pm) - deepest(&pn)).abs() < 1e-9;
            if close {
                matched += 1;
            } else if taken - matched < 6 {
                eprintln!("ours {m:?}\ntheirs {n:?}\n");
            }
        }
    }
    (taken, matched)
}

#[test]
fn cylinder_box_manifolds_match_parrys() {
    let cyl = pair_shape(SharedShape::cylinder(0.05, 0.05), Se3::identity(), true);
    let cube = pair_shape(SharedShape::cuboid(0.05, 0.05, 0.05), Se3::identity(), true);
    for (i, (a, b)) in [(&cyl, &cube), (&cube, &cyl)].into_iter().enumerate() {
        let (taken, matched) = manifolds(a, b, 31 + i as u64);
        eprintln!("case {i}: {matched} of {taken} taken calls match parry's");
        assert!(taken >= 50, "case {i}: only {taken} calls taken");
        assert!(
            matched * 20 >= taken * 19,
            "case {i}: {matched} of {taken} match"
        );
    }
}
