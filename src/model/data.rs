use super::Model;
use crate::spatial::{CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};

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
    /// Each body's joint as the hot passes run it (`joint::dispatch_of` of
    /// the model this workspace was made for, entry 0 unused): the passes at
    /// forward kinematics' placements (the simulation's bias and CRBA) read
    /// it instead of re-deriving it per body and pass.
    pub(crate) dispatch: Vec<(super::joint::Dispatch<T>, T, T)>,
    /// `k k` for `k = u*` of each body whose joint is revolute about an
    /// oblique unit axis `u` (`Dispatch::RevU`; zero for the others): the
    /// square in Rodrigues' `1 + k s + k² (1 − c)` made once, for forward
    /// kinematics on this model's own workspace (`forward_kinematics_pass`).
    pub(crate) axis_k2: Vec<Matrix3<T>>,
    /// Whether each body's inertia is exactly zero ([`crate::spatial::Inertia::is_zero`]
    /// of the model this workspace was made for): the simulation's bias pass
    /// leaves such a body's own force out.
    pub(crate) massless: Vec<bool>,
    /// Every body but the world is a lone free body on the world, its
    /// coordinates in body order ([`all_lone_free`] of the model
    /// this workspace was made for): the simulation's bias pass with the
    /// kinetic energy then runs as one pass over the bodies.
    pub(crate) lone_free: bool,
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
    /// C(q, v) computed ahead by the simulation's energy guard at the state
    /// (`step_bias_q`, `step_bias_v`) from the joint placements of forward
    /// kinematics there, for the next step's free velocity
    /// (`rnea::bias_at_placements_ahead`): the pass the step would run, so
    /// the same numbers, with the guard's kinetic energy read from its body
    /// velocities (one velocity pass at a state, not two).
    pub(crate) step_bias: DVector<T>,
    /// The configuration of `step_bias`.
    pub(crate) step_bias_q: DVector<T>,
    /// The velocity of `step_bias`.
    pub(crate) step_bias_v: DVector<T>,
    /// `step_bias` holds C at (`step_bias_q`, `step_bias_v`), not yet used.
    pub(crate) step_bias_ok: bool,
    /// A step's free velocity asked for C at placements since the guard last
    /// ran: the guard computes it ahead.
    pub(crate) step_bias_wanted: bool,
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
    /// ABA on lone free bodies (`dynamics::aba_lone`): each body's `Iᴬ = Î`
    /// factored, kept from call to call (a lone body's articulated inertia
    /// in its own frame is its rigid inertia, a constant), with the inertia
    /// it is the factor of (made again when that changes).
    pub(crate) aba_kept: Vec<KeptLdl6>,

    /// Every joint's world Jacobian, 6 × nv (`joint_jacobians`).
    pub jacobians: DMatrix<T>,

    // Derivatives (docs/theory.md §"Derivatives"). Results first.
    /// ∂τ/∂q (nv × nv, tangent space) from `rnea_derivatives` (`aba_derivatives`
    /// leaves it at a = q̈, on its low-rank route only each joint's own block).
    pub dtau_dq: DMatrix<T>,
    /// ∂τ/∂v (nv × nv) from `rnea_derivatives` (as `dtau_dq` after
    /// `aba_derivatives`).
    pub dtau_dv: DMatrix<T>,
    /// ∂q̈/∂q (nv × nv, tangent space) from `aba_derivatives`.
    pub dqdd_dq: DMatrix<T>,
    /// ∂q̈/∂v (nv × nv) from `aba_derivatives`.
    pub dqdd_dv: DMatrix<T>,
    /// H⁻¹ = ∂q̈/∂τ (nv × nv, whole and symmetric) from `aba_derivatives`.
    pub minv: DMatrix<T>,
    /// Derivatives: first column of each body's joint in the column space of the
    /// recursion (one column per joint velocity coordinate, mimic joints their own).
    pub deriv_col0: Vec<usize>,
    /// Derivatives: one past the last column of each body's subtree (bodies are
    /// in depth-first order, so a subtree's columns are contiguous).
    pub deriv_sub_end: Vec<usize>,
    /// Derivatives: each column's coordinate in v (a mimic joint's: its leader's).
    pub deriv_col_iv: Vec<usize>,
    /// Derivatives: whether the column space is v's own (no mimic joint): the
    /// recursion then writes the results directly.
    pub deriv_direct: bool,
    /// Derivatives: world velocity `⁰v̂ᵢ` of each body.
    pub deriv_ov: Vec<Motion<T>>,
    /// Derivatives: world acceleration `⁰âᵢ` of each body, gravity included.
    pub deriv_oa: Vec<Motion<T>>,
    /// Derivatives: composite world inertia of each body's subtree.
    pub deriv_oy: Vec<CompositeInertia<T>>,
    /// Derivatives: the composite variation `Ẏ = v×*Y − Y v× + (·)×*(Y v)` (world)
    /// of each subtree, by its parts: the symmetric 3x3 `S = ω×I_o − I_o ω× − h vᵀ
    /// − v hᵀ + 2 (v·h) 1` (docs/theory.md §"Derivatives").
    pub deriv_doy: Vec<Matrix3<T>>,
    /// Derivatives: the momentum `Y v = [hₙ; h_f]` of each subtree (world), the
    /// other parts of `Ẏ`.
    pub deriv_hm: Vec<Force<T>>,
    /// Derivatives: composite world force of each body's subtree.
    pub deriv_of: Vec<Force<T>>,
    /// Derivatives: per body, the subtree's external couples Σ t (world).
    pub deriv_ext_t: Vec<Vector3<T>>,
    /// Derivatives: per body, the subtree's external forces Σ f (world).
    pub deriv_ext_f: Vec<Vector3<T>>,
    /// Derivatives: per body, Σ p fᵀ of the subtree's external forces (world points p).
    pub deriv_ext_p: Vec<Matrix3<T>>,
    /// Derivatives: per body, the external wrenches as spatial forces at the world
    /// origin (what `rnea` and forward dynamics take).
    pub deriv_fext: Vec<Force<T>>,
    /// Derivatives, per column: the world motion subspace `J = ⁰X̂ᵢ S`.
    pub deriv_j: Vec<Motion<T>>,
    /// Derivatives, per column: ∂⁰v̂/∂q of the subtree (`⁰v̂_λ × J`).
    pub deriv_dvdq: Vec<Motion<T>>,
    /// Derivatives, per column: ∂⁰â/∂q of the subtree.
    pub deriv_dadq: Vec<Motion<T>>,
    /// Derivatives, per column: ∂⁰â/∂v of the subtree.
    pub deriv_dadv: Vec<Motion<T>>,
    /// Derivatives, per column: ∂F/∂q of the subtree force.
    pub deriv_dfdq: Vec<Force<T>>,
    /// Derivatives, per column: ∂F/∂v of the subtree force.
    pub deriv_dfdv: Vec<Force<T>>,
    /// Derivatives, per column: `Yᶜ J` (∂F/∂a).
    pub deriv_dfda: Vec<Force<T>>,
    /// Derivatives, per column: `(Ẏᶜ)ᵀ J`.
    pub deriv_ytj: Vec<Force<T>>,
    /// Derivatives, per column: the external-force term `[e; 0]` of the lower block.
    pub deriv_ext_e: Vec<Force<T>>,
    /// Derivatives, per column, by components (the sweep's loops over columns
    /// vectorise): J (rows 0–5), `Yᶜ J` (6–11), the angular part of `(Ẏᶜ)ᵀ J`
    /// (12–14) and of e (15–17); component k of column c at `k ncol + c`.
    pub deriv_cols: Vec<T>,
    /// Derivatives: whether the sweep forms ∂τ/∂x's entries by loops over rows
    /// that read the columns by components (`deriv_cols`: long patterns, ≥ 32
    /// rows a column on average) rather than column by column (the short loops
    /// of branched trees, where the loops' set-up outweighs them).
    pub deriv_by_cols: bool,
    /// Derivatives with mimic joints: ∂τ/∂q, ∂τ/∂v, ∂τ/∂a over the column space
    /// (then reduced by G); empty without mimic joints.
    pub deriv_full: [DMatrix<T>; 3],
    /// Derivatives: a scratch nv × nv matrix (`aba_derivatives`' transposes).
    pub deriv_scratch: DMatrix<T>,
    /// Derivatives: a scratch vector of size nv (`aba_derivatives`' q̈).
    pub deriv_tmp: DVector<T>,
    /// Derivatives, per velocity coordinate: one past the last coordinate of its
    /// subtree (the rows below it where ∂τ/∂x's column can be non-zero).
    pub deriv_dof_end: Vec<usize>,
    /// Derivatives: the ancestors of every velocity coordinate as runs `[lo, hi)`
    /// of consecutive coordinates, coordinate k's at
    /// `deriv_anc_runs[deriv_anc_run0[k]..deriv_anc_run0[k + 1]]` (the rows above
    /// it where ∂τ/∂x's column can be non-zero).
    pub deriv_anc_runs: Vec<(usize, usize)>,
    /// Derivatives: where each coordinate's runs start in `deriv_anc_runs` (nv + 1).
    pub deriv_anc_run0: Vec<usize>,

    // H⁻¹ by the world-frame articulated-body recursion (`aba_derivatives`,
    // docs/theory.md §"Derivatives").
    /// H⁻¹, per velocity coordinate: its world motion subspace column `J = ⁰X̂ᵢ S`.
    pub minv_j: Vec<Motion<T>>,
    /// H⁻¹, per velocity coordinate: `U D⁻¹` (world).
    pub minv_udinv: Vec<Force<T>>,
    /// H⁻¹, per velocity coordinate: `u = τ − Jᵀ pᴬ`.
    pub minv_uq: Vec<T>,
    /// H⁻¹: articulated inertia of each body (6x6, angular first, world); left
    /// holding a non-root body's Iᵃ = Iᴬ − U D⁻¹ Uᵀ (scratch, updated in place).
    pub minv_ia: Vec<Matrix6<T>>,
    /// H⁻¹: world velocity of each body.
    pub minv_ov: Vec<Motion<T>>,
    /// H⁻¹: velocity-product acceleration, then acceleration, of each body (world,
    /// gravity included).
    pub minv_agf: Vec<Motion<T>>,
    /// H⁻¹: articulated bias force of each body (world).
    pub minv_of: Vec<Force<T>>,
    /// H⁻¹, per column (leaves inwards): the force a unit τ of that coordinate
    /// passes to the current body's parent, by components (6 × nv: component k of
    /// column c at `k nv + c`).
    pub minv_fcol: Vec<T>,
    /// H⁻¹, per body and per column c from its first coordinate on (root
    /// outwards): the body's acceleration under a unit τ_c, by components
    /// (component k at `minv_acol_off[i] + k nv + c`). Only the children read a
    /// body's, so bodies share buffers of 6 nv: two per level of branching (an
    /// only child takes the other one of its parent's pair).
    pub minv_acol: Vec<T>,
    /// H⁻¹: where each body's buffer starts in `minv_acol`.
    pub minv_acol_off: Vec<usize>,
    /// Derivatives: whether `aba_derivatives` forms −H⁻¹ ∂τ/∂x from ∂τ/∂x's
    /// low-rank parts (long chains, docs/theory.md §"Derivatives", "The products")
    /// rather than by the tree-pattern product; chosen here by operation counts
    /// (either gives the same result; models with mimic joints use neither).
    pub deriv_low_rank: bool,
    /// Derivatives (low-rank products): per body, the subtree sums
    /// `Σ H⁻¹[:, r] αᵣᵀ` (nv × 12 by columns) in shared buffers.
    pub deriv_prod_s: Vec<T>,
    /// Derivatives (low-rank products): where each body's buffer starts in
    /// `deriv_prod_s`.
    pub deriv_prod_s_off: Vec<usize>,
}

impl<T: Scalar> Data<T> {
    /// The workspace for `model`, every entry zero (or the identity).
    pub fn new(model: &Model<T>) -> Self {
        let nb = model.nbodies;
        let nv = model.nv;
        let (col0, sub_end, ncol, direct) = derivative_columns(model);
        let mut col_iv = vec![0; ncol];
        for i in 1..nb {
            for c in 0..model.joints[i].nv() {
                col_iv[col0[i] + c] = model.joints[i].iv + c;
            }
        }
        let nfull = if direct { 0 } else { ncol };
        let (dof_end, anc_runs, anc_run0) = coordinate_runs(model, &sub_end, direct);
        // the column accelerations' buffers: an only child alternates with its
        // parent, the children of a branching body go one pair deeper
        let mut acol_off = vec![0; nb];
        let mut acol_len = 0;
        if direct {
            let mut nchild = vec![0usize; nb];
            for i in 1..nb {
                nchild[model.parent[i]] += 1;
            }
            let mut buf = vec![0usize; nb];
            for i in 1..nb {
                let p = model.parent[i];
                buf[i] = if p == 0 {
                    0
                } else if nchild[p] == 1 {
                    buf[p] ^ 1
                } else {
                    (buf[p] | 1) + 1
                };
                acol_off[i] = buf[i] * 6 * nv;
                acol_len = acol_len.max(acol_off[i] + 6 * nv);
            }
        }
        // the low-rank products: their count (47 nv² multiply-adds in axpy loops,
        // taken at half the tiled product's rate) against the tiled product's
        // (2 nv Σ_c rows of column c's pattern)
        let mut s_off = vec![0; nb];
        let mut s_len = 0;
        let mut low_rank = false;
        let mut by_cols = false;
        if direct && nv > 0 {
            let rows: usize = (0..nv)
                .map(|c| {
                    let anc: usize = anc_runs[anc_run0[c]..anc_run0[c + 1]]
                        .iter()
                        .map(|(lo, hi)| hi - lo)
                        .sum();
                    anc + dof_end[c] - c
                })
                .sum();
            low_rank = 94 * nv * nv < 2 * nv * rows;
            by_cols = rows >= 32 * nv;
        }
        if direct {
            let mut nchild = vec![0usize; nb];
            for i in 1..nb {
                nchild[model.parent[i]] += 1;
            }
            let mut slot = vec![0usize; nb];
            for i in 1..nb {
                let p = model.parent[i];
                slot[i] = if p == 0 || nchild[p] == 1 {
                    slot[p]
                } else {
                    slot[p] + 1
                };
                s_off[i] = slot[i] * 12 * nv;
                s_len = s_len.max(s_off[i] + 12 * nv);
            }
        }
        let dispatch: Vec<_> = model.joints[..nb]
            .iter()
            .map(super::joint::dispatch_of)
            .collect();
        Self {
            li_m_i: vec![Se3::identity(); nb],
            o_m_i: vec![Se3::identity(); nb],
            lone_free: all_lone_free(model, &dispatch),
            dispatch,
            axis_k2: model.joints[..nb]
                .iter()
                .map(|j| match super::joint::dispatch_of(j).0 {
                    super::joint::Dispatch::RevU(u) => {
                        let k = crate::spatial::skew(&u);
                        k * k
                    }
                    _ => Matrix3::zeros(),
                })
                .collect(),
            massless: model.inertias[..nb].iter().map(|i| i.is_zero()).collect(),
            o_m_f: vec![Se3::identity(); model.frames.len()],
            v: vec![Motion::zero(); nb],
            a: vec![Motion::zero(); nb],
            f: vec![Force::zero(); nb],
            tau: DVector::zeros(nv),
            bias: DVector::zeros(nv),
            step_bias: DVector::zeros(nv),
            step_bias_q: DVector::zeros(model.nq),
            step_bias_v: DVector::zeros(nv),
            step_bias_ok: false,
            step_bias_wanted: false,
            qdd: DVector::zeros(nv),
            h: lazy_zeros(nv, nv),
            chol: lazy_zeros(nv, nv),
            tmp_a: DVector::zeros(nv),
            crba_ic: vec![CompositeInertia::zero(); nb],
            crba_f: DMatrix::zeros(nv, 6),
            crba_fc: vec![Force::zero(); nv],
            aba_ia: vec![Matrix6::zeros(); nb],
            aba_u: vec![Vector6::zeros(); nb],
            aba_dinv: vec![T::zero(); nb],
            aba_uq: vec![T::zero(); nb],
            aba_c: vec![Motion::zero(); nb],
            aba_kept: vec![KeptLdl6::NONE; nb],
            jacobians: DMatrix::zeros(6, nv),
            dtau_dq: lazy_zeros(nv, nv),
            dtau_dv: lazy_zeros(nv, nv),
            dqdd_dq: lazy_zeros(nv, nv),
            dqdd_dv: lazy_zeros(nv, nv),
            minv: lazy_zeros(nv, nv),
            deriv_col0: col0,
            deriv_sub_end: sub_end,
            deriv_col_iv: col_iv,
            deriv_direct: direct,
            deriv_ov: vec![Motion::zero(); nb],
            deriv_oa: vec![Motion::zero(); nb],
            deriv_oy: vec![CompositeInertia::zero(); nb],
            deriv_doy: vec![Matrix3::zeros(); nb],
            deriv_hm: vec![Force::zero(); nb],
            deriv_of: vec![Force::zero(); nb],
            deriv_ext_t: vec![Vector3::zeros(); nb],
            deriv_ext_f: vec![Vector3::zeros(); nb],
            deriv_ext_p: vec![Matrix3::zeros(); nb],
            deriv_fext: vec![Force::zero(); nb],
            deriv_j: vec![Motion::zero(); ncol],
            deriv_dvdq: vec![Motion::zero(); ncol],
            deriv_dadq: vec![Motion::zero(); ncol],
            deriv_dadv: vec![Motion::zero(); ncol],
            deriv_dfdq: vec![Force::zero(); ncol],
            deriv_dfdv: vec![Force::zero(); ncol],
            deriv_dfda: vec![Force::zero(); ncol],
            deriv_ytj: vec![Force::zero(); ncol],
            deriv_ext_e: vec![Force::zero(); ncol],
            deriv_cols: vec![T::zero(); if by_cols { 18 * ncol } else { 0 }],
            deriv_by_cols: by_cols,
            deriv_full: std::array::from_fn(|_| lazy_zeros(nfull, nfull)),
            deriv_scratch: lazy_zeros(nv, nv),
            deriv_tmp: DVector::zeros(nv),
            deriv_dof_end: dof_end,
            deriv_anc_runs: anc_runs,
            deriv_anc_run0: anc_run0,
            minv_j: vec![Motion::zero(); nv],
            minv_udinv: vec![Force::zero(); nv],
            minv_uq: vec![T::zero(); nv],
            minv_ia: vec![Matrix6::zeros(); nb],
            minv_ov: vec![Motion::zero(); nb],
            minv_agf: vec![Motion::zero(); nb],
            minv_of: vec![Force::zero(); nb],
            minv_fcol: vec![T::zero(); 6 * nv],
            minv_acol: vec![T::zero(); acol_len],
            minv_acol_off: acol_off,
            deriv_low_rank: low_rank,
            deriv_prod_s: vec![T::zero(); s_len],
            deriv_prod_s_off: s_off,
        }
    }
}

/// An r × c zero matrix whose memory the system zeroes page by page when first
/// touched (`vec![0; n]` of a float asks the allocator for zeroed memory:
/// `calloc`, fresh pages for a large block), where `DMatrix::zeros` writes every
/// entry. A scene of a thousand models has an nv of thousands: an nv × nv
/// matrix of 300 MB that most steps touch only on H's tree pattern, or never
/// (the derivatives' results), then costs the pages used, not the whole.
pub(crate) fn lazy_zeros<T: Scalar>(r: usize, c: usize) -> DMatrix<T> {
    DMatrix::from_vec(r, c, vec![T::zero(); r * c])
}

/// Per velocity coordinate (a model without mimic joints): one past its subtree's
/// last coordinate, and its ancestors as runs `[lo, hi)` of consecutive
/// coordinates (flat, with each coordinate's start; nv + 1 starts). Empty with
/// mimic joints.
fn coordinate_runs<T: Scalar>(
    model: &Model<T>,
    sub_end: &[usize],
    direct: bool,
) -> (Vec<usize>, Vec<(usize, usize)>, Vec<usize>) {
    if !direct {
        return (Vec::new(), Vec::new(), Vec::new());
    }
    let nv = model.nv;
    let lambda = &model.dof_parent;
    let mut dof_end = vec![0; nv];
    for (j, &e) in model.joints.iter().zip(sub_end).skip(1) {
        for c in 0..j.nv() {
            dof_end[j.iv + c] = e;
        }
    }
    let mut runs = Vec::new();
    let mut run0 = Vec::with_capacity(nv + 1);
    for k in 0..nv {
        run0.push(runs.len());
        let mut j = lambda[k];
        while j != usize::MAX {
            let hi = j + 1;
            while j > 0 && lambda[j] == j - 1 {
                j -= 1;
            }
            runs.push((j, hi));
            j = lambda[j];
        }
    }
    run0.push(runs.len());
    (dof_end, runs, run0)
}

/// The derivatives' column space (docs/theory.md §"Derivatives"): each body's first
/// column (its joint's velocity coordinates counted in body order, a mimic joint
/// its own), one past its subtree's last column, the number of columns, and
/// whether the columns are v's own coordinates.
fn derivative_columns<T: Scalar>(model: &Model<T>) -> (Vec<usize>, Vec<usize>, usize, bool) {
    let nb = model.nbodies;
    let mut col0 = vec![0; nb];
    let mut sub_end = vec![0; nb];
    let mut n = 0;
    let mut direct = true;
    for i in 1..nb {
        col0[i] = n;
        direct &= model.joints[i].iv == n;
        n += model.joints[i].nv();
        sub_end[i] = n;
    }
    direct &= n == model.nv;
    for i in (1..nb).rev() {
        let p = model.parent[i];
        if p != 0 {
            sub_end[p] = sub_end[p].max(sub_end[i]);
        }
    }
    (col0, sub_end, n, direct)
}

/// Whether every body of `model` but the world hangs from the world by a
/// free joint (`dispatch`: each body's joint as [`Data`] keeps it) whose six
/// velocity coordinates are body i's `6 (i − 1) .. 6 i`, and nothing else
/// has one (nv = 6 (nb − 1)): the bias pass of `dynamics::rnea_lone` then
/// writes every entry of C once.
fn all_lone_free<T: Scalar>(
    model: &Model<T>,
    dispatch: &[(super::joint::Dispatch<T>, T, T)],
) -> bool {
    let nb = model.nbodies;
    nb >= 2
        && model.nv == 6 * (nb - 1)
        && (1..nb).all(|i| {
            model.parent.get(i) == Some(&0)
                && matches!(dispatch.get(i), Some((super::joint::Dispatch::Free, _, _)))
                && model.joints.get(i).is_some_and(|j| j.iv == 6 * (i - 1))
        })
}

/// A body's `Iᴬ = Î` (6 × 6, angular first, from its origin-form inertia)
/// factored as `L D Lᵀ` (`dynamics::linalg::spd6_factor`), kept for ABA on
/// lone free bodies.
#[derive(Clone, Copy, Debug)]
pub(crate) struct KeptLdl6 {
    /// The inertia (origin form) the factor is of, or none yet.
    pub(crate) of: Option<CompositeInertia<f64>>,
    /// L's strict lower triangle packed by rows and D⁻¹; `None`: that
    /// inertia is not positive definite (ABA's singular pivot).
    pub(crate) ldl: Option<([f64; 15], [f64; 6])>,
}

impl KeptLdl6 {
    /// Nothing factored yet.
    pub(crate) const NONE: Self = Self {
        of: None,
        ldl: None,
    };
}
