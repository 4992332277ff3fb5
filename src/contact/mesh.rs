//! Mesh files as URDFs use them, read only for ground contact and reduced to
//! their vertex positions (the contact shape is their convex hull).
//!
//! - STL (ASCII or binary) through `stl_io`;
//! - Wavefront OBJ through `tobj` (every object's `v` positions);
//! - COLLADA (`.dae`) through a minimal reader. The vertices are the
//!   `<float_array>` of the `<source>` that a geometry's
//!   `<vertices><input semantic="POSITION">` names, those of them that the
//!   geometry's `<triangles>`, `<polylist>` and `<polygons>` index (the whole
//!   array for a geometry without such primitives or whose primitives index
//!   nothing; assimp, which coal and Pinocchio use, also drops positions that
//!   nothing indexes: see docs/meshes.md), placed by the scene graph: the visual
//!   scene `<scene><instance_visual_scene url>` names (else the first one) is
//!   walked, each `<node>`'s transform elements (`<matrix>`, row-major;
//!   `<translate>`; `<rotate>`, axis and angle in degrees; `<scale>`) are
//!   multiplied in document order onto its parent's transform, and every
//!   `<instance_geometry>` (and `<instance_node>` of a node in the file) emits
//!   its geometry's positions in that transform — a geometry placed twice
//!   appears twice. The result is scaled by the document's `<asset><unit meter>`.
//!   `<up_axis>` is ignored, as ROS tools do (so does coal's loader, which
//!   Pinocchio uses). A `<skew>` or
//!   `<lookat>` above a placed geometry is an error; `<instance_controller>`
//!   (skinned meshes) places nothing. A document whose scene places no geometry
//!   (or that has no scene) gives every POSITION array, untransformed.
//!
//!   For drawing, [`load_mesh_colored`] also gives each DAE triangle the diffuse
//!   `<color>` of its material: the primitive's `material` symbol, bound by the
//!   placing `<instance_geometry>`'s `<instance_material symbol target>` (else
//!   taken as a material id), the material's `<instance_effect>`, the effect's
//!   `<diffuse><color>` (none for a `<texture>`).

use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::Path;

/// Why a mesh could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {message}")]
pub struct MeshError {
    /// The mesh file.
    pub file: String,
    /// What is wrong with it.
    pub message: String,
}

fn err(path: &Path, message: impl Into<String>) -> MeshError {
    MeshError {
        file: path.display().to_string(),
        message: message.into(),
    }
}

/// A triangle mesh as a mesh file gives it: vertex positions (in the file's
/// units times the scale asked for) and triangles as indices into them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles, three indices into `vertices` each (polygons fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// The vertex positions of a mesh file, in the file's units times `scale`.
/// Non-finite coordinates are an error; an empty mesh is an error.
pub fn load_vertices(path: &Path, scale: [f64; 3]) -> Result<Vec<Vector3<f64>>, MeshError> {
    let (raw, _, _) = read_raw(path, false)?;
    scaled(path, raw, scale)
}

/// The vertices and triangles of a mesh file (STL, OBJ, DAE as [`load_vertices`]
/// reads them: the same vertices, DAE nodes placed alike), in the file's units
/// times `scale`. DAE triangles come from `<triangles>`, `<polylist>` and
/// `<polygons>` (fan-triangulated), OBJ faces are triangulated; an index outside
/// the vertices is an error, and so is a mesh without vertices.
pub fn load_mesh(path: &Path, scale: [f64; 3]) -> Result<TriMesh, MeshError> {
    load_mesh_colored(path, scale).map(|(m, _)| m)
}

/// A triangle's colour as its mesh file gives it: red, green, blue, alpha in 0..1.
pub type Rgba = [f64; 4];

/// [`load_mesh`] and each triangle's colour where the file gives one (a DAE
/// material's diffuse colour, see the module doc; `None` for STL and OBJ, and for
/// DAE triangles without a material colour). The colours are as many as the
/// triangles.
pub fn load_mesh_colored(
    path: &Path,
    scale: [f64; 3],
) -> Result<(TriMesh, Vec<Option<Rgba>>), MeshError> {
    let (raw, triangles, mut colors) = read_raw(path, true)?;
    colors.resize(triangles.len(), None);
    let n = raw.len();
    if let Some(t) = triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(err(
            path,
            format!("a triangle {t:?} indexes past the {n} vertices"),
        ));
    }
    Ok((
        TriMesh {
            vertices: scaled(path, raw, scale)?,
            triangles,
        },
        colors,
    ))
}

/// Scales raw positions, refusing an empty mesh and non-finite vertices.
fn scaled(
    path: &Path,
    raw: Vec<[f64; 3]>,
    scale: [f64; 3],
) -> Result<Vec<Vector3<f64>>, MeshError> {
    if raw.is_empty() {
        return Err(err(path, "the mesh has no vertices"));
    }
    let mut out = Vec::with_capacity(raw.len());
    for p in raw {
        let v = Vector3::new(p[0] * scale[0], p[1] * scale[1], p[2] * scale[2]);
        if !v.iter().all(|x| x.is_finite()) {
            return Err(err(path, "the mesh has a non-finite vertex"));
        }
        out.push(v);
    }
    Ok(out)
}

/// Raw positions, triangles and triangle colours.
type RawMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<Option<Rgba>>);

/// Raw positions of a mesh file and, when `with_triangles`, its triangles and
/// their colours (DAE only; empty otherwise).
fn read_raw(path: &Path, with_triangles: bool) -> Result<RawMesh, MeshError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mut triangles = Vec::new();
    let mut colors = Vec::new();
    let raw: Vec<[f64; 3]> = match ext.as_str() {
        "stl" => {
            let mut f =
                std::fs::File::open(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
            let mesh = stl_io::read_stl(&mut f)
                .map_err(|e| err(path, format!("not a valid STL file: {e}")))?;
            if with_triangles {
                for face in &mesh.faces {
                    let [a, b, c] = face.vertices;
                    let idx =
                        |i: usize| u32::try_from(i).map_err(|_| err(path, "too many vertices"));
                    triangles.push([idx(a)?, idx(b)?, idx(c)?]);
                }
            }
            mesh.vertices
                .iter()
                .map(|v| [v.0[0] as f64, v.0[1] as f64, v.0[2] as f64])
                .collect()
        }
        "obj" => {
            let opts = tobj::LoadOptions {
                triangulate: with_triangles,
                ..tobj::LoadOptions::default()
            };
            let (models, _) = tobj::load_obj(path, &opts)
                .map_err(|e| err(path, format!("not a valid OBJ file: {e}")))?;
            let mut out = Vec::new();
            for m in &models {
                let base = u32::try_from(out.len()).map_err(|_| err(path, "too many vertices"))?;
                if with_triangles {
                    for t in m.mesh.indices.chunks_exact(3) {
                        if let &[a, b, c] = t {
                            triangles.push([base + a, base + b, base + c]);
                        }
                    }
                }
                for c in m.mesh.positions.chunks_exact(3) {
                    out.push([c[0] as f64, c[1] as f64, c[2] as f64]);
                }
            }
            out
        }
        "dae" => {
            let bytes = std::fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))?;
            let text = String::from_utf8_lossy(&bytes);
            let dae = read_dae_colored(&text).map_err(|m| err(path, m))?;
            if with_triangles {
                triangles = dae.triangles;
                colors = dae.colors;
            }
            dae.positions
        }
        other => {
            return Err(err(
                path,
                format!("unsupported mesh format \"{other}\" (STL, OBJ and DAE are read)"),
            ))
        }
    };
    Ok((raw, triangles, colors))
}

/// A 4×4 affine transform acting on column vectors (COLLADA's convention).
type Mat4 = nalgebra::Matrix4<f64>;

/// Most node visits the scene walk makes (`<instance_node>` can form cycles or
/// blow up exponentially).
const MAX_DAE_NODE_VISITS: usize = 1_000_000;
/// Most vertices the scene walk emits (one geometry can be instanced many times).
const MAX_DAE_VERTICES: usize = 5_000_000;

/// A `<node>` of a visual scene or of `<library_nodes>`.
struct DaeNode {
    /// `id`, else `name`, for messages.
    label: String,
    /// Product of the node's transform elements, in document order.
    local: Mat4,
    /// A transform element that is not applied (`skew`, `lookat`).
    unsupported: Option<&'static str>,
    /// `<instance_geometry url>`s.
    geometries: Vec<String>,
    /// Per `<instance_geometry>`: its `<instance_material symbol>` → `target` id.
    bindings: Vec<HashMap<String, String>>,
    /// `<instance_node url>`s.
    instances: Vec<String>,
    children: Vec<usize>,
}

struct DaeVisualScene {
    id: Option<String>,
    roots: Vec<usize>,
}

/// What the text being collected belongs to.
enum DaeText {
    /// A `<float_array id>`.
    Array(String),
    /// A transform element (`matrix`, `translate`, `rotate`, `scale`) of a node.
    Transform(&'static str, usize),
    /// A `<vcount>` or `<p>` of the primitive being read.
    Indices(&'static str),
    /// The `<diffuse><color>` of an `<effect id>`.
    Color(String),
}

/// A `<triangles>`, `<polylist>` or `<polygons>` element of a geometry.
#[derive(Default)]
struct DaePrim {
    kind: &'static str,
    /// Indices per vertex (the largest input offset plus one).
    stride: usize,
    /// The offset and `source` (a `<vertices>` id) of the VERTEX input.
    vertex: Option<(usize, String)>,
    /// The `material` symbol.
    material: Option<String>,
    vcount: Vec<usize>,
    /// Every `<p>`, in order (`<polygons>` has one per polygon).
    ps: Vec<Vec<u32>>,
}

impl DaePrim {
    /// The primitive's triangles as indices into its position source of `n`
    /// vertices (polygons fan-triangulated).
    fn triangles(&self, n: usize, out: &mut Vec<[u32; 3]>, base: u32) -> Result<(), String> {
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
fn dae_snippet(s: &str) -> String {
    let mut out: String = s.chars().take(120).collect();
    if out.len() < s.len() {
        out.push('…');
    }
    out
}

/// The numbers of a whitespace-separated list; `what` names it in errors.
fn dae_numbers(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split_whitespace()
        .map(|s| {
            s.parse::<f64>()
                .map_err(|_| format!("{what}: \"{}\" is not a number", dae_snippet(s)))
        })
        .collect()
}

/// The id a local reference `#id` names.
fn dae_local_ref<'a>(url: &'a str, element: &str) -> Result<&'a str, String> {
    url.strip_prefix('#').ok_or_else(|| {
        format!(
            "<{element} url=\"{}\">: only references inside the file (\"#id\") are read",
            dae_snippet(url)
        )
    })
}

/// The matrix of a node transform element (`kind` is its name) from its text.
fn dae_transform(kind: &'static str, text: &str, node: &str) -> Result<Mat4, String> {
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

/// Positions of a COLLADA document (see the module doc).
#[cfg(test)]
fn read_dae_positions(text: &str) -> Result<Vec<[f64; 3]>, String> {
    read_dae(text).map(|(p, _)| p)
}

/// Positions of a COLLADA document (see the module doc) and the triangles of the
/// placed geometries' primitives.
#[cfg(test)]
fn read_dae(text: &str) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>), String> {
    read_dae_colored(text).map(|d| (d.positions, d.triangles))
}

/// What [`read_dae_colored`] reads.
struct DaeMesh {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// One a triangle.
    colors: Vec<Option<Rgba>>,
}

/// Positions, triangles and triangle colours of a COLLADA document (see the
/// module doc).
fn read_dae_colored(text: &str) -> Result<DaeMesh, String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut arrays: HashMap<String, Vec<f64>> = HashMap::new();
    // source id -> float_array id
    let mut source_array: HashMap<String, String> = HashMap::new();
    // Every POSITION source, in document order (the fallback without a scene).
    let mut position_sources: Vec<String> = Vec::new();
    // geometry id -> its POSITION sources (none for a geometry without them)
    let mut geometry_positions: HashMap<String, Vec<String>> = HashMap::new();
    let mut nodes: Vec<DaeNode> = Vec::new();
    let mut node_ids: HashMap<String, usize> = HashMap::new();
    let mut scenes: Vec<DaeVisualScene> = Vec::new();
    let mut scene_url: Option<String> = None;
    // Local names of the open elements.
    let mut open: Vec<Vec<u8>> = Vec::new();
    // The open `<node>`s.
    let mut node_stack: Vec<usize> = Vec::new();
    let mut current_source: Option<String> = None;
    let mut current_geometry: Option<String> = None;
    let mut current_scene: Option<usize> = None;
    let mut collecting: Option<DaeText> = None;
    let mut buf = String::new();
    let mut in_vertices = false;
    // `<vertices id>` -> its POSITION source
    let mut vertices_source: HashMap<String, String> = HashMap::new();
    let mut current_vertices: Option<String> = None;
    // geometry id -> its primitives
    let mut geometry_prims: HashMap<String, Vec<DaePrim>> = HashMap::new();
    let mut geometry_order: Vec<String> = Vec::new();
    let mut current_prim: Option<DaePrim> = None;
    // The `<instance_geometry>` being read: (node, index among its geometries).
    let mut current_instance: Option<(usize, usize)> = None;
    // material id -> effect id; effect id -> diffuse colour
    let mut material_effect: HashMap<String, String> = HashMap::new();
    let mut effect_color: HashMap<String, Rgba> = HashMap::new();
    let mut current_material: Option<String> = None;
    let mut current_effect: Option<String> = None;
    let mut unit = 1.0;
    // Ends the text being collected, `collecting`, into its array or node.
    let finish = |collecting: DaeText,
                  buf: &str,
                  arrays: &mut HashMap<String, Vec<f64>>,
                  nodes: &mut Vec<DaeNode>,
                  colors: &mut HashMap<String, Rgba>|
     -> Result<(), String> {
        match collecting {
            DaeText::Array(id) => {
                let vals: Result<Vec<f64>, _> =
                    buf.split_whitespace().map(str::parse::<f64>).collect();
                let vals = vals.map_err(|_| {
                    format!("float_array \"{}\": not a number list", dae_snippet(&id))
                })?;
                arrays.entry(id).or_default().extend(vals);
            }
            DaeText::Transform(kind, i) => {
                if let Some(node) = nodes.get_mut(i) {
                    let m = dae_transform(kind, buf, &node.label)?;
                    node.local *= m;
                }
            }
            // (read by the caller)
            DaeText::Indices(_) => {}
            DaeText::Color(effect) => {
                // r g b [a]; a colour that is not numbers is no colour
                let v: Vec<f64> = buf
                    .split_whitespace()
                    .filter_map(|x| x.parse::<f64>().ok())
                    .filter(|x| x.is_finite())
                    .collect();
                if let [r, g, b, rest @ ..] = v.as_slice() {
                    let a = rest.first().copied().unwrap_or(1.0);
                    colors.insert(effect, [*r, *g, *b, a].map(|x| x.clamp(0.0, 1.0)));
                }
            }
        }
        Ok(())
    };
    loop {
        let ev = reader
            .read_event()
            .map_err(|e| format!("not a valid COLLADA (XML) file: {e}"))?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let is_start = matches!(ev, Event::Start(_));
                let name = e.local_name();
                let parent = open.last().map(Vec::as_slice);
                let attr = |key: &[u8]| -> Option<String> {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.local_name().as_ref() == key)
                        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
                };
                let in_node = parent == Some(b"node".as_slice());
                let top_node = node_stack.last().copied();
                match name.as_ref() {
                    b"source" if is_start => current_source = attr(b"id"),
                    b"float_array" => {
                        if let Some(id) = attr(b"id") {
                            if let Some(s) = &current_source {
                                source_array.insert(s.clone(), id.clone());
                            }
                            if is_start {
                                buf.clear();
                                collecting = Some(DaeText::Array(id));
                            } else {
                                // `<float_array count="0"/>`: an empty array.
                                arrays.entry(id).or_default();
                            }
                        }
                    }
                    b"geometry" if is_start => {
                        current_geometry = attr(b"id");
                        if let Some(g) = &current_geometry {
                            geometry_positions.entry(g.clone()).or_default();
                            geometry_order.push(g.clone());
                        }
                    }
                    b"vertices" => {
                        in_vertices = is_start;
                        current_vertices = attr(b"id");
                    }
                    kind @ (b"triangles" | b"polylist" | b"polygons")
                        if is_start && current_geometry.is_some() =>
                    {
                        current_prim = Some(DaePrim {
                            kind: match kind {
                                b"triangles" => "triangles",
                                b"polylist" => "polylist",
                                _ => "polygons",
                            },
                            material: attr(b"material"),
                            ..DaePrim::default()
                        });
                    }
                    b"input" if current_prim.is_some() && !in_vertices => {
                        let offset = match attr(b"offset") {
                            Some(o) => o.trim().parse::<usize>().map_err(|_| {
                                format!("<input offset=\"{}\">: not an index", dae_snippet(&o))
                            })?,
                            None => 0,
                        };
                        if let Some(prim) = current_prim.as_mut() {
                            prim.stride = prim.stride.max(offset + 1);
                            if attr(b"semantic").as_deref() == Some("VERTEX") {
                                let src = attr(b"source").unwrap_or_default();
                                prim.vertex =
                                    Some((offset, src.trim_start_matches('#').to_string()));
                            }
                        }
                    }
                    kind @ (b"vcount" | b"p") if current_prim.is_some() => {
                        let kind = if kind == b"p" { "p" } else { "vcount" };
                        if is_start {
                            buf.clear();
                            collecting = Some(DaeText::Indices(kind));
                        } else if let Some(prim) = current_prim.as_mut() {
                            if kind == "p" {
                                prim.ps.push(Vec::new());
                            }
                        }
                    }
                    b"input" if in_vertices && attr(b"semantic").as_deref() == Some("POSITION") => {
                        if let Some(s) = attr(b"source") {
                            let s = s.trim_start_matches('#').to_string();
                            if let Some(v) = &current_vertices {
                                vertices_source.insert(v.clone(), s.clone());
                            }
                            if let Some(g) = &current_geometry {
                                geometry_positions
                                    .entry(g.clone())
                                    .or_default()
                                    .push(s.clone());
                            }
                            position_sources.push(s);
                        }
                    }
                    // The document's `<COLLADA><asset><unit>` only.
                    b"unit" if open.len() == 2 && parent == Some(b"asset".as_slice()) => {
                        if let Some(m) = attr(b"meter") {
                            match m.trim().parse::<f64>() {
                                Ok(m) if m.is_finite() && m > 0.0 => unit = m,
                                _ => {
                                    return Err(format!(
                                        "<unit meter=\"{}\">: not a positive number",
                                        dae_snippet(&m)
                                    ))
                                }
                            }
                        }
                    }
                    b"visual_scene" => {
                        scenes.push(DaeVisualScene {
                            id: attr(b"id"),
                            roots: Vec::new(),
                        });
                        current_scene = is_start.then(|| scenes.len() - 1);
                    }
                    b"instance_visual_scene" if parent == Some(b"scene".as_slice()) => {
                        scene_url = Some(attr(b"url").ok_or("<instance_visual_scene> has no url")?);
                    }
                    b"node" => {
                        let id = attr(b"id");
                        let label = id
                            .clone()
                            .or_else(|| attr(b"name"))
                            .unwrap_or_else(|| "(unnamed)".to_string());
                        let i = nodes.len();
                        nodes.push(DaeNode {
                            label,
                            local: Mat4::identity(),
                            unsupported: None,
                            geometries: Vec::new(),
                            bindings: Vec::new(),
                            instances: Vec::new(),
                            children: Vec::new(),
                        });
                        if let Some(id) = id {
                            node_ids.entry(id).or_insert(i);
                        }
                        match (parent, top_node, current_scene) {
                            (Some(b"node"), Some(p), _) => {
                                if let Some(p) = nodes.get_mut(p) {
                                    p.children.push(i);
                                }
                            }
                            (Some(b"visual_scene"), _, Some(s)) => {
                                if let Some(s) = scenes.get_mut(s) {
                                    s.roots.push(i);
                                }
                            }
                            _ => {}
                        }
                        if is_start {
                            node_stack.push(i);
                        }
                    }
                    kind @ (b"matrix" | b"translate" | b"rotate" | b"scale") if in_node => {
                        if let Some(i) = top_node {
                            let kind = match kind {
                                b"matrix" => "matrix",
                                b"translate" => "translate",
                                b"rotate" => "rotate",
                                _ => "scale",
                            };
                            let collect = DaeText::Transform(kind, i);
                            if is_start {
                                buf.clear();
                                collecting = Some(collect);
                            } else {
                                finish(collect, "", &mut arrays, &mut nodes, &mut effect_color)?;
                            }
                        }
                    }
                    kind @ (b"skew" | b"lookat") if in_node => {
                        if let Some(node) = top_node.and_then(|i| nodes.get_mut(i)) {
                            node.unsupported.get_or_insert(if kind == b"skew" {
                                "skew"
                            } else {
                                "lookat"
                            });
                        }
                    }
                    kind @ (b"instance_geometry" | b"instance_node") if in_node => {
                        if let Some(node) = top_node.and_then(|i| nodes.get_mut(i)) {
                            let geometry = kind == b"instance_geometry";
                            let Some(url) = attr(b"url") else {
                                return Err(format!(
                                    "node \"{}\": <{}> has no url",
                                    dae_snippet(&node.label),
                                    if geometry {
                                        "instance_geometry"
                                    } else {
                                        "instance_node"
                                    }
                                ));
                            };
                            if geometry {
                                node.geometries.push(url);
                                node.bindings.push(HashMap::new());
                                if is_start {
                                    current_instance =
                                        top_node.map(|n| (n, node.geometries.len() - 1));
                                }
                            } else {
                                node.instances.push(url);
                            }
                        }
                    }
                    b"instance_material" => {
                        if let (Some((n, g)), Some(symbol), Some(target)) =
                            (current_instance, attr(b"symbol"), attr(b"target"))
                        {
                            if let Some(b) = nodes.get_mut(n).and_then(|n| n.bindings.get_mut(g)) {
                                b.insert(symbol, target.trim_start_matches('#').to_string());
                            }
                        }
                    }
                    b"material" if is_start => current_material = attr(b"id"),
                    b"instance_effect" => {
                        if let (Some(m), Some(url)) = (&current_material, attr(b"url")) {
                            material_effect
                                .insert(m.clone(), url.trim_start_matches('#').to_string());
                        }
                    }
                    b"effect" if is_start => current_effect = attr(b"id"),
                    b"color" if is_start && parent == Some(b"diffuse".as_slice()) => {
                        if let Some(e) = &current_effect {
                            buf.clear();
                            collecting = Some(DaeText::Color(e.clone()));
                        }
                    }
                    _ => {}
                }
                if is_start {
                    open.push(name.as_ref().to_vec());
                }
            }
            Event::Text(ref t) if collecting.is_some() => {
                buf.push_str(&String::from_utf8_lossy(t.as_ref()));
            }
            Event::CData(ref t) if collecting.is_some() => {
                buf.push_str(&String::from_utf8_lossy(t.as_ref()));
            }
            Event::GeneralRef(ref r) if collecting.is_some() => {
                // `&#32;` and the like; a named entity has no place in numbers.
                match r.resolve_char_ref() {
                    Ok(Some(c)) => buf.push(c),
                    _ => {
                        let name = String::from_utf8_lossy(r.as_ref()).into_owned();
                        let element = match &collecting {
                            Some(DaeText::Array(id)) => {
                                format!("float_array \"{}\"", dae_snippet(id))
                            }
                            Some(DaeText::Transform(kind, _)) => format!("<{kind}>"),
                            Some(DaeText::Indices(kind)) => format!("<{kind}>"),
                            Some(DaeText::Color(_)) => "<color>".to_string(),
                            None => String::new(),
                        };
                        return Err(format!(
                            "{element}: the entity reference &{}; in a number list",
                            dae_snippet(&name)
                        ));
                    }
                }
            }
            Event::End(ref e) => {
                open.pop();
                match e.local_name().as_ref() {
                    b"float_array" | b"matrix" | b"translate" | b"rotate" | b"scale" | b"color" => {
                        if let Some(c) = collecting.take() {
                            finish(c, &buf, &mut arrays, &mut nodes, &mut effect_color)?;
                            buf.clear();
                        }
                    }
                    b"instance_geometry" => current_instance = None,
                    b"material" => current_material = None,
                    b"effect" => current_effect = None,
                    b"vcount" | b"p" => {
                        if let (Some(DaeText::Indices(kind)), Some(prim)) =
                            (collecting.take(), current_prim.as_mut())
                        {
                            let ints: Result<Vec<u32>, _> =
                                buf.split_whitespace().map(str::parse::<u32>).collect();
                            let ints = ints.map_err(|_| {
                                format!("<{}><{kind}>: not a list of indices", prim.kind)
                            })?;
                            if kind == "p" {
                                prim.ps.push(ints);
                            } else {
                                prim.vcount.extend(ints.iter().map(|&c| c as usize));
                            }
                            buf.clear();
                        }
                    }
                    b"triangles" | b"polylist" | b"polygons" => {
                        if let (Some(prim), Some(g)) = (current_prim.take(), &current_geometry) {
                            geometry_prims.entry(g.clone()).or_default().push(prim);
                        }
                    }
                    b"source" => current_source = None,
                    b"geometry" => current_geometry = None,
                    b"vertices" => in_vertices = false,
                    b"visual_scene" => current_scene = None,
                    b"node" => {
                        node_stack.pop();
                    }
                    _ => {}
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let positions_of = |s: &str| -> Result<&Vec<f64>, String> {
        source_array
            .get(s)
            .and_then(|a| arrays.get(a))
            .ok_or_else(|| format!("POSITION source \"{}\" has no float_array", dae_snippet(s)))
    };
    // The colour of a primitive's material symbol under an instance's bindings.
    let color_of = |symbol: Option<&String>, bind: &HashMap<String, String>| -> Option<Rgba> {
        let s = symbol?;
        let material = bind.get(s).unwrap_or(s);
        effect_color.get(material_effect.get(material)?).copied()
    };
    let no_bindings = HashMap::new();
    let mut colors: Vec<Option<Rgba>> = Vec::new();
    // The triangles of geometry `g` whose POSITION sources start at `bases`,
    // and their colours under the material bindings `bind`.
    let mut emit_triangles = |g: &str,
                              bases: &HashMap<&str, u32>,
                              bind: &HashMap<String, String>,
                              tris: &mut Vec<[u32; 3]>|
     -> Result<(), String> {
        for prim in geometry_prims.get(g).map(Vec::as_slice).unwrap_or_default() {
            let Some((_, vref)) = &prim.vertex else {
                continue;
            };
            let src = vertices_source
                .get(vref)
                .map(String::as_str)
                .unwrap_or(vref);
            let (Some(&base), Ok(arr)) = (bases.get(src), positions_of(src)) else {
                return Err(format!(
                    "<{}>: the VERTEX input \"{}\" names no POSITION source of its geometry",
                    prim.kind,
                    dae_snippet(vref)
                ));
            };
            prim.triangles(arr.len() / 3, tris, base)?;
            colors.resize(tris.len(), color_of(prim.material.as_ref(), bind));
        }
        Ok(())
    };
    let mut tris: Vec<[u32; 3]> = Vec::new();

    // The scene `<scene><instance_visual_scene>` names, else the first one.
    let scene = match &scene_url {
        Some(url) => {
            let id = dae_local_ref(url, "instance_visual_scene")?;
            let found = scenes.iter().find(|s| s.id.as_deref() == Some(id));
            Some(found.ok_or_else(|| {
                format!(
                    "<instance_visual_scene url=\"{}\"> names no visual_scene",
                    dae_snippet(url)
                )
            })?)
        }
        None => scenes.first(),
    };
    if let Some(scene) = scene {
        let mut out = Vec::new();
        // Whether each placed position is kept.
        let mut used: Vec<bool> = Vec::new();
        let mut instanced = false;
        // (node, parent's world transform, the node that has an unsupported transform)
        let mut stack: Vec<(usize, Mat4, Option<usize>)> = scene
            .roots
            .iter()
            .rev()
            .map(|&r| (r, Mat4::identity(), None))
            .collect();
        let mut visits = 0usize;
        while let Some((i, parent_world, unsupported)) = stack.pop() {
            visits += 1;
            if visits > MAX_DAE_NODE_VISITS {
                return Err(format!(
                    "the visual scene visits more than {MAX_DAE_NODE_VISITS} nodes \
                     (an <instance_node> cycle?)"
                ));
            }
            let Some(node) = nodes.get(i) else { continue };
            let world = parent_world * node.local;
            let unsupported = if node.unsupported.is_some() {
                Some(i)
            } else {
                unsupported
            };
            for (k, url) in node.geometries.iter().enumerate() {
                instanced = true;
                if let Some(u) = unsupported.and_then(|u| nodes.get(u)) {
                    return Err(format!(
                        "node \"{}\": <{}> is not read, and the node places <instance_geometry url=\"{}\">",
                        dae_snippet(&u.label),
                        u.unsupported.unwrap_or("?"),
                        dae_snippet(url)
                    ));
                }
                let id = dae_local_ref(url, "instance_geometry")?;
                let sources = geometry_positions.get(id).ok_or_else(|| {
                    format!(
                        "<instance_geometry url=\"{}\"> names no geometry",
                        dae_snippet(url)
                    )
                })?;
                let mut bases: HashMap<&str, u32> = HashMap::new();
                let first_triangle = tris.len();
                for s in sources {
                    let arr = positions_of(s)?;
                    bases.entry(s.as_str()).or_insert(out.len() as u32);
                    if out.len() + arr.len() / 3 > MAX_DAE_VERTICES {
                        return Err(format!(
                            "the visual scene places more than {MAX_DAE_VERTICES} vertices"
                        ));
                    }
                    for c in arr.chunks_exact(3) {
                        if let &[x, y, z] = c {
                            let p = world * nalgebra::Vector4::new(x, y, z, 1.0);
                            out.push([p.x * unit, p.y * unit, p.z * unit]);
                        }
                    }
                }
                let bind = node.bindings.get(k).unwrap_or(&no_bindings);
                emit_triangles(id, &bases, bind, &mut tris)?;
                // Only the positions its primitives index (all of them when it has
                // none, or when they index nothing).
                let placed = tris.get(first_triangle..).unwrap_or_default();
                used.resize(out.len(), placed.is_empty());
                for &i in placed.iter().flatten() {
                    if let Some(u) = used.get_mut(i as usize) {
                        *u = true;
                    }
                }
            }
            // Children after instanced nodes, each in document order.
            for &c in node.children.iter().rev() {
                stack.push((c, world, unsupported));
            }
            for url in node.instances.iter().rev() {
                let id = dae_local_ref(url, "instance_node")?;
                let &j = node_ids.get(id).ok_or_else(|| {
                    format!("<instance_node url=\"{}\"> names no node", dae_snippet(url))
                })?;
                stack.push((j, world, unsupported));
            }
        }
        if instanced {
            let (positions, triangles) = keep_used(out, tris, &used);
            return Ok(DaeMesh {
                positions,
                triangles,
                colors,
            });
        }
    }
    // No scene places a geometry: every POSITION array, untransformed.
    let mut out = Vec::new();
    let mut bases: HashMap<&str, u32> = HashMap::new();
    for s in &position_sources {
        bases.entry(s.as_str()).or_insert(out.len() as u32);
        for c in positions_of(s)?.chunks_exact(3) {
            if let &[x, y, z] = c {
                out.push([x * unit, y * unit, z * unit]);
            }
        }
    }
    for g in &geometry_order {
        emit_triangles(g, &bases, &no_bindings, &mut tris)?;
    }
    Ok(DaeMesh {
        positions: out,
        triangles: tris,
        colors,
    })
}

/// The positions marked `used`, and the triangles (which index only used ones)
/// renumbered for them.
fn keep_used(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dae_positions_and_unit() {
        let dae = r##"<?xml version="1.0"?>
<COLLADA><asset><unit meter="0.001"/></asset>
<library_geometries><geometry><mesh>
<source id="pos"><float_array id="pos-array" count="6">1 2 3 4 5 6</float_array></source>
<source id="nrm"><float_array id="nrm-array" count="3">0 0 1</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#pos"/></vertices>
</mesh></geometry></library_geometries></COLLADA>"##;
        let p = read_dae_positions(dae).unwrap();
        assert_eq!(p.len(), 2);
        assert!((p[1][2] - 0.006).abs() < 1e-15);
    }

    /// A document with one triangle geometry `tri` (points (1,0,0), (0,2,0),
    /// (0,0,3)) and `scene` as its `<library_visual_scenes>` content.
    fn dae_with_scene(scene: &str) -> String {
        format!(
            r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="1"/><up_axis>Y_UP</up_axis></asset>
<library_geometries><geometry id="tri"><mesh>
<source id="tri-pos"><float_array id="tri-pos-array" count="9">1 0 0 0 2 0 0 0 3</float_array></source>
<vertices id="tri-v"><input semantic="POSITION" source="#tri-pos"/></vertices>
</mesh></geometry>
<geometry id="unused"><mesh>
<source id="u-pos"><float_array id="u-pos-array" count="3">100 100 100</float_array></source>
<vertices id="u-v"><input semantic="POSITION" source="#u-pos"/></vertices>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">{scene}</visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#S"/></scene>
</COLLADA>"##
        )
    }

    fn assert_points(got: &[[f64; 3]], want: &[[f64; 3]]) {
        assert_eq!(got.len(), want.len(), "{got:?}");
        for (g, w) in got.iter().zip(want) {
            for k in 0..3 {
                assert!((g[k] - w[k]).abs() < 1e-12, "{got:?} != {want:?}");
            }
        }
    }

    #[test]
    fn dae_matrix_scale_and_translation() {
        // Millimetres scaled to metres and moved, as anymal_foot.dae does
        // (plus a translation); the never-placed geometry is left out.
        let dae = dae_with_scene(
            r##"<node id="cam"><matrix>1 0 0 7 0 1 0 8 0 0 1 9 0 0 0 1</matrix></node>
<node id="n"><matrix sid="transform">0.001 0 0 0.5
 0 0.001 0 -0.25
 0 0 0.001 2
 0 0 0 1</matrix>
<instance_geometry url="#tri"><bind_material/></instance_geometry></node>"##,
        );
        let p = read_dae_positions(&dae).unwrap();
        assert_points(
            &p,
            &[[0.501, -0.25, 2.0], [0.5, -0.248, 2.0], [0.5, -0.25, 2.003]],
        );
        // The unit applies after the node transform, translation included.
        let dae = dae.replace(r#"meter="1""#, r#"meter="0.5""#);
        let p = read_dae_positions(&dae).unwrap();
        assert_points(
            &p,
            &[
                [0.2505, -0.125, 1.0],
                [0.25, -0.124, 1.0],
                [0.25, -0.125, 1.0015],
            ],
        );
    }

    #[test]
    fn dae_nested_nodes_compose_in_order() {
        // parent: translate then rotate 90° about z; child: translate (1,0,0).
        // world = T(10,0,0) · Rz(90°) · T(1,0,0), so p -> (10 - (y), x + 1, z).
        let dae = dae_with_scene(
            r##"<node id="a"><translate>10 0 0</translate><rotate>0 0 1 90</rotate>
<node id="b"><translate>1 0 0</translate><instance_geometry url="#tri"/></node>
</node>"##,
        );
        let p = read_dae_positions(&dae).unwrap();
        assert_points(&p, &[[10.0, 2.0, 0.0], [8.0, 1.0, 0.0], [10.0, 1.0, 3.0]]);
        // Other order inside one node: rotate, then translate (in the rotated frame).
        let dae = dae_with_scene(
            r##"<node id="a"><rotate>0 0 1 90</rotate><translate>1 0 0</translate><scale>2 2 2</scale>
<instance_geometry url="#tri"/></node>"##,
        );
        let p = read_dae_positions(&dae).unwrap();
        assert_points(&p, &[[0.0, 3.0, 0.0], [-4.0, 1.0, 0.0], [0.0, 1.0, 6.0]]);
    }

    #[test]
    fn dae_geometry_placed_twice_gives_both() {
        let dae = dae_with_scene(
            r##"<node id="a"><translate>0 0 1</translate><instance_geometry url="#tri"/></node>
<node id="b"><translate>0 0 -1</translate><instance_geometry url="#tri"/></node>"##,
        );
        let p = read_dae_positions(&dae).unwrap();
        assert_points(
            &p,
            &[
                [1.0, 0.0, 1.0],
                [0.0, 2.0, 1.0],
                [0.0, 0.0, 4.0],
                [1.0, 0.0, -1.0],
                [0.0, 2.0, -1.0],
                [0.0, 0.0, 2.0],
            ],
        );
    }

    #[test]
    fn dae_instance_node_and_chosen_scene() {
        let dae = r##"<COLLADA>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa">1 2 3</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
</mesh></geometry></library_geometries>
<library_nodes><node id="lib"><scale>2 2 2</scale><instance_geometry url="#g"/></node></library_nodes>
<library_visual_scenes>
<visual_scene id="first"><node><instance_geometry url="#g"/></node></visual_scene>
<visual_scene id="second"><node><translate>0 0 10</translate><instance_node url="#lib"/></node></visual_scene>
</library_visual_scenes>
<scene><instance_visual_scene url="#second"/></scene></COLLADA>"##;
        assert_points(&read_dae_positions(dae).unwrap(), &[[2.0, 4.0, 16.0]]);
        // Without <scene>, the first visual scene.
        let first = dae.replace(
            r##"<scene><instance_visual_scene url="#second"/></scene>"##,
            "",
        );
        assert_points(&read_dae_positions(&first).unwrap(), &[[1.0, 2.0, 3.0]]);
        // A scene that places nothing: every POSITION array, untransformed.
        let none = dae.replace(r##"<instance_node url="#lib"/>"##, "");
        assert_points(&read_dae_positions(&none).unwrap(), &[[1.0, 2.0, 3.0]]);
        // An <instance_node> cycle is an error, not a hang.
        let cycle = dae.replace(
            r##"<instance_geometry url="#g"/></node></library_nodes>"##,
            r##"<instance_geometry url="#g"/><instance_node url="#lib"/></node></library_nodes>"##,
        );
        let e = read_dae_positions(&cycle).unwrap_err();
        assert!(e.contains("instance_node"), "{e}");
    }

    #[test]
    fn dae_bad_scene_graphs_are_errors() {
        let cases: &[(&str, &str)] = &[
            (
                r##"<node id="n"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0</matrix><instance_geometry url="#tri"/></node>"##,
                "<matrix> has 15 numbers, expected 16",
            ),
            (
                r##"<node id="n"><matrix/><instance_geometry url="#tri"/></node>"##,
                "<matrix> has 0 numbers",
            ),
            (
                r##"<node id="n"><translate>1 x 2</translate><instance_geometry url="#tri"/></node>"##,
                "<translate>: \"x\" is not a number",
            ),
            (
                r##"<node id="n"><scale>1 inf 2</scale><instance_geometry url="#tri"/></node>"##,
                "<scale> has a non-finite number",
            ),
            (
                r##"<node id="n"><rotate>0 0 0 30</rotate><instance_geometry url="#tri"/></node>"##,
                "<rotate> has a zero axis",
            ),
            (
                r##"<node id="n"><rotate>0 0 1 NaN</rotate><instance_geometry url="#tri"/></node>"##,
                "<rotate> has a non-finite number",
            ),
            (
                r##"<node id="n"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1</matrix><instance_geometry url="#tri"/></node>"##,
                "<matrix>: the last row is not 0 0 0 1",
            ),
            (
                r##"<node id="n"><instance_geometry url="#nowhere"/></node>"##,
                "<instance_geometry url=\"#nowhere\"> names no geometry",
            ),
            (
                r##"<node id="n"><instance_geometry url="other.dae#tri"/></node>"##,
                "only references inside the file",
            ),
            (
                r##"<node id="n"><instance_geometry/></node>"##,
                "<instance_geometry> has no url",
            ),
            (
                r##"<node id="n"><instance_node url="#nowhere"/></node>"##,
                "<instance_node url=\"#nowhere\"> names no node",
            ),
            (
                r##"<node id="n"><skew>45 1 0 0 0 1 0</skew><node><instance_geometry url="#tri"/></node></node>"##,
                "node \"n\": <skew> is not read",
            ),
        ];
        for (scene, want) in cases {
            let e = read_dae_positions(&dae_with_scene(scene)).unwrap_err();
            assert!(e.contains(want), "{scene}: {e}");
            if scene.contains("<matrix") {
                assert!(e.contains("node \"n\""), "{e}");
            }
        }
        // A scene url that names no scene; a bad unit.
        let e = read_dae_positions(&dae_with_scene("").replace("url=\"#S\"", "url=\"#T\""))
            .unwrap_err();
        assert!(
            e.contains("<instance_visual_scene url=\"#T\"> names no visual_scene"),
            "{e}"
        );
        let e = read_dae_positions(&dae_with_scene("").replace("meter=\"1\"", "meter=\"-2\""))
            .unwrap_err();
        assert!(e.contains("<unit meter=\"-2\">"), "{e}");
        // A camera node with a bad-free <lookat> and no geometry is fine.
        let ok = dae_with_scene(
            r##"<node id="cam"><lookat>0 0 1 0 0 0 0 1 0</lookat><instance_camera url="#c"/></node>
<node id="n"><instance_geometry url="#tri"/></node>"##,
        );
        assert_eq!(read_dae_positions(&ok).unwrap().len(), 3);
    }

    #[test]
    fn dae_empty_float_array_is_empty_not_missing() {
        // anymal_hip_l.dae has `<float_array id=".." count="0"/>` geometries.
        let dae = dae_with_scene(r##"<node><instance_geometry url="#e"/><instance_geometry url="#tri"/></node>"##)
            .replace(
                "</library_geometries>",
                r##"<geometry id="e"><mesh><source id="e-pos"><float_array id="e-pos-array" count="0"/></source>
<vertices id="e-v"><input semantic="POSITION" source="#e-pos"/></vertices></mesh></geometry></library_geometries>"##,
            );
        assert_eq!(read_dae_positions(&dae).unwrap().len(), 3);
    }

    #[test]
    fn dae_triangles_of_placed_polylists() {
        // A unit square as one quad (polylist, normals interleaved: stride 2) and
        // one triangle, placed twice: the second copy's indices start at 4.
        let dae = r##"<COLLADA><asset><unit meter="0.5"/></asset>
<library_geometries><geometry id="sq"><mesh>
<source id="p"><float_array id="pa">0 0 0 1 0 0 1 1 0 0 1 0</float_array></source>
<source id="n"><float_array id="na">0 0 1</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<polylist count="1"><input semantic="VERTEX" source="#v" offset="0"/>
<input semantic="NORMAL" source="#n" offset="1"/><vcount>4</vcount><p>0 0 1 0 2 0 3 0</p></polylist>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>3 2 1</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">
<node><instance_geometry url="#sq"/></node>
<node><translate>0 0 2</translate><instance_geometry url="#sq"/></node>
</visual_scene></library_visual_scenes></COLLADA>"##;
        let (p, t) = read_dae(dae).unwrap();
        assert_eq!(p.len(), 8);
        assert_eq!(p[6], [0.5, 0.5, 1.0]);
        assert_eq!(
            t,
            vec![
                [0, 1, 2],
                [0, 2, 3],
                [3, 2, 1],
                [4, 5, 6],
                [4, 6, 7],
                [7, 6, 5]
            ]
        );
        // The positions are those load_vertices reads.
        assert_eq!(read_dae_positions(dae).unwrap(), p);
        // An index past the positions is an error naming the primitive.
        let bad = dae.replace("<p>3 2 1</p>", "<p>3 2 9</p>");
        let e = read_dae(&bad).unwrap_err();
        assert!(e.contains("<triangles>: vertex index 9"), "{e}");
        // A position no primitive indexes is dropped (from the vertices and from
        // the triangles' numbering), in every placed copy.
        let extra = dae
            .replace("0 1 0</float_array>", "0 1 0 5 5 5</float_array>")
            .replace("<p>3 2 1</p>", "<p>3 2 1</p><p></p>");
        let (p2, t2) = read_dae(&extra).unwrap();
        assert_eq!((p2, t2), (p.clone(), t.clone()));
        // Without primitives a geometry's every position is kept.
        let bare = extra
            .split("<polylist")
            .next()
            .map(|head| {
                format!(
                    "{head}</mesh>{}",
                    extra.split("</triangles>\n</mesh>").nth(1).unwrap_or("")
                )
            })
            .unwrap();
        let (p3, t3) = read_dae(&bare).unwrap();
        assert_eq!((p3.len(), t3.len()), (10, 0), "{bare}");
    }

    #[test]
    fn dae_triangle_colours_from_bound_materials() {
        // Two primitives: "A" bound to material red (effect colour 1 0 0 1),
        // "B" naming material id blue directly (no binding; effect colour without
        // alpha), and a third whose effect has a texture (no colour).
        let dae = r##"<COLLADA><asset><unit meter="1"/></asset>
<library_effects>
<effect id="red-fx"><profile_COMMON><technique sid="c"><phong>
<emission><color>0 0 0 1</color></emission><diffuse><color sid="diffuse">1 0 0 1</color></diffuse>
</phong></technique></profile_COMMON></effect>
<effect id="blue-fx"><profile_COMMON><technique sid="c"><lambert><diffuse><color>0 0 0.5</color></diffuse></lambert></technique></profile_COMMON></effect>
<effect id="tex-fx"><profile_COMMON><technique sid="c"><lambert><diffuse><texture texture="img"/></diffuse></lambert></technique></profile_COMMON></effect>
</library_effects>
<library_materials>
<material id="red"><instance_effect url="#red-fx"/></material>
<material id="blue"><instance_effect url="#blue-fx"/></material>
<material id="tex"><instance_effect url="#tex-fx"/></material>
</library_materials>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa">0 0 0 1 0 0 1 1 0 0 1 0</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles material="A" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
<polylist material="blue" count="1"><input semantic="VERTEX" source="#v" offset="0"/><vcount>4</vcount><p>0 1 2 3</p></polylist>
<triangles material="tex" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 2 3</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">
<node><instance_geometry url="#g"><bind_material><technique_common>
<instance_material symbol="A" target="#red"/><instance_material symbol="tex" target="#tex"/>
</technique_common></bind_material></instance_geometry></node>
<node><translate>0 0 1</translate><instance_geometry url="#g"/></node>
</visual_scene></library_visual_scenes></COLLADA>"##;
        let d = read_dae_colored(dae).unwrap();
        let red = Some([1.0, 0.0, 0.0, 1.0]);
        let blue = Some([0.0, 0.0, 0.5, 1.0]);
        // first copy: red, blue ×2 (the quad), none; the second copy has no
        // bindings: "A" names no material, "blue" still does, "tex" has no colour
        assert_eq!(
            d.colors,
            vec![red, blue, blue, None, None, blue, blue, None]
        );
        assert_eq!(d.colors.len(), d.triangles.len());
        // the same triangles as read_dae gives
        assert_eq!(read_dae(dae).unwrap().1, d.triangles);
    }

    #[test]
    fn stl_and_obj_triangles() {
        let dir = tempfile::tempdir().unwrap();
        let stl = dir.path().join("t.stl");
        std::fs::write(
            &stl,
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n\
             facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
        )
        .unwrap();
        let m = load_mesh(&stl, [2.0, 1.0, 1.0]).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles.len(), 2);
        // The second triangle is (1,0,0), (1,1,0), (0,1,0), x scaled by 2.
        let corners: Vec<_> = m.triangles[1]
            .iter()
            .map(|&i| m.vertices[i as usize])
            .collect();
        assert_eq!(corners[0], Vector3::new(2.0, 0.0, 0.0));
        assert_eq!(corners[1], Vector3::new(2.0, 1.0, 0.0));
        assert_eq!(corners[2], Vector3::new(0.0, 1.0, 0.0));
        assert_eq!(load_vertices(&stl, [2.0, 1.0, 1.0]).unwrap(), m.vertices);

        let obj = dir.path().join("q.obj");
        std::fs::write(&obj, "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 5\nv 1 0 5\nv 0 1 5\nf 5 6 7\n").unwrap();
        let m = load_mesh(&obj, [1.0; 3]).unwrap();
        assert_eq!(m.vertices.len(), 7);
        assert_eq!(m.triangles.len(), 3);
        // The quad's two triangles cover its area (1), the last triangle is z = 5.
        let area = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            (b - a).cross(&(c - a)).norm() / 2.0
        };
        assert!((area(&m.triangles[0]) + area(&m.triangles[1]) - 1.0).abs() < 1e-12);
        assert!(m.triangles[2]
            .iter()
            .all(|&i| m.vertices[i as usize].z == 5.0));
    }

    #[test]
    fn missing_file_names_it() {
        let e = load_vertices(Path::new("/nonexistent/foot.stl"), [1.0; 3]).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/foot.stl"));
    }
}
