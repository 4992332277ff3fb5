//! The derivatives of one simulation step (docs/theory.md §"Transition
//! Jacobians"): A = ∂x'/∂x and B = ∂x'/∂τ_ff of the step a new [`Simulation`]
//! with the same settings, gains and targets makes from (q, v) with joint
//! torques τ_ff, in the tangent space: x = (q, v), δx = [δq; δv] with
//! q ⊕ δq ([`integrate`]) and δq' = q'₀ ⊖ q' ([`difference`]).
//!
//! - [`JacobianMethod::Forward`] and [`JacobianMethod::Central`]: finite
//!   differences of that step, one step per column (forward) or two
//!   (central), as MuJoCo's `mjd_transitionFD` (`fd.rs`);
//! - [`JacobianMethod::Analytic`]: the step's own chain rule (`analytic.rs`).
//!
//! A step is one step of `dt` (an adaptive integrator's steps up to `dt`).
//! Nothing of the simulation called on changes: the work is done on a copy,
//! made at the first call and kept by the simulation (`Workspace`) for the
//! next ones, which copy into it only what may have changed since (the servos'
//! gains and targets; a new model makes a new copy).

mod analytic;
mod fd;
mod output;
mod position;
mod second_order;
mod smooth;

use crate::model::configuration::{difference, integrate};
use crate::sim::servo::FREE;
use crate::sim::{SimError, Simulation};
use nalgebra::{DMatrix, DVector};
use std::sync::{Arc, Mutex, TryLockError};

/// The copy of a simulation its transition Jacobians are computed in, kept
/// between calls (a clone of the simulation starts without one; a call that
/// finds it in use by another thread works in a copy of its own); and, in
/// that copy, the analytic route's scratch matrices, sized at its first call
/// and reused (nothing in them is carried from one call to the next).
#[derive(Default)]
pub(in crate::sim) struct Workspace {
    slot: Mutex<Option<Box<Simulation>>>,
    scratch: analytic::Scratch,
}

impl Clone for Workspace {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Workspace")
    }
}

/// How [`Simulation::transition_jacobians`] differentiates the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum JacobianMethod {
    /// Through the step's own equations (docs/theory.md §"Transition Jacobians").
    #[default]
    Analytic,
    /// Forward differences: one step per column, error O(ε).
    Forward,
    /// Central differences: two steps per column, error O(ε²).
    Central,
}

impl JacobianMethod {
    /// Every method, by name.
    pub const ALL: [JacobianMethod; 3] = [
        JacobianMethod::Analytic,
        JacobianMethod::Forward,
        JacobianMethod::Central,
    ];
    /// The name (`"analytic"`, `"forward"`, `"central"`).
    pub fn name(self) -> &'static str {
        match self {
            JacobianMethod::Analytic => "analytic",
            JacobianMethod::Forward => "forward",
            JacobianMethod::Central => "central",
        }
    }
    /// The method of a name; `None` for an unknown one.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// The transition Jacobians of one step: `a` (2nv × 2nv), `b` (2nv × nv).
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionJacobians {
    /// ∂x'/∂x, x = (q, v) in the tangent space.
    pub a: DMatrix<f64>,
    /// ∂x'/∂τ_ff (a floating base's six columns zero).
    pub b: DMatrix<f64>,
}

impl Simulation {
    /// The transition Jacobians of one step of `dt` from the current (q, v)
    /// with joint torques `tau` (nv; a floating base's six entries ignored, as
    /// the step ignores them), the step being the one a new simulation with
    /// these settings, gains and targets would make (no contact points or warm
    /// starts carried from earlier steps). `eps`: the finite differences' step
    /// (unused by the analytic method). The simulation is not changed.
    pub fn transition_jacobians(
        &self,
        tau: &DVector<f64>,
        method: JacobianMethod,
        eps: f64,
    ) -> Result<TransitionJacobians, SimError> {
        let mut slot = match self.deriv.slot.try_lock() {
            Ok(s) => s,
            Err(TryLockError::Poisoned(p)) => p.into_inner(),
            Err(TryLockError::WouldBlock) => {
                let mut work = self.derivative_workspace();
                return work.transition_jacobians_at(&self.q, &self.v, tau, method, eps);
            }
        };
        let work = match slot.as_mut() {
            Some(w) if w.answers_for(self) => w,
            _ => slot.insert(Box::new(self.derivative_workspace())),
        };
        work.copy_settings(self);
        work.transition_jacobians_at(&self.q, &self.v, tau, method, eps)
    }

    /// Whether this workspace of `from` still answers as a new copy would: the
    /// same model, and the same pairs of bodies dropped for overlapping at the
    /// start (decided anew at each state set before the first step: a copy of
    /// a simulation that has stepped keeps its decision, which the workspace
    /// has when it was made after that decision).
    fn answers_for(&self, from: &Simulation) -> bool {
        fn dropped(s: &Simulation) -> Option<&[crate::contact::DroppedPair]> {
            s.contact.as_ref().map(|c| &c.dropped[..])
        }
        Arc::ptr_eq(&self.model, &from.model) && (from.steps == 0 || dropped(self) == dropped(from))
    }

    /// The settings of `from` that change after construction (the servos'
    /// gains and targets), copied into this workspace of it.
    fn copy_settings(&mut self, from: &Simulation) {
        let (s, f) = (&mut self.servo, &from.servo);
        s.kp.copy_from(&f.kp);
        s.kd.copy_from(&f.kd);
        s.q_ref.copy_from(&f.q_ref);
        s.v_ref.copy_from(&f.v_ref);
        s.active = f.active;
        // before the first step the pairs' start overlaps are decided at the state
        self.steps = from.steps;
    }

    /// A copy of this simulation to compute transition Jacobians in (see
    /// [`Simulation::transition_jacobians_at`]); a batch makes one per thread.
    pub fn derivative_workspace(&self) -> Simulation {
        let mut work = self.clone();
        // a perturbed step is not a passive run to guard
        work.opts.max_energy_rise = None;
        // a new simulation cannot fall asleep within its first `dt` (an
        // island sleeps after `sleep_time` still): the workspace skips the
        // sleep test, whose stillness timers would otherwise run on from one
        // call to the next
        if work.opts.sleep_time > work.dt {
            work.sleep.on = false;
        }
        work
    }

    /// [`Simulation::transition_jacobians`] at (q, v), computed in this
    /// simulation, which is left in an unspecified state (a workspace from
    /// [`Simulation::derivative_workspace`]). Bad sizes or non-finite entries
    /// are an error.
    pub fn transition_jacobians_at(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
        tau: &DVector<f64>,
        method: JacobianMethod,
        eps: f64,
    ) -> Result<TransitionJacobians, SimError> {
        let nv = self.model.nv;
        if tau.len() != nv || !tau.iter().all(|x| x.is_finite()) {
            return Err(SimError::Invalid(format!(
                "tau of size {} (the model needs nv = {nv}), finite",
                tau.len()
            )));
        }
        if method != JacobianMethod::Analytic && !(eps > 0.0 && eps.is_finite()) {
            return Err(SimError::Invalid(format!(
                "eps must be a positive number (got {eps})"
            )));
        }
        self.fresh_state(q, v)?;
        match method {
            JacobianMethod::Analytic => match self.analytic_jacobians(tau)? {
                Some(j) => Ok(j),
                // where the analytic route does not reach: central differences
                None => self.fd_jacobians(q, v, tau, true, 1e-6),
            },
            JacobianMethod::Forward | JacobianMethod::Central => {
                self.fd_jacobians(q, v, tau, method == JacobianMethod::Central, eps)
            }
        }
    }

    /// The state of a new simulation set to (q, v): time 0, the adaptive step
    /// at `dt`, the contact detection's history as built and then at the
    /// neutral configuration (as `new` leaves it), warm starts forgotten.
    pub(in crate::sim) fn fresh_state(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
    ) -> Result<(), SimError> {
        self.t = 0.0;
        self.smooth.h_next = self.dt;
        // (without contact the state set first leaves nothing behind)
        if let Some(c) = self.contact.as_mut() {
            c.forget_history();
            self.q = self.model.neutral();
            self.v.as_mut_slice().fill(0.0);
            self.state_changed();
        }
        self.set_state(q, v)
    }

    /// One step of `dt` from a fresh (q, v) with joint torques `tau` (base part
    /// ignored); returns (q', v').
    pub(in crate::sim) fn fresh_step(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
        tau: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), SimError> {
        self.fresh_state(q, v)?;
        self.set_joint_torques(tau);
        let dt = self.dt;
        while self.t < dt {
            self.step_until(dt)?;
        }
        Ok((self.q.clone(), self.v.clone()))
    }

    /// The applied torques: `tau`'s joint entries, the floating base's zero.
    pub(in crate::sim) fn set_joint_torques(&mut self, tau: &DVector<f64>) {
        let n = tau.len().min(self.tau_applied.len());
        self.torques_mut();
        for k in 0..n {
            self.tau_applied[k] = if self.servo.iq[k] == FREE {
                0.0
            } else {
                tau[k]
            };
        }
    }
}

/// q ⊕ δq (sizes are the model's: checked by the callers).
pub(in crate::sim) fn plus(sim: &Simulation, q: &DVector<f64>, dq: &DVector<f64>) -> DVector<f64> {
    integrate(&sim.model, q, dq).unwrap_or_else(|_| q.clone())
}

/// q₁ ⊖ q₀.
pub(in crate::sim) fn minus(
    sim: &Simulation,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> DVector<f64> {
    difference(&sim.model, q0, q1).unwrap_or_else(|_| DVector::zeros(sim.model.nv))
}
