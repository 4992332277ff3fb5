//! Constrained forward dynamics (mechanisms.md §"Semantics"; docs/theory.md
//! §"Constrained dynamics"): q̈ and λ of
//!
//! ```text
//! H q̈ + C = τ + Σ Jᵀ w_ext + J_cᵀ λ,     J_c q̈ + γ_c = 0,
//! ```
//!
//! with the rows the classical accelerations of the constraints in world
//! coordinates (`point`: p̈₁ − p̈₂; `frame`: also ω̇₁ − ω̇₂; `joint`:
//! q̈₁ − ratio · q̈₂). By the range-space route: q̈₀ = H⁻¹(τ − C) and
//! Y = H⁻¹ J_cᵀ from H's tree-sparse factor (`ltdl.rs`), K = J_c Y,
//! λ = K⁺ (−γ_c − J_c q̈₀) (least norm when rows are redundant, `kkt.rs`),
//! q̈ = q̈₀ + Y λ.

pub(crate) use super::constraint_rows::{bias_rows, jacobian_rows, side_point};
pub use super::constraint_rows::{constraint_jacobian, constraint_violation};
use super::kkt::{add_rank1, mul_add, KktFactor};
use super::kkt_blocks::{self, MAX_SHARED};
use super::ltdl;
use super::{check_massless, check_sizes, forward_dynamics_crba, linalg, DynamicsError};
use crate::model::{ConstraintKind, Constraints, Data, DimensionError, Model};
use crate::spatial::ops::madd;
use crate::spatial::{Force, Motion};
use nalgebra::{DMatrix, DVector};

/// Why constrained dynamics has no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstraintDynamicsError {
    /// The unconstrained dynamics has none (singular H, sizes, names).
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// The rows J_c q̈ = −γ_c have no solution (names the constraints whose rows
    /// are left unsatisfied).
    #[error("the constraints {} are inconsistent: their rows J_c q̈ + γ_c = 0 have no solution in this state", .0.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", "))]
    Inconsistent(Vec<String>),
}

impl From<DimensionError> for ConstraintDynamicsError {
    fn from(e: DimensionError) -> Self {
        Self::Dynamics(e.into())
    }
}

/// The workspace and results of the constrained algorithms for one model and
/// one constraint set (m rows): sized once, no allocation per call.
#[derive(Clone, Debug)]
pub struct ConstraintData {
    /// Number of rows m.
    pub rows: usize,
    /// J_c (m × nv, columns as v).
    pub jc: DMatrix<f64>,
    /// γ_c = J̇_c v (m).
    pub gamma: DVector<f64>,
    /// λ (m), stacked in constraint order (point: force; frame: force then
    /// torque; joint: the generalized force on joint1), world coordinates.
    pub lambda: DVector<f64>,
    /// The constrained q̈ (nv).
    pub qdd: DVector<f64>,
    /// J_cᵀ λ (nv).
    pub generalized_force: DVector<f64>,
    /// ∂q̈/∂q (nv × nv, tangent space) from the derivatives.
    pub dqdd_dq: DMatrix<f64>,
    /// ∂q̈/∂v.
    pub dqdd_dv: DMatrix<f64>,
    /// ∂q̈/∂τ = H⁻¹ − Y K⁺ Yᵀ (= M_c).
    pub dqdd_dtau: DMatrix<f64>,
    /// Y = H⁻¹ J_cᵀ (nv × m; after [`constraint_dynamics`] on a model whose H
    /// is factorised tree-sparse (`super::dense_factor`), W = L⁻ᵀ J_cᵀ coordinate-major, W[k, r] at k m + r, in its
    /// storage; Ȳ = Y S after the derivatives, `KktFactor::right_half`).
    pub(crate) y: DMatrix<f64>,
    /// K = J_c Y (m × m).
    pub(crate) k: DMatrix<f64>,
    /// Scratch (nv × m): the derivatives' `right_half`.
    pub(crate) p: DMatrix<f64>,
    pub(crate) kkt: KktFactor,
    /// Scratch: m entries.
    pub(crate) r: DVector<f64>,
    /// Scratch: m entries.
    pub(crate) r2: DVector<f64>,
    /// Derivatives: ∂(J_c a + γ_c)/∂q at a = q̈, transposed (nv × m).
    pub(crate) aq: DMatrix<f64>,
    /// Derivatives: ∂(J_c a + γ_c)/∂v, transposed (nv × m).
    pub(crate) av: DMatrix<f64>,
    /// Derivatives: the world columns of one side's path (scratch).
    pub(crate) path: Vec<(usize, usize, Motion<f64>)>,
    /// Derivatives: per body, the world velocity-product acceleration.
    pub(crate) oa0: Vec<Motion<f64>>,
    /// Scratch (nv): D⁻¹ of H's tree-sparse factor.
    pub(crate) dinv: Vec<f64>,
    /// Scratch (nv): per coordinate, the span `lo..hi` of rows of J_c (and of
    /// W = L⁻ᵀ J_cᵀ) that can be non-zero in its column (`constrained_paths`).
    pub(crate) span: Vec<(usize, usize)>,
    /// Scratch: one side's path of bodies.
    pub(crate) bodies: Vec<usize>,
    /// The row blocks of K's block-diagonal part (`kkt_blocks`).
    pub(crate) blocks: Vec<(usize, usize)>,
    /// The spans `blocks` and `blocked` were found from.
    pub(crate) blocks_span: Vec<(usize, usize)>,
    /// Whether the rows have that structure (K solved from its blocks).
    pub(crate) blocked: bool,
    /// Scratch (`MAX_SHARED` × m): the shared coordinates' rows of W.
    pub(crate) brows: Vec<f64>,
    /// Scratch (`MAX_SHARED`): their pivots.
    pub(crate) bd: Vec<f64>,
    /// Scratch (m × `MAX_SHARED`): the blocks' factors.
    pub(crate) lf: Vec<f64>,
    /// Scratch (m): their diagonals' reciprocals.
    pub(crate) ld: Vec<f64>,
    /// Scratch (m × `MAX_SHARED`).
    pub(crate) z: Vec<f64>,
}

impl ConstraintData {
    /// The workspace for `model` and `constraints`.
    pub fn new(model: &Model, constraints: &Constraints) -> Self {
        let (m, nv) = (constraints.rows(), model.nv);
        Self {
            rows: m,
            jc: DMatrix::zeros(m, nv),
            gamma: DVector::zeros(m),
            lambda: DVector::zeros(m),
            qdd: DVector::zeros(nv),
            generalized_force: DVector::zeros(nv),
            dqdd_dq: DMatrix::zeros(nv, nv),
            dqdd_dv: DMatrix::zeros(nv, nv),
            dqdd_dtau: DMatrix::zeros(nv, nv),
            y: DMatrix::zeros(nv, m),
            k: DMatrix::zeros(m, m),
            p: DMatrix::zeros(nv, m),
            kkt: KktFactor::new(m),
            r: DVector::zeros(m),
            r2: DVector::zeros(m),
            aq: DMatrix::zeros(nv, m),
            av: DMatrix::zeros(nv, m),
            path: Vec::with_capacity(model.nv),
            oa0: vec![Motion::zero(); model.nbodies],
            dinv: vec![0.0; nv],
            span: vec![(0, 0); nv],
            bodies: Vec::with_capacity(model.nbodies),
            blocks: Vec::with_capacity(m),
            blocks_span: vec![(usize::MAX, usize::MAX); nv],
            blocked: false,
            brows: vec![0.0; MAX_SHARED * m],
            bd: vec![0.0; MAX_SHARED],
            lf: vec![0.0; m * MAX_SHARED],
            ld: vec![0.0; m],
            z: vec![0.0; m * MAX_SHARED],
        }
    }
}

/// The world poses `data.o_m_i` (from `data.li_m_i`, left by the passes that
/// leave world poses out) of the bodies on the constraints' paths to the root,
/// the only ones J_c and γ_c read (the other bodies' are left as they were),
/// and `span[k]`: the rows `lo..hi` of J_c that can be non-zero in column k,
/// from the constraints whose sides' paths (a `joint` constraint: its
/// coordinates' ancestors-or-self) hold coordinate k (empty, lo ≥ hi, when
/// none does). A coordinate's span covers its descendants', so the rows of
/// W = L⁻ᵀ J_cᵀ, which gather their descendants' in the elimination, keep to
/// the spans too (`ltdl::ltdl_rows`).
fn constrained_paths(
    model: &Model,
    data: &mut Data,
    c: &Constraints,
    span: &mut [(usize, usize)],
    bodies: &mut Vec<usize>,
) {
    let nv = model.nv;
    span[..nv].fill((usize::MAX, 0));
    fn mark(span: &mut [(usize, usize)], k: usize, r0: usize, r1: usize) {
        let s = &mut span[k];
        *s = (s.0.min(r0), s.1.max(r1));
    }
    let mut row = 0;
    for con in &c.items {
        let (r0, r1) = (row, row + con.rows());
        match &con.kind {
            ConstraintKind::Joint { v1, second, .. } => {
                for v in std::iter::once(*v1).chain(second.map(|(_, v2)| v2)) {
                    let mut k = v;
                    while k != usize::MAX {
                        mark(span, k, r0, r1);
                        k = model.dof_parent[k];
                    }
                }
            }
            _ => {
                for side in [&con.a, &con.b] {
                    bodies.clear();
                    let mut b = side.body;
                    while b != 0 {
                        bodies.push(b);
                        b = model.parent[b];
                    }
                    // root outwards: the same compositions as a whole pass
                    for &b in bodies.iter().rev() {
                        data.o_m_i[b] = data.o_m_i[model.parent[b]].compose(&data.li_m_i[b]);
                        let jt = &model.joints[b];
                        for k in jt.iv..jt.iv + jt.nv() {
                            mark(span, k, r0, r1);
                        }
                    }
                }
            }
        }
        row = r1;
    }
    // every ancestor's span covers its descendants' (λ(k) < k)
    for k in (0..nv).rev() {
        let p = model.dof_parent[k];
        if p != usize::MAX {
            let (lo, hi) = span[k];
            mark(span, p, lo, hi);
        }
    }
}

/// Sizes and the workspace's rows.
pub(crate) fn check_workspace(
    model: &Model,
    cd: &ConstraintData,
    c: &Constraints,
) -> Result<(), DimensionError> {
    DimensionError::check("constraint rows", cd.rows, c.rows())?;
    DimensionError::check("constraint workspace columns", model.nv, cd.jc.ncols())
}

/// The constrained forward dynamics (mechanisms.md §"Semantics"): `cd.qdd` = q̈,
/// `cd.lambda` = λ (least norm with redundant rows), `cd.generalized_force` =
/// J_cᵀ λ, `cd.jc`, `cd.gamma`; `fext` as [`super::forward_dynamics`] takes it
/// (per body, world, at the origin). Inconsistent rows are
/// [`ConstraintDynamicsError::Inconsistent`]. No allocation.
#[allow(clippy::too_many_arguments)]
pub fn constraint_dynamics<'c>(
    model: &Model,
    data: &mut Data,
    cd: &'c mut ConstraintData,
    constraints: &Constraints,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
) -> Result<&'c DVector<f64>, ConstraintDynamicsError> {
    constraint_dynamics_with(model, data, cd, constraints, q, v, tau, fext, false)
}

/// [`constraint_dynamics`]; `need_factor`: leave K's factor in `cd.kkt` (the
/// derivatives read it), else K may be solved from its blocks
/// (`kkt_blocks`) without a factor of its own.
#[allow(clippy::too_many_arguments)]
pub(crate) fn constraint_dynamics_with<'c>(
    model: &Model,
    data: &mut Data,
    cd: &'c mut ConstraintData,
    constraints: &Constraints,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
    fext: Option<&[Force<f64>]>,
    need_factor: bool,
) -> Result<&'c DVector<f64>, ConstraintDynamicsError> {
    check_sizes(model, q, &[("v", v), ("tau", tau)], fext)?;
    check_massless(model)?;
    check_workspace(model, cd, constraints)?;
    // C (with body velocities and velocity-product accelerations), H's factor;
    // the dense route also q̈₀, the tree route leaves τ − C in data.qdd (its
    // solve shares the elimination of J_cᵀ below)
    let dense = super::dense_factor(model);
    let mut placed = false;
    if dense {
        forward_dynamics_crba(model, data, q, v, tau, fext)?;
    } else {
        // H's factor comes below, fused with the elimination of J_cᵀ (H's
        // pattern written into the factor's storage by the CRBA where it can)
        placed = super::bias_and_crba_factor(model, data, q, v, fext);
        data.qdd.copy_from(tau);
        data.qdd -= &data.bias;
    }
    constrained_paths(model, data, constraints, &mut cd.span, &mut cd.bodies);
    jacobian_rows(model, data, constraints, &mut cd.jc);
    let g = model.gravity;
    let d: &Data = data;
    bias_rows(
        d,
        constraints,
        |b| d.o_m_i[b].act_motion(&d.v[b]),
        |b| {
            // the pass's accelerations carry the world's −g: removed
            let mut a = d.o_m_i[b].act_motion(&d.a[b]);
            a.lin += g;
            a
        },
        &mut cd.gamma,
    );
    if dense {
        cd.qdd.copy_from(&data.qdd);
        // Y = H⁻¹ J_cᵀ (dense Cholesky), every row at once: J_c's columns are
        // the rows of J_cᵀ, m contiguous entries each
        let (n, m) = (model.nv, cd.rows);
        let x = cd.p.as_mut_slice();
        x.copy_from_slice(cd.jc.as_slice());
        linalg::cholesky_solve_rows(&data.chol, m, x);
        let y = cd.y.as_mut_slice();
        for i in 0..n {
            for r in 0..m {
                y[i + r * n] = x[i * m + r];
            }
        }
        return solve_rows(cd, constraints).map(|_| &cd.qdd);
    }
    // H = Lᵀ D L (tree-sparse): W = L⁻ᵀ J_cᵀ keeps each row's support on its
    // path to the root; K = Wᵀ D⁻¹ W; q̈ = L⁻¹ D⁻¹ (w₀ + W λ) with
    // w₀ = L⁻ᵀ (τ − C), eliminated with W, and J_c q̈₀ = Wᵀ D⁻¹ w₀ formed with K
    // (docs/theory.md §"Constrained dynamics", "Solving"). W is kept
    // coordinate-major (W[k, r] at k m + r, J_c's own column-major storage):
    // every elimination step is one m-wide axpy over all the rows at once. The
    // elimination runs inside H's factorisation (`ltdl_rows`: one walk of the
    // tree), and K gathers each coordinate's term as its row becomes final.
    let (n, m) = (model.nv, cd.rows);
    let lam = &model.dof_parent;
    let direct = data.deriv_direct;
    // rows in disjoint blocks besides a few shared coordinates (a free base's
    // six): those coordinates' rows are kept aside (B, D_B) and K's
    // block-diagonal part alone is formed (`kkt_blocks`)
    let blocked = !need_factor && kkt_blocks::blocked(cd, n);
    let w = &mut cd.y.as_mut_slice()[..n * m];
    w.copy_from_slice(&cd.jc.as_slice()[..n * m]);
    // K = Wᵀ D⁻¹ W = Σₖ D⁻¹ₖ W[k, :]ᵀ W[k, :]: by rank-1 updates of contiguous
    // columns (K[s, r] at s + r m), the upper triangle then mirrored; and
    // −J_c q̈₀ = −Wᵀ D⁻¹ w₀ into cd.r
    let k = &mut cd.k.as_mut_slice()[..m * m];
    k.fill(0.0);
    let jq0 = cd.r.as_mut_slice();
    jq0.fill(0.0);
    let Data { h, chol, qdd, .. } = &mut *data;
    let dv = &mut cd.dinv[..n];
    let (brows, bd) = (&mut cd.brows, &mut cd.bd);
    let mut g = 0;
    ltdl::ltdl_rows(
        h,
        lam,
        chol,
        m,
        w,
        qdd.as_mut_slice(),
        &cd.span,
        placed,
        |c, d, lo, xk, bc| {
            let dinv = 1.0 / d;
            dv[c] = dinv;
            let s0 = bc * dinv;
            // xk: row c of W on its nonzero span lo..lo + len (zero elsewhere)
            for (r, &xr) in (lo..).zip(xk) {
                if xr != 0.0 {
                    jq0[r] = madd(-xr, s0, jq0[r]);
                }
            }
            if blocked && lo == 0 && xk.len() == m {
                // a shared coordinate: its row and pivot kept aside
                brows[g * m..(g + 1) * m].copy_from_slice(xk);
                bd[g] = d;
                g += 1;
            } else {
                add_rank1(k, m, lo, xk, dinv);
            }
        },
    )
    .map_err(DynamicsError::Singular)?;
    // λ = K⁻¹ (−γ_c − J_c q̈₀) from K's blocks, where they are well inside
    // full rank (then K is: consistent rows)
    let solved = blocked && kkt_blocks::solve_or_form(cd, g);
    if !solved {
        let k = &mut cd.k.as_mut_slice()[..m * m];
        for r in 0..m {
            for s2 in 0..r {
                k[r + s2 * m] = k[s2 + r * m];
            }
        }
        solve_lambda_r(cd, constraints)?;
    }
    let (runs, run0) = (&data.deriv_anc_runs, &data.deriv_anc_run0);
    let u = data.chol.as_slice();
    // t = D⁻¹ (w₀ + W λ), then q̈ = L⁻¹ t (root outwards)
    let w = &cd.y.as_slice()[..n * m];
    let lambda = cd.lambda.as_slice();
    let b = data.qdd.as_slice();
    let t = cd.qdd.as_mut_slice();
    let dv = &cd.dinv[..n];
    let span = &cd.span[..n];
    for c in 0..n {
        // row c of W is zero outside its span
        let (lo, hi) = span[c];
        let mut acc = b[c];
        if lo < hi {
            for (&x, &l) in w[c * m + lo..c * m + hi].iter().zip(&lambda[lo..hi]) {
                acc = madd(x, l, acc);
            }
        }
        t[c] = acc * dv[c];
    }
    for i in 0..n {
        let mut s1 = t[i];
        if direct {
            let ui = &u[i * n..i * n + i];
            for &(lo, hi) in &runs[run0[i]..run0[i + 1]] {
                for (&l, &x) in ui[lo..hi].iter().zip(&t[lo..hi]) {
                    s1 = madd(-l, x, s1);
                }
            }
        } else {
            let mut j = lam[i];
            while j != usize::MAX {
                s1 -= u[j + i * n] * t[j];
                j = lam[j];
            }
        }
        t[i] = s1;
    }
    data.qdd.copy_from(&cd.qdd);
    // J_cᵀ λ: column c of J_c is zero outside its span
    let g = cd.generalized_force.as_mut_slice();
    let l = cd.lambda.as_slice();
    for (c, gc) in g.iter_mut().enumerate() {
        let (lo, hi) = cd.span[c];
        let mut s = 0.0;
        if lo < hi {
            for (&x, &y) in cd.jc.as_slice()[c * m + lo..c * m + hi]
                .iter()
                .zip(&l[lo..hi])
            {
                s = madd(x, y, s);
            }
        }
        *gc = s;
    }
    Ok(&cd.qdd)
}

/// With `cd.qdd` = q̈₀, `cd.jc`, `cd.gamma`, `cd.y` set: K, its factor, λ, the
/// consistency test, q̈ = q̈₀ + Y λ and J_cᵀ λ.
pub(crate) fn solve_rows(
    cd: &mut ConstraintData,
    constraints: &Constraints,
) -> Result<(), ConstraintDynamicsError> {
    mul_add(&mut cd.k, 1.0, &cd.jc, &cd.y, 0.0);
    solve_lambda(cd, constraints)?;
    cd.qdd.gemv(1.0, &cd.y, &cd.lambda, 1.0);
    generalized_force(cd);
    Ok(())
}

/// `cd.generalized_force` = J_cᵀ λ: per coordinate one dot of J_c's column
/// (m contiguous entries) with λ.
fn generalized_force(cd: &mut ConstraintData) {
    let m = cd.rows;
    let g = cd.generalized_force.as_mut_slice();
    if m == 0 {
        g.fill(0.0);
        return;
    }
    let l = cd.lambda.as_slice();
    for (gc, col) in g.iter_mut().zip(cd.jc.as_slice().chunks_exact(m)) {
        let mut s = 0.0;
        for (&x, &y) in col.iter().zip(l) {
            s = madd(x, y, s);
        }
        *gc = s;
    }
}

/// With `cd.k` = K, `cd.qdd` = q̈₀, `cd.jc`, `cd.gamma` set: K's factor, λ = K⁺ r
/// with r = −γ_c − J_c q̈₀, and the consistency test (r in K's range).
fn solve_lambda(
    cd: &mut ConstraintData,
    constraints: &Constraints,
) -> Result<(), ConstraintDynamicsError> {
    cd.r.gemv(-1.0, &cd.jc, &cd.qdd, 0.0);
    solve_lambda_r(cd, constraints)
}

/// [`solve_lambda`] with `cd.r` = −J_c q̈₀ given (`cd.qdd` not read).
fn solve_lambda_r(
    cd: &mut ConstraintData,
    constraints: &Constraints,
) -> Result<(), ConstraintDynamicsError> {
    let m = cd.rows;
    cd.kkt.factor(&cd.k);
    // r = −γ − J_c q̈₀
    let scale = cd.r.amax() + cd.gamma.amax();
    cd.r -= &cd.gamma;
    cd.lambda.copy_from(&cd.r);
    cd.kkt.solve(cd.lambda.as_mut_slice());
    cd.kkt.out_of_range(cd.r.as_slice(), cd.r2.as_mut_slice());
    let tol = 1e-7 * scale.max(f64::MIN_POSITIVE);
    if m > 0 && cd.r2.amax() > tol {
        let mut names = Vec::new();
        let mut row = 0;
        for con in &constraints.items {
            if (row..row + con.rows()).any(|i| cd.r2[i].abs() > tol) {
                names.push(con.name.clone());
            }
            row += con.rows();
        }
        return Err(ConstraintDynamicsError::Inconsistent(names));
    }
    Ok(())
}
