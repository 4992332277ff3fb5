//! A [`Simulation`]'s state and its read-outs: time, (q, v), applied torques,
//! energy; what a new state resets.

use super::*;

impl Simulation {
    /// The integrator in use (`SimOptions::integrator`, or the scene's default).
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }
    /// The constraint solve's work so far: rows times sweeps, summed over the
    /// islands and the steps (velocity solve, its energy-safe exit and the
    /// position pass). A measure of cost that does not depend on the machine:
    /// two piles far apart cost twice one pile.
    pub fn solve_work(&self) -> u64 {
        self.cons.work
    }
    /// Simulated time (s), 0 at construction.
    pub fn time(&self) -> f64 {
        self.t
    }
    /// Sets the simulated time (s); the state is untouched.
    pub fn set_time(&mut self, t: f64) {
        self.t = t;
    }
    /// The step (s): every step's for a fixed-step integrator, the first for `dop853`.
    pub fn dt(&self) -> f64 {
        self.dt
    }
    /// The options it was built with.
    pub fn options(&self) -> &SimOptions {
        &self.opts
    }
    /// Configuration (nq): with a floating base, position (m, world) and
    /// quaternion (x, y, z, w) first, then the joints (rad or m).
    pub fn q(&self) -> &DVector<f64> {
        &self.q
    }
    /// Velocity (nv): with a floating base, linear (m/s) and angular (rad/s)
    /// velocity in the body frame first, then the joint rates (rad/s or m/s).
    pub fn v(&self) -> &DVector<f64> {
        &self.v
    }
    /// Sets the state (a floating base's quaternion is normalised). Wrong lengths
    /// or non-finite values are an error. The divergence test's reference is
    /// taken anew from this state (after its violations are recovered).
    pub fn set_state(&mut self, q: &DVector<f64>, v: &DVector<f64>) -> Result<(), SimError> {
        if q.len() != self.model.nq || v.len() != self.model.nv {
            return Err(SimError::Invalid(format!(
                "state of sizes ({}, {}) for a model with nq = {}, nv = {}",
                q.len(),
                v.len(),
                self.model.nq,
                self.model.nv
            )));
        }
        if !q.iter().chain(v.iter()).all(|x| x.is_finite()) {
            return Err(SimError::Invalid("non-finite state".into()));
        }
        self.q.copy_from(q);
        self.v.copy_from(v);
        normalize_quats(&self.model, &mut self.q);
        self.state_changed();
        Ok(())
    }

    /// After the state was set: warm starts forgotten, contacts found, the
    /// divergence reference reset (recovery first where the state violates a
    /// constraint).
    pub(super) fn state_changed(&mut self) {
        self.sensors.forget();
        self.smooth.fsal_ok = false;
        self.cons.reset_warm_start();
        self.sleep.wake_all(&self.model);
        // (C computed ahead with sleeping trees left out: not this state's)
        self.data.step_bias_ok = false;
        if self.steps == 0 {
            self.decide_start_overlaps();
        }
        self.refresh_contacts();
        let loops_open = self.restart_loops();
        self.guard.reference = None;
        self.guard.recovering_until = if !self.violates() && !loops_open {
            // the reference is read only by the divergence test of a passive
            // run (`check_energy`): a run without it (a derivative workspace)
            // skips the energy
            if self.opts.max_energy_rise.is_some() {
                let e = self.update_energy();
                if e.is_finite() {
                    self.guard.reference = Some(e);
                    self.guard.v_ref.copy_from(&self.v);
                }
            }
            None
        } else {
            Some(self.t + 2.0)
        };
    }

    /// Whether the state violates a constraint ([`Simulation::start_violations`]
    /// non-empty), found without building the list (a scene's models all at
    /// the origin at construction overlap pairwise).
    pub(super) fn violates(&self) -> bool {
        let (depth, excess) = self.worst_violation();
        (self.contact.is_some() && depth > self.opts.contact.margin) || excess > 1e-9
    }

    /// The applied generalized forces (joint torques; with a floating base the first
    /// six are the base force and torque, body frame). Joint entries are clamped to
    /// their effort limits when used.
    pub fn torques_mut(&mut self) -> &mut DVector<f64> {
        self.forcing_changed = true;
        self.sleep.wake_pending = true;
        &mut self.tau_applied
    }
    /// The applied generalized forces (nv) as set, before clamping to effort limits.
    pub fn torques(&self) -> &DVector<f64> {
        &self.tau_applied
    }
    /// Sets the applied generalized forces (as [`Simulation::torques_mut`]), their
    /// length (nv) and finiteness checked: a wrong length is an error, nothing set.
    pub fn set_torques(&mut self, tau: &DVector<f64>) -> Result<(), SimError> {
        if tau.len() != self.model.nv || !tau.iter().all(|x| x.is_finite()) {
            return Err(SimError::Invalid(format!(
                "torques of size {} (the model needs nv = {}), finite",
                tau.len(),
                self.model.nv
            )));
        }
        self.torques_mut().copy_from(tau);
        Ok(())
    }
    /// Kinetic plus gravitational potential energy (J), the potential being
    /// −Σ mᵢ gᵀcᵢ (zero at the world origin); with an armature, its rotors'
    /// ½ A v² is kinetic energy too. The value the step's energy guard computed
    /// when there is one (no work, no allocation), else computed afresh from
    /// (q, v) with a small per-body scratch ([`crate::dynamics::energies`]).
    pub fn energy(&self) -> f64 {
        if let Some(e) = self.energy_now {
            return e;
        }
        let (ke, pe) = crate::dynamics::energies(&self.model, &self.q, &self.v)
            .unwrap_or((f64::NAN, f64::NAN));
        ke + pe + self.armature_energy() + self.spring_energy()
    }

    /// The joint springs' potential `½ Σ k (q − springref)²` (MJCF `stiffness`;
    /// 0 without springs).
    pub(super) fn spring_energy(&self) -> f64 {
        let mut e = 0.0;
        if !self.guard.springs {
            return e;
        }
        for d in &self.model.dofs {
            if d.stiffness > 0.0 && d.stiffness.is_finite() && d.kind.nv() == 1 {
                let x = self.q[d.iq] - d.springref;
                e += 0.5 * d.stiffness * x * x;
            }
        }
        e
    }

    /// The rotors' kinetic energy `½ Σ A v²` (0 without an armature).
    pub(super) fn armature_energy(&self) -> f64 {
        if !self.has_armature {
            return 0.0;
        }
        let mut e = 0.0;
        for (a, v) in self.armature.as_slice().iter().zip(self.v.as_slice()) {
            e += 0.5 * a * v * v;
        }
        e
    }

    /// [`Simulation::energy`], cached until the state changes (the energy guard's
    /// path: the poses of the last contact refresh reused).
    pub(super) fn update_energy(&mut self) -> f64 {
        if let Some(e) = self.energy_now {
            return e;
        }
        // the world poses are current when the contact refresh at the end of
        // the last step (or a previous call) computed them at this q
        if !self.fk_valid {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        // v has nv entries (the simulation's own state): no size error
        // (the sleeping trees' bodies left out of the pass: at rest, no kinetic
        // energy, and their C is not used while they sleep; `wake` drops the C
        // computed ahead)
        let skip = self.sleep.bodies_asleep();
        let e = kinetic_energy_step_ahead(&self.model, &mut self.data, &self.q, &self.v, skip)
            + potential_energy(&self.model, &self.data)
            + self.armature_energy()
            + self.spring_energy();
        self.energy_now = Some(e);
        e
    }

    /// Before the first step: the self pairs overlapping at this state are
    /// dropped (scene.md "Who touches whom" rule 4; decided anew at each state
    /// set before the run starts).
    pub(super) fn decide_start_overlaps(&mut self) {
        let Some(c) = self.contact.as_mut() else {
            return;
        };
        if c.pairs.is_none() {
            return;
        }
        forward_kinematics(&self.model, &mut self.data, &self.q);
        c.drop_start_overlaps(&self.model, &self.data.o_m_i);
    }
}
