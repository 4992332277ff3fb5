//! Finite differences of the fresh step (MuJoCo's `mjd_transitionFD`): column
//! j of A and B is (x'(x ⊕ ε eⱼ) ⊖ x'(x))/ε (forward) or
//! (x'(x ⊕ ε eⱼ) ⊖ x'(x ⊖ ε eⱼ))/(2ε) (central), the outputs compared in
//! the tangent space at the unperturbed x'₀.

use super::{minus, plus, TransitionJacobians};
use crate::sim::{SimError, Simulation};
use nalgebra::{DMatrix, DVector};

impl Simulation {
    /// A and B by finite differences of step `eps` (see the module doc).
    pub(in crate::sim) fn fd_jacobians(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
        tau: &DVector<f64>,
        central: bool,
        eps: f64,
    ) -> Result<TransitionJacobians, SimError> {
        let nv = self.model.nv;
        let (q0, v0) = self.fresh_step(q, v, tau)?;
        let mut a = DMatrix::zeros(2 * nv, 2 * nv);
        let mut b = DMatrix::zeros(2 * nv, nv);
        // δx' of a perturbed step's end state, in the tangent space at x'₀
        let delta = |sim: &Simulation, q1: &DVector<f64>, v1: &DVector<f64>| {
            let mut d = DVector::zeros(2 * nv);
            d.rows_mut(0, nv).copy_from(&minus(sim, &q0, q1));
            d.rows_mut(nv, nv).copy_from(&(v1 - &v0));
            d
        };
        let signs: &[f64] = if central { &[1.0, -1.0] } else { &[1.0] };
        let scale = if central { 0.5 / eps } else { 1.0 / eps };
        // 3 kinds of column: δq (0), δv (1), δτ (2)
        for kind in 0..3 {
            for j in 0..nv {
                if kind == 2 && self.servo.iq[j] == crate::sim::servo::FREE {
                    continue;
                }
                let mut col = DVector::zeros(2 * nv);
                for &s in signs {
                    let mut e = DVector::zeros(nv);
                    e[j] = s * eps;
                    let (q1, v1) = match kind {
                        0 => self.fresh_step(&plus(self, q, &e), v, tau)?,
                        1 => self.fresh_step(q, &(v + &e), tau)?,
                        _ => self.fresh_step(q, v, &(tau + &e))?,
                    };
                    col.axpy(s * scale, &delta(self, &q1, &v1), 1.0);
                }
                match kind {
                    0 => a.column_mut(j).copy_from(&col),
                    1 => a.column_mut(nv + j).copy_from(&col),
                    _ => b.column_mut(j).copy_from(&col),
                }
            }
        }
        Ok(TransitionJacobians { a, b })
    }
}
