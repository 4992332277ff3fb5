//! The sections a simulation reads besides the bodies: `<contact><exclude>`
//! (body pairs that never touch) and `<keyframe><key>` (named starting states in
//! MuJoCo's qpos/qvel order), checked against the compiled bodies and joints.

use super::compile::{MjJointType, World};
use super::xml::El;
use super::MjcfError;

/// A `<key>`: MuJoCo's qpos and qvel (MuJoCo's order and conventions; `None`:
/// qpos0, zero velocity).
#[derive(Clone, Debug, PartialEq)]
pub struct MjKey {
    /// Its name (`key_K` when unnamed, K its MuJoCo id).
    pub name: String,
    /// MuJoCo's qpos (nq), if given.
    pub qpos: Option<Vec<f64>>,
    /// MuJoCo's qvel (nv), if given.
    pub qvel: Option<Vec<f64>>,
    /// MuJoCo's ctrl (nu), if given.
    pub ctrl: Option<Vec<f64>>,
}

const KEY_ATTRS: &[&str] = &[
    "name", "time", "qpos", "qvel", "act", "ctrl", "mpos", "mquat",
];
const EXCLUDE_ATTRS: &[&str] = &["name", "body1", "body2"];

/// MuJoCo's nq and nv of the compiled joints.
fn sizes(world: &World) -> (usize, usize) {
    world.joints.iter().fold((0, 0), |(q, v), j| match j.kind {
        MjJointType::Free => (q + 7, v + 6),
        MjJointType::Ball => (q + 4, v + 3),
        MjJointType::Hinge | MjJointType::Slide => (q + 1, v + 1),
    })
}

fn check_known(el: &El, known: &[&str]) -> Result<(), MjcfError> {
    match el.attrs.iter().find(|(k, _)| !known.contains(&k.as_str())) {
        Some((k, _)) => Err(el.err(format!("unknown attribute \"{k}\""))),
        None => Ok(()),
    }
}

fn numbers(el: &El, k: &str) -> Result<Option<Vec<f64>>, MjcfError> {
    let Some(s) = el.attr(k) else {
        return Ok(None);
    };
    s.split_whitespace()
        .map(|p| match p.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(el.err(format!("{k}: \"{p}\" is not a finite number"))),
            Err(_) => Err(el.err(format!("{k}: \"{p}\" is not numeric"))),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}

/// Reads the `<keyframe>` sections' keys into `world.keys`.
pub(super) fn keyframes(world: &mut World, sections: &[&El]) -> Result<(), MjcfError> {
    let (nq, nv) = sizes(world);
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        if el.tag != "key" {
            return Err(el.err(format!("unknown element <{}> in <keyframe>", el.tag)));
        }
        check_known(el, KEY_ATTRS)?;
        let qpos = numbers(el, "qpos")?;
        let qvel = numbers(el, "qvel")?;
        let ctrl = numbers(el, "ctrl")?;
        let nu = world.actuators.len();
        for (k, v, n) in [
            ("qpos", &qpos, nq),
            ("qvel", &qvel, nv),
            ("ctrl", &ctrl, nu),
        ] {
            if let Some(v) = v
                && v.len() != n
            {
                return Err(el.err(format!(
                    "{k} has {} numbers, the model's {k} has {n}",
                    v.len()
                )));
            }
        }
        let name = match el.attr("name") {
            Some(n) if !n.is_empty() => n.to_string(),
            _ => format!("key_{}", world.keys.len()),
        };
        if world.keys.iter().any(|k| k.name == name) {
            return Err(el.err("duplicate keyframe name"));
        }
        world.keys.push(MjKey {
            name,
            qpos,
            qvel,
            ctrl,
        });
    }
    Ok(())
}

/// Reads the `<contact>` sections' `<exclude>`s into `world.excludes`; a
/// `<pair>` is reported as not modelled.
pub(super) fn contacts(
    world: &mut World,
    sections: &[&El],
    not_modelled: &mut Vec<String>,
) -> Result<(), MjcfError> {
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        match el.tag.as_str() {
            "exclude" => {
                check_known(el, EXCLUDE_ATTRS)?;
                let body = |k: &str| -> Result<usize, MjcfError> {
                    let n = el
                        .attr(k)
                        .ok_or_else(|| el.err(format!("{k}: missing (a body name)")))?;
                    world
                        .bodies
                        .iter()
                        .position(|b| b.name == n)
                        .ok_or_else(|| el.err(format!("{k}=\"{n}\": no such body")))
                };
                let pair = (body("body1")?, body("body2")?);
                world.excludes.push(pair);
            }
            "pair" => {
                let line = "<contact><pair>: explicit contact pairs are not modelled (the geoms' contype/conaffinity decide)".to_string();
                if !not_modelled.contains(&line) {
                    not_modelled.push(line);
                }
            }
            t => return Err(el.err(format!("unknown element <{t}> in <contact>"))),
        }
    }
    Ok(())
}

/// Checks that every `<asset>` `<mesh>` and `<hfield>` file exists (relative to
/// `meshdir`, else `assetdir`, else the model's directory, as MuJoCo resolves
/// them): a missing one is an error naming the asset and its `file`.
pub(super) fn asset_files(
    sections: &[&El],
    compilers: &[&El],
    base_dir: &std::path::Path,
) -> Result<(), MjcfError> {
    let dir_of = |k: &str| compilers.iter().rev().find_map(|c| c.attr(k));
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        let dir = match el.tag.as_str() {
            "mesh" | "skin" => dir_of("meshdir").or_else(|| dir_of("assetdir")),
            "hfield" => dir_of("assetdir"),
            _ => continue,
        };
        let Some(file) = el.attr("file") else {
            continue;
        };
        let path = match dir {
            Some(d) => base_dir.join(d).join(file),
            None => base_dir.join(file),
        };
        if !path.is_file() {
            return Err(el.err(format!(
                "file=\"{file}\": cannot read {} (no such file)",
                path.display()
            )));
        }
    }
    Ok(())
}

/// `<asset><mesh>`es by name (`name`, else the file name without its
/// extension, as MuJoCo names them), their files resolved as [`asset_files`]
/// does and their `scale` with class defaults applied.
pub(super) fn meshes(
    sections: &[&El],
    compilers: &[&El],
    base_dir: &std::path::Path,
    defaults: &super::attrs::Defaults,
) -> Result<std::collections::HashMap<String, super::world::MjMesh>, MjcfError> {
    let dir_of = |k: &str| compilers.iter().rev().find_map(|c| c.attr(k));
    let dir = dir_of("meshdir").or_else(|| dir_of("assetdir"));
    let mut out = std::collections::HashMap::new();
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        if el.tag != "mesh" {
            continue;
        }
        let a = defaults.resolve(el, "main")?;
        let file = el.attr("file");
        let name = match (el.attr("name"), file) {
            (Some(n), _) => n.to_string(),
            (None, Some(f)) => {
                let f = std::path::Path::new(f);
                f.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            }
            (None, None) => continue,
        };
        let file = file.map(|f| match dir {
            Some(d) => base_dir.join(d).join(f),
            None => base_dir.join(f),
        });
        let scale = a.partial::<3>("scale", [1.0; 3])?;
        if scale.iter().any(|x| !x.is_finite()) {
            return Err(a.err("scale", "must be finite"));
        }
        use crate::mesh::MeshInertia;
        let inertia = match a.get("inertia").unwrap_or("legacy") {
            "legacy" => MeshInertia::Legacy,
            "exact" => MeshInertia::Exact,
            "convex" => MeshInertia::Convex,
            "shell" => MeshInertia::Shell,
            v => {
                return Err(a.err(
                    "inertia",
                    format!("\"{v}\" is not legacy, exact, convex or shell"),
                ))
            }
        };
        out.insert(
            name,
            super::world::MjMesh {
                file,
                scale,
                inertia,
            },
        );
    }
    Ok(out)
}

/// `<asset><material>` colours by name (`rgba`, MuJoCo's default white; class
/// defaults applied), for the geoms that name them.
pub(super) fn materials(
    sections: &[&El],
    defaults: &super::attrs::Defaults,
) -> Result<std::collections::HashMap<String, [f64; 4]>, MjcfError> {
    let mut out = std::collections::HashMap::new();
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        if el.tag != "material" {
            continue;
        }
        let Some(name) = el.attr("name") else {
            continue;
        };
        let a = defaults.resolve(el, "main")?;
        out.insert(name.to_string(), a.partial::<4>("rgba", [1.0; 4])?);
    }
    Ok(out)
}
