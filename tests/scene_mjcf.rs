//! A scene's MJCF model (mjcf.md §"Entry points", scene.md §"More in a
//! scene"): `{"name": …, "mjcf": "file.xml", "position": …}` is the file's
//! whole world placed by the model's pose. Gymnasium's ant placed in a scene
//! moves as `urdyn simulate ant.xml` (the same simulation, built as
//! tests/mjcf_sim.rs builds it) with every link pose moved by that pose; the
//! keys that do not apply to an MJCF model are errors naming them; an ant
//! beside a URDF lamp; an MJCF world of several trees and a static geom;
//! `initial` arrays for an MJCF model's ball and free joints.

use nalgebra::{DVector, Matrix3, Vector3};
use std::path::{Path, PathBuf};
use urdyn::dynamics_f64::{forward_kinematics, update_frames};
use urdyn::mjcf;
use urdyn::scene::Scene;
use urdyn::sim::{SimOptions, Simulation};
use urdyn::spatial::{quat_to_matrix, Se3};
use urdyn::{Data, Model};

fn gym() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/gymnasium")
}

fn scene_in(dir: &Path, json: &str) -> Result<Scene, urdyn::SceneError> {
    Scene::from_json(json, "test.json", dir, &[])
}

/// `urdyn simulate ant.xml`'s simulation (src/cli/simulate_mjcf.rs): the
/// file's ground plane and its friction, its timestep; without the speculative
/// margin, as a scene's contact.
fn ant_alone() -> Simulation {
    let (model, world) = mjcf::load_file_with_world(gym().join("ant.xml")).expect("loads");
    let mut opts = SimOptions {
        sleep: false,
        ..SimOptions::of_mjcf_world(&world)
    };
    opts.contact.travel_factor = 0.0;
    Simulation::new(model, opts).expect("sim")
}

/// A scene's simulation as `urdyn simulate SCENE.json` builds it (its ground
/// and the ground's contact parameters), at the ant's timestep.
fn scene_sim(s: &Scene) -> Simulation {
    let opts = SimOptions {
        dt: 0.01,
        sleep: false,
        ..SimOptions::of_scene(s)
    };
    let mut sim = Simulation::new(s.model.clone(), opts).expect("sim");
    sim.set_state(&s.q0, &s.v0).expect("state");
    sim
}

/// Steps to time `t` (`step_until` takes one step).
fn run_to(sim: &mut Simulation, t: f64) {
    while sim.time() < t - 1e-9 {
        sim.step_until(t).expect("step");
    }
}

/// Every link frame's world pose at q.
fn link_poses(model: &Model, q: &DVector<f64>) -> Vec<(String, Se3<f64>)> {
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q).expect("fk");
    update_frames(model, &mut data);
    model
        .frames
        .iter()
        .zip(&data.o_m_f)
        .map(|(f, m)| (f.name.clone(), *m))
        .collect()
}

/// The largest difference between `scene`'s frames `PREFIX/NAME` and
/// `pose ∘ alone`'s frame `NAME` (rotation entries and metres), over every
/// frame of `alone`.
fn gap(
    scene: &[(String, Se3<f64>)],
    prefix: &str,
    alone: &[(String, Se3<f64>)],
    pose: &Se3<f64>,
) -> f64 {
    let mut worst = 0.0f64;
    for (name, m) in alone {
        let full = format!("{prefix}/{name}");
        let (_, s) = scene
            .iter()
            .find(|(n, _)| *n == full)
            .unwrap_or_else(|| panic!("no frame {full} in the scene"));
        let want = pose.compose(m);
        worst = worst
            .max((s.rot - want.rot).amax())
            .max((s.trans - want.trans).amax());
    }
    worst
}

/// A rotation of `a` rad about z as a quaternion x, y, z, w.
fn about_z(a: f64) -> [f64; 4] {
    [0.0, 0.0, (a / 2.0).sin(), (a / 2.0).cos()]
}

/// The ant of `ant.xml` placed at `p`, turned `a` rad about z, against
/// `simulate ant.xml`: the largest link pose gap at each time of `times`.
fn ant_gaps(p: [f64; 3], a: f64, times: &[f64]) -> Vec<(f64, f64)> {
    let o = about_z(a);
    let json = format!(
        r#"{{"models": [{{"name": "ant", "mjcf": "ant.xml", "position": [{}, {}, {}],
            "orientation_xyzw": [{}, {}, {}, {}]}}]}}"#,
        p[0], p[1], p[2], o[0], o[1], o[2], o[3]
    );
    let s = scene_in(&gym(), &json).unwrap_or_else(|e| panic!("{e}"));
    let pose = Se3::new(quat_to_matrix(o[0], o[1], o[2], o[3]), Vector3::from(p));
    // the file's floor plane (z = 0, friction 1) is the scene's ground, moved with the ant
    let g = s.ground.expect("the floor plane is the ground");
    assert_eq!((g.height, g.friction), (p[2], 1.0));
    assert!(s.models[0].mjcf);
    // the torso's free joint: q is its world pose, (0, 0, 0.75) of the file placed
    let mut alone = ant_alone();
    assert_eq!(s.model.nq, alone.model.nq);
    let want = pose.compose(&Se3::from_translation(Vector3::new(0.0, 0.0, 0.75)));
    let q = &s.q0;
    assert!((Vector3::new(q[0], q[1], q[2]) - want.trans).amax() < 1e-15);
    let r = quat_to_matrix(q[3], q[4], q[5], q[6]);
    assert!((r - want.rot).amax() < 1e-15);
    // the actuators come along, renamed
    assert_eq!(s.model.actuators.len(), 8);
    assert!(s.model.actuators.iter().all(|a| a.name.starts_with("ant/")));
    let mut sim = scene_sim(&s);
    let mut worst = Vec::new();
    for &t in times {
        run_to(&mut sim, t);
        run_to(&mut alone, t);
        let a = link_poses(&alone.model, alone.q());
        let b = link_poses(&s.model, sim.q());
        worst.push((t, gap(&b, "ant", &a, &pose)));
    }
    // it fell and landed on its legs: the torso is below where it started
    let z = sim.q()[2] - p[2];
    assert!(z < 0.75 - 0.2 && z > 0.0, "torso {z} m above the ground");
    assert!(sim.active_contacts() >= 4);
    worst
}

#[test]
fn an_ant_placed_in_a_scene_moves_as_simulate_ant_xml_moved_by_its_pose() {
    // placed at the origin: the same simulation, bit for bit
    let same = ant_gaps([0.0; 3], 0.0, &[0.5, 2.0]);
    assert!(same.iter().all(|&(_, w)| w == 0.0), "{same:?}");
    // moved: the fall (0.3 s), the landing (0.4–0.5 s) and the rest, within
    // rounding carried through the contact solve's tolerance
    let times = [0.0, 0.3, 0.4, 0.45, 0.5, 0.6, 1.0, 2.0];
    let moved = ant_gaps([1.5, -2.0, 0.25], 0.0, &times);
    println!("ant moved by (1.5, -2, 0.25): largest link pose gap by time {moved:?}");
    for (t, w) in moved {
        assert!(w < 1e-8, "at t = {t}: link poses differ by {w}");
    }
    // moved and turned 0.6 rad about z: the same until it lands; then a
    // capsule's contact points on the ground are picked along world-fixed
    // tangents (src/contact/narrow.rs), so a turned ant lands on slightly
    // other points (measured: 1.6e-5 m from 0.45 s on, not growing)
    let turned = ant_gaps([1.5, -2.0, 0.25], 0.6, &times);
    println!("ant moved and turned 0.6 rad: largest link pose gap by time {turned:?}");
    for (t, w) in turned {
        let tol = if t < 0.35 { 1e-12 } else { 1e-4 };
        assert!(w < tol, "at t = {t}: link poses differ by {w}");
    }
}

fn refused(json: &str) -> urdyn::SceneError {
    match scene_in(&gym(), json) {
        Ok(_) => panic!("accepted: {json}"),
        Err(e) => e,
    }
}

#[test]
fn keys_that_do_not_apply_to_an_mjcf_model_are_errors_naming_them() {
    for (extra, key) in [
        (r#""base": "floating""#, "models[0].base"),
        (r#""srdf": "ant.srdf""#, "models[0].srdf"),
        (r#""pose": "home""#, "models[0].pose"),
        (
            r#""initial": {"base": {"position": [0, 0, 1]}}"#,
            "models[0].initial.base",
        ),
        (
            r#""orientation_xyzw": [0.2588190451, 0, 0, 0.9659258263]"#,
            "models[0].orientation_xyzw",
        ),
    ] {
        let e = refused(&format!(
            r#"{{"models": [{{"name": "ant", "mjcf": "ant.xml", {extra}}}]}}"#
        ));
        assert_eq!(e.key, key, "{e}");
    }
    let e = refused(r#"{"models": [{"name": "ant", "mjcf": "ant.xml", "urdf": "a.urdf"}]}"#);
    assert_eq!(e.key, "models[0]");
    assert!(e.message.contains("both"), "{e}");
    let e = refused(r#"{"models": [{"name": "ant"}]}"#);
    assert_eq!(e.key, "models[0]");
    assert!(e.message.contains("neither"), "{e}");
    let e = refused(r#"{"models": [{"name": "ant", "mjcf": "no_such.xml"}]}"#);
    assert_eq!(e.key, "models[0].mjcf");
    assert!(e.missing.is_some());
    // a floor at z = 0 and the scene's ground at z = 0.1: two grounds
    let e =
        refused(r#"{"ground": {"height": 0.1}, "models": [{"name": "ant", "mjcf": "ant.xml"}]}"#);
    assert_eq!(e.key, "models[0].mjcf");
    // the same ground twice is one ground
    let s = scene_in(
        &gym(),
        r#"{"ground": {"height": 0.25, "friction": 0.7},
            "models": [{"name": "ant", "mjcf": "ant.xml", "position": [0, 0, 0.25]}]}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.ground.map(|g| (g.height, g.friction)), Some((0.25, 0.7)));
    assert!(
        s.warnings.iter().any(|w| w.contains("friction 1")),
        "{:?}",
        s.warnings
    );
    // equality constraints cannot be dropped
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/equality");
    let e = scene_in(
        &dir,
        r#"{"models": [{"name": "m", "mjcf": "equalities.xml"}]}"#,
    )
    .err()
    .expect("refused");
    assert_eq!(e.key, "models[0].mjcf");
    assert!(e.message.contains("<equality>"), "{e}");
}

#[test]
fn an_mjcf_ant_beside_a_urdf_lamp() {
    let lamp = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/lamp.urdf");
    let json = format!(
        r#"{{"models": [{{"name": "ant", "mjcf": "ant.xml", "position": [0, 0, 0]}},
                       {{"name": "lamp", "urdf": "{}", "base": "floating", "position": [4, 0, 0.5]}}]}}"#,
        lamp.display()
    );
    let s = scene_in(&gym(), &json).unwrap_or_else(|e| panic!("{e}"));
    let lamp_alone = urdyn::load_file(
        &lamp,
        urdyn::LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let mut alone = ant_alone();
    assert_eq!(s.model.nq, alone.model.nq + lamp_alone.nq);
    assert_eq!(s.model.trees.len(), 2);
    assert_eq!(s.model.trees[1].q.start, alone.model.nq);
    // the lamp's base starts at its position
    let f = &s.model.free_joints[s.model.trees[1].free.expect("floating")];
    assert_eq!(&s.q0.as_slice()[f.iq..f.iq + 3], &[4.0, 0.0, 0.5]);
    // 4 m apart: the ant moves as alone
    let mut sim = scene_sim(&s);
    for t in [0.5, 1.0] {
        run_to(&mut sim, t);
        run_to(&mut alone, t);
        let a = link_poses(&alone.model, alone.q());
        let b = link_poses(&s.model, sim.q());
        let w = gap(&b, "ant", &a, &Se3::identity());
        assert!(w < 1e-6, "at t = {t}: the ant's links differ by {w}");
    }
    // the lamp fell onto the ant's floor (its base lower than it started)
    let z = sim.q()[f.iq + 2];
    assert!(z < 0.5, "lamp base at z = {z}");
}

#[test]
fn an_mjcf_world_of_several_trees_and_a_static_geom() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("two.xml"),
        r#"<mujoco model="two">
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <geom name="step" type="box" pos="1 0 0.05" size="0.2 0.2 0.05"/>
    <body name="a" pos="0 0 0.5"><freejoint name="fa"/><geom type="sphere" size="0.1"/></body>
    <body name="b" pos="0 1 0.5"><joint name="hb" type="hinge" axis="1 0 0"/><geom type="capsule" fromto="0 0 0 0 0.3 0" size="0.05"/></body>
  </worldbody>
</mujoco>"#,
    )
    .unwrap();
    let s = scene_in(
        dir.path(),
        r#"{"models": [{"name": "w", "mjcf": "two.xml", "position": [2, 3, 0.5]}]}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // one tree per child of <worldbody>, each named after the model
    assert_eq!(s.model.trees.len(), 2);
    assert!(s.model.trees.iter().all(|t| t.name == "w"));
    assert_eq!((s.model.nq, s.model.nv), (8, 7));
    assert_eq!(s.model.trees[1].q, 7..8);
    // the free body's q: (0, 0, 0.5) placed at (2, 3, 0.5)
    assert_eq!(&s.q0.as_slice()[..7], &[2.0, 3.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    // the hinged body hangs from the pose
    let poses = link_poses(&s.model, &s.q0);
    let b = poses.iter().find(|(n, _)| n == "w/b").expect("w/b").1;
    assert_eq!(b.trans, Vector3::new(2.0, 4.0, 1.0));
    assert_eq!(b.rot, Matrix3::identity());
    // the step stays an obstacle, on the world, placed
    let step = s
        .model
        .collisions
        .iter()
        .find(|c| c.body == 0)
        .expect("the step");
    assert_eq!(step.model, urdyn::model::OBSTACLE);
    assert_eq!(step.placement.trans, Vector3::new(3.0, 3.0, 0.55));
    // the floor is the ground, moved up
    assert_eq!(s.ground.map(|g| g.height), Some(0.5));
    // a side of `exclude` may name the model: all its links
    let s2 = scene_in(
        dir.path(),
        r#"{"models": [{"name": "w", "mjcf": "two.xml"}], "exclude": [["w", "w"]]}"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(s2.exclude.contains(&("w/a".to_string(), "w/b".to_string())));
}

#[test]
fn the_replay_page_of_a_scene_draws_an_mjcf_model_on_the_scenes_bodies() {
    use urdyn::cli::view::Geometry;
    let (alone, world) = mjcf::load_file_with_world(gym().join("ant.xml")).expect("loads");
    let own = urdyn::cli::view::mjcf::geometry(&alone, &world, "ant.xml");
    let lamp = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/lamp.urdf");
    let json = format!(
        r#"{{"models": [{{"name": "l", "urdf": "{}"}},
                       {{"name": "ant", "mjcf": "ant.xml", "position": [1, 2, 0]}}]}}"#,
        lamp.display()
    );
    let s = scene_in(&gym(), &json).unwrap_or_else(|e| panic!("{e}"));
    let g = Geometry::load_scene(&s, &[]).expect("drawn");
    let ant: Vec<_> = g
        .visuals
        .iter()
        .filter(|v| v.link.starts_with("ant/"))
        .collect();
    assert_eq!(ant.len(), own.visuals.len());
    // every drawn ant geom sits on the scene body of its link's frame
    for v in &ant {
        let f = s.model.frames.iter().find(|f| f.name == v.link);
        if let Some(f) = f {
            assert_eq!(v.body, f.body, "{}", v.link);
        }
    }
    let torso = s
        .model
        .frames
        .iter()
        .find(|f| f.name == "ant/torso")
        .unwrap();
    assert!(ant.iter().any(|v| v.body == torso.body && torso.body > 0));
}

#[test]
fn initial_sets_an_mjcf_models_ball_and_free_joints_with_arrays() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("ball.xml"),
        r#"<mujoco model="ball">
  <worldbody>
    <body name="a" pos="0 0 0.5"><freejoint name="fa"/><geom type="sphere" size="0.1"/>
      <body name="b" pos="0 0 -0.2"><joint name="sb" type="ball"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.05"/></body>
    </body>
  </worldbody>
</mujoco>"#,
    )
    .unwrap();
    // the model turned 90° about z and moved to (2, 3, 0.5); its free
    // joint given in the file's frame, its ball joint turned 60° about x
    let (s60, c60) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let json = format!(
        r#"{{"models": [{{"name": "w", "mjcf": "ball.xml", "position": [2, 3, 0.5],
        "orientation_xyzw": [0, 0, {h}, {h}],
        "initial": {{"q": {{"fa": [1, 0, 0.25, 0, 0, 0, 1], "sb": [{s60}, 0, 0, {c60}]}},
                    "v": {{"fa": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], "sb": [1, 2, 3]}},
                    "tau": {{"sb": [0, 0, 0.5]}}}}}}]}}"#,
        h = std::f64::consts::FRAC_1_SQRT_2
    );
    let s = scene_in(dir.path(), &json).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.model.nq, s.model.nv), (11, 9));
    let q = s.q0.as_slice();
    // (1, 0, 0.25) turned 90° about z is (0, 1, 0.25), moved by the position
    let want = [2.0, 4.0, 0.75];
    for k in 0..3 {
        assert!((q[k] - want[k]).abs() < 1e-12, "{q:?}");
    }
    // the orientation is the pose's
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for (k, w) in [0.0, 0.0, h, h].iter().enumerate() {
        assert!((q[3 + k] - w).abs() < 1e-12, "{q:?}");
    }
    // the ball joint's quaternion as given (a joint's own frame)
    for (k, w) in [s60, 0.0, 0.0, c60].iter().enumerate() {
        assert!((q[7 + k] - w).abs() < 1e-15, "{q:?}");
    }
    // child-frame velocities and torques as given
    assert_eq!(
        s.v0.as_slice(),
        &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.0, 2.0, 3.0]
    );
    assert_eq!(
        s.tau0.as_slice(),
        &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5]
    );
    // a quaternion within 1e-3 of unit norm is normalised
    let near = json.replace(&format!("[{s60}, 0, 0, {c60}]"), "[0, 0, 0, 1.0005]");
    let s = scene_in(dir.path(), &near).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(&s.q0.as_slice()[7..11], &[0.0, 0.0, 0.0, 1.0]);
    // errors name the key and what the joint takes
    for (text, key, says) in [
        (
            json.replace(&format!("[{s60}, 0, 0, {c60}]"), "[0, 0, 0, 2]"),
            "models[0].initial.q.sb",
            "unit quaternion",
        ),
        (
            json.replace(&format!("[{s60}, 0, 0, {c60}]"), "0.5"),
            "models[0].initial.q.sb",
            "a spherical joint takes an array of 4 numbers [qx, qy, qz, qw], found a number",
        ),
        (
            json.replace("\"sb\": [1, 2, 3]", "\"sb\": [1, 2]"),
            "models[0].initial.v.sb",
            "an array of 3 numbers [wx, wy, wz], found an array of 2",
        ),
    ] {
        let e = scene_in(dir.path(), &text)
            .expect_err("refused")
            .to_string();
        assert!(e.contains(key) && e.contains(says), "{e}");
    }
}
