//! One line for every command-line error: clap's parse errors reworded, and the
//! hints the command line adds to library errors.

use crate::args::Cli;

/// What the command line adds to a library error that the library words
/// neutrally (it names no flag): a collision mesh that cannot be found.
pub(crate) fn cli_hint(e: &anyhow::Error) -> &'static str {
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
pub(crate) fn parse_error_line(e: &clap::Error, argv: &[String]) -> String {
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
