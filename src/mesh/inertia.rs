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
