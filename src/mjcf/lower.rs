//! Lowering MuJoCo's compiled [`World`] into a [`Model`] (docs/theory.md §"MJCF
//! import"). MuJoCo places a body at `B₀ · T₁(q₁) ⋯ Tₙ(qₙ)`: `B₀` its frame in its
//! parent's, each hinge `Tₖ = Trans(pₖ) Rot(aₖ, qₖ − refₖ) Trans(−pₖ)` about its own
//! anchor pₖ, each slide `Trans(aₖ (qₖ − refₖ))`. urdyn gives every joint a body:
//! the joint's placement is the frame before it composed with `Trans(pₖ)`, so the
//! joint's body frame sits at the anchor; the next placement starts with
//! `Trans(−pₖ)`. The MJCF body's own frame is then a frame on the chain's last
//! body, which carries its mass (the chain's other bodies are massless). A body
//! without joints is welded to its parent's body, a free joint's body has the
//! identity placement (q is the world pose, as MuJoCo's qpos).

use super::compile::{MjGeomType, MjJointType, World};
use super::MjcfError;
use crate::model::{
    Axis, CollisionFilter, CollisionGeom, DofInfo, Frame, ImportReport, Joint, JointKind,
    JointLimits, LinkMass, Model, Shape, Topology, Tree, OBSTACLE,
};
use crate::spatial::{CompositeInertia, Inertia, Se3};
use nalgebra::{UnitQuaternion, Vector3};

fn se3(p: &Vector3<f64>, q: &UnitQuaternion<f64>) -> Se3<f64> {
    Se3::new(q.to_rotation_matrix().into_inner(), *p)
}

pub(super) fn lower(world: &World) -> Result<Model, MjcfError> {
    let nb = world.bodies.len();
    let mut parent = vec![0usize];
    let mut joints = vec![Joint {
        kind: JointKind::Free,
        iq: 0,
        iv: 0,
        mult: 1.0,
        offset: 0.0,
    }];
    let mut placements = vec![Se3::identity()];
    let mut inertias = vec![Inertia::zero()];
    let mut body_joint_names = vec!["universe".to_string()];
    let mut body_link_names = vec!["world".to_string()];
    let mut dofs = Vec::new();
    let mut frames = Vec::new();
    let mut trees: Vec<Tree> = Vec::new();
    let mut report = ImportReport::default();
    // urdyn body of each MJCF body and the MJCF body frame in it
    let mut ub = vec![0usize; nb];
    let mut ub_m = vec![Se3::identity(); nb];
    let mut depth = vec![0usize; nb];
    let (mut nq, mut nv) = (0usize, 0usize);
    let mut qpos0 = Vec::new();
    let mut springdampers = Vec::new();
    for b in 1..nb {
        let body = &world.bodies[b];
        let p = body.parent;
        depth[b] = if p == 0 { 0 } else { depth[p] + 1 };
        if p == 0 {
            // a new tree: one per child of <worldbody>
            if let Some(t) = trees.last_mut() {
                close_tree(t, parent.len(), frames.len(), dofs.len(), nq, nv);
            }
            trees.push(Tree {
                name: String::new(),
                bodies: parent.len()..parent.len(),
                frames: frames.len()..frames.len(),
                dofs: dofs.len()..dofs.len(),
                q: nq..nq,
                v: nv..nv,
                free: None,
            });
        }
        let mut at = ub[p];
        let mut cur = ub_m[p].compose(&se3(&body.pos, &body.quat));
        let mut names = Vec::new();
        for j in body.joints.clone() {
            let jt = &world.joints[j];
            names.push(jt.name.clone());
            let (kind, placement, after) = match jt.kind {
                MjJointType::Free => {
                    // q is the body's world pose (MuJoCo's qpos): identity placement
                    let (p, r) = (&body.pos, &body.quat);
                    qpos0.extend([p.x, p.y, p.z, r.i, r.j, r.k, r.w]);
                    (JointKind::Free, Se3::identity(), Se3::identity())
                }
                MjJointType::Ball => {
                    // a rotation about the anchor, as a hinge's
                    qpos0.extend([0.0, 0.0, 0.0, 1.0]);
                    if jt.range.is_some() {
                        report.warnings.push(format!(
                            "joint \"{}\": a ball joint's range (a cone limit) is not modelled",
                            jt.name
                        ));
                    }
                    (
                        JointKind::Spherical,
                        cur.compose(&Se3::from_translation(jt.pos)),
                        Se3::from_translation(-jt.pos),
                    )
                }
                MjJointType::Hinge => (
                    JointKind::Revolute(Axis::from_unit(jt.axis)),
                    cur.compose(&Se3::from_translation(jt.pos)),
                    Se3::from_translation(-jt.pos),
                ),
                MjJointType::Slide => (
                    JointKind::Prismatic(Axis::from_unit(jt.axis)),
                    cur,
                    Se3::identity(),
                ),
            };
            let (nqj, nvj) = (kind.nq(), kind.nv());
            parent.push(at);
            joints.push(Joint {
                kind,
                iq: nq,
                iv: nv,
                mult: 1.0,
                offset: if nvj == 1 { -jt.reference } else { 0.0 },
            });
            placements.push(placement);
            inertias.push(Inertia::zero());
            body_joint_names.push(jt.name.clone());
            let last = j + 1 == body.joints.end;
            body_link_names.push(if last {
                body.name.clone()
            } else {
                format!("{}/{}", body.name, jt.name)
            });
            if nvj == 1 {
                qpos0.push(jt.reference);
            }
            let one_dof = nvj == 1;
            if let Some((timeconst, dampratio)) = jt.springdamper {
                springdampers.push(super::springdamper::SpringDamper {
                    dof: dofs.len(),
                    timeconst,
                    dampratio,
                });
            }
            dofs.push(DofInfo {
                name: jt.name.clone(),
                kind,
                iq: nq,
                iv: nv,
                limits: JointLimits {
                    lower: jt.range.filter(|_| one_dof).map(|r| r.0),
                    upper: jt.range.filter(|_| one_dof).map(|r| r.1),
                    effort: None,
                    velocity: None,
                },
                damping: jt.damping,
                friction: jt.frictionloss,
                continuous: jt.kind == MjJointType::Hinge && jt.range.is_none(),
                armature: jt.armature,
                stiffness: jt.stiffness,
                springref: jt.springref,
            });
            nq += nqj;
            nv += nvj;
            at = parent.len() - 1;
            cur = after;
        }
        ub[b] = at;
        ub_m[b] = cur;
        let own = Inertia::new(body.mass, body.com, body.inertia);
        if at != 0 {
            inertias[at] = inertias[at].add(&cur.act_inertia(&own));
        } else if body.mass > 0.0 {
            report.ignored.push(format!(
                "body \"{}\": welded to the world, its mass ({} kg) moves nothing",
                body.name, body.mass
            ));
        }
        frames.push(Frame {
            name: body.name.clone(),
            body: at,
            placement: cur,
        });
        report.bodies.push(LinkMass {
            name: body.name.clone(),
            mass: body.mass,
            com: body.com,
            inertia: body.inertia,
        });
        for (name, sp, sq) in &body.sites {
            if frames.iter().any(|f: &Frame| &f.name == name) {
                report.warnings.push(format!(
                    "site \"{name}\": a body has the same name; the site is not a frame"
                ));
                continue;
            }
            frames.push(Frame {
                name: name.clone(),
                body: at,
                placement: cur.compose(&se3(sp, sq)),
            });
        }
        let joints_text = if names.is_empty() {
            "welded".to_string()
        } else {
            names.join(", ")
        };
        report.tree.push(format!(
            "{}{} [{}]  mass {} kg",
            "  ".repeat(depth[b].min(64)),
            body.name,
            joints_text,
            body.mass
        ));
    }
    if let Some(t) = trees.last_mut() {
        close_tree(t, parent.len(), frames.len(), dofs.len(), nq, nv);
    }
    let nbodies = parent.len();

    // collision shapes (MuJoCo's geoms that may collide); planes are the
    // ground (`collide::ground`), ellipsoids, meshes and height fields are not
    // collision shapes yet
    let mut collisions = Vec::new();
    let mut colliding = vec![false; world.geoms.len()];
    let mut later = 0usize;
    // `<flag contact="disable">`: no geom collides
    let geoms = if world.contact_disabled {
        &world.geoms[..0]
    } else {
        &world.geoms[..]
    };
    for (k, g) in geoms.iter().enumerate() {
        if g.contype == 0 && g.conaffinity == 0 {
            continue;
        }
        let s = g.size;
        let shape = match g.kind {
            MjGeomType::Sphere => Shape::Sphere { radius: s[0] },
            MjGeomType::Capsule => Shape::Capsule {
                radius: s[0],
                length: 2.0 * s[1],
            },
            MjGeomType::Cylinder => Shape::Cylinder {
                radius: s[0],
                length: 2.0 * s[1],
            },
            MjGeomType::Box => Shape::Box {
                size: [2.0 * s[0], 2.0 * s[1], 2.0 * s[2]],
            },
            MjGeomType::Plane => continue,
            _ => {
                later += 1;
                continue;
            }
        };
        colliding[k] = true;
        let at = ub[g.body];
        collisions.push(CollisionGeom {
            link: world.bodies[g.body].name.clone(),
            body: at,
            placement: ub_m[g.body].compose(&se3(&g.pos, &g.quat)),
            shape,
            trimesh: false,
            friction: g.friction[0],
            // welded to the world: a static obstacle (touches every moving body)
            model: if at == 0 { OBSTACLE } else { 0 },
        });
    }
    if later > 0 {
        report.warnings.push(format!(
            "{later} ellipsoid, height-field or mesh geom(s): not collision shapes (not modelled in contact)"
        ));
    }
    let (ground, ground_warnings) = super::collide::ground(world);
    report.warnings.extend(ground_warnings);
    let (excluded, filter_warnings) =
        super::collide::excluded_pairs(world, &ub, &colliding, ground.as_ref());
    report.warnings.extend(filter_warnings);
    report.warnings.extend(world.warnings.iter().cloned());

    // λ: the previous velocity coordinate on the path to the root
    let mut last_v = vec![usize::MAX; nbodies];
    let mut dof_parent = vec![usize::MAX; nv];
    for b in 1..nbodies {
        let mut prev = last_v[parent[b]];
        let j = &joints[b];
        for k in 0..j.nv() {
            dof_parent[j.iv + k] = prev;
            prev = j.iv + k;
        }
        last_v[b] = prev;
    }
    let massless_joints = massless(&parent, &joints, &inertias, &dofs, &body_joint_names);
    for name in &massless_joints {
        report.warnings.push(format!(
            "joint \"{name}\" moves only massless bodies: H is singular, there is no forward dynamics"
        ));
    }
    let topology = Topology::new(&dof_parent, nbodies, false);
    let mut model = Model {
        name: world.name.clone(),
        nq,
        nv,
        nbodies,
        parent,
        joints,
        placement_zero_trans: crate::model::zero_translations(&placements),
        placement_identity: crate::model::identity_rotations(&placements),
        placements,
        inertias_origin: inertias
            .iter()
            .map(CompositeInertia::from_inertia)
            .collect(),
        inertias,
        body_joint_names,
        body_link_names,
        gravity: world.gravity,
        floating_base: false,
        free_joints: Vec::new(),
        trees,
        dofs,
        frames,
        collisions,
        collision_filter: CollisionFilter {
            excluded,
            self_collision: vec![true],
        },
        dof_parent,
        has_mimic: false,
        massless_joints,
        topology,
        source: None,
        report,
        qpos0: Some(qpos0),
        actuators: Vec::new(),
        keyframes: Vec::new(),
        equalities: Default::default(),
        equality_active: Vec::new(),
    };
    // before the tendons fold their springs onto the dofs (actuators::lower)
    super::springdamper::apply(&mut model, &springdampers);
    super::actuators::lower(world, &mut model)?;
    super::equality::lower(world, &ub, &ub_m, &mut model)?;
    Ok(model)
}

fn close_tree(t: &mut Tree, nb: usize, nf: usize, nd: usize, nq: usize, nv: usize) {
    t.bodies.end = nb;
    t.frames.end = nf;
    t.dofs.end = nd;
    t.q.end = nq;
    t.v.end = nv;
}

/// Joints whose subtree has neither mass nor inertia nor armature (H singular).
fn massless(
    parent: &[usize],
    joints: &[Joint<f64>],
    inertias: &[Inertia<f64>],
    dofs: &[DofInfo],
    names: &[String],
) -> Vec<String> {
    let n = parent.len();
    let mut sub = vec![0.0f64; n];
    for b in (1..n).rev() {
        sub[b] += inertias[b].mass + inertias[b].inertia_c.abs().max();
        if parent[b] != 0 {
            sub[parent[b]] += sub[b];
        }
    }
    let armature = |b: usize| {
        let j = &joints[b];
        j.nv() == 1 && dofs.iter().any(|d| d.name == names[b] && d.armature > 0.0)
    };
    (1..n)
        .filter(|&b| sub[b] == 0.0 && !armature(b))
        .map(|b| names[b].clone())
        .collect()
}
