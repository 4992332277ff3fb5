//! Islands (scene.md §"Large scenes: islands and sleep", issue 30 "Must
//! show"): the constraint solve is island by island, so two piles far apart
//! cost what each costs alone, never more (no cross term: a global solve
//! sweeps every row until the slowest pile has converged). Cost is counted as
//! the solve's work (rows × sweeps, `Simulation::solve_work`), not wall time.

use serde_json::Value;
use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

fn dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/scenes")
}

fn spec(name: &str) -> Value {
    let p = dir().join(name);
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

/// `spec` with its models and obstacles moved `dx` along x and renamed.
fn shifted(mut s: Value, dx: f64, prefix: &str) -> Value {
    for key in ["models", "obstacles"] {
        for m in s[key].as_array_mut().unwrap() {
            let x = m["position"][0].as_f64().unwrap();
            m["position"][0] = (x + dx).into();
            let n = m["name"].as_str().unwrap().to_string();
            m["name"] = format!("{prefix}{n}").into();
        }
    }
    s
}

fn joined(a: Value, b: Value) -> Value {
    let mut s = a;
    for key in ["models", "obstacles"] {
        let extra = b[key].as_array().unwrap().clone();
        s[key].as_array_mut().unwrap().extend(extra);
    }
    s
}

/// The solve's work over 1 s (sleep off: every step solves every pile).
fn work(s: &Value) -> u64 {
    let scene = Scene::from_json(&s.to_string(), "piles.json", &dir(), &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let opts = SimOptions {
        sleep: false,
        ..SimOptions::of_scene(&scene)
    };
    let mut sim = Simulation::new(scene.model.clone(), opts).unwrap();
    sim.set_state(&scene.q0, &scene.v0).unwrap();
    while sim.time() < 1.0 {
        sim.step().unwrap();
    }
    sim.solve_work()
}

#[test]
fn two_piles_ten_metres_apart_cost_what_each_costs_alone() {
    let a = spec("pile_boxes_16.json");
    let b = shifted(spec("pile_mixed_16.json"), 10.0, "b_");
    let (wa, wb) = (work(&a), work(&b));
    let both = work(&joined(a.clone(), b));
    assert!(wa > 0 && wb > 0);
    // each pile's island converges on its own: the sum, give or take the
    // order of the contact points (a different warm start)
    let sum = (wa + wb) as f64;
    assert!(
        (both as f64) <= 1.05 * sum,
        "two piles {both}, alone {wa} + {wb}"
    );
    // the form: two piles of one kind cost at most 2.2× one
    let two = work(&joined(a.clone(), shifted(a, 10.0, "c_")));
    assert!(two as f64 <= 2.2 * wa as f64, "two piles {two}, one {wa}");
}

/// `urdyn simulate --scene` of `scene` for `t` s with `args`: its CSV (a
/// file named by the scene and the arguments: the tests run at once).
fn csv(scene: &std::path::Path, t: f64, args: &[&str]) -> String {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned());
    let out = std::env::temp_dir().join(format!(
        "urdyn_islands_{}_{}_{}.csv",
        std::process::id(),
        stem.unwrap_or_default(),
        args.join("_").replace('-', "")
    ));
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg("--scene")
        .arg(scene)
        .args(["--duration", &t.to_string(), "--dt", "0.001", "--out"])
        .arg(&out)
        .args(args)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let s = std::fs::read_to_string(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    s
}

#[test]
fn threads_one_and_two_give_identical_csvs_on_a_pile_with_sleep_on_and_off() {
    // the 64-box pile: dozens of islands while it falls, one heap at the end,
    // boxes falling asleep from about 0.8 s
    let scene = dir().join("pile_boxes_64.json");
    for sleep in [&[][..], &["--no-sleep"][..]] {
        let one = csv(&scene, 1.2, &[sleep, &["--threads", "1"]].concat());
        let two = csv(&scene, 1.2, &[sleep, &["--threads", "2"]].concat());
        assert_eq!(one.lines().count(), 1201 + 1, "{sleep:?}");
        // the same file, byte for byte (every figure printed to round-trip)
        let first_diff = one.lines().zip(two.lines()).position(|(a, b)| a != b);
        assert_eq!(
            first_diff, None,
            "{sleep:?}: rows differ from line {first_diff:?}"
        );
        assert_eq!(one, two, "{sleep:?}");
    }
}

/// The mixed pile of 256 (balls, boxes and cylinders: a hundred islands a
/// solve, the position pass's joins) on 1 and 2 threads: the same CSV, byte
/// for byte, whichever thread solved which island or searched which of the
/// ground's shapes (256 shapes: the ground detection in chunks on the team,
/// the pairs' broad phase beside it, src/contact/ground/team.rs).
#[test]
fn threads_one_and_two_give_identical_csvs_on_the_mixed_256_pile() {
    let scene = dir().join("pile_mixed_256.json");
    let one = csv(&scene, 0.4, &["--every", "1", "--threads", "1"]);
    let two = csv(&scene, 0.4, &["--every", "1", "--threads", "2"]);
    assert_eq!(one.lines().count(), 401 + 1);
    let first_diff = one.lines().zip(two.lines()).position(|(a, b)| a != b);
    assert_eq!(first_diff, None, "rows differ from line {first_diff:?}");
    assert_eq!(one, two);
}

/// The box pile of 256 on 1 and 2 threads: the same CSV, byte for byte,
/// with the narrow phase on the team (a detection of this pile visits
/// hundreds of pairs: chunks of them on both threads,
/// src/contact/pairs/visit.rs) as well as the islands, and the ground
/// detection's chunks of shapes beside the pairs' broad phase
/// (src/contact/ground/team.rs).
#[test]
fn threads_one_and_two_give_identical_csvs_on_the_boxes_256_pile() {
    let scene = dir().join("pile_boxes_256.json");
    let one = csv(&scene, 0.3, &["--every", "5", "--threads", "1"]);
    let two = csv(&scene, 0.3, &["--every", "5", "--threads", "2"]);
    assert_eq!(one.lines().count(), 61 + 1);
    let first_diff = one.lines().zip(two.lines()).position(|(a, b)| a != b);
    assert_eq!(first_diff, None, "rows differ from line {first_diff:?}");
    assert_eq!(one, two);
}

/// The box pile of 1024 on 1 and 2 threads, every step printed: the same
/// CSV, byte for byte, through the round-31 parallel stages as well — the
/// contact rows' entries by ranges of contacts once a step has 512 points
/// or more (src/sim/constraints/team.rs) and the broad phase's member loop
/// by ranges of members beside the ground's shapes
/// (src/contact/pairs/members.rs), and the rows' form by ranges of rows
/// (src/sim/solver/form/team.rs: thousands of rows once landed).
#[test]
fn threads_one_and_two_give_identical_csvs_on_the_boxes_1024_pile() {
    let scene = dir().join("pile_boxes_1024.json");
    let one = csv(&scene, 0.25, &["--every", "1", "--threads", "1"]);
    let two = csv(&scene, 0.25, &["--every", "1", "--threads", "2"]);
    assert_eq!(one.lines().count(), 251 + 1);
    let first_diff = one.lines().zip(two.lines()).position(|(a, b)| a != b);
    assert_eq!(first_diff, None, "rows differ from line {first_diff:?}");
    assert_eq!(one, two);
}

/// `Simulation::new_at` (built at the scene's start state: contacts looked
/// for once, there) steps exactly as `new` then `set_state` (which first looks
/// for contacts with every model at the origin, all pairs overlapping: the
/// O(N²) setup it avoids): the same q and v to the bit after 0.6 s of a mixed
/// pile falling into its bin (boxes, balls and cylinders), sleep on.
#[test]
fn built_at_the_start_state_steps_as_new_then_set_state() {
    let s = spec("pile_mixed_16.json");
    let scene = Scene::from_json(&s.to_string(), "pile.json", &dir(), &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let opts = SimOptions::of_scene(&scene);
    let mut a = Simulation::new(scene.model.clone(), opts.clone()).unwrap();
    a.set_state(&scene.q0, &scene.v0).unwrap();
    let mut b = Simulation::new_at(scene.model.clone(), opts, &scene.q0, &scene.v0).unwrap();
    assert_eq!(a.q(), b.q());
    while a.time() < 0.6 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert!(a.contact_points().len() > 4, "the pile is in contact");
    let bits = |x: &nalgebra::DVector<f64>| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(a.q()), bits(b.q()));
    assert_eq!(bits(a.v()), bits(b.v()));
}
