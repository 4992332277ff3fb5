use super::Model;
use crate::spatial::{CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{DMatrix, DVector, Matrix6, Vector6};

/// The preallocated workspace of every algorithm: sized once from a [`Model`],
/// then reused with no allocation in the hot path. The results and the
/// kinematics come first; then each algorithm's own scratch, named after it
/// (`crba_*`, `aba_*`), which nothing outside that algorithm reads.
#[derive(Clone, Debug)]
pub struct Data<T: Scalar = f64> {
    // Kinematics (forward kinematics, RNEA, ABA).
    /// `liMi`: body i's frame in its parent's frame.
    pub li_m_i: Vec<Se3<T>>,
    /// `oMi`: body i's frame in the world.
    pub o_m_i: Vec<Se3<T>>,
    /// `oMf`: every URDF link frame in the world.
    pub o_m_f: Vec<Se3<T>>,
    /// Spatial velocity of each body (body frame).
    pub v: Vec<Motion<T>>,
    /// Spatial acceleration of each body (body frame, gravity included, docs/theory.md §"Gravity").
    pub a: Vec<Motion<T>>,
    /// Spatial force transmitted by each body's joint (body frame, docs/theory.md
    /// §"Force recursion").
    pub f: Vec<Force<T>>,

    // Results.
    /// Generalized forces from inverse dynamics.
    pub tau: DVector<T>,
    /// C(q, v) (docs/theory.md §"Bias forces").
    pub bias: DVector<T>,
    /// Generalized accelerations from forward dynamics.
    pub qdd: DVector<T>,
    /// The joint-space inertia matrix H(q) (full, symmetric).
    pub h: DMatrix<T>,
    /// The factor of H (Cholesky or tree-sparse LTDL, docs/theory.md §"Tree-sparse LTDL").
    pub chol: DMatrix<T>,

    // Forward dynamics by inverse dynamics (docs/theory.md §"Forward dynamics by
    // inverse dynamics").
    /// Scratch vector of size nv.
    pub tmp_a: DVector<T>,

    // CRBA (docs/theory.md §"Composite-rigid-body algorithm").
    /// CRBA: composite inertia of each body's subtree (origin form, body frame).
    pub crba_ic: Vec<CompositeInertia<T>>,
    /// CRBA: `F = I^c S` of every velocity coordinate, moved towards the root,
    /// structure of arrays (nv x 6: columns nx, ny, nz, fx, fy, fz).
    pub crba_f: DMatrix<T>,
    /// CRBA (local frames): `F = I^c S` of every velocity coordinate of the current
    /// subtree, in the frame it has been carried to.
    pub crba_fc: Vec<Force<T>>,

    // ABA (docs/theory.md §"Articulated-body algorithm").
    /// ABA: articulated inertia `Iᴬ` of each body (6x6, angular-first, body frame).
    pub aba_ia: Vec<Matrix6<T>>,
    /// ABA: `U = Iᴬ S` of a 1-DoF joint; for a free joint, `τ − pᴬ` as a 6-vector.
    pub aba_u: Vec<Vector6<T>>,
    /// ABA: `1 / D = 1 / (Sᵀ U)` of a 1-DoF joint.
    pub aba_dinv: Vec<T>,
    /// ABA: `u = τ − Sᵀ pᴬ` of a 1-DoF joint.
    pub aba_uq: Vec<T>,
    /// ABA: velocity-product acceleration `c = v × S q̇` of each body.
    pub aba_c: Vec<Motion<T>>,
}

impl<T: Scalar> Data<T> {
    /// The workspace for `model`, every entry zero (or the identity).
    pub fn new(model: &Model<T>) -> Self {
        let nb = model.nbodies;
        let nv = model.nv;
        Self {
            li_m_i: vec![Se3::identity(); nb],
            o_m_i: vec![Se3::identity(); nb],
            o_m_f: vec![Se3::identity(); model.frames.len()],
            v: vec![Motion::zero(); nb],
            a: vec![Motion::zero(); nb],
            f: vec![Force::zero(); nb],
            tau: DVector::zeros(nv),
            bias: DVector::zeros(nv),
            qdd: DVector::zeros(nv),
            h: DMatrix::zeros(nv, nv),
            chol: DMatrix::zeros(nv, nv),
            tmp_a: DVector::zeros(nv),
            crba_ic: vec![CompositeInertia::zero(); nb],
            crba_f: DMatrix::zeros(nv, 6),
            crba_fc: vec![Force::zero(); nv],
            aba_ia: vec![Matrix6::zeros(); nb],
            aba_u: vec![Vector6::zeros(); nb],
            aba_dinv: vec![T::zero(); nb],
            aba_uq: vec![T::zero(); nb],
            aba_c: vec![Motion::zero(); nb],
        }
    }
}
