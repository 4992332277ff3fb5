//! The pieces of the COLLADA reader ([`super::dae`]): a primitive's
//! triangulation, number lists, local references, node transforms, and the
//! positions that the triangles use.

use nalgebra::Vector3;

/// A 4 × 4 homogeneous transform of the scene graph.
pub(super) type Mat4 = nalgebra::Matrix4<f64>;

/// A `<triangles>`, `<polylist>` or `<polygons>` element of a geometry.
#[derive(Default)]
pub(super) struct DaePrim {
    pub(super) kind: &'static str,
    /// Indices per vertex (the largest input offset plus one).
    pub(super) stride: usize,
    /// The offset and `source` (a `<vertices>` id) of the VERTEX input.
    pub(super) vertex: Option<(usize, String)>,
    /// The `material` symbol.
    pub(super) material: Option<String>,
    pub(super) vcount: Vec<usize>,
    /// Every `<p>`, in order (`<polygons>` has one per polygon).
    pub(super) ps: Vec<Vec<u32>>,
}

impl DaePrim {
    /// The primitive's triangles as indices into its position source of `n`
    /// vertices (polygons fan-triangulated).
    pub(super) fn triangles(
        &self,
        n: usize,
        out: &mut Vec<[u32; 3]>,
        base: u32,
    ) -> Result<(), String> {
        let Some((offset, _)) = &self.vertex else {
            return Ok(());
        };
        let stride = self.stride.max(1);
        let corner = |p: &[u32], k: usize| -> Result<u32, String> {
            let i = p
                .get(k * stride + offset)
                .copied()
                .ok_or_else(|| format!("<{}>: <p> ends inside a vertex", self.kind))?;
            if i as usize >= n {
                return Err(format!(
                    "<{}>: vertex index {i} is past the {n} positions",
                    self.kind
                ));
            }
            Ok(base + i)
        };
        let mut fan = |p: &[u32], first: usize, count: usize| -> Result<(), String> {
            if count < 3 {
                return Ok(());
            }
            let a = corner(p, first)?;
            for k in first + 1..first + count - 1 {
                out.push([a, corner(p, k)?, corner(p, k + 1)?]);
            }
            Ok(())
        };
        match self.kind {
            "polylist" => {
                let p: Vec<u32> = self.ps.concat();
                let mut first = 0;
                for &c in &self.vcount {
                    fan(&p, first, c)?;
                    first += c;
                }
            }
            "polygons" => {
                for p in &self.ps {
                    fan(p, 0, p.len() / stride)?;
                }
            }
            _ => {
                let p: Vec<u32> = self.ps.concat();
                for t in 0..p.len() / (3 * stride) {
                    fan(&p, 3 * t, 3)?;
                }
            }
        }
        Ok(())
    }
}

/// At most 120 characters of `s`, for messages.
pub(super) fn dae_snippet(s: &str) -> String {
    let mut out: String = s.chars().take(120).collect();
    if out.len() < s.len() {
        out.push('…');
    }
    out
}

/// The numbers of a whitespace-separated list; `what` names it in errors.
pub(super) fn dae_numbers(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split_whitespace()
        .map(|s| {
            s.parse::<f64>()
                .map_err(|_| format!("{what}: \"{}\" is not a number", dae_snippet(s)))
        })
        .collect()
}

/// The id a local reference `#id` names.
pub(super) fn dae_local_ref<'a>(url: &'a str, element: &str) -> Result<&'a str, String> {
    url.strip_prefix('#').ok_or_else(|| {
        format!(
            "<{element} url=\"{}\">: only references inside the file (\"#id\") are read",
            dae_snippet(url)
        )
    })
}

/// The matrix of a node transform element (`kind` is its name) from its text.
pub(super) fn dae_transform(kind: &'static str, text: &str, node: &str) -> Result<Mat4, String> {
    let what = format!("node \"{}\": <{kind}>", dae_snippet(node));
    let v = dae_numbers(text, &what)?;
    let expected = match kind {
        "matrix" => 16,
        "rotate" => 4,
        _ => 3,
    };
    if v.len() != expected {
        return Err(format!(
            "{what} has {} numbers, expected {expected}",
            v.len()
        ));
    }
    if !v.iter().all(|x| x.is_finite()) {
        return Err(format!("{what} has a non-finite number"));
    }
    let m = match (kind, v.as_slice()) {
        ("matrix", _) => {
            let m = Mat4::from_row_slice(&v);
            let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)] - 1.0];
            if bottom.iter().any(|x| x.abs() > 1e-9) {
                return Err(format!(
                    "{what}: the last row is not 0 0 0 1 (projective transforms are not read)"
                ));
            }
            let mut m = m;
            m.set_row(3, &nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0));
            m
        }
        ("translate", &[x, y, z]) => Mat4::new_translation(&Vector3::new(x, y, z)),
        ("scale", &[x, y, z]) => Mat4::new_nonuniform_scaling(&Vector3::new(x, y, z)),
        ("rotate", &[x, y, z, degrees]) => {
            match nalgebra::Unit::try_new(Vector3::new(x, y, z), 0.0) {
                Some(axis) => nalgebra::Rotation3::from_axis_angle(&axis, degrees.to_radians())
                    .to_homogeneous(),
                None if degrees == 0.0 => Mat4::identity(),
                None => return Err(format!("{what} has a zero axis")),
            }
        }
        _ => return Err(format!("{what} is not a transform this reader knows")),
    };
    if !m.iter().all(|x| x.is_finite()) {
        return Err(format!("{what} has a non-finite number"));
    }
    Ok(m)
}

/// The positions marked `used`, and the triangles (which index only used ones)
/// renumbered for them.
pub(super) fn keep_used(
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    used: &[bool],
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    if used.iter().all(|&u| u) {
        return (positions, triangles);
    }
    let mut new_index = vec![0u32; positions.len()];
    let mut kept = Vec::with_capacity(positions.len());
    for (i, p) in positions.into_iter().enumerate() {
        if used.get(i).copied().unwrap_or(true) {
            new_index[i] = kept.len() as u32;
            kept.push(p);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| new_index.get(i as usize).copied().unwrap_or(0)))
        .collect();
    (kept, triangles)
}
