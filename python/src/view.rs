//! Pictures from Python (python.md §"Introspection, contacts, batched control,
//! pictures"): `urdyn.write_html(path, model_or_scene, q, t=None, dt=None)` and
//! a `Simulation`'s recording (`sim.record`, `sim.write_html`), both through the
//! CLI's replay page writer (`urdyn::cli::view`), nothing re-implemented.

use crate::args::{read_array, read_q, value_error};
use crate::model::PyModel;
use crate::scene::PyScene;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use urdyn::cli::view::{write_page, ContactArrow, Geometry, Recorder};
use urdyn::nalgebra::DVector;
use urdyn::{Model, Scene};

/// What a page is drawn from: the model, its drawn geometry and the ground.
pub struct Stage {
    pub model: Model,
    pub geometry: Geometry,
    pub ground: Option<f64>,
}

/// The stage of a `Model` (a scene's model: its scene) or a `Scene`; `ground`
/// for a lone model's page.
pub fn stage(source: &Bound<'_, PyAny>, ground: Option<f64>) -> PyResult<Stage> {
    if let Ok(s) = source.extract::<PyRef<'_, PyScene>>() {
        return scene_stage(&s.scene, &s.package_dirs);
    }
    let m = source
        .extract::<PyRef<'_, PyModel>>()
        .map_err(|_| value_error("model_or_scene: expected a urdyn.Model or a urdyn.Scene"))?;
    model_stage(&m, ground)
}

fn scene_stage(scene: &Scene, package_dirs: &[PathBuf]) -> PyResult<Stage> {
    let geometry = Geometry::load_scene(scene, package_dirs)
        .map_err(|e| value_error(format!("{}: {e}", scene.file)))?;
    Ok(Stage {
        model: scene.model.clone(),
        geometry,
        ground: scene.ground.map(|g| g.height),
    })
}

/// The stage of a model (a scene's: its scene rebuilt from the text).
pub fn model_stage(m: &PyModel, ground: Option<f64>) -> PyResult<Stage> {
    if let Some((text, file, dir)) = &m.scene_state {
        let scene = Scene::from_json(text, file, dir, &m.package_dirs)
            .map_err(|e| value_error(e.to_string()))?;
        let mut st = scene_stage(&scene, &m.package_dirs)?;
        st.model.gravity = m.model.gravity;
        return Ok(st);
    }
    let geometry = match &m.model.source {
        Some(path) => Geometry::load(&m.model, path, &m.package_dirs),
        None => {
            // a model from text: its visuals read from a copy of the text
            let dir = std::env::temp_dir();
            let path = dir.join(format!("urdyn-page-{}.urdf", std::process::id()));
            std::fs::write(&path, &m.text)
                .map_err(|e| value_error(format!("{}: cannot write: {e}", path.display())))?;
            let g = Geometry::load(&m.model, &path, &m.package_dirs);
            let _ = std::fs::remove_file(&path);
            g
        }
    }
    .map_err(|e| value_error(e.to_string()))?;
    Ok(Stage {
        model: m.model.clone(),
        geometry,
        ground,
    })
}

/// One recorded row: time, q, the plotted values (energy, contacts,
/// penetration) and the contact arrows.
#[derive(Clone, Debug)]
pub struct Frame {
    pub t: f64,
    pub q: DVector<f64>,
    pub plot: [f64; 3],
    pub arrows: Vec<ContactArrow>,
}

/// Writes the page of `frames` (time order) to `path`; returns the frames kept.
pub fn write(path: &Path, stage: &Stage, frames: &[Frame]) -> PyResult<usize> {
    let duration = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) => b.t - a.t,
        _ => 0.0,
    };
    let with_contacts = frames.iter().any(|f| !f.arrows.is_empty());
    let mut rec = Recorder::new(&stage.model, duration, with_contacts);
    let last = frames.len().saturating_sub(1);
    for (k, f) in frames.iter().enumerate() {
        rec.offer(f.t, &f.q, f.plot, &f.arrows, k == last);
    }
    let s = write_page(path, &stage.model, &stage.geometry, &rec, stage.ground)
        .map_err(|e| value_error(e.to_string()))?;
    Ok(s.frames)
}

/// `urdyn.write_html(path, model_or_scene, q, t=None, dt=None)`: the replay page
/// of a trajectory q (T, nq), frame k at `t[k]` (increasing), else `k·dt` (dt
/// default 1e-3 s); both given is a `ValueError`. Frames may be thinned for
/// size (as the CLI's pages). Returns the number of frames the page holds.
#[pyfunction]
#[pyo3(signature = (path, model_or_scene, q, t=None, dt=None))]
pub fn write_html(
    #[pyo3(from_py_with = crate::args::named::path)] path: PathBuf,
    model_or_scene: &Bound<'_, PyAny>,
    q: &Bound<'_, PyAny>,
    t: Option<&Bound<'_, PyAny>>,
    dt: Option<f64>,
) -> PyResult<usize> {
    let st = stage(model_or_scene, Some(0.0))?;
    let (nq, quats) = (st.model.nq, crate::args::quat_offsets(&st.model));
    let (shape, data) = read_array(q, "q")?;
    if shape.len() != 2 || shape[1] != nq {
        return Err(value_error(format!(
            "q has shape {shape:?}, expected (T, {nq}) (nq = {nq})"
        )));
    }
    let n = shape[0];
    let times: Vec<f64> = match (t.filter(|t| !t.is_none()), dt) {
        (Some(_), Some(_)) => {
            return Err(value_error("t and dt: give one of them, not both"));
        }
        (Some(t), None) => {
            let (ts, tv) = read_array(t, "t")?;
            if ts != [n] {
                return Err(value_error(format!(
                    "t has shape {ts:?}, expected ({n},) (one time per row of q)"
                )));
            }
            if let Some(k) = (1..n).find(|&k| tv[k] <= tv[k - 1]) {
                return Err(value_error(format!(
                    "t[{k}] = {} does not increase (t[{}] = {})",
                    tv[k],
                    k - 1,
                    tv[k - 1]
                )));
            }
            tv
        }
        (None, dt) => {
            let dt = dt.unwrap_or(1e-3);
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(value_error(format!(
                    "dt must be a positive number (got {dt})"
                )));
            }
            (0..n).map(|k| k as f64 * dt).collect()
        }
    };
    let py = q.py();
    let mut frames = Vec::with_capacity(n);
    for (k, &tk) in times.iter().enumerate() {
        let row = numpy::PyArray1::from_slice(py, &data[k * nq..(k + 1) * nq]);
        let mut qk = DVector::zeros(nq);
        read_q(row.as_any(), &format!("q[{k}]"), &quats, &mut qk)?;
        frames.push(Frame {
            t: tk,
            q: qk,
            plot: [f64::NAN; 3],
            arrows: Vec::new(),
        });
    }
    write(&path, &st, &frames)
}
