//! The tests of `src/contact/narrow/cylinder/apart.rs`: a cylinder apart
//! from a box's edge or corner, its distance and closest points in closed
//! form against the exact answer of the construction and parry's GJK
//! (`query::contact`) on random poses, and the pairs' manifolds with the
//! closed form against parry's dispatcher.

use crate::common::lcg::Lcg;
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::query::gjk::GJKResult;
use parry3d_f64::query::{self, ContactManifold, ContactManifoldsWorkspace};
use parry3d_f64::shape::{Cylinder, SharedShape};
use urdyn::nalgebra::{Rotation3, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{cylinder_box_apart, pair_shape, to_pose};

use super::contact_cylinder_pfm::{both, unit};
use super::contact_cylinder_rim::cases;

type Man = ContactManifold<(), ()>;

/// A random point q on a random edge or corner of the box of half extents
/// `e` and a direction n strictly inside that feature's normal cone (out
/// of the box): the box's support point along n is q alone.
fn on_feature(g: &mut Lcg, e: PVec) -> (PVec, PVec) {
    let mut sign = || {
        if g.uniform(-1.0, 1.0) < 0.0 {
            -1.0
        } else {
            1.0
        }
    };
    let sg = PVec::new(sign(), sign(), sign());
    if g.uniform(0.0, 3.0) < 1.0 {
        // a corner
        let w = PVec::new(
            g.uniform(0.02, 1.0),
            g.uniform(0.02, 1.0),
            g.uniform(0.02, 1.0),
        );
        return (sg * e, (sg * w).normalize());
    }
    let i = (g.uniform(0.0, 3.0) as usize).min(2);
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let phi = g.uniform(0.01, std::f64::consts::FRAC_PI_2 - 0.01);
    let mut q = sg * e;
    q[i] = g.uniform(-e[i], e[i]);
    let mut n = PVec::ZERO;
    n[j] = phi.cos() * sg[j];
    n[k] = phi.sin() * sg[k];
    (q, n)
}

/// A pose (the cylinder's frame in the box's) whose cylinder lies `gap`
/// beyond a random edge point or corner q of the box along n (its support
/// point along −n at q + gap n): the distance is `gap`, its points q and
/// q + gap n. Returns (pose, q, n).
fn apart_pose(g: &mut Lcg, cyl: &Cylinder, e: PVec, gap: f64) -> (Pose, PVec, PVec) {
    let rot = Rotation3::from_axis_angle(&unit(g), g.uniform(-3.2, 3.2));
    let (q, n) = on_feature(g, e);
    let nv = Vector3::new(n.x, n.y, n.z);
    let u = rot.matrix().column(1).into_owned();
    let nu = nv.dot(&u);
    let w = (nv - u * nu).normalize();
    // the cylinder's least point along n: the cap against n, the rim's
    // point opposite n's part across the axis
    let support = -u * cyl.half_height.copysign(nu) - w * cyl.radius;
    let at = Vector3::new(q.x, q.y, q.z) + nv * gap - support;
    (to_pose(&Se3::new(*rot.matrix(), at)), q, n)
}

#[test]
fn apart_matches_construction_and_gjk() {
    let max_dist = 0.02;
    for (case, (cyl, cub)) in cases().iter().enumerate() {
        let mut g = Lcg(71 + case as u64);
        let tries = 1000;
        let (mut taken, mut beyond) = (0, 0);
        let (mut dd, mut dp, mut dn) = (0.0f64, 0.0f64, 0.0f64);
        let (mut gd, mut gp, mut gn) = (0.0f64, 0.0f64, 0.0f64);
        for t in 0..tries {
            let gap = 10f64.powf(g.uniform(-6.5, -1.5));
            let (b_m_c, q, n) = apart_pose(&mut g, cyl, cub.half_extents, gap);
            let cyl_first = t % 2 == 0;
            let pos12 = if cyl_first { b_m_c.inverse() } else { b_m_c };
            let Some(found) = cylinder_box_apart(cyl, cub, &pos12, cyl_first, max_dist) else {
                continue;
            };
            // in the box's frame: (the cylinder's point, the box's, n out
            // of the box)
            let (pc, pb, nb) = match found {
                GJKResult::ClosestPoints(p1, p2, m) if cyl_first => (
                    b_m_c.transform_point(p1),
                    b_m_c.transform_point(p2),
                    b_m_c.rotation * -m,
                ),
                GJKResult::ClosestPoints(p1, p2, m) => (p2, p1, m),
                GJKResult::NoIntersection(_) => {
                    assert!(gap > max_dist - 1e-9, "try {t}: beyond at gap {gap}");
                    beyond += 1;
                    continue;
                }
                other => panic!("try {t}: {other:?}"),
            };
            assert!(gap <= max_dist + 1e-9, "try {t}: taken at gap {gap}");
            taken += 1;
            dd = dd.max(((pc - pb).length() - gap).abs());
            dp = dp.max((pb - q).length()).max((pc - (q + n * gap)).length());
            dn = dn.max((nb - n).length());
            assert!(
                ((pc - pb).length() - gap).abs() < 1e-12
                    && (pb - q).length() < 1e-10
                    && (pc - (q + n * gap)).length() < 1e-10
                    && (nb - n).length() < 1e-6,
                "try {t}: gap {gap}, ({pc:?}, {pb:?}, {nb:?}) against ({:?}, {q:?}, {n:?})",
                q + n * gap
            );
            // parry's GJK from scratch
            // (None at the smallest gaps: GJK's stop finds them touching)
            let Some(c) = query::contact(&b_m_c, cyl, &Pose::IDENTITY, cub, max_dist)
                .expect("parry takes a cylinder and a box")
            else {
                continue;
            };
            // parry's normal2 leaves the box toward the cylinder, as nb.
            // GJK stops on a curved rim short of the least: its distance
            // up to ~12× the true one at 1 µm (or under it, ~0.4×) and
            // its normal off by up to ~0.2 rad at tens of µm in these tries
            gd = gd.max((c.dist - gap).abs() / gap);
            gp = gp
                .max((c.point1 - pc).length())
                .max((c.point2 - pb).length());
            gn = gn.max((c.normal2 - nb).length());
            assert!(
                (c.dist - gap).abs() < 5e-5,
                "try {t}: gap {gap}, parry's {}",
                c.dist
            );
        }
        eprintln!(
            "case {case}: taken {taken}, beyond {beyond} of {tries}: against the construction \
             |Δdist| ≤ {dd:e}, |Δp| ≤ {dp:e}, |Δn| ≤ {dn:e}; against GJK |Δdist|/dist ≤ {gd:e}, \
             |Δp| ≤ {gp:e}, |Δn| ≤ {gn:e}"
        );
        assert!(
            taken + beyond >= tries * 99 / 100,
            "case {case}: only {taken} + {beyond} of {tries} taken"
        );
    }
}

/// The points as places (the midpoints of the pairs in a's frame, one
/// within 1 µm: parry's clip may give a point twice) and their gaps.
fn places(m: &Man, pos12: &Pose) -> Vec<(PVec, f64)> {
    let mut v: Vec<(PVec, f64)> = Vec::new();
    for p in &m.points {
        let x = (p.local_p1 + pos12.transform_point(p.local_p2)) * 0.5;
        if !v.iter().any(|(y, _)| (x - *y).length() < 1e-6) {
            v.push((x, p.dist));
        }
    }
    v
}

/// The manifolds of cylinder–box pairs (both orders) apart near an edge or
/// a corner within the margin (5 mm): ours (the closed forms on) against
/// parry's dispatcher, one call from scratch a pose, to GJK's error (its
/// normal off by up to ~2e-2 on a rim: the clipped points move with it,
/// and where it tips a clipped feature over (a box's edge for its face,
/// a cap's square for the side) the points are others: ~1 call in 4).
#[test]
fn apart_manifolds_match_parrys() {
    let shapes = [
        (
            SharedShape::cylinder(0.05, 0.05),
            SharedShape::cuboid(0.05, 0.05, 0.05),
        ),
        (
            SharedShape::cylinder(0.2, 0.03),
            SharedShape::cuboid(0.3, 0.05, 0.2),
        ),
    ];
    for (case, (c, b)) in shapes.iter().enumerate() {
        let cyl = pair_shape(c.clone(), Se3::identity(), true);
        let cub = pair_shape(b.clone(), Se3::identity(), true);
        let (cs, bs) = (c.as_cylinder().copied(), b.as_cuboid().copied());
        let (Some(cs), Some(bs)) = (cs, bs) else {
            panic!("shapes")
        };
        let mut g = Lcg(91 + case as u64);
        let (mut calls, mut matched) = (0, 0);
        let (mut dg, mut dn, mut dp) = (0.0f64, 0.0f64, 0.0f64);
        for t in 0..600 {
            let gap = 10f64.powf(g.uniform(-6.0, -2.4));
            let (b_m_c, _, _) = apart_pose(&mut g, &cs, bs.half_extents, gap);
            let cyl_first = t % 2 == 0;
            let (pos12, a, bb) = if cyl_first {
                (b_m_c.inverse(), &cyl, &cub)
            } else {
                (b_m_c, &cub, &cyl)
            };
            let mut ours: Vec<Man> = Vec::new();
            let mut theirs: Vec<Man> = Vec::new();
            let mut workspace: Option<ContactManifoldsWorkspace> = None;
            both(
                &pos12,
                (a, bb),
                (&mut ours, &mut theirs),
                &mut workspace,
                true,
            );
            calls += 1;
            let (m, n) = (&ours[0], &theirs[0]);
            let (pm, pn) = (places(m, &pos12), places(n, &pos12));
            // the same places to GJK's error (module doc of the test above):
            // the normals to 2e-2, each place within 1 mm and its gap
            // within 0.5 mm of one of parry's, and ours as deep or deeper
            // (GJK's distance an upper bound)
            let dnor = (m.local_n1 - n.local_n1).length();
            let mut worst = (0.0f64, 0.0f64);
            let found = pm.iter().all(|(x, d)| {
                let near = pn
                    .iter()
                    .map(|(y, e)| ((*x - *y).length(), (d - e).abs()))
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some(w) = near {
                    worst = (worst.0.max(w.0), worst.1.max(w.1));
                }
                near.is_some_and(|w| w.0 < 1e-3 && w.1 < 5e-4)
            });
            let deepest = |v: &[(PVec, f64)]| v.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let close = dnor < 2e-2
                && pm.len() == pn.len()
                && found
                && deepest(&pm) <= deepest(&pn) + 1e-12;
            if close {
                matched += 1;
                dn = dn.max(dnor);
                dp = dp.max(worst.0);
                dg = dg.max(worst.1);
            } else if calls - matched < 4 {
                eprintln!("try {t} (gap {gap}): ours {m:?}\ntheirs {n:?}\n");
            }
        }
        eprintln!(
            "case {case}: {matched} of {calls} calls match parry's (|Δn| ≤ {dn:e}, |Δplace| ≤ {dp:e}, |Δgap| ≤ {dg:e})"
        );
        assert!(
            matched * 100 >= calls * 70,
            "case {case}: {matched} of {calls} match"
        );
    }
}
