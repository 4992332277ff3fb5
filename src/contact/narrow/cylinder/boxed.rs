//! A box on a cylinder's cap in closed form: its corner (or a level edge
//! or face) on the cap's plane, the cap's disc the region of [`on_face`]
//! (the exactness test on the box's deepest point over the disc, its points
//! the box's face toward the cap clipped against parry's square of the cap,
//! turned to the deepest point's foot as parry turns it to GJK's point).

use super::{on_face, CylBox, Face, Feature, Other, Pts, Region, LEVEL};
use crate::spatial::Se3;
use nalgebra::Vector3;

/// The contact of a box of half extents `e` at `c_m_b` (its frame in the
/// cylinder's) with the nearer cap of a cylinder (parry's: axis y, half
/// height `h`, radius `r`) within `margin`, where the cap's plane is the
/// exact one: a box's corner (or level edge or face) on the cap, [`on_face`]
/// with the cap's disc the region. Points written to `out` in the
/// cylinder's frame, the normal (out of the cap) in it.
pub(crate) fn box_on_cap(
    h: f64,
    r: f64,
    e: &Vector3<f64>,
    c_m_b: &Se3<f64>,
    margin: f64,
    out: &mut Pts,
) -> CylBox {
    out.1 = 0;
    let c = c_m_b.trans;
    let s = if c.y >= 0.0 { 1.0 } else { -1.0 };
    // the box's reach along y: Σ eₗ|R_yl|
    let rot = &c_m_b.rot;
    let reach = e[0] * rot[(1, 0)].abs() + e[1] * rot[(1, 1)].abs() + e[2] * rot[(1, 2)].abs();
    let sep = s * c.y - h - reach;
    let n = Vector3::new(0.0, s, 0.0);
    if sep > margin {
        return CylBox::Apart(n);
    }
    let face = Face {
        i: 1,
        s,
        off: h,
        region: Region::Disc(r),
        f: 10 + u64::from(s < 0.0),
    };
    if on_face(Other::Box(*e), c_m_b, face, sep, margin, out) {
        CylBox::Plane(n)
    } else {
        CylBox::Other
    }
}

/// A box's (half extents `e`) [`Feature`] on `face` (outward normal `n`):
/// its deepest corner, else (a level edge or face, its rise across it at
/// most [`LEVEL`]) the level feature's point nearest the face's centre line;
/// its face of normal nearest −n (parry's `Cuboid::support_face`).
pub(super) fn box_feature(
    e: &Vector3<f64>,
    q_m_b: &Se3<f64>,
    face: &Face,
    n: &Vector3<f64>,
    depth: f64,
) -> Option<Feature> {
    let (j, k) = ((face.i + 1) % 3, (face.i + 2) % 3);
    let c = q_m_b.trans;
    let rot = &q_m_b.rot;
    let nb = rot.transpose() * n;
    let ax = |l: usize| -> Vector3<f64> { rot.column(l).into() };
    // the deepest corner: −sign(n·Rₗ) eₗ along each axis
    let sg = |l: usize| if nb[l] > 0.0 { -1.0 } else { 1.0 };
    let p0 = c + ax(0) * (sg(0) * e[0]) + ax(1) * (sg(1) * e[1]) + ax(2) * (sg(2) * e[2]);
    let level = |l: usize| 2.0 * e[l] * nb[l].abs() <= LEVEL;
    let stand = if face.over(&p0, depth) {
        p0
    } else if level(0) || level(1) || level(2) {
        // the level feature's centre, then along each level axis to the
        // point nearest the centre line (the level axes are square to n:
        // their (j, k) shadows orthogonal)
        let mut a = p0;
        for l in (0..3).filter(|&l| level(l)) {
            a -= ax(l) * (sg(l) * e[l]);
        }
        for l in (0..3).filter(|&l| level(l)) {
            let d = ax(l);
            let dd = d[j] * d[j] + d[k] * d[k];
            if dd > 0.0 {
                a += d * (-(a[j] * d[j] + a[k] * d[k]) / dd).clamp(-e[l], e[l]);
            }
        }
        a
    } else {
        return None;
    };
    // the face toward −n: axis of largest |n·Rₗ|
    let f = (0..3)
        .max_by(|&x, &y| nb[x].abs().total_cmp(&nb[y].abs()))
        .unwrap_or(0);
    let (fa, fb) = ((f + 1) % 3, (f + 2) % 3);
    let nf = ax(f) * sg(f);
    let fc = c + nf * e[f];
    let (da, db) = (ax(fa) * e[fa], ax(fb) * e[fb]);
    Some(Feature {
        p0,
        stand,
        vs: [fc + da + db, fc - da + db, fc - da - db, fc + da - db],
        m: 4,
        plane: (nf, fc),
        code: 2 * f as u64 + u64::from(sg(f) < 0.0),
    })
}
