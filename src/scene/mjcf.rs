//! A scene's MJCF model (mjcf.md §"Entry points", scene.md §"More in a
//! scene"): `{"name": …, "mjcf": "file.xml", "position": …}` is the file's
//! whole world as `urdyn simulate file.xml` builds it (`crate::mjcf::
//! load_file_with_world`: its bodies, one tree per child of `<worldbody>`; its
//! static geoms, which stay obstacles in the forest; its upward-facing plane,
//! which becomes the scene's ground), placed by the model's pose. What a
//! scene cannot carry is never silently dropped: `<equality>` constraints are
//! an error (dropping them changes the motion), keyframes and the import
//! report's lines are warnings.

use super::file::ModelSpec;
use super::load::Loader;
use super::SceneError;
use crate::model::Model;
use crate::spatial::Se3;
use nalgebra::Vector3;
use std::path::PathBuf;

/// An MJCF model, loaded for a scene.
pub(super) struct MjcfModel {
    /// The model as `crate::mjcf::load_file` gives it.
    pub model: Model,
    /// The file, resolved against the scene's folder.
    pub path: PathBuf,
    /// The file's ground plane placed by the model's pose: (height, friction).
    pub ground: Option<(f64, f64)>,
}

/// A scene's ground from its MJCF models' planes and its `"ground"` key.
pub(super) struct Grounds {
    /// (model index, height, friction) of each MJCF model's ground plane.
    pub planes: Vec<(usize, f64, f64)>,
}

impl Loader<'_> {
    /// Loads `models[K]` (`key`) whose `"mjcf"` is `file`, placed at `pose`;
    /// the lines a scene reports go to `warnings`.
    pub(super) fn mjcf_model(
        &self,
        key: &str,
        m: &ModelSpec,
        file: &str,
        pose: &Se3<f64>,
        warnings: &mut Vec<String>,
    ) -> Result<MjcfModel, SceneError> {
        let refused = [
            (m.base.is_some(), "base", "which joints are free"),
            (m.srdf.is_some(), "srdf", "which bodies never touch"),
            (m.pose.is_some(), "pose", "the starting configuration"),
        ];
        for (given, k, what) in refused {
            if given {
                return Err(self.err(
                    format!("{key}.{k}"),
                    format!("\"{k}\" does not apply to an MJCF model (the file says {what})"),
                ));
            }
        }
        if m.initial.as_ref().is_some_and(|i| i.base.is_some()) {
            return Err(self.err(
                format!("{key}.initial.base"),
                "an MJCF model has no floating base: its free joints start where the file puts them, placed by the model's position and orientation_xyzw",
            ));
        }
        let k = format!("{key}.mjcf");
        let path = self.existing(&k, file)?;
        let (model, world) =
            crate::mjcf::load_file_with_world(&path).map_err(|e| self.err(&k, e.to_string()))?;
        let n = model.equalities.items.len();
        if n > 0 {
            return Err(self.err(
                &k,
                format!(
                    "{file}: its {n} <equality> constraint(s) cannot be carried into a scene yet (dropping them would change the motion)"
                ),
            ));
        }
        if !model.keyframes.is_empty() {
            warnings.push(format!(
                "{}: {k}: {file}: its {} <keyframe> key(s) are not carried (the model starts at the file's qpos0, placed by the model's pose; \"initial\" sets its joints)",
                self.file,
                model.keyframes.len()
            ));
        }
        for w in model.report.warnings.iter().chain(&model.report.ignored) {
            warnings.push(format!("{}: {k}: {file}: {w}", self.file));
        }
        // the ground plane, placed: it must stay horizontal
        let ground = match crate::mjcf::ground_of(&world) {
            None => None,
            Some(g) => {
                let up = pose.rot * Vector3::z();
                if (up.z - 1.0).abs() > 1e-9 {
                    return Err(self.err(
                        format!("{key}.orientation_xyzw"),
                        format!(
                            "tilts the ground plane of {file} (its normal would be [{:.6}, {:.6}, {:.6}]): a scene's ground is horizontal; turn the model about z only",
                            up.x, up.y, up.z
                        ),
                    ));
                }
                Some((pose.trans.z + g.height, g.friction))
            }
        };
        Ok(MjcfModel {
            model,
            path,
            ground,
        })
    }

    /// The scene's ground: the `"ground"` key's, else the MJCF models' planes
    /// (all at one height, or an error naming the model that differs).
    pub(super) fn merge_grounds(
        &self,
        ground: Option<super::Ground>,
        grounds: &Grounds,
        warnings: &mut Vec<String>,
    ) -> Result<Option<super::Ground>, SceneError> {
        let mut out = ground;
        let from_key = ground.is_some();
        for &(i, height, friction) in &grounds.planes {
            let key = format!("models[{i}].mjcf");
            match &out {
                None => {
                    out = Some(super::Ground {
                        height,
                        friction,
                        torsion: None,
                        rolling: None,
                    })
                }
                Some(g) if (g.height - height).abs() > 1e-9 => {
                    let other = if from_key {
                        "the scene's \"ground\"".to_string()
                    } else {
                        "another MJCF model's ground plane".to_string()
                    };
                    return Err(self.err(
                        key,
                        format!(
                            "the file's ground plane, placed, is at z = {height}, {other} at z = {}: a scene has one ground (move the model or the ground)",
                            g.height
                        ),
                    ));
                }
                Some(g) if g.friction != friction => warnings.push(format!(
                    "{}: {key}: the file's ground plane has friction {friction}; the scene's ground keeps {}",
                    self.file, g.friction
                )),
                Some(_) => {}
            }
        }
        Ok(out)
    }
}

/// The SCENE.json text of an MJCF file's whole world alone (mjcf.md §"Entry
/// points", Python's `Scene.from_mjcf`): one model named after the file's stem
/// (`ant` for ant.xml), its file by name, relative to the file's folder.
pub fn mjcf_scene_json(path: &std::path::Path) -> String {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .map(|s| s.trim().replace('/', "_"))
        .filter(|s| !s.is_empty() && !s.chars().any(char::is_control))
        .unwrap_or_else(|| "model".to_string());
    let file = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    serde_json::json!({"models": [{"name": stem, "mjcf": file}]}).to_string()
}
