//! The command line's arguments (clap), as cli.md lists them.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "urdyn",
    version,
    about = "URDF-driven rigid multibody dynamics (Featherstone spatial vectors)"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Print the kinematic tree, degrees of freedom, masses, merged links, collision
    /// geometry and warnings of a URDF or an MJCF file.
    Inspect {
        /// The URDF or MJCF file (root `<robot>` or `<mujoco>`).
        urdf: PathBuf,
        /// Give the root link a free 6-DoF joint (unit quaternion) instead of welding it.
        #[arg(long)]
        floating_base: bool,
        /// A root for package://NAME/... mesh paths (repeatable; ROS_PACKAGE_PATH is also read).
        #[arg(long, value_name = "DIR")]
        package_path: Vec<PathBuf>,
        /// Treat every warning as an error: fail (non-zero exit) with the first one.
        #[arg(long)]
        strict: bool,
        /// Print one JSON object (mass properties per link or MJCF body, q and v
        /// names, warnings) instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// Evaluate inverse dynamics, forward dynamics, C(q, v), H(q) and link poses for a
    /// batch of states (JSON in, JSON out; see eval-contract.md).
    Eval {
        /// The URDF or MJCF file (a URDF's mesh files are never read).
        urdf: PathBuf,
        /// The states JSON file.
        #[arg(long, value_name = "STATES.json")]
        states: PathBuf,
        /// Give the root link a free 6-DoF joint (unit quaternion) instead of welding it.
        #[arg(long)]
        floating_base: bool,
        /// Write the result here (atomically) instead of standard output.
        #[arg(long, value_name = "OUT.json")]
        output: Option<PathBuf>,
    },
    /// Simulate the robot, an MJCF world or a scene (joint damping, friction, limits from
    /// the file; contact with the ground, between the robot's own links and, with
    /// --scene, between models and with obstacles) and write its trajectory as CSV.
    Simulate(Box<SimulateCmd>),
    /// Time each dynamics algorithm on random states of this robot (median ns per call).
    Bench(BenchArgs),
    /// Write one self-contained HTML page that replays a trajectory CSV of `simulate`
    /// in 3D (no network, no other file; opens from disk in any current browser).
    View {
        /// The URDF or MJCF file (with --scene: the trajectory CSV).
        urdf: Option<PathBuf>,
        /// The trajectory CSV that `simulate --out` wrote.
        traj: Option<PathBuf>,
        /// A scene file (scene.md) in place of the URDF: `view --scene SCENE.json TRAJ.csv`.
        #[arg(long, value_name = "SCENE.json")]
        scene: Option<PathBuf>,
        /// The root link has a free 6-DoF joint (as when the trajectory was simulated).
        #[arg(long)]
        floating_base: bool,
        /// A root for package://NAME/... mesh paths (repeatable; ROS_PACKAGE_PATH is also read).
        #[arg(long, value_name = "DIR")]
        package_path: Vec<PathBuf>,
        /// The page to write (atomically).
        #[arg(long, value_name = "PAGE.html")]
        out: PathBuf,
    },
}

/// `urdyn simulate` options (cli.md).
#[derive(clap::Args)]
#[command(
    after_help = "Contact is between the links' collision geometry and the ground plane, and between two links of one robot (self-collision) that are not a body and its parent, not on one body, not both welded to the world and not a <disable_collisions> pair of an SRDF; pairs that overlap at the start are dropped with a warning. With --scene, also between the models and with the scene's obstacles (scene.md \"Who touches whom\"). An MJCF world's contact follows its file (contype/conaffinity, the parent-child filter, <exclude>, <pair>; planes facing up are the ground). Contact model: velocity-level impulses with exact Coulomb friction (stick and slip), solved each step."
)]
pub(crate) struct SimulateCmd {
    /// The URDF or MJCF file.
    pub(crate) urdf: Option<PathBuf>,
    /// A scene file (scene.md: several models, obstacles, ground) in place of the URDF;
    /// the per-model options (--floating-base, --initial, --above-ground, --ground,
    /// --no-ground, --friction) live in the file.
    #[arg(long, value_name = "SCENE.json")]
    pub(crate) scene: Option<PathBuf>,
    /// Give the root link a free 6-DoF joint (unit quaternion, no Euler angles).
    #[arg(long)]
    pub(crate) floating_base: bool,
    /// Simulated seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 2.0,
        allow_hyphen_values = true
    )]
    pub(crate) duration: f64,
    /// Step in seconds (the first step of an adaptive integrator) [default: 0.001; an MJCF file's <option timestep>].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub(crate) dt: Option<f64>,
    /// Start an MJCF model from its keyframe <key name="NAME">.
    #[arg(long, value_name = "NAME")]
    pub(crate) key: Option<String>,
    /// An MJCF model's actuator controls: a CSV with a t column and one column per actuator name, held piecewise constant.
    #[arg(long, value_name = "FILE.csv")]
    pub(crate) controls: Option<PathBuf>,
    /// Integrator (see --list-integrators); default: euler with ground contact, dop853 without.
    #[arg(long, value_name = "NAME")]
    pub(crate) integrator: Option<String>,
    /// Print the available integrator names, one a line, and exit.
    #[arg(long)]
    pub(crate) list_integrators: bool,
    /// Error tolerance of adaptive integrators: RMS_i(e_i / (X + X*|y_i|)) <= 1 per step (fixed-step ones ignore it).
    #[arg(
        long,
        value_name = "X",
        default_value_t = 1e-6,
        allow_hyphen_values = true
    )]
    pub(crate) tol: f64,
    /// One state object as in eval's states list (q, v, base, tau and base.force/torque as constant forces).
    #[arg(long, value_name = "STATE.json")]
    pub(crate) initial: Option<PathBuf>,
    /// With --floating-base: before the first step, move the base vertically so that the
    /// lowest point of the collision geometry is H above the ground (after --initial).
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub(crate) above_ground: Option<f64>,
    /// Rotor inertia added to every joint's diagonal of H (kg·m² or kg).
    #[arg(
        long,
        value_name = "X",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub(crate) armature: f64,
    /// Ground plane height (contact on when any moving link has collision geometry).
    #[arg(
        long,
        value_name = "Z",
        allow_hyphen_values = true,
        conflicts_with = "no_ground"
    )]
    pub(crate) ground: Option<f64>,
    /// No ground plane: no contact at all.
    #[arg(long)]
    pub(crate) no_ground: bool,
    /// No island sleeps (sleep is on by default: still islands stop costing).
    #[arg(long)]
    pub(crate) no_sleep: bool,
    /// Threads the islands are solved on (0: every core; at most 1024; default the scene's, else 1).
    #[arg(long, value_name = "N")]
    pub(crate) threads: Option<usize>,
    /// Gravity vector.
    #[arg(
        long,
        value_name = "GX,GY,GZ",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub(crate) gravity: Option<Vec<f64>>,
    /// Coulomb friction coefficient between links and the ground [default: 1.0].
    #[arg(long, value_name = "MU", allow_hyphen_values = true)]
    pub(crate) friction: Option<f64>,
    /// A root for package://NAME/... mesh paths (repeatable; ROS_PACKAGE_PATH is also read).
    #[arg(long, value_name = "DIR")]
    pub(crate) package_path: Vec<PathBuf>,
    /// Trajectory CSV file (written atomically).
    #[arg(long, value_name = "TRAJ.csv")]
    pub(crate) out: Option<PathBuf>,
    /// Also write the 3D replay page of `urdyn view` for this run, with its contact
    /// points and forces.
    #[arg(long, value_name = "PAGE.html")]
    pub(crate) html: Option<PathBuf>,
    /// Write every Nth step (the final state is always written).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_hyphen_values = true
    )]
    pub(crate) every: i64,
}

#[derive(clap::Args)]
pub(crate) struct BenchArgs {
    /// The URDF or MJCF file.
    pub(crate) urdf: PathBuf,
    /// Give the root link a free 6-DoF joint (unit quaternion) instead of welding it.
    #[arg(long)]
    pub(crate) floating_base: bool,
    /// Time only this algorithm (repeatable): rnea, bias, crba, aba, fd-rnea, fd-crba, fd, fk,
    /// rnea-derivatives, aba-derivatives, jacobians, constraint-dynamics,
    /// constraint-dynamics-derivatives (the last two need --hold, --hold6 or --weld).
    #[arg(long = "algo", value_name = "NAME")]
    pub(crate) algos: Vec<String>,
    /// Timed samples per algorithm (each a batch of calls of about 50 µs).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 300,
        allow_hyphen_values = true
    )]
    pub(crate) samples: i64,
    /// Soft time limit per algorithm in seconds (lowers the samples, never below 5).
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 1.5,
        allow_hyphen_values = true
    )]
    pub(crate) budget: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub(crate) json: bool,
    /// A `point` constraint holding LINK's origin where it is in the first sampled
    /// state (repeatable; for constraint-dynamics, mechanisms.md).
    #[arg(long = "hold", value_name = "LINK")]
    pub(crate) hold: Vec<String>,
    /// A `frame` constraint holding LINK's frame where it is in the first sampled state.
    #[arg(long = "hold6", value_name = "LINK")]
    pub(crate) hold6: Vec<String>,
    /// A `frame` constraint welding two links' frames together (L1,L2).
    #[arg(long = "weld", value_name = "L1,L2")]
    pub(crate) weld: Vec<String>,
}
