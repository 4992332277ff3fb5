//! `urdyn simulate` (cli.md): run a [`Simulation`] and write its trajectory CSV.

use crate::cli::output::write_atomic;
use crate::cli::state;
use crate::sim::{column_names, Integrator, SimError, SimOptions, Simulation};
use crate::{LoadOptions, Model};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

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
    if !(args.duration.is_finite() && args.duration >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--duration must be a non-negative number (got {})",
            args.duration
        )));
    }
    if let Some(dt) = args.dt
        && !(dt.is_finite() && dt > 0.0)
    {
        return Err(SimulateError::Option(format!(
            "--dt must be a positive number (got {dt})"
        )));
    }
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return Err(SimulateError::Option(format!(
            "--tol must be a positive number (got {})",
            args.tol
        )));
    }
    if !(args.friction.is_finite() && args.friction >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--friction must be a non-negative number (got {})",
            args.friction
        )));
    }
    if args.every == 0 {
        return Err(SimulateError::Option("--every must be at least 1".into()));
    }
    if !(args.armature.is_finite() && args.armature >= 0.0) {
        return Err(SimulateError::Option(format!(
            "--armature must be a non-negative number (got {})",
            args.armature
        )));
    }
    if let Some(h) = args.above_ground {
        if !h.is_finite() {
            return Err(SimulateError::Option(format!(
                "--above-ground must be a finite number (got {h})"
            )));
        }
        if !args.floating_base {
            return Err(SimulateError::Option(
                "--above-ground needs --floating-base (a fixed root cannot be moved)".into(),
            ));
        }
    }
    let integrator = match &args.integrator {
        None => None,
        Some(n) => Some(Integrator::from_name(n).ok_or_else(|| {
            let names: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
            SimulateError::Option(format!(
                "--integrator: unknown integrator \"{n}\" (one of: {})",
                names.join(", ")
            ))
        })?),
    };
    if let Some(g) = args.gravity {
        if !g.iter().all(|x| x.is_finite()) {
            return Err(SimulateError::Option(
                "--gravity: non-finite component".into(),
            ));
        }
    }
    if let Some(g) = args.ground {
        if !g.is_finite() {
            return Err(SimulateError::Option(
                "--ground must be a finite number".into(),
            ));
        }
    }
    if let (Some(scene), Some(k)) = (&args.scene, &args.key) {
        return Err(SimulateError::Option(format!(
            "--key {k}: keyframes belong to MJCF files, not to the scene {}",
            scene.display()
        )));
    }
    if let Some(scene) = &args.scene {
        let given = [
            (args.floating_base, "--floating-base"),
            (args.initial.is_some(), "--initial"),
            (args.above_ground.is_some(), "--above-ground"),
            (args.ground.is_some(), "--ground"),
            (args.no_ground, "--no-ground"),
        ];
        if let Some((_, opt)) = given.iter().find(|(g, _)| *g) {
            return Err(SimulateError::Option(format!(
                "{opt} is a per-model option: with --scene it lives in the scene file {} (scene.md)",
                scene.display()
            )));
        }
    }
    let (mut model, init, opts, mut geometry, urdf_name, loops) = match &args.scene {
        Some(path) => scene_setup(args, path, integrator)?,
        None if crate::load::file_format(&args.urdf) == crate::load::Format::Mjcf => {
            super::simulate_mjcf::setup(args, integrator)?
        }
        None => urdf_setup(args, integrator)?,
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
    let mut sim = Simulation::new(model, opts).map_err(sim_err)?;
    if let Some(sv) = &init {
        sim.set_state(&sv.q, &sv.v).map_err(sim_err)?;
        sim.torques_mut().copy_from(&sv.tau);
    }
    // loop constraints: world anchors left out are placed at the start state; a
    // start violating one by more than 1 mm is one warning line (mechanisms.md)
    if let Some(set) = loops {
        for line in sim.set_constraints(set).map_err(sim_err)? {
            warn(&format!("warning: {urdf_name}: {line}"));
        }
    }
    let has_loops = sim.has_constraints();
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
    // a start that violates a constraint: one line for the ground (its deepest
    // link), one a joint outside its limits, one a pair of shapes inside each
    // other (a link in an obstacle or another body); the run recovers gently
    let violations = sim.start_violations();
    let in_ground: Vec<_> = violations
        .iter()
        .filter_map(|v| match v {
            crate::sim::Violation::Ground { link, depth } => Some((link, *depth)),
            _ => None,
        })
        .collect();
    if let Some(&(link, depth)) = in_ground.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        let others = match in_ground.len() - 1 {
            0 => String::new(),
            1 => " (and 1 other link)".into(),
            n => format!(" (and {n} other links)"),
        };
        warn(&format!(
            "warning: {urdf_name}: link \"{link}\" starts {depth:.4} m inside the ground{others}; pushed out at most {} m/s",
            sim.options().contact.max_push_speed
        ));
    }
    for v in violations.iter().filter(|v| {
        matches!(
            v,
            crate::sim::Violation::Limit { .. } | crate::sim::Violation::Overlap { .. }
        )
    }) {
        warn(&format!("warning: {urdf_name}: {v}"));
    }
    let duration = args.duration;
    let every = args.every;
    let progress = if args.progress && duration > 0.0 {
        let pb = indicatif::ProgressBar::new(1000);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% t = {msg} s  eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(pb)
    } else {
        None
    };

    // The simulation thread hands raw rows (t, q, v, energy, contacts,
    // penetration) in blocks to a writer thread, which formats the CSV: the step
    // loop never formats a number. (The energy is computed here, from the
    // kinematics the step's contact detection left, at a fraction of its cost
    // in the writer.) Blocks are recycled (no allocation once both are in
    // flight), the channel is bounded (the writer cannot fall behind by more
    // than a few blocks).
    let (nq, nv) = (sim.model.nq, sim.model.nv);
    let width = row_width(nq, nv) + usize::from(has_loops);
    let header = {
        let (qn, vn) = column_names(&sim.model);
        let mut h = String::from("t");
        for n in qn.iter().chain(vn.iter()) {
            h.push(',');
            h.push_str(n);
        }
        h.push_str(",energy,contacts,penetration,awake");
        if has_loops {
            h.push_str(",constraint_violation");
        }
        h.push('\n');
        h
    };
    let block_rows = 256usize;
    let e0 = sim.energy();
    let mut recorder = args
        .html
        .as_ref()
        .map(|_| crate::cli::view::Recorder::new(&sim.model, duration, true));
    let mut loop_body = |w: Option<&mut (dyn Write + Send)>| -> Result<Summary, SimulateError> {
        let mut max_pen = sim.penetration();
        let mut max_viol = if has_loops {
            sim.constraint_violation()
        } else {
            0.0
        };
        // the clock starts inside the scope, once the writer is set up
        let start = std::thread::scope(|scope| {
            let (to_writer, from_sim) = std::sync::mpsc::sync_channel::<Vec<f64>>(4);
            let (recycle, recycled) = std::sync::mpsc::channel::<Vec<f64>>();
            // set-up, not stepping: the writer thread is started and the blocks
            // in flight are allocated and touched (their pages faulted in)
            // before the clock starts
            let touched = || {
                let mut b = vec![0.0f64; width * block_rows];
                b.clear();
                b
            };
            let writer = w.map(|w| {
                for _ in 0..BLOCKS_IN_FLIGHT {
                    let _ = recycle.send(touched());
                }
                scope.spawn(|| write_rows(w, &header, (nq, nv, has_loops), from_sim, recycle))
            });
            let mut block: Vec<f64> = touched();
            let start = Instant::now();
            let push_row = |sim: &mut Simulation,
                            block: &mut Vec<f64>,
                            recorder: &mut Option<crate::cli::view::Recorder>,
                            last: bool|
             -> Result<(), SimulateError> {
                let e = finite_energy(sim, &urdf_name)?;
                block.push(sim.time());
                block.extend_from_slice(sim.q().as_slice());
                block.extend_from_slice(sim.v().as_slice());
                block.push(e);
                block.push(sim.active_contacts() as f64);
                block.push(sim.penetration());
                block.push(sim.awake() as f64);
                if has_loops {
                    let c = sim.constraint_violation();
                    block.push(c);
                }
                if let Some(r) = recorder {
                    let plot = [e, sim.active_contacts() as f64, sim.penetration()];
                    r.offer_with(sim.time(), sim.q(), plot, last, |out| {
                        out.extend(sim.contact_forces().iter().map(|c| {
                            crate::cli::view::ContactArrow {
                                point: c.point.point.into(),
                                force: c.force.into(),
                            }
                        }))
                    });
                }
                Ok(())
            };
            // sends a full block (or, at the end, the last one); a writer that hung
            // up has failed: its error is collected at the join below
            let send = |block: &mut Vec<f64>| -> bool {
                if writer.is_none() {
                    block.clear();
                    return true;
                }
                let next = recycled
                    .try_recv()
                    .unwrap_or_else(|_| Vec::with_capacity(width * block_rows));
                to_writer.send(std::mem::replace(block, next)).is_ok()
            };
            let mut sim_result = push_row(&mut sim, &mut block, &mut recorder, duration <= 0.0);
            let mut k = 0u64;
            let mut last_tick = 0u64;
            while sim_result.is_ok() && sim.time() < duration {
                let t_stop = match schedule.as_mut().map(|s| s.apply_due(&mut sim)) {
                    None => duration,
                    Some(Ok(t)) => t.min(duration),
                    Some(Err(error)) => {
                        sim_result = Err(SimulateError::Sim {
                            urdf: urdf_name.clone(),
                            error,
                        });
                        break;
                    }
                };
                if let Err(error) = sim.step_until(t_stop) {
                    sim_result = Err(SimulateError::Sim {
                        urdf: urdf_name.clone(),
                        error,
                    });
                    break;
                }
                k += 1;
                max_pen = max_pen.max(sim.penetration());
                if has_loops {
                    max_viol = max_viol.max(sim.constraint_violation());
                }
                let last = sim.time() >= duration;
                if last || k % every as u64 == 0 {
                    if let Err(e) = push_row(&mut sim, &mut block, &mut recorder, last) {
                        sim_result = Err(e);
                        break;
                    }
                    if block.len() >= width * block_rows && !send(&mut block) {
                        break;
                    }
                }
                if let Some(pb) = &progress {
                    let tick = (sim.time() / duration * 1000.0) as u64;
                    if tick != last_tick {
                        last_tick = tick;
                        pb.set_position(tick);
                        pb.set_message(format!("{:.3}", sim.time()));
                    }
                }
            }
            if sim_result.is_ok() && !block.is_empty() {
                send(&mut block);
            }
            drop(to_writer);
            let written = match writer {
                Some(h) => h.join().unwrap_or_else(|_| {
                    Err(SimulateError::Output("trajectory writer failed".into()))
                }),
                None => Ok(()),
            };
            sim_result?;
            written.map(|()| start)
        })?;
        if let Some(pb) = &progress {
            pb.finish_and_clear();
        }
        let wall = start.elapsed().as_secs_f64();
        let e = finite_energy(&mut sim, &urdf_name)?;
        Ok(Summary {
            steps: sim.steps,
            wall_seconds: wall,
            simulated_seconds: sim.time(),
            real_time_factor: if wall > 0.0 {
                sim.time() / wall
            } else {
                f64::INFINITY
            },
            energy_start: e0,
            energy_end: e,
            max_penetration: max_pen,
            integrator: sim.integrator().name(),
            contact_queries: sim.contact_queries(),
            mean_awake: sim.mean_awake(),
            max_constraint_violation: has_loops.then_some(max_viol),
        })
    };
    let summary = match &args.out {
        Some(path) => {
            let mut result = None;
            write_atomic(path, |w| match loop_body(Some(w)) {
                Ok(s) => {
                    result = Some(s);
                    Ok(())
                }
                Err(e) => Err(e.to_string()),
            })
            .map_err(SimulateError::Output)?;
            result.ok_or_else(|| SimulateError::Output("no result".into()))
        }
        None => loop_body(None),
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

/// A lone URDF's run: `--floating-base`, `--initial`, the ground and friction options.
fn urdf_setup(args: &SimulateArgs, integrator: Option<Integrator>) -> Result<Setup, SimulateError> {
    if let Some(k) = &args.key {
        return Err(SimulateError::Option(format!(
            "--key {k}: keyframes belong to MJCF files ({} is not one)",
            args.urdf.display()
        )));
    }
    let model: Model = crate::load_file(
        &args.urdf,
        LoadOptions {
            floating_base: args.floating_base,
        },
    )?;
    let urdf_name = args.urdf.display().to_string();
    // the initial state (checked before anything is simulated)
    let init = match &args.initial {
        Some(p) => {
            let name = p.display().to_string();
            let text = state::read_text(p)?;
            let st = state::parse_state(&text, &name)?;
            let base_acc = st.base.as_ref().and_then(|b| {
                if b.linear_acceleration.is_some() {
                    Some("base.linear_acceleration")
                } else if b.angular_acceleration.is_some() {
                    Some("base.angular_acceleration")
                } else {
                    None
                }
            });
            if let Some(key) = st.a.as_ref().map(|_| "a").or(base_acc) {
                return Err(state::StateError {
                    file: name,
                    key: key.into(),
                    message: "not allowed in --initial (accelerations are simulated)".into(),
                }
                .into());
            }
            Some(st.to_vectors(&model, &name, "(state)")?)
        }
        None => None,
    };
    let mut contact = crate::contact::ContactParams::default();
    contact.friction = args.friction;
    let opts = SimOptions {
        dt: args.dt.unwrap_or(DEFAULT_DT),
        integrator,
        tol: args.tol,
        ground: if args.no_ground {
            None
        } else {
            Some(args.ground.unwrap_or(0.0))
        },
        contact,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        sleep: !args.no_sleep,
        threads: args.threads.unwrap_or(1),
        ..SimOptions::default()
    };
    // The page's geometry is read before anything is simulated (a missing mesh
    // is reported at once).
    let geometry = match &args.html {
        Some(_) => Some(crate::cli::view::Geometry::load(
            &model,
            &args.urdf,
            &args.package_path,
        )?),
        None => None,
    };
    Ok((model, init, opts, geometry, urdf_name, None))
}

/// A scene's run: models, obstacles, ground, friction and the starting state
/// from the file (scene.md).
fn scene_setup(
    args: &SimulateArgs,
    path: &std::path::Path,
    integrator: Option<Integrator>,
) -> Result<Setup, SimulateError> {
    let scene = crate::scene::Scene::from_file(path, &args.package_path)?;
    for w in &scene.warnings {
        warn(&format!("warning: {w}"));
    }
    let model = scene.model.clone();
    let init = state::StateVectors {
        q: scene.q0.clone(),
        v: scene.v0.clone(),
        a: nalgebra::DVector::zeros(model.nv),
        tau: scene.tau0.clone(),
        fext: Vec::new(),
        frames: Vec::new(),
        derivatives: false,
    };
    let mut contact = crate::contact::ContactParams::default();
    if let Some(g) = scene.ground {
        contact.friction = g.friction;
    }
    let opts = SimOptions {
        dt: args.dt.unwrap_or(DEFAULT_DT),
        integrator,
        tol: args.tol,
        ground: scene.ground.map(|g| g.height),
        contact,
        package_paths: args.package_path.clone(),
        armature: args.armature,
        sleep: !args.no_sleep && scene.spec.sleep.unwrap_or(true),
        sleep_velocity: scene.spec.sleep_velocity.unwrap_or(1e-3),
        sleep_time: scene.spec.sleep_time.unwrap_or(0.5),
        threads: args.threads.or(scene.spec.threads).unwrap_or(1),
        never_sleep: scene
            .spec
            .models
            .iter()
            .filter(|m| m.sleep == Some(false))
            .map(|m| m.name.clone())
            .collect(),
        ..SimOptions::default()
    };
    let geometry = match &args.html {
        Some(_) => Some(crate::cli::view::Geometry::load_scene(
            &scene,
            &args.package_path,
        )?),
        None => None,
    };
    // the scene's loop constraints (mechanisms.md §"Simulation")
    let loops = (!scene.constraints.items.is_empty()).then(|| scene.constraints.clone());
    Ok((model, Some(init), opts, geometry, scene.file.clone(), loops))
}

/// Blocks of rows allocated for the writer before the stepping starts (the
/// channel holds 4, the writer formats one and the simulation fills one).
const BLOCKS_IN_FLIGHT: usize = 6;

/// One warning line on standard error (the run goes on).
pub(crate) fn warn(line: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// Numbers in one raw row handed to the writer: t, q (nq), v (nv), energy,
/// contacts, penetration, awake.
fn row_width(nq: usize, nv: usize) -> usize {
    1 + nq + nv + 4
}

/// The writer thread: the header, then the CSV line of every row.
fn write_rows(
    w: &mut (dyn Write + Send),
    header: &str,
    (nq, nv, has_loops): (usize, usize, bool),
    rows: std::sync::mpsc::Receiver<Vec<f64>>,
    recycle: std::sync::mpsc::Sender<Vec<f64>>,
) -> Result<(), SimulateError> {
    use std::fmt::Write as _;
    let io = |e: std::io::Error| SimulateError::Output(format!("cannot write trajectory: {e}"));
    let width = row_width(nq, nv) + usize::from(has_loops);
    let mut line = String::with_capacity(32 * width + 64);
    w.write_all(header.as_bytes()).map_err(io)?;
    let mut rb = zmij::Buffer::new();
    for block in rows {
        for row in block.chunks_exact(width) {
            let (t, rest) = row.split_at(1);
            let (qs, rest) = rest.split_at(nq);
            let (vs, rest) = rest.split_at(nv);
            let t = t.first().copied().unwrap_or(0.0);
            let (e, contacts, pen, awake) = (
                rest.first().copied().unwrap_or(0.0),
                rest.get(1).copied().unwrap_or(0.0),
                rest.get(2).copied().unwrap_or(0.0),
                rest.get(3).copied().unwrap_or(0.0),
            );
            line.clear();
            line.push_str(rb.format(t));
            for x in qs.iter().chain(vs.iter()) {
                line.push(',');
                line.push_str(rb.format(*x));
            }
            line.push(',');
            line.push_str(rb.format(e));
            line.push(',');
            // (formatting into a String cannot fail)
            let _ = write!(line, "{}", contacts as u64);
            line.push(',');
            line.push_str(rb.format(pen));
            line.push(',');
            let _ = write!(line, "{}", awake as u64);
            if has_loops {
                line.push(',');
                line.push_str(rb.format(rest.get(4).copied().unwrap_or(0.0)));
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
        let mut block = block;
        block.clear();
        let _ = recycle.send(block);
    }
    Ok(())
}

/// The energy of the current state, or the error naming its time when it is not
/// finite (q and v are checked by every step; an overflowing energy is not).
fn finite_energy(sim: &mut Simulation, urdf_name: &str) -> Result<f64, SimulateError> {
    let e = sim.energy();
    if e.is_finite() {
        Ok(e)
    } else {
        Err(SimulateError::Sim {
            urdf: urdf_name.to_string(),
            error: SimError::NonFinite {
                t: sim.time(),
                quantity: "energy".into(),
            },
        })
    }
}
