//! Validation of the parsed URDF: names, the tree, every number, inertias and
//! mimic relations. Errors name the element; suspicious-but-usable input becomes
//! a warning in the import report.

use super::parse::Parsed;
use super::types::JointType;
use super::UrdfError;
use std::collections::HashMap;

/// What validation established about the parsed robot.
pub(crate) struct Checked {
    /// The root link (index into `robot.links`): the one link no joint has as child.
    pub root: usize,
    /// Child joints of each link, in byte-wise order of the joints' names: urdfdom
    /// keeps joints in a `std::map`, so `pin.buildModelFromUrdf` visits a link's
    /// children in that order, and so does the engine (docs/theory.md §"Degrees of freedom order").
    pub children: Vec<Vec<usize>>,
    /// For each joint: Some((ultimate leader joint, multiplier, offset)) if it mimics.
    pub mimic: Vec<Option<(usize, f64, f64)>>,
    /// The scan's warnings plus validation's own (the import report's).
    pub warnings: Vec<String>,
    /// Elements skipped whole, one line a kind (the import report's).
    pub ignored: Vec<String>,
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

pub(crate) fn is_movable(t: &JointType) -> bool {
    matches!(
        t,
        JointType::Revolute
            | JointType::Continuous
            | JointType::Prismatic
            | JointType::Floating
            | JointType::Planar
            | JointType::Spherical
    )
}

/// Whether a joint type moves one coordinate (revolute, continuous, prismatic).
pub(crate) fn is_scalar(t: &JointType) -> bool {
    matches!(
        t,
        JointType::Revolute | JointType::Continuous | JointType::Prismatic
    )
}

pub(crate) fn validate(parsed: &Parsed, file: &str) -> Result<Checked, UrdfError> {
    let robot = &parsed.robot;
    let err = |el: String, msg: String| UrdfError::new(file, Some(el), msg);
    if robot.links.is_empty() {
        return Err(UrdfError::new(
            file,
            Some("<robot>".into()),
            "no <link> elements",
        ));
    }
    let mut warnings = parsed.warnings.clone();
    let mut ignored: Vec<String> = parsed.ignored_tags.clone();

    // Names.
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if l.name.is_empty() {
            return Err(err(
                format!("link #{}", i + 1),
                "link without a name".into(),
            ));
        }
        if link_index.insert(l.name.as_str(), i).is_some() {
            return Err(err(
                format!("link \"{}\"", l.name),
                "duplicate link name".into(),
            ));
        }
    }
    let mut joint_index: HashMap<&str, usize> = HashMap::new();
    for (i, j) in robot.joints.iter().enumerate() {
        if j.name.is_empty() {
            return Err(err(
                format!("joint #{}", i + 1),
                "joint without a name".into(),
            ));
        }
        if joint_index.insert(j.name.as_str(), i).is_some() {
            return Err(err(
                format!("joint \"{}\"", j.name),
                "duplicate joint name".into(),
            ));
        }
    }

    // Links: inertials and collision geometry.
    for l in &robot.links {
        let el = format!("link \"{}\" <inertial>", l.name);
        let i = &l.inertial;
        if !finite3(&i.origin.xyz.0) || !finite3(&i.origin.rpy.0) {
            return Err(err(el, "non-finite <origin>".into()));
        }
        let m = i.mass.value;
        if !m.is_finite() || m < 0.0 {
            return Err(err(
                el,
                format!("mass must be finite and non-negative, got {m}"),
            ));
        }
        let t = &i.inertia;
        let vals = [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
        if vals.iter().any(|x| !x.is_finite()) {
            return Err(err(el, "non-finite <inertia>".into()));
        }
        let scale = vals.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // Eigenvalues of the tensor scaled to entries in [-1, 1]: huge (1e300) or
        // tiny entries neither overflow nor underflow.
        let mat = nalgebra::Matrix3::new(
            t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
        ) / if scale > 0.0 { scale } else { 1.0 };
        let eig = nalgebra::SymmetricEigen::try_new(mat, f64::EPSILON, 1000)
            .map(|e| e.eigenvalues * scale)
            .ok_or_else(|| err(el.clone(), "inertia eigenvalues did not converge".into()))?;
        let tol = 1e-9 * scale.max(1e-300);
        let (e0, e1, e2) = (eig[0], eig[1], eig[2]);
        if e0.min(e1).min(e2) < -tol {
            // Loaded as written, as Pinocchio does: the dynamics are exactly the
            // URDF's; a mass matrix that is then not positive definite is the
            // singular-H error of the algorithms (docs/theory.md, "Spatial inertia").
            warnings.push(format!(
                "link \"{}\": inertia is not positive semi-definite (principal moments {e0:.3e}, {e1:.3e}, {e2:.3e}): loaded as written",
                l.name
            ));
        } else if scale > 0.0 {
            let s = [e0, e1, e2];
            let bad = (0..3).any(|k| s[(k + 1) % 3] + s[(k + 2) % 3] < s[k] - tol);
            if bad {
                warnings.push(format!(
                    "link \"{}\": inertia breaks the triangle inequality (principal moments {e0:.3e}, {e1:.3e}, {e2:.3e}): not a physical rigid body",
                    l.name
                ));
            } else if e0.min(e1).min(e2) <= tol {
                warnings.push(format!(
                    "link \"{}\": inertia is only semi-definite (singular)",
                    l.name
                ));
            }
        }
        if m == 0.0 && scale > 0.0 {
            warnings.push(format!(
                "link \"{}\": zero mass but non-zero rotational inertia",
                l.name
            ));
        }
        for (k, c) in l.collision.iter().enumerate() {
            let el = format!("link \"{}\" <collision> #{}", l.name, k + 1);
            if !finite3(&c.origin.xyz.0) || !finite3(&c.origin.rpy.0) {
                return Err(err(el, "non-finite <origin>".into()));
            }
            use super::types::Geometry as G;
            let ok = match &c.geometry {
                G::Box { size } => size.0.iter().all(|x| x.is_finite() && *x >= 0.0),
                G::Cylinder { radius, length } | G::Capsule { radius, length } => {
                    radius.is_finite() && length.is_finite() && *radius >= 0.0 && *length >= 0.0
                }
                G::Sphere { radius } => radius.is_finite() && *radius >= 0.0,
                G::Mesh { scale, .. } => scale.as_ref().map_or(true, |s| finite3(&s.0)),
            };
            if !ok {
                return Err(err(
                    el,
                    "geometry sizes must be finite and non-negative".into(),
                ));
            }
        }
    }

    // Joints: links, types, numbers.
    let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (ji, j) in robot.joints.iter().enumerate() {
        let el = format!("joint \"{}\"", j.name);
        let p = *link_index.get(j.parent.link.as_str()).ok_or_else(|| {
            err(
                el.clone(),
                format!("parent link \"{}\" does not exist", j.parent.link),
            )
        })?;
        let c = *link_index.get(j.child.link.as_str()).ok_or_else(|| {
            err(
                el.clone(),
                format!("child link \"{}\" does not exist", j.child.link),
            )
        })?;
        if p == c {
            return Err(err(
                el,
                format!("link \"{}\" is its own parent", j.parent.link),
            ));
        }
        if let Some(other) = parent_joint[c] {
            return Err(err(
                el,
                format!(
                    "link \"{}\" already has a parent (joint \"{}\")",
                    j.child.link, robot.joints[other].name
                ),
            ));
        }
        parent_joint[c] = Some(ji);
        children[p].push(ji);
        if !finite3(&j.origin.xyz.0) || !finite3(&j.origin.rpy.0) {
            return Err(err(el, "non-finite <origin>".into()));
        }
        if is_scalar(&j.joint_type) || j.joint_type == JointType::Planar {
            let a = j.axis.xyz.0;
            if !finite3(&a) {
                return Err(err(el, "non-finite <axis>".into()));
            }
            if a.iter().map(|x| x * x).sum::<f64>().sqrt() <= 1e-12 {
                return Err(err(el, "zero <axis>".into()));
            }
        }
        if is_scalar(&j.joint_type) {
            let l = &j.limit;
            for (v, n) in [
                (l.lower, "lower"),
                (l.upper, "upper"),
                (l.effort, "effort"),
                (l.velocity, "velocity"),
            ] {
                if v.is_nan() {
                    return Err(err(format!("{el} <limit>"), format!("{n} is NaN")));
                }
            }
            if l.lower.is_finite() && l.upper.is_finite() && l.lower > l.upper {
                return Err(err(
                    format!("{el} <limit>"),
                    format!("lower {} > upper {}", l.lower, l.upper),
                ));
            }
            if j.joint_type != JointType::Continuous && l.lower == 0.0 && l.upper == 0.0 {
                warnings.push(format!(
                    "joint \"{}\": no <limit> or a 0..0 range: position limits unknown (treated as unlimited, not locked)",
                    j.name
                ));
            }
        }
        if let Some(d) = &j.dynamics {
            if !d.damping.is_finite()
                || !d.friction.is_finite()
                || d.damping < 0.0
                || d.friction < 0.0
            {
                return Err(err(
                    format!("{el} <dynamics>"),
                    "damping and friction must be finite and non-negative".into(),
                ));
            }
        }
        if j.calibration.is_some() || j.safety_controller.is_some() {
            ignored.push(format!(
                "joint \"{}\": <calibration>/<safety_controller> (not used by dynamics)",
                j.name
            ));
        }
    }

    // One root, no cycles: every link reachable from the single parentless link.
    let roots: Vec<usize> = (0..robot.links.len())
        .filter(|&i| parent_joint[i].is_none())
        .collect();
    if roots.is_empty() {
        // Every link has a parent: following parents from any link runs into a cycle.
        let mut l = 0;
        let mut steps = 0;
        while let Some(j) = parent_joint[l] {
            l = link_index
                .get(robot.joints[j].parent.link.as_str())
                .copied()
                .unwrap_or(0);
            steps += 1;
            if steps > robot.links.len() {
                break;
            }
        }
        return Err(err(
            format!("link \"{}\"", robot.links[l].name),
            "is part of a cycle of joints: the robot has no root link".into(),
        ));
    }
    if roots.len() > 1 {
        let names: Vec<String> = roots
            .iter()
            .take(4)
            .map(|&i| format!("\"{}\"", robot.links[i].name))
            .collect();
        return Err(UrdfError::new(
            file,
            Some(format!("link {}", names[1])),
            format!(
                "more than one root link ({}): the links do not form one tree",
                names.join(", ")
            ),
        ));
    }
    let root = roots[0];
    let mut seen = vec![false; robot.links.len()];
    let mut stack = vec![root];
    let mut count = 0;
    while let Some(l) = stack.pop() {
        if seen[l] {
            continue;
        }
        seen[l] = true;
        count += 1;
        for &j in &children[l] {
            if let Some(&c) = link_index.get(robot.joints[j].child.link.as_str()) {
                stack.push(c);
            }
        }
    }
    if count != robot.links.len() {
        let l = (0..robot.links.len()).find(|&i| !seen[i]).unwrap_or(0);
        return Err(err(
            format!("link \"{}\"", robot.links[l].name),
            "is part of a cycle of joints".into(),
        ));
    }

    // Mimic relations: resolved to the end of each chain.
    let mut direct: Vec<Option<(usize, f64, f64)>> = vec![None; robot.joints.len()];
    for (ji, j) in robot.joints.iter().enumerate() {
        let Some(m) = &j.mimic else { continue };
        let el = format!("joint \"{}\" <mimic>", j.name);
        if !is_movable(&j.joint_type) {
            ignored.push(format!(
                "joint \"{}\": <mimic> on a fixed joint (ignored)",
                j.name
            ));
            continue;
        }
        if !is_scalar(&j.joint_type) {
            return Err(err(
                el,
                format!(
                    "a {} joint cannot mimic (only revolute, continuous and prismatic joints can)",
                    format!("{:?}", j.joint_type).to_lowercase()
                ),
            ));
        }
        let leader = *joint_index.get(m.joint.as_str()).ok_or_else(|| {
            err(
                el.clone(),
                format!("leader joint \"{}\" does not exist", m.joint),
            )
        })?;
        if !is_movable(&robot.joints[leader].joint_type) {
            return Err(err(
                el,
                format!("leader joint \"{}\" is not movable", m.joint),
            ));
        }
        if !is_scalar(&robot.joints[leader].joint_type) {
            return Err(err(
                el,
                format!(
                    "leader joint \"{}\" has several degrees of freedom",
                    m.joint
                ),
            ));
        }
        let mult = m.multiplier.unwrap_or(1.0);
        let off = m.offset.unwrap_or(0.0);
        if !mult.is_finite() || !off.is_finite() {
            return Err(err(el, "non-finite multiplier or offset".into()));
        }
        direct[ji] = Some((leader, mult, off));
    }
    let mut mimic = vec![None; robot.joints.len()];
    for ji in 0..robot.joints.len() {
        let Some((mut leader, mut mult, mut off)) = direct[ji] else {
            continue;
        };
        let mut steps = 0;
        while let Some((l2, m2, o2)) = direct[leader] {
            // q_leader = m2 q_l2 + o2  =>  q = mult (m2 q_l2 + o2) + off
            off += mult * o2;
            mult *= m2;
            leader = l2;
            steps += 1;
            if steps > robot.joints.len() {
                return Err(err(
                    format!("joint \"{}\" <mimic>", robot.joints[ji].name),
                    "mimic cycle".into(),
                ));
            }
        }
        if leader == ji {
            return Err(err(
                format!("joint \"{}\" <mimic>", robot.joints[ji].name),
                "mimic cycle".into(),
            ));
        }
        mimic[ji] = Some((leader, mult, off));
    }
    // Pinocchio's order: a link's children by their joints' names, byte-wise.
    for c in &mut children {
        c.sort_by(|&a, &b| {
            robot.joints[a]
                .name
                .as_bytes()
                .cmp(robot.joints[b].name.as_bytes())
        });
    }
    Ok(Checked {
        root,
        children,
        mimic,
        warnings,
        ignored,
    })
}
