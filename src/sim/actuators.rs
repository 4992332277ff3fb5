//! The model's actuators in a simulation (mjcf.md §"What the file becomes",
//! docs/theory.md §"MJCF actuators"): `set_controls(u)` turns each actuator's
//! force f = (g₀ + g₁L + g₂L̇)·u + b₀ + b₁L + b₂L̇ (L = gear·q, the joint's
//! force gear·f, u clamped into ctrlrange) into what the simulation already
//! integrates. Summed per joint with its spring k (springref − q):
//! τ = c − K q − D v with K = k − Σ gear²(g₁u + b₁), D = −Σ gear²(g₂u + b₂),
//! c = k·springref + Σ gear·(g₀u + b₀). K and D are the joint's servo gains
//! (integrated implicitly: position and velocity actuators are servos), the
//! actuators' part of c a constant applied torque; a force range is the
//! joint's effort limit (set at import where that is exact). The controls
//! hold until set again.

use crate::sim::{SimError, Simulation};
use nalgebra::DVector;

impl Simulation {
    /// Sets the actuators' controls (nu = `model.actuators.len()`, in the
    /// file's order; each clamped into its `ctrlrange` when limited). They
    /// replace the servo gains and targets ([`Simulation::set_gains`],
    /// [`Simulation::set_targets`]) with the actuators' and the joint springs',
    /// and move the applied torques ([`Simulation::torques`]) by the change of
    /// the actuators' constant forces (torques set afterwards replace them:
    /// [`Simulation::actuator_torques`] is that part). A wrong length, a
    /// non-finite control or a control that would give a joint a negative
    /// stiffness or damping (a general actuator's positive bias) is an error
    /// and nothing is set.
    pub fn set_controls(&mut self, u: &DVector<f64>) -> Result<(), SimError> {
        let model = self.model.clone();
        let nu = model.actuators.len();
        if u.len() != nu {
            return Err(SimError::Invalid(format!(
                "controls have {} entries, the model has nu = {nu} actuators",
                u.len()
            )));
        }
        if let Some(k) = u.iter().position(|x| !x.is_finite()) {
            return Err(SimError::Invalid(format!(
                "control {k} (actuator \"{}\") is not a finite number ({})",
                model.actuators[k].name, u[k]
            )));
        }
        if nu == 0 {
            return Ok(());
        }
        let nv = model.nv;
        let (mut kp, mut kd) = (DVector::zeros(nv), DVector::zeros(nv));
        let mut spring = DVector::zeros(nv);
        let mut ff = DVector::zeros(nv);
        let mut q_ref = self.servo.q_ref.clone();
        for d in &model.dofs {
            if d.kind.nv() == 1 && d.stiffness.is_finite() && d.stiffness > 0.0 {
                kp[d.iv] = d.stiffness;
                spring[d.iv] = d.stiffness * d.springref;
            }
        }
        for (a, &x) in model.actuators.iter().zip(u.iter()) {
            let x = match a.ctrlrange {
                Some((lo, hi)) => x.clamp(lo, hi),
                None => x,
            };
            // a constant force along a fixed tendon over several joints
            crate::sim::tendons::add_tendon_force(&mut ff, a, x);
            let Some((iv, _)) = a.dof else { continue };
            let g = a.gear;
            ff[iv] += g * (a.gain[0] * x + a.bias[0]);
            kp[iv] -= g * g * (a.gain[1] * x + a.bias[1]);
            kd[iv] -= g * g * (a.gain[2] * x + a.bias[2]);
        }
        for d in model.dofs.iter().filter(|d| d.kind.nv() == 1) {
            let (iv, iq) = (d.iv, d.iq);
            for (what, g) in [("stiffness", kp[iv]), ("damping", kd[iv])] {
                if g < 0.0 || !g.is_finite() {
                    return Err(SimError::Invalid(format!(
                        "joint \"{}\": its actuators give a negative {what} ({g}) at these controls, which urdyn does not model",
                        d.name
                    )));
                }
            }
            if kp[iv] > 0.0 {
                q_ref[iq] = spring[iv] / kp[iv];
            }
        }
        self.set_targets(&q_ref, None)?;
        self.set_gains(&kp, &kd)?;
        let change = &ff - &self.servo.ctrl_tau;
        *self.torques_mut() += change;
        self.servo.ctrl_tau = ff;
        self.servo.controls.copy_from(u);
        Ok(())
    }

    /// The controls as last set (nu; zero until [`Simulation::set_controls`]).
    pub fn controls(&self) -> &DVector<f64> {
        &self.servo.controls
    }

    /// The actuators' constant forces per v coordinate (the part of the
    /// applied torques [`Simulation::set_controls`] put there).
    pub fn actuator_torques(&self) -> &DVector<f64> {
        &self.servo.ctrl_tau
    }

    /// Starts from the model's keyframe `name` (MJCF `<keyframe><key>`): its q,
    /// v and controls (zero when the key gives none). An unknown name is an
    /// error listing the known ones.
    pub fn set_key(&mut self, name: &str) -> Result<(), SimError> {
        let model = self.model.clone();
        let Some(k) = model.keyframes.iter().find(|k| k.name == name) else {
            let names: Vec<_> = model.keyframes.iter().map(|k| k.name.as_str()).collect();
            return Err(SimError::Invalid(format!(
                "no keyframe \"{name}\" (the model has: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )));
        };
        let u = match &k.ctrl {
            Some(c) => DVector::from_column_slice(c),
            None => DVector::zeros(model.actuators.len()),
        };
        self.set_controls(&u)?;
        self.set_state(&k.q, &k.v)
    }
}
