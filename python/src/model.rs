//! `urdyn.Model` (the immutable model, its names, pickling) and `urdyn.Data`
//! (the preallocated workspace).

use crate::args::named;
use crate::args::{not_found_error, quat_offsets, read3, read_q, value_error};
use crate::introspect::{self, link_inertials, py_slice, LinkInertial};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use urdyn::model::FrameId;
use urdyn::nalgebra::{DVector, Vector3};
use urdyn::spatial::Force;
use urdyn::{LoadOptions, Model};

/// How a pickled model made elsewhere is rebuilt: given the model's gravity,
/// the function (of `urdyn._urdyn`) and its arguments. The maker of the model
/// (a scene) sets it, so that this file knows nothing of scenes.
pub type Rebuild =
    Arc<dyn Fn(Python<'_>, [f64; 3]) -> PyResult<(Py<PyAny>, Py<PyTuple>)> + Send + Sync>;

/// A multibody model imported from a URDF (`Model.from_urdf`).
#[pyclass(name = "Model", module = "urdyn")]
#[derive(Clone)]
pub struct PyModel {
    pub model: Model,
    /// The URDF text (a pickled model is rebuilt from it).
    pub text: String,
    /// The name used in messages (the file's path, or "<string>").
    pub file: String,
    pub package_dirs: Vec<PathBuf>,
    /// Index into `model.frames` of every URDF link.
    pub links: HashMap<String, usize>,
    /// A scene's model: the scene's JSON text, file name and folder (its
    /// replay page draws the scene's obstacles).
    pub scene_state: Option<(String, String, PathBuf)>,
    /// How a model made elsewhere (a scene's) is rebuilt when unpickled.
    pub rebuild: Option<Rebuild>,
    /// Every URDF link's own `<inertial>` (`link_mass`, `link_inertia`).
    pub inertials: HashMap<String, LinkInertial>,
    /// An MJCF model's bodies' own inertials, compiled at the first
    /// `link_mass`/`link_inertia`.
    mjcf_inertials: OnceLock<HashMap<String, LinkInertial>>,
    /// An MJCF model: the folder its includes and meshes are read from (`text`
    /// is then the MJCF text; a pickled model is rebuilt from both).
    pub mjcf_dir: Option<PathBuf>,
}

impl PyModel {
    fn build(
        text: String,
        file: String,
        floating_base: bool,
        source: Option<PathBuf>,
        package_dirs: Vec<PathBuf>,
    ) -> PyResult<Self> {
        let mut model = urdyn::load_str(&text, &file, LoadOptions { floating_base })
            .map_err(|e| value_error(e.to_string()))?;
        model.source = source;
        let links = model
            .frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        let inertials = link_inertials(&text, "");
        Ok(Self {
            model,
            text,
            file,
            package_dirs,
            links,
            scene_state: None,
            rebuild: None,
            inertials,
            mjcf_inertials: OnceLock::new(),
            mjcf_dir: None,
        })
    }

    /// A model made elsewhere (a scene's: `scene_state` its JSON text, file
    /// and folder; its maker sets `rebuild`), its links indexed.
    pub fn from_parts(
        model: Model,
        file: String,
        package_dirs: Vec<PathBuf>,
        scene_state: Option<(String, String, PathBuf)>,
        inertials: HashMap<String, LinkInertial>,
    ) -> Self {
        let links = model
            .frames
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        Self {
            model,
            text: String::new(),
            file,
            package_dirs,
            links,
            scene_state,
            rebuild: None,
            inertials,
            mjcf_inertials: OnceLock::new(),
            mjcf_dir: None,
        }
    }

    /// Link `name`'s own inertial (a URDF's `<inertial>`, an MJCF body's as
    /// MuJoCo compiles it; `None` without one), `link` in the message.
    fn own_inertial(&self, name: &str) -> PyResult<Option<&LinkInertial>> {
        self.link(name, "link")?;
        let table = match &self.mjcf_dir {
            Some(dir) => self
                .mjcf_inertials
                .get_or_init(|| introspect::mjcf_inertials(&self.text, &self.file, dir)),
            None => &self.inertials,
        };
        Ok(table.get(name))
    }

    /// The frame index of URDF link `name` (`arg` in the message).
    pub fn link(&self, name: &str, arg: &str) -> PyResult<usize> {
        self.links.get(name).copied().ok_or_else(|| {
            let links = self.model.frames.iter().map(|f| f.name.as_str());
            let near = urdyn::model::nearest(name, links)
                .map(|k| format!(" (nearest: \"{k}\")"))
                .unwrap_or_default();
            value_error(format!(
                "{arg}: unknown link \"{name}\" in {}{near}",
                self.file
            ))
        })
    }

    /// The world wrenches `{link: (force3, torque3)}` at the link origins as
    /// per-body spatial forces ([`urdyn::dynamics::add_link_wrench`]), needing
    /// the world poses in `data` (forward kinematics at the state's q).
    pub fn fext(
        &self,
        dict: &Bound<'_, pyo3::types::PyDict>,
        data: &urdyn::Data,
        out: &mut [Force],
    ) -> PyResult<()> {
        out.iter_mut().for_each(|f| *f = Force::zero());
        for (key, value) in dict.iter() {
            let name: String = key
                .extract()
                .map_err(|_| value_error("fext: keys must be link names (str)"))?;
            let fi = self.link(&name, "fext")?;
            let pair = value.cast::<pyo3::types::PySequence>().map_err(|_| {
                value_error(format!("fext[\"{name}\"]: expected (force3, torque3)"))
            })?;
            if pair.len().unwrap_or(0) != 2 {
                return Err(value_error(format!(
                    "fext[\"{name}\"]: expected (force3, torque3)"
                )));
            }
            let f = read3(&pair.get_item(0)?, &format!("fext[\"{name}\"] force"))?;
            let t = read3(&pair.get_item(1)?, &format!("fext[\"{name}\"] torque"))?;
            let (f, t) = (Vector3::from(f), Vector3::from(t));
            urdyn::dynamics::add_link_wrench(&self.model, data, FrameId(fi), &f, &t, out)
                .map_err(|e| value_error(format!("fext[\"{name}\"]: {e}")))?;
        }
        Ok(())
    }
}

#[pymethods]
impl PyModel {
    /// Imports a URDF file. `package_dirs`: roots for `package://` mesh paths
    /// (used by `Simulation` for collision meshes).
    #[staticmethod]
    #[pyo3(signature = (path, floating_base=false, package_dirs=None))]
    fn from_urdf(
        #[pyo3(from_py_with = named::path)] path: PathBuf,
        #[pyo3(from_py_with = named::floating_base)] floating_base: bool,
        #[pyo3(from_py_with = named::package_dirs)] package_dirs: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        // a file that does not exist: FileNotFoundError, with the CLI's line
        if let Err(e) = std::fs::metadata(&path) {
            let msg = format!("{}: cannot read file: {e}", path.display());
            return Err(match e.kind() {
                std::io::ErrorKind::NotFound => not_found_error(msg),
                _ => value_error(msg),
            });
        }
        // the library's loader gives the CLI's messages for a bad file
        urdyn::load_file(&path, LoadOptions { floating_base })
            .map_err(|e| value_error(e.to_string()))?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| value_error(format!("{}: cannot read file: {e}", path.display())))?;
        Self::build(
            text,
            path.display().to_string(),
            floating_base,
            Some(path),
            package_dirs.unwrap_or_default(),
        )
    }

    /// Imports an MJCF file (mjcf.md): its whole world (every body with its
    /// joints, in MuJoCo's qpos order; each ball or free joint's quaternion
    /// `[qx, qy, qz, qw]`, a free joint's linear velocity in its body frame:
    /// `from_mujoco_qpos`/`from_mujoco_qvel` convert). Joint `armature` is in
    /// `crba` and `forward_dynamics` as in MuJoCo's qM (`model.armature`).
    #[staticmethod]
    fn from_mjcf(#[pyo3(from_py_with = named::path)] path: PathBuf) -> PyResult<Self> {
        crate::mjcf::from_mjcf(path)
    }

    /// Imports MJCF text; `<include>`s and meshes are read under `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (xml, base_dir=PathBuf::from(".")))]
    fn from_mjcf_string(
        #[pyo3(from_py_with = named::xml)] xml: String,
        #[pyo3(from_py_with = named::base_dir)] base_dir: PathBuf,
    ) -> PyResult<Self> {
        crate::mjcf::from_mjcf_string(xml, "<string>".into(), base_dir)
    }

    /// Imports a URDF or an MJCF file, the format from its content (a root
    /// `<mujoco>` is MJCF whatever the extension); `floating_base=True` beside
    /// an MJCF file is a `ValueError` (the file says which joints are free).
    #[staticmethod]
    #[pyo3(signature = (path, floating_base=false, package_dirs=None))]
    fn from_file(
        #[pyo3(from_py_with = named::path)] path: PathBuf,
        #[pyo3(from_py_with = named::floating_base)] floating_base: bool,
        #[pyo3(from_py_with = named::package_dirs)] package_dirs: Option<Vec<PathBuf>>,
    ) -> PyResult<Self> {
        match urdyn::load::file_format(&path) {
            urdyn::load::Format::Mjcf => {
                if floating_base {
                    let e = urdyn::load_model(&path, LoadOptions { floating_base });
                    return Err(value_error(
                        e.err().map(|e| e.to_string()).unwrap_or_default(),
                    ));
                }
                crate::mjcf::from_mjcf(path)
            }
            _ => Self::from_urdf(path, floating_base, package_dirs),
        }
    }

    /// Imports URDF text.
    #[staticmethod]
    #[pyo3(signature = (xml, floating_base=false))]
    fn from_urdf_string(
        #[pyo3(from_py_with = named::xml)] xml: String,
        #[pyo3(from_py_with = named::floating_base)] floating_base: bool,
    ) -> PyResult<Self> {
        Self::build(xml, "<string>".into(), floating_base, None, Vec::new())
    }

    /// Length of q.
    #[getter]
    fn nq(&self) -> usize {
        self.model.nq
    }
    /// Length of v, a, tau.
    #[getter]
    fn nv(&self) -> usize {
        self.model.nv
    }
    /// The name of every entry of q, as eval's (a floating base's `base_x` …
    /// `base_qw` first; mechanisms.md).
    #[getter]
    fn q_names(&self) -> Vec<String> {
        self.model.q_names()
    }
    /// The name of every entry of v (and a, tau), as eval's (`base_vx` … first).
    #[getter]
    fn v_names(&self) -> Vec<String> {
        self.model.v_names()
    }
    /// The joint degrees of freedom in engine order (the base's 6 not included).
    #[getter]
    fn dof_names(&self) -> Vec<String> {
        self.model.dofs.iter().map(|d| d.name.clone()).collect()
    }
    /// Every URDF link, in the URDF's order.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.model.frames.iter().map(|f| f.name.clone()).collect()
    }
    /// Whether the root has a free 6-DoF joint.
    #[getter]
    fn floating_base(&self) -> bool {
        self.model.floating_base
    }
    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.model.name.clone()
    }
    /// Mass of the links that move (kg).
    #[getter]
    fn total_mass(&self) -> f64 {
        self.model.inertias.iter().skip(1).map(|i| i.mass).sum()
    }
    /// The import report's warnings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.model.report.warnings.clone()
    }
    /// Gravity in the world frame (m/s²).
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.model.gravity.as_slice())
    }
    #[setter]
    fn set_gravity(&mut self, g: &Bound<'_, PyAny>) -> PyResult<()> {
        let g = read3(g, "gravity")?;
        self.model.gravity = Vector3::new(g[0], g[1], g[2]);
        Ok(())
    }
    /// The neutral configuration: joints at 0, the base at the origin with the
    /// identity orientation.
    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let mut q = DVector::zeros(self.model.nq);
        if self.model.floating_base {
            q[6] = 1.0;
        }
        PyArray1::from_slice(py, q.as_slice())
    }
    // --- Introspection (python.md §"Introspection, contacts, ..."; introspect.rs) ---

    /// `slice` of joint `name`'s entries in q (Pinocchio's idx_q/nq; a continuous
    /// joint one entry, a floating base "base" / "MODEL/base" seven).
    fn joint_q_slice<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::name)] name: String,
    ) -> PyResult<Bound<'py, PyAny>> {
        py_slice(py, &introspect::joint_ranges(&self.model, &name)?.0)
    }
    /// `slice` of joint `name`'s entries in v (Pinocchio's idx_v/nv).
    fn joint_v_slice<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::name)] name: String,
    ) -> PyResult<Bound<'py, PyAny>> {
        py_slice(py, &introspect::joint_ranges(&self.model, &name)?.1)
    }
    /// `slice` of a scene model's entries in q (a lone URDF: "robot", all of q).
    fn model_q_slice<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::name)] name: String,
    ) -> PyResult<Bound<'py, PyAny>> {
        py_slice(py, &introspect::model_ranges(&self.model, &name)?.0)
    }
    /// `slice` of a scene model's entries in v.
    fn model_v_slice<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::name)] name: String,
    ) -> PyResult<Bound<'py, PyAny>> {
        py_slice(py, &introspect::model_ranges(&self.model, &name)?.1)
    }
    /// The models in q order: a scene's names, ["robot"] for a lone URDF.
    #[getter]
    fn models(&self) -> Vec<String> {
        introspect::models(&self.model)
            .into_iter()
            .map(|m| m.0)
            .collect()
    }
    /// (nq,) lower position limits: -inf where none, on continuous joints and the base.
    #[getter]
    fn lower_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, introspect::position_limits(&self.model).0)
    }
    /// (nq,) upper position limits: +inf where none, on continuous joints and the base.
    #[getter]
    fn upper_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, introspect::position_limits(&self.model).1)
    }
    /// (nv,) `<limit effort>` (N·m or N; inf where none and on the base): what
    /// `step` clamps each joint torque to.
    #[getter]
    fn effort_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let e = introspect::per_dof(&self.model, f64::INFINITY, |d| {
            d.limits
                .effort
                .filter(|&e| e > 0.0)
                .unwrap_or(f64::INFINITY)
        });
        PyArray1::from_vec(py, e)
    }
    /// (nv,) `<limit velocity>` (rad/s or m/s; inf where none and on the base).
    #[getter]
    fn velocity_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let e = introspect::per_dof(&self.model, f64::INFINITY, |d| {
            d.limits.velocity.unwrap_or(f64::INFINITY)
        });
        PyArray1::from_vec(py, e)
    }
    /// (nv,) viscous damping the simulation uses (`<dynamics damping>`; base 0).
    #[getter]
    fn damping<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let e = introspect::per_dof(&self.model, 0.0, |d| {
            if d.damping.is_finite() {
                d.damping.max(0.0)
            } else {
                0.0
            }
        });
        PyArray1::from_vec(py, e)
    }
    /// (nv,) Coulomb joint friction the simulation uses (`<dynamics friction>`; base 0).
    #[getter]
    fn friction<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, introspect::per_dof(&self.model, 0.0, |d| d.friction))
    }
    /// (nv,) rotor inertia on each joint's diagonal: an MJCF joint's
    /// `armature` (in H as MuJoCo's qM: `crba`, `rnea`, `forward_dynamics`
    /// include it); a URDF has none (zeros).
    #[getter]
    fn armature<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let a = self
            .model
            .armature()
            .unwrap_or_else(|| DVector::zeros(self.model.nv));
        PyArray1::from_slice(py, a.as_slice())
    }
    /// A link's own `<inertial>` mass (kg; 0 without one); an MJCF body's
    /// own mass as MuJoCo's `body_mass` (from its geoms where it has no
    /// `<inertial>`).
    fn link_mass(&self, #[pyo3(from_py_with = named::link)] link: String) -> PyResult<f64> {
        Ok(self.own_inertial(&link)?.map_or(0.0, |i| i.mass))
    }
    /// A link's own (centre of mass (3), inertia about it (3, 3)), link frame
    /// (zeros without an `<inertial>`).
    #[allow(clippy::type_complexity)]
    fn link_inertia<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = named::link)] link: String,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>)> {
        let (c, i) = self
            .own_inertial(&link)?
            .map_or((Vector3::zeros(), urdyn::nalgebra::Matrix3::zeros()), |l| {
                (l.com, l.inertia)
            });
        let rows: Vec<Vec<f64>> = (0..3)
            .map(|r| (0..3).map(|k| i[(r, k)]).collect())
            .collect();
        let m = PyArray2::from_vec2(py, &rows).map_err(|e| value_error(e.to_string()))?;
        Ok((PyArray1::from_slice(py, c.as_slice()), m))
    }

    /// A new preallocated workspace for this model.
    fn create_data(&self) -> PyData {
        PyData::new(&self.model)
    }
    fn __repr__(&self) -> String {
        format!(
            "urdyn.Model(\"{}\", nq={}, nv={}, floating_base={})",
            self.model.name,
            self.model.nq,
            self.model.nv,
            if self.model.floating_base {
                "True"
            } else {
                "False"
            }
        )
    }
    /// Pickling: the URDF text and the options (the model is rebuilt from them).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Py<PyAny>, Bound<'py, PyTuple>)> {
        let f = py
            .import("urdyn._urdyn")?
            .getattr("_model_from_state")?
            .unbind();
        let dirs: Vec<String> = self
            .package_dirs
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        let g = [
            self.model.gravity.x,
            self.model.gravity.y,
            self.model.gravity.z,
        ];
        if let Some(rebuild) = &self.rebuild {
            let (f, args) = rebuild(py, g)?;
            return Ok((f, args.into_bound(py)));
        }
        if let Some(dir) = &self.mjcf_dir {
            let f = py
                .import("urdyn._urdyn")?
                .getattr("_mjcf_model_from_state")?
                .unbind();
            let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.clone());
            let args = (
                self.text.clone(),
                self.file.clone(),
                dir.display().to_string(),
                g,
            )
                .into_pyobject(py)?;
            return Ok((f, args));
        }
        let source = self.model.source.as_ref().map(|p| p.display().to_string());
        let args = (
            self.text.clone(),
            self.file.clone(),
            self.model.floating_base,
            dirs,
            g,
            source,
        )
            .into_pyobject(py)?;
        Ok((f, args))
    }
}

/// Rebuilds a pickled `Model`.
#[pyfunction]
pub fn _model_from_state(
    text: String,
    file: String,
    floating_base: bool,
    package_dirs: Vec<PathBuf>,
    gravity: [f64; 3],
    source: Option<PathBuf>,
) -> PyResult<PyModel> {
    let mut m = PyModel::build(text, file, floating_base, source, package_dirs)?;
    m.model.gravity = Vector3::new(gravity[0], gravity[1], gravity[2]);
    Ok(m)
}

/// The preallocated workspace of one model (`model.create_data()`).
#[pyclass(name = "Data", module = "urdyn")]
pub struct PyData {
    pub data: urdyn::Data,
    /// The offsets in q of the free joints' unit quaternions.
    pub quats: Vec<usize>,
    pub nq: usize,
    pub nv: usize,
    pub nbodies: usize,
    pub q: DVector<f64>,
    pub v: DVector<f64>,
    pub a: DVector<f64>,
    pub fext: Vec<Force>,
}

impl PyData {
    pub fn new(model: &Model) -> Self {
        Self {
            data: urdyn::Data::new(model),
            quats: quat_offsets(model),
            nq: model.nq,
            nv: model.nv,
            nbodies: model.nbodies,
            q: DVector::zeros(model.nq),
            v: DVector::zeros(model.nv),
            a: DVector::zeros(model.nv),
            fext: vec![Force::zero(); model.nbodies],
        }
    }
    /// Reads the configuration `x` into `self.q` ([`read_q`]: length nq,
    /// finite, a floating base's quaternion of unit norm within 1e-3).
    pub fn read_q(&mut self, x: &Bound<'_, PyAny>) -> PyResult<()> {
        read_q(x, "q", &self.quats, &mut self.q)
    }
    /// A `ValueError` unless this workspace was made for a model of `model`'s shape.
    pub fn check(&self, model: &Model) -> PyResult<()> {
        if self.nq != model.nq || self.nv != model.nv || self.nbodies != model.nbodies {
            return Err(value_error(format!(
                "data: made for another model (nq = {}, nv = {}), this one has nq = {}, nv = {}",
                self.nq, self.nv, model.nq, model.nv
            )));
        }
        Ok(())
    }
}
