//! Time integration of the multibody system with joint dynamics and ground
//! contact: a [`Simulation`] that a program steps itself.
//!
//! # State and equations
//! The state is y = (q, v): q = [p, quaternion (x, y, z, w), joints] with a
//! floating base, v = [v_lin, ω (body frame), joint rates], as Pinocchio's free
//! flyer ([`crate::model::configuration`]). The equations of motion are
//!
//! (H(q) + A) v̇ = sat(τ_applied) − C(q, v) − D v + τ_c + Jᵀf̂
//!
//! where A is the armature (rotor inertia on each joint's diagonal,
//! [`SimOptions::armature`]), sat clamps each joint's applied torque to its URDF
//! effort limit, D is the diagonal of URDF `<dynamics damping>`, τ_c the
//! generalized forces of joint friction and joint limits and f̂ the ground
//! contact forces (world-frame spatial forces per body, docs/theory.md §"External
//! forces"), found by the constraint solve of [`constraints`].
//!
//! # Damping is never explicit where it is stiff
//! Joint damping on light links is stiff (allegro's hand: λmax(H⁻¹D) ≈ 2e6 s⁻¹).
//! The time-stepping step (semi-implicit Euler) solves with H̃ = H + A + Δt·D:
//! H̃ (v⁺ − v) = Δt (τ − C − D v) + Jᵀλ, stable for any damping at any step
//! (a damped free joint decays exactly by H/(H + Δt D) a step) and accurate
//! on an overdamped link's creep. `rk4` and `dop853` keep damping in their
//! right-hand side while Δt·tr((H + A)⁻¹D) lies inside their stability
//! interval (an adaptive step is capped there); a step where even `dt` does
//! not is taken by the time-stepping scheme (`src/sim/integrators/damping.rs`
//! says why not a splitting).
//!
//! # Contact and limits: time stepping
//! A step that touches anything (a contact point within the margin, a joint
//! within 1 mm of a limit) is taken by the time-stepping scheme whatever the
//! integrator: impulses λ at the velocity level so that v⁺ satisfies the
//! constraints ([`solver`]), q⁺ = q ⊕ Δt (v⁺ + w) with w the position pass's
//! pseudo-velocity (split impulse), which removes penetration and limit
//! violations at a capped rate and never enters v. This scheme never adds
//! energy at an impact (the impulses are dissipative, restitution 0 by
//! default); a higher-order method holding impulsive forces constant over a
//! step does. `rk4` and `dop853` integrate the smooth phases between.
//!
//! # Integrators
//! - `euler`: semi-implicit (symplectic) Euler, v⁺ = v + Δt H̃⁻¹(…),
//!   q⁺ = q ⊕ Δt v⁺ (quaternion times exp(Δt ω/2)).
//! - `rk4`: classical 4th-order Runge–Kutta on y, quaternion included in the ODE,
//!   renormalised after each step.
//! - `dop853`: Dormand–Prince 8(5,3) with error control: a step is accepted when
//!   RMSᵢ(eᵢ / (X + X·max(|yᵢ|, |yᵢ⁺|))) ≤ 1 (X = `tol`), step size
//!   h ← h·min(10, max(0.2, 0.9·err^(−1/8))).
//!
//! The last step of a run lands exactly on its end; a remainder shorter than a
//! tenth of the step is merged into the step before it (never a sliver step).
//!
//! # Honest failure
//! A state that turns non-finite stops the run ([`SimError::NonFinite`]). A
//! *passive* run (every applied torque zero) whose mechanical energy rises
//! above its reference by more than [`SimOptions::max_energy_rise`] stops with
//! [`SimError::Diverging`]. The reference is the energy at the start, or, when
//! the start violates a constraint ([`Simulation::start_violations`]), the
//! energy once those violations are recovered (or 2 s after the start).
//!
//! Nothing is allocated in [`Simulation::step`]: every buffer is sized at construction.

mod actuators;
pub mod constraints;
mod contact_view;
pub mod derivatives;
pub mod factor;
mod loops;
pub use loops::LoopForce;
pub(crate) mod integrators;
pub mod newton;
pub use contact_view::Violation;
mod sensors;
mod servo;
mod sleep;
pub mod solver;

pub use derivatives::{JacobianMethod, TransitionJacobians};
pub use integrators::Integrator;

use crate::contact::{Collision, ContactError, ContactParams, ContactPoint};
use crate::dynamics::DynamicsError;
use crate::dynamics::{
    forward_kinematics_pass as forward_kinematics, kinetic_energy_from_placements, potential_energy,
};
use crate::model::configuration::normalize_quats;
use crate::model::{Data, JointKind, Model};
use constraints::{Constraints, RowParams};
use nalgebra::{DVector, Vector3};
use std::{path::PathBuf, sync::Arc};

/// A passive run diverges when its energy rises above the reference by more
/// than `relative · (|E_ref| + M·|g|·1 m) + absolute` (M the total mass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyBound {
    /// Allowed rise as a fraction of `|E_ref| + M·|g|·1 m` (dimensionless).
    pub relative: f64,
    /// J.
    pub absolute: f64,
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
    /// Ground contact: friction, restitution, position pass, detection margin.
    pub contact: ContactParams,
    /// Roots for `package://` mesh paths.
    pub package_paths: Vec<PathBuf>,
    /// Joint friction / limit / effort / damping from the URDF (on by default).
    pub joint_dynamics: bool,
    /// Rotor inertia added to every joint's diagonal of H (kg·m² or kg; not
    /// the floating base's). The URDF has no tag for it. Default 0.
    pub armature: f64,
    /// Projected Gauss–Seidel sweeps at most, and its tolerance on the rows'
    /// velocities (m/s, rad/s). 20 sweeps: a humanoid collapsing on the
    /// ground (talos_reduced, g1) hit a 60-sweep cap in a third to two thirds
    /// of its steps at 1e-7 with no better end state; an iterate stopped by the
    /// cap is made energy-safe (`constraints`), so the cap costs accuracy in
    /// the force distribution only, never energy.
    pub solver_iterations: usize,
    /// The solve stops when no row's velocity changes by more than this in a
    /// sweep (m/s or rad/s).
    pub solver_tol: f64,
    /// The constraint solver: projected Gauss–Seidel (the default) or the
    /// primal Newton method ([`newton`]; benches/solver_compare.md measures both).
    pub solver: Solver,
    /// Over-relaxation of the solver's scalar rows (projected SOR), in (0, 2).
    /// 1.3 (over-relaxing only sweeps 4 to `solver_iterations`/2, then one plain
    /// sweep) cut the lamp drop's mean sweeps per step from 7.1 to 5.0 (same
    /// tolerance, same resting state) against plain Gauss–Seidel (1.0).
    pub solver_relaxation: f64,
    /// The fastest a joint-limit violation is undone by the position pass
    /// (rad/s or m/s; the contact's cap is `contact.max_push_speed`).
    pub limit_push_speed: f64,
    /// The divergence test of passive runs (`None`: off).
    pub max_energy_rise: Option<EnergyBound>,
    /// Still islands sleep (scene.md §"Large scenes"; default on).
    pub sleep: bool,
    /// The speed under which a shape's points count as still (m/s, 1e-3).
    pub sleep_velocity: f64,
    /// How long an island is still before it sleeps (s, 0.5).
    pub sleep_time: f64,
    /// Threads the islands are solved on (0: every core; 1 the default).
    pub threads: usize,
    /// Scene models that never sleep (their own `"sleep": false`), by name.
    pub never_sleep: Vec<String>,
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
            armature: 0.0,
            solver_iterations: 20,
            solver_tol: 1e-6,
            solver: Solver::Pgs,
            solver_relaxation: 1.3,
            limit_push_speed: 1.0,
            max_energy_rise: Some(EnergyBound {
                relative: 1e-2,
                absolute: 1e-2,
            }),
            sleep: true,
            sleep_velocity: 1e-3,
            sleep_time: 0.5,
            threads: 1,
            never_sleep: Vec::new(),
        }
    }
}

/// The joint springs of `model` (an MJCF joint's `stiffness` about its
/// `springref`, on hinge and slide joints) as servo gains and targets, `None`
/// when there is none (or joint dynamics are off).
fn joint_springs(model: &Model, on: bool) -> Option<(DVector<f64>, DVector<f64>)> {
    if !on
        || !model
            .dofs
            .iter()
            .any(|d| d.stiffness > 0.0 && d.kind.nv() == 1)
    {
        return None;
    }
    let mut kp = DVector::zeros(model.nv);
    let mut q_ref = model.neutral();
    for d in &model.dofs {
        if d.kind.nv() == 1 && d.stiffness.is_finite() && d.stiffness > 0.0 {
            kp[d.iv] = d.stiffness;
            q_ref[d.iq] = d.springref;
        }
    }
    Some((kp, q_ref))
}

/// The velocity-level constraint solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solver {
    /// Projected Gauss–Seidel on the Delassus matrix, exact disc cones ([`solver`]).
    #[default]
    Pgs,
    /// Primal Newton on nearly hard constraints, pyramidal cones ([`newton`]).
    Newton,
}

impl Solver {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Solver::Pgs => "pgs",
            Solver::Newton => "newton",
        }
    }
    /// The solver of a command-line name.
    pub fn from_name(s: &str) -> Option<Self> {
        [Solver::Pgs, Solver::Newton]
            .into_iter()
            .find(|x| x.name() == s)
    }
}

/// Why a simulation could not be set up or continue.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// Ground contact could not be set up (a collision mesh missing or unreadable).
    #[error(transparent)]
    Contact(#[from] ContactError),
    /// The dynamics failed (a joint moving only massless links, a singular mass matrix).
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// q or v turned non-finite (or an adaptive step size underflowed).
    #[error("the state turned non-finite at t = {t} s ({quantity})")]
    NonFinite {
        /// Simulated time of the failure (s).
        t: f64,
        /// The first non-finite quantity, by its trajectory column name (`q:NAME`, `v:NAME`).
        quantity: String,
    },
    /// A passive run whose energy rose past the bound.
    #[error("diverging at t = {t} s: the energy rose from {reference:.6e} J to {energy:.6e} J with no torque applied ({quantity} grew fastest)")]
    Diverging {
        /// Simulated time of the failure (s).
        t: f64,
        /// Mechanical energy now (J).
        energy: f64,
        /// The reference energy it rose from (J).
        reference: f64,
        /// The velocity coordinate whose magnitude grew most since the
        /// reference, by its column name (`v:NAME`).
        quantity: String,
    },
    /// A bad option or state (non-positive `dt`, wrong state length, …): the message.
    #[error("{0}")]
    Invalid(String),
}

/// A point of ground contact after a step: where, how deep, and its force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactForce {
    /// The contact point (link shape, world position, gap).
    pub point: ContactPoint,
    /// World-frame force on the link at `point.point` (N).
    pub force: Vector3<f64>,
}

/// Dense work of the implicit mass matrix H̃ = H + A + h·D.
#[derive(Clone, Debug)]
pub(crate) struct MassWork {
    /// The factor of the last H̃.
    f: factor::MassFactor,
    vfree: DVector<f64>,
    tau: DVector<f64>,
    vtot: DVector<f64>,
}

/// Work of the smooth (higher-order) steps.
#[derive(Clone, Debug)]
struct SmoothWork {
    data: Data,
    qn: DVector<f64>,
    vv: DVector<f64>,
    tau: DVector<f64>,
    /// Joint friction held constant over the step.
    tau_c: DVector<f64>,
    y: DVector<f64>,
    y_new: DVector<f64>,
    y_stage: DVector<f64>,
    k: Vec<DVector<f64>>,
    h_next: f64,
    fsal_ok: bool,
}

/// The divergence test's state.
#[derive(Clone, Debug)]
struct EnergyGuard {
    /// The reference energy (None: not set yet, or not passive).
    reference: Option<f64>,
    v_ref: DVector<f64>,
    /// Start violations are being recovered until this time.
    recovering_until: Option<f64>,
    /// M·|g|·1 m, the energy scale of the relative bound.
    scale: f64,
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
///
/// A `Simulation` clones (the model shared, contact shapes and workspace
/// copied): a batch of runs builds its meshes' hulls once and clones the prototype.
#[derive(Clone, Debug)]
pub struct Simulation {
    /// The model simulated (joints, limits, damping, collision geometry), shared.
    pub model: Arc<Model>,
    integrator: Integrator,
    dt: f64,
    tol: f64,
    opts: SimOptions,
    t: f64,
    q: DVector<f64>,
    v: DVector<f64>,
    /// Applied generalized forces (joint torques clamped to effort; base force/torque).
    tau_applied: DVector<f64>,
    /// Per-v-coordinate viscous damping, armature, effort limits.
    damping: DVector<f64>,
    armature: DVector<f64>,
    effort: Vec<f64>,
    has_damping: bool,
    has_armature: bool,
    data: Data,
    contact: Option<Collision>,
    points: Vec<ContactPoint>,
    /// `data.o_m_i` holds the world poses at the current `q`.
    fk_valid: bool,
    cons: Constraints,
    row_params: RowParams,
    mass: MassWork,
    smooth: SmoothWork,
    servo: servo::Servo,
    sensors: sensors::Sensors,
    forcing_changed: bool,
    guard: EnergyGuard,
    /// The energy at the current state, once computed.
    energy_now: Option<f64>,
    deriv: derivatives::Workspace,
    sleep: sleep::Sleep,
    /// Per tree: driven now (scratch of the sleep test).
    sleep_forced: Vec<bool>,
    /// Steps taken.
    pub steps: u64,
    /// Adaptive (`dop853`) steps rejected by the error test and retried
    /// shorter; not counted in `steps`.
    pub rejected: u64,
    /// Right-hand-side (dynamics) evaluations: one a time-stepping step, one a
    /// Runge–Kutta stage.
    pub rhs_evals: u64,
    /// Projected Gauss–Seidel sweeps and constraint rows, summed over the steps.
    pub pgs_sweeps: u64,
    /// Constraint rows solved, summed over the steps (rows / steps: the mean
    /// rows a step that touched anything).
    pub rows_total: u64,
}

impl Simulation {
    /// Sets up a simulation of `model` at its neutral configuration, at rest.
    /// Contact shapes (and meshes) are built here when `opts.ground` is set and a
    /// moving link has collision geometry.
    pub fn new(model: Model, opts: SimOptions) -> Result<Self, SimError> {
        let positive = |x: f64, name: &str| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(SimError::Invalid(format!(
                    "{name} must be a positive number (got {x})"
                )))
            }
        };
        positive(opts.dt, "--dt")?;
        positive(opts.tol, "--tol")?;
        positive(opts.limit_push_speed, "limit_push_speed")?;
        positive(opts.contact.max_push_speed, "contact.max_push_speed")?;
        positive(opts.sleep_velocity, "sleep_velocity")?;
        if !(opts.sleep_time.is_finite() && opts.sleep_time >= 0.0) {
            return Err(SimError::Invalid(format!(
                "sleep_time must be a non-negative number (got {})",
                opts.sleep_time
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
        let a = opts.armature;
        if !(a.is_finite() && a >= 0.0) {
            return Err(SimError::Invalid(format!(
                "--armature must be a non-negative number (got {a})"
            )));
        }
        crate::dynamics::check_massless(&model)?;
        // the ground, obstacles and pairs of bodies (none of them: no contact work)
        let contact = Collision::build(&model, opts.ground, opts.contact, &opts.package_paths)?;
        let integrator = opts
            .integrator
            .unwrap_or(Integrator::default_for(contact.is_some()));
        let (nq, nv) = (model.nq, model.nv);
        let mut damping = DVector::zeros(nv);
        let mut armature = DVector::zeros(nv);
        let mut effort = vec![f64::INFINITY; nv];
        for (d, _, iv) in model.dof_indices() {
            let info = &model.dofs[d];
            // --armature on every joint, plus the model's own (an MJCF joint's
            // `armature`: MuJoCo's qM diagonal)
            armature[iv] = a + info.armature.max(0.0);
            if opts.joint_dynamics {
                damping[iv] = if info.damping.is_finite() {
                    info.damping.max(0.0)
                } else {
                    0.0
                };
                if let Some(e) = info.limits.effort {
                    if e > 0.0 {
                        effort[iv] = e;
                    }
                }
            }
        }
        let max_points = contact.as_ref().map_or(0, |c| c.max_points());
        let pair_points = contact
            .as_ref()
            .and_then(|c| c.pairs.as_ref())
            .map_or(0, |p| p.max_points());
        let mass_factor = factor::MassFactor::new(&model);
        let nslots = contact.as_ref().map_or(0, |c| c.nslots);
        let row_params = RowParams {
            joint_dynamics: opts.joint_dynamics,
            restitution: opts.contact.restitution,
            gravity: model.gravity.norm(),
            beta: opts.contact.baumgarte,
            contact_push_cap: opts.contact.max_push_speed,
            limit_push_cap: opts.limit_push_speed,
            contact_slop: opts.contact.slop,
            limit_slop: 1e-4,
        };
        let total_mass: f64 = model.inertias.iter().skip(1).map(|i| i.mass).sum();
        let scale = total_mass * model.gravity.norm();
        let has_damping = damping.iter().any(|&d| d > 0.0);
        let has_armature = armature.iter().any(|&x| x > 0.0);
        let springs = joint_springs(&model, opts.joint_dynamics);
        let spheres = contact.as_ref().map_or(Vec::new(), |c| c.body_spheres());
        let sleep = sleep::Sleep::new(
            &model,
            opts.sleep,
            opts.sleep_velocity,
            opts.sleep_time,
            spheres,
            &opts.never_sleep,
        );
        let mut sim = Self {
            sleep,
            sleep_forced: vec![false; model.trees.len()],
            integrator,
            dt: opts.dt,
            tol: opts.tol,
            t: 0.0,
            q: model.neutral(),
            v: DVector::zeros(nv),
            tau_applied: DVector::zeros(nv),
            damping,
            armature,
            effort,
            has_damping,
            has_armature,
            data: Data::new(&model),
            cons: Constraints::new(
                &model,
                &mass_factor,
                max_points,
                pair_points,
                nslots,
                opts.solver == Solver::Newton,
            ),
            contact,
            points: Vec::with_capacity(max_points),
            fk_valid: false,
            row_params,
            mass: MassWork {
                f: mass_factor,
                vfree: DVector::zeros(nv),
                tau: DVector::zeros(nv),
                vtot: DVector::zeros(nv),
            },
            smooth: SmoothWork {
                data: Data::new(&model),
                qn: model.neutral(),
                vv: DVector::zeros(nv),
                tau: DVector::zeros(nv),
                tau_c: DVector::zeros(nv),
                y: DVector::zeros(nq + nv),
                y_new: DVector::zeros(nq + nv),
                y_stage: DVector::zeros(nq + nv),
                k: (0..13).map(|_| DVector::zeros(nq + nv)).collect(),
                h_next: opts.dt,
                fsal_ok: false,
            },
            servo: servo::Servo::new(&model, &model.neutral()),
            sensors: sensors::Sensors::new(nq, nv),
            forcing_changed: true,
            energy_now: None,
            guard: EnergyGuard {
                reference: None,
                v_ref: DVector::zeros(nv),
                recovering_until: None,
                scale,
            },
            steps: 0,
            rejected: 0,
            rhs_evals: 0,
            pgs_sweeps: 0,
            rows_total: 0,
            opts,
            model: Arc::new(model),
            deriv: Default::default(),
        };
        if let Some((kp, q_ref)) = springs {
            // joint springs (MJCF `stiffness`/`springref`) are servos without
            // damping gain: τ = k (springref − q), integrated implicitly
            sim.set_targets(&q_ref, None)?;
            sim.set_gains(&kp, &DVector::zeros(nv))?;
        }
        sim.state_changed();
        Ok(sim)
    }

    /// The integrator in use (`SimOptions::integrator`, or the scene's default).
    pub fn integrator(&self) -> Integrator {
        self.integrator
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
    fn state_changed(&mut self) {
        self.sensors.forget();
        self.smooth.fsal_ok = false;
        self.cons.reset_warm_start();
        self.sleep.wake_all(&self.model);
        if self.steps == 0 {
            self.decide_start_overlaps();
        }
        self.refresh_contacts();
        self.guard.reference = None;
        self.guard.recovering_until = if !self.violates() {
            let e = self.update_energy();
            if e.is_finite() {
                self.guard.reference = Some(e);
                self.guard.v_ref.copy_from(&self.v);
            }
            None
        } else {
            Some(self.t + 2.0)
        };
    }

    /// Whether the state violates a constraint ([`Simulation::start_violations`]
    /// non-empty), found without building the list (a scene's models all at
    /// the origin at construction overlap pairwise).
    fn violates(&self) -> bool {
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
    fn spring_energy(&self) -> f64 {
        let mut e = 0.0;
        for d in &self.model.dofs {
            if d.stiffness > 0.0 && d.stiffness.is_finite() && d.kind.nv() == 1 {
                let x = self.q[d.iq] - d.springref;
                e += 0.5 * d.stiffness * x * x;
            }
        }
        e
    }

    /// The rotors' kinetic energy `½ Σ A v²` (0 without an armature).
    fn armature_energy(&self) -> f64 {
        if !self.has_armature {
            return 0.0;
        }
        let mut e = 0.0;
        for (a, v) in self.armature.iter().zip(self.v.iter()) {
            e += 0.5 * a * v * v;
        }
        e
    }

    /// [`Simulation::energy`], cached until the state changes (the energy guard's
    /// path: the poses of the last contact refresh reused).
    fn update_energy(&mut self) -> f64 {
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
        let e = kinetic_energy_from_placements(&self.model, &mut self.data, &self.v)
            .unwrap_or(f64::NAN)
            + potential_energy(&self.model, &self.data)
            + self.armature_energy()
            + self.spring_energy();
        self.energy_now = Some(e);
        e
    }

    /// Before the first step: the self pairs overlapping at this state are
    /// dropped (scene.md "Who touches whom" rule 4; decided anew at each state
    /// set before the run starts).
    fn decide_start_overlaps(&mut self) {
        let Some(c) = self.contact.as_mut() else {
            return;
        };
        if c.pairs.is_none() {
            return;
        }
        forward_kinematics(&self.model, &mut self.data, &self.q);
        c.drop_start_overlaps(&self.model, &self.data.o_m_i);
    }

    /// Forward kinematics and contact detection at the current q.
    fn refresh_contacts(&mut self) {
        self.fk_valid = false;
        self.energy_now = None;
        if let Some(c) = self.contact.as_mut() {
            forward_kinematics(&self.model, &mut self.data, &self.q);
            c.detect(&self.data.o_m_i, &mut self.points, &self.sleep.body_asleep);
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
        let h = if time_stepping {
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
        self.t = if h >= remaining { t_end } else { self.t + h };
        self.sensors.end(h);
        self.steps += 1;
        self.sleep.hold(&self.model, &mut self.q, &mut self.v);
        normalize_quats(&self.model, &mut self.q);
        // 3. the new state: finite, its contacts, its energy
        self.check_finite()?;
        self.fk_valid = false;
        self.refresh_contacts();
        if self.cons.loops.is_some() {
            self.clip_loop_energy();
        }
        self.update_sleep(h);
        self.check_energy()?;
        Ok(h)
    }

    /// The longest step in which no joint moving toward a limit can reach it
    /// at twice its current speed (+∞ when none moves toward one). A joint
    /// within reach at `dt` has a row already (the step is time stepping).
    fn limit_reach_cap(&self) -> f64 {
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
    fn assemble_rows(&mut self, h: f64) -> constraints::RowCounts {
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

    fn check_finite(&self) -> Result<(), SimError> {
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
    fn check_energy(&mut self) -> Result<(), SimError> {
        let Some(bound) = self.opts.max_energy_rise else {
            return Ok(());
        };
        if self.servo.active || self.tau_applied.iter().any(|&x| x != 0.0) {
            self.guard.reference = None;
            return Ok(());
        }
        if let Some(until) = self.guard.recovering_until {
            let (depth, excess) = self.worst_violation();
            let recovered = self.t >= until || (depth <= 1e-3 && excess <= 1e-3);
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

    /// Applied generalized force with joint torques clamped to effort limits.
    fn clamped_tau(&self, out: &mut DVector<f64>) {
        for (k, o) in out.iter_mut().enumerate() {
            let e = self.effort[k];
            *o = self.tau_applied[k].clamp(-e, e);
        }
    }
}

/// A joint's limits (±∞ where the URDF gives none) and how far `q` lies
/// outside them (negative inside).
fn limit_excess(info: &crate::model::DofInfo, q: f64) -> (f64, f64, f64) {
    let lower = info.limits.lower.unwrap_or(f64::NEG_INFINITY);
    let upper = info.limits.upper.unwrap_or(f64::INFINITY);
    (lower, upper, (lower - q).max(q - upper))
}

/// `dt`, or the remaining time when that is shorter or exceeds `dt` by less
/// than a tenth of it (no sliver step at the end of a run).
fn land(dt: f64, remaining: f64) -> f64 {
    if remaining <= dt * 1.1 {
        remaining
    } else {
        dt
    }
}

/// The trajectory column names of q and v (cli.md, mechanisms.md): `q:` and `v:`
/// before each of [`Model::q_names`] and [`Model::v_names`] (a floating base
/// first: `q:base_x … q:base_qw`, `v:base_vx … v:base_wz`; a spherical joint
/// `q:J:qx …`, `v:J:wx …`).
pub fn column_names(model: &Model) -> (Vec<String>, Vec<String>) {
    (
        model.q_names().iter().map(|n| format!("q:{n}")).collect(),
        model.v_names().iter().map(|n| format!("v:{n}")).collect(),
    )
}

/// Whether a model's joint kinds are all supported by
/// [`integrate_config`](crate::model::configuration::integrate_config).
pub fn supports(model: &Model) -> bool {
    model
        .joints
        .iter()
        .enumerate()
        .skip(1)
        .all(|(b, j)| match j.kind {
            JointKind::Free => {
                model.free_joints.iter().any(|f| f.body == b)
                    || model.dofs.iter().any(|d| d.iv == j.iv && d.kind == j.kind)
            }
            _ => true,
        })
}
