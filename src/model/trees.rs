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
    /// A one-tree model's tree: every body, frame and coordinate.
    pub fn whole(nbodies: usize, nframes: usize, ndofs: usize, floating: bool) -> Self {
        let (bq, bv) = if floating { (7, 6) } else { (0, 0) };
        Tree {
            name: String::new(),
            bodies: 1..nbodies,
            frames: 0..nframes,
            dofs: 0..ndofs,
            q: 0..bq + ndofs,
            v: 0..bv + ndofs,
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
    /// Every degree of freedom as `(d, iq, iv)`: its position in [`Model::dofs`]
    /// and its indices in q and v, in engine order.
    pub fn dof_indices(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.trees.iter().flat_map(|t| {
            let (q0, v0) = (t.joint_q(), t.joint_v());
            t.dofs
                .clone()
                .enumerate()
                .map(move |(k, d)| (d, q0 + k, v0 + k))
        })
    }
    /// The index in q of the degree of freedom `dofs[d]`.
    pub fn dof_q(&self, d: usize) -> usize {
        self.tree_of_dof(d)
            .map_or(d, |t| t.joint_q() + d - t.dofs.start)
    }
    /// The index in v of the degree of freedom `dofs[d]`.
    pub fn dof_v(&self, d: usize) -> usize {
        self.tree_of_dof(d)
            .map_or(d, |t| t.joint_v() + d - t.dofs.start)
    }
    /// The degree of freedom at velocity index `iv`, if it is a joint's (not a
    /// free joint's).
    pub fn dof_at_v(&self, iv: usize) -> Option<usize> {
        let t = self.trees.iter().find(|t| t.v.contains(&iv))?;
        let k = iv.checked_sub(t.joint_v())?;
        (k < t.dofs.len()).then_some(t.dofs.start + k)
    }
    fn tree_of_dof(&self, d: usize) -> Option<&Tree> {
        self.trees.iter().find(|t| t.dofs.contains(&d))
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
