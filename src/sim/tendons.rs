//! Fixed tendons in a simulation (mjcf.md §"What the file becomes",
//! docs/theory.md §"MJCF fixed tendons"). A tendon that moves one joint is
//! that joint's spring, damper, range and actuator gear at import
//! (src/mjcf/tendons.rs), simulated as the joint's own. What is left here: a
//! constant-force actuator on a tendon over several joints, whose force f
//! acts as the generalized force τᵢ = gear·cᵢ·f on each of its joints
//! (the tendon's Jacobian, constant for a fixed tendon).

use crate::model::Actuator;
use nalgebra::DVector;

/// Adds actuator `a`'s constant force at control `u` (already clamped into its
/// ctrlrange), f = g₀·u + b₀, along its tendon to `tau` (nothing for an
/// actuator without a tendon moment).
pub(crate) fn add_tendon_force(tau: &mut DVector<f64>, a: &Actuator, u: f64) {
    if a.moment.is_empty() {
        return;
    }
    let f = a.gain[0] * u + a.bias[0];
    for &(iv, m) in &a.moment {
        tau[iv] += m * f;
    }
}
