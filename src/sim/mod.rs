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
mod equalities;
pub mod factor;
mod factor_dense;
mod loops;
mod tendons;
pub use loops::LoopForce;
pub(crate) mod integrators;
mod islands;
pub mod newton;
pub(crate) mod parallel;
pub use contact_view::Violation;
mod build;
pub use build::MAX_THREADS;
mod doze;
mod sensors;
mod servo;
mod sleep;
pub mod solver;
mod state;
mod step;

pub use derivatives::{JacobianMethod, TransitionJacobians};
pub use integrators::Integrator;

use crate::contact::{Collision, ContactError, ContactParams, ContactPoint};
use crate::dynamics::DynamicsError;
use crate::dynamics::{
    forward_kinematics_pass as forward_kinematics, kinetic_energy_step_ahead, potential_energy,
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
    /// Threads the islands are solved on (0: every core; 1 the default; at
    /// most 1024).
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
    /// The joints of `Model::dofs` that are free or planar (the semi-implicit
    /// step's frame-rate terms: src/sim/integrators/euler.rs), in order.
    frame_dofs: Vec<usize>,
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
    /// Some 1-DoF joint has a spring (`Simulation::spring_energy` is not 0).
    springs: bool,
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
