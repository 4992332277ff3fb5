//! `urdyn simulate MODEL.xml` (mjcf.md §"What the file becomes"): the file's
//! whole world — its bodies with their collision geoms (MuJoCo's pair filter,
//! `crate::mjcf`), its upward-facing plane as the ground with the plane's
//! friction, joint damping, frictionloss, springs, limits and armature (the
//! simulation reads them from the model's degrees of freedom), `<option>`'s
//! timestep (unless `--dt`) and gravity, and `--key NAME` starting states;
//! contact with the speculative margin of MuJoCo's large steps.
//! What is not simulated is one warning line each (the import report's).
//! Actuators are driven by `--controls FILE.csv` (cli.md) and a key's `ctrl`.

use super::simulate::{warn, Setup, SimulateArgs, SimulateError};
use crate::cli::state;
use crate::mjcf;
use crate::sim::{Integrator, SimOptions};
use nalgebra::DVector;

/// Lines of the import report that a simulation of the world does not honour.
fn unmodelled(model: &crate::Model) -> impl Iterator<Item = &String> {
    model.report.warnings.iter().chain(&model.report.ignored)
}

/// An MJCF file's run: model, ground, options and starting state from the file.
pub(crate) fn setup(
    args: &SimulateArgs,
    integrator: Option<Integrator>,
) -> Result<Setup, SimulateError> {
    let name = args.urdf.display().to_string();
    let refused = [
        (args.floating_base, "--floating-base"),
        (args.ground.is_some(), "--ground"),
        (args.no_ground, "--no-ground"),
        (args.above_ground.is_some(), "--above-ground"),
    ];
    if let Some((_, opt)) = refused.iter().find(|(g, _)| *g) {
        return Err(SimulateError::Option(format!(
            "{name}: {opt} does not apply to an MJCF file (the file says which joints are free and its planes are the ground)"
        )));
    }
    if let (Some(k), Some(_)) = (&args.key, &args.initial) {
        return Err(SimulateError::Option(format!(
            "{name}: --key {k} and --initial both give the starting state: give one"
        )));
    }
    let (model, world) = mjcf::load_file_with_world(&args.urdf)?;
    for w in unmodelled(&model) {
        warn(&format!("warning: {name}: {w}"));
    }
    let init = match (&args.key, &args.initial) {
        (Some(k), _) => Some(key_state(&model, &world, k, &name)?),
        (None, Some(p)) => {
            let file = p.display().to_string();
            let text = state::read_text(p)?;
            let st = state::parse_state(&text, &file)?;
            if st.a.is_some() {
                return Err(state::StateError {
                    file,
                    key: "a".into(),
                    message: "not allowed in --initial (accelerations are simulated)".into(),
                }
                .into());
            }
            Some(st.to_vectors(&model, &file, "(state)")?)
        }
        (None, None) => None,
    };
    // the file's step, ground, friction and the speculative margin
    // (docs/theory.md §"Speculative margin"), the command's options over them
    let world_opts = SimOptions::of_mjcf_world(&world);
    let opts = SimOptions {
        dt: args.dt.unwrap_or(world_opts.dt),
        integrator,
        tol: args.tol,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        sleep: !args.no_sleep,
        threads: args.threads.unwrap_or(1),
        ..world_opts
    };
    // --html: every geom of the world in its colour (src/cli/view/mjcf.rs)
    let geometry = args
        .html
        .as_ref()
        .map(|_| crate::cli::view::mjcf::geometry(&model, &world, &name));
    Ok((model, init, opts, geometry, name, None))
}

/// The starting state of keyframe `key` (MuJoCo's qpos/qvel converted).
fn key_state(
    model: &crate::Model,
    world: &mjcf::World,
    key: &str,
    file: &str,
) -> Result<state::StateVectors, SimulateError> {
    let Some(k) = world.keys.iter().find(|k| k.name == key) else {
        let names: Vec<_> = world.keys.iter().map(|k| k.name.as_str()).collect();
        return Err(SimulateError::Option(format!(
            "{file}: --key {key}: no such keyframe (the file has: {})",
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            }
        )));
    };
    let bad = |e: crate::model::DimensionError| {
        SimulateError::Option(format!("{file}: <key name=\"{key}\">: {e}"))
    };
    let qpos = match &k.qpos {
        Some(p) => DVector::from_column_slice(p),
        None => mjcf::to_mujoco_qpos(model, &model.neutral()).map_err(bad)?,
    };
    let q = mjcf::from_mujoco_qpos(model, &qpos).map_err(bad)?;
    let v = match &k.qvel {
        Some(qv) => {
            mjcf::from_mujoco_qvel(model, &qpos, &DVector::from_column_slice(qv)).map_err(bad)?
        }
        None => DVector::zeros(model.nv),
    };
    Ok(state::StateVectors {
        q,
        v,
        a: DVector::zeros(model.nv),
        tau: DVector::zeros(model.nv),
        fext: Vec::new(),
        frames: Vec::new(),
        derivatives: false,
    })
}

/// The controls of a run (`--controls FILE.csv`, `--key NAME`'s `ctrl`): rows
/// of (t, u) applied when the simulation reaches t and held until the next.
#[derive(Clone, Debug)]
pub(crate) struct ControlSchedule {
    rows: Vec<(f64, DVector<f64>)>,
    next: usize,
}

impl ControlSchedule {
    /// Applies every row due at the simulation's time; returns the time of the
    /// next change (∞ when none is left).
    pub fn apply_due(
        &mut self,
        sim: &mut crate::sim::Simulation,
    ) -> Result<f64, crate::sim::SimError> {
        let t = sim.time();
        let slack = 1e-12 * t.abs().max(1.0);
        while let Some((tk, u)) = self.rows.get(self.next) {
            if *tk > t + slack {
                return Ok(*tk);
            }
            sim.set_controls(u)?;
            self.next += 1;
        }
        Ok(f64::INFINITY)
    }
}

/// The run's control schedule: `None` when neither `--controls` nor a key's
/// `ctrl` gives one. `--controls` beside a URDF or a scene is an error.
pub(crate) fn schedule(
    args: &SimulateArgs,
    model: &crate::Model,
) -> Result<Option<ControlSchedule>, SimulateError> {
    let is_mjcf =
        args.scene.is_none() && crate::load::file_format(&args.urdf) == crate::load::Format::Mjcf;
    if let (Some(p), false) = (&args.controls, is_mjcf) {
        return Err(SimulateError::Option(format!(
            "--controls {}: controls drive an MJCF file's actuators ({} is not one)",
            p.display(),
            args.scene.as_ref().unwrap_or(&args.urdf).display()
        )));
    }
    if !is_mjcf {
        return Ok(None);
    }
    let nu = model.actuators.len();
    let start = args
        .key
        .as_ref()
        .and_then(|k| model.keyframes.iter().find(|f| &f.name == k))
        .and_then(|k| k.ctrl.clone())
        .map(DVector::from_vec);
    let mut rows = Vec::new();
    if let Some(u) = &start {
        rows.push((f64::NEG_INFINITY, u.clone()));
    }
    if let Some(path) = &args.controls {
        let base = start.unwrap_or_else(|| DVector::zeros(nu));
        rows.extend(read_controls(path, model, &base)?);
    }
    Ok((!rows.is_empty()).then_some(ControlSchedule { rows, next: 0 }))
}

/// Reads `--controls FILE.csv` (cli.md): a `t` column and one column per
/// actuator name (an actuator without a column keeps `base`), rows in
/// increasing t.
fn read_controls(
    path: &std::path::Path,
    model: &crate::Model,
    base: &DVector<f64>,
) -> Result<Vec<(f64, DVector<f64>)>, SimulateError> {
    let file = path.display().to_string();
    let err = |m: String| SimulateError::Option(format!("--controls {file}: {m}"));
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(err(
            "empty file (needs a header: t and actuator names)".into()
        ));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    if names.first() != Some(&"t") {
        return Err(err(format!(
            "the first column must be t (got \"{}\")",
            names.first().unwrap_or(&"")
        )));
    }
    let mut cols = Vec::with_capacity(names.len() - 1);
    for (c, n) in names.iter().enumerate().skip(1) {
        let Some(a) = model.actuators.iter().position(|a| a.name == *n) else {
            let known: Vec<_> = model.actuators.iter().map(|a| a.name.as_str()).collect();
            return Err(err(format!(
                "column {} \"{n}\": no such actuator (the model has: {})",
                c + 1,
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )));
        };
        if cols.contains(&a) {
            return Err(err(format!(
                "column {} \"{n}\": a second column of this actuator",
                c + 1
            )));
        }
        cols.push(a);
    }
    let mut rows: Vec<(f64, DVector<f64>)> = Vec::new();
    for (i, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            return Err(err(format!(
                "line {}: {} values, the header has {} columns",
                i + 1,
                cells.len(),
                names.len()
            )));
        }
        let mut vals = Vec::with_capacity(cells.len());
        for (c, s) in cells.iter().enumerate() {
            match s.parse::<f64>() {
                Ok(x) if x.is_finite() => vals.push(x),
                _ => {
                    return Err(err(format!(
                        "line {}, column \"{}\": \"{s}\" is not a finite number",
                        i + 1,
                        names[c]
                    )))
                }
            }
        }
        let t = vals[0];
        if t < 0.0 || rows.last().is_some_and(|(tp, _)| t <= *tp) {
            return Err(err(format!(
                "line {}: t = {t} must be ≥ 0 and above the previous row's",
                i + 1
            )));
        }
        let mut u = base.clone();
        for (&a, &x) in cols.iter().zip(&vals[1..]) {
            u[a] = x;
        }
        rows.push((t, u));
    }
    Ok(rows)
}
