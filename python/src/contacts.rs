//! `sim.contacts()` and `sim.contact_forces()` (python.md §"Introspection,
//! contacts, batched control, pictures"): every contact point with both sides
//! named, the true normal, the force and the signed depth.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use urdyn::contact::ContactPoint;
use urdyn::nalgebra::Vector3;
use urdyn::sim::Simulation;

/// One contact point as `contacts()` lists it (world frame).
pub struct Contact {
    /// The side's URDF link (`MODEL/LINK` in a scene).
    pub link: String,
    /// The other side: a link, an obstacle's name or "ground".
    pub other: String,
    pub point: Vector3<f64>,
    /// Unit, from `other` into `link`.
    pub normal: Vector3<f64>,
    /// On `link` (N).
    pub force: Vector3<f64>,
    /// > 0 penetrating, < 0 a gap (m).
    pub depth: f64,
}

/// Every contact point: those the contact refresh at the end of the last step
/// found (within the contact margin; the points `penetration` and the CSV's
/// column are measured on), each with the force the last step's solve put on
/// the point of the same slot and features (zero if none), then any point that
/// carried force in the solve but is gone at the step's end (as the solve saw
/// it). A point between two links is listed once, `link` the one first in
/// `link_names` (a scene: the model first in the file), an obstacle or the
/// ground always `other`. `frames`: the model's link names and their order.
pub fn contacts(sim: &Simulation, frames: &HashMap<String, usize>) -> Vec<Contact> {
    let forces = sim.contact_forces();
    let mut used = vec![false; forces.len()];
    let mut out = Vec::with_capacity(sim.contact_points().len());
    for p in sim.contact_points() {
        let k = forces.iter().enumerate().position(|(k, f)| {
            !used[k]
                && f.point.slot == p.slot
                && f.point.key == p.key
                && f.point.geom == p.geom
                && f.point.other_geom == p.other_geom
        });
        let force = k.map_or_else(Vector3::zeros, |k| {
            used[k] = true;
            forces[k].force
        });
        out.push(entry(sim, frames, p, force));
    }
    for (f, _) in forces.iter().zip(&used).filter(|(_, u)| !**u) {
        out.push(entry(sim, frames, &f.point, f.force));
    }
    out
}

/// The entry of point `p` with force `force` on its `geom` side, sides ordered.
fn entry(
    sim: &Simulation,
    frames: &HashMap<String, usize>,
    p: &ContactPoint,
    force: Vector3<f64>,
) -> Contact {
    let link = sim.contact_link(p).unwrap_or("").to_string();
    let other = sim.contact_other_link(p).unwrap_or("ground").to_string();
    let c = Contact {
        link,
        other,
        point: p.point,
        normal: p.normal,
        force,
        depth: -p.gap,
    };
    // the other side first in link_names (an obstacle or the ground is never a link)
    let swap = match (frames.get(&c.link), frames.get(&c.other)) {
        (Some(a), Some(b)) => b < a,
        (None, Some(_)) => true,
        _ => false,
    };
    if swap {
        Contact {
            link: c.other,
            other: c.link,
            normal: -c.normal,
            force: -c.force,
            ..c
        }
    } else {
        c
    }
}

/// A contact as a dict: link, other, point, normal, force, depth.
pub fn to_dict<'py>(py: Python<'py>, c: &Contact) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let arr = |v: &Vector3<f64>| numpy::PyArray1::from_slice(py, v.as_slice());
    d.set_item("link", &c.link)?;
    d.set_item("other", &c.other)?;
    d.set_item("point", arr(&c.point))?;
    d.set_item("normal", arr(&c.normal))?;
    d.set_item("force", arr(&c.force))?;
    d.set_item("depth", c.depth)?;
    Ok(d)
}
