//! The COLLADA (`.dae`) reader of [`super`] (the module doc says what it reads):
//! the document walked with quick-xml, the scene graph placed, the primitives
//! triangulated, the materials' diffuse colours bound.

#[path = "dae_doc.rs"]
mod doc;

use super::dae_parts::{dae_local_ref, dae_snippet, keep_used, DaePrim, Mat4};
use super::Rgba;
use doc::{finish, DaeNode, DaeText, DaeVisualScene};
use std::collections::HashMap;

/// Most node visits the scene walk makes (`<instance_node>` can form cycles or
/// blow up exponentially).
const MAX_DAE_NODE_VISITS: usize = 1_000_000;
/// Most vertices the scene walk emits (one geometry can be instanced many times).
const MAX_DAE_VERTICES: usize = 5_000_000;

/// What [`read_dae_colored`] reads.
pub struct DaeMesh {
    /// The placed positions (m).
    pub positions: Vec<[f64; 3]>,
    /// The placed primitives' triangles, indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// One a triangle.
    pub colors: Vec<Option<Rgba>>,
}

/// Positions, triangles and triangle colours of a COLLADA document (see the
/// module doc).
pub(crate) fn read_dae_colored(text: &str) -> Result<DaeMesh, String> {
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
