//! Simulating an MJCF world (mjcf.md §"What the file becomes"): Gymnasium's
//! hopper and ant on their floor plane, a pendulum whose armature sets its
//! period (closed form), a damped double pendulum with springs against
//! MuJoCo's trajectory (tests/oracle/make_mjcf_sim_fixture.py), keyframes and
//! the CLI's MJCF path; the speculative margin (docs/theory.md §"Speculative
//! margin"): Gymnasium's humanoid lands at its 3 ms step less than 1 mm deep,
//! and a slow scene's run is the constant margin's bit for bit.

use nalgebra::DVector;
use std::path::{Path, PathBuf};
use urdyn::contact::ContactParams;
use urdyn::mjcf;
use urdyn::sim::{Integrator, SimOptions, Simulation};

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/mjcf")
        .join(rel)
}

/// The simulation `urdyn simulate MODEL.xml` runs: the file's ground plane,
/// its friction and timestep (the speculative margin's factor left at 0).
fn world_sim(rel: &str, integrator: Option<Integrator>) -> (Simulation, mjcf::World) {
    world_sim_travel(rel, integrator, 0.0)
}

/// [`world_sim`] with the speculative margin's factor `c` (`urdyn simulate`
/// sets [`ContactParams::TRAVEL`]; 0: the constant δ alone).
fn world_sim_travel(
    rel: &str,
    integrator: Option<Integrator>,
    c: f64,
) -> (Simulation, mjcf::World) {
    let (model, world) = mjcf::load_file_with_world(fixture(rel)).expect("loads");
    let mut opts = SimOptions {
        integrator,
        sleep: false,
        ..SimOptions::of_mjcf_world(&world)
    };
    opts.contact.travel_factor = c;
    (Simulation::new(model, opts).expect("sim"), world)
}

/// Runs to `t_end`, returning the energy after every step (with the time).
fn energies(sim: &mut Simulation, t_end: f64) -> Vec<(f64, f64)> {
    let mut out = vec![(sim.time(), sim.energy())];
    while sim.time() < t_end {
        sim.step_until(t_end).expect("step");
        out.push((sim.time(), sim.energy()));
    }
    out
}

fn max_rise(e: &[(f64, f64)], after: f64) -> f64 {
    e.windows(2)
        .filter(|w| w[0].0 >= after)
        .map(|w| w[1].1 - w[0].1)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn gymnasium_hopper_dropped_lands_on_its_plane_and_energy_never_rises() {
    let (mut sim, world) = world_sim("gymnasium/hopper.xml", None);
    let ground = mjcf::ground_of(&world).expect("hopper's floor is the ground");
    assert_eq!(ground.height, 0.0);
    // rootz (ref 1.25: the standing pose) raised 0.3 m
    let mut q = sim.q().clone();
    assert_eq!(sim.model.dofs[1].name, "rootz");
    q[1] += 0.3;
    let v = DVector::zeros(sim.model.nv);
    sim.set_state(&q, &v).unwrap();
    let e0 = sim.energy();
    let e = energies(&mut sim, 1.0);
    // it fell 0.3 m and landed on the foot: contact, no penetration beyond 1 mm
    assert!(sim.active_contacts() > 0, "not on the ground");
    assert!(
        sim.penetration() < 1e-3,
        "penetration {}",
        sim.penetration()
    );
    // the impact dissipates: energy drops, and no step raises it (J)
    let rise = max_rise(&e, 0.0);
    assert!(rise < 1e-6, "energy rose by {rise} J in a step");
    assert!(
        e.last().unwrap().1 < e0 - 1.0,
        "{} -> {}",
        e0,
        e.last().unwrap().1
    );
}

#[test]
fn gymnasium_ant_falls_onto_its_plane_and_comes_to_rest() {
    let (mut sim, _) = world_sim("gymnasium/ant.xml", None);
    // the torso's free joint: q = its world pose (0, 0, 0.75)
    assert!((sim.q()[2] - 0.75).abs() < 1e-12);
    let e = energies(&mut sim, 4.0);
    // the ankles start outside their limits (q = 0, range 30°–70°): once the
    // position pass has brought them back (≤ 0.52 rad at 1 rad/s, settled by
    // 1 s), the energy never rises by more than 1 µJ a step
    let rise = max_rise(&e, 1.0);
    assert!(rise < 1e-6, "energy rose by {rise} J in a step");
    let v_max = sim.v().amax();
    assert!(v_max < 1e-3, "still moving: |v|max = {v_max}");
    assert!(
        sim.active_contacts() >= 4,
        "{} contacts",
        sim.active_contacts()
    );
    assert!(sim.penetration() < 1e-3);
    // the torso rests above the floor, on its legs
    let z = sim.q()[2];
    assert!(z > 0.2 && z < 0.75, "torso at z = {z}");
}

#[test]
fn the_armature_sets_the_pendulum_period() {
    let (model, _) =
        mjcf::load_file_with_world(fixture("sim/pendulum_armature.xml")).expect("loads");
    assert_eq!(model.dofs[0].armature, 0.25);
    let opts = SimOptions {
        dt: 1e-3,
        integrator: Some(Integrator::from_name("dop853").unwrap()),
        tol: 1e-11,
        ground: None,
        sleep: false,
        ..SimOptions::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let theta0 = 1e-3;
    sim.set_state(&DVector::from_element(1, theta0), &DVector::zeros(1))
        .unwrap();
    // T = 2π √((m l² + I_c + a)/(m g l)) (small angle; the amplitude's
    // correction θ₀²/16 ≈ 6e-8 is below the tolerance)
    let (m, l, ic, a, g): (f64, f64, f64, f64, f64) = (1.5, 0.8, 0.01, 0.25, 9.81);
    let period = 2.0 * std::f64::consts::PI * ((m * l * l + ic + a) / (m * g * l)).sqrt();
    let without = 2.0 * std::f64::consts::PI * ((m * l * l + ic) / (m * g * l)).sqrt();
    assert!((period - without) / period > 0.1);
    // downward zero crossings of θ (θ̇ < 0), linearly interpolated
    let mut crossings = Vec::new();
    let (mut t_prev, mut q_prev) = (0.0, theta0);
    while sim.time() < 3.2 * period {
        let t_next = sim.time() + 1e-3;
        sim.step_until(t_next).unwrap();
        let (t, q) = (sim.time(), sim.q()[0]);
        if q_prev > 0.0 && q <= 0.0 {
            crossings.push(t_prev + (t - t_prev) * q_prev / (q_prev - q));
        }
        (t_prev, q_prev) = (t, q);
    }
    assert!(crossings.len() >= 3, "{crossings:?}");
    let measured = (crossings[2] - crossings[0]) / 2.0;
    let rel = (measured - period).abs() / period;
    eprintln!(
        "mjcf_sim: period {measured} s, closed form {period} s, without armature {without} s"
    );
    assert!(
        rel < 1e-5,
        "period {measured} s, closed form {period} s (without armature {without} s): rel {rel}"
    );
}

#[test]
fn a_damped_double_pendulum_with_springs_follows_mujoco() {
    let text = std::fs::read_to_string(fixture("sim/mujoco_double_pendulum_passive.json"))
        .expect("fixture");
    let fx: serde_json::Value = serde_json::from_str(&text).unwrap();
    let (model, world) =
        mjcf::load_file_with_world(fixture("sim/double_pendulum_passive.xml")).expect("loads");
    assert_eq!(world.keys[0].name, "swing");
    let opts = SimOptions {
        dt: 1e-3,
        integrator: Some(Integrator::from_name("dop853").unwrap()),
        tol: 1e-10,
        ground: None,
        sleep: false,
        ..SimOptions::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let key = &world.keys[0];
    let q0 = DVector::from_column_slice(key.qpos.as_ref().unwrap());
    let v0 = DVector::from_column_slice(key.qvel.as_ref().unwrap());
    sim.set_state(&q0, &v0).unwrap();
    let nums = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let mut worst: f64 = 0.0;
    for s in fx["samples"].as_array().unwrap() {
        let t = s["t"].as_f64().unwrap();
        while sim.time() < t {
            sim.step_until(t).unwrap();
        }
        assert!((sim.time() - t).abs() < 1e-12);
        for (ours, theirs) in [(sim.q(), nums(&s["qpos"])), (sim.v(), nums(&s["qvel"]))] {
            for (a, b) in ours.iter().zip(&theirs) {
                worst = worst.max((a - b).abs());
            }
        }
    }
    // MuJoCo's RK4 at 1e-5 s (error ~1e-15 over 2 s) and urdyn's dop853 at
    // tol 1e-10 (its global error on this smooth, mildly damped system stays
    // within ~1e-8): 1e-7 rad and rad/s leaves room for neither a missing
    // armature (a 5 % change of the inertia) nor a wrong springref
    eprintln!("mjcf_sim: worst |urdyn − MuJoCo| = {worst:e}");
    assert!(worst < 1e-7, "worst |urdyn − MuJoCo| = {worst}");
}

#[test]
fn simulate_reads_the_mjcf_world_and_its_keyframe() {
    let out = std::env::temp_dir().join(format!("mjcf_sim_{}.csv", std::process::id()));
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg(fixture("sim/double_pendulum_passive.xml"))
        .args([
            "--key",
            "swing",
            "--duration",
            "0.01",
            "--integrator",
            "euler",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    let first: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(&first[..5], &[0.0, 1.0, -0.5, 0.3, -1.0]);
    // dt from <option timestep> (0.001): 10 steps, 11 rows
    assert_eq!(csv.lines().count(), 12);
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_urdyn"))
        .arg("simulate")
        .arg(fixture("sim/double_pendulum_passive.xml"))
        .args(["--key", "nope", "--duration", "0.01"])
        .output()
        .expect("runs");
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("--key nope: no such keyframe (the file has: swing)"),
        "{err}"
    );
}

/// `<option><flag contact="disable">` (dm_control's point_mass): nothing
/// collides, as in MuJoCo (which finds no contact there, while the point mass
/// starts inside the world's `target` sphere); the same file without the flag
/// has collision shapes.
#[test]
fn a_disabled_contact_flag_leaves_no_collision_shape() {
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/dm_control");
    let text = std::fs::read_to_string(dir.join("point_mass.xml")).unwrap();
    assert!(text.contains(r#"<flag contact="disable"/>"#));
    let off = urdyn::mjcf::load_str(&text, "point_mass.xml", &dir).unwrap();
    assert!(off.collisions.is_empty(), "{:?}", off.collisions.len());
    let on = urdyn::mjcf::load_str(
        &text.replace(r#"<flag contact="disable"/>"#, ""),
        "point_mass.xml",
        &dir,
    )
    .unwrap();
    assert!(!on.collisions.is_empty());
}

/// The deepest penetration of Gymnasium's humanoid dropped from its default
/// pose, stepped 1 s at its file's dt (3 ms) as `urdyn simulate` steps it,
/// with the speculative margin's factor `c` (0: the constant δ alone).
fn humanoid_deepest(c: f64) -> f64 {
    let (mut sim, world) = world_sim_travel(
        "gymnasium/humanoid.xml",
        Some(Integrator::SemiImplicitEuler),
        c,
    );
    assert!(mjcf::ground_of(&world).is_some(), "a floor");
    let (mut deepest, mut landed) = (0.0f64, false);
    while sim.time() < 1.0 {
        sim.step().unwrap();
        deepest = deepest.max(sim.penetration());
        landed |= sim.active_contacts() > 0;
    }
    assert!(landed);
    deepest
}

#[test]
fn gymnasium_humanoid_lands_at_its_file_dt_less_than_a_millimetre_deep() {
    assert_eq!(
        mjcf::load_file_with_world(fixture("gymnasium/humanoid.xml"))
            .unwrap()
            .1
            .timestep,
        0.003
    );
    // falling at 3 m/s and turning, a limb travels ~9 mm in a 3 ms step, more
    // than δ = 5 mm: with δ alone its first contact is found 2.6 mm deep
    // (0.78 s); with the margin grown to c·(last step's travel) it is found
    // before the impact and the speculative row stops it at the floor
    let late = humanoid_deepest(0.0);
    assert!(late > 2e-3, "δ alone: {late} m");
    let deepest = humanoid_deepest(ContactParams::TRAVEL);
    assert!(deepest < 1e-3, "penetration {deepest} m");
}

#[test]
fn a_slow_scene_keeps_the_constant_margin_bit_for_bit() {
    // the lamp dropped 0.5 m onto the table at dt 1 ms: it moves at most
    // 3.1 mm a step, c·s = 4.7 mm < δ = 5 mm: the margin never grows, and the
    // run is the constant margin's exactly
    let s = urdyn::scene::Scene::from_file(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/lamp_on_table.json"),
        &[],
    )
    .unwrap();
    let run = |c: f64| {
        assert!(s.ground.is_some(), "a ground");
        let mut opts = SimOptions::of_scene(&s);
        opts.contact.travel_factor = c;
        let mut sim = Simulation::new(s.model.clone(), opts).unwrap();
        sim.set_state(&s.q0, &s.v0).unwrap();
        let (mut qs, mut fastest) = (Vec::new(), 0.0f64);
        while sim.time() < 1.0 {
            sim.step().unwrap();
            qs.extend_from_slice(sim.q().as_slice());
            fastest = fastest.max(sim.v().amax());
        }
        assert!(sim.active_contacts() > 0, "on the table");
        (qs, fastest)
    };
    let (grown, fastest) = run(ContactParams::TRAVEL);
    let (constant, _) = run(0.0);
    assert!(fastest > 3.0, "it fell at {fastest} m/s");
    assert!(grown == constant, "the trajectories differ");
}

#[test]
fn gymnasium_ant_lands_under_a_millimetre_and_rests_with_the_margin() {
    // `urdyn simulate ant.xml` (the speculative margin on, euler, dt 10 ms):
    // the ant lands on four feet with its ankles on their limits, 16 rows on
    // 14 dofs, a redundant set whose subspace step once took a rounding-level
    // pivot for a row and gave impulses of 1e7 N·s: every later step then hit
    // the sweep cap, a foot was left moving into the floor at 0.275 m/s and
    // sank 2.7 mm at 0.36 s (benches/mjcf_results.md, round 6)
    let (mut sim, world) = world_sim_travel(
        "gymnasium/ant.xml",
        Some(Integrator::SemiImplicitEuler),
        ContactParams::TRAVEL,
    );
    assert!(mjcf::ground_of(&world).is_some(), "a floor");
    let cap = SimOptions::default().solver_iterations as u64;
    let (mut deepest, mut capped_at_rest) = (0.0f64, 0);
    while sim.time() < 3.0 - 1e-9 {
        let s0 = sim.pgs_sweeps;
        sim.step().unwrap();
        deepest = deepest.max(sim.penetration());
        if sim.time() > 1.0 && sim.pgs_sweeps - s0 >= cap {
            capped_at_rest += 1;
        }
    }
    // the issue's bound: under a millimetre where MuJoCo's soft contact sinks
    assert!(deepest < 1e-3, "penetration {deepest} m");
    // at rest on its four feet, the solve converged (not stopped by its cap)
    assert_eq!(capped_at_rest, 0, "steps at the sweep cap after 1 s");
    assert!(sim.active_contacts() >= 4);
    let v = sim.v().amax();
    assert!(v < 1e-5, "|v|max = {v} at 3 s");
}
