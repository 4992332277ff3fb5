//! Every fixture robot and state against Pinocchio (tests/oracle/make_fixtures.py):
//! tau, qdd, bias, H, link poses and the base block (external wrenches included),
//! max relative error max|x − y| / max(1, max|y|) ≤ 1e-9 per quantity; the
//! kinematic quantities of contract v2 (frame Jacobians, velocities, classical
//! accelerations, centre of mass, momentum, energies) ≤ 1e-12.

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
    /// The worst kinematic (contract v2) error and where.
    worst_kin: f64,
    where_kin: String,
    /// Worst error per quantity name (for the report).
    per: std::collections::BTreeMap<String, f64>,
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
        let q = what.split(' ').nth(2).unwrap_or("").to_string();
        let w = self.per.entry(q).or_insert(0.0);
        *w = w.max(e);
        if e > self.worst {
            self.worst = e;
            self.where_ = what;
        }
    }
    fn add_kin(&mut self, what: String, e: f64) {
        self.add(what.clone(), 0.0);
        let q = what.split(' ').nth(2).unwrap_or("").to_string();
        let w = self.per.entry(q).or_insert(0.0);
        *w = w.max(e);
        assert!(e.is_finite(), "{what}: non-finite comparison");
        if e > self.worst_kin {
            self.worst_kin = e;
            self.where_kin = what;
        }
    }
}

/// The rows of a matrix with its columns reordered by `perm` (got's column of
/// each of want's), flattened.
fn permuted_columns(m: &Value, perm: &[usize]) -> Vec<f64> {
    let mut out = Vec::new();
    for row in m.as_array().unwrap() {
        for &k in perm {
            out.push(row[k].as_f64().unwrap());
        }
    }
    out
}

/// Contract v2: the frames a state asked for, the centre of mass, the momentum and
/// the energies.
fn compare_kinematics(c: &mut Cmp, s: usize, g: &Value, w: &Value, perm: &[usize]) {
    let pair = |gv: &Value, wv: &Value| {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        flat(gv, &mut a);
        flat(wv, &mut b);
        rel(&a, &b)
    };
    if let Some(wf) = w.get("frames").and_then(|f| f.as_object()) {
        let gf = g["frames"].as_object().expect("frames missing");
        assert_eq!(gf.len(), wf.len(), "state {s}: frame count");
        for (link, wl) in wf {
            let gl = &gf[link];
            for key in ["jacobian", "jacobian_local"] {
                let mut want = Vec::new();
                flat(&wl[key], &mut want);
                let e = rel(&permuted_columns(&gl[key], perm), &want);
                c.add_kin(format!("state {s} {key} {link}"), e);
            }
            for key in ["velocity", "acceleration"] {
                for part in ["linear", "angular"] {
                    let e = pair(&gl[key][part], &wl[key][part]);
                    c.add_kin(format!("state {s} {key} {link} {part}"), e);
                }
            }
        }
    } else {
        assert!(g.get("frames").is_none(), "state {s}: frames not asked for");
    }
    for part in ["position", "velocity"] {
        c.add_kin(
            format!("state {s} com_{part}"),
            pair(&g["com"][part], &w["com"][part]),
        );
    }
    let mut want = Vec::new();
    flat(&w["com"]["jacobian"], &mut want);
    let e = rel(&permuted_columns(&g["com"]["jacobian"], perm), &want);
    c.add_kin(format!("state {s} com_jacobian"), e);
    for part in ["linear", "angular"] {
        let e = pair(&g["momentum"][part], &w["momentum"][part]);
        c.add_kin(format!("state {s} momentum_{part}"), e);
    }
    for part in ["kinetic", "potential"] {
        let e = pair(&g["energy"][part], &w["energy"][part]);
        c.add_kin(format!("state {s} energy_{part}"), e);
    }
}

fn compare(name: &str, got: &Value, want: &Value) -> Cmp {
    let mut c = Cmp {
        worst: 0.0,
        where_: String::new(),
        worst_kin: 0.0,
        where_kin: String::new(),
        per: Default::default(),
    };
    let gn: Vec<String> = serde_json::from_value(got["dof_names"].clone()).unwrap();
    let wn: Vec<String> = serde_json::from_value(want["dof_names"].clone()).unwrap();
    // The engine's order is Pinocchio's (docs/theory.md §"Degrees of freedom order").
    assert_eq!(
        gn, wn,
        "{name}: dof names or their order differ from Pinocchio's"
    );
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
        compare_kinematics(&mut c, s, g, w, &perm);
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
    let mut per = std::collections::BTreeMap::<String, f64>::new();
    for d in &dirs {
        let (name, c) = run_fixture(d);
        println!(
            "{name:24} worst relative error {:.2e} ({}); kinematics {:.2e} ({})",
            c.worst, c.where_, c.worst_kin, c.where_kin
        );
        for (q, e) in &c.per {
            let w = per.entry(q.clone()).or_insert(0.0);
            *w = w.max(*e);
        }
        if c.worst > 1e-9 {
            failures.push(format!("{name}: {:.3e} at {}", c.worst, c.where_));
        }
        if c.worst_kin > 1e-12 {
            failures.push(format!("{name}: {:.3e} at {}", c.worst_kin, c.where_kin));
        }
    }
    println!("worst relative error per quantity over every fixture:");
    for (q, e) in &per {
        println!("  {q:24} {e:.2e}");
    }
    assert!(
        failures.is_empty(),
        "fixtures over tolerance: {failures:#?}"
    );
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
        assert!(
            c.worst_kin <= 1e-12,
            "{name}: {:.3e} at {}",
            c.worst_kin,
            c.where_kin
        );
    }
}

/// FD(ID(q̈)) = q̈ on every fixture robot and state, fixed and floating, with the
/// state's external wrenches (`fext`) applied to both.
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
        let mut pushed = 0;
        for (i, s) in states.states.iter().enumerate() {
            let sv = s
                .to_vectors(&model, "states.json", &format!("states[{i}]"))
                .unwrap();
            // the state's external wrenches, by link, onto their bodies
            let mut fext = vec![urdyn::spatial::Force::zero(); model.nbodies];
            urdyn::dynamics_f64::forward_kinematics(&model, &mut data, &sv.q).unwrap();
            for (link, f, t) in &sv.fext {
                urdyn::dynamics_f64::add_link_wrench(&model, &data, *link, f, t, &mut fext)
                    .unwrap();
            }
            pushed += usize::from(!sv.fext.is_empty());
            let fx = Some(fext.as_slice());
            let tau = urdyn::dynamics_f64::rnea(&model, &mut data, &sv.q, &sv.v, &sv.a, fx)
                .unwrap()
                .clone();
            let qdd =
                urdyn::dynamics_f64::forward_dynamics(&model, &mut data, &sv.q, &sv.v, &tau, fx)
                    .unwrap()
                    .clone();
            worst = worst.max((&qdd - &sv.a).amax() / (1.0f64).max(sv.a.amax()));
        }
        println!("{name:24} FD(ID(a)) relative error {worst:.2e} ({pushed} states with fext)");
        assert!(
            pushed >= 2,
            "{name}: the fixture has too few external wrenches"
        );
        assert!(worst <= 1e-10, "{name}: FD(ID(a)) off by {worst:e}");
    }
}
