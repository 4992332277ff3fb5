//! src/sim/doze.rs, round 22: a quiet island's doze period doubles from
//! N_DOZE = 8 up to 32 steps while each full step finds it as it left it. A
//! box sliding slowly on frictionless ground dozes at the long period and
//! falls asleep where the run without doze puts it, at the same step; a box
//! resting at the long period wakes (a full step) at the first step a falling
//! box touches it.

use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};

fn root() -> &'static std::path::Path {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `models`: (name, position) of 0.2 m boxes on a ground of friction `mu`.
fn scene(models: &[(&str, [f64; 3])], mu: f64) -> Scene {
    let list: Vec<String> = models
        .iter()
        .map(|(n, p)| {
            format!(
                r#"{{"name": "{n}", "urdf": "tests/urdf/crate_box.urdf", "base": "floating",
                    "friction": {mu}, "position": [{}, {}, {}]}}"#,
                p[0], p[1], p[2]
            )
        })
        .collect();
    let json = format!(
        r#"{{"ground": {{"height": 0.0, "friction": {mu}}}, "models": [{}]}}"#,
        list.join(", ")
    );
    Scene::from_json(&json, "doze_period.json", root(), &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn simulation(s: &Scene, v: &nalgebra::DVector<f64>, doze: bool) -> Simulation {
    let opts = SimOptions::of_scene(s);
    let mut sim = Simulation::new(s.model.clone(), opts).unwrap();
    sim.set_state(&s.q0, v).unwrap();
    sim.set_doze(doze);
    sim
}

#[test]
fn a_box_sliding_slowly_dozes_at_the_long_period_and_sleeps_where_the_run_without_doze_does() {
    // resting on the ground (its centre 0.1 m up), sliding along x at
    // 15 µm/s on frictionless ground: below GROW_SPEED · sleep_velocity
    // (20 µm/s), so its period grows; it moves 7.5 µm in the 0.5 s before it
    // sleeps, 15 nm a step
    let s = scene(&[("m", [0.0, 0.0, 0.1])], 0.0);
    let mut v = s.v0.clone();
    v[0] = 1.5e-5;
    let run = |doze: bool| {
        let mut sim = simulation(&s, &v, doze);
        let mut longest = 0;
        while sim.sleeping("m") != Some(true) {
            assert!(sim.time() < 1.5, "never asleep (doze {doze})");
            sim.step().unwrap();
            longest = longest.max(sim.doze_period("m").unwrap_or(0));
        }
        (
            sim.time(),
            sim.q().as_slice().to_vec(),
            longest,
            sim.doze_steps(),
        )
    };
    let (t_on, q_on, longest, steps) = run(true);
    let (t_off, q_off, _, off_steps) = run(false);
    assert_eq!(off_steps, 0);
    assert_eq!(longest, 32, "the period never grew to 32");
    assert!(steps > 300, "dozed {steps} steps");
    assert!((t_on - t_off).abs() < 1e-9, "asleep at {t_on} s, {t_off} s");
    // it slid; the two runs agree closer than half a step's travel (15 nm):
    // no dozing step is lost or taken twice at any period
    assert!(q_off[0] > 6e-6, "slid only {} m", q_off[0]);
    let d = q_on
        .iter()
        .zip(&q_off)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        d < 7e-9,
        "{d} from the run without doze: {q_on:?} {q_off:?}"
    );
}

#[test]
fn a_box_resting_at_the_long_period_wakes_at_the_first_touch_of_a_falling_box() {
    // a rests from the start; b falls from 0.9 m onto it (touching after
    // ~0.35 s, before a would sleep at ~0.55 s)
    let s = scene(&[("a", [0.0, 0.0, 0.1]), ("b", [0.03, 0.0, 0.9])], 0.8);
    let mut sim = simulation(&s, &s.v0.clone(), true);
    let (bodies_a, bodies_b) = (
        sim.model.trees[0].bodies.clone(),
        sim.model.trees[1].bodies.clone(),
    );
    let mut longest_before = 0;
    let mut touch_at = None;
    let mut deepest = 0.0f64;
    while sim.time() < 0.8 {
        let dozing_before = sim.dozing("a") == Some(true);
        let period_before = sim.doze_period("a").unwrap_or(0);
        sim.step().unwrap();
        let touching = sim.contact_points().iter().any(|p| {
            (bodies_a.contains(&p.body) && bodies_b.contains(&p.other))
                || (bodies_b.contains(&p.body) && bodies_a.contains(&p.other))
        });
        if touching && touch_at.is_none() {
            // the first step whose detection joins them: a was dozing into it
            // at the long period and stops at once (its next step is full)
            touch_at = Some(sim.time());
            assert!(dozing_before, "a was not dozing when b arrived");
            assert_eq!(period_before, 32, "a's period when b arrived");
            assert_eq!(sim.dozing("a"), Some(false), "at {} s", sim.time());
            assert_eq!(sim.doze_period("a"), None);
        }
        if touch_at.is_none() {
            longest_before = longest_before.max(sim.doze_period("a").unwrap_or(0));
        }
        deepest = deepest.max(sim.penetration());
    }
    assert_eq!(longest_before, 32);
    assert!(touch_at.is_some(), "b never reached a");
    assert!(deepest < 5e-3, "{deepest} m deep");
}
