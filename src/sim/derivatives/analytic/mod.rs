//! The analytic transition Jacobians of the time-stepping step
//! (docs/theory.md §"Transition Jacobians"), at the step's own solution.
//!
//! The step is taken once, by the step's own code; its rows, impulses λ,
//! servo saturation and factor of H̃ are then differentiated:
//! - the velocity equation H̃ a = u − C − D v + e + Jᵀλ/h (a = (v⁺ − v)/h
//!   less the free base's frame rate) gives
//!   H̃ δa = −K_q δq − K_v δv + U δτ + Jᵀδλ/h with
//!   K_q = ∂ID/∂q − ∂(Jᵀλ)/∂q / h + Kp, K_v = ∂ID/∂v + D + Kd + h Kp
//!   (ID at (q, v, a); servo terms on the joints whose servo is not saturated);
//! - the rows' velocities u = J(q) v⁺ vary as δu = J δv⁺ + (∂J/∂q δq) v⁺, and
//!   the solve's active set fixes one linear equation a row: a separating
//!   contact (and a joint-friction row at its bound) keeps δλ = 0; a sticking
//!   contact, a pressing normal and an engaged limit keep δu = δb (b = −φ/h
//!   while the gap φ is open); a sliding pair keeps λₜ = −μ λₙ ûₜ, linearised;
//! - δv⁺ = δv + h δa + h ∂(ω × v_lin)/∂v δv, then the configuration update
//!   q⁺ = q ⊕ h v⁺ and the free base's velocity rotation, differentiated in
//!   the tangent space (right Jacobian of SO(3)).
//!
//! Redundant rows (more than the contact or loop can fix) leave λ non-unique
//! but v⁺ unique, and v⁺ is what is differentiated (docs/theory.md §"Step
//! Jacobians with redundant rows"); where sliding rows leave even v⁺ to the
//! solve's pick, `None` (central differences). Loop rows are equality rows;
//! the position pass's w is differentiated in `position.rs` (§"Loops and the
//! position pass in the step Jacobians"). Contact points are material points
//! of their link (hull and box vertices), a sphere's and a capsule's
//! lowest point the point below its centre.

mod rows;

pub(super) use rows::solve_basic;
use rows::{
    cq_row_dot, dot_rows, equality_row, lin, omega, set, shape, spin_sliding, velocity_determined,
    z0_product,
};

use super::position::PositionPass;
use super::second_order::{add_second_order, loop_gamma_derivatives, loop_rows};
use super::smooth::Tableau;
use super::TransitionJacobians;
use crate::contact::ContactPoint;
use crate::dynamics::linalg::{by_size, cholesky_fast, cholesky_solve_rows};
use crate::dynamics::{rnea_derivatives, DynamicsError};
use crate::sim::integrators::dop853_tableau::{A, B, N_STAGES};
use crate::sim::integrators::explicit_limit;
use crate::sim::solver::RowKind;
use crate::sim::{Integrator, SimError, Simulation};
use crate::spatial::skew;
use nalgebra::{DMatrix, DVector, Vector3};
use std::ops::AddAssign;

/// The analytic route's scratch vectors and matrices, kept in the derivative
/// workspace and resized only when the model's size changes: every entry is
/// written before it is read in each call (nothing is carried between calls).
pub(in crate::sim) struct Scratch {
    q0: DVector<f64>,
    v0: DVector<f64>,
    q1: DVector<f64>,
    v1: DVector<f64>,
    vplus: DVector<f64>,
    vtot: DVector<f64>,
    acc: DVector<f64>,
    col: DVector<f64>,
    points: Vec<ContactPoint>,
    u_free: Vec<f64>,
    kq_diag: Vec<f64>,
    kv_diag: Vec<f64>,
    minv: DMatrix<f64>,
    l: DMatrix<f64>,
    kk: DMatrix<f64>,
    z0: DMatrix<f64>,
}

impl Default for Scratch {
    fn default() -> Self {
        let (v, m) = (DVector::zeros(0), DMatrix::zeros(0, 0));
        Self {
            q0: v.clone(),
            v0: v.clone(),
            q1: v.clone(),
            v1: v.clone(),
            vplus: v.clone(),
            vtot: v.clone(),
            acc: v.clone(),
            col: v,
            points: Vec::new(),
            u_free: Vec::new(),
            kq_diag: Vec::new(),
            kv_diag: Vec::new(),
            minv: m.clone(),
            l: m.clone(),
            kk: m.clone(),
            z0: m,
        }
    }
}

impl Simulation {
    /// A and B through the step's own equations, from the fresh state (set by
    /// the caller) with joint torques `tau`: the steps up to `dt` (one for a
    /// fixed-step integrator), each differentiated by its own scheme, composed.
    /// `None` where the analytic route does not reach (docs/theory.md
    /// §"Transition Jacobians": several free joints, or a contact between two
    /// bodies in the step): the caller takes central differences there.
    pub(in crate::sim) fn analytic_jacobians(
        &mut self,
        tau: &DVector<f64>,
    ) -> Result<Option<TransitionJacobians>, SimError> {
        let f = &self.model.free_joints;
        // joints of several degrees of freedom inside the tree: central differences
        if f.len() > 1
            || f.first().is_some_and(|f| f.iv != 0 || f.iq != 0)
            || !self.model.all_dofs_scalar()
        {
            return Ok(None);
        }
        self.set_joint_torques(tau);
        let mut sc = std::mem::take(&mut self.deriv.scratch);
        let r = self.steps_jacobian(tau, &mut sc);
        self.deriv.scratch = sc;
        r
    }

    /// [`Simulation::analytic_jacobians`]' steps, composed.
    fn steps_jacobian(
        &mut self,
        tau: &DVector<f64>,
        sc: &mut Scratch,
    ) -> Result<Option<TransitionJacobians>, SimError> {
        let dt = self.dt;
        let mut out: Option<TransitionJacobians> = None;
        while self.t < dt {
            let Some(j) = self.substep_jacobian(dt, tau, sc)? else {
                return Ok(None);
            };
            out = Some(match out {
                None => j,
                // x'' = Aₛ x' + Bₛ τ after x' = A x + B τ
                Some(p) => TransitionJacobians {
                    b: &j.a * p.b + j.b,
                    a: j.a * p.a,
                },
            });
        }
        Ok(out)
    }

    /// One step toward `t_end`, taken, and its Jacobians [δq'; δv'] over the
    /// columns (δq, δv) and δτ by the scheme it took.
    fn substep_jacobian(
        &mut self,
        t_end: f64,
        tau: &DVector<f64>,
        sc: &mut Scratch,
    ) -> Result<Option<TransitionJacobians>, SimError> {
        set(&mut sc.q0, &self.q);
        set(&mut sc.v0, &self.v);
        sc.points.clone_from(&self.points);
        // the step's scheme, as step_until chooses it
        let h_fixed = crate::sim::land(self.dt, t_end - self.t);
        let counts = self.assemble_rows(h_fixed);
        if self.points.iter().any(|p| p.other != 0) {
            return Ok(None);
        }
        let mut implicit = self.integrator == Integrator::SemiImplicitEuler || counts.touching();
        if !implicit && (self.has_damping || self.servo.active) {
            implicit = self.damping_rate()? * h_fixed > explicit_limit(self.integrator);
        }
        let h = self.step_until(t_end)?;
        if !implicit {
            let q1 = self.q.clone();
            let rk4_a: [&[f64]; 4] = [&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]];
            let rk4_b = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];
            let a_all: &'static [[f64; N_STAGES]; N_STAGES] = &A;
            let dop_a: Vec<&[f64]> = (0..N_STAGES).map(|s| &a_all[s][..s]).collect();
            let tab = match self.integrator {
                Integrator::Rk4 => Tableau {
                    a: &rk4_a,
                    b: &rk4_b,
                },
                _ => Tableau { a: &dop_a, b: &B },
            };
            let j = self.smooth_step_jacobian(&sc.q0, &sc.v0, &q1, tau, h, &tab)?;
            let n = self.model.nv;
            return Ok(Some(TransitionJacobians {
                a: j.columns(0, 2 * n).into_owned(),
                b: j.columns(2 * n, n).into_owned(),
            }));
        }
        self.implicit_step_jacobian(sc, counts, h, tau)
    }

    /// The Jacobian of the time-stepping step just taken from (`sc.q0`,
    /// `sc.v0`) with the contact points `sc.points` and rows `counts`, of
    /// length `h`.
    fn implicit_step_jacobian(
        &mut self,
        sc: &mut Scratch,
        counts: crate::sim::constraints::RowCounts,
        h: f64,
        tau: &DVector<f64>,
    ) -> Result<Option<TransitionJacobians>, SimError> {
        let n = self.model.nv;
        let rows_used = self.cons.rows_len() > 0 && counts.total() > 0;
        // v⁺ in the start frame (before the base velocity's rotation), w
        set(&mut sc.vplus, &self.mass.vfree);
        let mut push: Option<DVector<f64>> = None;
        if rows_used {
            sc.vplus += self.cons.impulse_velocity();
        }
        set(&mut sc.vtot, &sc.vplus);
        if rows_used && let Some(w) = self.cons.push_velocity() {
            sc.vtot += w;
            push = Some(w.clone());
        }
        let (q0, v0, points) = (&sc.q0, &sc.v0, &sc.points[..]);
        let (vplus, vtot) = (&sc.vplus, &sc.vtot);
        // the loop constraints' rows (after every other row)
        let loops = if rows_used {
            match loop_rows(self, self.cons.rows_view()) {
                Some(l) => l,
                None => return Ok(None),
            }
        } else {
            Vec::new()
        };
        let m = if rows_used {
            self.cons.rows_view().n
        } else {
            0
        };
        // back at the start: poses and H̃ (the step's saturation set); the
        // step's end state is put back at the end
        set(&mut sc.q1, &self.q);
        set(&mut sc.v1, &self.v);
        self.q.copy_from(q0);
        self.v.copy_from(v0);
        let floating = self.model.floating_base;
        let vo = self.model.joint_v_offset();
        // a = (v⁺ − v)/h − frame rate
        if sc.acc.len() != n {
            sc.acc = DVector::zeros(n);
        }
        let acc = &mut sc.acc;
        for i in 0..n {
            acc[i] = (vplus[i] - v0[i]) / h;
        }
        if floating {
            let fr = omega(v0).cross(&lin(v0));
            for i in 0..3 {
                acc[i] -= fr[i];
            }
        }
        let acc = &sc.acc;
        // ∂(H w)/∂q = ∂ID/∂q (q, v, a + w) − ∂ID/∂q (q, v, a) (ID is affine in a)
        let mut hw_q = None;
        if let Some(w) = push.as_ref() {
            rnea_derivatives(&self.model, &mut self.data, q0, v0, &(acc + w), None)?;
            hw_q = Some(self.data.dtau_dq.clone());
        }
        // the loop rows' ∂γ/∂q, ∂γ/∂v from a pass at (q, v, 0)
        let (mut gq, mut gv) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
        if !loops.is_empty() && push.is_some() {
            rnea_derivatives(
                &self.model,
                &mut self.data,
                q0,
                v0,
                &DVector::zeros(n),
                None,
            )?;
            loop_gamma_derivatives(self, &loops, &mut gq, &mut gv);
        }
        // ∂ID/∂q, ∂ID/∂v at (q, v, a) in data.dtau_dq, dtau_dv, ∂ID/∂a = H in
        // data.h, the poses at q
        rnea_derivatives(&self.model, &mut self.data, q0, v0, acc, None)?;
        if let Some(x) = hw_q.as_mut() {
            *x -= &self.data.dtau_dq;
        }
        self.fk_valid = true;
        // a dense factor (a short chain): H̃⁻¹ below from a Cholesky factor of
        // H̃ solved against all n unit columns at once, the step's factor
        // left alone (nothing after this reads it: the next step forms its own)
        let dense = !self.model.has_mimic && !self.mass.f.is_tree();
        if self.model.has_mimic {
            self.factor_mass(h)?;
        } else {
            // H̃ = H + A + hD + h Kd + h² Kp (the step's saturation set), as
            // factor_mass adds it to its H
            for k in 0..n {
                self.data.h[(k, k)] +=
                    self.armature[k] + h * self.damping[k] + self.servo.diag(k, h);
            }
            if dense {
                shape(&mut sc.l, n, n);
                cholesky_fast(&self.data.h, &mut sc.l)
                    .map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)))?;
            } else {
                self.mass
                    .f
                    .factor(&self.data.h)
                    .map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)))?;
            }
        }
        // the diagonal terms of K_q (Kp) and K_v (D + Kd + h Kp), the effort clamp's
        let s = &self.servo;
        let (u_free, kq_diag, kv_diag) = (&mut sc.u_free, &mut sc.kq_diag, &mut sc.kv_diag);
        u_free.clear();
        u_free.resize(n, 0.0);
        kq_diag.clear();
        kq_diag.resize(n, 0.0);
        kv_diag.clear();
        kv_diag.extend_from_slice(self.damping.as_slice());
        for k in 0..n {
            if k >= vo && s.saturated[k] == 0 {
                u_free[k] = 1.0;
                if s.active {
                    kq_diag[k] = s.kp[k];
                    kv_diag[k] += s.kd[k] + h * s.kp[k];
                }
            }
        }
        if !self.servo.active {
            // the plain clamp: a joint whose τ_ff passes its effort is held there
            for k in vo..n {
                if tau[k].abs() > self.effort[k] {
                    u_free[k] = 0.0;
                }
            }
        }
        // the rows: Jacobian, kinds, impulses; their second-order terms
        let rows = self.cons.rows_view();
        let mut jac = DMatrix::<f64>::zeros(m, n);
        for r in 0..m {
            for (c, x) in rows.jrow(r) {
                jac[(r, c)] = x;
            }
        }
        let mut jq = DMatrix::<f64>::zeros(m, n);
        // (no rows: no second-order terms, nothing allocated)
        let mut gc = DMatrix::<f64>::zeros(if m > 0 { n } else { 0 }, if m > 0 { n } else { 0 });
        if m > 0 {
            add_second_order(self, points, &loops, &rows.lambda, vplus, &mut gc, &mut jq);
        }
        // H̃⁻¹ (n solves), Y = H̃⁻¹Jᵀ, W = J Y
        shape(&mut sc.minv, n, n);
        if sc.col.len() != n {
            sc.col = DVector::zeros(n);
        }
        let (minv, col) = (&mut sc.minv, &mut sc.col);
        if dense {
            // the rows of the solution against 1 are H̃⁻¹'s (symmetric)
            minv.as_mut_slice().fill(0.0);
            minv.fill_diagonal(1.0);
            cholesky_solve_rows(&sc.l, n, minv.as_mut_slice());
        } else {
            for c in 0..n {
                col.fill(0.0);
                col[c] = 1.0;
                self.mass.f.solve(col);
                minv.column_mut(c).copy_from(col);
            }
        }
        let minv = &sc.minv;
        let y = DMatrix::from_fn(n, m, |i, r| dot_rows(minv, i, &jac, r));
        let w = DMatrix::from_fn(m, m, |a, b| (0..n).map(|k| jac[(a, k)] * y[(k, b)]).sum());
        // Z0: δv⁺ without the impulses' variation, columns (δq, δv, δτ):
        // H̃⁻¹ [∂(Jᵀλ)/∂q − h K_q, −h K_v, h U] + [0, 1, 0] with K_q = ∂ID/∂q + Kp,
        // K_v = ∂ID/∂v + D + Kd + h Kp
        shape(&mut sc.kk, n, 2 * n);
        let kk = &mut sc.kk;
        kk.columns_mut(0, n).copy_from(&self.data.dtau_dq);
        kk.columns_mut(n, n).copy_from(&self.data.dtau_dv);
        for k in 0..n {
            kk[(k, k)] += kq_diag[k];
            kk[(k, n + k)] += kv_diag[k];
        }
        *kk *= -h;
        if m > 0 {
            kk.columns_mut(0, n).add_assign(&gc);
        }
        shape(&mut sc.z0, n, 3 * n);
        sc.z0.as_mut_slice().fill(0.0);
        let z0 = &mut sc.z0;
        {
            let (zs, ms, ks) = (z0.as_mut_slice(), minv.as_slice(), kk.as_slice());
            by_size!(n, N => z0_product::<N>(zs, ms, ks, n));
        }
        for k in 0..n {
            z0[(k, n + k)] += 1.0;
            if u_free[k] != 0.0 {
                z0.column_mut(2 * n + k).axpy(h, &minv.column(k), 0.0);
            }
        }
        if floating {
            // h ∂(ω × l)/∂v = h ([ω]×, −[l]×) on the linear rows
            let (om, l) = (skew(&omega(v0)) * h, skew(&lin(v0)) * (-h));
            for i in 0..3 {
                for j in 0..3 {
                    z0[(i, n + j)] += om[(i, j)];
                    z0[(i, n + 3 + j)] += l[(i, j)];
                }
            }
        }
        // the active set's equations M δλ = R
        if m > 0 {
            let mut cq = &jac * &*z0;
            for r in 0..m {
                for c in 0..n {
                    cq[(r, c)] += jq[(r, c)];
                }
            }
            let mut mm = DMatrix::zeros(m, m);
            let mut rr = DMatrix::zeros(m, 3 * n);
            let mut r = 0;
            let mut any_sliding = false;
            while r < m {
                match rows.kind[r] {
                    RowKind::Normal => {
                        let (ln, l1, l2) = (rows.lambda[r], rows.lambda[r + 1], rows.lambda[r + 2]);
                        let mu = match rows.kind[r + 1] {
                            RowKind::Tangent { mu, .. } => mu,
                            _ => 0.0,
                        };
                        if ln <= 0.0 {
                            // separating: δλ = 0 on all three
                            for k in r..r + 3 {
                                mm[(k, k)] = 1.0;
                            }
                        } else {
                            let ut = Vector3::new(
                                cq_row_dot(&jac, r + 1, vplus),
                                cq_row_dot(&jac, r + 2, vplus),
                                0.0,
                            );
                            let lt = (l1 * l1 + l2 * l2).sqrt();
                            let sliding = lt >= mu * ln * (1.0 - 1e-9) && ut.norm() > 1e-9;
                            // normal: δu = δb
                            equality_row(&mut mm, &mut rr, &w, &cq, &jac, rows.b[r], r, n, h);
                            if sliding {
                                any_sliding = true;
                                // λₜ = −μ λₙ û: δλₜ + μ û δλₙ + κ P δuₜ = 0
                                let un = ut.norm();
                                let uh = [ut.x / un, ut.y / un];
                                let kappa = mu * ln / un;
                                for a in 0..2 {
                                    let ra = r + 1 + a;
                                    mm[(ra, ra)] += 1.0;
                                    mm[(ra, r)] += mu * uh[a];
                                    for b in 0..2 {
                                        let p = if a == b { 1.0 } else { 0.0 } - uh[a] * uh[b];
                                        let rb = r + 1 + b;
                                        for k in 0..m {
                                            mm[(ra, k)] += kappa * p * w[(rb, k)];
                                        }
                                        for c in 0..3 * n {
                                            rr[(ra, c)] -= kappa * p * cq[(rb, c)];
                                        }
                                    }
                                }
                            } else {
                                for k in r + 1..r + 3 {
                                    equality_row(&mut mm, &mut rr, &w, &cq, &jac, 0.0, k, n, h);
                                }
                            }
                        }
                        r += 3;
                    }
                    RowKind::Tangent { normal, mu } if r + 1 < m => {
                        // a torsional or rolling pair (sim/constraints/spin.rs)
                        let ln = rows.lambda.get(normal).copied().unwrap_or(0.0);
                        let ut = [cq_row_dot(&jac, r, vplus), cq_row_dot(&jac, r + 1, vplus)];
                        let lt = rows.lambda[r].hypot(rows.lambda[r + 1]);
                        let un = ut[0].hypot(ut[1]);
                        if ln <= 0.0 {
                            mm[(r, r)] = 1.0;
                            mm[(r + 1, r + 1)] = 1.0;
                        } else if lt >= mu * ln * (1.0 - 1e-9) && un > 1e-9 {
                            any_sliding = true;
                            let uh = [ut[0] / un, ut[1] / un];
                            spin_sliding(
                                &mut mm,
                                &mut rr,
                                &w,
                                &cq,
                                (r, normal),
                                mu * ln / un,
                                mu,
                                uh,
                            );
                        } else {
                            for k in r..r + 2 {
                                if w[(k, k)] > 1e-14 {
                                    equality_row(&mut mm, &mut rr, &w, &cq, &jac, 0.0, k, n, h);
                                } else {
                                    mm[(k, k)] = 1.0;
                                }
                            }
                        }
                        r += 2;
                    }
                    RowKind::Box { limit } => {
                        if rows.lambda[r].abs() >= limit * (1.0 - 1e-9) {
                            mm[(r, r)] = 1.0;
                        } else {
                            equality_row(&mut mm, &mut rr, &w, &cq, &jac, 0.0, r, n, h);
                        }
                        r += 1;
                    }
                    RowKind::Bilateral => {
                        // a loop row: δu = 0 (velocity target 0, λ free)
                        equality_row(&mut mm, &mut rr, &w, &cq, &jac, 0.0, r, n, h);
                        r += 1;
                    }
                    RowKind::Unilateral => {
                        if rows.lambda[r] <= 0.0 {
                            mm[(r, r)] = 1.0;
                        } else {
                            equality_row(&mut mm, &mut rr, &w, &cq, &jac, rows.b[r], r, n, h);
                        }
                        r += 1;
                    }
                    _ => r += 1,
                }
            }
            // a stick set's rows can be redundant (a flat foot's vertices, a
            // planar leg's feet sideways): M = W there, and Jᵀδλ is the same
            // for any solution (W's null space is Jᵀ's): a basic one. Sliding
            // rows on redundant contacts leave it to the choice of solution
            // (the normal impulses' split): the least-norm one (SVD)
            let dl = if any_sliding {
                let svd = mm.svd(true, true);
                let tol = 1e-12 * svd.singular_values.max().max(1e-300);
                // the velocity must not depend on the solution chosen: every
                // null vector ν of M has H̃⁻¹Jᵀν = 0 (docs/theory.md §"Step
                // Jacobians with redundant rows"); else the step's v⁺ is the
                // solve's own pick among many, and no linearisation gives it
                if !velocity_determined(&svd, tol, &y) {
                    return Ok(None);
                }
                svd.solve(&rr, tol)
                    .map_err(|e| SimError::Invalid(format!("transition_jacobians: {e}")))?
            } else {
                solve_basic(mm, rr, 1e-12)
            };
            z0.gemm(1.0, &y, &dl, 1.0);
        }
        let dvplus = &sc.z0;
        // the position pass's δw (docs/theory.md §"Loops and the position pass
        // in the step Jacobians"): added to the configuration's velocity only
        let mut dvtot = None;
        if let (Some(wv), Some(hwq)) = (push.as_ref(), hw_q.as_ref()) {
            let mut gcm = DMatrix::<f64>::zeros(n, n);
            let mut jqw = DMatrix::<f64>::zeros(m, n);
            add_second_order(self, points, &loops, &rows.mu, wv, &mut gcm, &mut jqw);
            let pass = PositionPass {
                jac: &jac,
                y: &y,
                w: &w,
                minv,
                h_w_q: hwq,
                gc_mu: &gcm,
                jq_w: &jqw,
                gq: &gq,
                gv: &gv,
                loops: &loops,
                h,
            };
            dvtot = Some(dvplus + self.position_pass_jacobian(&pass));
        }
        self.q.copy_from(&sc.q1);
        self.v.copy_from(&sc.v1);
        self.fk_valid = false;
        // without the position pass δv_tot = δv⁺ (no copy)
        let dvtot = dvtot.as_ref().unwrap_or(dvplus);
        Ok(Some(self.output_map(vtot, vplus, dvtot, dvplus, h)))
    }
}
