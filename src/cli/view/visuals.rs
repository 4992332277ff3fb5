//! The drawable elements of a URDF: every `<link>`'s `<visual>` and `<collision>`
//! (origin, geometry, material) and the top-level `<material>` colours, read with
//! quick-xml. The import keeps going past visual elements it cannot use (no dynamics
//! reads them), and so does this reader: a malformed piece is left out with a
//! warning naming the link and the element.

use crate::model::Shape;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use quick_xml::events::{BytesStart, Event};
use std::collections::HashMap;

/// A `<visual>` or `<collision>` element.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// `link_M_piece`: rotation and translation.
    pub rot: Matrix3<f64>,
    /// (m, link frame).
    pub xyz: Vector3<f64>,
    /// The `<geometry>`.
    pub shape: Shape,
    /// `<material name>` of a visual.
    pub material: Option<String>,
    /// `<material><color rgba>` of a visual.
    pub color: Option<[f64; 4]>,
}

/// A link's pieces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinkPieces {
    /// `<link name>`.
    pub name: String,
    /// Its `<visual>`s, in file order.
    pub visuals: Vec<Piece>,
    /// Its `<collision>`s, in file order.
    pub collisions: Vec<Piece>,
}

/// What a URDF draws: its links' pieces, the named material colours and the
/// warnings about pieces left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Drawables {
    /// In file order.
    pub links: Vec<LinkPieces>,
    /// The top-level `<material>`s' colours by name.
    pub materials: HashMap<String, [f64; 4]>,
    /// One line a piece left out.
    pub warnings: Vec<String>,
}

/// The piece being read.
#[derive(Default)]
struct Open {
    visual: bool,
    rot: Option<Matrix3<f64>>,
    xyz: Option<Vector3<f64>>,
    shape: Option<Shape>,
    material: Option<String>,
    color: Option<[f64; 4]>,
    /// Why the piece is left out.
    bad: Option<String>,
}

fn attr(e: &BytesStart, key: &[u8]) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.local_name().as_ref() == key)
        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
}

/// `n` finite numbers from an attribute's text.
fn numbers<const N: usize>(text: &str) -> Option<[f64; N]> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|s| s.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// The numbers of attribute `key` of `e` (`default` when it is absent), or the
/// reason they are unusable.
fn numbers_attr<const N: usize>(
    e: &BytesStart,
    element: &str,
    key: &str,
    default: Option<[f64; N]>,
) -> Result<[f64; N], String> {
    match attr(e, key.as_bytes()) {
        Some(text) => numbers::<N>(&text).ok_or_else(|| {
            format!(
                "<{element} {key}=\"{}\">: not {N} finite numbers",
                text.trim()
            )
        }),
        None => default.ok_or_else(|| format!("<{element}> has no {key}")),
    }
}

/// The shape element `e` (named `name`) of a `<geometry>`.
fn shape(e: &BytesStart, name: &str) -> Result<Option<Shape>, String> {
    let size = |key: &str| -> Result<f64, String> {
        let [x] = numbers_attr::<1>(e, name, key, None)?;
        if x < 0.0 {
            return Err(format!("<{name} {key}=\"{x}\">: negative"));
        }
        Ok(x)
    };
    Ok(Some(match name {
        "box" => {
            let s = numbers_attr::<3>(e, name, "size", None)?;
            if s.iter().any(|x| *x < 0.0) {
                return Err("<box size>: negative".into());
            }
            Shape::Box { size: s }
        }
        "cylinder" => Shape::Cylinder {
            radius: size("radius")?,
            length: size("length")?,
        },
        "capsule" => Shape::Capsule {
            radius: size("radius")?,
            length: size("length")?,
        },
        "sphere" => Shape::Sphere {
            radius: size("radius")?,
        },
        "mesh" => {
            let file = attr(e, b"filename").ok_or("<mesh> has no filename")?;
            Shape::Mesh {
                filename: file,
                scale: numbers_attr::<3>(e, name, "scale", Some([1.0; 3]))?,
            }
        }
        _ => return Ok(None),
    }))
}

/// Reads the drawable elements of URDF text (already accepted by the import, so
/// well-formed XML without entities; an XML error here is still an error).
pub(crate) fn read(text: &str) -> Result<Drawables, String> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = Drawables::default();
    let mut stack: Vec<String> = Vec::new();
    let mut link: Option<LinkPieces> = None;
    let mut piece: Option<Open> = None;
    // the top-level <material> being read
    let mut material: Option<String> = None;
    loop {
        let ev = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML: {e}"))?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let start = matches!(ev, Event::Start(_));
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                let depth = stack.len();
                let parent = stack.last().map(String::as_str);
                match (depth, name.as_str()) {
                    (1, "link") => {
                        let l = LinkPieces {
                            name: attr(e, b"name").unwrap_or_default(),
                            ..LinkPieces::default()
                        };
                        if start {
                            link = Some(l);
                        } else {
                            out.links.push(l);
                        }
                    }
                    (1, "material") => {
                        material = attr(e, b"name").filter(|_| start);
                    }
                    (2, "color") if parent == Some("material") => {
                        if let (Some(m), Some(c)) = (&material, attr(e, b"rgba")) {
                            if let Some(c) = numbers::<4>(&c) {
                                out.materials.insert(m.clone(), c);
                            }
                        }
                    }
                    (2, kind @ ("visual" | "collision")) if link.is_some() => {
                        let mut open = Open {
                            visual: kind == "visual",
                            ..Open::default()
                        };
                        if !start {
                            open.bad = Some("has no <geometry>".into());
                        }
                        piece = Some(open);
                        if !start {
                            finish(&mut piece, &mut link, &mut out.warnings);
                        }
                    }
                    (3, "origin") => {
                        if let Some(p) = piece.as_mut() {
                            let xyz = numbers_attr::<3>(e, "origin", "xyz", Some([0.0; 3]));
                            let rot = match (attr(e, b"rpy"), attr(e, b"quat_xyzw")) {
                                (_, Some(q)) => numbers::<4>(&q)
                                    .and_then(|[x, y, z, w]| {
                                        UnitQuaternion::try_new(Quaternion::new(w, x, y, z), 1e-12)
                                    })
                                    .map(|q| q.to_rotation_matrix().into_inner())
                                    .ok_or_else(|| {
                                        format!(
                                            "<origin quat_xyzw=\"{}\">: not a quaternion",
                                            q.trim()
                                        )
                                    }),
                                (rpy, None) => {
                                    let text = rpy.unwrap_or_else(|| "0 0 0".into());
                                    numbers::<3>(&text)
                                        .map(|[r, p, y]| crate::spatial::rpy_to_matrix(r, p, y))
                                        .ok_or_else(|| {
                                            format!(
                                                "<origin rpy=\"{}\">: not 3 finite numbers",
                                                text.trim()
                                            )
                                        })
                                }
                            };
                            match (xyz, rot) {
                                (Ok(x), Ok(r)) => {
                                    p.xyz = Some(Vector3::from(x));
                                    p.rot = Some(r);
                                }
                                (Err(m), _) | (_, Err(m)) => {
                                    p.bad.get_or_insert(m);
                                }
                            }
                        }
                    }
                    (4, _) if parent == Some("geometry") => {
                        if let Some(p) = piece.as_mut() {
                            match shape(e, &name) {
                                Ok(Some(s)) => p.shape = Some(s),
                                Ok(None) => {
                                    p.bad.get_or_insert(format!(
                                        "<geometry><{name}> is not a shape this viewer draws"
                                    ));
                                }
                                Err(m) => {
                                    p.bad.get_or_insert(m);
                                }
                            }
                        }
                    }
                    (3, "material") => {
                        if let Some(p) = piece.as_mut() {
                            p.material = attr(e, b"name").filter(|n| !n.is_empty());
                        }
                    }
                    (4, "color") if parent == Some("material") => {
                        if let Some(p) = piece.as_mut() {
                            p.color = attr(e, b"rgba").and_then(|c| numbers::<4>(&c));
                        }
                    }
                    _ => {}
                }
                if start {
                    stack.push(name);
                }
            }
            Event::End(_) => {
                let name = stack.pop().unwrap_or_default();
                match (stack.len(), name.as_str()) {
                    (1, "link") => {
                        if let Some(l) = link.take() {
                            out.links.push(l);
                        }
                    }
                    (1, "material") => material = None,
                    (2, "visual" | "collision") => finish(&mut piece, &mut link, &mut out.warnings),
                    _ => {}
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(out)
}

/// Ends the open piece: onto its link, or a warning when it is unusable.
fn finish(piece: &mut Option<Open>, link: &mut Option<LinkPieces>, warnings: &mut Vec<String>) {
    let (Some(p), Some(l)) = (piece.take(), link.as_mut()) else {
        return;
    };
    let element = if p.visual { "visual" } else { "collision" };
    let bad = p
        .bad
        .or_else(|| p.shape.is_none().then(|| "has no <geometry> shape".into()));
    match (bad, p.shape) {
        (None, Some(shape)) => {
            let piece = Piece {
                rot: p.rot.unwrap_or_else(Matrix3::identity),
                xyz: p.xyz.unwrap_or_else(Vector3::zeros),
                shape,
                material: p.material,
                color: p.color,
            };
            if p.visual {
                l.visuals.push(piece);
            } else {
                l.collisions.push(piece);
            }
        }
        (bad, _) => warnings.push(format!(
            "link \"{}\": <{element}> {}: not drawn",
            l.name,
            bad.unwrap_or_default()
        )),
    }
}
