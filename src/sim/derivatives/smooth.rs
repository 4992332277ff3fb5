//! The analytic Jacobian of a smooth (rk4, dop853) step: the Runge–Kutta
//! chain rule through its stages (docs/theory.md §"Transition Jacobians").
//!
//! The integrators work on y = (q, v) with the quaternion inside the ODE:
//! kₛ = f(yₛ), yₛ = y + h Σⱼ aₛⱼ kⱼ, y⁺ = y + h Σⱼ bⱼ kⱼ, so
//! δkₛ = F(yₛ) δyₛ + F_τ(yₛ) δτ with F = ∂f/∂y, and δy⁺ follows the same sums.
//! F is q̇'s derivative (ṗ = R(q̂) v_lin, the quaternion rate ½ q ⊗ (ω, 0),
//! joints q̇ = v) and v̇ = (H + A)⁻¹(sat(τ + servo) + τ_c − D v − C)'s:
//! ∂v̇/∂q = −(H + A)⁻¹(∂ID/∂q + Kp) (ID at (q̂, v, v̇), tangent space, then
//! composed with the raw quaternion's tangent map),
//! ∂v̇/∂v = −(H + A)⁻¹(∂ID/∂v + D + Kd), ∂v̇/∂τ = (H + A)⁻¹ on joints whose
//! torque is not clamped. The
//! held joint friction τ_c is held in the derivative too.

use crate::dynamics::linalg::{chol_solve_slice, cholesky_fast};
use crate::dynamics::{bias, mass_matrix, DynamicsError};
use crate::model::configuration::normalize_quat;
use crate::sim::{SimError, Simulation};
use crate::spatial::{quat_to_matrix, skew};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// An explicit Runge–Kutta tableau: stage coefficients a (row s: aₛⱼ, j < s)
/// and weights b.
pub(super) struct Tableau<'a> {
    pub a: &'a [&'a [f64]],
    pub b: &'a [f64],
}

impl Simulation {
    /// [δq'; δv'] over the columns (δq, δv, δτ) of one smooth step of length
    /// `h` from (q0, v0) with the tableau `t`; `tau`: the joint torques. The
    /// step has been taken (its held joint friction is in `smooth.tau_c`).
    pub(super) fn smooth_step_jacobian(
        &mut self,
        q0: &DVector<f64>,
        v0: &DVector<f64>,
        q1: &DVector<f64>,
        tau: &DVector<f64>,
        h: f64,
        t: &Tableau<'_>,
    ) -> Result<DMatrix<f64>, SimError> {
        let (nq, n) = (self.model.nq, self.model.nv);
        let ny = nq + n;
        let ns = t.b.len();
        // stage states and their slopes, as the integrator computed them
        let mut y0 = DVector::zeros(ny);
        y0.rows_mut(0, nq).copy_from(q0);
        y0.rows_mut(nq, n).copy_from(v0);
        let mut ys: Vec<DVector<f64>> = Vec::with_capacity(ns);
        let mut ks: Vec<DVector<f64>> = Vec::with_capacity(ns);
        for s in 0..ns {
            let mut y = y0.clone();
            for (j, a) in t.a[s].iter().enumerate() {
                if *a != 0.0 {
                    y.axpy(h * a, &ks[j], 1.0);
                }
            }
            self.smooth.y_stage.copy_from(&y);
            self.eval_rhs(crate::sim::integrators::RhsIn::Stage, 0)?;
            ks.push(self.smooth.k[0].clone());
            ys.push(y);
        }
        // the chain rule over the 3n columns
        let tin = self.tangent_to_raw(q0);
        let mut dy0 = DMatrix::zeros(ny, 3 * n);
        dy0.view_mut((0, 0), (ny, 2 * n)).copy_from(&tin);
        let mut dks: Vec<DMatrix<f64>> = Vec::with_capacity(ns);
        for (s, ysv) in ys.iter().enumerate() {
            let mut dy = dy0.clone();
            for (j, a) in t.a[s].iter().enumerate() {
                if *a != 0.0 {
                    dy += &dks[j] * (h * a);
                }
            }
            let (fy, ft) = self.rhs_jacobian(ysv, tau)?;
            let mut dk = &fy * &dy;
            let mut view = dk.view_mut((0, 2 * n), (ny, n));
            view += &ft;
            dks.push(dk);
        }
        let mut dy1 = dy0;
        for (j, b) in t.b.iter().enumerate() {
            if *b != 0.0 {
                dy1 += &dks[j] * (h * b);
            }
        }
        // raw y⁺ → the tangent at q1 (the normalised result)
        let mut yraw = y0;
        for (j, b) in t.b.iter().enumerate() {
            yraw.axpy(h * b, &ks[j], 1.0);
        }
        let tq = self.raw_to_tangent(q1, &yraw.rows(0, nq).into_owned());
        let mut tout = DMatrix::zeros(2 * n, ny);
        tout.view_mut((0, 0), (n, nq)).copy_from(&tq);
        for k in 0..n {
            tout[(n + k, nq + k)] = 1.0;
        }
        Ok(tout * dy1)
    }

    /// ∂f/∂y (ny × ny) and ∂f/∂τ (ny × nv) of the smooth right-hand side at the
    /// raw state `y`.
    fn rhs_jacobian(
        &mut self,
        y: &DVector<f64>,
        tau: &DVector<f64>,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), SimError> {
        let (nq, n) = (self.model.nq, self.model.nv);
        let ny = nq + n;
        let (qo, vo) = (self.model.joint_q_offset(), self.model.joint_v_offset());
        let qraw = y.rows(0, nq).into_owned();
        let mut qh = qraw.clone();
        if self.model.floating_base {
            normalize_quat(&mut qh);
        }
        let v = y.rows(nq, n).into_owned();
        // v̇ = M⁻¹(τ_tot − C), M = H + A, and which torques are clamped
        let mut ttot = DVector::zeros(n);
        let mut free = vec![false; n];
        for k in 0..n {
            let (tf, e) = (tau[k], self.effort[k]);
            let mut t = if k < vo { 0.0 } else { tf };
            if self.servo.active && k >= vo {
                let iq = qo + k - vo;
                t += self.servo.torque(iq, k, qh[iq], v[k]);
            }
            free[k] = k >= vo && t.abs() < e;
            ttot[k] = t.clamp(-e, e) + self.smooth.tau_c[k] - self.damping[k] * v[k];
        }
        let c = bias(&self.model, &mut self.data, &qh, &v, None)?.clone();
        mass_matrix(&self.model, &mut self.data, &qh)?;
        let mut m = self.data.h.clone();
        for k in 0..n {
            m[(k, k)] += self.armature[k];
        }
        let mut chol = DMatrix::zeros(n, n);
        cholesky_fast(&m, &mut chol).map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)))?;
        let minv = |x: &mut DVector<f64>| chol_solve_slice(chol.as_slice(), n, x.as_mut_slice());
        let mut qdd = ttot - c;
        minv(&mut qdd);
        let (mut dq, mut dv) = self.id_derivatives(&qh, &v, &qdd)?;
        let s = &self.servo;
        for k in 0..n {
            dv[(k, k)] += self.damping[k];
            if free[k] && s.active {
                dq[(k, k)] += s.kp[k];
                dv[(k, k)] += s.kd[k];
            }
        }
        // −M⁻¹ dq, −M⁻¹ dv, M⁻¹ U
        let mut fvq = DMatrix::zeros(n, n);
        let mut fvv = DMatrix::zeros(n, n);
        let mut ft = DMatrix::zeros(ny, n);
        let mut col = DVector::zeros(n);
        for j in 0..n {
            col.copy_from(&(-dq.column(j)));
            minv(&mut col);
            fvq.column_mut(j).copy_from(&col);
            col.copy_from(&(-dv.column(j)));
            minv(&mut col);
            fvv.column_mut(j).copy_from(&col);
            if free[j] {
                col.fill(0.0);
                col[j] = 1.0;
                minv(&mut col);
                ft.view_mut((nq, j), (n, 1)).copy_from(&col);
            }
        }
        let mut fy = DMatrix::zeros(ny, ny);
        // v̇'s rows: ∂/∂q_raw = ∂v̇/∂δq · ∂δq/∂q_raw
        let traw = self.raw_to_tangent(&qh, &qraw);
        fy.view_mut((nq, 0), (n, nq)).copy_from(&(&fvq * &traw));
        fy.view_mut((nq, nq), (n, n)).copy_from(&fvv);
        // q̇'s rows
        for d in 0..self.model.dofs.len() {
            fy[(qo + d, nq + vo + d)] = 1.0;
        }
        if self.model.floating_base {
            let r = quat_to_matrix(qh[3], qh[4], qh[5], qh[6]);
            let l = Vector3::new(v[0], v[1], v[2]);
            // ṗ = R(q̂) l: ∂/∂l = R, ∂/∂q_raw = −R [l]× ∂δθ/∂q_raw
            let dpdth = -r * skew(&l);
            for i in 0..3 {
                for j in 0..3 {
                    fy[(i, nq + j)] = r[(i, j)];
                }
                for j in 0..nq {
                    let mut x = 0.0;
                    for a in 0..3 {
                        x += dpdth[(i, a)] * traw[(3 + a, j)];
                    }
                    fy[(i, j)] = x;
                }
            }
            // the quaternion rate ½ q ⊗ (ω, 0) with q raw (x, y, z, w)
            let (x, yy, z, w) = (qraw[3], qraw[4], qraw[5], qraw[6]);
            let (wx, wy, wz) = (v[3], v[4], v[5]);
            let dq_dq = [
                [0.0, wz, -wy, wx],
                [-wz, 0.0, wx, wy],
                [wy, -wx, 0.0, wz],
                [-wx, -wy, -wz, 0.0],
            ];
            let dq_dw = [[w, -z, yy], [z, w, -x], [-yy, x, w], [-x, -yy, -z]];
            for i in 0..4 {
                for j in 0..4 {
                    fy[(3 + i, 3 + j)] = 0.5 * dq_dq[i][j];
                }
                for j in 0..3 {
                    fy[(3 + i, nq + 3 + j)] = 0.5 * dq_dw[i][j];
                }
            }
        }
        Ok((fy, ft))
    }

    /// The raw state's derivative (ny × 2nv) of x ⊕ δx at the configuration
    /// `q` (unit quaternion): δp = R δl, δquat = ½ q ⊗ (δθ, 0), the rest 1.
    fn tangent_to_raw(&self, q: &DVector<f64>) -> DMatrix<f64> {
        let (nq, n) = (self.model.nq, self.model.nv);
        let mut t = DMatrix::zeros(nq + n, 2 * n);
        let (qo, vo) = (self.model.joint_q_offset(), self.model.joint_v_offset());
        for d in 0..self.model.dofs.len() {
            t[(qo + d, vo + d)] = 1.0;
        }
        for k in 0..n {
            t[(nq + k, n + k)] = 1.0;
        }
        if self.model.floating_base {
            let r = quat_to_matrix(q[3], q[4], q[5], q[6]);
            let (x, y, z, w) = (q[3], q[4], q[5], q[6]);
            let qv = Vector3::new(x, y, z);
            let m: Matrix3<f64> = Matrix3::identity() * w + skew(&qv);
            for i in 0..3 {
                for j in 0..3 {
                    t[(i, j)] = r[(i, j)];
                    t[(3 + i, 3 + j)] = 0.5 * m[(i, j)];
                }
                t[(6, 3 + i)] = -0.5 * qv[i];
            }
        }
        t
    }

    /// The tangent displacement's derivative (nv × nq) at the normalised
    /// configuration `qh` from a raw one `qraw` (its quaternion |q| ≠ 1 allowed):
    /// δl = Rᵀ δp, δθ = (2/|q|)(ŵ δq_v − δq_w q̂_v − q̂_v × δq_v), joints 1.
    fn raw_to_tangent(&self, qh: &DVector<f64>, qraw: &DVector<f64>) -> DMatrix<f64> {
        let (nq, n) = (self.model.nq, self.model.nv);
        let mut t = DMatrix::zeros(n, nq);
        let (qo, vo) = (self.model.joint_q_offset(), self.model.joint_v_offset());
        for d in 0..self.model.dofs.len() {
            t[(vo + d, qo + d)] = 1.0;
        }
        if self.model.floating_base {
            let r = quat_to_matrix(qh[3], qh[4], qh[5], qh[6]);
            let norm =
                (qraw[3] * qraw[3] + qraw[4] * qraw[4] + qraw[5] * qraw[5] + qraw[6] * qraw[6])
                    .sqrt();
            let qv = Vector3::new(qh[3], qh[4], qh[5]);
            let m: Matrix3<f64> = (Matrix3::identity() * qh[6] - skew(&qv)) * (2.0 / norm);
            for i in 0..3 {
                for j in 0..3 {
                    t[(i, j)] = r[(j, i)];
                    t[(3 + i, 3 + j)] = m[(i, j)];
                }
                t[(3 + i, 6)] = -qv[i] * 2.0 / norm;
            }
        }
        t
    }
}
