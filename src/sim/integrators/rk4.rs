//! Classical 4th-order Runge–Kutta on y = (q, v) (quaternion in the ODE,
//! renormalised after the step).

use super::smooth::RhsIn;
use crate::sim::{SimError, Simulation};

impl Simulation {
    /// One smooth step of length `h`; `friction`: joint friction rows exist.
    pub(in crate::sim) fn rk4_step(&mut self, h: f64, friction: bool) -> Result<(), SimError> {
        self.hold_joint_friction(h, friction)?;
        self.load_y();
        self.eval_rhs(RhsIn::Y, 0)?;
        let c = [0.5, 0.5, 1.0];
        for s in 0..3 {
            let w = &mut self.smooth;
            w.y_stage.copy_from(&w.y);
            w.y_stage.axpy(c[s] * h, &w.k[s], 1.0);
            self.eval_rhs(RhsIn::Stage, s + 1)?;
        }
        let w = &mut self.smooth;
        for i in 0..w.y.len() {
            w.y[i] += h / 6.0 * (w.k[0][i] + 2.0 * w.k[1][i] + 2.0 * w.k[2][i] + w.k[3][i]);
        }
        self.store_y(false);
        let _ = self.project_limits();
        self.fk_valid = false;
        Ok(())
    }
}
