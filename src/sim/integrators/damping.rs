//! How stiff the joint damping is, for the smooth integrators' switch.
//!
//! Joint damping on a light link is stiff: the damping flow v̇ = −M⁻¹D v
//! (M = H + A) has rates up to λmax(M⁻¹D) (allegro's hand: about 2e6 s⁻¹). An
//! explicit method is stable on it only while h·λ stays inside its stability
//! interval (rk4's reaches 2.78, dop853's about 6). Splitting the damping off
//! (Strang, with an L-stable substep) is stable but wrong for overdamped
//! links: their creep under a load F is h·F/D a step, and the split moves them
//! by h²F/(2M), hλ/2 times too far. So the smooth integrators take damping in
//! their right-hand side while h·tr(M⁻¹D) ≤ [`explicit_limit`] (tr ≥ λmax: a
//! safe bound), an adaptive step is capped there, and a step where even `dt` is
//! past it is taken by the time-stepping scheme, whose damping is implicit
//! (H̃ = H + A + h D): stable at any stiffness and accurate on the creep.

use crate::sim::{Integrator, SimError, Simulation};

/// h·tr((H + A)⁻¹D) up to which an integrator keeps damping explicit.
pub(crate) fn explicit_limit(integrator: Integrator) -> f64 {
    match integrator {
        Integrator::Dop853 => 4.0,
        _ => 2.0,
    }
}

impl Simulation {
    /// The damping's stiffness bound tr((H + A)⁻¹D) = Σ Dᵢ (H + A)⁻¹ᵢᵢ at the
    /// current q (s⁻¹; 0 without damping).
    pub(in crate::sim) fn damping_rate(&mut self) -> Result<f64, SimError> {
        if !self.has_damping && !self.servo.active {
            return Ok(0.0);
        }
        self.factor_mass(0.0)?;
        let mut rate = 0.0;
        // servos: their damping gain adds to D, their stiffness to the
        // oscillation rate √tr((H + A)⁻¹Kp) (docs/theory.md §"Joint servos")
        let mut stiff = 0.0;
        for i in 0..self.model.nv {
            let d = self.damping[i] + self.servo.kd[i];
            if d > 0.0 {
                rate += d * self.mass.f.inverse_diagonal(i);
            }
            let kp = self.servo.kp[i];
            if kp > 0.0 {
                stiff += kp * self.mass.f.inverse_diagonal(i);
            }
        }
        Ok(rate + stiff.sqrt())
    }
}
