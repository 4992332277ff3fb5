//! A model as a forest: one tree per URDF model under the world (body 0), each
//! with its own contiguous bodies, links, degrees of freedom and q, v ranges
//! (a lone URDF is one tree), and the free joints among their roots.

use super::Model;
use crate::spatial::Scalar;
use std::ops::Range;

/// One URDF model of a [`Model`]: its contiguous ranges of bodies, frames
/// (links), degrees of freedom and coordinates. A floating tree's q starts with
/// its free joint's 7 coordinates and its v with its 6, then its joints.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tree {
    /// The model's name in its scene (empty for a lone URDF: names unprefixed).
    pub name: String,
    /// Its bodies (the world excluded).
    pub bodies: Range<usize>,
    /// Its URDF links in [`Model::frames`].
    pub frames: Range<usize>,
    /// Its joint degrees of freedom in [`Model::dofs`].
    pub dofs: Range<usize>,
    /// Its configuration coordinates.
    pub q: Range<usize>,
    /// Its velocity coordinates.
    pub v: Range<usize>,
    /// Index in [`Model::free_joints`] of its free root joint, if it floats.
    pub free: Option<usize>,
}

impl Tree {
    /// A one-tree model's tree: every body, frame and coordinate (`nq`, `nv`: the
    /// model's, a free base's included).
    pub fn whole(
        nbodies: usize,
        nframes: usize,
        ndofs: usize,
        nq: usize,
        nv: usize,
        floating: bool,
    ) -> Self {
        Tree {
            name: String::new(),
            bodies: 1..nbodies,
            frames: 0..nframes,
            dofs: 0..ndofs,
            q: 0..nq,
            v: 0..nv,
            free: floating.then_some(0),
        }
    }
    /// The first joint coordinate in q (after a free joint's 7).
    pub fn joint_q(&self) -> usize {
        self.q.start + if self.free.is_some() { 7 } else { 0 }
    }
    /// The first joint coordinate in v (after a free joint's 6).
    pub fn joint_v(&self) -> usize {
        self.v.start + if self.free.is_some() { 6 } else { 0 }
    }
    /// `"NAME/"` in a scene, `""` for a lone URDF: the prefix of its names.
    pub fn prefix(&self) -> String {
        if self.name.is_empty() {
            String::new()
        } else {
            format!("{}/", self.name)
        }
    }
}

/// A free (6-DoF) root joint: its body and where its coordinates start
/// (q: position then quaternion x, y, z, w; v: body-frame linear then angular).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FreeJoint {
    /// The body the joint moves.
    pub body: usize,
    /// Its first coordinate in q (7 of them).
    pub iq: usize,
    /// Its first coordinate in v (6 of them).
    pub iv: usize,
    /// The stem of its column names: `base` (a lone URDF) or `MODEL/base`.
    pub name: String,
}

impl<T: Scalar> Model<T> {
    /// Every 1-DoF joint as `(d, iq, iv)`: its position in [`Model::dofs`] and
    /// its indices in q and v, in engine order. Joints of several degrees of
    /// freedom (spherical, planar, floating) are left out: see
    /// [`Model::joint_indices`].
    pub fn dof_indices(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.dofs
            .iter()
            .enumerate()
            .filter(|(_, d)| d.kind.nv() == 1)
            .map(|(k, d)| (k, d.iq, d.iv))
    }
    /// Every joint that owns coordinates as `(d, iq, iv)`, whatever its number of
    /// coordinates ([`JointKind::nq`], [`JointKind::nv`] of `dofs[d].kind`).
    ///
    /// [`JointKind::nq`]: super::JointKind::nq
    /// [`JointKind::nv`]: super::JointKind::nv
    pub fn joint_indices(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.dofs
            .iter()
            .enumerate()
            .map(|(k, d)| (k, d.iq, d.iv))
    }
    /// The index in q of the (first coordinate of the) joint `dofs[d]`.
    pub fn dof_q(&self, d: usize) -> usize {
        self.dofs[d].iq
    }
    /// The index in v of the (first coordinate of the) joint `dofs[d]`.
    pub fn dof_v(&self, d: usize) -> usize {
        self.dofs[d].iv
    }
    /// The joint (in [`Model::dofs`]) whose velocity coordinates hold `iv`, if it
    /// is a joint's (not a free base's).
    pub fn dof_at_v(&self, iv: usize) -> Option<usize> {
        let k = self.dofs.partition_point(|d| d.iv <= iv).checked_sub(1)?;
        let d = &self.dofs[k];
        (iv < d.iv + d.kind.nv()).then_some(k)
    }
    /// The tree (model) body `b` belongs to (`None` for the world).
    pub fn tree_of_body(&self, b: usize) -> Option<usize> {
        self.trees.iter().position(|t| t.bodies.contains(&b))
    }
    /// The tree (model) a frame (URDF link) belongs to.
    pub fn tree_of_frame(&self, f: usize) -> Option<usize> {
        self.trees.iter().position(|t| t.frames.contains(&f))
    }
}
