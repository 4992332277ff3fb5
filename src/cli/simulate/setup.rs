//! `urdyn simulate`'s set-up of a lone URDF or of a scene file: the model, the
//! starting state, the options and the replay page's geometry.

use super::{warn, Setup, SimulateArgs, SimulateError, DEFAULT_DT};
use crate::cli::state;
use crate::sim::{Integrator, SimOptions};
use crate::{LoadOptions, Model};

/// A lone URDF's run: `--floating-base`, `--initial`, the ground and friction options.
pub(super) fn urdf(
    args: &SimulateArgs,
    integrator: Option<Integrator>,
) -> Result<Setup, SimulateError> {
    if let Some(k) = &args.key {
        return Err(SimulateError::Option(format!(
            "--key {k}: keyframes belong to MJCF files ({} is not one)",
            args.urdf.display()
        )));
    }
    let model: Model = crate::load_file(
        &args.urdf,
        LoadOptions {
            floating_base: args.floating_base,
        },
    )?;
    let urdf_name = args.urdf.display().to_string();
    // the initial state (checked before anything is simulated)
    let init = match &args.initial {
        Some(p) => {
            let name = p.display().to_string();
            let text = state::read_text(p)?;
            let st = state::parse_state(&text, &name)?;
            let base_acc = st.base.as_ref().and_then(|b| {
                if b.linear_acceleration.is_some() {
                    Some("base.linear_acceleration")
                } else if b.angular_acceleration.is_some() {
                    Some("base.angular_acceleration")
                } else {
                    None
                }
            });
            if let Some(key) = st.a.as_ref().map(|_| "a").or(base_acc) {
                return Err(state::StateError {
                    file: name,
                    key: key.into(),
                    message: "not allowed in --initial (accelerations are simulated)".into(),
                }
                .into());
            }
            Some(st.to_vectors(&model, &name, "(state)")?)
        }
        None => None,
    };
    let mut contact = crate::contact::ContactParams::default();
    contact.friction = args.friction;
    let opts = SimOptions {
        dt: args.dt.unwrap_or(DEFAULT_DT),
        integrator,
        tol: args.tol,
        ground: if args.no_ground {
            None
        } else {
            Some(args.ground.unwrap_or(0.0))
        },
        contact,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        ..SimOptions::default()
    }
    .with_islands(None, args.no_sleep.then_some(false), args.threads);
    // The page's geometry is read before anything is simulated (a missing mesh
    // is reported at once).
    let geometry = match &args.html {
        Some(_) => Some(crate::cli::view::Geometry::load(
            &model,
            &args.urdf,
            &args.package_path,
        )?),
        None => None,
    };
    Ok((model, init, opts, geometry, urdf_name, None))
}

/// A scene's run: models, obstacles, ground, friction and the starting state
/// from the file (scene.md).
pub(super) fn scene(
    args: &SimulateArgs,
    path: &std::path::Path,
    integrator: Option<Integrator>,
) -> Result<Setup, SimulateError> {
    let scene = crate::scene::Scene::from_file(path, &args.package_path)?;
    for w in &scene.warnings {
        warn(&format!("warning: {w}"));
    }
    let model = scene.model.clone();
    let init = state::StateVectors {
        q: scene.q0.clone(),
        v: scene.v0.clone(),
        a: nalgebra::DVector::zeros(model.nv),
        tau: scene.tau0.clone(),
        fext: Vec::new(),
        frames: Vec::new(),
        derivatives: false,
    };
    let opts = SimOptions {
        dt: args.dt.unwrap_or(DEFAULT_DT),
        integrator,
        tol: args.tol,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        ..SimOptions::of_scene(&scene)
    }
    .with_islands(None, args.no_sleep.then_some(false), args.threads);
    let geometry = match &args.html {
        Some(_) => Some(crate::cli::view::Geometry::load_scene(
            &scene,
            &args.package_path,
        )?),
        None => None,
    };
    // the scene's loop constraints (mechanisms.md §"Simulation")
    let loops = (!scene.constraints.items.is_empty()).then(|| scene.constraints.clone());
    Ok((model, Some(init), opts, geometry, scene.file.clone(), loops))
}
