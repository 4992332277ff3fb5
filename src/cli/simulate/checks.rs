//! `urdyn simulate`'s checks: the options before anything is read, and the
//! start's violations (one warning line each) before anything is simulated.

use super::{warn, SimulateArgs, SimulateError};
use crate::cli::output::not_an_input;
use crate::sim::{Integrator, Simulation};

/// Checks every option's value and combination; returns the integrator asked for.
pub(super) fn options(args: &SimulateArgs) -> Result<Option<Integrator>, SimulateError> {
    if !(args.duration.is_finite() && args.duration >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--duration must be a non-negative number (got {})",
            args.duration
        )));
    }
    if let Some(dt) = args.dt
        && !(dt.is_finite() && dt > 0.0)
    {
        return Err(SimulateError::Option(format!(
            "--dt must be a positive number (got {dt})"
        )));
    }
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return Err(SimulateError::Option(format!(
            "--tol must be a positive number (got {})",
            args.tol
        )));
    }
    if !(args.friction.is_finite() && args.friction >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--friction must be a non-negative number (got {})",
            args.friction
        )));
    }
    if args.every == 0 {
        return Err(SimulateError::Option("--every must be at least 1".into()));
    }
    if !(args.armature.is_finite() && args.armature >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--armature must be a non-negative number (got {})",
            args.armature
        )));
    }
    if let Some(h) = args.above_ground {
        if !h.is_finite() {
            return Err(SimulateError::Option(format!(
                "--above-ground must be a finite number (got {h})"
            )));
        }
        if !args.floating_base {
            return Err(SimulateError::Option(
                "--above-ground needs --floating-base (a fixed root cannot be moved)".into(),
            ));
        }
    }
    let integrator = match &args.integrator {
        None => None,
        Some(n) => Some(Integrator::from_name(n).ok_or_else(|| {
            let names: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
            SimulateError::Option(format!(
                "--integrator: unknown integrator \"{n}\" (one of: {})",
                names.join(", ")
            ))
        })?),
    };
    if let Some(g) = args.gravity {
        if !g.iter().all(|x| x.is_finite()) {
            return Err(SimulateError::Option(
                "--gravity: non-finite component".into(),
            ));
        }
    }
    if let Some(g) = args.ground {
        if !g.is_finite() {
            return Err(SimulateError::Option(
                "--ground must be a finite number".into(),
            ));
        }
    }
    if let (Some(scene), Some(k)) = (&args.scene, &args.key) {
        return Err(SimulateError::Option(format!(
            "--key {k}: keyframes belong to MJCF files, not to the scene {}",
            scene.display()
        )));
    }
    if let Some(scene) = &args.scene {
        let given = [
            (args.floating_base, "--floating-base"),
            (args.initial.is_some(), "--initial"),
            (args.above_ground.is_some(), "--above-ground"),
            (args.ground.is_some(), "--ground"),
            (args.no_ground, "--no-ground"),
        ];
        if let Some((_, opt)) = given.iter().find(|(g, _)| *g) {
            return Err(SimulateError::Option(format!(
                "{opt} is a per-model option: with --scene it lives in the scene file {} (scene.md)",
                scene.display()
            )));
        }
    }
    // an output naming an input (or the other output) would replace it
    let mut inputs: Vec<(&str, &std::path::Path)> = match &args.scene {
        Some(scene) => vec![("--scene", scene.as_path())],
        None => vec![("the model", args.urdf.as_path())],
    };
    inputs.extend(args.initial.as_deref().map(|p| ("--initial", p)));
    inputs.extend(args.controls.as_deref().map(|p| ("--controls", p)));
    if let Some(out) = &args.out {
        not_an_input(out, "--out", &inputs).map_err(SimulateError::Option)?;
        inputs.push(("--out", out.as_path()));
    }
    if let Some(html) = &args.html {
        not_an_input(html, "--html", &inputs).map_err(SimulateError::Option)?;
    }
    Ok(integrator)
}

/// Warns about a start that violates a constraint: one line for the ground
/// (its deepest link), one a joint outside its limits, one a pair of shapes
/// inside each other (a link in an obstacle or another body); the run
/// recovers gently.
pub(super) fn warn_start(sim: &Simulation, urdf_name: &str) {
    let violations = sim.start_violations();
    let in_ground: Vec<_> = violations
        .iter()
        .filter_map(|v| match v {
            crate::sim::Violation::Ground { link, depth } => Some((link, *depth)),
            _ => None,
        })
        .collect();
    if let Some(&(link, depth)) = in_ground.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        let others = match in_ground.len() - 1 {
            0 => String::new(),
            1 => " (and 1 other link)".into(),
            n => format!(" (and {n} other links)"),
        };
        warn(&format!(
            "warning: {urdf_name}: link \"{link}\" starts {depth:.4} m inside the ground{others}; pushed out at most {} m/s",
            sim.options().contact.max_push_speed
        ));
    }
    for v in violations.iter().filter(|v| {
        matches!(
            v,
            crate::sim::Violation::Limit { .. } | crate::sim::Violation::Overlap { .. }
        )
    }) {
        warn(&format!("warning: {urdf_name}: {v}"));
    }
}
