//! `<equality>` (mjcf.md §"What the file becomes", docs/theory.md §"MJCF
//! equality constraints"): `connect`, `weld` and linear `joint` equalities
//! become mechanisms.md's `point`, `frame` and `joint` loop constraints, with
//! MuJoCo's compiled anchors (its `eq_data`):
//!
//! - `connect` (bodies): a point `anchor` of body1 held on the point of body2
//!   (or the world) where it is at qpos0; (sites): site1's origin on site2's.
//! - `weld` (bodies): frame1 on body1 = (`relpose`'s position, its unit
//!   quaternion) when `relpose`'s quaternion is not zero, else the pose of
//!   frame2 relative to body1 at qpos0; frame2 on body2 = (`anchor`, identity).
//!   MuJoCo holds body1's point at frame1's position on body2's at `anchor`,
//!   and body2's orientation at body1's · relpose: both frames coincide.
//!   (sites): site1's frame on site2's.
//! - `joint`: q₁ − ref₁ = a₀ + a₁ (q₂ − ref₂) is `q₁ = a₁ q₂ + (a₀ + ref₁ − a₁ ref₂)`
//!   (no joint2: q₁ = a₀ + ref₁); a non-zero a₂…a₄ is not modelled.
//!
//! `solref`, `solimp`, `torquescale` do not apply (rigid constraints);
//! `active="false"` ones are kept, off. Tendon and flex equalities are one
//! "not modelled" line each and left out.

use super::attrs::Defaults;
use super::compile::{MjJointType, World};
use super::xml::El;
use super::MjcfError;
use crate::model::{Attachment, Constraint, ConstraintKind, Model};
use crate::spatial::Se3;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::collections::HashSet;

/// What a compiled equality holds (MuJoCo ids; poses in the bodies' frames).
#[derive(Clone, Debug, PartialEq)]
pub enum MjEqKind {
    /// Point `p1` of `body1` on point `p2` of `body2` (0: the world).
    Connect {
        /// body1 (MuJoCo id).
        body1: usize,
        /// body2 (0: the world).
        body2: usize,
        /// The point in body1's frame.
        p1: Vector3<f64>,
        /// The point in body2's frame.
        p2: Vector3<f64>,
    },
    /// Frame `f1` of `body1` on frame `f2` of `body2`.
    Weld {
        /// body1 (MuJoCo id).
        body1: usize,
        /// body2 (0: the world).
        body2: usize,
        /// The frame in body1's frame.
        f1: (Vector3<f64>, UnitQuaternion<f64>),
        /// The frame in body2's frame.
        f2: (Vector3<f64>, UnitQuaternion<f64>),
    },
    /// q[joint1] − ref₁ = a₀ + a₁ (q[joint2] − ref₂) (MuJoCo joint ids).
    Joint {
        /// joint1.
        joint1: usize,
        /// joint2, if any.
        joint2: Option<usize>,
        /// `polycoef[0]`.
        a0: f64,
        /// `polycoef[1]`.
        a1: f64,
    },
}

/// A compiled equality constraint.
#[derive(Clone, Debug, PartialEq)]
pub struct MjEquality {
    /// Its name (`equality_K` when unnamed, K its MuJoCo id).
    pub name: String,
    /// What it holds (`None`: a kind urdyn does not model, left out).
    pub kind: Option<MjEqKind>,
    /// `active` (off: kept, switched off at the start).
    pub active: bool,
    pub(crate) label: String,
}

type Orientation = UnitQuaternion<f64>;

const ATTRS: &[&str] = &[
    "name",
    "class",
    "active",
    "solref",
    "solimp",
    "body1",
    "body2",
    "site1",
    "site2",
    "anchor",
    "relpose",
    "torquescale",
    "joint1",
    "joint2",
    "polycoef",
    "tendon1",
    "tendon2",
    "flex",
];

/// Each MuJoCo body's world pose at qpos0 (the bodies' defined frames).
fn poses0(world: &World) -> Vec<Se3<f64>> {
    let mut x = vec![Se3::identity(); world.bodies.len()];
    for b in 1..world.bodies.len() {
        let body = &world.bodies[b];
        let own = Se3::new(body.quat.to_rotation_matrix().into_inner(), body.pos);
        x[b] = x[body.parent].compose(&own);
    }
    x
}

fn to_se3(f: &(Vector3<f64>, UnitQuaternion<f64>)) -> Se3<f64> {
    Se3::new(f.1.to_rotation_matrix().into_inner(), f.0)
}

/// Reads the `<equality>` sections into `world.equalities`.
pub(super) fn read(
    world: &mut World,
    sections: &[&El],
    defaults: &Defaults,
    not_modelled: &mut Vec<String>,
) -> Result<(), MjcfError> {
    let x0 = poses0(world);
    let mut names = HashSet::new();
    let mut skipped: Vec<(&'static str, usize)> = Vec::new();
    let mut skip = |what: &'static str| match skipped.iter_mut().find(|(w, _)| *w == what) {
        Some(s) => s.1 += 1,
        None => skipped.push((what, 1)),
    };
    for el in sections.iter().flat_map(|s| s.children.iter()) {
        let tag = el.tag.as_str();
        if !matches!(tag, "connect" | "weld" | "joint" | "tendon" | "flex") {
            return Err(el.err(format!("unknown element <{tag}> in <equality>")));
        }
        let a = defaults.resolve_as(el, "main", "equality")?;
        a.check_known(ATTRS)?;
        let id = world.equalities.len();
        let name = match el.attr("name") {
            Some(n) => {
                if !names.insert(n.to_string()) {
                    return Err(el.err(format!("name=\"{n}\": duplicate equality name")));
                }
                n.to_string()
            }
            None => format!("equality_{id}"),
        };
        let active = a.flag("active")?.unwrap_or(true);
        let body = |k: &str| -> Result<Option<usize>, MjcfError> {
            match el.attr(k) {
                None => Ok(None),
                Some(n) => world
                    .bodies
                    .iter()
                    .position(|b| b.name == n)
                    .map(Some)
                    .ok_or_else(|| a.err(k, "no such body")),
            }
        };
        let site = |k: &str| -> Result<Option<(usize, Vector3<f64>, Orientation)>, MjcfError> {
            let Some(n) = el.attr(k) else { return Ok(None) };
            for (b, body) in world.bodies.iter().enumerate() {
                if let Some((_, p, q)) = body.sites.iter().find(|s| s.0 == n) {
                    return Ok(Some((b, *p, *q)));
                }
            }
            Err(a.err(k, "no such site"))
        };
        let joint = |k: &str| -> Result<Option<usize>, MjcfError> {
            let Some(n) = el.attr(k) else { return Ok(None) };
            let j = world
                .joints
                .iter()
                .position(|j| j.name == n)
                .ok_or_else(|| a.err(k, "no such joint"))?;
            match world.joints[j].kind {
                MjJointType::Hinge | MjJointType::Slide => Ok(Some(j)),
                _ => Err(a.err(k, "a joint equality needs a hinge or slide joint")),
            }
        };
        let kind = match tag {
            "connect" | "weld" => {
                let (b1, b2, s1, s2) = (
                    body("body1")?,
                    body("body2")?,
                    site("site1")?,
                    site("site2")?,
                );
                let frames = match (b1, s1, s2) {
                    (Some(_), Some(_), _) => {
                        return Err(a.err("site1", "body1 and site1 both given: give one"))
                    }
                    (Some(_), None, Some(_)) => {
                        return Err(a.err("site2", "site2 belongs with site1, not body1"))
                    }
                    (Some(b1), None, None) => {
                        let b2 = b2.unwrap_or(0);
                        let anchor = Vector3::from(a.arr::<3>("anchor")?.unwrap_or([0.0; 3]));
                        if tag == "connect" {
                            // body2's point: where body1's anchor is at qpos0
                            let p2 = x0[b2].inv_act_point(&x0[b1].act_point(&anchor));
                            (
                                b1,
                                b2,
                                (anchor, UnitQuaternion::identity()),
                                (p2, UnitQuaternion::identity()),
                            )
                        } else {
                            let f2 = (anchor, UnitQuaternion::identity());
                            let rel = a
                                .arr::<7>("relpose")?
                                .unwrap_or([0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
                            let q = Quaternion::new(rel[3], rel[4], rel[5], rel[6]);
                            let f1 = if q.norm() > 0.0 {
                                (
                                    Vector3::new(rel[0], rel[1], rel[2]),
                                    UnitQuaternion::from_quaternion(q),
                                )
                            } else {
                                // frame2's pose in body1 at qpos0
                                let m = x0[b1].inverse().compose(&x0[b2]).compose(&to_se3(&f2));
                                let r = nalgebra::Rotation3::from_matrix_unchecked(m.rot);
                                (m.trans, UnitQuaternion::from_rotation_matrix(&r))
                            };
                            (b1, b2, f1, f2)
                        }
                    }
                    (None, Some((sb1, p1, q1)), Some((sb2, p2, q2))) => {
                        if el.attr("body2").is_some() {
                            return Err(a.err("body2", "body2 belongs with body1, not site1"));
                        }
                        (sb1, sb2, (p1, q1), (p2, q2))
                    }
                    (None, Some(_), None) => return Err(a.err("site2", "site1 needs site2")),
                    (None, None, _) => return Err(a.err("body1", "needs body1 or site1")),
                };
                let (body1, body2, f1, f2) = frames;
                Some(if tag == "connect" {
                    MjEqKind::Connect {
                        body1,
                        body2,
                        p1: f1.0,
                        p2: f2.0,
                    }
                } else {
                    MjEqKind::Weld {
                        body1,
                        body2,
                        f1,
                        f2,
                    }
                })
            }
            "joint" => {
                let j1 = joint("joint1")?.ok_or_else(|| a.err("joint1", "missing"))?;
                let j2 = joint("joint2")?;
                if j2 == Some(j1) {
                    return Err(a.err("joint2", "is joint1: both sides on one joint"));
                }
                let c = a.partial::<5>("polycoef", [0.0, 1.0, 0.0, 0.0, 0.0])?;
                if j2.is_some() && c[2..].iter().any(|x| *x != 0.0) {
                    skip("joint equalities with a non-linear polycoef");
                    None
                } else {
                    Some(MjEqKind::Joint {
                        joint1: j1,
                        joint2: j2,
                        a0: c[0],
                        a1: c[1],
                    })
                }
            }
            "tendon" => {
                skip("tendon equalities");
                None
            }
            _ => {
                skip("flex equalities");
                None
            }
        };
        world.equalities.push(MjEquality {
            name,
            kind,
            active,
            label: el.label(),
        });
    }
    for (what, n) in skipped {
        not_modelled.push(format!("{n} {what}: not modelled (left out)"));
    }
    Ok(())
}

/// Lowers the world's equalities into `model.equalities` (`ub[b]`, `ub_m[b]`:
/// the urdyn body of MuJoCo body b and b's frame in it). An equality whose two
/// sides are welded to one body holds nothing: reported and left out.
pub(super) fn lower(
    world: &World,
    ub: &[usize],
    ub_m: &[Se3<f64>],
    model: &mut Model,
) -> Result<(), MjcfError> {
    let attach = |b: usize, f: &(Vector3<f64>, UnitQuaternion<f64>)| Attachment {
        body: ub[b],
        link: (b != 0).then(|| world.bodies[b].name.clone()),
        local: ub_m[b].compose(&to_se3(f)),
    };
    let dof = |j: usize| model.dofs.iter().find(|d| d.name == world.joints[j].name);
    let mut items = Vec::new();
    let mut active = Vec::new();
    for e in &world.equalities {
        let Some(kind) = &e.kind else { continue };
        let c = match kind {
            MjEqKind::Connect {
                body1,
                body2,
                p1,
                p2,
            } => {
                let u = UnitQuaternion::identity();
                (
                    ConstraintKind::Point,
                    attach(*body1, &(*p1, u)),
                    attach(*body2, &(*p2, u)),
                )
            }
            MjEqKind::Weld {
                body1,
                body2,
                f1,
                f2,
            } => (
                ConstraintKind::Frame,
                attach(*body1, f1),
                attach(*body2, f2),
            ),
            MjEqKind::Joint {
                joint1,
                joint2,
                a0,
                a1,
            } => {
                let (Some(d1), d2) = (dof(*joint1), joint2.map(dof)) else {
                    return Err(MjcfError::new(
                        &model_file(model),
                        Some(e.label.clone()),
                        "joint1: not a degree of freedom of the model",
                    ));
                };
                let r1 = world.joints[*joint1].reference;
                let (second, offset) = match (joint2, d2) {
                    (Some(j2), Some(Some(d2))) => {
                        let r2 = world.joints[*j2].reference;
                        (Some((d2.iq, d2.iv)), a0 + r1 - a1 * r2)
                    }
                    (None, _) => (None, a0 + r1),
                    _ => {
                        return Err(MjcfError::new(
                            &model_file(model),
                            Some(e.label.clone()),
                            "joint2: not a degree of freedom of the model",
                        ));
                    }
                };
                let w = Attachment {
                    body: 0,
                    link: None,
                    local: Se3::identity(),
                };
                let prismatic = matches!(d1.kind, crate::model::JointKind::Prismatic(_));
                (
                    ConstraintKind::Joint {
                        q1: d1.iq,
                        v1: d1.iv,
                        second,
                        ratio: if joint2.is_some() { *a1 } else { 1.0 },
                        offset,
                        prismatic,
                    },
                    w.clone(),
                    w,
                )
            }
        };
        let (kind, a, b) = c;
        if !matches!(kind, ConstraintKind::Joint { .. }) && a.body == b.body {
            model.report.ignored.push(format!(
                "equality \"{}\": both sides are welded to one body: it holds nothing (left out)",
                e.name
            ));
            continue;
        }
        items.push(Constraint {
            name: e.name.clone(),
            kind,
            a,
            b,
            hold: false,
        });
        active.push(e.active);
    }
    model.equalities = crate::model::Constraints { items };
    model.equality_active = active;
    Ok(())
}

fn model_file(model: &Model) -> String {
    model
        .source
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "(mjcf)".into())
}
