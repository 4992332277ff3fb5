//! Several URDF models in one [`Model`]: a forest, one tree per model under the
//! world (body 0). Each model's bodies, links, degrees of freedom and
//! coordinates stay contiguous and in its own (Pinocchio's) order; models come
//! in the given order. A fixed model's links welded to the world move to its
//! pose; a floating model's free joint starts at the world origin (its pose is
//! its starting q). Every name becomes `MODEL/NAME`.
//!
//! A part may itself be a forest (an MJCF file's world: one tree per child of
//! `<worldbody>`): each of its trees stays a tree here, named after the part;
//! its children of the world on a free joint keep their identity placement,
//! their q (from the part's `qpos0`) is placed by the part's pose (a free
//! joint's q is a world pose); its shapes on the world stay obstacles; its
//! actuators come along, renamed `MODEL/NAME` and shifted to the forest's
//! coordinates.

use crate::model::{
    CollisionFilter, CollisionGeom, FreeJoint, JointKind, Model, Topology, Tree, OBSTACLE,
};
use crate::spatial::Se3;
use nalgebra::Vector3;
use nalgebra::{Rotation3, UnitQuaternion};

/// One model of the forest: its name, the model as loaded (fixed or floating),
/// and, for a fixed one, where its root frame is welded.
pub struct Part {
    /// The model's name (the prefix of its names).
    pub name: String,
    /// The model, as `load_file` gave it.
    pub model: Model,
    /// `world_M_root` of a fixed model (ignored for a floating one).
    pub pose: Se3<f64>,
    /// Its links' friction coefficient.
    pub friction: f64,
    /// Contact between two of its links.
    pub self_collision: bool,
}

fn prefixed(prefix: &str, name: &str) -> String {
    format!("{prefix}/{name}")
}

/// The forest of `parts`, in order, under gravity `g`: each part's collision
/// shapes get its index as their model and its friction; its self-collision
/// flag goes into the collision filter. Mesh filenames of the collision
/// geometry are kept as each model gave them (resolve them first: the forest
/// has no one source file).
pub fn forest(name: &str, parts: Vec<Part>, gravity: Vector3<f64>) -> Model {
    let mut m = Model {
        name: name.to_string(),
        nq: 0,
        nv: 0,
        nbodies: 1,
        parent: vec![0],
        joints: Vec::new(),
        placements: vec![Se3::identity()],
        placement_identity: vec![true],
        placement_zero_trans: vec![true],
        inertias: Vec::new(),
        inertias_origin: Vec::new(),
        body_joint_names: vec!["universe".into()],
        body_link_names: vec!["world".into()],
        gravity,
        floating_base: false,
        free_joints: Vec::new(),
        trees: Vec::new(),
        dofs: Vec::new(),
        frames: Vec::new(),
        collisions: Vec::new(),
        collision_filter: CollisionFilter {
            excluded: Vec::new(),
            self_collision: Vec::new(),
        },
        dof_parent: Vec::new(),
        has_mimic: false,
        massless_joints: Vec::new(),
        topology: Topology::default(),
        source: None,
        report: Default::default(),
        qpos0: None,
        actuators: Vec::new(),
        keyframes: Vec::new(),
        equalities: Default::default(),
        equality_active: Vec::new(),
    };
    let any_qpos0 = parts.iter().any(|p| p.model.qpos0.is_some());
    let mut qpos0: Vec<f64> = Vec::new();
    for (i, part) in parts.into_iter().enumerate() {
        let p = &part.model;
        if i == 0 {
            m.joints.push(p.joints[0].clone());
            m.inertias.push(p.inertias[0]);
            m.inertias_origin.push(p.inertias_origin[0]);
        }
        let pre = part.name.as_str();
        let (b0, q0, v0, d0, f0) = (m.nbodies, m.nq, m.nv, m.dofs.len(), m.frames.len());
        // body b > 0 of the part is b0 + b − 1 here; its body 0 is the world
        let body = |b: usize| if b == 0 { 0 } else { b0 + b - 1 };
        let floating = p.floating_base;
        let weld = if floating { Se3::identity() } else { part.pose };
        for b in 1..p.nbodies {
            m.parent.push(body(p.parent[b]));
            let mut j = p.joints[b].clone();
            j.iq += q0;
            j.iv += v0;
            m.joints.push(j);
            // a child of the world hangs from the model's pose (but a free
            // joint's q is its world pose)
            let free_root = p.parent[b] == 0 && matches!(p.joints[b].kind, JointKind::Free);
            let x = if p.parent[b] == 0 && !free_root {
                weld.compose(&p.placements[b])
            } else {
                p.placements[b]
            };
            m.placement_identity
                .push(crate::model::identity_rotation(&x));
            m.placement_zero_trans
                .push(crate::model::zero_translation(&x));
            m.placements.push(x);
            m.inertias.push(p.inertias[b]);
            m.inertias_origin.push(p.inertias_origin[b]);
            m.body_joint_names
                .push(prefixed(pre, &p.body_joint_names[b]));
            m.body_link_names.push(prefixed(pre, &p.body_link_names[b]));
        }
        for f in &p.frames {
            let mut f = f.clone();
            f.name = prefixed(pre, &f.name);
            if f.body == 0 {
                f.placement = weld.compose(&f.placement);
            }
            f.body = body(f.body);
            m.frames.push(f);
        }
        for c in &p.collisions {
            let mut c: CollisionGeom = c.clone();
            c.link = prefixed(pre, &c.link);
            if c.body == 0 {
                c.placement = weld.compose(&c.placement);
            }
            c.body = body(c.body);
            // a part's own obstacles (an MJCF world's static geoms) stay obstacles
            if c.model != OBSTACLE {
                c.model = i;
            }
            c.friction = part.friction;
            m.collisions.push(c);
        }
        for d in &p.dofs {
            let mut d = d.clone();
            d.name = prefixed(pre, &d.name);
            d.iq += q0;
            d.iv += v0;
            m.dofs.push(d);
        }
        m.dof_parent.extend(
            p.dof_parent
                .iter()
                .map(|&k| if k == usize::MAX { k } else { k + v0 }),
        );
        m.has_mimic |= p.has_mimic;
        m.collision_filter.self_collision.push(part.self_collision);
        m.collision_filter.excluded.extend(
            p.collision_filter
                .excluded
                .iter()
                .map(|(a, b)| (prefixed(pre, a), prefixed(pre, b))),
        );
        m.massless_joints
            .extend(p.massless_joints.iter().map(|j| prefixed(pre, j)));
        let report = &p.report;
        m.report.merged.extend(
            report
                .merged
                .iter()
                .map(|(a, b)| (prefixed(pre, a), prefixed(pre, b))),
        );
        m.report
            .tree
            .extend(report.tree.iter().map(|l| format!("{pre}: {l}")));
        m.report
            .ignored
            .extend(report.ignored.iter().map(|l| format!("{pre}: {l}")));
        m.report
            .warnings
            .extend(report.warnings.iter().map(|l| format!("{pre}: {l}")));
        let free = floating.then(|| {
            m.free_joints.push(FreeJoint {
                body: b0,
                iq: q0,
                iv: v0,
                name: prefixed(pre, "base"),
            });
            m.free_joints.len() - 1
        });
        for a in &p.actuators {
            let mut a = a.clone();
            a.name = prefixed(pre, &a.name);
            a.dof = a.dof.map(|(iv, iq)| (iv + v0, iq + q0));
            for (iv, _) in &mut a.moment {
                *iv += v0;
            }
            m.actuators.push(a);
        }
        if any_qpos0 {
            let mut q = p.neutral().as_slice().to_vec();
            // the part's free roots: world poses, placed by the part's pose
            for b in 1..p.nbodies {
                let j = &p.joints[b];
                if floating || p.parent[b] != 0 || !matches!(j.kind, JointKind::Free) {
                    continue;
                }
                let x = &q[j.iq..j.iq + 7];
                let r = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                    x[6], x[3], x[4], x[5],
                ));
                let wr = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                    weld.rot,
                ));
                let t = weld.rot * nalgebra::Vector3::new(x[0], x[1], x[2]) + weld.trans;
                let o = wr * r;
                q[j.iq..j.iq + 7].copy_from_slice(&[t.x, t.y, t.z, o.i, o.j, o.k, o.w]);
            }
            qpos0.extend(q);
        }
        m.nbodies += p.nbodies - 1;
        m.nq += p.nq;
        m.nv += p.nv;
        if p.trees.len() > 1 && !floating {
            // a forest itself (an MJCF world): each of its trees
            for t in &p.trees {
                m.trees.push(Tree {
                    name: part.name.clone(),
                    bodies: b0 + t.bodies.start - 1..b0 + t.bodies.end - 1,
                    frames: f0 + t.frames.start..f0 + t.frames.end,
                    dofs: d0 + t.dofs.start..d0 + t.dofs.end,
                    q: q0 + t.q.start..q0 + t.q.end,
                    v: v0 + t.v.start..v0 + t.v.end,
                    free: None,
                });
            }
        } else {
            m.trees.push(Tree {
                name: part.name.clone(),
                bodies: b0..m.nbodies,
                frames: f0..m.frames.len(),
                dofs: d0..m.dofs.len(),
                q: q0..m.nq,
                v: v0..m.nv,
                free,
            });
        }
    }
    if any_qpos0 {
        m.qpos0 = Some(qpos0);
    }
    m.floating_base = m.free_joints.first().is_some_and(|f| f.body == 1);
    m.topology = Topology::new(&m.dof_parent, m.nbodies, m.has_mimic);
    m.topology.mimic_tree = m.has_mimic
        && Topology::mimic_tree_sparse(
            &m.parent,
            |b| (m.joints[b].iv, m.joints[b].nv()),
            &m.dof_parent,
        );
    m
}
