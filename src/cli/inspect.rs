//! `urdyn inspect`: the model as a person reads it.

use crate::contact::resolve_mesh_path;
use crate::model::{Model, Shape};
use std::fmt::Write;
use std::path::PathBuf;

/// Every warning of the import report plus the inspection's own (mesh files
/// that are not found), in the order `inspect` prints them.
pub fn warnings(model: &Model, package_paths: &[PathBuf]) -> Vec<String> {
    let mut warnings = model.report.warnings.clone();
    for c in &model.collisions {
        if let Shape::Mesh { filename, .. } = &c.shape {
            if resolve_mesh_path(filename, model.source.as_deref(), package_paths).is_none() {
                warnings.push(format!(
                    "link \"{}\": mesh file \"{filename}\" not found (needed only for contact)",
                    c.link
                ));
            }
        }
    }
    warnings
}

/// A human-readable report: the tree, the DoFs, masses, merged links, collision
/// geometry and warnings.
pub fn report(model: &Model, package_paths: &[PathBuf]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "robot \"{}\"{}",
        model.name,
        if model.floating_base {
            " (floating base)"
        } else {
            " (fixed base)"
        }
    );
    let _ = writeln!(
        s,
        "nq = {}, nv = {}, bodies = {}",
        model.nq,
        model.nv,
        model.nbodies - 1
    );
    let _ = writeln!(s, "\nkinematic tree (link [joint to parent]):");
    for line in &model.report.tree {
        let _ = writeln!(s, "  {line}");
    }
    let _ = writeln!(s, "\ndegrees of freedom (engine order):");
    if model.floating_base {
        let _ = writeln!(
            s,
            "  base: x y z (position) + unit quaternion; v = body-frame linear, angular"
        );
    }
    for (k, d) in model.dofs.iter().enumerate() {
        let lim = match (d.limits.lower, d.limits.upper) {
            _ if d.kind.nv() != 1 => {
                format!("{} ({} q, {} v)", d.kind.name(), d.kind.nq(), d.kind.nv())
            }
            (Some(l), Some(u)) => format!("[{l}, {u}]"),
            _ if d.continuous => "continuous".to_string(),
            _ => "no position limit known".to_string(),
        };
        let _ = writeln!(
            s,
            "  {k:3} {}  {lim}  damping {} friction {}",
            d.name, d.damping, d.friction
        );
    }
    let _ = writeln!(s, "\nbodies (links merged through fixed joints):");
    for b in 1..model.nbodies {
        let i = &model.inertias[b];
        let _ = writeln!(
            s,
            "  {} (joint \"{}\"): mass {:.6} kg",
            model.body_link_names[b], model.body_joint_names[b], i.mass
        );
    }
    let _ = writeln!(
        s,
        "total mass of moving bodies: {:.6} kg",
        model.total_mass()
    );
    if !model.report.merged.is_empty() {
        let _ = writeln!(s, "\nmerged links:");
        for (l, into) in &model.report.merged {
            let _ = writeln!(s, "  {l} -> {into}");
        }
    }
    let _ = writeln!(s, "\ncollision geometry:");
    if model.collisions.is_empty() {
        let _ = writeln!(s, "  none");
    }
    for c in &model.collisions {
        let extra = match &c.shape {
            Shape::Mesh { filename, .. } => format!(" {filename}"),
            _ => String::new(),
        };
        let _ = writeln!(s, "  {}: {}{}", c.link, c.shape.kind(), extra);
    }
    if !model.report.ignored.is_empty() {
        let _ = writeln!(s, "\nignored:");
        for i in &model.report.ignored {
            let _ = writeln!(s, "  {i}");
        }
    }
    let warnings = warnings(model, package_paths);
    let _ = writeln!(s, "\nwarnings:");
    if warnings.is_empty() {
        let _ = writeln!(s, "  none");
    }
    for w in &warnings {
        let _ = writeln!(s, "  {w}");
    }
    s
}

/// `inspect --json` (mjcf.md): each link's (MJCF body's) own mass, centre of mass
/// and inertia about it in its frame, the q and v names, the warnings.
pub fn json(model: &Model, package_paths: &[PathBuf]) -> serde_json::Value {
    let mut bodies = serde_json::Map::new();
    for b in &model.report.bodies {
        let i = &b.inertia;
        let rows: Vec<[f64; 3]> = (0..3).map(|r| [i[(r, 0)], i[(r, 1)], i[(r, 2)]]).collect();
        bodies.insert(
            b.name.clone(),
            serde_json::json!({"mass": b.mass, "com": [b.com.x, b.com.y, b.com.z], "inertia": rows}),
        );
    }
    let (qn, vn) = (model.q_names(), model.v_names());
    serde_json::json!({
        "bodies": bodies,
        "q_names": qn,
        "v_names": vn,
        "warnings": warnings(model, package_paths),
    })
}
