//! Scenes (shared/spec/scene.md): several URDF models in one `Model` — names
//! `MODEL/NAME`, q and v each model in file order — and every algorithm on the
//! forest equal to each model alone.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use urdyn::dynamics_f64::{self as dynamics, Reference};
use urdyn::model::configuration::random_configuration;
use urdyn::scene::Scene;
use urdyn::sim::{column_names, SimOptions, Simulation};
use urdyn::spatial::Se3;
use urdyn::{Data, LoadOptions, Model};

fn asset(p: &str) -> String {
    format!("{}/assets/{p}", env!("CARGO_MANIFEST_DIR"))
}

fn scene(json: &str) -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    Scene::from_json(json, "test.json", &dir, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// ur5 welded at a turned, tilted pose; the lamp floating; panda welded at a shift.
const THREE: &str = r#"{
  "models": [
    {"name": "arm", "urdf": "robots/ur5.urdf", "base": "fixed", "position": [0.3, -0.2, 0.1],
     "orientation_xyzw": [0.1, 0.2, 0.3, 0.9273618495495703]},
    {"name": "lamp", "urdf": "lamp.urdf", "base": "floating", "position": [1, 2, 0.5],
     "initial": {"q": {"elbow": 0.3}, "v": {"elbow": -0.5},
                 "base": {"linear_velocity": [0.1, 0, 0], "angular_velocity": [0, 0, 2]}}},
    {"name": "panda", "urdf": "robots/panda.urdf", "base": "fixed", "position": [-1, 0, 0]}
  ]
}"#;

fn quat_rot(x: f64, y: f64, z: f64, w: f64) -> Matrix3<f64> {
    let n = (x * x + y * y + z * z + w * w).sqrt();
    urdyn::spatial::quat_to_matrix(x / n, y / n, z / n, w / n)
}

#[test]
fn names_and_layout_follow_the_file() {
    let s = scene(THREE);
    let m = &s.model;
    let ur5 = urdyn::load_file(asset("robots/ur5.urdf"), LoadOptions::default()).unwrap();
    let lamp = urdyn::load_file(
        asset("lamp.urdf"),
        LoadOptions {
            floating_base: true,
        },
    )
    .unwrap();
    let panda = urdyn::load_file(asset("robots/panda.urdf"), LoadOptions::default()).unwrap();
    assert_eq!(m.nq, ur5.nq + lamp.nq + panda.nq);
    assert_eq!(m.nv, ur5.nv + lamp.nv + panda.nv);
    assert_eq!(m.trees.len(), 3);
    assert_eq!(m.free_joints.len(), 1);
    // the lamp's free joint starts after the arm's joints
    assert_eq!(m.free_joints[0].iq, ur5.nq);
    assert_eq!(m.free_joints[0].iv, ur5.nv);
    assert!(!m.floating_base, "body 1 is the arm's first joint");
    // names: MODEL/NAME, each model's in its own (Pinocchio's) order
    let want: Vec<String> = ur5
        .dofs
        .iter()
        .map(|d| format!("arm/{}", d.name))
        .chain(lamp.dofs.iter().map(|d| format!("lamp/{}", d.name)))
        .chain(panda.dofs.iter().map(|d| format!("panda/{}", d.name)))
        .collect();
    assert_eq!(m.dof_names(), want);
    let links: Vec<String> = ur5
        .frames
        .iter()
        .map(|f| format!("arm/{}", f.name))
        .chain(lamp.frames.iter().map(|f| format!("lamp/{}", f.name)))
        .chain(panda.frames.iter().map(|f| format!("panda/{}", f.name)))
        .collect();
    assert_eq!(m.link_names(), links);
    // q and v indices by name
    assert_eq!(
        m.q_index("lamp/elbow").unwrap(),
        ur5.nq + 7 + lamp.q_index("elbow").unwrap() - 7
    );
    assert_eq!(
        m.v_index("panda/panda_joint1").unwrap(),
        ur5.nv + lamp.nv + panda.v_index("panda_joint1").unwrap()
    );
    // the CSV's columns (scene.md "Names and output")
    let (qn, vn) = column_names(m);
    assert_eq!(qn.len(), m.nq);
    assert_eq!(qn[ur5.nq], "q:lamp/base_x");
    assert_eq!(qn[ur5.nq + 6], "q:lamp/base_qw");
    assert_eq!(vn[ur5.nv], "v:lamp/base_vx");
    assert_eq!(vn[ur5.nv + 5], "v:lamp/base_wz");
    assert_eq!(qn[0], format!("q:arm/{}", ur5.dofs[0].name));
    // the start: the lamp's pose and initial state, everything else neutral
    let (iq, iv) = (ur5.nq, ur5.nv);
    assert_eq!(
        s.q0.rows(iq, 7).as_slice(),
        &[1.0, 2.0, 0.5, 0.0, 0.0, 0.0, 1.0]
    );
    assert_eq!(s.q0[m.q_index("lamp/elbow").unwrap()], 0.3);
    assert_eq!(s.v0[m.v_index("lamp/elbow").unwrap()], -0.5);
    assert_eq!(s.v0.rows(iv, 6).as_slice(), &[0.1, 0.0, 0.0, 0.0, 0.0, 2.0]);
    assert_eq!(s.q0.rows(0, ur5.nq).amax(), 0.0);
    // the arm's links welded at its pose: its root frame is the pose
    let mut data = Data::new(m);
    dynamics::forward_kinematics(m, &mut data, &s.q0).unwrap();
    let root = m.frame_id(&format!("arm/{}", ur5.frames[0].name)).unwrap();
    let x = dynamics::frame_placement(m, &data, root).unwrap();
    let r = quat_rot(0.1, 0.2, 0.3, 0.9273618495495703);
    assert!((x.rot - r).amax() < 1e-15 && (x.trans - Vector3::new(0.3, -0.2, 0.1)).amax() < 1e-15);
}

/// The forest's q (or v) split into the three models' vectors.
fn split(m: &Model, x: &DVector<f64>, q: bool) -> Vec<DVector<f64>> {
    m.trees
        .iter()
        .map(|t| {
            let r = if q { t.q.clone() } else { t.v.clone() };
            DVector::from_column_slice(&x.as_slice()[r])
        })
        .collect()
}

#[test]
fn every_algorithm_on_the_forest_equals_each_model_alone() {
    // with panda (mimic fingers: CRBA and the dense factor), and with solo12
    // floating in its place (no mimic: ABA too)
    every_algorithm_on(THREE, ("robots/panda.urdf", false));
    let solo = THREE.replace(
        r#""urdf": "robots/panda.urdf", "base": "fixed""#,
        r#""urdf": "robots/solo12.urdf", "base": "floating""#,
    );
    every_algorithm_on(&solo, ("robots/solo12.urdf", true));
}

fn every_algorithm_on(json: &str, third: (&str, bool)) {
    let s = scene(json);
    let m = &s.model;
    let r = quat_rot(0.1, 0.2, 0.3, 0.9273618495495703);
    let t = Vector3::new(0.3, -0.2, 0.1);
    let g = m.gravity;
    // each model alone, gravity in its root frame (the arm's root is turned by R)
    let mut alone = vec![
        urdyn::load_file(asset("robots/ur5.urdf"), LoadOptions::default()).unwrap(),
        urdyn::load_file(
            asset("lamp.urdf"),
            LoadOptions {
                floating_base: true,
            },
        )
        .unwrap(),
        urdyn::load_file(
            asset(third.0),
            LoadOptions {
                floating_base: third.1,
            },
        )
        .unwrap(),
    ];
    assert_eq!(m.has_mimic, !third.1);
    alone[0].gravity = r.transpose() * g;
    let mut data = Data::new(m);
    let mut datas: Vec<Data> = alone.iter().map(Data::new).collect();
    for seed in 0..5u64 {
        let q = random_configuration(m, seed);
        let v = DVector::from_fn(m.nv, |k, _| {
            ((k * 7 + seed as usize) % 11) as f64 * 0.1 - 0.5
        });
        let a = DVector::from_fn(m.nv, |k, _| ((k * 5 + 3) % 13) as f64 * 0.2 - 1.2);
        let (qs, vs, as_) = (split(m, &q, true), split(m, &v, false), split(m, &a, false));
        // inverse dynamics: τ per model
        let tau = dynamics::rnea(m, &mut data, &q, &v, &a, None)
            .unwrap()
            .clone();
        let taus = split(m, &tau, false);
        // H block-diagonal, each block the model's own
        let h = dynamics::mass_matrix(m, &mut data, &q).unwrap().clone();
        let h = DMatrix::from_fn(
            m.nv,
            m.nv,
            |i, j| if i <= j { h[(i, j)] } else { h[(j, i)] },
        );
        let fd = dynamics::forward_dynamics(m, &mut data, &q, &v, &tau, None)
            .unwrap()
            .clone();
        if !m.has_mimic {
            let qdd_aba = dynamics::aba(m, &mut data, &q, &v, &tau, None)
                .unwrap()
                .clone();
            assert!((&qdd_aba - &a).amax() < 1e-7, "aba round trip");
        }
        assert!((&fd - &a).amax() < 1e-7, "forward dynamics round trip");
        let ke = dynamics::kinetic_energy(m, &mut data, &q, &v).unwrap();
        dynamics::forward_kinematics(m, &mut data, &q).unwrap();
        let pe = dynamics::potential_energy(m, &data);
        let (mut ke_sum, mut pe_sum) = (0.0, 0.0);
        for (k, (am, ad)) in alone.iter().zip(datas.iter_mut()).enumerate() {
            let tr = &m.trees[k];
            let ta = dynamics::rnea(am, ad, &qs[k], &vs[k], &as_[k], None).unwrap();
            assert!(
                (ta - &taus[k]).amax() < 1e-9,
                "tau of model {k}: {}",
                (ta - &taus[k]).amax()
            );
            let ha = dynamics::mass_matrix(am, ad, &qs[k]).unwrap().clone();
            let ha = DMatrix::from_fn(
                am.nv,
                am.nv,
                |i, j| if i <= j { ha[(i, j)] } else { ha[(j, i)] },
            );
            for i in 0..m.nv {
                for j in tr.v.clone() {
                    let want = if tr.v.contains(&i) {
                        ha[(i - tr.v.start, j - tr.v.start)]
                    } else {
                        0.0
                    };
                    assert!((h[(i, j)] - want).abs() < 1e-10, "H[{i}, {j}] model {k}");
                }
            }
            let qdd = dynamics::forward_dynamics(am, ad, &qs[k], &vs[k], &taus[k], None)
                .unwrap()
                .clone();
            let f = DVector::from_column_slice(&fd.as_slice()[tr.v.clone()]);
            assert!((qdd - f).amax() < 1e-7, "qdd of model {k}");
            ke_sum += dynamics::kinetic_energy(am, ad, &qs[k], &vs[k]).unwrap();
            dynamics::forward_kinematics(am, ad, &qs[k]).unwrap();
            pe_sum += dynamics::potential_energy(am, ad);
            // a link's local Jacobian: the model's own columns, zero elsewhere
            let link = am.frames.last().unwrap().name.clone();
            let (fa, ff) = (
                am.frame_id(&link).unwrap(),
                m.frame_id(&format!("{}/{link}", tr.name)).unwrap(),
            );
            let mut ja = DMatrix::zeros(6, am.nv);
            let mut jf = DMatrix::zeros(6, m.nv);
            dynamics::frame_jacobian(am, ad, fa, Reference::Local, &mut ja).unwrap();
            dynamics::frame_jacobian(m, &data, ff, Reference::Local, &mut jf).unwrap();
            for c in 0..m.nv {
                for row in 0..6 {
                    let want = if tr.v.contains(&c) {
                        ja[(row, c - tr.v.start)]
                    } else {
                        0.0
                    };
                    assert!((jf[(row, c)] - want).abs() < 1e-12, "J of {link}");
                }
            }
        }
        assert!((ke - ke_sum).abs() < 1e-9 * ke.abs().max(1.0));
        // the arm's potential is offset by its mass at the pose's translation
        let m_arm: f64 = alone[0].total_mass();
        let want_pe = pe_sum - m_arm * g.dot(&t);
        assert!(
            (pe - want_pe).abs() < 1e-9 * pe.abs().max(1.0),
            "{pe} {want_pe}"
        );
    }
}

#[test]
fn a_forest_steps_as_its_models_alone() {
    // two floating lamps and a fixed ur5 in free fall (no ground): each model
    // steps as it would alone (the arm falling limp would fold onto itself:
    // its self-collision, which a lone URDF does not have, is off)
    let s = scene(
        r#"{"models": [
        {"name": "a", "urdf": "lamp.urdf", "base": "floating", "position": [-3, 0, 1],
         "initial": {"v": {"elbow": 1.0}, "base": {"angular_velocity": [0.3, -0.2, 1]}}},
        {"name": "arm", "urdf": "robots/ur5.urdf", "base": "fixed", "self_collision": false},
        {"name": "b", "urdf": "lamp.urdf", "base": "floating", "position": [3, 0, 1],
         "initial": {"q": {"shoulder": 0.4}}}]}"#,
    );
    let opts = || SimOptions {
        ground: None,
        integrator: Some(urdyn::sim::Integrator::SemiImplicitEuler),
        ..SimOptions::default()
    };
    let mut sim = Simulation::new(s.model.clone(), opts()).unwrap();
    sim.set_state(&s.q0, &s.v0).unwrap();
    let mut alone: Vec<Simulation> = s
        .model
        .trees
        .iter()
        .map(|t| {
            let file = if t.name == "arm" {
                "robots/ur5.urdf"
            } else {
                "lamp.urdf"
            };
            let m = urdyn::load_file(
                asset(file),
                LoadOptions {
                    floating_base: t.free.is_some(),
                },
            )
            .unwrap();
            let mut sim = Simulation::new(m, opts()).unwrap();
            let q = DVector::from_column_slice(&s.q0.as_slice()[t.q.clone()]);
            let v = DVector::from_column_slice(&s.v0.as_slice()[t.v.clone()]);
            sim.set_state(&q, &v).unwrap();
            sim
        })
        .collect();
    for _ in 0..300 {
        sim.step().unwrap();
        for a in alone.iter_mut() {
            a.step().unwrap();
        }
    }
    for (t, a) in s.model.trees.iter().zip(&alone) {
        let q = &sim.q().as_slice()[t.q.clone()];
        let d = q
            .iter()
            .zip(a.q().iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-9, "model {}: q differs by {d}", t.name);
    }
    // the floating lamps fell freely: 1 − ½ g t² below their start (0.3 s)
    let z = sim.q()[s.model.free_joints[1].iq + 2];
    assert!(z < 1.0 - 0.4 && z > 1.0 - 0.5, "{z}");
}

#[test]
fn a_fixed_model_is_welded_at_its_pose() {
    let s =
        scene(r#"{"models": [{"name": "table", "urdf": "table.urdf", "position": [0.6, 0, 0]}]}"#);
    let m = &s.model;
    assert_eq!((m.nq, m.nv, m.nbodies), (0, 0, 1));
    // the table's top face at 0.75 m: its collision box on the world body
    let top = m.collisions.iter().find(|c| c.link == "table/top").unwrap();
    assert_eq!(top.body, 0);
    assert!((top.placement.trans - Vector3::new(0.6, 0.0, 0.73)).amax() < 1e-15);
    let leg = m
        .collisions
        .iter()
        .find(|c| c.link == "table/leg_3")
        .unwrap();
    assert!((leg.placement.trans - Vector3::new(0.15, -0.25, 0.355)).amax() < 1e-15);
    let _ = Se3::<f64>::identity();
}

#[test]
fn obstacles_frictions_and_the_collision_filter() {
    let s = scene(
        r#"{"ground": {"friction": 0.5},
        "models": [
          {"name": "table", "urdf": "table.urdf", "position": [0.6, 0, 0], "friction": 0.3},
          {"name": "lamp", "urdf": "lamp.urdf", "base": "floating", "self_collision": false}],
        "obstacles": [
          {"name": "step", "box": [0.4, 1.0, 0.1], "position": [1.5, 0, 0.05], "friction": 0.7},
          {"name": "hills", "heightfield": {"heights": [[0.0, 0.1], [0.05, 0.2]], "size": [4.0, 4.0]},
           "position": [3, 0, 0]}],
        "exclude": [["lamp/base", "table/leg_1"], ["lamp", "step"]]}"#,
    );
    let m = &s.model;
    assert_eq!(s.ground.unwrap().friction, 0.5);
    let geom = |l: &str| m.collisions.iter().find(|c| c.link == l).unwrap();
    assert_eq!(
        (geom("table/top").model, geom("table/top").friction),
        (0, 0.3)
    );
    assert_eq!(
        (geom("lamp/base").model, geom("lamp/base").friction),
        (1, 1.0)
    );
    let step = geom("step");
    assert_eq!(
        (step.model, step.body, step.friction),
        (urdyn::model::OBSTACLE, 0, 0.7)
    );
    assert!(matches!(step.shape, urdyn::model::Shape::Box { size } if size == [0.4, 1.0, 0.1]));
    assert!((step.placement.trans - Vector3::new(1.5, 0.0, 0.05)).amax() == 0.0);
    assert!(
        matches!(&geom("hills").shape, urdyn::model::Shape::HeightField { heights, size }
        if heights.len() == 2 && *size == [4.0, 4.0])
    );
    let f = &m.collision_filter;
    assert_eq!(f.self_collision, vec![true, false]);
    assert!(f.is_excluded("table/leg_1", "lamp/base"));
    // "lamp" stands for every link of the lamp
    for l in [
        "lamp/base",
        "lamp/lower_arm",
        "lamp/upper_arm",
        "lamp/shade",
    ] {
        assert!(f.is_excluded("step", l), "{l}");
    }
    assert!(!f.is_excluded("table/top", "lamp/shade"));
}
