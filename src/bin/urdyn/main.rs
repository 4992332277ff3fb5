//! The `urdyn` command line (contract: shared/spec/cli.md). Thin: parse the
//! arguments, call the library, print one line on error.

use anyhow::{anyhow, Result};
use clap::Parser;
use std::io::Write;
use std::path::PathBuf;
use urdyn::cli::{eval, inspect, output, state};
use urdyn::LoadOptions;

mod args;
mod errors;

use args::{BenchArgs, Cli, Command, SimulateCmd};
use errors::{cli_hint, parse_error_line};

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
        say(format_args!("urdyn: {n}"));
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
            if let Some(o) = &output {
                let inputs = [
                    ("the model", urdf.as_path()),
                    ("--states", states.as_path()),
                ];
                output::not_an_input(o, "--output", &inputs).map_err(|e| anyhow!(e))?;
            }
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
            let inputs: Vec<(&str, &std::path::Path)> = [
                ("--scene", scene.as_deref()),
                // (with --scene the first argument is the trajectory)
                (
                    if scene.is_some() {
                        "the trajectory"
                    } else {
                        "the model"
                    },
                    urdf.as_deref(),
                ),
                ("the trajectory", traj.as_deref()),
            ]
            .into_iter()
            .filter_map(|(w, p)| Some((w, p?)))
            .collect();
            output::not_an_input(&out, "--out", &inputs).map_err(|e| anyhow!(e))?;
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
                say(format_args!("warning: {w}"));
            }
            say(format_args!("urdyn {summary}"));
        }
    }
    Ok(())
}

fn run_simulate(c: SimulateCmd) -> Result<()> {
    use std::io::IsTerminal;
    use urdyn::sim::Integrator;
    if c.list_integrators {
        let mut out = std::io::stdout().lock();
        for i in Integrator::ALL {
            writeln!(out, "{}", i.name())?;
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
    say(format_args!("urdyn {summary}"));
    Ok(())
}

/// One line to standard error; a closed stderr (`2>&1 | head -1`) is not an
/// error (`eprintln!` panics on it, and in the panic hook aborts).
fn say(line: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
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
        say(format_args!(
            "urdyn: internal error{at}: {msg} (please report this bug)"
        ));
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
            say(format_args!("urdyn: {}", parse_error_line(&e, &argv)));
            std::process::exit(2);
        }
    };
    if let Err(e) = run(cli) {
        let text = format!("{e:#}{}", cli_hint(&e));
        say(format_args!(
            "urdyn: {}",
            text.lines().collect::<Vec<_>>().join(" ")
        ));
        std::process::exit(1);
    }
}
