//! `urdyn simulate MODEL.xml` (mjcf.md §"What the file becomes"): the file's
//! whole world — its bodies with their collision geoms (MuJoCo's pair filter,
//! `crate::mjcf`), its upward-facing plane as the ground with the plane's
//! friction, joint damping, frictionloss, springs, limits and armature (the
//! simulation reads them from the model's degrees of freedom), `<option>`'s
//! timestep (unless `--dt`) and gravity, and `--key NAME` starting states.
//! What is not simulated is one warning line each (the import report's).

use super::simulate::{warn, Setup, SimulateArgs, SimulateError, DEFAULT_DT};
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
    if args.html.is_some() {
        return Err(SimulateError::Option(format!(
            "{name}: --html: the replay page of an MJCF world is not supported yet (simulate without --html)"
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
    let ground = mjcf::ground_of(&world);
    let mut contact = crate::contact::ContactParams::default();
    if let Some(g) = &ground {
        contact.friction = g.friction;
    }
    let dt = args.dt.unwrap_or(if world.timestep > 0.0 {
        world.timestep
    } else {
        DEFAULT_DT
    });
    let opts = SimOptions {
        dt,
        integrator,
        tol: args.tol,
        ground: ground.as_ref().map(|g| g.height),
        contact,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        sleep: !args.no_sleep,
        threads: args.threads.unwrap_or(1),
        ..SimOptions::default()
    };
    Ok((model, init, opts, None, name, None))
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
