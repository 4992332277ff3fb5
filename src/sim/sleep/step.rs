//! Sleep's part of a step (src/sim/sleep.rs): the islands an awake body
//! touches woken, the body velocities the still test reads, and the count
//! after the step (driven trees, still times, islands put to sleep).

impl super::super::Simulation {
    /// Sleep's work at the end of a step of `h`: islands that an awake body
    /// touches woken (their contacts found), then the still islands put to sleep.
    pub(in crate::sim) fn update_sleep(&mut self, h: f64) {
        if !self.sleep.on {
            self.sleep.after_step(
                &self.model,
                h,
                &[],
                &[],
                &self.q,
                &mut self.v,
                &mut self.points,
                &[],
                &[],
            );
            return;
        }
        // (a point with no side asleep or dozing wakes nothing: one scan
        // tells whether any has one)
        while self.sleep.touches_masked(&self.points)
            && (self.sleep.wake_touched(&self.model, &self.points)
                | self.sleep.undoze_touched(&self.model, &self.points))
        {
            self.refresh_contacts();
        }
        if !self.fk_valid {
            crate::dynamics::forward_kinematics_pass(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        // body velocities (body frame) from the poses' joint transforms, the
        // position pass's push included (a point pushed out moves)
        let model = &self.model;
        let data = &mut self.data;
        // (v itself without a push: no copy)
        let vw = match self.cons.push_velocity() {
            Some(w) => {
                crate::sim::step::plus_into(&mut self.sleep.vw, &self.v, w);
                self.sleep.vw.as_slice()
            }
            None => self.v.as_slice(),
        };
        // (the awake trees' bodies: a tree's bodies are one range after their
        // parents, whose root hangs from the world; sleeping ones are not read)
        // (a body on the world: its parent's velocity is zero, moved into its
        // frame a zero but for the signs of its zeros; these velocities are
        // read only by the speed tests' norms, here and in a dozing step's
        // `account_sleep`, until the energy pass writes them anew)
        // (the joint kind matched by the key `data.dispatch` keeps for each
        // body, not found again from the joint at each use)
        use crate::model::JointModel as _;
        data.v[0] = crate::spatial::Motion::zero();
        if data.lone_free {
            // (every body a free body on the world: v̂ᵢ = 0 + ŝᵢ q̇ᵢ, no
            // parent's velocity and no joint kind to match)
            for &t in self.sleep.awake_trees() {
                for i in model.trees[t].bodies.clone() {
                    let mut vi = crate::spatial::Motion::zero();
                    crate::model::joint::FreeJ {
                        j: &model.joints[i],
                    }
                    .add_motion(&mut vi, vw);
                    data.v[i] = vi;
                }
            }
            self.account_sleep(h);
            return;
        }
        for &t in self.sleep.awake_trees() {
            let tree = &model.trees[t];
            for i in tree.bodies.clone() {
                let p = model.parent[i];
                let mut vi = match p {
                    0 => crate::spatial::Motion::zero(),
                    _ => data.li_m_i[i].inv_act_motion(&data.v[p]),
                };
                match data.dispatch.get(i) {
                    Some(&key) => crate::model::dispatch_keyed!(
                        &model.joints[i], key, false, jm => jm.add_motion(&mut vi, vw)
                    ),
                    None => crate::model::dispatch_joint!(
                        &model.joints[i], false, jm => jm.add_motion(&mut vi, vw)
                    ),
                }
                data.v[i] = vi;
            }
        }
        self.account_sleep(h);
    }

    /// The awake trees driven now (`sleep_forced`): a nonzero applied force,
    /// or a servo on one of its dofs (each tree's dofs one range: a slice
    /// test of each vector).
    fn mark_forced(&mut self) {
        let tau = self.tau_applied.as_slice();
        let servo = self
            .servo
            .active
            .then(|| (self.servo.kp.as_slice(), self.servo.kd.as_slice()));
        for &t in self.sleep.awake_trees() {
            let r = self.model.trees[t].v.clone();
            let set = |x: &[f64]| {
                x.get(r.clone())
                    .is_some_and(|x| x.iter().any(|&x| x != 0.0))
            };
            self.sleep_forced[t] = set(tau) || servo.is_some_and(|(kp, kd)| set(kp) || set(kd));
        }
    }

    /// Sleep's count after a step of `h` from the body velocities in
    /// `data.v` (set by `Simulation::update_sleep`; held through a dozing
    /// step, `Simulation::dozing_step`): the driven trees, the still times,
    /// the islands that fall asleep, the new dozes' warm starts kept aside.
    pub(in crate::sim) fn account_sleep(&mut self, h: f64) {
        // trees driven now (read for the awake trees only); with no applied
        // force and no servo, the common case, none: found by one pass over
        // tau instead of a slice test a tree (`mark_forced`)
        let tau = self.tau_applied.as_slice();
        if !self.servo.active && !crate::sim::step::any_nonzero(tau) {
            // (the sleeping trees' entries are not read: each is set here
            // again before its tree is counted awake)
            self.sleep_forced.fill(false);
        } else {
            self.mark_forced();
        }
        let slept = self.sleep.after_step(
            &self.model,
            h,
            &self.data.v,
            &self.sleep_forced,
            &self.q,
            &mut self.v,
            &mut self.points,
            self.cons.contact_forces(),
            self.cons.body_forces(),
        );
        if slept {
            self.energy_now = None;
        }
        if !self.sleep.doze.new_slots.is_empty() {
            self.cons.hold_warm(&self.sleep.doze.held);
            self.sleep.doze.unhold();
        }
        self.sleep.compose();
    }
}
