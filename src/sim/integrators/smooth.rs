//! What the smooth (higher-order) steps share: the right-hand side ẏ = f(y)
//! of the undamped system with the step's constant forcing, the state vector,
//! joint friction held over a step, and the limit projection after it.

use super::solve_rows;
use crate::dynamics::linalg::{chol_solve_slice, cholesky_fast};
use crate::dynamics::{bias, forward_dynamics, mass_matrix, DynamicsError};
use crate::model::configuration::{config_rate, normalize_quats};
use crate::sim::{SimError, Simulation};

/// Which state vector the right-hand side reads.
#[derive(Clone, Copy)]
pub(in crate::sim) enum RhsIn {
    Y,
    Stage,
    New,
}

impl Simulation {
    /// ẏ = f(y) into `k[out]`: q̇ from v, v̇ = (H + A)⁻¹(sat(τ) + τ_c − C − D v)
    /// (a smooth step is taken only where the damping is mild: [`super::damping`]).
    pub(in crate::sim) fn eval_rhs(&mut self, which: RhsIn, out: usize) -> Result<(), SimError> {
        self.rhs_evals += 1;
        let model = &self.model;
        let (nq, nv) = (model.nq, model.nv);
        let w = &mut self.smooth;
        let y = match which {
            RhsIn::Y => &w.y,
            RhsIn::Stage => &w.y_stage,
            RhsIn::New => &w.y_new,
        };
        w.qn.copy_from(&y.rows(0, nq));
        w.vv.copy_from(&y.rows(nq, nv));
        normalize_quats(model, &mut w.qn);
        for k in 0..nv {
            let (t, e) = (self.tau_applied[k], self.effort[k]);
            let applied = self.servo.rhs_torque(t, e, &w.qn, &w.vv, k);
            // the last stage's applied torque ([`Simulation::applied_torques`])
            self.servo.applied[k] = applied;
            w.tau[k] = applied + w.tau_c[k];
        }
        if self.has_damping {
            for k in 0..nv {
                w.tau[k] -= self.damping[k] * w.vv[k];
            }
        }
        let dy = &mut w.k[out];
        config_rate(model, &w.qn, y, &w.vv, dy);
        if self.has_armature {
            // (H + A) v̇ = τ − C by a dense factorisation
            let d = &mut w.data;
            bias(model, d, &w.qn, &w.vv, None)?;
            mass_matrix(model, d, &w.qn)?;
            for k in 0..nv {
                d.h[(k, k)] += self.armature[k];
                d.qdd[k] = w.tau[k] - d.bias[k];
            }
            cholesky_fast(&d.h, &mut d.chol)
                .map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)))?;
            chol_solve_slice(d.chol.as_slice(), nv, d.qdd.as_mut_slice());
            dy.rows_mut(nq, nv).copy_from(&d.qdd);
        } else {
            let a = forward_dynamics(model, &mut w.data, &w.qn, &w.vv, &w.tau, None)?;
            dy.rows_mut(nq, nv).copy_from(a);
        }
        Ok(())
    }

    pub(in crate::sim) fn load_y(&mut self) {
        let nq = self.model.nq;
        let w = &mut self.smooth;
        w.y.rows_mut(0, nq).copy_from(&self.q);
        w.y.rows_mut(nq, self.model.nv).copy_from(&self.v);
    }

    pub(in crate::sim) fn store_y(&mut self, from_new: bool) {
        let nq = self.model.nq;
        let w = &self.smooth;
        let src = if from_new { &w.y_new } else { &w.y };
        self.q.copy_from(&src.rows(0, nq));
        self.v.copy_from(&src.rows(nq, self.model.nv));
        normalize_quats(&self.model, &mut self.q);
    }

    /// Joint friction for a smooth step of length `h` (no contact, no limit
    /// engaged): its impulses by the constraint solve at (q, v), held constant
    /// over the step as τ_c. Without friction rows τ_c = 0.
    pub(in crate::sim) fn hold_joint_friction(
        &mut self,
        h: f64,
        friction: bool,
    ) -> Result<(), SimError> {
        self.smooth.tau_c.fill(0.0);
        if !friction {
            self.cons.clear_forces();
            return Ok(());
        }
        self.assemble_rows(h);
        self.free_velocity(h, true)?;
        let imp = solve_rows(
            &mut self.cons,
            &self.model,
            &self.points,
            &self.mass,
            &self.opts,
            h,
        );
        self.pgs_sweeps += imp.sweeps as u64;
        self.smooth.tau_c.copy_from(imp.tau_joint);
        self.rows_total += self.cons.rows_len() as u64;
        self.forcing_changed = true;
        Ok(())
    }

    /// After a smooth step (which began clear of every limit), a joint found
    /// past a position limit is put back on it and its velocity into the limit
    /// removed (this only takes kinetic energy away). Returns whether it moved
    /// anything.
    pub(in crate::sim) fn project_limits(&mut self) -> bool {
        let mut moved = false;
        if !self.opts.joint_dynamics {
            return moved;
        }
        for (d, iq, iv) in self.model.dof_indices() {
            let info = &self.model.dofs[d];
            if info.continuous {
                continue;
            }
            if let Some(lo) = info.limits.lower {
                if self.q[iq] < lo {
                    moved = true;
                    self.q[iq] = lo;
                    self.v[iv] = self.v[iv].max(0.0);
                }
            }
            if let Some(hi) = info.limits.upper {
                if self.q[iq] > hi {
                    moved = true;
                    self.q[iq] = hi;
                    self.v[iv] = self.v[iv].min(0.0);
                }
            }
        }
        moved
    }
}
