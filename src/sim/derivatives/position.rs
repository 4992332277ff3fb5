//! The position pass differentiated (docs/theory.md §"Loops and the position
//! pass in the step Jacobians"): the pseudo-velocity w = H̃⁻¹Jᵀμ of the rows
//! the pass works on (contact normals and joint limits, μ ≥ 0; loop rows, μ
//! free), with J w = b_pos on the rows it holds (loop rows; unilateral rows
//! with μ > 0) and δμ = 0 on the others. Linearised:
//!
//! ```text
//! H̃ δw = −∂(H w)/∂q δq + ∂(Jᵀμ)/∂q δq + Jᵀ δμ
//! J_A δw + (∂J_A/∂q δq) w = δb_pos,A
//! ```
//!
//! The row space of J_A fixes J_Aᵀδμ whatever solution δμ is taken (the
//! rows may be redundant: a planar four-bar closed by a 3-D point), so δw is
//! unique. Targets: a loop row's b_pos = clamp(−φ/h, ±cap) − ½hγ, so δb_pos =
//! −J δq / h (unclamped) − ½h (∂γ/∂q δq + ∂γ/∂v δv); a penetrating contact's
//! or limit's min(β(−φ − slop)/h, cap), δb_pos = −β J δq / h below the cap.

use super::analytic::solve_basic;
use super::second_order::loop_residual;
use crate::sim::solver::RowKind;
use crate::sim::Simulation;
use nalgebra::DMatrix;

/// What the position pass's derivative is built from (n = nv, m rows).
pub(super) struct PositionPass<'a> {
    /// The rows' Jacobian J (m × n).
    pub jac: &'a DMatrix<f64>,
    /// Y = H̃⁻¹Jᵀ (n × m).
    pub y: &'a DMatrix<f64>,
    /// W = J H̃⁻¹ Jᵀ (m × m).
    pub w: &'a DMatrix<f64>,
    /// H̃⁻¹ (n × n).
    pub minv: &'a DMatrix<f64>,
    /// ∂(H w)/∂q (n × n).
    pub h_w_q: &'a DMatrix<f64>,
    /// ∂(Jᵀμ)/∂q (n × n).
    pub gc_mu: &'a DMatrix<f64>,
    /// (∂J/∂q) w (m × n).
    pub jq_w: &'a DMatrix<f64>,
    /// The loop rows' ∂γ/∂q, ∂γ/∂v (m × n, zero on other rows).
    pub gq: &'a DMatrix<f64>,
    /// See `gq`.
    pub gv: &'a DMatrix<f64>,
    /// The active loop constraints and their first rows.
    pub loops: &'a [(usize, usize)],
    /// The step.
    pub h: f64,
}

impl Simulation {
    /// δw over the columns (δq, δv, δτ) (n × 3n), at the step's poses.
    pub(super) fn position_pass_jacobian(&self, p: &PositionPass<'_>) -> DMatrix<f64> {
        let n = self.model.nv;
        let h = p.h;
        let rows = self.cons.rows_view();
        let m = rows.n;
        // Z_w: δw at fixed μ (δq columns only)
        let mut zw = DMatrix::<f64>::zeros(n, 3 * n);
        let k = p.gc_mu - p.h_w_q;
        zw.columns_mut(0, n).copy_from(&(p.minv * k));
        // the rows the pass holds, and their targets' derivatives
        let mut held = Vec::new();
        let mut dbpos = DMatrix::<f64>::zeros(m, 3 * n);
        let beta = self.row_params.beta;
        let loop_cap = self
            .row_params
            .contact_push_cap
            .max(self.row_params.limit_push_cap);
        for r in 0..m {
            if rows.w[r] <= 1e-14 || rows.w[r].is_nan() {
                continue;
            }
            match rows.kind[r] {
                RowKind::Normal | RowKind::Unilateral if rows.mu[r] > 0.0 => {
                    let cap = if rows.kind[r] == RowKind::Normal {
                        self.row_params.contact_push_cap
                    } else {
                        self.row_params.limit_push_cap
                    };
                    held.push(r);
                    if rows.bpos[r] > 0.0 && rows.bpos[r] < cap {
                        for c in 0..n {
                            dbpos[(r, c)] = -beta * p.jac[(r, c)] / h;
                        }
                    }
                }
                RowKind::Bilateral => held.push(r),
                _ => {}
            }
        }
        for &(k, r0) in p.loops {
            let phi = loop_residual(self, k);
            // the step's rows: the world rows along the kept directions E
            let Some(l) = self.cons.loops.as_ref() else {
                continue;
            };
            let m = l.set.items[k].rows();
            let (e, kept) = l.row_basis(k);
            let phi_rows: Vec<f64> = (0..kept)
                .map(|t| (0..m).map(|i| e[t * m + i] * phi[i]).sum())
                .collect();
            for (t, phi_t) in phi_rows.iter().enumerate() {
                let r = r0 + t;
                let open = (phi_t / h).abs() < loop_cap;
                for c in 0..n {
                    let mut x = -0.5 * h * p.gq[(r, c)];
                    if open {
                        x -= p.jac[(r, c)] / h;
                    }
                    dbpos[(r, c)] = x;
                    dbpos[(r, n + c)] = -0.5 * h * p.gv[(r, c)];
                }
            }
        }
        if held.is_empty() {
            return zw;
        }
        // W_AA δμ_A = δb_pos − J_A Z_w − (∂J_A/∂q) w
        let a = held.len();
        let jz = p.jac * &zw;
        let mut mm = DMatrix::zeros(a, a);
        let mut rr = DMatrix::zeros(a, 3 * n);
        for (i, &r) in held.iter().enumerate() {
            for (j, &s) in held.iter().enumerate() {
                mm[(i, j)] = p.w[(r, s)];
            }
            for c in 0..3 * n {
                rr[(i, c)] = dbpos[(r, c)] - jz[(r, c)];
            }
            for c in 0..n {
                rr[(i, c)] -= p.jq_w[(r, c)];
            }
        }
        let dmu = solve_basic(mm, rr, 1e-12);
        for (i, &r) in held.iter().enumerate() {
            for c in 0..3 * n {
                let x = dmu[(i, c)];
                if x != 0.0 {
                    zw.column_mut(c).axpy(x, &p.y.column(r), 1.0);
                }
            }
        }
        zw
    }
}
