//! Scenes (`../shared/spec/scene.md`): several URDF or MJCF models, static obstacles
//! and an optional ground in one simulation. Import layer, beside
//! [`crate::urdf`]: a SCENE.json (or a [`SceneSpec`] built in code) is checked
//! key by key, its URDFs and SRDFs loaded, and the models joined into one
//! [`Model`] (a forest: one tree per model, names `MODEL/NAME`, q and v each
//! model in file order); obstacles become collision geometry on the world
//! (body 0). What the simulation needs besides (ground, friction, the starting
//! state, the pairs that never touch) is kept on the [`Scene`].

mod file;
mod forest;
mod initial;
mod load;
mod mjcf;
mod obstacles;
pub mod srdf;

pub use file::{
    BaseSpec, GroundSpec, HeightFieldSpec, InitialBaseSpec, InitialSpec, InitialValue, ModelSpec,
    ObstacleSpec, RoundSpec, SceneSpec,
};
pub use forest::{forest, Part};
pub use mjcf::mjcf_scene_json;

use crate::model::{Model, Shape};
use crate::spatial::Se3;
use nalgebra::DVector;
use std::path::{Path, PathBuf};

/// A bad scene: one line naming the scene file, the key path and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {key}: {message}")]
pub struct SceneError {
    /// The scene file (as given).
    pub file: String,
    /// The key path in it (`models[1].urdf`, `obstacles[0] (step)`).
    pub key: String,
    /// What is wrong.
    pub message: String,
    /// The path of a file that does not exist, when that is what is wrong.
    pub missing: Option<PathBuf>,
}

impl SceneError {
    fn new(file: &str, key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            key: key.into(),
            message: message.into(),
            missing: None,
        }
    }
}

/// The ground plane of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Height of the plane z = height (m).
    pub height: f64,
    /// Its side's friction coefficient.
    pub friction: f64,
    /// Torsional friction coefficient (m), if the scene sets one
    /// (docs/theory.md §"Torsional and rolling friction").
    pub torsion: Option<f64>,
    /// Rolling friction coefficient (m), if the scene sets one.
    pub rolling: Option<f64>,
}

/// One model of a loaded scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneModel {
    /// Its name (the prefix of its names).
    pub name: String,
    /// The URDF file, or the MJCF file when `mjcf` (resolved against the
    /// scene file's folder).
    pub urdf: PathBuf,
    /// Whether `urdf` is an MJCF file (the model is its whole world).
    pub mjcf: bool,
    /// Whether its root is on a free joint.
    pub floating: bool,
    /// `world_M_root` at the start.
    pub pose: Se3<f64>,
    /// Its links' friction coefficient.
    pub friction: f64,
    /// Contact between two of its links.
    pub self_collision: bool,
    /// Its SRDF's `<disable_collisions>` pairs that name two of its links
    /// (`MODEL/LINK` names).
    pub disabled: Vec<(String, String)>,
}

/// A static obstacle of a loaded scene (also a body-0 collision geometry of
/// [`Scene::model`] named as the obstacle).
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Its name.
    pub name: String,
    /// Its shape (a mesh's filename resolved against the scene file's folder).
    pub shape: Shape,
    /// `world_M_obstacle`.
    pub placement: Se3<f64>,
    /// Its friction coefficient.
    pub friction: f64,
}

/// A scene, loaded: the one [`Model`] of all its models, the obstacles (on the
/// world body), the ground, and the starting state.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The document as read (or built).
    pub spec: SceneSpec,
    /// The scene file's name in messages.
    pub file: String,
    /// The folder its relative paths are resolved against.
    pub base_dir: PathBuf,
    /// Every model as one forest (names `MODEL/NAME`), obstacles as world geometry.
    pub model: Model,
    /// The models in file order.
    pub models: Vec<SceneModel>,
    /// The obstacles in file order.
    pub obstacles: Vec<Obstacle>,
    /// The ground plane, if any.
    pub ground: Option<Ground>,
    /// Link pairs never in contact (`exclude`): `MODEL/LINK` or obstacle names.
    pub exclude: Vec<(String, String)>,
    /// The starting configuration (poses, `pose`, `initial`).
    pub q0: DVector<f64>,
    /// The starting velocity.
    pub v0: DVector<f64>,
    /// Constant generalized forces (`initial.tau`, `initial.base.force/torque`).
    pub tau0: DVector<f64>,
    /// What loaded but deserves a line (SRDF names the URDF lacks, ...).
    pub warnings: Vec<String>,
    /// The loop constraints (`"constraints"`), built against `model`; give
    /// them to [`crate::sim::Simulation::set_constraints`] after its start state.
    pub constraints: crate::model::Constraints,
}

fn read_text(path: &Path) -> Result<String, std::io::Error> {
    let bytes = std::fs::read(path)?;
    String::from_utf8(bytes)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

use load::Loader;

impl Scene {
    /// Reads and loads a SCENE.json; relative paths are taken against its folder,
    /// `package://` meshes against `package_paths` as in cli.md.
    pub fn from_file(
        path: impl AsRef<Path>,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        if path.is_dir() {
            return Err(SceneError::new(
                &name,
                "(file)",
                "is a directory, not a scene file",
            ));
        }
        let text = read_text(path).map_err(|e| {
            let mut err = SceneError::new(&name, "(file)", format!("cannot read: {e}"));
            if e.kind() == std::io::ErrorKind::NotFound {
                err.message = format!("file \"{name}\" not found");
                err.missing = Some(path.to_path_buf());
            }
            err
        })?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Self::from_json(&text, &name, &dir, package_paths)
    }

    /// The whole world of an MJCF file as a scene (mjcf.md §"Entry points"):
    /// the scene [`mjcf_scene_json`] writes for it, one model named after the
    /// file's stem, its names `STEM/NAME`.
    pub fn from_mjcf(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let text = mjcf_scene_json(path);
        Self::from_json(&text, &path.display().to_string(), &dir, &[])
    }

    /// Loads SCENE.json text; `file` names it in messages, `base_dir` resolves
    /// its relative paths.
    pub fn from_json(
        text: &str,
        file: &str,
        base_dir: &Path,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        let spec = file::parse_spec(text).map_err(|(k, m)| SceneError::new(file, k, m))?;
        Self::from_spec(spec, file, base_dir, package_paths)
    }

    /// Loads a scene built in code (the same checks as a file's).
    pub fn from_spec(
        spec: SceneSpec,
        file: &str,
        base_dir: &Path,
        package_paths: &[PathBuf],
    ) -> Result<Self, SceneError> {
        Loader {
            file,
            base_dir,
            package_paths,
        }
        .load(spec)
    }
}
