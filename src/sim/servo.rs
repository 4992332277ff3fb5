//! Joint servos: τ = τ_ff + kp (q_ref − q) + kd (v_ref − v) per degree of
//! freedom, clamped to the URDF's `<limit effort>`, integrated implicitly as the
//! joint damping is (docs/theory.md §"Joint servos").
//!
//! In the time-stepping step the servo is taken at the end of the step,
//! q⁺ ≈ q + h v⁺ and v⁺ = v + Δv: h τ_s = h e − (h kd + h² kp) Δv with the
//! explicit part e = kp (q_ref − q − h v) + kd (v_ref − v), so the step solves
//! with H̃ = H + A + h D + h Kd + h² Kp and the right-hand side gains h e:
//! stable at any gain (a servoed free joint is a damped oscillator that the
//! scheme can only damp). A joint whose servo torque at v⁺ would pass its
//! effort limit is *saturated*: its torque is ±effort, a constant, and its
//! implicit term is dropped (the clamp's derivative is zero there); the set of
//! saturated joints is found by re-solving until no free joint passes its limit.
//! The smooth integrators (rk4, dop853) take the clamped servo torque in their
//! right-hand side while it is mild for them (the damping's rate test with
//! the servo added, `integrators/damping.rs`) and hand a stiff step to the
//! implicit scheme.

use crate::dynamics::{bias, bias_at_placements};
use crate::model::Model;
use crate::sim::{SimError, Simulation};
use nalgebra::DVector;

/// The servos' gains and targets (all zero: no servo, nothing computed).
#[derive(Clone, Debug)]
pub(crate) struct Servo {
    /// Stiffness per v coordinate (N·m/rad or N/m; base entries 0).
    pub kp: DVector<f64>,
    /// Damping gain per v coordinate (N·m·s/rad or N·s/m; base entries 0).
    pub kd: DVector<f64>,
    /// Position targets (nq; the base's part unused).
    pub q_ref: DVector<f64>,
    /// Velocity targets (nv).
    pub v_ref: DVector<f64>,
    /// Some gain is nonzero.
    pub active: bool,
    /// Per v coordinate: 0 free, +1 / −1 held at +effort / −effort in the last
    /// implicit solve.
    pub saturated: Vec<i8>,
    /// The servo torque of each v coordinate in the last step (clamped, with τ_ff).
    pub applied: DVector<f64>,
    /// The q index of each v coordinate's joint ([`FREE`] on a free joint's
    /// six: no servo there).
    pub iq: Vec<usize>,
    /// The model's actuators' controls as last set (nu; `actuators.rs`).
    pub controls: DVector<f64>,
    /// The actuators' constant force per v coordinate, part of the applied
    /// torques (`actuators.rs`).
    pub ctrl_tau: DVector<f64>,
}

/// [`Servo::iq`] of a free joint's coordinate.
pub(crate) const FREE: usize = usize::MAX;

/// The servo's gains and targets as slices cut to nv (the per-dof loops of
/// [`Simulation::servo_free_velocity`]: no bounds test on a v-indexed entry).
struct Gains<'a> {
    kp: &'a [f64],
    kd: &'a [f64],
    q_ref: &'a [f64],
    v_ref: &'a [f64],
}

impl<'a> Gains<'a> {
    fn of(
        kp: &'a DVector<f64>,
        kd: &'a DVector<f64>,
        q_ref: &'a DVector<f64>,
        v_ref: &'a DVector<f64>,
        nv: usize,
    ) -> Self {
        Self {
            kp: &kp.as_slice()[..nv],
            kd: &kd.as_slice()[..nv],
            q_ref: q_ref.as_slice(),
            v_ref: &v_ref.as_slice()[..nv],
        }
    }
    /// [`Servo::torque`] on the cut slices.
    #[inline(always)]
    fn torque(&self, iq: usize, iv: usize, q: f64, v: f64) -> f64 {
        pd(
            self.kp[iv],
            self.kd[iv],
            self.q_ref[iq] - q,
            self.v_ref[iv] - v,
        )
    }
}

/// The servo law of one coordinate, τ = kp e_q + kd e_v from its errors
/// e_q = q_ref − q and e_v = v_ref − v.
#[inline(always)]
fn pd(kp: f64, kd: f64, e_q: f64, e_v: f64) -> f64 {
    kp * e_q + kd * e_v
}

impl Servo {
    /// No servo on `model`; `q_ref` starts at `q0`.
    pub fn new(model: &Model, q0: &DVector<f64>) -> Self {
        let nv = model.nv;
        let mut iq = vec![FREE; nv];
        for (_, jq, jv) in model.dof_indices() {
            iq[jv] = jq;
        }
        Self {
            iq,
            kp: DVector::zeros(nv),
            kd: DVector::zeros(nv),
            q_ref: q0.clone(),
            v_ref: DVector::zeros(nv),
            active: false,
            saturated: vec![0; nv],
            applied: DVector::zeros(nv),
            controls: DVector::zeros(model.actuators.len()),
            ctrl_tau: DVector::zeros(nv),
        }
    }

    /// The implicit diagonal c·kd + c²·kp of v coordinate `k` (0 when saturated
    /// or inactive), c the step (0: the explicit stiffness tests).
    #[inline(always)]
    pub fn diag(&self, k: usize, c: f64) -> f64 {
        if !self.active || self.saturated.get(k) != Some(&0) {
            return 0.0;
        }
        let (kd, kp) = (self.kd.as_slice(), self.kp.as_slice());
        c * kd[k] + c * c * kp[k]
    }

    /// τ_ff + the servo torque at (q, v) of v coordinate `k`, clamped to
    /// `effort` (the plain clamp without servos): the smooth right-hand side's
    /// applied torque.
    #[inline]
    pub fn rhs_torque(
        &self,
        tau_ff: f64,
        effort: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        k: usize,
    ) -> f64 {
        let mut t = tau_ff;
        let iq = self.iq[k];
        if self.active && iq != FREE {
            t += self.torque(iq, k, q[iq], v[k]);
        }
        t.clamp(-effort, effort)
    }

    /// The unclamped servo torque of v coordinate `iv` (q coordinate `iq`) at (q, v).
    #[inline(always)]
    pub fn torque(&self, iq: usize, iv: usize, q: f64, v: f64) -> f64 {
        // (slices: one bounds test an entry, not a matrix index's)
        let (kp, kd) = (self.kp.as_slice(), self.kd.as_slice());
        let (q_ref, v_ref) = (self.q_ref.as_slice(), self.v_ref.as_slice());
        pd(kp[iv], kd[iv], q_ref[iq] - q, v_ref[iv] - v)
    }
}

impl Simulation {
    /// Sets the servo gains per v coordinate (nv each; a floating base's six
    /// entries must be 0). Negative, non-finite or wrongly sized gains, or a
    /// nonzero gain on a base entry, are an error and nothing is set. Gains
    /// all 0 (the default) switch the servos off: the step is then bit for bit
    /// the one without servos.
    pub fn set_gains(&mut self, kp: &DVector<f64>, kd: &DVector<f64>) -> Result<(), SimError> {
        let nv = self.model.nv;
        for (name, g) in [("kp", kp), ("kd", kd)] {
            if g.len() != nv {
                return Err(SimError::Invalid(format!(
                    "{name} has {} entries, the model has nv = {nv}",
                    g.len()
                )));
            }
            for (k, &x) in g.iter().enumerate() {
                if !x.is_finite() || x < 0.0 {
                    return Err(SimError::Invalid(format!(
                        "{name}[{k}] must be a finite number ≥ 0 (got {x})"
                    )));
                }
                if self.servo.iq[k] == FREE && x != 0.0 {
                    return Err(SimError::Invalid(format!(
                        "{name}[{k}] is a floating-base entry: its gain must be 0 (got {x})"
                    )));
                }
            }
        }
        let s = &mut self.servo;
        s.kp.copy_from(kp);
        s.kd.copy_from(kd);
        s.active = kp.iter().chain(kd.iter()).any(|&x| x != 0.0);
        s.saturated.fill(0);
        self.forcing_changed = true;
        self.sleep.wake_pending = true;
        self.smooth.fsal_ok = false;
        Ok(())
    }

    /// Sets the same gains on every joint (base entries 0); see [`Simulation::set_gains`].
    pub fn set_gains_uniform(&mut self, kp: f64, kd: f64) -> Result<(), SimError> {
        let nv = self.model.nv;
        let iq = &self.servo.iq;
        let fill = |g: f64| DVector::from_fn(nv, |k, _| if iq[k] == FREE { 0.0 } else { g });
        self.set_gains(&fill(kp), &fill(kd))
    }

    /// Sets the servo targets: `q_ref` (nq; a floating base's part ignored) and
    /// `v_ref` (nv; `None`: zero). Wrong sizes or non-finite entries are an
    /// error and nothing is set. Targets persist across [`Simulation::set_state`].
    pub fn set_targets(
        &mut self,
        q_ref: &DVector<f64>,
        v_ref: Option<&DVector<f64>>,
    ) -> Result<(), SimError> {
        let (nq, nv) = (self.model.nq, self.model.nv);
        if q_ref.len() != nq {
            return Err(SimError::Invalid(format!(
                "q_ref has {} entries, the model has nq = {nq}",
                q_ref.len()
            )));
        }
        if let Some(k) = q_ref.iter().position(|x| !x.is_finite()) {
            return Err(SimError::Invalid(format!(
                "q_ref[{k}] is not a finite number ({})",
                q_ref[k]
            )));
        }
        if let Some(v) = v_ref {
            if v.len() != nv {
                return Err(SimError::Invalid(format!(
                    "v_ref has {} entries, the model has nv = {nv}",
                    v.len()
                )));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(SimError::Invalid(format!(
                    "v_ref[{k}] is not a finite number ({})",
                    v[k]
                )));
            }
        }
        let s = &mut self.servo;
        s.q_ref.copy_from(q_ref);
        match v_ref {
            Some(v) => s.v_ref.copy_from(v),
            None => s.v_ref.fill(0.0),
        }
        self.forcing_changed = true;
        self.sleep.wake_pending = true;
        self.smooth.fsal_ok = false;
        Ok(())
    }

    /// The servo gains (kp, kd), nv each.
    pub fn gains(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.servo.kp, &self.servo.kd)
    }
    /// The servo targets (q_ref: nq, v_ref: nv).
    pub fn targets(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.servo.q_ref, &self.servo.v_ref)
    }
    /// Whether a servo gain is nonzero.
    pub fn has_servos(&self) -> bool {
        self.servo.active
    }
    /// The generalized forces the last step applied (nv): τ_ff plus the servo
    /// torque, each joint's clamped to its effort limit; with implicit servos
    /// their end-of-step value, for a smooth (RK, adaptive) step the last
    /// stage's; a floating base's entries as set. Zero before the first step.
    pub fn applied_torques(&self) -> &DVector<f64> {
        &self.servo.applied
    }

    /// The free velocity with servos (the servo form of
    /// [`Simulation::free_velocity`]'s dense branch):
    /// v* = v + h H̃⁻¹(u − C − D v) with H̃ = H + A + h D + h Kd + h² Kp on the
    /// free joints and u = τ_ff + e (e the servo's explicit part), or ±effort on
    /// the saturated ones; the saturated set grows until no free joint's torque
    /// at v* passes its limit.
    pub(in crate::sim) fn servo_free_velocity(&mut self, h: f64) -> Result<(), SimError> {
        let nv = self.model.nv;
        // C(q, v), as the dense branch of free_velocity computes it
        let mut c = std::mem::replace(&mut self.mass.vtot, DVector::zeros(0));
        let r = if self.fk_valid && self.v.len() == nv {
            bias_at_placements(&self.model, &mut self.data, &self.v);
            Ok(&self.data.bias)
        } else {
            bias(&self.model, &mut self.data, &self.q, &self.v, None)
        };
        let r = r.map(|b| c.copy_from(b)).map_err(SimError::from);
        if let Err(e) = r {
            self.mass.vtot = c;
            return Err(e);
        }
        // (the per-dof loops below read slices cut to nv: one bounds test an
        // entry at most, where a DVector's index tests a matrix shape)
        let s = &mut self.servo;
        let (kp, kd) = (&s.kp.as_slice()[..nv], &s.kd.as_slice()[..nv]);
        let (effort, tau_ff) = (&self.effort[..nv], &self.tau_applied.as_slice()[..nv]);
        // start with the joints whose servo has no gain and whose τ_ff passes
        // the limit saturated (the plain clamp), every servoed joint free
        for (k, sat) in s.saturated[..nv].iter_mut().enumerate() {
            let (e, t) = (effort[k], tau_ff[k]);
            let servoed = kp[k] != 0.0 || kd[k] != 0.0;
            *sat = if !servoed && t.abs() > e {
                t.signum() as i8
            } else {
                0
            };
        }
        let mut tau = std::mem::replace(&mut self.mass.tau, DVector::zeros(0));
        let mut result = Ok(());
        for _pass in 0..=nv.min(8) {
            // u − C − D v, u = τ_ff + e on free joints, ±effort on saturated ones
            {
                let s = &self.servo;
                let (q, v) = (self.q.as_slice(), &self.v.as_slice()[..nv]);
                let (cs, damping) = (&c.as_slice()[..nv], &self.damping.as_slice()[..nv]);
                let (effort, tau_ff) = (&self.effort[..nv], &self.tau_applied.as_slice()[..nv]);
                let (sat, iqs) = (&s.saturated[..nv], &s.iq[..nv]);
                let g = Gains::of(&s.kp, &s.kd, &s.q_ref, &s.v_ref, nv);
                let kp = g.kp;
                for (k, tk) in tau.as_mut_slice()[..nv].iter_mut().enumerate() {
                    let u = match sat[k] {
                        0 => {
                            // τ_ff + e, e = kp (q_ref − q − h v) + kd (v_ref − v) (0 on base entries)
                            let iq = iqs[k];
                            let e = if iq == FREE {
                                0.0
                            } else {
                                g.torque(iq, k, q[iq], v[k]) - h * kp[k] * v[k]
                            };
                            tau_ff[k] + e
                        }
                        sg => f64::from(sg) * effort[k],
                    };
                    *tk = u - cs[k] - damping[k] * v[k];
                }
            }
            if let Err(e) = self.factor_mass(h) {
                result = Err(e);
                break;
            }
            self.mass.f.solve(&mut tau);
            self.mass.vfree.copy_from(&self.v);
            self.mass.vfree.axpy(h, &tau, 1.0);
            // a free joint whose torque at v* passes its limit is saturated
            let mut grew = false;
            let s = &mut self.servo;
            let g = Gains::of(&s.kp, &s.kd, &s.q_ref, &s.v_ref, nv);
            let (iqs, saturated) = (&s.iq[..nv], &mut s.saturated[..nv]);
            let (q, vfree) = (self.q.as_slice(), &self.mass.vfree.as_slice()[..nv]);
            let (effort, tau_ff) = (&self.effort[..nv], &self.tau_applied.as_slice()[..nv]);
            for k in 0..nv {
                let iq = iqs[k];
                if iq == FREE || saturated[k] != 0 || !effort[k].is_finite() {
                    continue;
                }
                // τ_ff + the servo torque at q⁺ ≈ q + h v*, v⁺ = v*
                let v1 = vfree[k];
                let t = tau_ff[k] + g.torque(iq, k, q[iq] + h * v1, v1);
                if t.abs() > effort[k] {
                    saturated[k] = t.signum() as i8;
                    grew = true;
                }
            }
            if !grew {
                break;
            }
        }
        let mut applied = std::mem::replace(&mut self.servo.applied, DVector::zeros(0));
        let s = &self.servo;
        let g = Gains::of(&s.kp, &s.kd, &s.q_ref, &s.v_ref, nv);
        let (iqs, saturated) = (&s.iq[..nv], &s.saturated[..nv]);
        let (q, vfree) = (self.q.as_slice(), &self.mass.vfree.as_slice()[..nv]);
        let (effort, tau_ff) = (&self.effort[..nv], &self.tau_applied.as_slice()[..nv]);
        for (k, a) in applied.as_mut_slice()[..nv].iter_mut().enumerate() {
            let iq = iqs[k];
            *a = match saturated[k] {
                0 if iq != FREE => {
                    let v1 = vfree[k];
                    tau_ff[k] + g.torque(iq, k, q[iq] + h * v1, v1)
                }
                0 => tau_ff[k],
                sg => f64::from(sg) * effort[k],
            };
        }
        self.servo.applied = applied;
        self.mass.tau = tau;
        self.mass.vtot = c;
        result
    }
}
