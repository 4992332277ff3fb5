//! The tests of `src/contact/narrow/cylinder.rs`: the closed-form cylinder on
//! a box's face against parry's manifold of the pair
//! (`contact_manifold_pfm_pfm`: GJK + EPA, the support features clipped) on
//! random poses near contact. Where the closed form applies: the same normal
//! and deepest gap (to EPA's tolerance), and, where parry's features are
//! fixed by the pose (a side, a cap tilted off level; a level cap's square
//! turns with GJK's point), the same points; apart, parry finds no point
//! within the margin. The same for a cylinder on another's cap (parry's
//! cap is its square, turned to GJK's point), and for a box on a cylinder's
//! cap.

use crate::common::lcg::Lcg;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::details::contact_manifold_pfm_pfm;
use parry3d_f64::query::ContactManifold;
use parry3d_f64::shape::{Cuboid, Cylinder, PackedFeatureId, SupportMap};
use urdyn::nalgebra::{Rotation3, Unit, Vector3};
use urdyn::spatial::Se3;
use urdyn::testing::contact::{box_on_cap, cylinder_on_box, cylinder_on_cylinder, to_pose, to_v};

/// `src/contact/narrow/cylinder.rs`'s `LEVEL` (m): a feature rising at most
/// this across itself is level for the plane forms, so their depth is exact
/// to it, and their normal (the face's) may differ from the exact one (the
/// level feature's own face normal, where that is the least) by up to the
/// rise over the feature's width ([`level_tilt`]).
const LEVEL: f64 = 1e-7;

/// The most a feature of width at least `w` (m) that is level to [`LEVEL`]
/// tilts (rad).
fn level_tilt(w: f64) -> f64 {
    LEVEL / w
}

fn unit(g: &mut Lcg) -> Unit<Vector3<f64>> {
    Unit::new_normalize(Vector3::new(
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
        g.uniform(-1.0, 1.0),
    ))
}

/// A rotation near one with the cylinder's cap or side on face axis `i`
/// of the box, or anywhere, tilted by up to `tilt` rad and spun about its
/// axis.
fn rotation(g: &mut Lcg, i: usize, tilt: f64) -> Rotation3<f64> {
    let mut axis = Vector3::zeros();
    axis[(i + 1) % 3] = 1.0;
    let base = match g.uniform(0.0, 3.0) as usize {
        // the cylinder's y along face axis i: a cap on the face
        0 => Rotation3::rotation_between(&Vector3::y(), &{
            let mut a = Vector3::zeros();
            a[i] = 1.0;
            a
        })
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)),
        // its y across axis i: the side on the face
        1 => Rotation3::rotation_between(&Vector3::y(), &axis).unwrap_or_else(Rotation3::identity),
        _ => Rotation3::from_axis_angle(&unit(g), g.uniform(-3.1, 3.1)),
    };
    let spin = Rotation3::from_axis_angle(&Vector3::y_axis(), g.uniform(-3.1, 3.1));
    Rotation3::from_axis_angle(&unit(g), g.uniform(0.0, tilt)) * base * spin
}

#[derive(Default, Debug)]
struct Seen {
    declined: usize,
    apart: usize,
    plane: usize,
    touching: usize,
    sets: usize,
    /// Largest |Δnormal|, |Δdeepest gap|, Δ of a matched point's position
    /// and gap.
    dn: f64,
    dd: f64,
    dp: f64,
    dg: f64,
    /// Poses where EPA's depth is shallower than the exact one.
    epa: usize,
}

/// Whether `p` has a match (position within `tol`, gap within 1e-5) in `qs`
/// (a crossing of two edges at a shallow angle moves along them by the
/// normal's error over the angle: 4e-5 m seen for EPA's).
fn matched(p: &(Vector3<f64>, f64), qs: &[(Vector3<f64>, f64)], tol: f64, seen: &mut Seen) -> bool {
    let best = qs
        .iter()
        .min_by(|a, b| (a.0 - p.0).norm().total_cmp(&(b.0 - p.0).norm()));
    match best {
        Some(q) if (q.0 - p.0).norm() < tol && (q.1 - p.1).abs() < 1e-5 => {
            seen.dp = seen.dp.max((q.0 - p.0).norm());
            seen.dg = seen.dg.max((q.1 - p.1).abs());
            true
        }
        _ => false,
    }
}

/// Away from the margin's edge, each of parry's points (`theirs`: its GJK
/// stand-ins left out; `all`: every one) is one of ours and each of ours
/// (`pts`, without our level feature's stand-in for GJK's point, code 7) one
/// of parry's, by [`matched`] within 2e-4 m (`case` names the pose).
fn points_match(
    case: usize,
    theirs: &[(Vector3<f64>, f64)],
    all: &[(Vector3<f64>, f64)],
    pts: &[(Vector3<f64>, f64, u64)],
    margin: f64,
    seen: &mut Seen,
) {
    let ours: Vec<_> = pts
        .iter()
        .filter(|p| p.2 & 31 != 7)
        .map(|p| (p.0, p.1))
        .collect();
    for p in theirs.iter().filter(|p| p.1 < margin - 1e-6) {
        assert!(
            matched(p, &ours, 2e-4, seen),
            "case {case}: parry's {p:?} not in ours {ours:?}"
        );
    }
    for p in ours.iter().filter(|p| p.1 < margin - 1e-6) {
        assert!(
            matched(p, &all, 2e-4, seen),
            "case {case}: our {p:?} not in parry's {all:?}"
        );
    }
}

/// Compares one pose (`case` names it in failures).
fn compare(case: usize, (h, r): (f64, f64), e: &Vector3<f64>, b_m_c: &Se3<f64>, seen: &mut Seen) {
    let margin = 0.005;
    let ours = cylinder_on_box(h, r, e, b_m_c, margin);
    // parry: the box first, the cylinder second (pos12 = b_m_c)
    let bx = Cuboid::new(PVec::new(e.x, e.y, e.z));
    let cy = Cylinder::new(h, r);
    let mut man: ContactManifold<(), ()> = ContactManifold::new();
    contact_manifold_pfm_pfm(
        &to_pose(b_m_c),
        &bx,
        0.0,
        None,
        &cy,
        0.0,
        None,
        margin,
        &mut man,
    );
    // (the cylinder's point in the box's frame, gap) of parry's points
    // within the margin: the clipped features', and GJK's
    let point =
        |p: &parry3d_f64::query::TrackedContact<()>| (b_m_c.act_point(&to_v(p.local_p2)), p.dist);
    let gjk = |p: &&parry3d_f64::query::TrackedContact<()>| p.fid1 == PackedFeatureId::UNKNOWN;
    let near: Vec<_> = man.points.iter().filter(|p| p.dist <= margin).collect();
    let theirs: Vec<_> = near.iter().filter(|p| !gjk(p)).map(|p| point(p)).collect();
    let theirs_min = near.iter().map(|p| p.dist).fold(f64::INFINITY, f64::min);
    let Some((n, apart, pts)) = ours else {
        seen.declined += 1;
        return;
    };
    if apart {
        seen.apart += 1;
        assert!(
            theirs_min > margin - 1e-7,
            "case {case}: apart, parry {theirs_min}"
        );
        return;
    }
    seen.plane += 1;
    let deepest = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if near.is_empty() {
        // parry finds the shapes farther apart than the margin
        assert!(
            deepest > margin - 1e-7,
            "case {case}: parry none, ours {deepest}"
        );
        return;
    }
    seen.touching += 1;
    let m = to_v(man.local_n1);
    assert!(
        (m - n).norm() < 1e-6 + level_tilt(2.0 * h.min(r)),
        "case {case}: normal {n:?} vs parry's {m:?}"
    );
    assert!(
        (theirs_min - deepest).abs() < 1e-7 + LEVEL,
        "case {case}: deepest {deepest} vs parry's {theirs_min}"
    );
    seen.dn = seen.dn.max((m - n).norm());
    seen.dd = seen.dd.max((theirs_min - deepest).abs());
    // parry's features are the pose's own on a side or a tilted cap
    let u: Vector3<f64> = b_m_c.rot.column(1).into();
    let un = n.dot(&u).abs();
    let tilted = un < 0.45 || (un > 0.55 && r * (1.0 - un * un).sqrt() > 1e-3);
    if !tilted {
        return;
    }
    seen.sets += 1;
    let all: Vec<_> = near.iter().map(|p| point(p)).collect();
    points_match(case, &theirs, &all, &pts, margin, seen);
}

#[test]
fn random_cylinders_on_boxes_match_parrys_manifold() {
    let mut g = Lcg(11);
    let mut seen = Seen::default();
    for case in 0..20000 {
        // a third the pile's sizes (a 0.1 m box, a cylinder 0.1 m across
        // and long), else random
        let (e, h, r) = if case % 3 == 0 {
            (Vector3::new(0.05, 0.05, 0.05), 0.05, 0.05)
        } else {
            (
                Vector3::new(
                    g.uniform(0.05, 0.7),
                    g.uniform(0.05, 0.7),
                    g.uniform(0.05, 0.7),
                ),
                g.uniform(0.02, 0.1),
                g.uniform(0.02, 0.1),
            )
        };
        let i = (g.uniform(0.0, 3.0) as usize).min(2);
        let tilt = [0.0, 1e-3, 0.05, 0.5][case % 4];
        let rot = rotation(&mut g, i, tilt);
        let u: Vector3<f64> = rot.matrix().column(1).into();
        // over a random point of a face or past its edges, just above it
        // or in it
        let s = if g.uniform(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
        let mut c = Vector3::zeros();
        for l in 0..3 {
            let reach = e[l] + 0.5 * (h + r);
            c[l] = g.uniform(-reach, reach);
        }
        let rp = r * (1.0 - u[i] * u[i]).max(0.0).sqrt();
        c[i] = s * (e[i] + h * u[i].abs() + rp + g.uniform(-0.004, 0.008));
        compare(case, (h, r), &e, &Se3::new(*rot.matrix(), c), &mut seen);
    }
    eprintln!("{seen:?}");
    assert!(
        seen.plane > 8000 && seen.touching > 6000 && seen.sets > 3000 && seen.apart > 500,
        "{seen:?}"
    );
}

#[test]
fn resting_cylinders_on_boxes_match_parrys_deepest() {
    // the pile's cylinder standing and lying on its box, level, centred and
    // overhanging, resting within micrometres and in the margin
    let e = Vector3::new(0.05, 0.05, 0.05);
    let mut seen = Seen::default();
    // standing: the cylinder's y along the box's z; lying: along its y
    let standing = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
    let lying = Rotation3::identity();
    let spun = standing * Rotation3::from_axis_angle(&Vector3::y_axis(), 0.4);
    for (case, (rot, dx, dz)) in [
        (standing, 0.0, 0.0),
        (standing, 0.01, -2e-6),
        (standing, 0.03, 1e-3),
        (lying, 0.0, -3e-4),
        (lying, 0.02, 0.0),
        (spun, 0.0, -1e-4),
    ]
    .into_iter()
    .enumerate()
    {
        let u: Vector3<f64> = rot.matrix().column(1).into();
        let z = 0.05 + 0.05 * u.z.abs() + 0.05 * (1.0 - u.z * u.z).max(0.0).sqrt() + dz;
        let b_m_c = Se3::new(*rot.matrix(), Vector3::new(dx, 0.0, z));
        compare(case, (0.05, 0.05), &e, &b_m_c, &mut seen);
    }
    assert!(seen.touching >= 5 && seen.declined <= 1, "{seen:?}");
}

/// Compares cylinders `ca`, `cb` (half height, radius), b at `a_m_b`.
fn compare_pair(case: usize, ca: (f64, f64), cb: (f64, f64), a_m_b: &Se3<f64>, seen: &mut Seen) {
    let margin = 0.005;
    let ours = cylinder_on_cylinder(ca, cb, a_m_b, margin);
    let (cya, cyb) = (Cylinder::new(ca.0, ca.1), Cylinder::new(cb.0, cb.1));
    let mut man: ContactManifold<(), ()> = ContactManifold::new();
    contact_manifold_pfm_pfm(
        &to_pose(a_m_b),
        &cya,
        0.0,
        None,
        &cyb,
        0.0,
        None,
        margin,
        &mut man,
    );
    let near: Vec<_> = man.points.iter().filter(|p| p.dist <= margin).collect();
    let theirs_min = near.iter().map(|p| p.dist).fold(f64::INFINITY, f64::min);
    let Some((on_a, n, apart, pts)) = ours else {
        seen.declined += 1;
        return;
    };
    if apart {
        seen.apart += 1;
        assert!(
            theirs_min > margin - 1e-7,
            "case {case}: apart, parry {theirs_min}"
        );
        return;
    }
    seen.plane += 1;
    let deepest = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if near.is_empty() {
        assert!(
            deepest > margin - 1e-7,
            "case {case}: parry none, ours {deepest}"
        );
        return;
    }
    seen.touching += 1;
    // ours in the cap's cylinder's frame (p), out of it; parry's in a's, a
    // toward b; the other cylinder's (q's) points in p's frame
    let b_m_a = a_m_b.inverse();
    let (p_m_q, m) = if on_a {
        (*a_m_b, to_v(man.local_n1))
    } else {
        (b_m_a, -(b_m_a.rot * to_v(man.local_n1)))
    };
    let point = |t: &parry3d_f64::query::TrackedContact<()>| {
        let q = if on_a {
            a_m_b.act_point(&to_v(t.local_p2))
        } else {
            b_m_a.act_point(&to_v(t.local_p1))
        };
        (q, t.dist)
    };
    // q's level cap or side: its own face normal may be parry's
    let (hq, rq) = if on_a { cb } else { ca };
    assert!(
        (m - n).norm() < 1e-6 + level_tilt(2.0 * hq.min(rq)),
        "case {case}: normal {n:?} vs parry's {m:?}"
    );
    assert!(
        (theirs_min - deepest).abs() < 1e-7 + LEVEL,
        "case {case}: deepest {deepest} vs parry's {theirs_min}"
    );
    seen.dn = seen.dn.max((m - n).norm());
    seen.dd = seen.dd.max((theirs_min - deepest).abs());
    // the features are the pose's own: q's side or tilted cap, p's square
    // turned to a point off its axis
    // (a level side's GJK point, and so p's square, lies anywhere along it)
    let (hq, r) = (hq, rq);
    let u: Vector3<f64> = p_m_q.rot.column(1).into();
    let un = n.dot(&u).abs();
    let tilted =
        (un < 0.45 && 2.0 * hq * un > 1e-3) || (un > 0.55 && r * (1.0 - un * un).sqrt() > 1e-3);
    let deep = pts.iter().min_by(|a, b| a.1.total_cmp(&b.1)).map(|p| p.0);
    let off_axis = deep.is_some_and(|d| d.x.hypot(d.z) > 1e-3);
    if !tilted || !off_axis {
        return;
    }
    seen.sets += 1;
    let gjk = |t: &&parry3d_f64::query::TrackedContact<()>| t.fid1 == PackedFeatureId::UNKNOWN;
    let theirs: Vec<_> = near.iter().filter(|t| !gjk(t)).map(|t| point(t)).collect();
    let all: Vec<_> = near.iter().map(|t| point(t)).collect();
    points_match(case, &theirs, &all, &pts, margin, seen);
}

#[test]
fn random_cylinders_on_cylinders_match_parrys_manifold() {
    let mut g = Lcg(13);
    let mut seen = Seen::default();
    for case in 0..20000 {
        // a third the pile's cylinders, else random
        let (ca, cb) = if case % 3 == 0 {
            ((0.05, 0.05), (0.05, 0.05))
        } else {
            (
                (g.uniform(0.02, 0.1), g.uniform(0.02, 0.1)),
                (g.uniform(0.02, 0.1), g.uniform(0.02, 0.1)),
            )
        };
        // q on p's cap (p = a, or b every other case)
        let (p, q) = if case % 2 == 0 { (ca, cb) } else { (cb, ca) };
        let tilt = [0.0, 1e-3, 0.05, 0.5][(case / 2) % 4];
        let rot = rotation(&mut g, 1, tilt);
        let u: Vector3<f64> = rot.matrix().column(1).into();
        let s = if g.uniform(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
        let reach = p.1 + 0.5 * (q.0 + q.1);
        let mut c = Vector3::new(g.uniform(-reach, reach), 0.0, g.uniform(-reach, reach));
        let rp = q.1 * (1.0 - u.y * u.y).max(0.0).sqrt();
        c.y = s * (p.0 + q.0 * u.y.abs() + rp + g.uniform(-0.004, 0.008));
        let p_m_q = Se3::new(*rot.matrix(), c);
        let a_m_b = if case % 2 == 0 {
            p_m_q
        } else {
            p_m_q.inverse()
        };
        compare_pair(case, ca, cb, &a_m_b, &mut seen);
    }
    eprintln!("{seen:?}");
    assert!(
        seen.plane > 4000 && seen.touching > 4000 && seen.sets > 1500 && seen.apart > 500,
        "{seen:?}"
    );
}

/// Compares a box (half extents `e`) at `c_m_b` on the cap of a cylinder
/// (`h`, `r`) with parry's manifold (the cylinder first).
fn compare_cap(
    case: usize,
    (h, r): (f64, f64),
    e: &Vector3<f64>,
    c_m_b: &Se3<f64>,
    seen: &mut Seen,
) {
    let margin = 0.005;
    let ours = box_on_cap(h, r, e, c_m_b, margin);
    let cy = Cylinder::new(h, r);
    let bx = Cuboid::new(PVec::new(e.x, e.y, e.z));
    let mut man: ContactManifold<(), ()> = ContactManifold::new();
    contact_manifold_pfm_pfm(
        &to_pose(c_m_b),
        &cy,
        0.0,
        None,
        &bx,
        0.0,
        None,
        margin,
        &mut man,
    );
    // the box's point in the cylinder's frame, gap
    let point =
        |p: &parry3d_f64::query::TrackedContact<()>| (c_m_b.act_point(&to_v(p.local_p2)), p.dist);
    let gjk = |p: &&parry3d_f64::query::TrackedContact<()>| p.fid1 == PackedFeatureId::UNKNOWN;
    let near: Vec<_> = man.points.iter().filter(|p| p.dist <= margin).collect();
    let theirs_min = near.iter().map(|p| p.dist).fold(f64::INFINITY, f64::min);
    let Some((n, apart, pts)) = ours else {
        seen.declined += 1;
        return;
    };
    if apart {
        seen.apart += 1;
        assert!(
            theirs_min > margin - 1e-7,
            "case {case}: apart, parry {theirs_min}"
        );
        return;
    }
    seen.plane += 1;
    let deepest = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if near.is_empty() {
        assert!(
            deepest > margin - 1e-7,
            "case {case}: parry none, ours {deepest}"
        );
        return;
    }
    seen.touching += 1;
    let m = to_v(man.local_n1);
    assert!(
        (m - n).norm() < 1e-6 + level_tilt(2.0 * e.min()),
        "case {case}: normal {n:?} vs parry's {m:?}"
    );
    // the depth is the box's reach below the cap's plane along n (its
    // support point; a level feature's stand-in up to LEVEL above); EPA's may be shallower on a long box's near-level
    // edge (1e-5 m seen, its GJK point off the deepest corner, which then
    // lies outside parry's square): then ours must be the exact one
    let down = c_m_b.rot.transpose() * -n;
    let low = c_m_b.act_point(&to_v(
        bx.local_support_point(PVec::new(down.x, down.y, down.z)),
    ));
    let exact = n.dot(&low) - h;
    assert!(
        (exact - deepest).abs() < 2e-9 + LEVEL,
        "case {case}: deepest {deepest} vs the box's support {exact}"
    );
    if (theirs_min - deepest).abs() >= 1e-7 + LEVEL {
        assert!(
            theirs_min > deepest && theirs_min - deepest < 1e-4,
            "case {case}: deepest {deepest} vs parry's {theirs_min}"
        );
        seen.epa += 1;
        return;
    }
    seen.dn = seen.dn.max((m - n).norm());
    seen.dd = seen.dd.max((theirs_min - deepest).abs());
    // parry's features are the pose's own when a corner is deepest (no
    // level edge) off the cap's axis: the square turns to its foot
    let nb = c_m_b.rot.transpose() * n;
    let tilted = (0..3).all(|l| 2.0 * e[l] * nb[l].abs() > 1e-3);
    let deep = pts.iter().min_by(|a, b| a.1.total_cmp(&b.1)).map(|p| p.0);
    let off_axis = deep.is_some_and(|d| d.x.hypot(d.z) > 1e-3);
    if !tilted || !off_axis {
        return;
    }
    seen.sets += 1;
    let theirs: Vec<_> = near.iter().filter(|p| !gjk(p)).map(|p| point(p)).collect();
    let all: Vec<_> = near.iter().map(|p| point(p)).collect();
    points_match(case, &theirs, &all, &pts, margin, seen);
}

#[test]
fn random_boxes_on_cylinder_caps_match_parrys_manifold() {
    let mut g = Lcg(17);
    let mut seen = Seen::default();
    for case in 0..20000 {
        // a third the pile's sizes, else random
        let (e, h, r) = if case % 3 == 0 {
            (Vector3::new(0.05, 0.05, 0.05), 0.05, 0.05)
        } else {
            (
                Vector3::new(
                    g.uniform(0.02, 0.3),
                    g.uniform(0.02, 0.3),
                    g.uniform(0.02, 0.3),
                ),
                g.uniform(0.02, 0.2),
                g.uniform(0.05, 0.3),
            )
        };
        // a face level on the cap, an edge down (turned 45° about a face
        // axis), a corner down, or anywhere; tilted a little, spun about y
        let base = match case % 4 {
            0 => Rotation3::identity(),
            1 => Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4),
            2 => {
                Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_4)
                    * Rotation3::from_axis_angle(&Vector3::z_axis(), 0.6155)
            }
            _ => Rotation3::from_axis_angle(&unit(&mut g), g.uniform(-3.1, 3.1)),
        };
        let tilt = [0.0, 1e-3, 0.05, 0.3][(case / 4) % 4];
        let spin = Rotation3::from_axis_angle(&Vector3::y_axis(), g.uniform(-3.1, 3.1));
        let rot = Rotation3::from_axis_angle(&unit(&mut g), g.uniform(0.0, tilt)) * spin * base;
        let m = rot.matrix();
        let reach = e[0] * m[(1, 0)].abs() + e[1] * m[(1, 1)].abs() + e[2] * m[(1, 2)].abs();
        let s = if g.uniform(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 };
        let w = r + 0.5 * e.norm();
        let c = Vector3::new(
            g.uniform(-w, w),
            s * (h + reach + g.uniform(-0.004, 0.008)),
            g.uniform(-w, w),
        );
        compare_cap(case, (h, r), &e, &Se3::new(*m, c), &mut seen);
    }
    eprintln!("{seen:?}");
    assert!(
        seen.plane > 3000
            && seen.touching > 3000
            && seen.sets > 1500
            && seen.apart > 500
            && seen.epa * 100 < seen.touching,
        "{seen:?}"
    );
}
