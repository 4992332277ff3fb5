//! The page itself: the template with its style, script and data (the model's
//! frames, the visuals, the quantised meshes, the recorded frames) inlined.

use super::geometry::bounds;
use super::{Geometry, Recorder, VisualShape};
use crate::mesh::{Rgba, TriMesh};
use crate::Model;
use nalgebra::Matrix3;
use serde_json::{json, Value};
use std::collections::HashMap;

const PAGE_HTML: &str = include_str!("page.html");
const VIEWER_JS: &str = include_str!("viewer.js");
const VIEWER_CSS: &str = include_str!("viewer.css");

/// Standard base64 (with padding) of `bytes`.
pub(crate) fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let b = [
            c[0],
            c.get(1).copied().unwrap_or(0),
            c.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A rotation matrix row-major (nalgebra stores column-major: the transpose's storage).
fn rows9(r: &Matrix3<f64>) -> Vec<f64> {
    r.transpose().as_slice().to_vec()
}

/// The mesh quantised: 16 bits a coordinate over its bounding box, indices as
/// 16 bits when they fit (else 32). With triangle colours (`colors`, one a
/// triangle, or empty), the triangles are ordered by colour and `groups` lists
/// `[first index, index count, rgba or null]` per colour (null: the visual's).
fn mesh_json(m: &TriMesh, colors: &[Option<Rgba>]) -> Value {
    let (lo, hi) = bounds(m);
    let ext = (hi - lo).map(|e| if e > 0.0 { e } else { 1.0 });
    let mut v = Vec::with_capacity(m.vertices.len() * 6);
    for p in &m.vertices {
        for k in 0..3 {
            let q = ((p[k] - lo[k]) / ext[k] * 65535.0)
                .round()
                .clamp(0.0, 65535.0) as u16;
            v.extend_from_slice(&q.to_le_bytes());
        }
    }
    // colour groups in order of first appearance
    let key = |c: &Option<Rgba>| c.map(|c| c.map(f64::to_bits));
    let mut group_of: HashMap<Option<[u64; 4]>, usize> = HashMap::new();
    let mut palette: Vec<Option<Rgba>> = Vec::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let colored = colors.iter().any(Option::is_some);
    for t in 0..m.triangles.len() {
        let c = if colored {
            colors.get(t).copied().flatten()
        } else {
            None
        };
        let g = *group_of.entry(key(&c)).or_insert_with(|| {
            palette.push(c);
            members.push(Vec::new());
            palette.len() - 1
        });
        if let Some(list) = members.get_mut(g) {
            list.push(t);
        }
    }
    let wide = m.vertices.len() > 65536;
    let mut i = Vec::with_capacity(m.triangles.len() * if wide { 12 } else { 6 });
    let mut groups = Vec::new();
    let mut first = 0;
    for (c, list) in palette.iter().zip(&members) {
        for t in list.iter().filter_map(|&t| m.triangles.get(t)) {
            for &k in t {
                if wide {
                    i.extend_from_slice(&k.to_le_bytes());
                } else {
                    i.extend_from_slice(&(k as u16).to_le_bytes());
                }
            }
        }
        groups.push(json!([first, 3 * list.len(), c]));
        first += 3 * list.len();
    }
    let mut out = json!({
        "min": [lo.x, lo.y, lo.z],
        "ext": [ext.x, ext.y, ext.z],
        "v": base64(&v),
        "i": base64(&i),
        "wide": wide,
    });
    if colored {
        out["groups"] = Value::Array(groups);
    }
    out
}

/// The page's data (one JSON object the viewer reads).
fn page_data(model: &Model, geometry: &Geometry, rec: &Recorder, ground: Option<f64>) -> Value {
    let links: Vec<Value> = model
        .frames
        .iter()
        .map(|f| {
            json!({"name": f.name, "body": f.body,
                   "p": f.placement.trans.as_slice(), "R": rows9(&f.placement.rot)})
        })
        .collect();
    let visuals: Vec<Value> = geometry
        .visuals
        .iter()
        .map(|v| {
            let (kind, dims, mesh) = match &v.shape {
                VisualShape::Mesh(k) => ("mesh", vec![], Some(*k)),
                VisualShape::Box(s) => ("box", s.to_vec(), None),
                VisualShape::Cylinder { radius, length } => {
                    ("cylinder", vec![*radius, *length], None)
                }
                VisualShape::Capsule { radius, length } => {
                    ("capsule", vec![*radius, *length], None)
                }
                VisualShape::Sphere { radius } => ("sphere", vec![*radius], None),
                VisualShape::Ellipsoid { radii } => ("ellipsoid", radii.to_vec(), None),
            };
            json!({"link": v.link, "body": v.body, "p": v.placement.trans.as_slice(),
                   "R": rows9(&v.placement.rot), "kind": kind, "dims": dims,
                   "mesh": mesh, "rgba": v.rgba})
        })
        .collect();
    let f64s: Vec<u8> = rec.positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    let f32s: Vec<u8> = rec.rotations.iter().flat_map(|x| x.to_le_bytes()).collect();
    let series = |k: usize| -> Vec<Option<f64>> {
        rec.plot
            .iter()
            .map(|p| Some(p[k]).filter(|x| x.is_finite()))
            .collect()
    };
    let contacts = if rec.with_contacts {
        let arrows: Vec<u8> = rec
            .arrows
            .iter()
            .flat_map(|a| a.point.iter().chain(a.force.iter()).map(|&x| x as f32))
            .flat_map(f32::to_le_bytes)
            .collect();
        json!({"arrows": base64(&arrows), "offsets": rec.offsets})
    } else {
        Value::Null
    };
    json!({
        "robot": model.name,
        "ground": ground,
        "moving": rec.nmoving,
        "links": links,
        "visuals": visuals,
        "meshes": geometry
            .meshes
            .iter()
            .enumerate()
            .map(|(k, m)| mesh_json(m, geometry.mesh_colors.get(k).map(Vec::as_slice).unwrap_or_default()))
            .collect::<Vec<_>>(),
        "times": rec.times,
        "positions": base64(&f64s),
        "rotations": base64(&f32s),
        "energy": series(0),
        "contacts": series(1),
        "penetration": series(2),
        "contactForces": contacts,
        "loops": geometry.loops.iter().map(|l| json!({"name": l.name, "body1": l.body1,
            "p1": l.point1, "body2": l.body2, "p2": l.point2})).collect::<Vec<_>>(),
    })
}

/// Text safe inside HTML element content and attributes.
fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The whole page: the template with its style, script and data inlined.
pub fn page_html(
    model: &Model,
    geometry: &Geometry,
    rec: &Recorder,
    ground: Option<f64>,
) -> String {
    // JSON inside <script>: "</" only occurs in strings, where "<\/" means the same.
    let data = page_data(model, geometry, rec, ground)
        .to_string()
        .replace("</", "<\\/");
    let mut out = String::with_capacity(PAGE_HTML.len() + VIEWER_JS.len() + data.len() + 1024);
    let template = PAGE_HTML.replace("{{TITLE}}", &html_escape(&model.name));
    let mut rest = template.as_str();
    for (marker, text) in [
        ("{{CSS}}", VIEWER_CSS.to_string()),
        ("{{DATA}}", data),
        ("{{JS}}", VIEWER_JS.to_string()),
    ] {
        if let Some((head, tail)) = rest.split_once(marker) {
            out.push_str(head);
            out.push_str(&text);
            rest = tail;
        }
    }
    out.push_str(rest);
    out
}
