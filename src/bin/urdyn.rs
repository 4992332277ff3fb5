//! The `urdyn` command line (contract: shared/spec/cli.md). Thin: parse the
//! arguments, call the library, print one line on error.

use anyhow::{anyhow, Result};
use clap::{Parser, Subcommand};
use std::io::Write;
use std::path::PathBuf;
use urdyn::cli::{eval, inspect, output, state};
use urdyn::LoadOptions;

#[derive(Parser)]
#[command(
    name = "urdyn",
    version,
    about = "URDF-driven rigid multibody dynamics (Featherstone spatial vectors)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the kinematic tree, degrees of freedom, masses, merged links, collision
    /// geometry and warnings of a URDF.
    Inspect {
        /// The URDF file.
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
        /// The URDF file (mesh files are never read).
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
    /// Simulate the robot or a scene (joint damping, friction, limits from the
    /// URDF; contact with the ground, between the robot's own links and, with
    /// --scene, between models and with obstacles) and write its trajectory as CSV.
    Simulate(Box<SimulateCmd>),
    /// Time each dynamics algorithm on random states of this robot (median ns per call).
    Bench(BenchArgs),
    /// Write one self-contained HTML page that replays a trajectory CSV of `simulate`
    /// in 3D (no network, no other file; opens from disk in any current browser).
    View {
        /// The URDF file (with --scene: the trajectory CSV).
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
    after_help = "Contact is between the links' collision geometry and the ground plane, and between two links of one robot (self-collision) that are not a body and its parent, not on one body, not both welded to the world and not a <disable_collisions> pair of an SRDF; pairs that overlap at the start are dropped with a warning. With --scene, also between the models and with the scene's obstacles (scene.md \"Who touches whom\"). Contact model: velocity-level impulses with exact Coulomb friction (stick and slip), solved each step."
)]
struct SimulateCmd {
    /// The URDF file.
    urdf: Option<PathBuf>,
    /// A scene file (scene.md: several models, obstacles, ground) in place of the URDF;
    /// the per-model options (--floating-base, --initial, --above-ground, --ground,
    /// --no-ground, --friction) live in the file.
    #[arg(long, value_name = "SCENE.json")]
    scene: Option<PathBuf>,
    /// Give the root link a free 6-DoF joint (unit quaternion, no Euler angles).
    #[arg(long)]
    floating_base: bool,
    /// Simulated seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 2.0,
        allow_hyphen_values = true
    )]
    duration: f64,
    /// Step in seconds (the first step of an adaptive integrator) [default: 0.001; an MJCF file's <option timestep>].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    dt: Option<f64>,
    /// Start an MJCF model from its keyframe <key name="NAME">.
    #[arg(long, value_name = "NAME")]
    key: Option<String>,
    /// An MJCF model's actuator controls: a CSV with a t column and one column per actuator name, held piecewise constant.
    #[arg(long, value_name = "FILE.csv")]
    controls: Option<PathBuf>,
    /// Integrator (see --list-integrators); default: euler with ground contact, dop853 without.
    #[arg(long, value_name = "NAME")]
    integrator: Option<String>,
    /// Print the available integrator names, one a line, and exit.
    #[arg(long)]
    list_integrators: bool,
    /// Error tolerance of adaptive integrators: RMS_i(e_i / (X + X*|y_i|)) <= 1 per step (fixed-step ones ignore it).
    #[arg(
        long,
        value_name = "X",
        default_value_t = 1e-6,
        allow_hyphen_values = true
    )]
    tol: f64,
    /// One state object as in eval's states list (q, v, base, tau and base.force/torque as constant forces).
    #[arg(long, value_name = "STATE.json")]
    initial: Option<PathBuf>,
    /// With --floating-base: before the first step, move the base vertically so that the
    /// lowest point of the collision geometry is H above the ground (after --initial).
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    above_ground: Option<f64>,
    /// Rotor inertia added to every joint's diagonal of H (kg·m² or kg).
    #[arg(
        long,
        value_name = "X",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    armature: f64,
    /// Ground plane height (contact on when any moving link has collision geometry).
    #[arg(
        long,
        value_name = "Z",
        allow_hyphen_values = true,
        conflicts_with = "no_ground"
    )]
    ground: Option<f64>,
    /// No ground plane: no contact at all.
    #[arg(long)]
    no_ground: bool,
    /// No island sleeps (sleep is on by default: still islands stop costing).
    #[arg(long)]
    no_sleep: bool,
    /// Threads the islands are solved on (0: every core; default the scene's, else 1).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Gravity vector.
    #[arg(
        long,
        value_name = "GX,GY,GZ",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    gravity: Option<Vec<f64>>,
    /// Coulomb friction coefficient between links and the ground [default: 1.0].
    #[arg(long, value_name = "MU", allow_hyphen_values = true)]
    friction: Option<f64>,
    /// A root for package://NAME/... mesh paths (repeatable; ROS_PACKAGE_PATH is also read).
    #[arg(long, value_name = "DIR")]
    package_path: Vec<PathBuf>,
    /// Trajectory CSV file (written atomically).
    #[arg(long, value_name = "TRAJ.csv")]
    out: Option<PathBuf>,
    /// Also write the 3D replay page of `urdyn view` for this run, with its contact
    /// points and forces.
    #[arg(long, value_name = "PAGE.html")]
    html: Option<PathBuf>,
    /// Write every Nth step (the final state is always written).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_hyphen_values = true
    )]
    every: i64,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// The URDF file.
    urdf: PathBuf,
    /// Give the root link a free 6-DoF joint (unit quaternion) instead of welding it.
    #[arg(long)]
    floating_base: bool,
    /// Time only this algorithm (repeatable): rnea, bias, crba, aba, fd-rnea, fd-crba, fd, fk.
    #[arg(long = "algo", value_name = "NAME")]
    algos: Vec<String>,
    /// Timed samples per algorithm (each a batch of calls of about 50 µs).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 300,
        allow_hyphen_values = true
    )]
    samples: i64,
    /// Soft time limit per algorithm in seconds (lowers the samples, never below 5).
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 1.5,
        allow_hyphen_values = true
    )]
    budget: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// A `point` constraint holding LINK's origin where it is in the first sampled
    /// state (repeatable; for constraint-dynamics, mechanisms.md).
    #[arg(long = "hold", value_name = "LINK")]
    hold: Vec<String>,
    /// A `frame` constraint holding LINK's frame where it is in the first sampled state.
    #[arg(long = "hold6", value_name = "LINK")]
    hold6: Vec<String>,
    /// A `frame` constraint welding two links' frames together (L1,L2).
    #[arg(long = "weld", value_name = "L1,L2")]
    weld: Vec<String>,
}

fn bench(a: BenchArgs) -> Result<()> {
    use urdyn::cli::bench::{self, Algo, BenchError, BenchOptions};
    // (checked before the robot is loaded; a budget too large for a Duration is
    // refused here rather than panicking in from_secs_f64)
    let budget = match std::time::Duration::try_from_secs_f64(a.budget) {
        Ok(b) if a.budget > 0.0 => b,
        _ => {
            return Err(anyhow!(
                "--budget: must be a positive number of seconds (got {:?})",
                a.budget
            ))
        }
    };
    let model = urdyn::load_model(
        &a.urdf,
        LoadOptions {
            floating_base: a.floating_base,
        },
    )?;
    let algos = if a.algos.is_empty() {
        Algo::ALL.to_vec()
    } else {
        a.algos
            .iter()
            .map(|n| Algo::from_name(n).ok_or_else(|| BenchError::UnknownAlgo(n.clone())))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| anyhow!("--algo: {e}"))?
    };
    // (0 is refused by the library, naming --samples)
    let samples = usize::try_from(a.samples)
        .map_err(|_| anyhow!("--samples must be at least 1 (got {})", a.samples))?;
    let mut constraints = Vec::new();
    for l in &a.hold {
        constraints.push(serde_json::json!({"kind": "point", "link1": l}));
    }
    for l in &a.hold6 {
        constraints.push(serde_json::json!({"kind": "frame", "link1": l}));
    }
    for w in &a.weld {
        let (l1, l2) = w
            .split_once(',')
            .ok_or_else(|| anyhow!("--weld: expected L1,L2 (two link names), got {w:?}"))?;
        constraints.push(serde_json::json!({"kind": "frame", "link1": l1, "link2": l2}));
    }
    // the constraints are checked before timing (an unknown link names its option)
    if !constraints.is_empty() {
        urdyn::model::Constraints::from_json(&model, &constraints).map_err(|e| {
            let opt = ["--hold", "--hold6", "--weld"]
                .into_iter()
                .zip([a.hold.len(), a.hold6.len(), a.weld.len()])
                .scan(0, |acc, (o, n)| {
                    *acc += n;
                    Some((o, *acc))
                })
                .find(|&(_, end)| e.index < end)
                .map_or("--hold", |(o, _)| o);
            anyhow!("{opt}: {}", e.message)
        })?;
    }
    let algos = if a.algos.is_empty() && !constraints.is_empty() {
        Algo::ALL.into_iter().chain(Algo::CONSTRAINED).collect()
    } else {
        algos
    };
    if constraints.is_empty() && algos.iter().any(|x| Algo::CONSTRAINED.contains(x)) {
        return Err(anyhow!(
            "--algo: constraint-dynamics needs constraints: --hold LINK, --hold6 LINK or --weld L1,L2"
        ));
    }
    let opts = BenchOptions {
        algos,
        samples,
        budget,
        constraints,
    };
    let (results, notes) =
        bench::run(&model, &opts).map_err(|e| anyhow!("{}: {e}", a.urdf.display()))?;
    for n in notes {
        eprintln!("urdyn: {n}");
    }
    let text = if a.json {
        let mut j = serde_json::to_string(&bench::to_json(&model, &results))?;
        j.push('\n');
        j
    } else {
        bench::to_table(&model, &results)
    };
    std::io::stdout().write_all(text.as_bytes())?;
    Ok(())
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bench(a) => bench(a)?,
        Command::Inspect {
            urdf,
            floating_base,
            package_path,
            strict,
            json,
        } => {
            let model = urdyn::load_model(&urdf, LoadOptions { floating_base })?;
            if strict {
                if let Some(w) = inspect::warnings(&model, &package_path).first() {
                    anyhow::bail!("{}: {w} (--strict: warnings are errors)", urdf.display());
                }
            }
            let text = if json {
                let mut j = serde_json::to_string(&inspect::json(&model, &package_path))?;
                j.push('\n');
                j
            } else {
                inspect::report(&model, &package_path)
            };
            std::io::stdout().write_all(text.as_bytes())?;
        }
        Command::Eval {
            urdf,
            states,
            floating_base,
            output,
        } => {
            let model = urdyn::load_model(&urdf, LoadOptions { floating_base })?;
            let states_name = states.display().to_string();
            let text = state::read_text(&states)?;
            let parsed = state::parse_states(&text, &states_name)?;
            let mut json =
                eval::evaluate_json(&model, &parsed, &urdf.display().to_string(), &states_name)?;
            json.push('\n');
            match output {
                Some(path) => output::write_atomic(&path, |w| {
                    w.write_all(json.as_bytes())
                        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
                })
                .map_err(|e| anyhow!(e))?,
                None => std::io::stdout().write_all(json.as_bytes())?,
            }
        }
        Command::Simulate(cmd) => run_simulate(*cmd)?,
        Command::View {
            urdf,
            traj,
            scene,
            floating_base,
            package_path,
            out,
        } => {
            let summary = match (scene, urdf, traj) {
                (Some(scene), Some(traj), None) if !floating_base => {
                    urdyn::cli::view::run_scene(&urdyn::cli::view::SceneViewArgs {
                        scene,
                        traj,
                        package_path,
                        out,
                    })?
                }
                (Some(_), _, _) if floating_base => {
                    return Err(anyhow!(
                        "view: --floating-base is a per-model option: with --scene it lives in the scene file"
                    ))
                }
                (Some(_), _, _) => {
                    return Err(anyhow!(
                        "view: with --scene give the trajectory CSV only (view --scene SCENE.json TRAJ.csv --out PAGE.html)"
                    ))
                }
                (None, Some(urdf), Some(traj)) => {
                    urdyn::cli::view::run(&urdyn::cli::view::ViewArgs {
                        urdf,
                        traj,
                        floating_base,
                        package_path,
                        out,
                    })?
                }
                _ => {
                    return Err(anyhow!(
                        "view: expected ROBOT.urdf TRAJ.csv (or --scene SCENE.json TRAJ.csv)"
                    ))
                }
            };
            for w in &summary.warnings {
                eprintln!("warning: {w}");
            }
            eprintln!("urdyn {summary}");
        }
    }
    Ok(())
}

fn run_simulate(c: SimulateCmd) -> Result<()> {
    use std::io::IsTerminal;
    use urdyn::sim::Integrator;
    if c.list_integrators {
        for i in Integrator::ALL {
            println!("{}", i.name());
        }
        return Ok(());
    }
    let urdf = match (c.urdf, &c.scene) {
        (Some(u), None) => u,
        (None, Some(_)) => PathBuf::new(),
        (Some(u), Some(s)) => {
            return Err(anyhow!(
                "simulate: give a URDF or --scene, not both ({} and --scene {})",
                u.display(),
                s.display()
            ))
        }
        (None, None) => {
            return Err(anyhow!(
                "simulate: the URDF file argument is missing (or --scene SCENE.json)"
            ))
        }
    };
    if let (Some(s), Some(_)) = (&c.scene, c.friction) {
        return Err(anyhow!(
            "--friction is a per-model option: with --scene it lives in the scene file {} (scene.md)",
            s.display()
        ));
    }
    let gravity = match c.gravity {
        Some(g) => match g.as_slice() {
            [x, y, z] => Some([*x, *y, *z]),
            _ => return Err(anyhow!("--gravity: expected GX,GY,GZ")),
        },
        None => None,
    };
    // (0 is refused by the library, naming --every)
    let every = usize::try_from(c.every)
        .map_err(|_| anyhow!("--every must be at least 1 (got {})", c.every))?;
    let args = urdyn::cli::simulate::SimulateArgs {
        urdf,
        scene: c.scene,
        floating_base: c.floating_base,
        duration: c.duration,
        dt: c.dt,
        key: c.key,
        controls: c.controls,
        integrator: c.integrator,
        tol: c.tol,
        initial: c.initial,
        armature: c.armature,
        above_ground: c.above_ground,
        ground: c.ground,
        no_ground: c.no_ground,
        gravity,
        friction: c.friction.unwrap_or(1.0),
        package_path: c.package_path,
        out: c.out,
        html: c.html,
        every,
        progress: std::io::stderr().is_terminal(),
        no_sleep: c.no_sleep,
        threads: c.threads,
    };
    let summary = urdyn::cli::simulate::run(&args)?;
    eprintln!("urdyn {summary}");
    Ok(())
}

/// What the command line adds to a library error that the library words
/// neutrally (it names no flag): a collision mesh that cannot be found.
fn cli_hint(e: &anyhow::Error) -> &'static str {
    use urdyn::cli::simulate::SimulateError;
    use urdyn::contact::ContactError;
    use urdyn::sim::SimError;
    match e.downcast_ref::<SimulateError>() {
        Some(SimulateError::Sim {
            error: SimError::Contact(ContactError::MissingMesh { .. }),
            ..
        }) => " (give its package root with --package-path DIR or ROS_PACKAGE_PATH, or run with --no-ground)",
        _ => "",
    }
}

/// One line for a command-line parse error: clap's message (which spans several
/// lines, the missing arguments listed under the first) before the usage, then
/// clap's suggestions as "did you mean ...", and for the two mistakes a newcomer
/// makes most a line that names the expected form: a list option given as
/// separate values (`--gravity 0 0 -9.81`) and a required option's value given
/// as a positional (`eval ROBOT.urdf states.json`).
fn parse_error_line(e: &clap::Error, argv: &[String]) -> String {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    let text = e.to_string();
    let parts: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty() && !l.starts_with("tip:"))
        .collect();
    let mut line = if parts.is_empty() {
        "invalid arguments".to_string()
    } else {
        parts.join(" ").trim_start_matches("error: ").to_string()
    };
    if e.kind() == ErrorKind::UnknownArgument {
        if let Some(ContextValue::String(stray)) = e.get(ContextKind::InvalidArg) {
            if let Some(better) = stray_value_line(stray, argv) {
                return better;
            }
        }
    }
    let quote = |v: &ContextValue| match v {
        ContextValue::String(s) => Some(format!("'{s}'")),
        ContextValue::Strings(v) if !v.is_empty() => Some(
            v.iter()
                .map(|s| format!("'{s}'"))
                .collect::<Vec<_>>()
                .join(" or "),
        ),
        _ => None,
    };
    let mut tips = Vec::new();
    for kind in [
        ContextKind::SuggestedSubcommand,
        ContextKind::SuggestedArg,
        ContextKind::SuggestedValue,
    ] {
        if let Some(s) = e.get(kind).and_then(quote) {
            tips.push(format!("did you mean {s}?"));
        }
    }
    if let Some(ContextValue::StyledStrs(v)) = e.get(ContextKind::Suggested) {
        tips.extend(v.iter().map(|s| s.to_string()));
    }
    if !tips.is_empty() {
        line = format!("{line} ({})", tips.join("; "));
    }
    line
}

/// The line for a stray argument `stray` that clap found no place for, when the
/// command line shows what was meant: the values of a comma-separated list
/// option given as separate arguments (anywhere on the line), or the value of a required option that
/// was not given, written as a positional argument. `None` otherwise.
fn stray_value_line(stray: &str, argv: &[String]) -> Option<String> {
    use clap::CommandFactory;
    if stray.starts_with('-') && stray.parse::<f64>().is_err() {
        return None;
    }
    let root = Cli::command();
    let (at, sub) = argv.iter().enumerate().skip(1).find_map(|(i, a)| {
        root.get_subcommands()
            .find(|c| c.get_name() == a)
            .map(|c| (i, c))
    })?;
    let args = &argv[at + 1..];
    let long_of = |tok: &str| -> Option<clap::Arg> {
        let name = tok.strip_prefix("--")?;
        let name = name.split('=').next().unwrap_or(name);
        sub.get_arguments()
            .find(|a| a.get_long() == Some(name))
            .cloned()
    };
    let value_name = |a: &clap::Arg| {
        a.get_value_names()
            .map(|v| v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(" "))
            .unwrap_or_else(|| a.get_id().as_str().to_uppercase())
    };
    // a list option (value names such as GX,GY,GZ) followed by several numbers
    for (i, tok) in args.iter().enumerate() {
        let Some(arg) = long_of(tok) else { continue };
        let form = value_name(&arg);
        if !form.contains(',') {
            continue;
        }
        let mut values: Vec<&str> = tok.split_once('=').map(|(_, v)| v).into_iter().collect();
        values.extend(
            args[i + 1..]
                .iter()
                .take_while(|t| t.parse::<f64>().is_ok())
                .map(String::as_str),
        );
        // (whichever value clap tripped on: with the URDF after the list, the
        // second number is taken for the URDF and a later token is the stray)
        if values.len() > 1 {
            let long = arg.get_long().unwrap_or_default();
            return Some(format!(
                "--{long}: expected one argument of the form {form}, comma-separated without spaces (--{long} {}), got {} separate values",
                values.join(","),
                values.len()
            ));
        }
    }
    // a required option's value written as a positional argument
    let given = |long: &str| {
        args.iter()
            .any(|t| t == &format!("--{long}") || t.starts_with(&format!("--{long}=")))
    };
    let missing = sub
        .get_arguments()
        .find(|a| a.is_required_set() && a.get_long().is_some_and(|l| !given(l)))?;
    let long = missing.get_long().unwrap_or_default();
    Some(format!(
        "{}: unexpected argument '{stray}': give it with --{long} {} (--{long} {stray})",
        sub.get_name(),
        value_name(missing)
    ))
}

fn main() {
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("urdyn: internal error{at}: {msg} (please report this bug)");
    }));
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                std::process::exit(
                    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                        2
                    } else {
                        0
                    },
                );
            }
            let argv: Vec<String> = std::env::args_os()
                .map(|a| a.to_string_lossy().into_owned())
                .collect();
            eprintln!("urdyn: {}", parse_error_line(&e, &argv));
            std::process::exit(2);
        }
    };
    if let Err(e) = run(cli) {
        let text = format!("{e:#}{}", cli_hint(&e));
        eprintln!("urdyn: {}", text.lines().collect::<Vec<_>>().join(" "));
        std::process::exit(1);
    }
}
