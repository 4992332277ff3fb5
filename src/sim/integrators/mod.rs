//! The integrators, one a file: `euler` (the time-stepping scheme every step
//! that touches something takes), `rk4` and `dop853` (smooth phases), what
//! they share (`smooth`), the damping's stiffness test (`damping`) and the
//! implicit mass matrix.

mod damping;
pub(crate) use damping::explicit_limit;
mod dop853;
pub(in crate::sim) mod dop853_tableau;
mod euler;
mod rk4;
mod smooth;
pub(in crate::sim) use smooth::RhsIn;

use super::constraints::{Constraints, Impulses};
use super::{MassWork, SimError, SimOptions, Simulation};
use crate::contact::ContactPoint;
use crate::dynamics::{crba_upper, mass_matrix, DynamicsError};
use crate::model::Model;

/// The available integrators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// `euler`: semi-implicit (symplectic) Euler, fixed step, damping implicit;
    /// the time-stepping scheme (docs/theory.md §"Time stepping").
    SemiImplicitEuler,
    /// `rk4`: classical 4th-order Runge–Kutta, fixed step (docs/theory.md
    /// §"Smooth integrators").
    Rk4,
    /// `dop853`: Dormand–Prince 8(5,3), adaptive step under
    /// [`SimOptions::tol`] (docs/theory.md §"Smooth integrators").
    Dop853,
}

impl Integrator {
    /// Every integrator, in the order the command line lists them.
    pub const ALL: [Integrator; 3] = [
        Integrator::SemiImplicitEuler,
        Integrator::Rk4,
        Integrator::Dop853,
    ];
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => "euler",
            Integrator::Rk4 => "rk4",
            Integrator::Dop853 => "dop853",
        }
    }
    /// The integrator of a command-line name; `None` for an unknown name.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.name() == s)
    }
    /// A one-line description for `--help` and listings.
    pub fn description(self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => {
                "semi-implicit (symplectic) Euler, fixed step, 1st order, damping implicit"
            }
            Integrator::Rk4 => {
                "classical Runge-Kutta, fixed step, 4th order (steps with contact, limits or stiff damping by time stepping)"
            }
            Integrator::Dop853 => {
                "Dormand-Prince 8(5,3), adaptive step with --tol (steps with contact, limits or stiff damping by time stepping)"
            }
        }
    }
    /// Whether the step size is chosen by error control (`dop853`); the
    /// others take `dt` every step.
    pub fn is_adaptive(self) -> bool {
        matches!(self, Integrator::Dop853)
    }
    /// The default for a scene: semi-implicit Euler with ground contact (the
    /// contact solve is first order and Euler takes one dynamics call a step),
    /// DOP853 without (high order wins at every error level measured; a step
    /// whose damping is too stiff for it is taken by the implicit scheme).
    pub fn default_for(contact: bool) -> Self {
        if contact {
            Integrator::SemiImplicitEuler
        } else {
            Integrator::Dop853
        }
    }
}

impl Simulation {
    /// H̃ = H(q) + A + c·D at the current q, factored into `mass.f` (on a
    /// tree with the local-frame CRBA: formed in the factor's own packed
    /// storage, `data.h` untouched; else `data.h` is left holding H̃, its upper
    /// triangle only on a tree, all the tree-sparse factorisation reads).
    pub(in crate::sim) fn factor_mass(&mut self, c: f64) -> Result<(), SimError> {
        // a tree: H̃ formed and factored in the factor's packed storage, no
        // nv × nv matrix touched (`data.h` is left as it was)
        let placed = self.fk_valid && self.q.len() == self.model.nq;
        // only the awake trees (a sleeping tree's dofs are held, and no row
        // reaches them)
        self.mass
            .f
            .set_awake(&self.model, self.sleep.sleeping_trees());
        // (slices: one bounds test an entry, not a DVector's matrix index)
        let (arm, damp) = (self.armature.as_slice(), self.damping.as_slice());
        // H̃'s diagonal additions A + c D + c kd + c² kp, all at once (one
        // pass over slices, the same sums entry by entry as `Servo::diag`)
        let mut buf = std::mem::take(&mut self.mass.f.diag_buf);
        let filled = fill_diag(&mut buf, arm, damp, &self.servo, c);
        let servo = &self.servo;
        let at = if filled {
            self.mass.f.factor_at(
                &self.model,
                &mut self.data,
                self.q.as_slice(),
                placed,
                |k| buf[k],
            )
        } else {
            let diag = |k: usize| arm[k] + c * damp[k] + servo.diag(k, c);
            self.mass
                .f
                .factor_at(&self.model, &mut self.data, self.q.as_slice(), placed, diag)
        };
        self.mass.f.diag_buf = buf;
        if let Some(r) = at {
            return r.map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)));
        }
        // the joint placements of the last forward kinematics at this q are
        // reused where the local-frame CRBA runs (it fills all of H, what
        // either factor reads)
        let placed = self.fk_valid
            && self.q.len() == self.model.nq
            && crate::dynamics::crba_at_placements(&self.model, &mut self.data);
        if !placed {
            if self.mass.f.is_tree() {
                crba_upper(&self.model, &mut self.data, &self.q)?;
            } else {
                mass_matrix(&self.model, &mut self.data, &self.q)?;
            }
        }
        for k in 0..self.model.nv {
            self.data.h[(k, k)] += self.armature[k] + c * self.damping[k] + self.servo.diag(k, c);
        }
        self.mass
            .f
            .factor(&self.data.h)
            .map_err(|p| SimError::Dynamics(DynamicsError::Singular(p)))
    }
}

/// `buf[k] = arm[k] + c damp[k] + servo.diag(k, c)` for every k < nv (the
/// same operations in the same order as [`super::servo::Servo::diag`]'s
/// callers, over slices: no per-entry branch on the servo's state nor bounds
/// test). False, nothing written, where a slice is shorter than `buf`.
fn fill_diag(
    buf: &mut [f64],
    arm: &[f64],
    damp: &[f64],
    servo: &super::servo::Servo,
    c: f64,
) -> bool {
    let n = buf.len();
    let (Some(arm), Some(damp)) = (arm.get(..n), damp.get(..n)) else {
        return false;
    };
    if !servo.active {
        // (`Servo::diag` is 0 when inactive: the + 0 kept, −0 becomes +0)
        for ((b, &a), &d) in buf.iter_mut().zip(arm).zip(damp) {
            *b = a + c * d + 0.0;
        }
        return true;
    }
    let (Some(kd), Some(kp), Some(sat)) = (
        servo.kd.as_slice().get(..n),
        servo.kp.as_slice().get(..n),
        servo.saturated.get(..n),
    ) else {
        return false;
    };
    for k in 0..n {
        // c kd + c² kp on a free servo, 0 on a saturated one
        let s = if sat[k] == 0 {
            c * kd[k] + c * c * kp[k]
        } else {
            0.0
        };
        buf[k] = arm[k] + c * damp[k] + s;
    }
    true
}

/// The assembled rows' impulses at the free velocity `mass.vfree` with the
/// factor `mass.f` (fields of a [`Simulation`] passed apart, so that the
/// result borrows the constraints only).
pub(in crate::sim) fn solve_rows<'a>(
    cons: &'a mut Constraints,
    model: &Model,
    points: &[ContactPoint],
    mass: &MassWork,
    opts: &SimOptions,
    h: f64,
) -> Impulses<'a> {
    cons.solve(
        model,
        points,
        &mass.f,
        &mass.vfree,
        h,
        opts.solver_iterations,
        opts.solver_tol,
        opts.solver_relaxation,
        opts.solver,
    )
}
