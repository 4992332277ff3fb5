//! `urdyn eval` contract v3 (eval-contract.md §"Derivatives (version 3)") against
//! Pinocchio on every fixture robot that has derivative fixtures
//! (tests/oracle/make_derivative_fixtures.py: `deriv_states.json`,
//! `deriv_expected.json`, `deriv_meta.json`): ∂τ/∂q, ∂τ/∂v and every requested
//! frame's `jacobian_dot` within 1e-10 relative to max(1, max|ref|) per matrix; the
//! forward-dynamics derivatives within max(1e-10, 10 × Pinocchio's own ABA-vs-CRBA
//! disagreement on that state, `aba_routes` in deriv_meta.json) — for an
//! ill-conditioned H (icub_reduced, cond 5e5) the reference itself carries that error.

use serde_json::Value;
use std::path::{Path, PathBuf};
use urdyn::cli::{eval, state};
use urdyn::LoadOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn flat(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN)),
        Value::Array(a) => a.iter().for_each(|x| flat(x, out)),
        _ => out.push(f64::NAN),
    }
}

/// max|got − want| / max(1, max|want|).
fn rel(got: &Value, want: &Value) -> f64 {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    flat(got, &mut a);
    flat(want, &mut b);
    assert_eq!(a.len(), b.len(), "matrix sizes differ");
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let e = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale;
    if e.is_nan() {
        f64::INFINITY
    } else {
        e
    }
}

fn read(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// The fixture's worst errors: (rnea-side worst, where), and the dqdd failures.
fn run(dir: &Path) -> Vec<String> {
    let name = dir.file_name().unwrap().to_string_lossy().into_owned();
    let meta = read(&dir.join("deriv_meta.json"));
    let model = urdyn::load_file(
        root().join(meta["urdf"].as_str().unwrap()),
        LoadOptions {
            floating_base: meta["floating_base"].as_bool().unwrap(),
        },
    )
    .unwrap();
    let text = std::fs::read_to_string(dir.join("deriv_states.json")).unwrap();
    let states = state::parse_states(&text, "deriv_states.json").unwrap();
    let got = eval::evaluate(&model, &states, "robot.urdf", "deriv_states.json").unwrap();
    let want = read(&dir.join("deriv_expected.json"));
    assert_eq!(got["dof_names"], want["dof_names"], "{name}: dof order");
    let (gres, wres) = (
        got["results"].as_array().unwrap(),
        want["results"].as_array().unwrap(),
    );
    assert_eq!(gres.len(), wres.len(), "{name}: state count");
    let mut failures = Vec::new();
    let mut worst = (0.0f64, String::new());
    let mut worst_fd = (0.0f64, String::new());
    for (s, (g, w)) in gres.iter().zip(wres).enumerate() {
        let routes = meta["states"][s]["aba_routes"].as_f64().unwrap_or(0.0);
        let fd_bound = (10.0 * routes).max(1e-10);
        let (gd, wd) = (&g["derivatives"], &w["derivatives"]);
        assert!(
            gd.is_object(),
            "{name} state {s}: no derivatives in the result"
        );
        for key in ["dtau_dq", "dtau_dv", "dqdd_dq", "dqdd_dv", "dqdd_dtau"] {
            let e = rel(&gd[key], &wd[key]);
            let bound = if key.starts_with("dtau") {
                1e-10
            } else {
                fd_bound
            };
            let at = format!("{name} state {s} {key}");
            if key.starts_with("dtau") {
                if e > worst.0 {
                    worst = (e, at.clone());
                }
            } else if e > worst_fd.0 {
                worst_fd = (e, format!("{at} (bound {bound:.1e})"));
            }
            if e > bound {
                failures.push(format!("{at}: {e:.2e} > {bound:.1e}"));
            }
        }
        if let Some(wf) = w.get("frames").and_then(Value::as_object) {
            for (link, wl) in wf {
                let e = rel(&g["frames"][link]["jacobian_dot"], &wl["jacobian_dot"]);
                let at = format!("{name} state {s} jacobian_dot {link}");
                if e > worst.0 {
                    worst = (e, at.clone());
                }
                if e > 1e-10 {
                    failures.push(format!("{at}: {e:.2e} > 1e-10"));
                }
            }
        }
    }
    println!(
        "{name:22} dtau/jacobian_dot worst {:.2e} ({}); dqdd worst {:.2e} ({})",
        worst.0, worst.1, worst_fd.0, worst_fd.1
    );
    failures
}

#[test]
fn eval_derivatives_match_pinocchio_on_every_fixture() {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root().join("tests/fixtures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.join("deriv_states.json").is_file()
                && p.join("deriv_expected.json").is_file()
                && p.join("deriv_meta.json").is_file()
        })
        .collect();
    dirs.sort();
    assert!(
        dirs.len() >= 10,
        "derivative fixtures missing: run tests/oracle/run.sh"
    );
    let failures: Vec<String> = dirs.iter().flat_map(|d| run(d)).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
