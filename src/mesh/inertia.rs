//! A triangle mesh's volume, centre of mass and inertia as MuJoCo's compiler
//! takes them (`mjCMesh::Process`, `ComputeVolume`, `ComputeInertia` in
//! MuJoCo's src/user/user_mesh.cc; docs/theory.md §"Mesh mass properties"),
//! for the four rules of `<mesh inertia>`: `legacy` (MuJoCo's default: every
//! pyramid's volume counted positive, so an open mesh has a volume),
//! `exact` (signed: a closed mesh's true solid), `convex` (the convex
//! hull's solid) and `shell` (a thin surface of unit area density).

use super::TriMesh;
use nalgebra::{Matrix3, Vector3};

/// MuJoCo's `<mesh inertia>`: how a mesh's volume is taken.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshInertia {
    /// Pyramids from the face centroid, each volume taken positive (MuJoCo's
    /// default).
    #[default]
    Legacy,
    /// Pyramids signed (the solid a closed, outward-wound mesh bounds).
    Exact,
    /// The convex hull's solid.
    Convex,
    /// The surface, unit mass per unit area.
    Shell,
}

/// A mesh's mass properties at unit density, in the mesh's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshMass {
    /// Volume (m³; a shell's: its area, m²).
    pub volume: f64,
    /// Centre of mass.
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass at unit density (volume × m²).
    pub inertia: Matrix3<f64>,
}

/// MuJoCo's `mjMINVAL`.
const MINVAL: f64 = 1e-15;

/// A triangle's unit normal, centre and area (MuJoCo's `triangle`: a face
/// shorter than `MINVAL` in twice its area has area 0).
fn triangle(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>, f64) {
    let centre = (a + b + c) / 3.0;
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    if len < MINVAL {
        return (n, centre, 0.0);
    }
    (n / len, centre, 0.5 * len)
}

/// The mass properties of `mesh` by `rule` (see [`MeshInertia`]), or why
/// MuJoCo's compiler refuses them (its messages).
pub fn mass_properties(mesh: &TriMesh, rule: MeshInertia) -> Result<MeshMass, String> {
    let v = &mesh.vertices;
    let corner = |t: &[u32; 3], k: usize| -> Result<Vector3<f64>, String> {
        v.get(t[k] as usize)
            .copied()
            .ok_or_else(|| format!("a face names vertex {} of {}", t[k], v.len()))
    };
    let mut all = Vec::with_capacity(mesh.triangles.len());
    for t in &mesh.triangles {
        all.push([corner(t, 0)?, corner(t, 1)?, corner(t, 2)?]);
    }
    // the faces the solid is made of: the hull's for `convex`
    let faces = match rule {
        MeshInertia::Convex => hull_faces(v)?,
        _ => all.clone(),
    };
    // the area-weighted centroid of the faces: every pyramid's apex
    let (mut facecen, mut area) = (Vector3::zeros(), 0.0);
    for [a, b, c] in &all {
        let (_, centre, s) = triangle(a, b, c);
        facecen += s * centre;
        area += s;
    }
    if area < MINVAL {
        return Err("mesh surface area is too small".into());
    }
    facecen /= area;
    // the centre of mass: each pyramid's (or, for a shell, MuJoCo's same
    // weighting by the faces' areas) at ¾ of the way from apex to face centre
    let (mut com, mut total) = (Vector3::zeros(), 0.0);
    let shell = rule == MeshInertia::Shell;
    for [a, b, c] in if shell { &all } else { &faces } {
        let (n, centre, s) = triangle(a, b, c);
        let mut w = if shell {
            s
        } else {
            (centre - facecen).dot(&n) * s / 3.0
        };
        if rule == MeshInertia::Legacy {
            w = w.abs();
        }
        total += w;
        com += w * (centre * 0.75 + facecen * 0.25);
    }
    if total < MINVAL {
        return Err(if shell {
            "mesh surface area is too small".into()
        } else if total < 0.0 {
            "mesh volume is negative (misoriented triangles)".into()
        } else {
            "mesh volume is too small (try inertia=\"shell\")".into()
        });
    }
    com /= total;
    // the second moments about the centre of mass, pyramid by pyramid with
    // the apex there (a shell: triangle by triangle)
    let mut p = [0.0; 6];
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let mut volume = 0.0;
    for [a, b, c] in if shell { &all } else { &faces } {
        let (d, e, f) = (a - com, b - com, c - com);
        let (n, centre, s) = triangle(&d, &e, &f);
        let mut w = if shell { s } else { centre.dot(&n) * s / 3.0 };
        if rule == MeshInertia::Legacy {
            w = w.abs();
        }
        volume += w;
        let k = if shell { 12.0 } else { 20.0 };
        for (j, &(x, y)) in pairs.iter().enumerate() {
            p[j] += w / k
                * (2.0 * (d[x] * d[y] + e[x] * e[y] + f[x] * f[y])
                    + d[x] * e[y]
                    + d[y] * e[x]
                    + d[x] * f[y]
                    + d[y] * f[x]
                    + e[x] * f[y]
                    + e[y] * f[x]);
        }
    }
    let inertia = Matrix3::new(
        p[1] + p[2],
        -p[3],
        -p[4],
        -p[3],
        p[0] + p[2],
        -p[5],
        -p[4],
        -p[5],
        p[0] + p[1],
    );
    let mut eig = nalgebra::SymmetricEigen::new(inertia).eigenvalues;
    eig.as_mut_slice().sort_by(f64::total_cmp);
    if !(eig[2] > 0.0) {
        return Err("eigenvalue of mesh inertia must be positive".into());
    }
    let (atol, rtol) = (1e-9, 1e-6);
    for k in 0..3 {
        let (x, y, z) = (eig[k], eig[(k + 1) % 3], eig[(k + 2) % 3]);
        if x + y < z * (1.0 - rtol) - atol {
            return Err("eigenvalues of mesh inertia violate A + B >= C".into());
        }
    }
    Ok(MeshMass {
        volume,
        com,
        inertia,
    })
}

/// The outward triangles of the convex hull of `v` (parry's quickhull;
/// MuJoCo's is qhull's: the same solid, another triangulation).
fn hull_faces(v: &[Vector3<f64>]) -> Result<Vec<[Vector3<f64>; 3]>, String> {
    use parry3d_f64::math::Vector3 as PVec;
    let pts: Vec<PVec> = v.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
    let (hv, hf) = parry3d_f64::transformation::try_convex_hull(&pts)
        .map_err(|e| format!("no convex hull ({e:?})"))?;
    let at = |i: u32| {
        let p = hv[i as usize];
        Vector3::new(p.x, p.y, p.z)
    };
    Ok(hf.iter().map(|f| [at(f[0]), at(f[1]), at(f[2])]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box of half sizes `h` centred at `c`, its 12 triangles wound
    /// outward, or every other one flipped (`flip`).
    fn cuboid(h: [f64; 3], c: [f64; 3], flip: bool) -> TriMesh {
        let mut vertices = Vec::new();
        for k in 0..8 {
            let s = |bit: usize, i: usize| if k >> bit & 1 == 1 { h[i] } else { -h[i] };
            vertices.push(Vector3::new(s(0, 0) + c[0], s(1, 1) + c[1], s(2, 2) + c[2]));
        }
        // faces by their 4 corners, counter-clockwise seen from outside
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut triangles = Vec::new();
        for (i, q) in quads.iter().enumerate() {
            triangles.push([q[0], q[1], q[2]]);
            if flip && i % 2 == 0 {
                triangles.push([q[0], q[3], q[2]]);
            } else {
                triangles.push([q[0], q[2], q[3]]);
            }
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1e-12)
    }

    #[test]
    fn a_closed_box_is_the_solid_by_every_rule() {
        let (h, c) = ([0.1, 0.2, 0.3], [0.5, -0.25, 2.0]);
        let v = 8.0 * h[0] * h[1] * h[2];
        // the box's closed form: V (b² + c²)/3 with half sizes
        let want = [
            v * (h[1] * h[1] + h[2] * h[2]) / 3.0,
            v * (h[0] * h[0] + h[2] * h[2]) / 3.0,
            v * (h[0] * h[0] + h[1] * h[1]) / 3.0,
        ];
        for rule in [MeshInertia::Legacy, MeshInertia::Exact, MeshInertia::Convex] {
            let m = mass_properties(&cuboid(h, c, false), rule).unwrap();
            assert!(close(m.volume, v), "{rule:?}: {}", m.volume);
            assert!(
                (m.com - Vector3::from(c)).norm() < 1e-14,
                "{rule:?}: {}",
                m.com
            );
            for k in 0..3 {
                assert!(
                    close(m.inertia[(k, k)], want[k]),
                    "{rule:?} {k}: {}",
                    m.inertia
                );
            }
            assert!(m.inertia[(0, 1)].abs() < 1e-16 && m.inertia[(1, 2)].abs() < 1e-16);
        }
        // legacy takes a misoriented face's pyramid positive: the same box
        let m = mass_properties(&cuboid(h, c, true), MeshInertia::Legacy).unwrap();
        assert!(close(m.volume, v));
        // exact counts it negative: two flipped halves of faces cancel
        let m = mass_properties(&cuboid(h, c, true), MeshInertia::Exact).unwrap();
        assert!(m.volume > 0.0 && m.volume < 0.9 * v, "{}", m.volume);
    }

    #[test]
    fn a_shell_box_is_six_plates() {
        let (h, c) = ([0.1, 0.2, 0.3], [0.0, 0.0, 0.0]);
        let m = mass_properties(&cuboid(h, c, false), MeshInertia::Shell).unwrap();
        let (a, b, cc) = (h[0], h[1], h[2]);
        let area = 8.0 * (a * b + b * cc + a * cc);
        assert!(close(m.volume, area));
        // about x: the two plates normal to x (area 4bc each, Iₓ = A(b²+c²)/3),
        // the two normal to y (4ac at distance b: A(c²/3 + b²)), the two normal
        // to z (4ab at distance c: A(b²/3 + c²))
        let ix = 2.0 * 4.0 * b * cc * (b * b + cc * cc) / 3.0
            + 2.0 * 4.0 * a * cc * (cc * cc / 3.0 + b * b)
            + 2.0 * 4.0 * a * b * (b * b / 3.0 + cc * cc);
        assert!(
            close(m.inertia[(0, 0)], ix),
            "{} vs {ix}",
            m.inertia[(0, 0)]
        );
    }

    #[test]
    fn an_open_box_has_a_legacy_volume_and_no_exact_one() {
        // the box without its top (two triangles)
        let mut open = cuboid([0.1, 0.1, 0.1], [0.0; 3], false);
        open.triangles.truncate(10);
        let legacy = mass_properties(&open, MeshInertia::Legacy).unwrap();
        assert!(legacy.volume > 0.0);
        // a flat mesh has no volume by any solid rule
        let flat = TriMesh {
            vertices: vec![Vector3::zeros(), Vector3::x(), Vector3::y()],
            triangles: vec![[0, 1, 2]],
        };
        assert!(mass_properties(&flat, MeshInertia::Legacy).is_err());
    }
}
