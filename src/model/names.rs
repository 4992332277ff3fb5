//! Typed ids for joints, bodies and link frames, and lookups by name that fail
//! with an error naming the unknown name and the nearest known one.

use super::{JointKind, Model};
use crate::spatial::Scalar;
use std::ops::Range;

/// A body of [`Model`]: an index into its per-body arrays (`parent`, `joints`,
/// `inertias`, …; 0 is the world, with every link welded to it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(pub usize);

/// A joint of [`Model`]: joint i connects body i to its parent, so a `JointId`
/// indexes `model.joints` and `model.body_joint_names` (0 is the "universe").
/// Fixed URDF joints are merged away and have no id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JointId(pub usize);

/// A URDF link's frame: an index into `model.frames` (and `data.o_m_f`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FrameId(pub usize);

/// A name, or an id, that the model does not have.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// No `kind` ("joint", "link", …) of this name; `nearest` is the known name
    /// closest to it by edit distance, if the model has any.
    #[error("unknown {kind} \"{name}\"{}", nearest.as_ref().map(|n| format!(" (nearest: \"{n}\")")).unwrap_or_default())]
    Unknown {
        /// What was looked up: "joint", "link", "degree of freedom".
        kind: &'static str,
        /// The name asked for.
        name: String,
        /// The closest known name.
        nearest: Option<String>,
    },
    /// An id past the end of the model's arrays.
    #[error("{kind} id {id} out of range (the model has {len})")]
    OutOfRange {
        /// What the id indexes: "joint", "body", "frame".
        kind: &'static str,
        /// The id given.
        id: usize,
        /// How many there are.
        len: usize,
    },
}

/// Levenshtein edit distance (insertions, deletions, substitutions) by characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let up = row[j + 1];
            row[j + 1] = (up + 1).min(row[j] + 1).min(diag + usize::from(ca != *cb));
            diag = up;
        }
    }
    row[b.len()]
}

/// The candidate closest to `name` by [`edit_distance`]; among equals the one
/// sharing the longest prefix with `name`, then the first.
pub fn nearest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<String> {
    let prefix = |c: &str| {
        name.chars()
            .zip(c.chars())
            .take_while(|(a, b)| a == b)
            .count()
    };
    candidates
        .into_iter()
        .map(|c| (edit_distance(name, c), usize::MAX - prefix(c), c))
        .min_by_key(|(d, p, _)| (*d, *p))
        .map(|(_, _, c)| c.to_string())
}

fn find<'a>(
    kind: &'static str,
    name: &str,
    names: impl Iterator<Item = &'a str> + Clone,
) -> Result<usize, NameError> {
    names
        .clone()
        .position(|n| n == name)
        .ok_or_else(|| NameError::Unknown {
            kind,
            name: name.to_string(),
            nearest: nearest(name, names),
        })
}

impl<T: Scalar> Model<T> {
    /// The joint of a URDF joint name (movable joints, mimic joints included;
    /// the free base's joint is "root_joint").
    pub fn joint_id(&self, name: &str) -> Result<JointId, NameError> {
        find(
            "joint",
            name,
            self.body_joint_names.iter().skip(1).map(String::as_str),
        )
        .map(|i| JointId(i + 1))
    }
    /// The frame of a URDF link (every link, fixed-joint children included).
    pub fn frame_id(&self, link: &str) -> Result<FrameId, NameError> {
        find("link", link, self.frames.iter().map(|f| f.name.as_str())).map(FrameId)
    }
    /// The body a URDF link belongs to (links welded by fixed joints share one;
    /// links welded to the world belong to body 0).
    pub fn body_id(&self, link: &str) -> Result<BodyId, NameError> {
        self.frame_id(link).map(|f| BodyId(self.frames[f.0].body))
    }
    /// The URDF joint name of a joint.
    pub fn joint_name(&self, id: JointId) -> Result<&str, NameError> {
        self.body_joint_names
            .get(id.0)
            .map(String::as_str)
            .ok_or(NameError::OutOfRange {
                kind: "joint",
                id: id.0,
                len: self.nbodies,
            })
    }
    /// The URDF link name of a frame.
    pub fn frame_name(&self, id: FrameId) -> Result<&str, NameError> {
        self.frames
            .get(id.0)
            .map(|f| f.name.as_str())
            .ok_or(NameError::OutOfRange {
                kind: "frame",
                id: id.0,
                len: self.frames.len(),
            })
    }
    /// Every URDF link name, in `model.frames` order.
    pub fn link_names(&self) -> Vec<&str> {
        self.frames.iter().map(|f| f.name.as_str()).collect()
    }
    /// Whether a joint is a mimic joint (it follows a leader and owns no coordinate).
    pub fn is_mimic(&self, id: JointId) -> bool {
        self.joints.get(id.0).is_some_and(|j| {
            id.0 != 0
                && !matches!(j.kind, JointKind::Free)
                && self.body_joint_names[id.0] != self.dof_name_at(j.iv)
        })
    }
    fn dof_name_at(&self, iv: usize) -> &str {
        self.dof_at_v(iv)
            .and_then(|d| self.dofs.get(d))
            .map_or("", |d| d.name.as_str())
    }
    /// The joint's configuration coordinates: `q[range]` (7 for a free joint:
    /// position then quaternion x, y, z, w; 4 for a spherical joint's quaternion;
    /// 3 for a planar joint's x, y, θ; 1 for a revolute or prismatic joint).
    /// A mimic joint owns none: its range is empty. The universe's is empty.
    pub fn joint_q_range(&self, id: JointId) -> Result<Range<usize>, NameError> {
        self.joint_range(id, |j| (j.iq, j.nq()))
    }
    /// The joint's velocity coordinates: `v[range]` (and `a`, `tau`; 6 for the free
    /// base: body-frame linear then angular; 1 for a revolute or prismatic joint).
    /// A mimic joint owns none: its range is empty. The universe's is empty.
    pub fn joint_v_range(&self, id: JointId) -> Result<Range<usize>, NameError> {
        self.joint_range(id, |j| (j.iv, j.nv()))
    }
    fn joint_range(
        &self,
        id: JointId,
        f: impl Fn(&super::Joint<T>) -> (usize, usize),
    ) -> Result<Range<usize>, NameError> {
        let j = self.joints.get(id.0).ok_or(NameError::OutOfRange {
            kind: "joint",
            id: id.0,
            len: self.nbodies,
        })?;
        if id.0 == 0 || self.is_mimic(id) {
            return Ok(0..0);
        }
        let (start, n) = f(j);
        Ok(start..start + n)
    }
    /// The name of every entry of q in engine order (mechanisms.md "In `eval`"): a
    /// 1-DoF joint is its name; a spherical joint `J:qx, J:qy, J:qz, J:qw`; a
    /// planar joint `J:x, J:y, J:theta`; a floating joint `J:x, J:y, J:z, J:qx,
    /// J:qy, J:qz, J:qw`; a free base `base_x … base_qw` (`MODEL/base_x` in a scene).
    pub fn q_names(&self) -> Vec<String> {
        self.coordinate_names(true)
    }
    /// The name of every entry of v (and `a`, `tau`, H's rows) in engine order: a
    /// 1-DoF joint is its name; a spherical joint `J:wx, J:wy, J:wz`; a planar
    /// joint `J:vx, J:vy, J:wz`; a floating joint `J:vx, J:vy, J:vz, J:wx, J:wy,
    /// J:wz`; a free base `base_vx … base_wz`.
    pub fn v_names(&self) -> Vec<String> {
        self.coordinate_names(false)
    }
    fn coordinate_names(&self, q: bool) -> Vec<String> {
        const FREE_Q: [&str; 7] = ["x", "y", "z", "qx", "qy", "qz", "qw"];
        const FREE_V: [&str; 6] = ["vx", "vy", "vz", "wx", "wy", "wz"];
        let mut out = Vec::with_capacity(if q { self.nq } else { self.nv });
        for t in &self.trees {
            if let Some(f) = t.free.and_then(|i| self.free_joints.get(i)) {
                let s: &[&str] = if q { &FREE_Q } else { &FREE_V };
                out.extend(s.iter().map(|s| format!("{}_{s}", f.name)));
            }
            for d in &self.dofs[t.dofs.clone()] {
                let s: &[&str] = match (d.kind, q) {
                    (JointKind::Free, true) => &FREE_Q,
                    (JointKind::Free, false) => &FREE_V,
                    (JointKind::Spherical, true) => &["qx", "qy", "qz", "qw"],
                    (JointKind::Spherical, false) => &["wx", "wy", "wz"],
                    (JointKind::Planar, true) => &["x", "y", "theta"],
                    (JointKind::Planar, false) => &["vx", "vy", "wz"],
                    _ => &[],
                };
                if s.is_empty() {
                    out.push(d.name.clone());
                } else {
                    out.extend(s.iter().map(|s| format!("{}:{s}", d.name)));
                }
            }
        }
        out
    }
    /// The index in q of a degree of freedom (a movable, non-mimic 1-DoF joint) by name.
    pub fn q_index(&self, joint: &str) -> Result<usize, NameError> {
        self.dof_position(joint).map(|d| self.dof_q(d))
    }
    /// The index in v (and `a`, `tau`, H's rows) of a degree of freedom by name.
    pub fn v_index(&self, joint: &str) -> Result<usize, NameError> {
        self.dof_position(joint).map(|d| self.dof_v(d))
    }
    /// The position of a degree of freedom in `model.dofs` (neither a q nor a v index).
    fn dof_position(&self, joint: &str) -> Result<usize, NameError> {
        find(
            "degree of freedom",
            joint,
            self.dofs.iter().map(|d| d.name.as_str()),
        )
    }
}
