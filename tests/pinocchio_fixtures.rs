//! Every fixture robot and state against Pinocchio (tests/oracle/make_fixtures.py):
//! tau, qdd, bias, H, link poses and the base block, max relative error
//! max|x − y| / max(1, max|y|) ≤ 1e-9 per quantity.

use serde_json::Value;
use std::path::{Path, PathBuf};
use urdyn::cli::{eval, state};
use urdyn::LoadOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Worst relative error between two JSON trees of numbers; `names` maps the
/// mass matrix rows of `got` onto those of `want` (dof order may differ).
struct Cmp {
    worst: f64,
    where_: String,
}

fn flat(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN)),
        Value::Array(a) => a.iter().for_each(|x| flat(x, out)),
        _ => out.push(f64::NAN),
    }
}

fn rel(got: &[f64], want: &[f64]) -> f64 {
    assert_eq!(got.len(), want.len());
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    got.iter()
        .zip(want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale
}

impl Cmp {
    fn add(&mut self, what: String, e: f64) {
        assert!(e.is_finite(), "{what}: non-finite comparison");
        if e > self.worst {
            self.worst = e;
            self.where_ = what;
        }
    }
}

fn compare(name: &str, got: &Value, want: &Value) -> Cmp {
    let mut c = Cmp {
        worst: 0.0,
        where_: String::new(),
    };
    let gn: Vec<String> = serde_json::from_value(got["dof_names"].clone()).unwrap();
    let wn: Vec<String> = serde_json::from_value(want["dof_names"].clone()).unwrap();
    let mut sorted_g = gn.clone();
    let mut sorted_w = wn.clone();
    sorted_g.sort();
    sorted_w.sort();
    assert_eq!(sorted_g, sorted_w, "{name}: dof names differ");
    let gres = got["results"].as_array().unwrap();
    let wres = want["results"].as_array().unwrap();
    assert_eq!(gres.len(), wres.len());
    let floating = wres.first().is_some_and(|r| r.get("base").is_some());
    let nb = if floating { 6 } else { 0 };
    // index in got's H of each of want's rows
    let perm: Vec<usize> = (0..nb)
        .chain(
            wn.iter()
                .map(|n| nb + gn.iter().position(|g| g == n).unwrap()),
        )
        .collect();
    for (s, (g, w)) in gres.iter().zip(wres).enumerate() {
        for key in ["tau", "qdd", "bias"] {
            let gv: Vec<f64> = wn.iter().map(|n| g[key][n].as_f64().unwrap()).collect();
            let wv: Vec<f64> = wn.iter().map(|n| w[key][n].as_f64().unwrap()).collect();
            c.add(format!("state {s} {key}"), rel(&gv, &wv));
        }
        let gh = g["mass_matrix"].as_array().unwrap();
        let mut ghv = Vec::new();
        for &r in &perm {
            for &k in &perm {
                ghv.push(gh[r][k].as_f64().unwrap());
            }
        }
        let mut whv = Vec::new();
        flat(&w["mass_matrix"], &mut whv);
        c.add(format!("state {s} mass_matrix"), rel(&ghv, &whv));
        let wp = w["link_poses"].as_object().unwrap();
        assert_eq!(
            g["link_poses"].as_object().unwrap().len(),
            wp.len(),
            "{name}: link count"
        );
        let (mut gp, mut wpv) = (Vec::new(), Vec::new());
        for (link, pose) in wp {
            let gpose = g["link_poses"]
                .get(link)
                .unwrap_or_else(|| panic!("{name}: link {link} missing"));
            flat(&gpose["position"], &mut gp);
            flat(&gpose["rotation"], &mut gp);
            flat(&pose["position"], &mut wpv);
            flat(&pose["rotation"], &mut wpv);
        }
        c.add(format!("state {s} link_poses"), rel(&gp, &wpv));
        if floating {
            let (mut gb, mut wb) = (Vec::new(), Vec::new());
            for k in [
                "force",
                "torque",
                "bias_force",
                "bias_torque",
                "linear_acceleration",
                "angular_acceleration",
            ] {
                flat(&g["base"][k], &mut gb);
                flat(&w["base"][k], &mut wb);
            }
            c.add(format!("state {s} base"), rel(&gb, &wb));
        }
    }
    c
}

fn fixtures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("tests/fixtures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("expected.json").is_file())
        .collect();
    v.sort();
    v
}

fn run_fixture(dir: &Path) -> (String, Cmp) {
    let name = dir.file_name().unwrap().to_string_lossy().into_owned();
    let meta: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).unwrap()).unwrap();
    let urdf = root().join(meta["urdf"].as_str().unwrap());
    let floating = meta["floating_base"].as_bool().unwrap();
    let model = urdyn::load_file(
        &urdf,
        LoadOptions {
            floating_base: floating,
        },
    )
    .unwrap();
    let text = std::fs::read_to_string(dir.join("states.json")).unwrap();
    let states = state::parse_states(&text, "states.json").unwrap();
    let got = eval::evaluate(&model, &states, "robot.urdf", "states.json").unwrap();
    let want: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let c = compare(&name, &got, &want);
    (name, c)
}

#[test]
fn eval_matches_pinocchio_on_every_fixture() {
    let dirs = fixtures();
    assert!(
        dirs.len() >= 10,
        "fixtures missing: run tests/oracle/run.sh"
    );
    let mut failures = Vec::new();
    for d in &dirs {
        let (name, c) = run_fixture(d);
        println!(
            "{name:24} worst relative error {:.2e} ({})",
            c.worst, c.where_
        );
        if c.worst > 1e-9 {
            failures.push(format!("{name}: {:.3e} at {}", c.worst, c.where_));
        }
    }
    assert!(failures.is_empty(), "fixtures over 1e-9: {failures:#?}");
}

/// The robots that once failed to load (a `<texture>` without `filename`, 1e-6 kg
/// antennas with slightly indefinite inertias, loaded as written) agree with
/// Pinocchio to 1e-12.
#[test]
fn icub_and_tiago_match_pinocchio_to_1e_12() {
    for name in ["icub_reduced", "tiago"] {
        let (name, c) = run_fixture(&root().join("tests/fixtures").join(name));
        println!(
            "{name}: worst relative error {:.2e} ({})",
            c.worst, c.where_
        );
        assert!(c.worst <= 1e-12, "{name}: {:.3e} at {}", c.worst, c.where_);
    }
}

/// FD(ID(q̈)) = q̈ on every fixture robot and state, fixed and floating.
#[test]
fn forward_dynamics_inverts_inverse_dynamics_on_every_fixture() {
    for dir in fixtures() {
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let meta: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).unwrap()).unwrap();
        let urdf = root().join(meta["urdf"].as_str().unwrap());
        let floating = meta["floating_base"].as_bool().unwrap();
        let mut model = urdyn::load_file(
            &urdf,
            LoadOptions {
                floating_base: floating,
            },
        )
        .unwrap();
        let text = std::fs::read_to_string(dir.join("states.json")).unwrap();
        let states = state::parse_states(&text, "states.json").unwrap();
        if let Some(g) = states.gravity {
            model.gravity = nalgebra::Vector3::from(g);
        }
        let mut data = urdyn::Data::new(&model);
        let mut worst = 0.0f64;
        for (i, s) in states.states.iter().enumerate() {
            let sv = s
                .to_vectors(&model, "states.json", &format!("states[{i}]"))
                .unwrap();
            let tau = urdyn::dynamics::rnea(&model, &mut data, &sv.q, &sv.v, &sv.a, None).clone();
            let qdd =
                urdyn::dynamics::forward_dynamics(&model, &mut data, &sv.q, &sv.v, &tau, None)
                    .unwrap()
                    .clone();
            worst = worst.max((&qdd - &sv.a).amax() / (1.0f64).max(sv.a.amax()));
        }
        println!("{name:24} FD(ID(a)) relative error {worst:.2e}");
        assert!(worst <= 1e-10, "{name}: FD(ID(a)) off by {worst:e}");
    }
}
