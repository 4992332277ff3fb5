//! Dormand–Prince 8(5,3) with error control (Hairer's `dop853`). A step is accepted when
//! RMSᵢ(eᵢ / (X + X·max(|yᵢ|, |yᵢ⁺|))) ≤ 1 (X = `tol`); the next step is
//! h·min(10, max(0.2, 0.9·err^(−1/8))). With contact shapes in the scene a step
//! is at most `dt` (it may not outrun the detection margin), and with damping
//! at most the explicit limit over the damping rate ([`super::damping`]).

use super::dop853_tableau::{A, B, E3, E5, N_STAGES};
use super::smooth::RhsIn;
use crate::sim::{SimError, Simulation};

impl Simulation {
    /// One accepted step no longer than `remaining` (a remainder shorter than
    /// a tenth of the step is taken with it); returns its length.
    pub(in crate::sim) fn dop853_step(
        &mut self,
        remaining: f64,
        h_max: f64,
        friction: bool,
    ) -> Result<f64, SimError> {
        if self.contact.is_some() {
            self.smooth.h_next = self.smooth.h_next.min(self.dt);
        }
        self.smooth.h_next = self.smooth.h_next.min(h_max);
        let mut h = self.smooth.h_next.min(remaining);
        if remaining - h < 0.1 * h {
            h = remaining;
        }
        // k[0] = f(y) carried over from the last step (first same as last) is
        // valid only when nothing changed y or the forcing since
        let fsal = self.smooth.fsal_ok && !friction && !self.forcing_changed;
        let mut tries = 0;
        loop {
            tries += 1;
            self.hold_joint_friction(h, friction)?;
            self.load_y();
            if !(fsal && tries == 1) {
                self.eval_rhs(RhsIn::Y, 0)?;
            }
            self.forcing_changed = false;
            for s in 1..N_STAGES {
                let w = &mut self.smooth;
                w.y_stage.copy_from(&w.y);
                for (j, a) in A[s].iter().enumerate().take(s) {
                    if *a != 0.0 {
                        w.y_stage.axpy(h * a, &w.k[j], 1.0);
                    }
                }
                self.eval_rhs(RhsIn::Stage, s)?;
            }
            {
                let w = &mut self.smooth;
                w.y_new.copy_from(&w.y);
                for (j, b) in B.iter().enumerate() {
                    if *b != 0.0 {
                        w.y_new.axpy(h * b, &w.k[j], 1.0);
                    }
                }
            }
            self.eval_rhs(RhsIn::New, 12)?;
            // error estimate (Hairer's dop853: 5th- and 3rd-order estimators)
            let w = &self.smooth;
            let n = w.y.len();
            let (mut e5, mut e3) = (0.0, 0.0);
            for i in 0..n {
                let sc = self.tol + self.tol * w.y[i].abs().max(w.y_new[i].abs());
                let (mut s5, mut s3) = (0.0, 0.0);
                for j in 0..13 {
                    let kj = w.k[j][i];
                    s5 += E5[j] * kj;
                    s3 += E3[j] * kj;
                }
                e5 += (s5 / sc) * (s5 / sc);
                e3 += (s3 / sc) * (s3 / sc);
            }
            let err = if e5 == 0.0 && e3 == 0.0 {
                0.0
            } else {
                h * e5 / ((e5 + 0.01 * e3) * n as f64).sqrt()
            };
            if !err.is_finite() {
                return Err(SimError::NonFinite {
                    t: self.t + h,
                    quantity: "integrator error estimate".into(),
                });
            }
            if err <= 1.0 {
                let fac = if err == 0.0 {
                    10.0
                } else {
                    (0.9 * err.powf(-1.0 / 8.0)).min(10.0)
                };
                // do not let a landing step shrink the next one
                let w = &mut self.smooth;
                if h < remaining || h >= w.h_next {
                    w.h_next = h * fac;
                } else {
                    w.h_next = w.h_next.max(h * fac);
                }
                self.store_y(true);
                // k[0] = f(y_new) for the next step; the rest are scratch
                let w = &mut self.smooth;
                let last = w.k.swap_remove(12);
                w.k.insert(0, last);
                let projected = self.project_limits();
                self.smooth.fsal_ok = !friction && !projected;
                self.fk_valid = false;
                return Ok(h);
            }
            self.rejected += 1;
            h *= (0.9 * err.powf(-1.0 / 8.0)).clamp(0.2, 1.0);
            if h < 1e-14 * (1.0 + self.t.abs()) || tries > 200 {
                return Err(SimError::NonFinite {
                    t: self.t,
                    quantity: format!("step size underflow (h = {h:e})"),
                });
            }
        }
    }
}
