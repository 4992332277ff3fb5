//! src/sim/doze.rs: a quiet island's multirate step (issue #30). A box at rest
//! on the ground dozes (its contact points are held aside: the step searches
//! nothing for it) and falls asleep where the run without doze does; a ball
//! rolling slower than sleep_velocity falls asleep where that run puts it; a
//! box dropped onto a dozing box wakes it (a full step) at the touch.

use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

fn root() -> &'static std::path::Path {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `models`: (name, urdf, position) on the ground.
fn scene(models: &[(&str, &str, [f64; 3])]) -> Scene {
    let list: Vec<String> = models
        .iter()
        .map(|(n, u, p)| {
            format!(
                r#"{{"name": "{n}", "urdf": "{u}", "base": "floating", "position": [{}, {}, {}]}}"#,
                p[0], p[1], p[2]
            )
        })
        .collect();
    let json = format!(
        r#"{{"ground": {{"height": 0.0}}, "models": [{}]}}"#,
        list.join(", ")
    );
    Scene::from_json(&json, "doze.json", root(), &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn simulation(s: &Scene, doze: bool) -> Simulation {
    let opts = SimOptions::of_scene(s);
    let mut sim = Simulation::new(s.model.clone(), opts).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    sim.set_doze(doze);
    sim
}

/// Steps until model `m` sleeps (at most `t_max` s): the time and q then.
fn until_asleep(sim: &mut Simulation, m: &str, t_max: f64) -> (f64, Vec<f64>) {
    while sim.sleeping(m) != Some(true) {
        assert!(sim.time() < t_max, "{m} still awake at {} s", sim.time());
        sim.step().unwrap();
    }
    (sim.time(), sim.q().as_slice().to_vec())
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_box_at_rest_dozes_with_its_points_held_aside_and_sleeps_where_the_run_without_doze_does() {
    let s = scene(&[("m", "tests/urdf/crate_box.urdf", [0.0, 0.0, 0.1])]);
    let mut on = simulation(&s, true);
    let mut off = simulation(&s, false);
    let mut dozed = 0;
    while on.sleeping("m") != Some(true) {
        assert!(on.time() < 1.5, "never asleep");
        on.step().unwrap();
        if on.dozing("m") == Some(true) {
            dozed += 1;
            // awake, counted awake; its points out of the step's list (no
            // detection) but their forces still reported
            assert_eq!((on.awake(), on.sleeping("m")), (1, Some(false)));
            assert!(on.contact_points().is_empty());
            assert!(on.contact_forces().len() >= 4);
        }
    }
    // 7 steps of 8 doze once the box is still for 50 ms
    assert!(dozed > 300, "dozed {dozed} steps");
    assert_eq!(on.doze_steps(), dozed as u64);
    let (t_off, q_off) = until_asleep(&mut off, "m", 1.5);
    assert_eq!(off.doze_steps(), 0);
    // asleep at the same step, within 1e-6 m and rad of the same pose
    assert!(
        (on.time() - t_off).abs() < 1e-9,
        "{} s, {t_off} s",
        on.time()
    );
    let d = max_diff(on.q().as_slice(), &q_off);
    assert!(d < 1e-6, "{d} from the run without doze");
}

#[test]
fn a_ball_rolling_below_sleep_velocity_sleeps_where_the_run_without_doze_puts_it() {
    let s = scene(&[("b", "tests/urdf/heavy_ball.urdf", [0.0, 0.0, 0.08])]);
    let mut v = s.v0.clone();
    // 0.2 mm/s along x, rolling (body frame = world frame at the start): its
    // points at most 0.4 mm/s, below half sleep_velocity, where a tree dozes
    v[0] = 2e-4;
    v[4] = 2e-4 / 0.08;
    let run = |doze: bool| {
        let mut sim = simulation(&s, doze);
        sim.set_state(&s.q0, &v).unwrap();
        let (t, q) = until_asleep(&mut sim, "b", 2.0);
        (t, q, sim.doze_steps())
    };
    let (t_on, q_on, steps) = run(true);
    let (t_off, q_off, _) = run(false);
    assert!(steps > 100, "dozed {steps} steps");
    assert!((t_on - t_off).abs() < 0.01, "asleep at {t_on} s, {t_off} s");
    // within a few N h sleep_velocity (8 µm) of where it sleeps without doze
    let dx = max_diff(&q_on[..3], &q_off[..3]);
    assert!(dx < 3e-5, "{dx} m from the run without doze");
    assert!(
        (q_on[0] - q_off[0]).abs() < 3e-5 && q_off[0] > 5e-5,
        "{q_on:?} {q_off:?}"
    );
}

#[test]
fn a_box_dropped_onto_a_dozing_box_wakes_it_at_the_touch() {
    let s = scene(&[
        ("a", "tests/urdf/crate_box.urdf", [0.0, 0.0, 0.1]),
        ("b", "tests/urdf/crate_box.urdf", [0.02, 0.0, 0.55]),
    ]);
    let mut sim = simulation(&s, true);
    let (bodies_a, bodies_b) = (
        sim.model.trees[0].bodies.clone(),
        sim.model.trees[1].bodies.clone(),
    );
    let mut dozed_before = false;
    let mut touched = false;
    let mut deepest = 0.0f64;
    while sim.time() < 0.6 {
        sim.step().unwrap();
        let touching = sim.contact_points().iter().any(|p| {
            (bodies_a.contains(&p.body) && bodies_b.contains(&p.other))
                || (bodies_b.contains(&p.body) && bodies_a.contains(&p.other))
        });
        if !touched && !touching && sim.dozing("a") == Some(true) {
            dozed_before = true;
        }
        if touching {
            touched = true;
            // a point joins them: neither dozes, both in the step
            assert_eq!(sim.dozing("a"), Some(false), "at {} s", sim.time());
            assert_eq!(sim.dozing("b"), Some(false));
        }
        deepest = deepest.max(sim.penetration());
    }
    assert!(dozed_before, "a never dozed before b arrived");
    assert!(touched, "b never reached a");
    assert!(deepest < 5e-3, "{deepest} m deep");
}
