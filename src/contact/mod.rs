//! Contact: the collision geometry against the ground plane z = `ground`, against
//! static obstacles, and between bodies (the pipeline of [`Collision`]: the
//! ground's fast path [`ground`], then the pairs' broad phase [`broad`], pair
//! filter [`filter`] and narrow phase [`pairs`] on the shapes of [`shapes`]).
//!
//! # Geometry
//! Each `<collision>` element of a link that moves (links welded to the world take
//! no part) becomes a `parry3d-f64` shape: box → `Cuboid`, sphere → `Ball`,
//! cylinder → `Cylinder` (parry's axis is y, the URDF's z: a fixed x-rotation of
//! +90° is folded into the placement), capsule → `Capsule` (z axis), mesh →
//! `ConvexPolyhedron`, the convex hull of the file's vertices (STL, OBJ, DAE; see
//! [`mesh`]). Meshes are read only here, i.e. only when contact is on; a missing or
//! unreadable mesh file is an error naming the file and the link.
//! Pairs of shapes (two bodies, a body and an obstacle welded to the world) go
//! through scene.md "Who touches whom" ([`filter`]) and parry's contact
//! manifolds ([`pairs`]): see docs/theory.md §"Contact pairs".
//!
//! # Detection
//! Per step, a shape whose bounding sphere is clear of the plane by more than
//! the margin is skipped from its origin's height alone. The margin is
//! `δ` (5 mm), or, with [`ContactParams::travel_factor`] c > 0 (an MJCF
//! world), c times the distance the shape travelled in the last step when
//! that is more (a speculative margin: a fast impact is found before it,
//! docs/theory.md §"Speculative margin", `travel`). Otherwise
//! (one query, counted in [`GroundContact::queries`]) its contact *manifold* is
//! its points within `δ` of the plane, found without a general support query
//! (a plane's cheap special cases, as MuJoCo's colliders): a box's corners, a hull's vertices, a
//! cylinder's lowest rim points plus 6 samples on each rim, a sphere's lowest
//! point, a capsule's two end-sphere lowest points (a hull's candidates from its
//! vertices' heights, on its vertex graph when it is large). More than 4 such
//! points are reduced to 4: the deepest and the extremes in 3 horizontal
//! directions, each preferring a point kept last step (a persistent patch that
//! spans the support polygon, see `reduce`). Each
//! point keeps a stable *slot* (shape, feature) so the solver can warm-start.
//!
//! # Forces (solved in [`crate::sim`], docs/theory.md §"Constraint rows")
//! Contact is a velocity-level, time-stepping (Stewart–Trinkle / Anitescu) impulse
//! model: for a point with normal n = +z, signed gap φ (negative = penetration)
//! and Jacobian J (ṗ = J q̇), the step's impulse λ = (λₙ, λₜ₁, λₜ₂) satisfies
//!
//! - 0 ≤ λₙ ⊥ (uₙ − bₙ) ≥ 0 with uₙ = n·ṗ after the step and
//!   bₙ = −φ/Δt when φ > 0 (speculative: the gap may close, not overshoot) and
//!   bₙ = 0 when φ ≤ 0, or with restitution e > 0 and an approaching point,
//!   bₙ = max(bₙ, −e uₙ⁻);
//! - Coulomb's cone ‖λₜ‖ ≤ μ λₙ with maximal dissipation: λₜ opposes the tangential
//!   velocity, and the point sticks (uₜ = 0) while inside the cone — static
//!   friction is exact, not regularised;
//!
//! solved by projected Gauss–Seidel on the Delassus matrix W = J H̃⁻¹ Jᵀ
//! (H̃ = H + A + Δt·D, damping implicit), kept implicit as W = Y Yᵀ with
//! Y = J R⁻¹ (H̃ = RᵀR, tree-sparse: each row lives on its body's path to the
//! root, `crate::sim::factor`; the solver carries R Δv), warm-started from the last step's impulses (stable point slots), to
//! 1e-6 m/s (or rad/s) change per sweep, at most 20 sweeps; sweeps 4–10
//! over-relax the scalar rows by 1.3 (projected SOR) and a plain sweep ends the
//! solve (`crate::sim::solver`; a solve stopped by the cap is made
//! energy-safe). Penetration is removed by the position pass (split impulse):
//! a pseudo-velocity that moves q, never v, at β = 0.2 of the depth per step
//! and at most [`ContactParams::max_push_speed`] (0.5 m/s). The impulse is
//! turned into a world-frame spatial force per body, f̂ = Σ (p × F, F) with
//! F = (λₙ n + λₜ₁ t₁ + λₜ₂ t₂)/Δt (docs/theory.md §"External forces"). With
//! zero restitution the model never adds energy at an impact; it is
//! unconditionally stable at any step (no stiffness).

pub mod broad;
pub(crate) mod face;
pub(crate) mod fetch;
pub mod filter;
pub mod frame;
pub mod ground;
pub(crate) mod hull;
pub(crate) mod narrow;
pub mod pairs;
mod pipeline;
pub(crate) mod shapes;
pub(crate) mod travel;

pub use crate::mesh::resolve_mesh_path;
pub use filter::DroppedPair;
pub use ground::{GroundContact, GroundShape};
use nalgebra::Vector3;
pub use pairs::{tangents, PairContact};
pub use pipeline::Collision;

/// Contact parameters (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Coulomb friction coefficient μ between links and the ground.
    pub friction: f64,
    /// Newton restitution coefficient e (0: perfectly inelastic).
    pub restitution: f64,
    /// Baumgarte factor β: the fraction of a penetration removed per step by
    /// the position pass (never through the velocity).
    pub baumgarte: f64,
    /// The fastest the position pass pushes a penetrating point out (m/s): a
    /// start deep in the ground comes out slowly, never thrown.
    pub max_push_speed: f64,
    /// Penetration left alone (m): below it nothing is pushed.
    pub slop: f64,
    /// Detection margin δ (m): points closer than this to the plane are candidates.
    pub margin: f64,
    /// The most contact points a shape gives (MuJoCo gives a hull on a plane at
    /// most 3, a box 4): the deepest, then the extremes in this many minus one
    /// horizontal directions, each preferring last step's points. 4 with that
    /// persistent patch settles every robot of the sweep (without persistence, 4
    /// left solo12 rocking on its mesh links and needed 8). A hull may add as
    /// many points kept from last step that are still in the ground
    /// (docs/theory.md §"Contact geometry").
    pub max_points_per_shape: usize,
    /// Torsional friction coefficient μ_τ (m): a contact resists spinning
    /// about its normal with a torque up to μ_τ fₙ (MuJoCo's second friction
    /// coefficient, `condim` 4); applied where a shape pair touches at one
    /// point (docs/theory.md §"Torsional and rolling friction"). 0 (the
    /// default): off. 5 mm is MuJoCo's value, and what the Luxo scenes set.
    pub torsion: f64,
    /// Rolling friction coefficient μ_r (m): a contact resists rolling with a
    /// torque up to μ_r fₙ (MuJoCo's third, `condim` 6); applied where a shape
    /// pair touches at one or two points. 0 (the default): off. 1 mm, what
    /// the Luxo scenes set, is the rolling resistance of a hard wheel on a
    /// hard floor (c_rr = μ_r/R ≈ 0.01 at R = 0.1 m): a 0.1 m ball rolled at
    /// 1 m/s stops after about 7 m.
    pub rolling: f64,
    /// The speculative margin's factor c: a shape that moved s in the last
    /// step (toward the ground; in a pair, the two shapes' farthest points
    /// summed) is searched within max(δ, c·s) this step, so that an impact
    /// faster than δ a step is found before it, not millimetres deep
    /// (docs/theory.md §"Speculative margin"). 0 (the default): δ alone;
    /// [`Self::TRAVEL`] for an MJCF world's large steps (`urdyn simulate
    /// MODEL.xml`).
    pub travel_factor: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            friction: 1.0,
            restitution: 0.0,
            baumgarte: 0.2,
            max_push_speed: 0.5,
            slop: 1e-4,
            margin: 0.005,
            max_points_per_shape: 4,
            torsion: 0.0,
            rolling: 0.0,
            travel_factor: 0.0,
        }
    }
}

impl ContactParams {
    /// The speculative margin's factor of an MJCF world ([`Self::travel_factor`]).
    pub const TRAVEL: f64 = 1.5;
}

/// Why ground contact could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A collision mesh file that no package root or path resolves to.
    /// (The message names no flag: the CLI and the Python package each add how
    /// to give a package root or turn contact off.)
    #[error("link \"{link}\": collision mesh \"{file}\" not found")]
    MissingMesh {
        /// The URDF link whose `<collision>` names the mesh.
        link: String,
        /// The mesh filename as the URDF gives it.
        file: String,
    },
    /// A collision mesh file that was found but could not be read (unreadable,
    /// malformed, empty, or with non-finite coordinates).
    #[error("link \"{link}\": {source}")]
    Mesh {
        /// The URDF link whose `<collision>` names the mesh.
        link: String,
        /// What went wrong with the file.
        #[source]
        source: crate::mesh::MeshError,
    },
    /// A collision primitive with a non-finite or negative dimension.
    #[error("link \"{link}\": collision {kind} has a non-finite or negative size")]
    BadSize {
        /// The URDF link the primitive belongs to.
        link: String,
        /// The primitive: `box`, `sphere`, `cylinder` or `capsule`.
        kind: &'static str,
    },
}

/// "No geometry": [`ContactPoint::other_geom`] of a point on the ground.
pub const NO_GEOM: usize = usize::MAX;

/// A contact point found by [`Collision::detect`]: on the shape of geometry
/// `geom` (body `body`) against the ground or the geometry `other_geom` (body
/// `other`, 0 for the world: the ground or an obstacle).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// Index of the shape (ground points) or pair (pair points) in its detector.
    pub shape: usize,
    /// A stable identity of the point across steps (global slot index).
    pub slot: usize,
    /// The body the shape moves with (index into the model's bodies).
    pub body: usize,
    /// The contact point, world frame (between the two shapes' witness points).
    pub point: Vector3<f64>,
    /// Signed distance between the shapes along the normal (negative: penetration depth).
    pub gap: f64,
    /// Index of the shape's geometry in the model's collisions.
    pub geom: usize,
    /// The body on the other side (0: the world, i.e. the ground or an obstacle).
    pub other: usize,
    /// The other side's geometry in the model's collisions ([`NO_GEOM`]: the ground).
    pub other_geom: usize,
    /// Unit contact normal, world frame, from the other side toward this
    /// shape (+z on the ground): the direction of the impulse on `body`.
    pub normal: Vector3<f64>,
    /// The pair's Coulomb friction coefficient (the larger of its sides').
    pub friction: f64,
    /// A point whose slot held other features last step: no warm start.
    pub fresh: bool,
    /// The pair's features at the point (parry's feature ids; 0 on the ground).
    pub key: u64,
}
