//! `urdyn.Scene` (python.md §"Scenes"): a scene file's models, obstacles and
//! ground as one `Model` (names `MODEL/NAME`), its starting state, and the
//! options a `Simulation(scene)` / `rollout(scene, ...)` takes from it. A scene
//! pickles as its JSON text and the folder its paths are resolved against.

use crate::args::value_error;
use crate::introspect::{link_inertials, mjcf_inertials};
use crate::model::{PyModel, Rebuild};
use numpy::PyArray1;
use pyo3::exceptions::PyFileNotFoundError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::PathBuf;
use std::sync::Arc;
use urdyn::nalgebra::Vector3;
use urdyn::scene::{Scene, SceneError};

/// A scene (`Scene.from_file(path)`, `Scene.from_json(text, base_dir=None)`,
/// `Scene.from_mjcf(path)`).
#[pyclass(name = "Scene", module = "urdyn")]
#[derive(Clone)]
pub struct PyScene {
    pub scene: Scene,
    /// The JSON text (a pickled scene is rebuilt from it).
    pub text: String,
    pub package_dirs: Vec<PathBuf>,
}

/// `FileNotFoundError` for a missing file, else `ValueError`: one line naming
/// the scene file and the key.
fn scene_error(e: SceneError) -> PyErr {
    if e.missing.is_some() {
        PyFileNotFoundError::new_err(e.to_string())
    } else {
        value_error(e.to_string())
    }
}

impl PyScene {
    /// The `Model` of this scene (names `MODEL/NAME`; pickles as the scene).
    pub fn py_model(&self) -> PyModel {
        let s = &self.scene;
        let mut inertials = std::collections::HashMap::new();
        for m in &s.models {
            let Ok(text) = std::fs::read_to_string(&m.urdf) else {
                continue;
            };
            let pre = format!("{}/", m.name);
            if m.mjcf {
                // an MJCF model: each body's own inertial in its body frame,
                // as the forest carries it (`MODEL/BODY`)
                let dir = m.urdf.parent().unwrap_or(std::path::Path::new("."));
                let file = m.urdf.display().to_string();
                let own = mjcf_inertials(&text, &file, dir);
                inertials.extend(own.into_iter().map(|(k, v)| (format!("{pre}{k}"), v)));
            } else {
                inertials.extend(link_inertials(&text, &pre));
            }
        }
        // unpickled: `_scene_model_from_state` of the scene's text, file,
        // folder and package roots, and the model's gravity
        let (text, file) = (self.text.clone(), s.file.clone());
        let dir = std::fs::canonicalize(&s.base_dir).unwrap_or_else(|_| s.base_dir.clone());
        let dirs: Vec<String> = self
            .package_dirs
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        let rebuild: Rebuild = Arc::new(move |py, g| {
            let f = py
                .import("urdyn._urdyn")?
                .getattr("_scene_model_from_state")?
                .unbind();
            let args = (
                text.clone(),
                file.clone(),
                dir.display().to_string(),
                dirs.clone(),
                g,
            )
                .into_pyobject(py)?
                .unbind();
            Ok((f, args))
        });
        let mut m = PyModel::from_parts(
            s.model.clone(),
            s.file.clone(),
            self.package_dirs.clone(),
            Some((self.text.clone(), s.file.clone(), s.base_dir.clone())),
            inertials,
        );
        m.rebuild = Some(rebuild);
        m
    }

    fn build(
        text: String,
        file: &str,
        base_dir: PathBuf,
        package_dirs: Vec<PathBuf>,
    ) -> PyResult<Self> {
        let scene = Scene::from_json(&text, file, &base_dir, &package_dirs).map_err(scene_error)?;
        Ok(Self {
            scene,
            text,
            package_dirs,
        })
    }
}

#[pymethods]
impl PyScene {
    /// Reads a scene file; its relative paths are taken against its folder.
    #[staticmethod]
    #[pyo3(signature = (path, package_dirs=None))]
    fn from_file(
        #[pyo3(from_py_with = crate::args::named::path)] path: PathBuf,
        #[pyo3(from_py_with = crate::args::named::package_dirs)] package_dirs: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        let dirs = package_dirs.unwrap_or_default();
        let scene = Scene::from_file(&path, &dirs).map_err(scene_error)?;
        let text = std::fs::read_to_string(&path).map_err(|e| value_error(e.to_string()))?;
        Ok(Self {
            scene,
            text,
            package_dirs: dirs,
        })
    }

    /// The whole world of an MJCF file as a scene (mjcf.md §"Entry points"):
    /// one model named after the file's stem (names `STEM/NAME`), its static
    /// geoms obstacles, its floor plane the ground.
    #[staticmethod]
    fn from_mjcf(#[pyo3(from_py_with = crate::args::named::path)] path: PathBuf) -> PyResult<Self> {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let text = urdyn::scene::mjcf_scene_json(&path);
        Self::build(text, &path.display().to_string(), dir, Vec::new())
    }

    /// A scene from JSON text; relative paths against `base_dir` (default: the
    /// working directory).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None, package_dirs=None))]
    fn from_json(
        #[pyo3(from_py_with = crate::args::named::text)] text: String,
        #[pyo3(from_py_with = crate::args::named::base_dir_or_none)] base_dir: Option<PathBuf>,
        #[pyo3(from_py_with = crate::args::named::package_dirs)] package_dirs: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        Self::build(
            text,
            "<scene>",
            base_dir.unwrap_or_else(|| PathBuf::from(".")),
            package_dirs.unwrap_or_default(),
        )
    }

    /// The whole scene as one `Model` (`dof_names`, `link_names` as `MODEL/NAME`).
    #[getter]
    fn model(&self) -> PyModel {
        self.py_model()
    }

    /// The models' names, in file (and q) order.
    #[getter]
    fn model_names(&self) -> Vec<String> {
        self.scene.models.iter().map(|m| m.name.clone()).collect()
    }

    /// The obstacles' names.
    #[getter]
    fn obstacle_names(&self) -> Vec<String> {
        self.scene
            .obstacles
            .iter()
            .map(|o| o.name.clone())
            .collect()
    }

    /// The starting configuration (poses, `pose`, `initial`).
    #[getter]
    fn q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.scene.q0.as_slice())
    }

    /// The starting velocity.
    #[getter]
    fn v0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.scene.v0.as_slice())
    }

    /// The ground plane's height (None: no ground).
    #[getter]
    fn ground(&self) -> Option<f64> {
        self.scene.ground.map(|g| g.height)
    }

    /// Lines the loading warned about (SRDF names the URDF lacks, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "urdyn.Scene({} models, {} obstacles, nq={}, nv={})",
            self.scene.models.len(),
            self.scene.obstacles.len(),
            self.scene.model.nq,
            self.scene.model.nv
        )
    }

    /// Pickling: the JSON text, the folder and the package roots.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Py<PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("urdyn._urdyn")?
            .getattr("_scene_from_state")?
            .unbind();
        let dirs: Vec<String> = self
            .package_dirs
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        let dir = std::fs::canonicalize(&self.scene.base_dir)
            .unwrap_or_else(|_| self.scene.base_dir.clone());
        let args = (
            self.text.clone(),
            self.scene.file.clone(),
            dir.display().to_string(),
            dirs,
        )
            .into_pyobject(py)?;
        Ok((f, args))
    }
}

/// Rebuilds a pickled `Scene`.
#[pyfunction]
pub fn _scene_from_state(
    text: String,
    file: String,
    base_dir: PathBuf,
    package_dirs: Vec<PathBuf>,
) -> PyResult<PyScene> {
    PyScene::build(text, &file, base_dir, package_dirs)
}

/// Rebuilds a pickled scene's `Model`.
#[pyfunction]
pub fn _scene_model_from_state(
    text: String,
    file: String,
    base_dir: PathBuf,
    package_dirs: Vec<PathBuf>,
    gravity: [f64; 3],
) -> PyResult<PyModel> {
    let s = _scene_from_state(text, file, base_dir, package_dirs)?;
    let mut m = s.py_model();
    m.model.gravity = Vector3::new(gravity[0], gravity[1], gravity[2]);
    Ok(m)
}
