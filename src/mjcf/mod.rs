//! MJCF import (MuJoCo's XML, /work/shared/spec/mjcf.md): **read** (quick-xml
//! into an element tree, `<include>` expanded) → **compile** (MuJoCo's compiler
//! where it decides numbers: defaults, frames, orientations, `fromto`, joints,
//! mass properties; a [`World`] in MuJoCo's order and ids) → **lower** (a
//! [`Model`]: several joints of one body become a chain of bodies, each joint
//! about its own anchor), with the import report's lines for what urdyn does not
//! model.
//!
//! Why an own reader and not `mjcf-rs` (dimforge's MJCF parser, 0.34): urdyn
//! already parses XML with quick-xml (no new crate to build; mjcf-rs brings glam
//! and its own tree), the import must refuse DOCTYPE and entity declarations and
//! read no file but the `<include>`d ones relative to the model (urdyn's rule for
//! untrusted XML), and every error must name the file, the element (by name or
//! line) and the attribute — a typed AST with defaults already folded in loses
//! the element's line and which attribute came from which class. What decides
//! numbers (MuJoCo's compiler: mass properties, frames, `fromto`, joint
//! composition) is urdyn's in either case: mjcf-rs stops at the AST.

mod actuators;
mod attrs;
mod collide;
mod compile;
mod convert;
mod equality;
mod geom;
mod inertia;
mod lower;
mod orient;
mod sections;
mod springdamper;
mod tendons;
mod world;
mod xml;

pub use actuators::MjActuator;
pub use collide::Ground;
pub use compile::{MjBody, MjGeom, MjGeomType, MjJoint, MjJointType, MjMesh, World};
pub use convert::{from_mujoco_qpos, from_mujoco_qvel, to_mujoco_qpos, to_mujoco_qvel};
pub use equality::{MjEqKind, MjEquality};
pub use sections::MjKey;
pub use xml::is_mjcf_text;

use crate::model::Model;
use compile::{Ctx, Settings};
use nalgebra::Vector3;
use std::path::Path;

/// An MJCF import error: the file, the element (by name, else line) and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {}{message}", element.as_ref().map(|e| format!("{e}: ")).unwrap_or_default())]
pub struct MjcfError {
    /// The file (the model, or the included file the element is in).
    pub file: String,
    /// The offending element (`<joint name="hip">`, `<geom> (line 12)`), if any.
    pub element: Option<String>,
    /// What is wrong (naming the attribute).
    pub message: String,
}

impl MjcfError {
    pub(crate) fn new(file: &str, element: Option<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            element,
            message: message.into(),
        }
    }
}

/// Whether the file at `path` is MJCF (its root element is `<mujoco>`), whatever
/// its extension. An unreadable file is not.
pub fn is_mjcf_file(path: &Path) -> bool {
    std::fs::read(path)
        .ok()
        .and_then(|b| String::from_utf8(b).ok())
        .is_some_and(|t| is_mjcf_text(&t))
}

fn read_text(path: &Path) -> Result<String, MjcfError> {
    let name = path.display().to_string();
    let meta = std::fs::metadata(path)
        .map_err(|e| MjcfError::new(&name, None, format!("cannot read file: {e}")))?;
    if meta.is_dir() {
        return Err(MjcfError::new(
            &name,
            None,
            "is a directory, not an MJCF file",
        ));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| MjcfError::new(&name, None, format!("cannot read file: {e}")))?;
    String::from_utf8(bytes).map_err(|_| MjcfError::new(&name, None, "not UTF-8 text"))
}

fn dir_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Reads and imports an MJCF file (includes relative to its directory).
pub fn load_file(path: impl AsRef<Path>) -> Result<Model, MjcfError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    let world = compile(&text, &path.display().to_string(), dir_of(path), Some(path))?;
    let mut model = lower::lower(&world)?;
    model.source = Some(path.to_path_buf());
    Ok(model)
}

/// Reads an MJCF file into both its [`Model`] and MuJoCo's compiled [`World`]
/// (what a simulation reads besides the model: planes, keyframes).
pub fn load_file_with_world(path: impl AsRef<Path>) -> Result<(Model, World), MjcfError> {
    let path = path.as_ref();
    let world = load_world(path)?;
    let mut model = lower::lower(&world)?;
    model.source = Some(path.to_path_buf());
    Ok((model, world))
}

/// The ground an MJCF world's planes give (the highest upward-facing plane
/// welded to the world), if any.
pub fn ground_of(world: &World) -> Option<Ground> {
    collide::ground(world).0
}

/// Imports MJCF text; `file` names it in errors, includes are read under `base_dir`.
pub fn load_str(text: &str, file: &str, base_dir: &Path) -> Result<Model, MjcfError> {
    let world = compile_str(text, file, base_dir)?;
    lower::lower(&world)
}

/// MuJoCo's compiled world of an MJCF file (bodies, joints, geoms in MuJoCo's ids).
pub fn load_world(path: impl AsRef<Path>) -> Result<World, MjcfError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    compile(&text, &path.display().to_string(), dir_of(path), Some(path))
}

const SECTIONS: &[&str] = &[
    "compiler",
    "option",
    "size",
    "visual",
    "statistic",
    "default",
    "extension",
    "custom",
    "asset",
    "worldbody",
    "contact",
    "equality",
    "deformable",
    "tendon",
    "actuator",
    "sensor",
    "keyframe",
];

/// Reads and compiles MJCF text into MuJoCo's compiled [`World`].
pub fn compile_str(text: &str, file: &str, base_dir: &Path) -> Result<World, MjcfError> {
    compile(text, file, base_dir, None)
}

fn compile(
    text: &str,
    file: &str,
    base_dir: &Path,
    main: Option<&Path>,
) -> Result<World, MjcfError> {
    let root = xml::read(text, file, base_dir, main)?;
    for c in &root.children {
        if !SECTIONS.contains(&c.tag.as_str()) {
            return Err(c.err(format!("unknown element <{}> in <mujoco>", c.tag)));
        }
    }
    let of = |tag: &'static str| root.children.iter().filter(move |c| c.tag == tag);
    let defaults = attrs::Defaults::read(&of("default").collect::<Vec<_>>())?;
    let set = settings(&of("compiler").collect::<Vec<_>>(), &defaults)?;
    sections::asset_files(
        &of("asset").collect::<Vec<_>>(),
        &of("compiler").collect::<Vec<_>>(),
        base_dir,
    )?;
    let mut cx = Ctx {
        set,
        defaults: &defaults,
        world: World {
            name: root.attr("model").unwrap_or("MuJoCo Model").to_string(),
            bodies: vec![MjBody {
                name: "world".into(),
                parent: 0,
                pos: Vector3::zeros(),
                quat: nalgebra::UnitQuaternion::identity(),
                joints: 0..0,
                mass: 0.0,
                com: Vector3::zeros(),
                inertia: nalgebra::Matrix3::zeros(),
                sites: Vec::new(),
                explicit: None,
            }],
            joints: Vec::new(),
            geoms: Vec::new(),
            gravity: Vector3::new(0.0, 0.0, -9.81),
            timestep: 0.002,
            contact_disabled: false,
            excludes: Vec::new(),
            keys: Vec::new(),
            actuators: Vec::new(),
            tendons: Vec::new(),
            equalities: Vec::new(),
            meshes: sections::meshes(
                &of("asset").collect::<Vec<_>>(),
                &of("compiler").collect::<Vec<_>>(),
                base_dir,
                &defaults,
            )?,
            warnings: Vec::new(),
        },
        names: Default::default(),
        not_modelled: Vec::new(),
        materials: sections::materials(&of("asset").collect::<Vec<_>>(), &defaults)?,
    };
    options(&mut cx, &of("option").collect::<Vec<_>>())?;
    let origin = (Vector3::zeros(), nalgebra::UnitQuaternion::identity());
    for wb in of("worldbody") {
        compile::walk_children(&mut cx, wb, 0, "main", origin)?;
    }
    let mut world = cx.world;
    inertia::bodies(&mut world, &cx.set);
    tendons::read(
        &mut world,
        &of("tendon").collect::<Vec<_>>(),
        &defaults,
        cx.set.autolimits,
        &mut cx.not_modelled,
    )?;
    actuators::read(
        &mut world,
        &of("actuator").collect::<Vec<_>>(),
        &defaults,
        cx.set.autolimits,
        &mut cx.not_modelled,
    )?;
    equality::read(
        &mut world,
        &of("equality").collect::<Vec<_>>(),
        &defaults,
        &mut cx.not_modelled,
    )?;
    sections::keyframes(&mut world, &of("keyframe").collect::<Vec<_>>())?;
    sections::contacts(
        &mut world,
        &of("contact").collect::<Vec<_>>(),
        &mut cx.not_modelled,
    )?;
    for (tag, what) in [("sensor", "sensors: not modelled (urdyn has its own)")] {
        if of(tag).any(|s| !s.children.is_empty()) {
            cx.not_modelled.push(what.to_string());
        }
    }
    cx.not_modelled.sort();
    world.warnings = cx.not_modelled;
    Ok(world)
}

const COMPILER_ATTRS: &[&str] = &[
    "autolimits",
    "boundmass",
    "boundinertia",
    "settotalmass",
    "balanceinertia",
    "strippath",
    "coordinate",
    "angle",
    "fitaabb",
    "eulerseq",
    "meshdir",
    "texturedir",
    "assetdir",
    "discardvisual",
    "usethread",
    "fusestatic",
    "inertiafromgeom",
    "inertiagrouprange",
    "saveinertial",
    "alignfree",
    "convexhull",
];

fn settings(els: &[&xml::El], defaults: &attrs::Defaults) -> Result<Settings, MjcfError> {
    let mut s = Settings {
        degree: true,
        eulerseq: *b"xyz",
        autolimits: true,
        inertia_from_geom: None,
        group_range: (0, 5),
        settotalmass: -1.0,
        balanceinertia: false,
        boundmass: 0.0,
        boundinertia: 0.0,
    };
    for el in els {
        let a = defaults.resolve(el, "main")?;
        a.check_known(COMPILER_ATTRS)?;
        if let Some(v) = a.get("angle") {
            s.degree = match v {
                "degree" => true,
                "radian" => false,
                _ => return Err(a.err("angle", "must be degree or radian")),
            };
        }
        if let Some(v) = a.get("coordinate")
            && v != "local"
        {
            return Err(a.err("coordinate", "only local coordinates exist in MuJoCo 4"));
        }
        if let Some(v) = a.get("eulerseq") {
            let b = v.as_bytes();
            if b.len() != 3 || !b.iter().all(|c| b"xyzXYZ".contains(c)) {
                return Err(a.err("eulerseq", "must be three of x, y, z, X, Y, Z"));
            }
            s.eulerseq = [b[0], b[1], b[2]];
        }
        if let Some(v) = a.flag("autolimits")? {
            s.autolimits = v;
        }
        if let Some(v) = a.get("inertiafromgeom") {
            s.inertia_from_geom = match v {
                "true" => Some(true),
                "false" => Some(false),
                "auto" => None,
                _ => return Err(a.err("inertiafromgeom", "must be true, false or auto")),
            };
        }
        if let Some(v) = a.numbers("inertiagrouprange")? {
            match v.as_slice() {
                [lo, hi] if lo.fract() == 0.0 && hi.fract() == 0.0 => {
                    s.group_range = (*lo as i64, *hi as i64)
                }
                _ => return Err(a.err("inertiagrouprange", "needs two integers")),
            }
        }
        if let Some(v) = a.num("settotalmass")? {
            s.settotalmass = v;
        }
        if let Some(v) = a.flag("balanceinertia")? {
            s.balanceinertia = v;
        }
        s.boundmass = a.nonneg("boundmass", s.boundmass)?;
        s.boundinertia = a.nonneg("boundinertia", s.boundinertia)?;
    }
    Ok(s)
}

fn options(cx: &mut Ctx, els: &[&xml::El]) -> Result<(), MjcfError> {
    for el in els {
        let a = cx.defaults.resolve(el, "main")?;
        if let Some(g) = a.arr::<3>("gravity")? {
            cx.world.gravity = Vector3::from(g);
        }
        if let Some(t) = a.num("timestep")? {
            if t <= 0.0 {
                return Err(a.err("timestep", "must be positive"));
            }
            cx.world.timestep = t;
        }
        if let Some(i) = a.get("integrator") {
            cx.not_modelled.push(format!(
                "<option integrator=\"{i}\">: urdyn integrates with its own"
            ));
        }
        // MuJoCo's fluid forces (density and viscosity of the medium, wind): urdyn's
        // bodies move in vacuum, so a non-zero medium is reported, not silently dropped.
        for key in ["density", "viscosity"] {
            if let Some(v) = a.num(key)? {
                if v != 0.0 {
                    cx.not_modelled.push(format!(
                        "<option {key}=\"{v}\">: fluid forces (urdyn's bodies move in vacuum)"
                    ));
                }
            }
        }
        if let Some(w) = a.arr::<3>("wind")? {
            if w != [0.0; 3] {
                cx.not_modelled
                    .push("<option wind>: fluid forces (urdyn's bodies move in vacuum)".into());
            }
        }
        for f in el.children.iter().filter(|c| c.tag == "flag") {
            if f.attr("gravity") == Some("disable") {
                cx.world.gravity = Vector3::zeros();
            }
            if f.attr("contact") == Some("disable") {
                cx.world.contact_disabled = true;
            }
        }
    }
    Ok(())
}
