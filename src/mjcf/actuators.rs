//! `<actuator>` (mjcf.md §"What the file becomes"): MuJoCo's actuators in its
//! order, each as its general form — force f = gain(L, L̇)·u + bias(L, L̇) with an
//! affine gain g₀ + g₁L + g₂L̇ and an affine bias b₀ + b₁L + b₂L̇, L = gear·q the
//! actuator's length on its joint (docs/theory.md §"MJCF actuators"). `motor`,
//! `position` (`kp`, `kv`), `velocity` (`kv`), `damper` and `general` (fixed or
//! affine gain and bias) are these numbers; the rest (muscles, activation
//! dynamics, tendon, site and body transmissions) keep their place in the
//! control vector (nu as MuJoCo's) and are one "not modelled" line each.

use super::attrs::{Attrs, Defaults};
use super::compile::{MjJointType, World};
use super::xml::El;
use super::MjcfError;
use std::collections::HashSet;

/// A compiled actuator (MuJoCo's `actuator_*` of one actuator).
#[derive(Clone, Debug, PartialEq)]
pub struct MjActuator {
    /// Its name (`actuator_K` when unnamed, K its MuJoCo id).
    pub name: String,
    /// The MuJoCo joint it drives; `None`: not modelled (it keeps its control slot).
    pub joint: Option<usize>,
    /// The fixed tendon it pulls (MuJoCo tendon id), when that is its transmission.
    pub tendon: Option<usize>,
    /// `gear[0]`: L = gear·q, the joint's generalized force gear·f.
    pub gear: f64,
    /// Affine gain g₀ + g₁L + g₂L̇ (MuJoCo's `gainprm[0..3]`; fixed: g₁ = g₂ = 0).
    pub gain: [f64; 3],
    /// Affine bias b₀ + b₁L + b₂L̇ (`biasprm[0..3]`; none: zeros).
    pub bias: [f64; 3],
    /// `ctrlrange` when control-limited: u is clamped into it.
    pub ctrlrange: Option<(f64, f64)>,
    /// `forcerange` when force-limited: f is clamped into it.
    pub forcerange: Option<(f64, f64)>,
}

const COMMON: &[&str] = &[
    "name",
    "group",
    "ctrllimited",
    "forcelimited",
    "actlimited",
    "ctrlrange",
    "forcerange",
    "actrange",
    "lengthrange",
    "gear",
    "cranklength",
    "user",
    "joint",
    "jointinparent",
    "tendon",
    "cranksite",
    "slidersite",
    "site",
    "refsite",
    "body",
    "actdim",
    "actearly",
    "nsample",
    "interp",
    "delay",
];

/// Extra attributes of each element kind (beyond [`COMMON`]).
fn own_attrs(tag: &str) -> Option<&'static [&'static str]> {
    Some(match tag {
        "general" => &[
            "dyntype", "gaintype", "biastype", "dynprm", "gainprm", "biasprm",
        ],
        "motor" => &[],
        "position" => &["kp", "kv", "dampratio", "timeconst", "inheritrange"],
        "velocity" => &["kv"],
        "damper" => &["kv"],
        "intvelocity" => &["kp", "kv", "dampratio", "inheritrange"],
        "cylinder" => &["timeconst", "area", "diameter", "bias"],
        "muscle" => &[
            "timeconst",
            "tausmooth",
            "range",
            "force",
            "scale",
            "lmin",
            "lmax",
            "vmax",
            "fpmax",
            "fvmax",
        ],
        "adhesion" => &["gain"],
        "plugin" => &["plugin", "instance", "dyntype", "dynprm", "actrange"],
        _ => return None,
    })
}

/// `limited="true|false|auto"` with MuJoCo's `autolimits`: limited when a range is given.
pub(super) fn limited(
    a: &Attrs,
    flag: &str,
    range: &str,
    autolimits: bool,
) -> Result<Option<(f64, f64)>, MjcfError> {
    let r = a.arr::<2>(range)?;
    let on = match a.get(flag).unwrap_or("auto") {
        "true" => true,
        "false" => false,
        "auto" => autolimits && r.is_some(),
        _ => return Err(a.err(flag, "must be true, false or auto")),
    };
    match (on, r) {
        (false, _) => Ok(None),
        (true, None) => Err(a.err(flag, format!("limited without a {range}"))),
        (true, Some([lo, hi])) if lo > hi => Err(a.err(range, "lower bound above upper bound")),
        (true, Some([lo, hi])) => Ok(Some((lo, hi))),
    }
}

/// Reads the `<actuator>` sections into `world.actuators`, lines for what is
/// not modelled into `not_modelled`.
pub(super) fn read(
    world: &mut World,
    sections: &[&El],
    defaults: &Defaults,
    autolimits: bool,
    not_modelled: &mut Vec<String>,
) -> Result<(), MjcfError> {
    let mut names = HashSet::new();
    let mut note = |s: String| {
        if !not_modelled.contains(&s) {
            not_modelled.push(s);
        }
    };
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        let tag = el.tag.as_str();
        let own = own_attrs(tag)
            .ok_or_else(|| el.err(format!("unknown element <{tag}> in <actuator>")))?;
        let a = defaults.resolve(el, "main")?;
        let known: Vec<&str> = COMMON.iter().chain(own).copied().collect();
        a.check_known(&known)?;
        let id = world.actuators.len();
        let name = match el.attr("name") {
            Some(n) => {
                if !names.insert(n.to_string()) {
                    return Err(el.err(format!("name=\"{n}\": duplicate actuator name")));
                }
                n.to_string()
            }
            None => format!("actuator_{id}"),
        };
        let ctrlrange = limited(&a, "ctrllimited", "ctrlrange", autolimits)?;
        let forcerange = limited(&a, "forcelimited", "forcerange", autolimits)?;
        let gear = a.partial::<6>("gear", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0])?;
        // the transmission: exactly one target
        let targets: Vec<&str> = [
            "joint",
            "jointinparent",
            "tendon",
            "cranksite",
            "site",
            "body",
        ]
        .into_iter()
        .filter(|k| el.attr(k).is_some())
        .collect();
        if targets.len() != 1 {
            return Err(
                el.err("needs exactly one of joint, jointinparent, tendon, cranksite, site, body")
            );
        }
        let target = targets[0];
        let tname = el.attr(target).unwrap_or_default();
        let mut joint = None;
        let mut tendon = None;
        match target {
            "joint" | "jointinparent" => {
                let j = world
                    .joints
                    .iter()
                    .position(|j| j.name == tname)
                    .ok_or_else(|| a.err(target, "no such joint"))?;
                match world.joints[j].kind {
                    MjJointType::Hinge | MjJointType::Slide => joint = Some(j),
                    _ => note("actuators on ball or free joints".into()),
                }
            }
            "tendon" => {
                let t = world
                    .tendons
                    .iter()
                    .position(|t| t.name == tname)
                    .ok_or_else(|| a.err(target, "no such tendon"))?;
                match world.tendons[t].fixed {
                    true => tendon = Some(t),
                    false => note("actuators on spatial tendons".into()),
                }
            }
            "cranksite" => note("slider-crank actuators".into()),
            "site" => note("actuators on sites".into()),
            _ => note("actuators on bodies (adhesion)".into()),
        }
        let kv = |k: &str| -> Result<f64, MjcfError> {
            let x = a.num(k)?.unwrap_or(if k == "kp" { 1.0 } else { 0.0 });
            if x < 0.0 {
                return Err(a.err(k, "must not be negative"));
            }
            Ok(x)
        };
        let (gain, bias) = match tag {
            "motor" => ([1.0, 0.0, 0.0], [0.0; 3]),
            "position" => {
                if a.get("dampratio").is_some() || a.get("timeconst").is_some() {
                    note("position actuators' dampratio and timeconst".into());
                }
                if a.get("inheritrange").is_some() {
                    note("position actuators' inheritrange".into());
                }
                let (kp, kv) = (kv("kp")?, kv("kv")?);
                ([kp, 0.0, 0.0], [0.0, -kp, -kv])
            }
            "velocity" => {
                let kv = a.num("kv")?.unwrap_or(1.0);
                if kv < 0.0 {
                    return Err(a.err("kv", "must not be negative"));
                }
                ([kv, 0.0, 0.0], [0.0, 0.0, -kv])
            }
            "damper" => {
                let kv = kv("kv")?;
                if ctrlrange.is_none_or(|(lo, _)| lo < 0.0) {
                    return Err(el.err("a damper needs a non-negative ctrlrange"));
                }
                ([0.0, 0.0, -kv], [0.0; 3])
            }
            "general" => general(&a, &mut note)?,
            t => {
                note(format!("<{t}> actuators (activation dynamics)"));
                joint = None;
                tendon = None;
                ([0.0; 3], [0.0; 3])
            }
        };
        if gear[1..].iter().any(|g| *g != 0.0) && joint.is_some() {
            note("gear beyond its first entry on a hinge or slide joint (unused there)".into());
        }
        world.actuators.push(MjActuator {
            name,
            joint,
            tendon,
            gear: gear[0],
            gain,
            bias,
            ctrlrange,
            forcerange,
        });
    }
    Ok(())
}

/// A `<general>` actuator's gain and bias (fixed or affine; activation
/// dynamics are not modelled).
#[allow(clippy::type_complexity)]
fn general(a: &Attrs, note: &mut impl FnMut(String)) -> Result<([f64; 3], [f64; 3]), MjcfError> {
    if a.get("dyntype").is_some_and(|d| d != "none") {
        note("actuator activation dynamics (dyntype)".into());
    }
    let read = |k: &str, init: [f64; 3]| -> Result<[f64; 3], MjcfError> {
        let v = a.numbers(k)?.unwrap_or_default();
        if v.len() > 10 {
            return Err(a.err(k, "has more than 10 numbers"));
        }
        let mut out = init;
        for (o, x) in out.iter_mut().zip(v) {
            *o = x;
        }
        Ok(out)
    };
    let mut gain = read("gainprm", [1.0, 0.0, 0.0])?;
    let mut bias = read("biasprm", [0.0; 3])?;
    match a.get("gaintype").unwrap_or("fixed") {
        "fixed" => {
            gain[1] = 0.0;
            gain[2] = 0.0
        }
        "affine" => {}
        t => {
            note(format!("actuator gaintype \"{t}\""));
            gain = [0.0; 3];
        }
    }
    match a.get("biastype").unwrap_or("none") {
        "none" => bias = [0.0; 3],
        "affine" => {}
        t => {
            note(format!("actuator biastype \"{t}\""));
            bias = [0.0; 3];
        }
    }
    Ok((gain, bias))
}

/// The model's actuators and keyframes from the world's (after lowering: each
/// actuator's joint as its q and v coordinates; a force range as the joint's
/// effort limit where that is exact — one actuator on a joint without a
/// spring, a range symmetric about 0 — else a warning).
pub(super) fn lower(world: &World, model: &mut crate::model::Model) -> Result<(), MjcfError> {
    let joint_dof: Vec<Option<usize>> = world
        .joints
        .iter()
        .map(|j| {
            model
                .dofs
                .iter()
                .position(|d| d.name == j.name && d.kind.nv() == 1)
        })
        .collect();
    let dof_of = |j: usize| joint_dof[j];
    let single = super::tendons::lower(world, model, &dof_of);
    let mut acts = Vec::with_capacity(world.actuators.len());
    let mut per_dof = vec![0usize; model.dofs.len()];
    let mut coupled = 0usize;
    for a in &world.actuators {
        // (dof, the tendon's coefficient on it) or a constant force over several
        let (mut d, mut gear, mut moment) = (a.joint.and_then(dof_of), a.gear, Vec::new());
        if let Some(t) = a.tendon {
            if let Some((dt, c)) = single[t] {
                d = Some(dt);
                gear = a.gear * c;
            } else if a.gain[1..] == [0.0, 0.0] && a.bias[1..] == [0.0, 0.0] {
                moment = world.tendons[t]
                    .active()
                    .filter_map(|(j, c)| dof_of(j).map(|k| (model.dofs[k].iv, a.gear * c)))
                    .collect();
            } else {
                coupled += 1;
            }
        }
        if let Some(d) = d {
            per_dof[d] += 1;
        }
        acts.push((a, d, gear, moment));
    }
    if coupled > 0 {
        model.report.warnings.push(format!(
            "{coupled} actuator(s) with a length or velocity term on a fixed tendon over several joints: not modelled (coupled joints)"
        ));
    }
    let mut out = Vec::with_capacity(acts.len());
    for (a, d, gear, moment) in acts {
        if a.forcerange.is_some() && !moment.is_empty() {
            model.report.warnings.push(format!(
                "actuator \"{}\": its forcerange is not modelled (on a tendon over several joints)",
                a.name
            ));
        }
        if let (Some(d), Some((lo, hi))) = (d, a.forcerange) {
            let dof = &mut model.dofs[d];
            if per_dof[d] == 1 && dof.stiffness == 0.0 && lo == -hi {
                dof.limits.effort = Some(gear.abs() * hi);
            } else {
                model.report.warnings.push(format!(
                    "actuator \"{}\": its forcerange is not modelled (only a range symmetric about 0 of the joint's only actuator, on a joint without a spring, is)",
                    a.name
                ));
            }
        }
        out.push(crate::model::Actuator {
            name: a.name.clone(),
            dof: d.map(|d| (model.dofs[d].iv, model.dofs[d].iq)),
            moment,
            gear,
            gain: a.gain,
            bias: a.bias,
            ctrlrange: a.ctrlrange,
            forcerange: a.forcerange,
        });
    }
    model.actuators = out;
    let bad = |k: &str, e: crate::model::DimensionError| {
        MjcfError::new(
            "",
            Some(format!("<key name=\"{k}\">")),
            format!("cannot convert its state: {e}"),
        )
    };
    let mut keys = Vec::with_capacity(world.keys.len());
    for k in &world.keys {
        let qpos = match &k.qpos {
            Some(p) => nalgebra::DVector::from_column_slice(p),
            None => super::to_mujoco_qpos(model, &model.neutral()).map_err(|e| bad(&k.name, e))?,
        };
        let q = super::from_mujoco_qpos(model, &qpos).map_err(|e| bad(&k.name, e))?;
        let v = match &k.qvel {
            Some(qv) => {
                super::from_mujoco_qvel(model, &qpos, &nalgebra::DVector::from_column_slice(qv))
                    .map_err(|e| bad(&k.name, e))?
            }
            None => nalgebra::DVector::zeros(model.nv),
        };
        keys.push(crate::model::Keyframe {
            name: k.name.clone(),
            q,
            v,
            ctrl: k.ctrl.clone(),
        });
    }
    model.keyframes = keys;
    Ok(())
}
