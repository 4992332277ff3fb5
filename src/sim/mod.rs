//! Time integration of the multibody system with joint dynamics and ground
//! contact: a [`Simulation`] that a program steps itself.
//!
//! # State and equations
//! The state is y = (q, v): q = [p, quaternion (x, y, z, w), joints] with a
//! floating base, v = [v_lin, ω (body frame), joint rates], as Pinocchio's free
//! flyer. Its time derivative is
//!
//! - ṗ = R(q̂) v_lin, q̇_quat = ½ q ⊗ (ω, 0) (q̂: the normalised quaternion), joints q̇ = v;
//! - v̇ = FD(q, v, τ) = H⁻¹(τ − C(q, v)) with τ = sat(τ_applied) − B v + τ_c + Jᵀf̂,
//!
//! where sat clamps each joint's applied torque to its URDF effort limit, B is the
//! diagonal of URDF `<dynamics damping>`, τ_c the generalized forces of joint
//! friction and joint limits and f̂ the ground contact forces (world-frame spatial
//! forces per body, seed eq. 15's f̂ˣ). τ_c and f̂ come from the velocity-level
//! constraint solve of [`solver`] at the start of each step and are held constant
//! over it (so every integrator sees a smooth right-hand side within a step).
//!
//! # Integrators
//! - `euler`: semi-implicit (symplectic) Euler, v⁺ = v + Δt v̇(q, v),
//!   q⁺ = q ⊕ Δt v⁺ (quaternion times exp(Δt ω/2)); with constraints, v⁺ is exactly
//!   the constraint solve's end-of-step velocity (the time-stepping scheme).
//! - `rk4`: classical 4th-order Runge–Kutta on y, quaternion included in the ODE
//!   (4th order for the rotation too), renormalised after each step.
//! - `dop853`: Dormand–Prince 8(5,3) with error control: a step is accepted when
//!   RMSᵢ(eᵢ / (X + X·max(|yᵢ|, |yᵢ⁺|))) ≤ 1 (X = `tol`), step size
//!   h ← h·min(10, max(0.2, 0.9·err^(−1/8))); quaternion renormalised after each step.
//!
//! Nothing is allocated in [`Simulation::step`]: every buffer is sized at construction.

/// `$body` with the constant `$N` set to `$n` for the common sizes of the
/// simulation's small dense kernels (their loops then have lengths known at
/// compile time), to 0 otherwise (the kernel reads the length at run time).
macro_rules! by_size {
    ($n:expr, $N:ident => $body:expr) => {
        by_size!(@sizes $n, $N, $body, 6, 7, 8, 9, 12, 18)
    };
    (@sizes $n:expr, $N:ident, $body:expr, $($k:literal),*) => {
        match $n {
            $($k => {
                const $N: usize = $k;
                $body
            })*
            _ => {
                const $N: usize = 0;
                $body
            }
        }
    };
}

pub mod dop853_tableau;
pub mod solver;

use crate::contact::{ContactError, ContactParams, ContactPoint, GroundContact};
use crate::dynamics::linalg::cholesky;
use crate::dynamics::{
    bias, forward_dynamics, forward_kinematics, kinetic_energy_from_placements, mass_matrix,
    potential_energy, DynamicsError,
};
use crate::model::{Data, JointKind, Model};
use crate::spatial::{Force, Motion};
use nalgebra::{DMatrix, DVector, Vector3};
use solver::{RowKind, Rows};
use std::path::PathBuf;

/// The available integrators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    SemiImplicitEuler,
    Rk4,
    Dop853,
}

impl Integrator {
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
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.name() == s)
    }
    pub fn description(self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => {
                "semi-implicit (symplectic) Euler, fixed step, 1st order"
            }
            Integrator::Rk4 => "classical Runge-Kutta, fixed step, 4th order",
            Integrator::Dop853 => "Dormand-Prince 8(5,3), adaptive step with --tol",
        }
    }
    pub fn is_adaptive(self) -> bool {
        matches!(self, Integrator::Dop853)
    }
    /// The default for a scene: semi-implicit Euler with ground contact (the
    /// contact solve is first order and Euler takes one dynamics call a step),
    /// DOP853 without (high order wins at every error level measured).
    pub fn default_for(contact: bool) -> Self {
        if contact {
            Integrator::SemiImplicitEuler
        } else {
            Integrator::Dop853
        }
    }
}

/// Options of a [`Simulation`].
#[derive(Clone, Debug)]
pub struct SimOptions {
    /// Step (initial step for an adaptive integrator), s.
    pub dt: f64,
    /// `None`: [`Integrator::default_for`] the scene.
    pub integrator: Option<Integrator>,
    /// Error tolerance of adaptive integrators.
    pub tol: f64,
    /// Ground height; `None`: no ground (no contact work at all).
    pub ground: Option<f64>,
    pub contact: ContactParams,
    /// Roots for `package://` mesh paths.
    pub package_paths: Vec<PathBuf>,
    /// Joint friction / limit / effort / damping from the URDF (on by default).
    pub joint_dynamics: bool,
    /// Projected Gauss–Seidel sweeps at most, and its tolerance on the rows'
    /// velocities (m/s, rad/s).
    pub solver_iterations: usize,
    pub solver_tol: f64,
    /// Over-relaxation of the solver's scalar rows (projected SOR), in (0, 2).
    /// 1.3 (over-relaxing only sweeps 4 to `solver_iterations`/2, then one plain
    /// sweep) cut the lamp drop's mean sweeps per step from 7.1 to 5.0 (same
    /// tolerance, same resting state) against plain Gauss–Seidel (1.0).
    pub solver_relaxation: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            integrator: None,
            tol: 1e-6,
            ground: Some(0.0),
            contact: ContactParams::default(),
            package_paths: Vec::new(),
            joint_dynamics: true,
            solver_iterations: 60,
            solver_tol: 1e-7,
            solver_relaxation: 1.3,
        }
    }
}

/// Why a simulation could not be set up or continue.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error(transparent)]
    Contact(#[from] ContactError),
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    #[error("the state turned non-finite at t = {t} s ({quantity})")]
    NonFinite { t: f64, quantity: String },
    #[error("{0}")]
    Invalid(String),
}

/// A point of ground contact after a step: where, how deep, and its force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactForce {
    pub point: ContactPoint,
    /// World-frame force on the link at `point.point` (N).
    pub force: Vector3<f64>,
}

/// Workspace of the right-hand side.
#[derive(Clone, Debug)]
struct Rhs {
    data: Data,
    qn: DVector<f64>,
    vv: DVector<f64>,
    tau: DVector<f64>,
}

/// A simulation that a program steps itself.
///
/// ```no_run
/// # use urdyn::sim::{Simulation, SimOptions};
/// let model = urdyn::load_file(std::path::Path::new("robot.urdf"), Default::default()).unwrap();
/// let mut sim = Simulation::new(model, SimOptions::default()).unwrap();
/// while sim.time() < 1.0 {
///     let (q, v) = (sim.q().clone(), sim.v().clone());
///     for k in 0..q.len().min(v.len()) { sim.torques_mut()[k] = -10.0 * q[k] - 1.0 * v[k]; }
///     sim.step().unwrap();
/// }
/// ```
pub struct Simulation {
    pub model: Model,
    integrator: Integrator,
    dt: f64,
    tol: f64,
    opts: SimOptions,
    t: f64,
    q: DVector<f64>,
    v: DVector<f64>,
    /// Applied generalized forces (joint torques clamped to effort; base force/torque).
    tau_applied: DVector<f64>,
    /// Per-v-coordinate viscous damping, effort limits.
    damping: Vec<f64>,
    effort: Vec<f64>,
    data: Data,
    rhs: Rhs,
    contact: Option<GroundContact>,
    points: Vec<ContactPoint>,
    points_stale: bool,
    /// `data.o_m_i` holds the world poses at the current `q`.
    fk_valid: bool,
    rows: Rows,
    /// Which contact point each normal row belongs to (index into `points`).
    row_point: Vec<usize>,
    /// Warm-start impulses per contact slot (n, t1, t2) and per joint row.
    warm_contact: Vec<[f64; 3]>,
    /// The slots of `warm_contact` written by the last solve (the others are 0):
    /// only these are cleared, not the whole (mesh-sized) array every step.
    warm_slots: Vec<usize>,
    warm_joint: Vec<[f64; 3]>,
    /// World-frame motion subspace columns of each body (≤ 6).
    sw: Vec<[Motion; 6]>,
    /// Constant forcing of the current step.
    fext: Vec<Force>,
    tau_c: DVector<f64>,
    has_fext: bool,
    chol: DMatrix<f64>,
    tmp: DVector<f64>,
    vfree: DVector<f64>,
    contact_forces: Vec<ContactForce>,
    // integrator work
    y: DVector<f64>,
    y_new: DVector<f64>,
    y_stage: DVector<f64>,
    k: Vec<DVector<f64>>,
    h_next: f64,
    fsal_ok: bool,
    forcing_changed: bool,
    /// Steps taken, rejected (adaptive), right-hand-side evaluations.
    pub steps: u64,
    pub rejected: u64,
    pub rhs_evals: u64,
    /// Projected Gauss–Seidel sweeps and constraint rows, summed over the steps.
    pub pgs_sweeps: u64,
    pub rows_total: u64,
}

impl Simulation {
    /// Sets up a simulation of `model` at its neutral configuration, at rest.
    /// Contact shapes (and meshes) are built here when `opts.ground` is set and a
    /// moving link has collision geometry.
    pub fn new(model: Model, opts: SimOptions) -> Result<Self, SimError> {
        if !(opts.dt.is_finite() && opts.dt > 0.0) {
            return Err(SimError::Invalid(format!(
                "--dt must be a positive number (got {})",
                opts.dt
            )));
        }
        if !(opts.tol.is_finite() && opts.tol > 0.0) {
            return Err(SimError::Invalid(format!(
                "--tol must be a positive number (got {})",
                opts.tol
            )));
        }
        let w = opts.solver_relaxation;
        if !(w > 0.0 && w < 2.0) {
            return Err(SimError::Invalid(format!(
                "solver_relaxation must lie in (0, 2) (got {w})"
            )));
        }
        let f = opts.contact.friction;
        if !(f.is_finite() && f >= 0.0) {
            return Err(SimError::Invalid(format!(
                "--friction must be a non-negative number (got {f})"
            )));
        }
        crate::dynamics::check_massless(&model)?;
        let contact = match opts.ground {
            Some(g) => GroundContact::build(&model, g, opts.contact, &opts.package_paths)?,
            None => None,
        };
        let integrator = opts
            .integrator
            .unwrap_or(Integrator::default_for(contact.is_some()));
        let (nq, nv) = (model.nq, model.nv);
        let vo = model.joint_v_offset();
        let mut damping = vec![0.0; nv];
        let mut effort = vec![f64::INFINITY; nv];
        if opts.joint_dynamics {
            for (d, info) in model.dofs.iter().enumerate() {
                damping[vo + d] = info.damping.max(0.0);
                if let Some(e) = info.limits.effort {
                    if e > 0.0 {
                        effort[vo + d] = e;
                    }
                }
            }
        }
        let max_points = contact.as_ref().map_or(0, |c| c.max_points());
        let cap = 3 * max_points + 2 * model.dofs.len();
        let nslots = contact.as_ref().map_or(0, |c| c.nslots);
        let data = Data::new(&model);
        let rhs = Rhs {
            data: Data::new(&model),
            qn: model.neutral(),
            vv: DVector::zeros(nv),
            tau: DVector::zeros(nv),
        };
        let nb = model.nbodies;
        let q = model.neutral();
        let mut sim = Self {
            integrator,
            dt: opts.dt,
            tol: opts.tol,
            t: 0.0,
            v: DVector::zeros(nv),
            tau_applied: DVector::zeros(nv),
            damping,
            effort,
            data,
            rhs,
            contact,
            points: Vec::with_capacity(max_points),
            points_stale: true,
            rows: Rows::new(nv, cap),
            row_point: Vec::with_capacity(cap),
            warm_contact: vec![[0.0; 3]; nslots],
            warm_slots: Vec::with_capacity(cap),
            warm_joint: vec![[0.0; 3]; model.dofs.len()],
            sw: vec![[Motion::zero(); 6]; nb],
            fext: vec![Force::zero(); nb],
            tau_c: DVector::zeros(nv),
            has_fext: false,
            chol: DMatrix::zeros(nv, nv),
            tmp: DVector::zeros(nv),
            vfree: DVector::zeros(nv),
            contact_forces: Vec::with_capacity(max_points),
            y: DVector::zeros(nq + nv),
            y_new: DVector::zeros(nq + nv),
            y_stage: DVector::zeros(nq + nv),
            k: (0..13).map(|_| DVector::zeros(nq + nv)).collect(),
            h_next: opts.dt,
            fsal_ok: false,
            fk_valid: false,
            forcing_changed: true,
            steps: 0,
            rejected: 0,
            rhs_evals: 0,
            pgs_sweeps: 0,
            rows_total: 0,
            q,
            opts,
            model,
        };
        sim.refresh_contacts();
        Ok(sim)
    }

    pub fn integrator(&self) -> Integrator {
        self.integrator
    }
    pub fn time(&self) -> f64 {
        self.t
    }
    pub fn set_time(&mut self, t: f64) {
        self.t = t;
    }
    pub fn dt(&self) -> f64 {
        self.dt
    }
    pub fn q(&self) -> &DVector<f64> {
        &self.q
    }
    pub fn v(&self) -> &DVector<f64> {
        &self.v
    }
    /// Sets the state (a floating base's quaternion is normalised). Wrong lengths
    /// or non-finite values are an error.
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
        if self.model.floating_base {
            normalize_quat(&mut self.q);
        }
        self.fsal_ok = false;
        self.warm_contact.iter_mut().for_each(|w| *w = [0.0; 3]);
        self.warm_slots.clear();
        self.refresh_contacts();
        Ok(())
    }
    /// The applied generalized forces (joint torques; with a floating base the first
    /// six are the base force and torque, body frame). Joint entries are clamped to
    /// their effort limits when used.
    pub fn torques_mut(&mut self) -> &mut DVector<f64> {
        self.forcing_changed = true;
        &mut self.tau_applied
    }
    pub fn torques(&self) -> &DVector<f64> {
        &self.tau_applied
    }
    /// Whether this simulation has ground contact.
    pub fn has_contact(&self) -> bool {
        self.contact.is_some()
    }
    /// Narrow-phase contact queries performed so far (0 for a scene with no
    /// collision geometry or no ground).
    pub fn contact_queries(&self) -> u64 {
        self.contact.as_ref().map_or(0, |c| c.queries)
    }
    /// The lowest point of the collision geometry at the current state (m; +∞
    /// without contact shapes).
    pub fn lowest_point(&mut self) -> f64 {
        forward_kinematics(&self.model, &mut self.data, &self.q);
        match &self.contact {
            Some(c) => c.lowest_point(&self.data.o_m_i),
            None => f64::INFINITY,
        }
    }
    /// Contact points at the current state (within the detection margin).
    pub fn contact_points(&self) -> &[ContactPoint] {
        &self.points
    }
    /// Deepest penetration into the ground at the current state (m, 0 if none).
    pub fn penetration(&self) -> f64 {
        self.points.iter().map(|p| -p.gap).fold(0.0, f64::max)
    }
    /// The contact points that carried force in the last step, with their forces.
    pub fn contact_forces(&self) -> &[ContactForce] {
        &self.contact_forces
    }
    /// Number of contact points that carried force in the last step.
    pub fn active_contacts(&self) -> usize {
        self.contact_forces.len()
    }
    /// The ground contact wrench on each body in the last step (world frame, at
    /// the world origin; entry 0 is the world). Link names: `model.body_link_names`.
    pub fn body_contact_forces(&self) -> &[Force] {
        &self.fext
    }
    /// Kinetic plus gravitational potential energy (J), the potential being
    /// −Σ mᵢ gᵀcᵢ (zero at the world origin).
    pub fn energy(&mut self) -> f64 {
        // the joint placements and world poses are current when the contact
        // refresh at the end of the last step (or a previous call) computed them
        // at this q
        if !self.fk_valid {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        kinetic_energy_from_placements(&self.model, &mut self.data, &self.v)
            + potential_energy(&self.model, &self.data)
    }

    fn refresh_contacts(&mut self) {
        self.fk_valid = false;
        if let Some(c) = self.contact.as_mut() {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            c.detect(&self.data.o_m_i, &mut self.points);
            self.fk_valid = true;
        }
        self.points_stale = false;
    }

    /// One step of at most `dt` (fixed-step integrators take exactly `dt`; an
    /// adaptive one its own accepted step). Returns the step taken.
    pub fn step(&mut self) -> Result<f64, SimError> {
        self.step_until(f64::INFINITY)
    }

    /// One step that does not pass `t_end` (the last step is shortened to land on it).
    pub fn step_until(&mut self, t_end: f64) -> Result<f64, SimError> {
        let remaining = t_end - self.t;
        if !(remaining > 0.0) {
            return Ok(0.0);
        }
        self.fk_valid = false;
        let h = match self.integrator {
            Integrator::SemiImplicitEuler => {
                let h = land(self.dt, remaining);
                self.euler_step(h)?;
                h
            }
            Integrator::Rk4 => {
                let h = land(self.dt, remaining);
                self.constraint_solve(h)?;
                self.rk4_step(h)?;
                h
            }
            Integrator::Dop853 => self.dop853_step(remaining)?,
        };
        if self.integrator != Integrator::SemiImplicitEuler {
            self.project_limits();
        }
        self.t = if h >= remaining { t_end } else { self.t + h };
        self.steps += 1;
        if self.model.floating_base {
            normalize_quat(&mut self.q);
        }
        self.check_finite()?;
        self.refresh_contacts();
        Ok(h)
    }

    /// After a higher-order step (whose constraint forces were held constant),
    /// a joint found past a position limit is put back on it and its velocity
    /// into the limit removed (this only takes energy away).
    fn project_limits(&mut self) {
        if !self.opts.joint_dynamics {
            return;
        }
        let (qo, vo) = (self.model.joint_q_offset(), self.model.joint_v_offset());
        for (d, info) in self.model.dofs.iter().enumerate() {
            if info.continuous {
                continue;
            }
            let (iq, iv) = (qo + d, vo + d);
            if let Some(lo) = info.limits.lower {
                if self.q[iq] < lo {
                    self.q[iq] = lo;
                    self.v[iv] = self.v[iv].max(0.0);
                }
            }
            if let Some(hi) = info.limits.upper {
                if self.q[iq] > hi {
                    self.q[iq] = hi;
                    self.v[iv] = self.v[iv].min(0.0);
                }
            }
        }
    }

    fn check_finite(&self) -> Result<(), SimError> {
        let names = || crate::sim::column_names(&self.model);
        if let Some(k) = self.q.iter().position(|x| !x.is_finite()) {
            let (qn, _) = names();
            return Err(SimError::NonFinite {
                t: self.t,
                quantity: qn.get(k).cloned().unwrap_or_else(|| format!("q[{k}]")),
            });
        }
        if let Some(k) = self.v.iter().position(|x| !x.is_finite()) {
            let (_, vn) = names();
            return Err(SimError::NonFinite {
                t: self.t,
                quantity: vn.get(k).cloned().unwrap_or_else(|| format!("v[{k}]")),
            });
        }
        Ok(())
    }

    /// Applied generalized force with joint torques clamped to effort limits.
    fn clamped_tau(&self, out: &mut DVector<f64>) {
        for (k, o) in out.iter_mut().enumerate() {
            let e = self.effort[k];
            *o = self.tau_applied[k].clamp(-e, e);
        }
    }

    /// Builds and solves the step's constraint rows at (q, v) for a step `h`; fills
    /// `self.fext`, `self.tau_c`, `self.vfree` and (when rows exist) the
    /// Cholesky factor. Returns whether any row exists.
    fn constraint_solve(&mut self, h: f64) -> Result<bool, SimError> {
        if self.points_stale {
            self.refresh_contacts();
        }
        let model = &self.model;
        let (vo, qo) = (model.joint_v_offset(), model.joint_q_offset());
        self.rows.clear();
        self.row_point.clear();
        let beta = self.opts.contact.baumgarte;
        let target = |gap: f64| if gap > 0.0 { -gap / h } else { -beta * gap / h };
        // joint rows: friction and limits
        if self.opts.joint_dynamics {
            for (d, info) in model.dofs.iter().enumerate() {
                let (iq, iv) = (qo + d, vo + d);
                if info.friction > 0.0 {
                    let w = self.warm_joint[d][0];
                    if let Some(r) = self.rows.push(
                        RowKind::Box {
                            limit: info.friction * h,
                        },
                        0.0,
                        w,
                    ) {
                        self.rows.jrow_mut(r)[iv] = 1.0;
                    }
                }
                if info.continuous {
                    continue;
                }
                let (qd, vd) = (self.q[iq], self.v[iv]);
                let margin = 1e-3 + 2.0 * vd.abs() * h;
                if let Some(lo) = info.limits.lower {
                    let gap = qd - lo;
                    if gap < margin {
                        let w = self.warm_joint[d][1];
                        if let Some(r) = self.rows.push(RowKind::Unilateral, target(gap), w) {
                            self.rows.jrow_mut(r)[iv] = 1.0;
                        }
                    }
                }
                if let Some(hi) = info.limits.upper {
                    let gap = hi - qd;
                    if gap < margin {
                        let w = self.warm_joint[d][2];
                        if let Some(r) = self.rows.push(RowKind::Unilateral, target(gap), w) {
                            self.rows.jrow_mut(r)[iv] = -1.0;
                        }
                    }
                }
            }
        }
        let njoint_rows = self.rows.n;
        if !self.points.is_empty() {
            // world-frame motion subspace columns (data.o_m_i is current: refresh ran FK)
            for i in 1..model.nbodies {
                let j = &model.joints[i];
                let o = self.data.o_m_i[i];
                for c in 0..j.nv().min(6) {
                    self.sw[i][c] = o.act_motion(&j.subspace_column(c));
                }
            }
            let mu = self.opts.contact.friction;
            let e = self.opts.contact.restitution;
            for (pi, p) in self.points.iter().enumerate() {
                let warm = self.warm_contact.get(p.slot).copied().unwrap_or([0.0; 3]);
                let Some(rn) = self.rows.push(RowKind::Normal, 0.0, warm[0]) else {
                    break;
                };
                let Some(rt) = self
                    .rows
                    .push(RowKind::Tangent { normal: rn, mu }, 0.0, warm[1])
                else {
                    self.rows.pop(1);
                    break;
                };
                let Some(_) = self.rows.push(RowKind::Tangent2, 0.0, warm[2]) else {
                    self.rows.pop(2);
                    break;
                };
                self.row_point.push(pi);
                // rows n = z, t₁ = x, t₂ = y: the point velocity v_c + ω_c × p of each
                // ancestor's world-frame subspace column c
                let nvv = self.rows.nv;
                let mut b = p.body;
                while b != 0 {
                    let j = &model.joints[b];
                    for c in 0..j.nv().min(6) {
                        let s = &self.sw[b][c];
                        let vp = s.lin + s.ang.cross(&p.point);
                        let col = j.iv + c;
                        if col < nvv {
                            self.rows.j[rn * nvv + col] += vp.z;
                            self.rows.j[(rn + 1) * nvv + col] += vp.x;
                            self.rows.j[(rn + 2) * nvv + col] += vp.y;
                        }
                    }
                    b = model.parent[b];
                }
                // normal target: speculative / Baumgarte, restitution
                let un = solver::dot(self.rows.jrow(rn), self.v.as_slice());
                let mut bn = target(p.gap);
                // restitution only above the speed below which a bounce of one
                // step under gravity could gain energy: |u| > 2 g h e / (1 − e²)
                let g = self.model.gravity.norm();
                let vmin = (4.0 * g * h * e / (1.0 - e * e).max(1e-12)).max(1e-3);
                if e > 0.0 && e < 1.0 && un < -vmin && p.gap < -un * h {
                    bn = bn.max(-e * un);
                }
                self.rows.b[rn] = bn;
                let _ = rt;
            }
        }
        self.fext.iter_mut().for_each(|f| *f = Force::zero());
        self.tau_c.fill(0.0);
        self.contact_forces.clear();
        self.has_fext = false;
        if self.rows.n == 0 {
            return Ok(false);
        }
        // free velocity v* = v + h H⁻¹(τ − Bv − C)
        let mut tau = std::mem::replace(&mut self.tmp, DVector::zeros(0));
        self.clamped_tau(&mut tau);
        for k in 0..self.model.nv {
            tau[k] -= self.damping[k] * self.v[k];
        }
        bias(&self.model, &mut self.data, &self.q, &self.v, None);
        tau -= &self.data.bias;
        mass_matrix(&self.model, &mut self.data, &self.q);
        let chol_ok = cholesky_fast(&self.data.h, &mut self.chol);
        if let Err(p) = chol_ok {
            self.tmp = tau;
            return Err(DynamicsError::Singular(p).into());
        }
        chol_solve_slice(self.chol.as_slice(), self.model.nv, tau.as_mut_slice());
        self.vfree.copy_from(&self.v);
        self.vfree.axpy(h, &tau, 1.0);
        if self.model.floating_base {
            add_frame_rate(&mut self.vfree, &self.v, h);
        }
        // Y rows = L⁻¹ jᵣ (H = L Lᵀ, one forward substitution a row): the Delassus
        // matrix is W = J H⁻¹ Jᵀ = Y Yᵀ, so the solver works on Δv' = Lᵀ Δv with
        // uᵣ = cᵣ + yᵣ·Δv', and Δv = L⁻ᵀ Δv' once at the end
        let nv = self.model.nv;
        self.tmp = tau;
        self.rows
            .form_factored(self.chol.as_slice(), self.vfree.as_slice());
        let mut dv = std::mem::replace(&mut self.tmp, DVector::zeros(0));
        self.pgs_sweeps += self.rows.solve(
            dv.as_mut_slice(),
            self.opts.solver_iterations,
            self.opts.solver_tol,
            self.opts.solver_relaxation,
        ) as u64;
        chol_backward(self.chol.as_slice(), nv, dv.as_mut_slice());
        self.tmp = dv;
        self.rows_total += self.rows.n as u64;
        // results: warm starts, joint generalized forces, contact body forces
        let mut r = 0;
        if self.opts.joint_dynamics {
            for (d, info) in self.model.dofs.iter().enumerate() {
                let iv = vo + d;
                let mut w = [0.0; 3];
                if info.friction > 0.0 && r < njoint_rows {
                    w[0] = self.rows.lambda[r];
                    self.tau_c[iv] += self.rows.lambda[r] / h;
                    r += 1;
                }
                // limit rows were pushed in order lower, upper when present
                while r < njoint_rows && self.rows.kind[r] == RowKind::Unilateral {
                    let jv = self.rows.j[r * nv + iv];
                    if jv == 0.0 {
                        break;
                    }
                    if jv > 0.0 {
                        w[1] = self.rows.lambda[r];
                    } else {
                        w[2] = self.rows.lambda[r];
                    }
                    self.tau_c[iv] += jv * self.rows.lambda[r] / h;
                    r += 1;
                }
                self.warm_joint[d] = w;
            }
        }
        for &k in &self.warm_slots {
            if let Some(w) = self.warm_contact.get_mut(k) {
                *w = [0.0; 3];
            }
        }
        self.warm_slots.clear();
        for (c, &pi) in self.row_point.iter().enumerate() {
            let rn = njoint_rows + 3 * c;
            let (ln, l1, l2) = (
                self.rows.lambda[rn],
                self.rows.lambda[rn + 1],
                self.rows.lambda[rn + 2],
            );
            let Some(p) = self.points.get(pi) else {
                continue;
            };
            if let Some(w) = self.warm_contact.get_mut(p.slot) {
                *w = [ln, l1, l2];
                self.warm_slots.push(p.slot);
            }
            if ln > 0.0 {
                let f = Vector3::new(l1, l2, ln) / h;
                if let Some(fb) = self.fext.get_mut(p.body) {
                    *fb += Force::at_point(f, &p.point);
                }
                self.contact_forces.push(ContactForce {
                    point: *p,
                    force: f,
                });
                self.has_fext = true;
            }
        }
        self.forcing_changed = true;
        Ok(true)
    }

    fn euler_step(&mut self, h: f64) -> Result<(), SimError> {
        let rows = self.constraint_solve(h)?;
        let nv = self.model.nv;
        if rows {
            // v⁺ = v* + Σ λᵣ H⁻¹ jᵣ (the solver's Δv, left in `tmp`)
            self.v.copy_from(&self.vfree);
            self.v += &self.tmp;
        } else {
            let mut tau = std::mem::replace(&mut self.tmp, DVector::zeros(0));
            self.clamped_tau(&mut tau);
            for k in 0..nv {
                tau[k] -= self.damping[k] * self.v[k];
            }
            let a = forward_dynamics(&self.model, &mut self.data, &self.q, &self.v, &tau, None);
            let a = match a {
                Ok(a) => a,
                Err(e) => {
                    self.tmp = tau;
                    return Err(e.into());
                }
            };
            let v0 = std::mem::replace(&mut self.vfree, DVector::zeros(0));
            let mut v0 = v0;
            v0.copy_from(&self.v);
            self.v.axpy(h, a, 1.0);
            if self.model.floating_base {
                add_frame_rate(&mut self.v, &v0, h);
            }
            self.vfree = v0;
            self.tmp = tau;
        }
        self.rhs_evals += 1;
        integrate_config(&self.model, &mut self.q, &self.v, h);
        if self.model.floating_base {
            // the base's linear velocity, found in the start frame R, expressed in
            // the new frame R⁺ = R exp(hω⁺): rotated by exp(−hω⁺)
            let w = Vector3::new(self.v[3], self.v[4], self.v[5]) * h;
            let th = w.norm();
            if th > 0.0 {
                let r = crate::spatial::axis_angle(&(w / th), th);
                let vl = r.transpose() * Vector3::new(self.v[0], self.v[1], self.v[2]);
                self.v[0] = vl.x;
                self.v[1] = vl.y;
                self.v[2] = vl.z;
            }
        }
        Ok(())
    }

    /// ẏ = f(y) with the step's constant forcing.
    fn eval_rhs(&mut self, which: RhsIn, out: usize) -> Result<(), SimError> {
        self.rhs_evals += 1;
        let y = match which {
            RhsIn::Y => &self.y,
            RhsIn::Stage => &self.y_stage,
            RhsIn::New => &self.y_new,
        };
        let dy = &mut self.k[out];
        rhs(
            &self.model,
            &mut self.rhs,
            &self.tau_applied,
            &self.effort,
            &self.damping,
            &self.tau_c,
            if self.has_fext {
                Some(&self.fext)
            } else {
                None
            },
            y,
            dy,
        )
    }

    fn load_y(&mut self) {
        let nq = self.model.nq;
        self.y.rows_mut(0, nq).copy_from(&self.q);
        self.y.rows_mut(nq, self.model.nv).copy_from(&self.v);
    }

    fn store_y(&mut self, from_new: bool) {
        let nq = self.model.nq;
        let src = if from_new { &self.y_new } else { &self.y };
        self.q.copy_from(&src.rows(0, nq));
        self.v.copy_from(&src.rows(nq, self.model.nv));
    }

    fn rk4_step(&mut self, h: f64) -> Result<(), SimError> {
        self.load_y();
        self.eval_rhs(RhsIn::Y, 0)?;
        let c = [0.5, 0.5, 1.0];
        for s in 0..3 {
            self.y_stage.copy_from(&self.y);
            self.y_stage.axpy(c[s] * h, &self.k[s], 1.0);
            self.eval_rhs(RhsIn::Stage, s + 1)?;
        }
        let y = &mut self.y;
        let n = y.len();
        for i in 0..n {
            y[i] +=
                h / 6.0 * (self.k[0][i] + 2.0 * self.k[1][i] + 2.0 * self.k[2][i] + self.k[3][i]);
        }
        self.store_y(false);
        Ok(())
    }

    /// One accepted DOP853 step no longer than `remaining`; returns its length.
    fn dop853_step(&mut self, remaining: f64) -> Result<f64, SimError> {
        use dop853_tableau::{A, B, C, E3, E5, N_STAGES};
        // a step with constraint rows holds its forcing over the step: solve first
        // with ground contact a step may not outrun the detection margin: the
        // adaptive step is capped at `dt` (it can only shrink below it)
        if self.contact.is_some() {
            self.h_next = self.h_next.min(self.dt);
        }
        let had_rows = {
            let h0 = self.h_next.min(remaining);
            self.constraint_solve(h0)?
        };
        self.load_y();
        if !(self.fsal_ok && !had_rows && !self.forcing_changed) {
            self.eval_rhs(RhsIn::Y, 0)?;
        }
        self.forcing_changed = false;
        let n = self.y.len();
        let mut h = self.h_next.min(remaining);
        let mut tries = 0;
        loop {
            tries += 1;
            for s in 1..N_STAGES {
                self.y_stage.copy_from(&self.y);
                for (j, a) in A[s].iter().enumerate().take(s) {
                    if *a != 0.0 {
                        self.y_stage.axpy(h * a, &self.k[j], 1.0);
                    }
                }
                self.eval_rhs(RhsIn::Stage, s)?;
            }
            self.y_new.copy_from(&self.y);
            for (j, b) in B.iter().enumerate() {
                if *b != 0.0 {
                    self.y_new.axpy(h * b, &self.k[j], 1.0);
                }
            }
            self.eval_rhs(RhsIn::New, 12)?;
            // error estimate (Hairer's dop853: 5th- and 3rd-order estimators)
            let (mut e5, mut e3) = (0.0, 0.0);
            for i in 0..n {
                let sc = self.tol + self.tol * self.y[i].abs().max(self.y_new[i].abs());
                let (mut s5, mut s3) = (0.0, 0.0);
                for j in 0..13 {
                    let kj = self.k[j][i];
                    s5 += E5[j] * kj;
                    s3 += E3[j] * kj;
                }
                e5 += (s5 / sc) * (s5 / sc);
                e3 += (s3 / sc) * (s3 / sc);
            }
            let err = if e5 == 0.0 && e3 == 0.0 {
                0.0
            } else {
                h * e5 / ((e5 + 0.01 * e3) * n as f64).sqrt()
            };
            if !err.is_finite() {
                return Err(SimError::NonFinite {
                    t: self.t + h,
                    quantity: "integrator error estimate".into(),
                });
            }
            let _ = C;
            if err <= 1.0 {
                let fac = if err == 0.0 {
                    10.0
                } else {
                    (0.9 * err.powf(-1.0 / 8.0)).min(10.0)
                };
                // do not let a landing step shrink the next one
                if h < remaining || h >= self.h_next {
                    self.h_next = h * fac;
                } else {
                    self.h_next = self.h_next.max(h * fac);
                }
                self.store_y(true);
                let last = self.k.swap_remove(12);
                self.k.insert(0, last);
                // k was rotated: k[0] = f(y_new); the rest are scratch
                self.fsal_ok = !had_rows;
                return Ok(h);
            }
            self.rejected += 1;
            h *= (0.9 * err.powf(-1.0 / 8.0)).clamp(0.2, 1.0);
            if h < 1e-14 * (1.0 + self.t.abs()) || tries > 200 {
                return Err(SimError::NonFinite {
                    t: self.t,
                    quantity: format!("step size underflow (h = {h:e})"),
                });
            }
            if had_rows {
                self.constraint_solve(h)?;
                self.eval_rhs(RhsIn::Y, 0)?;
            }
        }
    }
}

/// Solves L Lᵀ x = b in place, L in the lower triangle of the column-major
/// `l` (n × n), column-oriented so that both passes read contiguous columns.
fn chol_solve_slice(l: &[f64], n: usize, x: &mut [f64]) {
    if l.len() < n * n || x.len() < n {
        return;
    }
    // common sizes with the length known at compile time (same arithmetic)
    by_size!(n, N => {
        chol_forward_n::<N>(l, n, x);
        chol_backward_n::<N>(l, n, x)
    })
}

/// Lᵀ x' = x for the Cholesky factor of [`chol_solve_slice`].
fn chol_backward(l: &[f64], n: usize, x: &mut [f64]) {
    if l.len() < n * n || x.len() < n {
        return;
    }
    by_size!(n, N => chol_backward_n::<N>(l, n, x))
}

/// L x' = x in place (forward substitution); `N = 0`: the length `n` at run
/// time. The caller checked `l.len() ≥ n²`, `x.len() ≥ n` (and `N ∈ {0, n}`).
#[inline(always)]
fn chol_forward_n<const N: usize>(l: &[f64], n: usize, x: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (l, x) = (&l[..n * n], &mut x[..n]);
    // SAFETY: k, i < n; l is n·n long, x n long.
    unsafe {
        for k in 0..n {
            let xk = *x.get_unchecked(k) / *l.get_unchecked(k * n + k);
            *x.get_unchecked_mut(k) = xk;
            if xk != 0.0 {
                for i in k + 1..n {
                    *x.get_unchecked_mut(i) -= *l.get_unchecked(k * n + i) * xk;
                }
            }
        }
    }
}

/// Lᵀ x' = x in place (back substitution).
#[inline(always)]
fn chol_backward_n<const N: usize>(l: &[f64], n: usize, x: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let (l, x) = (&l[..n * n], &mut x[..n]);
    // SAFETY: k, i < n; l is n·n long, x n long.
    unsafe {
        for k in (0..n).rev() {
            let mut s = -0.0;
            for i in k + 1..n {
                s += *x.get_unchecked(i) * *l.get_unchecked(k * n + i);
            }
            *x.get_unchecked_mut(k) = (*x.get_unchecked(k) - s) / *l.get_unchecked(k * n + k);
        }
    }
}

/// [`cholesky`] (same arithmetic, same order) with the size known at compile
/// time for common sizes and the bounds checked once.
fn cholesky_fast(h: &DMatrix<f64>, l: &mut DMatrix<f64>) -> Result<(), usize> {
    let n = h.nrows();
    if h.ncols() != n || l.nrows() != n || l.ncols() != n {
        return cholesky(h, l);
    }
    let (hs, ls) = (h.as_slice(), l.as_mut_slice());
    by_size!(n, N => cholesky_n::<N>(hs, ls, n))
}

#[inline(always)]
fn cholesky_n<const N: usize>(h: &[f64], l: &mut [f64], n: usize) -> Result<(), usize> {
    let n = if N == 0 { n } else { N };
    let (h, l) = (&h[..n * n], &mut l[..n * n]);
    let tiny = 64.0 * f64::EPSILON;
    // SAFETY: all indices are r + n·c with r, c < n; both slices are n·n long.
    unsafe {
        for j in 0..n {
            let hjj = *h.get_unchecked(j * n + j);
            let mut d = hjj;
            for k in 0..j {
                let ljk = *l.get_unchecked(k * n + j);
                d -= ljk * ljk;
            }
            if !(d > tiny * hjj.abs()) || !d.is_finite() {
                return Err(j);
            }
            let djj = d.sqrt();
            *l.get_unchecked_mut(j * n + j) = djj;
            for i in (j + 1)..n {
                let mut s = *h.get_unchecked(j * n + i);
                for k in 0..j {
                    s -= *l.get_unchecked(k * n + i) * *l.get_unchecked(k * n + j);
                }
                *l.get_unchecked_mut(j * n + i) = s / djj;
            }
        }
    }
    Ok(())
}

#[derive(Clone, Copy)]
enum RhsIn {
    Y,
    Stage,
    New,
}

/// Semi-implicit Euler on the free joint works in the frame fixed at the step's
/// start: the base's linear velocity changes there by the classical acceleration
/// a_lin + ω × v_lin (the spatial body-frame acceleration misses the frame's own
/// rotation); it is rotated into the new frame after the position update. Done
/// this way the rotation of the body-frame velocity is exact and adds no energy.
fn add_frame_rate(v_new: &mut DVector<f64>, v_old: &DVector<f64>, h: f64) {
    let w = Vector3::new(v_old[3], v_old[4], v_old[5]);
    let vl = Vector3::new(v_old[0], v_old[1], v_old[2]);
    let d = w.cross(&vl) * h;
    v_new[0] += d.x;
    v_new[1] += d.y;
    v_new[2] += d.z;
}

/// `dt`, or the remaining time when that is (nearly) shorter.
fn land(dt: f64, remaining: f64) -> f64 {
    if remaining <= dt * (1.0 + 1e-9) {
        remaining
    } else {
        dt
    }
}

#[allow(clippy::too_many_arguments)]
fn rhs(
    model: &Model,
    w: &mut Rhs,
    tau_applied: &DVector<f64>,
    effort: &[f64],
    damping: &[f64],
    tau_c: &DVector<f64>,
    fext: Option<&[Force]>,
    y: &DVector<f64>,
    dy: &mut DVector<f64>,
) -> Result<(), SimError> {
    let (nq, nv) = (model.nq, model.nv);
    w.qn.copy_from(&y.rows(0, nq));
    w.vv.copy_from(&y.rows(nq, nv));
    if model.floating_base {
        normalize_quat(&mut w.qn);
    }
    for k in 0..nv {
        let e = effort[k];
        w.tau[k] = tau_applied[k].clamp(-e, e) - damping[k] * w.vv[k] + tau_c[k];
    }
    // q̇
    config_rate(model, &w.qn, y, &w.vv, dy);
    let a = forward_dynamics(model, &mut w.data, &w.qn, &w.vv, &w.tau, fext)?;
    dy.rows_mut(nq, nv).copy_from(a);
    Ok(())
}

/// Writes q̇ into `dy[0..nq]`: ṗ = R(q̂) v_lin, quaternion rate ½ q ⊗ (ω, 0) (q taken
/// from `y`, unnormalised, so that the rate is the exact derivative of the ODE
/// state), joints q̇ = v.
fn config_rate(
    model: &Model,
    qn: &DVector<f64>,
    y: &DVector<f64>,
    v: &DVector<f64>,
    dy: &mut DVector<f64>,
) {
    let (qo, vo) = (model.joint_q_offset(), model.joint_v_offset());
    if model.floating_base {
        let r = crate::spatial::quat_to_matrix(qn[3], qn[4], qn[5], qn[6]);
        let pd = r * Vector3::new(v[0], v[1], v[2]);
        dy[0] = pd.x;
        dy[1] = pd.y;
        dy[2] = pd.z;
        let (x, yy, z, ww) = (y[3], y[4], y[5], y[6]);
        let (wx, wy, wz) = (v[3], v[4], v[5]);
        // (q ⊗ (ω,0)): vector = w ω + qv × ω, scalar = −qv·ω
        dy[3] = 0.5 * (ww * wx + yy * wz - z * wy);
        dy[4] = 0.5 * (ww * wy + z * wx - x * wz);
        dy[5] = 0.5 * (ww * wz + x * wy - yy * wx);
        dy[6] = -0.5 * (x * wx + yy * wy + z * wz);
    }
    for d in 0..model.dofs.len() {
        dy[qo + d] = v[vo + d];
    }
}

/// q ← q ⊕ h v: p += h R v_lin, quaternion ← quaternion ⊗ exp(h ω / 2), joints += h v.
pub fn integrate_config(model: &Model, q: &mut DVector<f64>, v: &DVector<f64>, h: f64) {
    let (qo, vo) = (model.joint_q_offset(), model.joint_v_offset());
    if model.floating_base {
        let r = crate::spatial::quat_to_matrix(q[3], q[4], q[5], q[6]);
        let dp = r * Vector3::new(v[0], v[1], v[2]) * h;
        q[0] += dp.x;
        q[1] += dp.y;
        q[2] += dp.z;
        let w = Vector3::new(v[3], v[4], v[5]) * h;
        let th = w.norm();
        let (s, c) = if th > 1e-12 {
            let (s, c) = (th / 2.0).sin_cos();
            (s / th, c)
        } else {
            (0.5 - th * th / 48.0, 1.0 - th * th / 8.0)
        };
        let (dx, dy, dz, dw) = (w.x * s, w.y * s, w.z * s, c);
        let (x, y, z, ww) = (q[3], q[4], q[5], q[6]);
        q[3] = ww * dx + x * dw + y * dz - z * dy;
        q[4] = ww * dy - x * dz + y * dw + z * dx;
        q[5] = ww * dz + x * dy - y * dx + z * dw;
        q[6] = ww * dw - x * dx - y * dy - z * dz;
        normalize_quat(q);
    }
    for d in 0..model.dofs.len() {
        q[qo + d] += h * v[vo + d];
    }
}

fn normalize_quat(q: &mut DVector<f64>) {
    let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
    if n > 0.0 && n.is_finite() {
        for k in 3..7 {
            q[k] /= n;
        }
    }
}

/// The trajectory column names of q and v (cli.md): a floating base first
/// (`q:base_x … q:base_qw`, `v:base_vx … v:base_wz`), then `q:NAME`/`v:NAME` per DoF.
pub fn column_names(model: &Model) -> (Vec<String>, Vec<String>) {
    let mut qn = Vec::with_capacity(model.nq);
    let mut vn = Vec::with_capacity(model.nv);
    if model.floating_base {
        for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
            qn.push(format!("q:base_{s}"));
        }
        for s in ["vx", "vy", "vz", "wx", "wy", "wz"] {
            vn.push(format!("v:base_{s}"));
        }
    }
    for d in &model.dofs {
        qn.push(format!("q:{}", d.name));
        vn.push(format!("v:{}", d.name));
    }
    (qn, vn)
}

/// Whether a model's joint kinds are all supported by [`integrate_config`].
pub fn supports(model: &Model) -> bool {
    model
        .joints
        .iter()
        .skip(1)
        .enumerate()
        .all(|(i, j)| match j.kind {
            JointKind::Free => i == 0,
            _ => true,
        })
}
