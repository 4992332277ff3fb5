//! The simulation `Simulation(...)` and `rollout(...)` start from: a `Model`'s
//! (neutral, at rest; loop constraints from `constraints=`) or a `Scene`'s (its
//! ground, friction, obstacles, start and `"constraints"`), and the start of a
//! run with loops ([`start_loops`]): both go through here, so that a rollout's
//! states equal, bit for bit, a `Simulation` stepped alone.

use crate::args::{not_found_error, value_error, Given};
use crate::constraints::PyConstraints;
use crate::model::PyModel;
use crate::scene::PyScene;
use crate::sim::integrators;
use pyo3::prelude::*;
use std::path::PathBuf;
use urdyn::contact::{ContactError, ContactParams};
use urdyn::model::Constraints;
use urdyn::nalgebra::DVector;
use urdyn::sim::{Integrator, SimError, SimOptions, Simulation};

/// A starting simulation with what a run with loops needs to start again.
pub(crate) struct Proto {
    /// The simulation at its start (loops set, holds placed there).
    pub sim: Simulation,
    /// The loop constraints as given (world holds not yet placed): a new
    /// start (`set_state`) places them again.
    pub loops: Option<Constraints>,
    /// The start's warning lines (a constraint violated by more than 1 mm).
    pub warnings: Vec<String>,
}

/// Starts the loops `set` at the simulation's current state (world anchors
/// left out placed where side 1 is now; the passive energy reference taken
/// afresh), the constraints named in `off` switched off. Returns the warning
/// lines of the constraints this state violates by more than 1 mm.
pub(crate) fn start_loops(
    sim: &mut Simulation,
    set: &Constraints,
    off: &[String],
) -> Result<Vec<String>, SimError> {
    let lines = sim.set_constraints(set.clone())?;
    for name in off {
        sim.set_constraint_active(name, false)?;
    }
    Ok(lines)
}

/// The loop constraints of `constraints=` for `model`: a `urdyn.Constraints`
/// made for it, or a list of the JSON objects as dicts.
fn read_constraints(model: &PyModel, c: &Bound<'_, PyAny>) -> PyResult<Constraints> {
    if let Ok(c) = c.extract::<PyRef<'_, PyConstraints>>() {
        c.check(model, "constraints")?;
        return Ok(c.constraints.clone());
    }
    if c.is_instance_of::<pyo3::types::PyList>() || c.is_instance_of::<pyo3::types::PyTuple>() {
        return Ok(PyConstraints::build(model, c)?.constraints);
    }
    Err(value_error(format!(
        "constraints: expected a urdyn.Constraints or a list of constraint dicts (got {})",
        c.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default()
    )))
}

/// A simulation of `model` at its neutral configuration (or at `start`), at
/// rest, with the options of `Simulation(...)` / `rollout(...)` over `base`:
/// the ground and contact parameters come from `base` (a scene's
/// [`SimOptions::of_scene`], or a model's `ground=` / `friction=`), the step,
/// integrator, package roots, sleep and threads from the call.
#[allow(clippy::too_many_arguments)]
fn prototype(
    model: &PyModel,
    base: SimOptions,
    dt: f64,
    integrator: Option<&str>,
    package_dirs: Option<Vec<PathBuf>>,
    islands: Islands<'_>,
    start: Option<(&DVector<f64>, &DVector<f64>)>,
) -> PyResult<Simulation> {
    let friction = base.contact.friction;
    let ground = base.ground;
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(value_error(format!(
            "dt must be a positive number (got {dt})"
        )));
    }
    if !(friction >= 0.0 && friction.is_finite()) {
        return Err(value_error(format!(
            "friction must be a finite number ≥ 0 (got {friction})"
        )));
    }
    if let Some(g) = ground {
        if !g.is_finite() {
            return Err(value_error(format!(
                "ground must be a finite number (got {g})"
            )));
        }
    }
    let integrator = match integrator {
        None => None,
        Some(name) => Some(Integrator::from_name(name).ok_or_else(|| {
            value_error(format!(
                "integrator: unknown \"{name}\" (one of: {})",
                integrators().join(", ")
            ))
        })?),
    };
    let opts = SimOptions {
        dt,
        integrator,
        package_paths: package_dirs.unwrap_or_else(|| model.package_dirs.clone()),
        ..base
    }
    .with_islands(islands.scene, islands.sleep, islands.threads);
    // At a given start, contacts are found once, there (a scene's models all sit at the
    // origin before it: every pair of a pile would overlap).
    let sim = match start {
        Some((q, v)) => Simulation::new_at(model.model.clone(), opts, q, v),
        None => Simulation::new(model.model.clone(), opts),
    };
    sim.map_err(|e| match e {
        // the library's message is neutral; the hint is Python's (the CLI names its flags)
        SimError::Contact(ContactError::MissingMesh { .. }) => not_found_error(format!(
            "{}: {e} (give its package root with package_dirs=[...] or ROS_PACKAGE_PATH, or pass ground=None for no contact)",
            model.file
        )),
        e => value_error(format!("{}: {e}", model.file)),
    })
}

/// Sleep and threads (scene.md §"Large scenes"): a scene's from its file, a
/// model alone's the defaults (it sleeps, one thread), `sleep=`/`threads=` of
/// the call over either ([`SimOptions::with_islands`], as `urdyn simulate`).
pub(crate) struct Islands<'a> {
    scene: Option<&'a urdyn::scene::SceneSpec>,
    sleep: Option<bool>,
    threads: Option<usize>,
}

/// A simulation of a scene at its starting state (poses, `pose`, `initial`),
/// with its ground, friction and obstacles; the scene's constant torques.
fn prototype_scene(
    scene: &PyScene,
    dt: f64,
    integrator: Option<&str>,
    package_dirs: Option<Vec<PathBuf>>,
    sleep: Option<bool>,
    threads: Option<usize>,
) -> PyResult<Simulation> {
    let s = &scene.scene;
    let model = scene.py_model();
    // as `urdyn simulate SCENE.json`: the file's settings where the call gives none
    let islands = Islands {
        scene: Some(&s.spec),
        sleep,
        threads,
    };
    // the ground, its contact parameters and the file's islands settings as
    // `urdyn simulate SCENE.json` reads them
    let mut sim = prototype(
        &model,
        SimOptions::of_scene(s),
        dt,
        integrator,
        package_dirs,
        islands,
        Some((&s.q0, &s.v0)),
    )?;
    sim.torques_mut().copy_from(&s.tau0);
    Ok(sim)
}

/// The simulation `Simulation(...)` / `rollout(...)` start from: of a `Model`
/// (neutral, at rest; the loops of `constraints`) or of a `Scene` (its ground,
/// friction, start and `"constraints"`; the `ground`, `friction` and
/// `constraints` the file decides: given beside a scene, even at their
/// defaults, they are a `ValueError`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn prototype_any(
    source: &Bound<'_, PyAny>,
    dt: f64,
    integrator: Option<&str>,
    ground: &Given,
    friction: &Given,
    package_dirs: Option<Vec<PathBuf>>,
    sleep: Option<bool>,
    threads: Option<usize>,
    constraints: Option<&Bound<'_, PyAny>>,
) -> PyResult<Proto> {
    let constraints = constraints.filter(|c| !c.is_none());
    if let Ok(scene) = source.extract::<PyRef<'_, PyScene>>() {
        for (name, g) in [("ground", ground), ("friction", friction)] {
            if g.given() {
                return Err(value_error(format!(
                    "{name}= does not apply beside a scene: the scene file decides its ground and friction ({})",
                    scene.scene.file
                )));
            }
        }
        if constraints.is_some() {
            return Err(value_error(format!(
                "constraints= does not apply beside a scene: the scene file's \"constraints\" decide ({})",
                scene.scene.file
            )));
        }
        let mut sim = prototype_scene(&scene, dt, integrator, package_dirs, sleep, threads)?;
        let set = &scene.scene.constraints;
        if set.items.is_empty() {
            return Ok(Proto {
                sim,
                loops: None,
                warnings: Vec::new(),
            });
        }
        let warnings = start_loops(&mut sim, set, &[])
            .map_err(|e| value_error(format!("{}: {e}", scene.scene.file)))?;
        return Ok(Proto {
            sim,
            loops: Some(set.clone()),
            warnings,
        });
    }
    let model = source
        .extract::<PyRef<'_, PyModel>>()
        .map_err(|_| value_error("model: expected a urdyn.Model or a urdyn.Scene".to_string()))?;
    let loops = constraints
        .map(|c| read_constraints(&model, c))
        .transpose()?
        .filter(|c| !c.items.is_empty());
    let py = source.py();
    let base = SimOptions {
        ground: ground.ground(py)?,
        contact: ContactParams {
            friction: friction.friction(py)?,
            ..ContactParams::default()
        },
        ..SimOptions::default()
    };
    let mut sim = prototype(
        &model,
        base,
        dt,
        integrator,
        package_dirs,
        Islands {
            scene: None,
            sleep,
            threads,
        },
        None,
    )?;
    let warnings = match &loops {
        Some(set) => {
            start_loops(&mut sim, set, &[]).map_err(|e| value_error(format!("constraints: {e}")))?
        }
        None => Vec::new(),
    };
    Ok(Proto {
        sim,
        loops,
        warnings,
    })
}
