//! The loops' projection after a step (docs/theory.md §"Loops in the
//! simulation", "Fast rotation"): the position pass's target J w = −φ/h − ½hγ
//! is a second-order prediction of where the step's curve q ⊕ h(v⁺ + w) takes
//! the rows; a mechanism turning fast (an arm spinning at ~100 rad/s about its
//! own axis in MJCF's `equalities.xml`) leaves the third-order residual
//! ≈ h³ω³r/6 a step. After the step, the rows' actual residual at q⁺ is measured
//! and the part of it beyond [`TOL`] (per row direction, from the residual the
//! position target aimed at) is removed by one Newton step on the rows,
//! q⁺ ← q⁺ ⊕ (−H̃⁻¹Jᵀ K⁻¹ r), K = J H̃⁻¹ Jᵀ, with J at q⁺ along the step's
//! kept directions and H̃ the step's factored mass matrix (the metric).
//!
//! Only the excess over TOL is projected (a dead zone, continuous in the
//! state), so a slow mechanism, whose residual stays below it, is never moved
//! and the step Jacobians stay those of the step without it; where it acts the
//! position pass already cancelled the residual to second order, so its
//! derivative is of third order.

use super::{residual, Loops};
use crate::dynamics::constraint_dynamics::jacobian_rows;
use crate::model::{configuration::integrate_config, ConstraintKind, Data, Model};
use crate::sim::factor::MassFactor;
use nalgebra::{DMatrix, DVector};

/// The residual (m or rad, per kept row direction) a step may leave beyond
/// the one its position target aimed at before the projection acts (a tenth of
/// mechanisms.md's 1e-6 for a closed passive mechanism).
pub(in crate::sim) const TOL: f64 = 1e-7;

/// Preallocated workspace of the projection (no allocation in a step).
#[derive(Clone, Debug)]
pub(super) struct Scratch {
    /// J at q⁺ (the set's rows × nv).
    jc: DMatrix<f64>,
    /// Each projected row eᵀJ (row-major, `nv` a row).
    a: Vec<f64>,
    /// Each projected row's H̃⁻¹ Jᵀ e (row-major, `nv` a row).
    y: Vec<f64>,
    /// K = A H̃⁻¹ Aᵀ, then its Cholesky factor (row-major, `rows²`).
    k: Vec<f64>,
    /// The rows' excess residual, then the multipliers.
    r: Vec<f64>,
    /// A solve's vector (nv).
    x: DVector<f64>,
    /// The configuration change (nv).
    dq: DVector<f64>,
}

impl Scratch {
    pub(super) fn new(m: usize, nv: usize) -> Self {
        Self {
            jc: DMatrix::zeros(m, nv),
            a: vec![0.0; m * nv],
            y: vec![0.0; m * nv],
            k: vec![0.0; m * m],
            r: vec![0.0; m],
            x: DVector::zeros(nv),
            dq: DVector::zeros(nv),
        }
    }
}

impl Loops {
    /// After a step: `data` holds the forward kinematics at `q` (= q⁺), `f` the
    /// step's factored H̃. Projects the `point`/`frame` rows' residual beyond
    /// [`TOL`] of their aim (module doc) out of `q`; constraints on a sleeping
    /// body and `joint` constraints (linear in q: the step lands on their aim)
    /// are left out. Returns whether `q` moved.
    pub(in crate::sim) fn project(
        &mut self,
        model: &Model,
        data: &Data,
        q: &mut DVector<f64>,
        f: &MassFactor,
        asleep: &[bool],
    ) -> bool {
        let mut s = std::mem::replace(&mut self.proj, Scratch::new(0, 0));
        let moved = self.project_with(&mut s, model, data, q, f, asleep);
        self.proj = s;
        moved
    }

    /// [`Loops::project`] with its scratch taken out.
    fn project_with(
        &self,
        s: &mut Scratch,
        model: &Model,
        data: &Data,
        q: &mut DVector<f64>,
        f: &MassFactor,
        asleep: &[bool],
    ) -> bool {
        let nv = model.nv;
        if s.x.len() != nv || s.jc.nrows() != self.set.rows() {
            return false;
        }
        // first: whether any row's residual leaves the dead zone (most steps:
        // none, and nothing more is done)
        let mut any = false;
        self.each_row(data, q, asleep, |_, _, _, excess| any |= excess != 0.0);
        if !any {
            return false;
        }
        jacobian_rows(model, data, &self.set, &mut s.jc);
        let mut n = 0;
        let mut finite = true;
        self.each_row(data, q, asleep, |e, first, m, excess| {
            // the row eᵀJ at q⁺ and H̃⁻¹ Jᵀ e
            let row = &mut s.a[n * nv..(n + 1) * nv];
            for (d, x) in row.iter_mut().enumerate() {
                *x = (0..m).map(|i| e[i] * s.jc[(first + i, d)]).sum();
            }
            s.x.as_mut_slice().copy_from_slice(row);
            f.solve(&mut s.x);
            s.y[n * nv..(n + 1) * nv].copy_from_slice(s.x.as_slice());
            s.r[n] = excess;
            finite &= excess.is_finite();
            n += 1;
        });
        if !finite || n == 0 {
            return false;
        }
        // K = A H̃⁻¹ Aᵀ (symmetric positive definite: the kept directions are
        // independent) and its Cholesky factor in place
        for i in 0..n {
            for j in 0..=i {
                let a = &s.a[i * nv..(i + 1) * nv];
                let y = &s.y[j * nv..(j + 1) * nv];
                let kij: f64 = a.iter().zip(y).map(|(p, r)| p * r).sum();
                s.k[i * n + j] = kij;
                s.k[j * n + i] = kij;
            }
        }
        if !cholesky(&mut s.k[..n * n], n) {
            return false;
        }
        cholesky_solve(&s.k[..n * n], n, &mut s.r[..n]);
        // dq = −Σ y_i μ_i, q ← q ⊕ dq
        s.dq.fill(0.0);
        for i in 0..n {
            let mu = s.r[i];
            for (d, y) in s.dq.iter_mut().zip(&s.y[i * nv..(i + 1) * nv]) {
                *d -= mu * y;
            }
        }
        if !s.dq.iter().all(|x| x.is_finite()) {
            return false;
        }
        integrate_config(model, q, &s.dq, 1.0);
        true
    }
}

impl Loops {
    /// Calls `visit(e, first, m, excess)` for each kept row direction `e` of
    /// each active `point`/`frame` constraint that has rows this step and no
    /// sleeping body (`first`: its first set row, `m` its rows), with the part
    /// of its residual at the state of `data` beyond [`TOL`] of its aim.
    fn each_row(
        &self,
        data: &Data,
        q: &DVector<f64>,
        asleep: &[bool],
        mut visit: impl FnMut(&[f64], usize, usize, f64),
    ) {
        for (k, c) in self.set.items.iter().enumerate() {
            if self.row_of[k].is_none()
                || matches!(c.kind, ConstraintKind::Joint { .. })
                || [c.a.body, c.b.body]
                    .iter()
                    .any(|&b| asleep.get(b) == Some(&true))
            {
                continue;
            }
            let (first, m) = (self.first[k], c.rows());
            let phi = residual(c, data, q.as_slice());
            for t in 0..self.kept[k] {
                let e = &self.basis[k][t * m..(t + 1) * m];
                let along: f64 = e.iter().zip(&phi[..m]).map(|(a, b)| a * b).sum();
                let res = along - self.aim[first + t];
                let excess = if res.is_finite() {
                    res - res.clamp(-TOL, TOL)
                } else {
                    f64::NAN
                };
                visit(e, first, m, excess);
            }
        }
    }
}

/// In-place Cholesky K = L Lᵀ of the `n × n` row-major `k` (L in the lower
/// triangle); false when K is not positive definite.
fn cholesky(k: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = k[j * n + j];
        for p in 0..j {
            d -= k[j * n + p] * k[j * n + p];
        }
        if !(d > 1e-14 * k[j * n + j].abs().max(f64::MIN_POSITIVE)) {
            return false;
        }
        let l = d.sqrt();
        k[j * n + j] = l;
        for i in j + 1..n {
            let mut x = k[i * n + j];
            for p in 0..j {
                x -= k[i * n + p] * k[j * n + p];
            }
            k[i * n + j] = x / l;
        }
    }
    true
}

/// x ← K⁻¹ x from [`cholesky`]'s factor.
fn cholesky_solve(l: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        let mut v = x[i];
        for p in 0..i {
            v -= l[i * n + p] * x[p];
        }
        x[i] = v / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = x[i];
        for p in i + 1..n {
            v -= l[p * n + i] * x[p];
        }
        x[i] = v / l[i * n + i];
    }
}

impl crate::sim::Simulation {
    /// After a step with loops: the projection of [`Loops::project`] at the new
    /// q; when it moves q, the contacts are found again there.
    pub(in crate::sim) fn project_loops(&mut self) {
        if self.cons.loops.is_none() {
            return;
        }
        if !self.fk_valid {
            crate::dynamics::forward_kinematics_pass(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        let Some(l) = self.cons.loops.as_mut() else {
            return;
        };
        let moved = l.project(
            &self.model,
            &self.data,
            &mut self.q,
            &self.mass.f,
            &self.sleep.body_asleep,
        );
        if moved {
            self.refresh_contacts();
        }
    }
}
