//! Lowering: the validated URDF tree becomes flat, parent-before-child bodies.
//! Links welded by fixed joints merge into their movable ancestor (masses, centres
//! of mass and inertias combined exactly); each link stays a frame on its body.

use super::parse::Parsed;
use super::types::JointType;
use super::validate::{is_movable, Checked};
use super::{LoadOptions, UrdfError};
use crate::model::{
    Axis, CollisionGeom, DofInfo, Frame, ImportReport, Joint, JointKind, JointLimits, Model, Shape,
};
use crate::spatial::{rpy_to_matrix, Inertia, Se3};
use nalgebra::{Matrix3, Vector3};

/// Tree lines deeper than this are indented no further (their depth is printed).
const MAX_INDENT: usize = 32;

fn pose(p: &super::types::Pose) -> Se3<f64> {
    let [r, pi, y] = p.rpy.0;
    Se3::new(rpy_to_matrix(r, pi, y), Vector3::from(p.xyz.0))
}

/// A link's inertia in its own frame: the `<inertial>` origin's rpy rotates the
/// given inertia tensor, its xyz places the centre of mass.
fn link_inertia(l: &super::types::Link) -> Inertia<f64> {
    let i = &l.inertial;
    let t = &i.inertia;
    let ic = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    pose(&i.origin).act_inertia(&Inertia::new(i.mass.value, Vector3::zeros(), ic))
}

fn shape(g: &super::types::Geometry) -> Shape {
    use super::types::Geometry as G;
    match g {
        G::Box { size } => Shape::Box { size: size.0 },
        G::Cylinder { radius, length } => Shape::Cylinder {
            radius: *radius,
            length: *length,
        },
        G::Capsule { radius, length } => Shape::Capsule {
            radius: *radius,
            length: *length,
        },
        G::Sphere { radius } => Shape::Sphere { radius: *radius },
        G::Mesh { filename, scale } => Shape::Mesh {
            filename: filename.clone(),
            scale: scale.as_ref().map(|s| s.0).unwrap_or([1.0, 1.0, 1.0]),
        },
    }
}

fn limits(j: &super::types::Joint) -> JointLimits {
    let l = &j.limit;
    let pos = |x: f64| x.is_finite().then_some(x);
    let positive = |x: f64| (x.is_finite() && x > 0.0).then_some(x);
    let unknown_range = l.lower == 0.0 && l.upper == 0.0;
    if j.joint_type == JointType::Continuous || unknown_range {
        JointLimits {
            lower: None,
            upper: None,
            effort: positive(l.effort),
            velocity: positive(l.velocity),
        }
    } else {
        JointLimits {
            lower: pos(l.lower),
            upper: pos(l.upper),
            effort: positive(l.effort),
            velocity: positive(l.velocity),
        }
    }
}

pub(crate) fn lower(
    parsed: &Parsed,
    checked: &Checked,
    file: &str,
    options: LoadOptions,
) -> Result<Model, UrdfError> {
    let robot = &parsed.robot;
    let link_index: std::collections::HashMap<&str, usize> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.as_str(), i))
        .collect();

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
    let mut body_urdf_joint: Vec<Option<usize>> = vec![None];
    let mut frames: Vec<Option<Frame<f64>>> = vec![None; robot.links.len()];
    let mut collisions = Vec::new();
    let mut report = ImportReport {
        warnings: checked.warnings.clone(),
        ignored: checked.ignored.clone(),
        ..Default::default()
    };

    let root_body = if options.floating_base {
        parent.push(0);
        joints.push(Joint {
            kind: JointKind::Free,
            iq: 0,
            iv: 0,
            mult: 1.0,
            offset: 0.0,
        });
        placements.push(Se3::identity());
        inertias.push(Inertia::zero());
        body_joint_names.push("root_joint".into());
        body_link_names.push(robot.links[checked.root].name.clone());
        body_urdf_joint.push(None);
        1
    } else {
        0
    };

    // Depth-first, children in byte-wise order of their joints' names (Pinocchio's
    // order, see `Checked::children`), iteratively (deep chains must not
    // overflow). A movable joint's body is numbered when its child link is visited,
    // so bodies come in depth-first pre-order: parent < child, subtrees contiguous.
    enum Via {
        Welded(usize, Se3<f64>),
        Joint(usize, Se3<f64>, usize),
    }
    let root_edge = if options.floating_base {
        "free joint to world"
    } else {
        "welded to world"
    };
    let mut stack: Vec<(usize, Via, usize, String)> = vec![(
        checked.root,
        Via::Welded(root_body, Se3::identity()),
        0,
        root_edge.to_string(),
    )];
    while let Some((li, via, depth, edge)) = stack.pop() {
        let link = &robot.links[li];
        let (body, b_m_l) = match via {
            Via::Welded(body, b_m_l) => (body, b_m_l),
            Via::Joint(pb, origin, ji) => {
                let j = &robot.joints[ji];
                let a = Vector3::from(j.axis.xyz.0);
                let axis = Axis::from_unit(a / a.norm());
                let kind = match j.joint_type {
                    JointType::Prismatic => JointKind::Prismatic(axis),
                    JointType::Spherical => JointKind::Spherical,
                    JointType::Planar => JointKind::Planar,
                    JointType::Floating => JointKind::Free,
                    _ => JointKind::Revolute(axis),
                };
                // a planar joint about another axis a: R_a Planar(q) R_aᵀ, R_a into
                // the placement and R_aᵀ onto the child's frames (docs/theory.md
                // §"Spherical, planar and floating joints")
                let (origin, b_m_l) =
                    if j.joint_type == JointType::Planar && a != a.norm() * Vector3::z() {
                        let ra = plane_rotation(&(a / a.norm()));
                        (
                            Se3::new(origin.rot * ra, origin.trans),
                            Se3::new(ra.transpose(), Vector3::zeros()),
                        )
                    } else {
                        (origin, Se3::identity())
                    };
                parent.push(pb);
                joints.push(Joint {
                    kind,
                    iq: 0,
                    iv: 0,
                    mult: 1.0,
                    offset: 0.0,
                });
                placements.push(origin);
                inertias.push(Inertia::zero());
                body_joint_names.push(j.name.clone());
                body_link_names.push(j.child.link.clone());
                body_urdf_joint.push(Some(ji));
                (parent.len() - 1, b_m_l)
            }
        };
        let mass = link.inertial.mass.value;
        let geoms: Vec<String> = link
            .collision
            .iter()
            .map(|c| shape(&c.geometry).kind().to_string())
            .collect();
        // Deep chains (thousands of links) must not make the report quadratic.
        let indent = if depth <= MAX_INDENT {
            "  ".repeat(depth)
        } else {
            format!("{}(depth {depth}) ", "  ".repeat(MAX_INDENT))
        };
        report.tree.push(format!(
            "{}{} [{}]  mass {} kg{}",
            indent,
            link.name,
            edge,
            mass,
            if geoms.is_empty() {
                String::new()
            } else {
                format!("  collision: {}", geoms.join(", "))
            }
        ));
        frames[li] = Some(Frame {
            name: link.name.clone(),
            body,
            placement: b_m_l,
        });
        let own = link_inertia(link);
        report.bodies.push(crate::model::LinkMass {
            name: link.name.clone(),
            mass: own.mass,
            com: own.com,
            inertia: own.inertia_c,
        });
        if body != 0 {
            let inertia = b_m_l.act_inertia(&own);
            inertias[body] = inertias[body].add(&inertia);
        }
        for c in &link.collision {
            collisions.push(CollisionGeom {
                link: link.name.clone(),
                body,
                placement: b_m_l.compose(&pose(&c.origin)),
                shape: shape(&c.geometry),
                trimesh: false,
                friction: 0.0,
                model: 0,
            });
        }
        for &ji in checked.children[li].iter().rev() {
            let j = &robot.joints[ji];
            let child = link_index[j.child.link.as_str()];
            let origin = b_m_l.compose(&pose(&j.origin));
            if !is_movable(&j.joint_type) {
                let into = if body == 0 {
                    "world".to_string()
                } else {
                    body_link_names[body].clone()
                };
                report.merged.push((j.child.link.clone(), into));
                stack.push((
                    child,
                    Via::Welded(body, origin),
                    depth + 1,
                    format!("fixed \"{}\"", j.name),
                ));
                continue;
            }
            let a = Vector3::from(j.axis.xyz.0) / Vector3::from(j.axis.xyz.0).norm();
            let kind_name = match j.joint_type {
                JointType::Prismatic => "prismatic",
                JointType::Continuous => "continuous",
                JointType::Spherical => "spherical",
                JointType::Planar => "planar",
                JointType::Floating => "floating",
                _ => "revolute",
            };
            let mimic = checked.mimic[ji].map_or(String::new(), |(l, m, o)| {
                format!(", mimics \"{}\" ×{m} {o:+}", robot.joints[l].name)
            });
            stack.push((
                child,
                Via::Joint(body, origin, ji),
                depth + 1,
                format!(
                    "{kind_name} \"{}\" axis ({:.4}, {:.4}, {:.4}){mimic}",
                    j.name, a.x, a.y, a.z
                ),
            ));
        }
    }
    // Bodies were numbered in pre-order from a stack: parent < child holds.
    let nbodies = parent.len();

    // Degrees of freedom: the base, then every non-mimic movable joint in body order.
    let (qoff, voff) = if options.floating_base {
        (7, 6)
    } else {
        (0, 0)
    };
    let mut dofs = Vec::new();
    let mut dof_of_joint: Vec<Option<usize>> = vec![None; robot.joints.len()];
    let (mut nq, mut nv) = (qoff, voff);
    for b in 1..nbodies {
        if let Some(ji) = body_urdf_joint[b] {
            if checked.mimic[ji].is_none() {
                let j = &robot.joints[ji];
                let k = dofs.len();
                dof_of_joint[ji] = Some(k);
                joints[b].iq = nq;
                joints[b].iv = nv;
                let kind = joints[b].kind;
                dofs.push(DofInfo {
                    name: j.name.clone(),
                    kind,
                    iq: nq,
                    iv: nv,
                    limits: limits(j),
                    damping: j.dynamics.as_ref().map_or(0.0, |d| d.damping),
                    friction: j.dynamics.as_ref().map_or(0.0, |d| d.friction),
                    continuous: j.joint_type == JointType::Continuous,
                    armature: 0.0,
                    stiffness: 0.0,
                    springref: 0.0,
                });
                nq += kind.nq();
                nv += kind.nv();
            }
        }
    }
    let mut has_mimic = false;
    for b in 1..nbodies {
        let Some(ji) = body_urdf_joint[b] else {
            continue;
        };
        if let Some((leader, mult, off)) = checked.mimic[ji] {
            let k = dof_of_joint[leader].ok_or_else(|| {
                UrdfError::new(
                    file,
                    Some(format!("joint \"{}\" <mimic>", robot.joints[ji].name)),
                    "leader is not a degree of freedom",
                )
            })?;
            joints[b].iq = dofs[k].iq;
            joints[b].iv = dofs[k].iv;
            joints[b].mult = mult;
            joints[b].offset = off;
            has_mimic = true;
        }
    }

    // λ: the previous velocity coordinate on the path to the root.
    let mut last_v = vec![usize::MAX; nbodies];
    let mut dof_parent = vec![usize::MAX; nv];
    for b in 1..nbodies {
        let inherited = last_v[parent[b]];
        let j = &joints[b];
        let own = match j.kind {
            _ if b == root_body => true,
            _ => body_urdf_joint[b].is_some_and(|ji| checked.mimic[ji].is_none()),
        };
        if own {
            let mut prev = inherited;
            for k in 0..j.nv() {
                dof_parent[j.iv + k] = prev;
                prev = j.iv + k;
            }
            last_v[b] = prev;
        } else {
            last_v[b] = inherited;
        }
    }

    // Massless subtrees: a joint that moves nothing with mass or inertia.
    let mut sub_mass = vec![0.0f64; nbodies];
    let mut sub_inertia = vec![0.0f64; nbodies];
    for b in (1..nbodies).rev() {
        sub_mass[b] += inertias[b].mass;
        sub_inertia[b] += inertias[b].inertia_c.abs().max();
        let p = parent[b];
        if p != 0 {
            sub_mass[p] += sub_mass[b];
            sub_inertia[p] += sub_inertia[b];
        }
    }
    // Per degree of freedom (a leader and its mimic followers together).
    let mut dof_mass = vec![0.0f64; nv];
    for b in 1..nbodies {
        let j = &joints[b];
        for k in 0..j.nv() {
            dof_mass[j.iv + k] += sub_mass[b] + sub_inertia[b];
        }
    }
    let mut massless_joints = Vec::new();
    for b in 1..nbodies {
        let j = &joints[b];
        let mimic = body_urdf_joint[b].is_some_and(|ji| checked.mimic[ji].is_some());
        if !mimic && dof_mass[j.iv] == 0.0 {
            let name = &body_joint_names[b];
            report.warnings.push(format!(
                "joint \"{name}\" moves only massless links: H is singular, there is no forward dynamics"
            ));
            massless_joints.push(name.clone());
        }
    }

    let frames: Vec<Frame<f64>> = frames.into_iter().flatten().collect();
    fold_axis_placements(&mut joints, &mut placements);
    let mut topology = crate::model::Topology::new(&dof_parent, nbodies, has_mimic);
    topology.mimic_tree = has_mimic
        && crate::model::Topology::mimic_tree_sparse(
            &parent,
            |b| (joints[b].iv, joints[b].nv()),
            &dof_parent,
        );
    Ok(Model {
        name: robot.name.clone(),
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
            .map(crate::spatial::CompositeInertia::from_inertia)
            .collect(),
        inertias,
        body_joint_names,
        body_link_names,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        floating_base: options.floating_base,
        free_joints: if options.floating_base {
            vec![crate::model::FreeJoint {
                body: 1,
                iq: 0,
                iv: 0,
                name: "base".into(),
            }]
        } else {
            Vec::new()
        },
        trees: vec![crate::model::Tree::whole(
            nbodies,
            frames.len(),
            dofs.len(),
            nq,
            nv,
            options.floating_base,
        )],
        dofs,
        frames,
        collisions,
        // one model; self-collision off: a URDF alone keeps today's contact
        // with the ground only (its trajectories, speed and allocation-free
        // step); a scene turns it on per model (scene.md's default)
        collision_filter: crate::model::CollisionFilter {
            excluded: Vec::new(),
            self_collision: vec![false],
        },
        dof_parent,
        has_mimic,
        massless_joints,
        topology,
        source: None,
        report,
        qpos0: None,
        actuators: Vec::new(),
        keyframes: Vec::new(),
        equalities: Default::default(),
        equality_active: Vec::new(),
    })
}

/// The smallest rotation taking z onto the unit vector `a` (a half turn about x
/// for a = −z): a planar joint's plane rotation R_a (mechanisms.md).
fn plane_rotation(a: &Vector3<f64>) -> Matrix3<f64> {
    let z = Vector3::z();
    if *a == z {
        return Matrix3::identity();
    }
    match nalgebra::Rotation3::rotation_between(&z, a) {
        Some(r) if a.dot(&z) > -1.0 + 1e-12 => *r.matrix(),
        _ => Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0),
    }
}

/// A revolute joint about x, y or z whose placement rotation is itself a rotation
/// about that axis by θ₀ (URDF arms often write `rpy="0 1.5708 0"` on a y-axis
/// joint): `R₀ R(q) = R(q + θ₀)`, so θ₀ moves into the joint's offset and the
/// placement keeps its translation only. The body frames are unchanged; the
/// algorithms then take the joint's axis-rotation path (a rotation mixing two
/// coordinates instead of a general 3x3 product). Only exact structure qualifies:
/// the axis row and column of R₀ are exactly those of the identity.
fn fold_axis_placements(joints: &mut [Joint<f64>], placements: &mut [Se3<f64>]) {
    for (j, x) in joints.iter_mut().zip(placements.iter_mut()) {
        let JointKind::Revolute(ax) = j.kind else {
            continue;
        };
        let (a, b, c) = match ax {
            Axis::X => (0, 1, 2),
            Axis::Y => (1, 2, 0),
            Axis::Z => (2, 0, 1),
            Axis::Unit(_) => continue,
        };
        let r = &x.rot;
        if *r == nalgebra::Matrix3::identity()
            || r[(a, a)] != 1.0
            || r[(a, b)] != 0.0
            || r[(a, c)] != 0.0
            || r[(b, a)] != 0.0
            || r[(c, a)] != 0.0
        {
            continue;
        }
        // The (b, c) block is [cos θ₀, −sin θ₀; sin θ₀, cos θ₀] (b, c cyclic after a).
        let theta = r[(c, b)].atan2(r[(b, b)]);
        let (s, co) = theta.sin_cos();
        let tol = 4.0 * f64::EPSILON;
        if (r[(b, b)] - co).abs() > tol
            || (r[(c, c)] - co).abs() > tol
            || (r[(c, b)] - s).abs() > tol
            || (r[(b, c)] + s).abs() > tol
        {
            continue;
        }
        j.offset += theta;
        x.rot = nalgebra::Matrix3::identity();
    }
}
