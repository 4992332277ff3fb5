//! A high-accuracy integrator of the constrained ODE for the mechanism examples
//! (examples/four_bar.rs, examples/quadruped_held.rs, tests/mechanism_examples/four_bar.rs):
//! classical RK4 on (q, v) with v̇ = q̈ of urdyn's `constraint_dynamics`
//! (mechanisms.md §"Semantics": H q̈ + C = τ + J_cᵀλ, J_c q̈ + γ_c = 0), each
//! stage's configuration q ⊕ h·Σ aᵢⱼ vⱼ (exact RK4 on vector joints; on a free
//! base the rotation's stages are frozen-frame, first order in the rotation's
//! curvature, enough for a base that barely turns), then a projection onto the
//! constraint manifold after every step:
//! - position: Gauss–Newton on the `point` rows' residual r(q) = p₁ − p₂,
//!   δq = −J_c⁺ r (least-norm, J_c⁺ by SVD, so a planar loop's identically zero
//!   row is ignored), until |r| < 1e-14 m;
//! - velocity: v ← v − J_c⁺ J_c v (the nearest v with J_c v = 0).
//!
//! The exact flow keeps c(q) = 0, J_c v = 0; RK4's drift off the manifold is
//! O(h⁵) a step, so the projection moves the state by that much and keeps the
//! method's fourth order (Hairer, Lubich, Wanner, "Geometric Numerical
//! Integration", IV.4). Only `point` constraints are projected.

#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};
use urdyn::dynamics_f64::{self as dynamics, ConstraintData};
use urdyn::model::{ConstraintKind, Constraints};
use urdyn::{Data, Model};

/// The joint torques of a state: `tau(system, q, v, t)`.
pub type TorqueFn<'a> =
    dyn FnMut(&mut Constrained, &DVector<f64>, &DVector<f64>, f64) -> DVector<f64> + 'a;

/// The model, its workspaces and the constraint set.
pub struct Constrained {
    /// The model.
    pub model: Model,
    /// Its data.
    pub data: Data,
    /// The constraints' workspace (λ, J_c, q̈ of the last call).
    pub cd: ConstraintData,
    /// The constraints (world anchors placed).
    pub c: Constraints,
}

impl Constrained {
    /// Builds the workspaces; `c`'s held anchors are placed at `q`.
    pub fn new(model: Model, mut c: Constraints, q: &DVector<f64>) -> Self {
        let mut data = Data::new(&model);
        dynamics::forward_kinematics(&model, &mut data, q).expect("q's size");
        c.place_holds(&data);
        let cd = ConstraintData::new(&model, &c);
        Self { model, data, cd, c }
    }

    /// q̈ of the constrained dynamics (λ in `self.cd.lambda`).
    pub fn qdd(&mut self, q: &DVector<f64>, v: &DVector<f64>, tau: &DVector<f64>) -> DVector<f64> {
        dynamics::constraint_dynamics(
            &self.model,
            &mut self.data,
            &mut self.cd,
            &self.c,
            q,
            v,
            tau,
            None,
        )
        .expect("consistent constraints")
        .clone()
    }

    /// The stacked residual p₁ − p₂ of the `point` constraints at q (3 rows each).
    pub fn residual(&mut self, q: &DVector<f64>) -> DVector<f64> {
        dynamics::forward_kinematics(&self.model, &mut self.data, q).expect("q's size");
        let mut r = DVector::zeros(self.c.rows());
        let mut row = 0;
        for con in &self.c.items {
            if con.kind == ConstraintKind::Point {
                let p1 = self.data.o_m_i[con.a.body].compose(&con.a.local).trans;
                let p2 = self.data.o_m_i[con.b.body].compose(&con.b.local).trans;
                r.rows_mut(row, 3).copy_from(&(p1 - p2));
            }
            row += con.rows();
        }
        r
    }

    /// J_c at q.
    pub fn jacobian(&mut self, q: &DVector<f64>) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(self.c.rows(), self.model.nv);
        dynamics::constraint_jacobian(&self.model, &mut self.data, &self.c, q, &mut j)
            .expect("q's size");
        j
    }

    /// The largest violation (m for `point`) at q.
    pub fn violation(&mut self, q: &DVector<f64>) -> f64 {
        let mut out = vec![0.0; self.c.items.len()];
        dynamics::constraint_violation(&self.model, &mut self.data, &self.c, q, &mut out)
            .expect("q's size");
        out.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// Kinetic plus potential energy (J).
    pub fn energy(&mut self, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
        let t = dynamics::kinetic_energy(&self.model, &mut self.data, q, v).expect("sizes");
        dynamics::forward_kinematics(&self.model, &mut self.data, q).expect("q's size");
        t + dynamics::potential_energy(&self.model, &self.data)
    }

    /// Projects (q, v) onto c(q) = 0, J_c v = 0 (module notes).
    pub fn project(&mut self, q: &mut DVector<f64>, v: &mut DVector<f64>) {
        for _ in 0..10 {
            let r = self.residual(q);
            if r.norm() < 1e-14 {
                break;
            }
            let jp = pinv(&self.jacobian(q));
            *q = dynamics_integrate(&self.model, q, &(-(jp * r)));
        }
        let j = self.jacobian(q);
        let jv = &j * &*v;
        *v -= pinv(&j) * jv;
    }

    /// One RK4 step of h from t; `tau(self, q, v, t)` gives the joint torques.
    pub fn rk4_step(
        &mut self,
        q: &mut DVector<f64>,
        v: &mut DVector<f64>,
        t: f64,
        h: f64,
        tau: &mut TorqueFn<'_>,
    ) {
        let mut f = |s: &mut Self, dq: &DVector<f64>, vs: &DVector<f64>, ts: f64| {
            let qs = dynamics_integrate(&s.model, q, dq);
            let u = tau(s, &qs, vs, ts);
            s.qdd(&qs, vs, &u)
        };
        let zero = DVector::zeros(v.len());
        let a1 = f(self, &zero, v, t);
        let v1 = v.clone();
        let v2 = &*v + &a1 * (h / 2.0);
        let a2 = f(self, &(&v1 * (h / 2.0)), &v2, t + h / 2.0);
        let v3 = &*v + &a2 * (h / 2.0);
        let a3 = f(self, &(&v2 * (h / 2.0)), &v3, t + h / 2.0);
        let v4 = &*v + &a3 * h;
        let a4 = f(self, &(&v3 * h), &v4, t + h);
        let dq = (&v1 + &v2 * 2.0 + &v3 * 2.0 + &v4) * (h / 6.0);
        *q = dynamics_integrate(&self.model, q, &dq);
        *v += (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (h / 6.0);
        self.project(q, v);
    }
}

/// q ⊕ dq (urdyn's `integrate`).
pub fn dynamics_integrate(model: &Model, q: &DVector<f64>, dq: &DVector<f64>) -> DVector<f64> {
    urdyn::model::configuration::integrate(model, q, dq).expect("sizes")
}

/// Moore–Penrose pseudo-inverse, singular values below 1e-10 · the largest dropped.
pub fn pinv(j: &DMatrix<f64>) -> DMatrix<f64> {
    let svd = j.clone().svd(true, true);
    let tol = 1e-10 * svd.singular_values.max().max(1e-300);
    svd.pseudo_inverse(tol).expect("svd with u and v")
}
