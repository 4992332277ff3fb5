//! `urdyn simulate` (cli.md): run a [`Simulation`] and write its trajectory CSV.
//! Stages: [`checks`] (the options, the start's violations), [`setup`] (a URDF
//! or a scene; MJCF files in `simulate_mjcf`), [`record`] (the stepping loop and
//! the CSV writer).

mod checks;
mod record;
mod setup;

use crate::cli::output::write_atomic;
use crate::cli::state;
use crate::sim::{SimError, SimOptions, Simulation};
use crate::Model;
use std::io::Write;
use std::path::PathBuf;

/// The command's options, as cli.md lists them.
#[derive(Clone, Debug)]
pub struct SimulateArgs {
    /// The URDF file (unused with `scene`).
    pub urdf: PathBuf,
    /// A scene file (scene.md) in place of the URDF: its models, obstacles,
    /// ground, friction and starting state. The per-model options
    /// (`floating_base`, `initial`, `above_ground`, `ground`, `no_ground`) are
    /// then an error; `friction` is ignored (the binary refuses `--friction`).
    pub scene: Option<PathBuf>,
    /// Give the root link a free 6-DoF joint (unit quaternion).
    pub floating_base: bool,
    /// Simulated seconds.
    pub duration: f64,
    /// Step (the first step of an adaptive integrator), s (`None`: an MJCF
    /// file's `<option timestep>`, else [`DEFAULT_DT`]).
    pub dt: Option<f64>,
    /// `--key NAME`: start an MJCF model from its `<keyframe><key name>`.
    pub key: Option<String>,
    /// `--controls FILE.csv`: an MJCF model's actuator controls over time
    /// (a `t` column and one column per actuator, held piecewise constant).
    pub controls: Option<PathBuf>,
    /// Integrator name (`None`: the project's best general choice).
    pub integrator: Option<String>,
    /// Error tolerance of adaptive integrators.
    pub tol: f64,
    /// One state object (as in eval's `states`) to start from.
    pub initial: Option<PathBuf>,
    /// Rotor inertia added to every joint's diagonal of H (finite, >= 0).
    pub armature: f64,
    /// With a floating base: lift or lower the base so that the collision
    /// geometry's lowest point is this far above the ground (after `initial`).
    pub above_ground: Option<f64>,
    /// Ground plane height (`None`: 0).
    pub ground: Option<f64>,
    /// No ground plane: no contact at all.
    pub no_ground: bool,
    /// Gravity vector (`None`: the model's).
    pub gravity: Option<[f64; 3]>,
    /// Coulomb friction coefficient between links and the ground.
    pub friction: f64,
    /// Roots for `package://NAME/...` mesh paths.
    pub package_path: Vec<PathBuf>,
    /// The trajectory CSV (written atomically).
    pub out: Option<PathBuf>,
    /// Also write the replay page of `urdyn view` for this run, with its contacts
    /// (written atomically after the trajectory).
    pub html: Option<PathBuf>,
    /// Write every Nth step (the final state always).
    pub every: usize,
    /// Show a progress bar (the binary sets this when standard error is a terminal).
    pub progress: bool,
    /// `--no-sleep`: no island sleeps (scene.md §"Large scenes").
    pub no_sleep: bool,
    /// `--threads N` (0: every core; `None`: the scene's, else 1).
    pub threads: Option<usize>,
}

impl SimulateArgs {
    /// The options of `urdyn simulate MODEL` with every other option at its
    /// default (cli.md): 1 s, the default step and integrator, a ground at 0
    /// with friction 1, sleep on, nothing written.
    pub fn new(model: impl Into<PathBuf>) -> Self {
        SimulateArgs {
            urdf: model.into(),
            scene: None,
            floating_base: false,
            duration: 1.0,
            dt: None,
            key: None,
            controls: None,
            integrator: None,
            tol: 1e-6,
            initial: None,
            armature: 0.0,
            above_ground: None,
            ground: None,
            no_ground: false,
            gravity: None,
            friction: 1.0,
            package_path: Vec::new(),
            out: None,
            html: None,
            every: 1,
            progress: false,
            no_sleep: false,
            threads: None,
        }
    }

    /// The options of `urdyn simulate --scene SCENE`, the rest at their defaults.
    pub fn scene(scene: impl Into<PathBuf>) -> Self {
        SimulateArgs {
            scene: Some(scene.into()),
            ..SimulateArgs::new(PathBuf::new())
        }
    }
}

/// The step when neither `--dt` nor an MJCF file's `<option timestep>` gives one (s).
pub const DEFAULT_DT: f64 = 1e-3;

/// What a run did (the summary line).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the step loop.
    pub wall_seconds: f64,
    /// Simulated seconds.
    pub simulated_seconds: f64,
    /// Simulated over wall-clock seconds.
    pub real_time_factor: f64,
    /// Mechanical energy at the start (J).
    pub energy_start: f64,
    /// Mechanical energy at the end (J).
    pub energy_end: f64,
    /// Deepest penetration into the ground during the run (m).
    pub max_penetration: f64,
    /// The integrator's name.
    pub integrator: &'static str,
    /// Narrow-phase contact queries made.
    pub contact_queries: u64,
    /// The mean number of awake models with degrees of freedom over the steps.
    pub mean_awake: f64,
    /// The largest loop-constraint violation over the run (m or rad; `None`
    /// without loop constraints).
    pub max_constraint_violation: Option<f64>,
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "simulate: {} steps ({}) in {:.4} s wall, real-time factor {:.1}, energy {:.9e} J -> {:.9e} J, deepest penetration {:.3e} m",
            self.steps,
            self.integrator,
            self.wall_seconds,
            self.real_time_factor,
            self.energy_start,
            self.energy_end,
            self.max_penetration,
        )?;
        if let Some(c) = self.max_constraint_violation {
            write!(f, ", largest constraint violation {c:.3e}")?;
        }
        write!(f, ", mean awake {:.2}", self.mean_awake)
    }
}

/// A failed run: one line naming the file, option or quantity.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The URDF could not be imported.
    #[error(transparent)]
    Urdf(#[from] crate::UrdfError),
    /// The MJCF file could not be imported.
    #[error(transparent)]
    Mjcf(#[from] crate::mjcf::MjcfError),
    /// The scene file is malformed or names what does not exist.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The `--initial` state is malformed.
    #[error(transparent)]
    State(#[from] state::StateError),
    /// (Not a `#[source]`: the message already carries the cause, and the CLI
    /// prints the chain — it would appear twice.)
    /// The simulation failed (diverged, turned non-finite, ...).
    #[error("{urdf}: {error}")]
    Sim {
        /// The URDF file.
        urdf: String,
        /// What went wrong.
        error: SimError,
    },
    /// A bad option value.
    #[error("{0}")]
    Option(String),
    /// The trajectory could not be written.
    #[error("{0}")]
    Output(String),
    /// The replay page (`--html`) could not be made.
    #[error(transparent)]
    View(#[from] crate::cli::view::ViewError),
}

/// Runs the command. The trajectory file is written atomically: a failed run
/// (bad input, a state turning non-finite) leaves no file.
pub fn run(args: &SimulateArgs) -> Result<Summary, SimulateError> {
    let integrator = checks::options(args)?;
    let (mut model, init, opts, mut geometry, urdf_name, loops) = match &args.scene {
        Some(path) => setup::scene(args, path, integrator)?,
        None if crate::load::file_format(&args.urdf) == crate::load::Format::Mjcf => {
            super::simulate_mjcf::setup(args, integrator)?
        }
        None => setup::urdf(args, integrator)?,
    };
    if let Some(g) = args.gravity {
        model.gravity = nalgebra::Vector3::new(g[0], g[1], g[2]);
    }
    for w in geometry.iter().flat_map(|g| &g.warnings) {
        warn(&format!("warning: {w}"));
    }
    let ground = opts.ground;
    let sim_err = |error| SimulateError::Sim {
        urdf: urdf_name.clone(),
        error,
    };
    // at the start state at once: contacts are not looked for with every
    // model of a scene at the origin first (O(N²))
    let mut sim = match &init {
        Some(sv) => Simulation::new_at(model, opts, &sv.q, &sv.v),
        None => Simulation::new(model, opts),
    }
    .map_err(sim_err)?;
    if let Some(sv) = &init {
        sim.torques_mut().copy_from(&sv.tau);
    }
    // loop constraints: world anchors left out are placed at the start state; a
    // start violating one by more than 1 mm is one warning line (mechanisms.md)
    if let Some(set) = loops {
        for line in sim.set_constraints(set).map_err(sim_err)? {
            warn(&format!("warning: {urdf_name}: {line}"));
        }
    } else if !sim.model.equalities.items.is_empty() {
        // an MJCF file's equalities (Simulation::new set them) at its start state
        for line in sim.constraint_start_lines() {
            warn(&format!("warning: {urdf_name}: {line}"));
        }
    }
    // MJCF actuators: --key's ctrl, then --controls' rows as time reaches them
    let mut schedule = super::simulate_mjcf::schedule(args, &sim.model)?;
    if let Some(s) = &mut schedule {
        s.apply_due(&mut sim).map_err(sim_err)?;
    }
    if let Some(h) = args.above_ground {
        if !sim.lift_above_ground(h).map_err(sim_err)? {
            warn(&format!(
                "warning: {urdf_name}: --above-ground {h}: no collision geometry touches a ground in this run, nothing moved"
            ));
        }
    }
    checks::warn_start(&sim, &urdf_name);
    let mut recorder = args
        .html
        .as_ref()
        .map(|_| crate::cli::view::Recorder::new(&sim.model, args.duration, true));
    let mut run = record::Run {
        sim: &mut sim,
        schedule: schedule.as_mut(),
        recorder: recorder.as_mut(),
        name: &urdf_name,
        duration: args.duration,
        every: args.every,
        progress: args.progress,
    };
    let summary = match &args.out {
        Some(path) => {
            let mut result = None;
            write_atomic(path, |w| match record::record(&mut run, Some(w)) {
                Ok(s) => {
                    result = Some(s);
                    Ok(())
                }
                Err(e) => Err(e.to_string()),
            })
            .map_err(SimulateError::Output)?;
            result.ok_or_else(|| SimulateError::Output("no result".into()))
        }
        None => record::record(&mut run, None),
    }?;
    if let (Some(path), Some(geometry), Some(recorder)) = (&args.html, &mut geometry, &recorder) {
        if let Some(set) = sim.constraints() {
            geometry.set_loops(set);
        }
        let page = crate::cli::view::write_page(path, &sim.model, geometry, recorder, ground)?;
        warn(&format!(
            "urdyn simulate: wrote the replay page {} ({})",
            path.display(),
            page.to_string().trim_start_matches("view: ")
        ));
    }
    Ok(summary)
}

/// What a run starts from: the model, its starting state, the options, the
/// page's geometry (with `--html`) and the name in messages.
pub(crate) type Setup = (
    Model,
    Option<state::StateVectors>,
    SimOptions,
    Option<crate::cli::view::Geometry>,
    String,
    Option<crate::model::Constraints>,
);

/// One warning line on standard error (the run goes on).
pub(crate) fn warn(line: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}
