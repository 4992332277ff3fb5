//! `<tendon>` (mjcf.md §"What the file becomes", docs/theory.md §"MJCF fixed
//! tendons"): a fixed tendon is a linear combination of joints, length
//! L = Σᵢ cᵢ qᵢ, velocity L̇ = Σᵢ cᵢ q̇ᵢ, and a force f along it acts on the
//! joints as τᵢ = cᵢ f. Its spring −k (L − L₀), damper −d L̇, its limits
//! lo ≤ L ≤ hi and an actuator on it (L_act = gear·L) are the file's.
//!
//! Lowered exactly where the tendon moves one joint (one non-zero cᵢ = c):
//! then L = c q, and the tendon's spring is the joint's (k c² about L₀ / c),
//! its damper the joint's (d c²), its range the joint's (lo / c, hi / c, the
//! two swapped when c < 0, intersected with the joint's own), an actuator on it
//! one on the joint with gear·c. A tendon on several joints acts through an
//! actuator with a constant force (motor-like: no length or velocity term), as
//! a constant generalized force gear·f·c. A tendon on several joints that has a
//! spring, a damper or a range, or a length- or velocity-dependent actuator,
//! couples its joints, which urdyn's servos (diagonal) do not model: reported.
//! A tendon with none of these acts on nothing and is silently kept out.
//! Spatial tendons are reported as not modelled.

use super::attrs::Defaults;
use super::compile::World;
use super::xml::El;
use super::MjcfError;
use std::collections::HashSet;

/// A compiled fixed tendon (MuJoCo's `tendon_*` and `wrap_*` of one tendon).
#[derive(Clone, Debug, PartialEq)]
pub struct MjTendon {
    /// Its name (`tendon_K` when unnamed, K its MuJoCo id).
    pub name: String,
    /// (MuJoCo joint id, coefficient): L = Σ coef · q.
    pub coefs: Vec<(usize, f64)>,
    /// `range` when limited.
    pub range: Option<(f64, f64)>,
    /// Spring stiffness k.
    pub stiffness: f64,
    /// Spring rest length L₀ (MuJoCo's: the length at the joints' springref unless given).
    pub springlength: f64,
    /// Damping d.
    pub damping: f64,
    /// `false` for a spatial tendon (kept for its id; not modelled).
    pub fixed: bool,
}

impl MjTendon {
    /// The joints it moves (non-zero coefficients).
    pub fn active(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.coefs.iter().copied().filter(|(_, c)| *c != 0.0)
    }
}

const ATTRS: &[&str] = &[
    "name",
    "class",
    "group",
    "limited",
    "actuatorfrclimited",
    "range",
    "actuatorfrcrange",
    "solreflimit",
    "solimplimit",
    "solreffriction",
    "solimpfriction",
    "frictionloss",
    "springlength",
    "width",
    "material",
    "margin",
    "stiffness",
    "damping",
    "armature",
    "rgba",
    "user",
];

/// Reads the `<tendon>` sections into `world.tendons` (MuJoCo's order), lines
/// for what is not modelled into `not_modelled`.
pub(super) fn read(
    world: &mut World,
    sections: &[&El],
    defaults: &Defaults,
    autolimits: bool,
    not_modelled: &mut Vec<String>,
) -> Result<(), MjcfError> {
    let mut note = |s: &str| {
        if !not_modelled.iter().any(|n| n == s) {
            not_modelled.push(s.to_string());
        }
    };
    let mut names = HashSet::new();
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        let fixed = match el.tag.as_str() {
            "fixed" => true,
            "spatial" => false,
            t => return Err(el.err(format!("unknown element <{t}> in <tendon>"))),
        };
        let a = defaults.resolve_as(el, "main", "tendon")?;
        a.check_known(ATTRS)?;
        let id = world.tendons.len();
        let name = match el.attr("name") {
            Some(n) => {
                if !names.insert(n.to_string()) {
                    return Err(el.err(format!("name=\"{n}\": duplicate tendon name")));
                }
                n.to_string()
            }
            None => format!("tendon_{id}"),
        };
        let range = super::actuators::limited(&a, "limited", "range", autolimits)?;
        let stiffness = a.nonneg("stiffness", 0.0)?;
        let damping = a.nonneg("damping", 0.0)?;
        if a.nonneg("frictionloss", 0.0)? > 0.0 {
            note("tendon frictionloss");
        }
        if a.nonneg("armature", 0.0)? > 0.0 {
            note("tendon armature");
        }
        let mut coefs = Vec::new();
        if fixed {
            for j in &el.children {
                if j.tag != "joint" {
                    return Err(j.err(format!("unknown element <{}> in <fixed>", j.tag)));
                }
                let ja = defaults.resolve_as(j, "main", "")?;
                ja.check_known(&["joint", "coef"])?;
                let jn = ja
                    .get("joint")
                    .ok_or_else(|| ja.err("joint", "is required"))?;
                let k = world
                    .joints
                    .iter()
                    .position(|x| x.name == jn)
                    .ok_or_else(|| ja.err("joint", format!("\"{jn}\": no such joint")))?;
                if !matches!(
                    world.joints[k].kind,
                    super::compile::MjJointType::Hinge | super::compile::MjJointType::Slide
                ) {
                    return Err(ja.err("joint", "a fixed tendon takes hinge and slide joints only"));
                }
                let c = ja.num("coef")?.unwrap_or(1.0);
                coefs.push((k, c));
            }
        } else {
            note("spatial tendons");
        }
        // MuJoCo: springlength -1 (the default) is the length at the joints'
        // spring rest positions (qpos_spring: each joint's springref).
        let l0: f64 = coefs
            .iter()
            .map(|&(j, c)| c * world.joints[j].springref)
            .sum();
        let springlength = match a.numbers("springlength")? {
            Some(v) if v.first().is_some_and(|x| *x >= 0.0) => {
                if v.len() > 1 && v[1] != v[0] {
                    note("tendon springs with a dead band (two springlength values)");
                }
                v[0]
            }
            _ => l0,
        };
        world.tendons.push(MjTendon {
            name,
            coefs,
            range,
            stiffness,
            springlength,
            damping,
            fixed,
        });
    }
    Ok(())
}

/// Lowers the tendons that act (module doc) into `model`'s joints; lines for
/// the couplings urdyn does not model into `model.report.warnings`. Returns,
/// per tendon, its one joint's dof index and coefficient when it moves one.
pub(super) fn lower(
    world: &World,
    model: &mut crate::model::Model,
    dof_of: &dyn Fn(usize) -> Option<usize>,
) -> Vec<Option<(usize, f64)>> {
    let mut single = Vec::with_capacity(world.tendons.len());
    let mut coupled = 0usize;
    for t in &world.tendons {
        let act: Vec<(usize, f64)> = t.active().collect();
        let one = match act.as_slice() {
            [(j, c)] => dof_of(*j).map(|d| (d, *c)),
            _ => None,
        };
        single.push(one);
        if !t.fixed {
            continue;
        }
        let Some((d, c)) = one else {
            if act.len() > 1 && (t.stiffness > 0.0 || t.damping > 0.0 || t.range.is_some()) {
                coupled += 1;
            }
            continue;
        };
        let dof = &mut model.dofs[d];
        if t.stiffness > 0.0 {
            // k_j (q − r_j) + k c² (q − L₀/c) = (k_j + k c²)(q − r) with r the
            // stiffness-weighted rest position.
            let (kj, kt) = (dof.stiffness, t.stiffness * c * c);
            dof.springref = (kj * dof.springref + kt * t.springlength / c) / (kj + kt);
            dof.stiffness = kj + kt;
        }
        dof.damping += t.damping * c * c;
        if let Some((lo, hi)) = t.range {
            let (a, b) = if c > 0.0 {
                (lo / c, hi / c)
            } else {
                (hi / c, lo / c)
            };
            let l = &mut dof.limits;
            l.lower = Some(l.lower.map_or(a, |x| x.max(a)));
            l.upper = Some(l.upper.map_or(b, |x| x.min(b)));
        }
    }
    if coupled > 0 {
        model.report.warnings.push(format!(
            "{coupled} fixed tendon(s) on several joints with a spring, damper or range: not modelled (coupled joints)"
        ));
    }
    single
}
