//! One step of a [`Simulation`], by stage: wake what must wake, the constraint
//! rows, the step (time stepping or the integrator), the new state's
//! contacts, sleep and the energy guard.

use super::*;

impl Simulation {
    /// Forward kinematics and contact detection at the current q.
    pub(super) fn refresh_contacts(&mut self) {
        self.fk_valid = false;
        self.energy_now = None;
        if let Some(c) = self.contact.as_mut() {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            // (the pairs' narrow phase on the team: the same points)
            let run = self
                .cons
                .team()
                .map(|t| t as &dyn crate::contact::pairs::Runner);
            let asleep = &self.sleep.body_asleep;
            c.detect_on(&self.data.o_m_i, &mut self.points, asleep, run);
            self.fk_valid = true;
        }
    }

    /// One step of at most `dt` (fixed-step integrators take exactly `dt`; an
    /// adaptive one its own accepted step). Returns the step taken.
    pub fn step(&mut self) -> Result<f64, SimError> {
        self.step_until(f64::INFINITY)
    }

    /// One step that does not pass `t_end` (the last step is shortened to land
    /// on it; a sliver shorter than a tenth of the step is merged into it).
    pub fn step_until(&mut self, t_end: f64) -> Result<f64, SimError> {
        let remaining = t_end - self.t;
        if !(remaining > 0.0) {
            return Ok(0.0);
        }
        let h_fixed = land(self.dt, remaining);
        if self.sleep.wake_pending {
            self.wake();
        }
        self.sensors.begin(&self.q, &self.v);
        if self.sleep.all_asleep() {
            // everything sleeps: the state stands, time passes
            self.t = if h_fixed >= remaining {
                t_end
            } else {
                self.t + h_fixed
            };
            self.sensors.end(h_fixed);
            self.steps += 1;
            self.sleep.count_idle_step();
            return Ok(h_fixed);
        }
        if self.sleep.quiet_dozing(&self.points) {
            // every awake tree dozes through this step (`doze`)
            return self.dozing_step(h_fixed, remaining, t_end);
        }
        // 1. the constraint rows at the start of the step (contact points were
        //    found at this q by the last step's refresh): a joint that can
        //    reach its limit within the step has a row
        let counts = self.assemble_rows(h_fixed);
        // 2. the step: time stepping when anything touches or the damping is
        //    too stiff for the explicit integrator even at dt, else the
        //    integrator; an adaptive step is capped so that no joint can reach a
        //    limit within it (it approaches in shorter steps, and the impact is
        //    taken by time stepping) and so that damping stays explicit-stable
        let mut time_stepping =
            self.integrator == Integrator::SemiImplicitEuler || counts.touching();
        let mut h_max = f64::INFINITY;
        if !time_stepping && (self.has_damping || self.servo.active) {
            let rate = self.damping_rate()?;
            let limit = integrators::explicit_limit(self.integrator);
            time_stepping = rate * h_fixed > limit;
            h_max = limit / rate;
        }
        if !time_stepping {
            h_max = h_max.min(self.limit_reach_cap());
        }
        let h = if self.sleep.all_dozing() {
            // every awake tree dozes (`doze`): their step is `doze_step`'s
            // (the last solve's forces stand, as a sleeping island's do)
            self.smooth.fsal_ok = false;
            h_fixed
        } else if time_stepping {
            self.euler_step(h_fixed, counts.total() > 0)?;
            self.smooth.fsal_ok = false;
            h_fixed
        } else {
            match self.integrator {
                Integrator::Rk4 => {
                    self.rk4_step(h_fixed, counts.friction > 0)?;
                    h_fixed
                }
                _ => self.dop853_step(remaining, h_max, counts.friction > 0)?,
            }
        };
        // 3. the new state: finite, its contacts, its energy
        self.advance(h, remaining, t_end)?;
        self.refresh_contacts();
        if self.cons.loops.is_some() {
            self.project_loops();
            self.clip_loop_energy();
        }
        self.update_sleep(h);
        self.check_energy()?;
        Ok(h)
    }

    /// A step of `h` in which every awake tree dozes and none stops
    /// (`Sleep::quiet_dozing`): their `doze_step` and sleep's count, no
    /// more. Every body is asleep or dozing before and after it, so the
    /// detection would search nothing (its list stays empty: the sleeping and
    /// dozing points are kept aside) and the dynamics has no row or tree to
    /// step; the last solve's forces stand. The energy guard is not run: the
    /// held velocities keep the kinetic energy, and the potential one moves by
    /// m g N h v at most (its next full step runs it); the bias computed
    /// ahead is dropped (the rnea checks q and v anyway).
    ///
    /// Skipping the detection finds the same points (none) but leaves the
    /// pair phase's own history (its broad-phase boxes, the pairs' kept
    /// features) a step or more behind: on the mixed piles the full step that
    /// follows can round differently (round 23: pile_mixed_16's final energy
    /// 9.649936098 → 9.649936140 J, 13 of 20 perturbed copies differ in the
    /// 8th–9th digit, mean awake and deepest penetration equal on all; the
    /// box piles byte-identical). With the detection run here it is
    /// byte-identical, and saves a quarter of what it saves without.
    pub(super) fn dozing_step(
        &mut self,
        h: f64,
        remaining: f64,
        t_end: f64,
    ) -> Result<f64, SimError> {
        self.smooth.fsal_ok = false;
        self.advance(h, remaining, t_end)?;
        self.energy_now = None;
        self.data.step_bias_ok = false;
        // (sleep's count on the body velocities of the last full step: a
        // dozing tree's speed is held, and no tree is awake but the dozing ones)
        self.account_sleep(h);
        Ok(h)
    }

    /// The end of a step of `h` (to `t_end` when `h` covers `remaining`):
    /// time and sensors, the sleeping trees' q back to where they fell asleep
    /// and the dozing ones' `doze_step` before the quaternions are normalised
    /// (bit for bit), a finite state, the pose-dependent caches dropped, the
    /// contact pipeline told the step's travel.
    fn advance(&mut self, h: f64, remaining: f64, t_end: f64) -> Result<(), SimError> {
        self.t = if h >= remaining { t_end } else { self.t + h };
        self.sensors.end(h);
        self.steps += 1;
        self.sleep.hold(&self.model, &mut self.q, &mut self.v);
        self.sleep
            .doze_step(&self.model, h, &mut self.q, &mut self.v);
        normalize_quats(&self.model, &mut self.q);
        self.check_finite()?;
        self.fk_valid = false;
        if let Some(c) = self.contact.as_mut() {
            // the speculative margin measures this step's travel (its next
            // step may be the full dt)
            c.stepped(if h > 0.0 { (self.dt / h).max(1.0) } else { 1.0 });
        }
        Ok(())
    }

    /// The longest step in which no joint moving toward a limit can reach it
    /// at twice its current speed (+∞ when none moves toward one). A joint
    /// within reach at `dt` has a row already (the step is time stepping).
    pub(super) fn limit_reach_cap(&self) -> f64 {
        let mut cap = f64::INFINITY;
        if !self.opts.joint_dynamics {
            return cap;
        }
        for (d, iq, iv) in self.model.dof_indices() {
            let info = &self.model.dofs[d];
            if info.continuous {
                continue;
            }
            let (q, v) = (self.q[iq], self.v[iv]);
            let gap = match (v < 0.0, info.limits.lower, info.limits.upper) {
                (true, Some(lo), _) => q - lo,
                (false, _, Some(hi)) if v > 0.0 => hi - q,
                _ => continue,
            };
            cap = cap.min((gap - 1e-3).max(0.0) / (2.0 * v.abs()));
        }
        cap.max(self.dt)
    }

    /// The constraint rows at the current state for a step `h`.
    pub(super) fn assemble_rows(&mut self, h: f64) -> constraints::RowCounts {
        let counts = self.cons.assemble(
            &self.model,
            &self.data.o_m_i,
            &self.q,
            &self.v,
            &self.points,
            &self.row_params,
            &self.mass.f,
            h,
        );
        if self.cons.loops.is_none() {
            return counts;
        }
        // loop rows: after every other row, from the world poses at q
        if !self.fk_valid {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        self.cons.assemble_loops(
            &self.model,
            &self.data,
            &self.q,
            &self.v,
            &self.row_params,
            &self.mass.f,
            h,
        )
    }

    pub(super) fn check_finite(&self) -> Result<(), SimError> {
        // the common case in one branch-free pass (vector compares) before the
        // search for the first bad entry
        if all_finite(self.q.as_slice()) && all_finite(self.v.as_slice()) {
            return Ok(());
        }
        let bad_q = self.q.iter().position(|x| !x.is_finite());
        let bad_v = self.v.iter().position(|x| !x.is_finite());
        if bad_q.is_none() && bad_v.is_none() {
            return Ok(());
        }
        let (qn, vn) = column_names(&self.model);
        let quantity = match (bad_q, bad_v) {
            (Some(k), _) => qn.get(k).cloned().unwrap_or_else(|| format!("q[{k}]")),
            (_, Some(k)) => vn.get(k).cloned().unwrap_or_else(|| format!("v[{k}]")),
            _ => String::new(),
        };
        Err(SimError::NonFinite {
            t: self.t,
            quantity,
        })
    }

    /// The divergence test of a passive run (see the module doc).
    pub(super) fn check_energy(&mut self) -> Result<(), SimError> {
        let Some(bound) = self.opts.max_energy_rise else {
            return Ok(());
        };
        if self.servo.active || any_nonzero(self.tau_applied.as_slice()) {
            self.guard.reference = None;
            return Ok(());
        }
        if let Some(until) = self.guard.recovering_until {
            let (depth, excess) = self.worst_violation();
            let recovered =
                self.t >= until || (depth <= 1e-3 && excess <= 1e-3 && !self.loops_recovering());
            if !recovered {
                return Ok(());
            }
            self.guard.recovering_until = None;
        }
        let e = self.update_energy();
        if !e.is_finite() {
            return Err(SimError::NonFinite {
                t: self.t,
                quantity: "energy".into(),
            });
        }
        let Some(e_ref) = self.guard.reference else {
            self.guard.reference = Some(e);
            self.guard.v_ref.copy_from(&self.v);
            return Ok(());
        };
        let allowed = bound.relative * (e_ref.abs() + self.guard.scale) + bound.absolute;
        if e - e_ref <= allowed {
            return Ok(());
        }
        // the velocity coordinate that grew the most
        let mut k_max = 0;
        let mut growth = f64::NEG_INFINITY;
        for k in 0..self.v.len() {
            let g = self.v[k].abs() - self.guard.v_ref[k].abs();
            if g > growth {
                growth = g;
                k_max = k;
            }
        }
        let (_, vn) = column_names(&self.model);
        Err(SimError::Diverging {
            t: self.t,
            energy: e,
            reference: e_ref,
            quantity: vn
                .get(k_max)
                .cloned()
                .unwrap_or_else(|| format!("v[{k_max}]")),
        })
    }
}

/// Every entry finite, without an early exit: x − x is +0 for a finite x and
/// NaN for ±∞ or NaN, so a sum of them is +0 exactly when every entry is
/// finite, in any order — summed in four lanes side by side.
#[inline]
fn all_finite(x: &[f64]) -> bool {
    let mut s = [0.0f64; 4];
    let mut quads = x.chunks_exact(4);
    for c in &mut quads {
        for k in 0..4 {
            s[k] += c[k] - c[k];
        }
    }
    for &v in quads.remainder() {
        s[0] += v - v;
    }
    (s[0] + s[1]) + (s[2] + s[3]) == 0.0
}

/// Some entry non-zero (NaN counts), without an early exit: x ≠ ±0 exactly
/// when its bits but the sign are not all zero, so the bits shifted past the
/// sign are or-ed (an integer reduction, in vector lanes).
#[inline]
pub(in crate::sim) fn any_nonzero(x: &[f64]) -> bool {
    x.iter().fold(0u64, |any, v| any | (v.to_bits() << 1)) != 0
}

/// `out = a + b` entry by entry (the sum `out.copy_from(a); out += b` makes).
#[inline]
pub(in crate::sim) fn plus_into(out: &mut DVector<f64>, a: &DVector<f64>, b: &DVector<f64>) {
    let (o, a, b) = (out.as_mut_slice(), a.as_slice(), b.as_slice());
    debug_assert!(o.len() == a.len() && o.len() == b.len());
    for ((o, &a), &b) in o.iter_mut().zip(a).zip(b) {
        *o = a + b;
    }
}
