//! The document pieces of the COLLADA reader ([`super`]): the scene graph's
//! nodes and visual scenes as read, what collected text belongs to, and how
//! that text is stored when its element ends.

use super::super::dae_parts::{dae_snippet, dae_transform, Mat4};
use super::super::Rgba;
use std::collections::HashMap;

/// A `<node>` of a visual scene or of `<library_nodes>`.
pub(super) struct DaeNode {
    /// `id`, else `name`, for messages.
    pub(super) label: String,
    /// Product of the node's transform elements, in document order.
    pub(super) local: Mat4,
    /// A transform element that is not applied (`skew`, `lookat`).
    pub(super) unsupported: Option<&'static str>,
    /// `<instance_geometry url>`s.
    pub(super) geometries: Vec<String>,
    /// Per `<instance_geometry>`: its `<instance_material symbol>` → `target` id.
    pub(super) bindings: Vec<HashMap<String, String>>,
    /// `<instance_node url>`s.
    pub(super) instances: Vec<String>,
    pub(super) children: Vec<usize>,
}

pub(super) struct DaeVisualScene {
    pub(super) id: Option<String>,
    pub(super) roots: Vec<usize>,
}

/// What the text being collected belongs to.
pub(super) enum DaeText {
    /// A `<float_array id>`.
    Array(String),
    /// A transform element (`matrix`, `translate`, `rotate`, `scale`) of a node.
    Transform(&'static str, usize),
    /// A `<vcount>` or `<p>` of the primitive being read.
    Indices(&'static str),
    /// The `<diffuse><color>` of an `<effect id>`.
    Color(String),
}

/// Ends the text being collected, `collecting`, into its array or node (or,
/// for a colour, into `colors`).
pub(super) fn finish(
    collecting: DaeText,
    buf: &str,
    arrays: &mut HashMap<String, Vec<f64>>,
    nodes: &mut [DaeNode],
    colors: &mut HashMap<String, Rgba>,
) -> Result<(), String> {
    match collecting {
        DaeText::Array(id) => {
            let vals: Result<Vec<f64>, _> = buf.split_whitespace().map(str::parse::<f64>).collect();
            let vals = vals
                .map_err(|_| format!("float_array \"{}\": not a number list", dae_snippet(&id)))?;
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
}
