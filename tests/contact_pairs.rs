//! Contact between two shapes: static obstacles (boxes, a non-convex mesh, a
//! height field) and self-collision, against closed forms and independent
//! distance queries (scene.md, docs/theory.md §"Contact pairs").

use nalgebra::{DVector, Matrix3, Rotation3, Vector3};
use urdyn::model::{CollisionGeom, Model, Shape, OBSTACLE};
use urdyn::sim::{SimOptions, Simulation};
use urdyn::spatial::Se3;

fn load(name: &str, floating_base: bool) -> Model {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::load_file(
        root.join("tests/urdf").join(name),
        urdyn::LoadOptions { floating_base },
    )
    .unwrap()
}

/// A static obstacle `shape` at `pose` (world frame) with friction `mu`.
fn obstacle(model: &mut Model, name: &str, shape: Shape, pose: Se3<f64>, mu: f64) {
    model.collisions.push(CollisionGeom {
        link: name.to_string(),
        body: 0,
        placement: pose,
        shape,
        trimesh: true,
        friction: mu,
        model: OBSTACLE,
    });
}

fn set_friction(model: &mut Model, mu: f64) {
    for g in model.collisions.iter_mut() {
        g.friction = mu;
    }
}

/// A floating model's state with the base at `p` (identity orientation, at rest).
fn at(sim: &mut Simulation, p: Vector3<f64>) {
    let mut q = sim.q().clone();
    q[0] = p.x;
    q[1] = p.y;
    q[2] = p.z;
    let v = DVector::zeros(sim.v().len());
    sim.set_state(&q, &v).unwrap();
}

fn base(sim: &Simulation) -> Vector3<f64> {
    Vector3::new(sim.q()[0], sim.q()[1], sim.q()[2])
}

/// Steps `t` seconds; returns the largest rise of the energy above its start
/// and the deepest penetration seen.
fn run(sim: &mut Simulation, t: f64) -> (f64, f64) {
    let e0 = sim.energy();
    let (mut rise, mut depth) = (f64::NEG_INFINITY, 0.0f64);
    let t_end = sim.time() + t;
    while sim.time() < t_end - 1e-9 {
        sim.step().unwrap();
        rise = rise.max(sim.energy() - e0);
        depth = depth.max(sim.penetration());
    }
    (rise, depth)
}

/// The ramp of slope θ: a long box whose top face has the normal
/// (sin θ, 0, cos θ) and passes through the origin; downhill is
/// (cos θ, 0, −sin θ).
fn ramp(theta: f64) -> (Shape, Se3<f64>, Vector3<f64>, Vector3<f64>) {
    let n = Vector3::new(theta.sin(), 0.0, theta.cos());
    let rot: Matrix3<f64> = Rotation3::from_axis_angle(&Vector3::y_axis(), theta).into_inner();
    let pose = Se3::new(rot, -n * 0.05);
    (
        Shape::Box {
            size: [6.0, 1.0, 0.1],
        },
        pose,
        n,
        Vector3::new(theta.cos(), 0.0, -theta.sin()),
    )
}

/// The acceleration down a ramp of slope θ of the ball (radius 0.1 m) with
/// the friction `mu` on both sides, from the distance covered in 0.6 s from
/// rest (s = ½ a t²), with the run's energy rise and deepest penetration.
fn ramp_acceleration(theta: f64, mu: f64) -> (f64, f64, f64) {
    let mut model = load("ball.urdf", true);
    set_friction(&mut model, mu);
    let (shape, pose, n, down) = ramp(theta);
    obstacle(&mut model, "ramp", shape, pose, mu);
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let start = n * 0.1;
    at(&mut sim, start);
    let t = 0.6;
    let (rise, depth) = run(&mut sim, t);
    let s = (base(&sim) - start).dot(&down);
    (2.0 * s / (t * t), rise, depth)
}

#[test]
fn a_ball_rolls_down_a_ramp_at_five_sevenths_g_sin_theta() {
    let theta = 20f64.to_radians();
    let g = 9.81;
    let (a, rise, depth) = ramp_acceleration(theta, 1.0);
    let want = 5.0 / 7.0 * g * theta.sin();
    assert!(
        (a - want).abs() < 0.02 * want,
        "rolling: a = {a}, 5/7 g sin θ = {want}"
    );
    assert!(rise < 1e-3, "the energy rose by {rise} J");
    assert!(depth < 1e-3, "penetration {depth} m");
}

#[test]
fn a_ball_slides_down_a_frictionless_ramp_at_g_sin_theta() {
    let theta = 20f64.to_radians();
    let g = 9.81;
    let (a, rise, depth) = ramp_acceleration(theta, 0.0);
    let want = g * theta.sin();
    assert!(
        (a - want).abs() < 0.02 * want,
        "sliding: a = {a}, g sin θ = {want}"
    );
    assert!(rise < 1e-3, "the energy rose by {rise} J");
    assert!(depth < 1e-3, "penetration {depth} m");
}

#[test]
fn contact_forces_are_reported_on_both_sides() {
    // the ball resting on a flat box obstacle: m g up on the ball, down on the box
    let mut model = load("ball.urdf", true);
    obstacle(
        &mut model,
        "table",
        Shape::Box {
            size: [1.0, 1.0, 0.1],
        },
        Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, -0.05)),
        1.0,
    );
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    at(&mut sim, Vector3::new(0.0, 0.0, 0.1));
    run(&mut sim, 0.5);
    let (mut on_ball, mut on_table) = (Vector3::zeros(), Vector3::zeros());
    for (link, f) in sim.link_contact_forces() {
        match link {
            "ball" => on_ball += f.force,
            "table" => on_table += f.force,
            other => panic!("a force on {other}"),
        }
    }
    let mg = 9.81;
    assert!(
        (on_ball - Vector3::new(0.0, 0.0, mg)).norm() < 1e-6 * mg,
        "{on_ball}"
    );
    assert!((on_table + on_ball).norm() < 1e-12, "{on_table}");
    assert!((base(&sim).z - 0.1).abs() < 1e-3, "{}", base(&sim));
}

/// A bowl: the lower half of a sphere of radius `r` centred at the origin,
/// triangulated in `rings` latitude rings of `seg` segments, written as OBJ.
fn bowl_obj(path: &std::path::Path, r: f64, rings: usize, seg: usize) {
    use std::fmt::Write;
    let mut s = String::new();
    // the pole, then ring k at polar angle π − k·(π/2)/rings
    writeln!(s, "v 0 0 {}", -r).unwrap();
    for k in 1..=rings {
        let polar = std::f64::consts::PI - k as f64 * std::f64::consts::FRAC_PI_2 / rings as f64;
        for j in 0..seg {
            let az = std::f64::consts::TAU * j as f64 / seg as f64;
            let (x, y, z) = (
                r * polar.sin() * az.cos(),
                r * polar.sin() * az.sin(),
                r * polar.cos(),
            );
            writeln!(s, "v {x} {y} {z}").unwrap();
        }
    }
    let v = |k: usize, j: usize| 2 + (k - 1) * seg + (j % seg);
    for j in 0..seg {
        writeln!(s, "f 1 {} {}", v(1, j), v(1, j + 1)).unwrap();
    }
    for k in 1..rings {
        for j in 0..seg {
            writeln!(s, "f {} {} {}", v(k, j), v(k + 1, j), v(k + 1, j + 1)).unwrap();
            writeln!(s, "f {} {} {}", v(k, j), v(k + 1, j + 1), v(k, j + 1)).unwrap();
        }
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn a_ball_in_a_non_convex_bowl_ends_at_its_bottom() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("bowl.obj");
    let r_bowl = 0.5;
    bowl_obj(&obj, r_bowl, 12, 32);
    let mut model = load("ball.urdf", true);
    obstacle(
        &mut model,
        "bowl",
        Shape::Mesh {
            filename: obj.display().to_string(),
            scale: [1.0; 3],
        },
        Se3::identity(),
        1.0,
    );
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    // dropped 10 cm above the bottom, 2 cm off centre, inside the bowl (the
    // bowl's convex hull would hold it at the rim, z = 0)
    at(&mut sim, Vector3::new(0.02, 0.0, -r_bowl + 0.1 + 0.1));
    let (rise, depth) = run(&mut sim, 3.0);
    let p = base(&sim);
    // at the bottom: the centre r_bowl − r from the bowl's centre (the
    // facets' chords lie within 1 − cos(7.5°) · r_bowl of the sphere)
    let lowest = -(r_bowl - 0.1);
    assert!(p.z < lowest + 5e-3 && p.z > lowest - 1e-2, "{p}");
    assert!(p.x.abs() < 0.03 && p.y.abs() < 0.03, "{p}");
    assert!(depth < 1e-3, "penetration {depth} m");
    assert!(rise < 1e-3, "the energy rose by {rise} J");
}

/// A height field of slope θ along x over 4 m × 4 m.
fn slope(theta: f64) -> Shape {
    let (rows, cols) = (9, 9);
    let size = [4.0, 4.0];
    let heights = (0..rows)
        .map(|_| {
            (0..cols)
                .map(|j| (-2.0 + 4.0 * j as f64 / (cols - 1) as f64) * theta.tan())
                .collect()
        })
        .collect();
    Shape::HeightField { heights, size }
}

#[test]
fn a_stool_on_a_ten_degree_height_field_slope_stays_put() {
    let theta = 10f64.to_radians();
    let mut model = load("stool.urdf", true);
    obstacle(&mut model, "hill", slope(theta), Se3::identity(), 1.0);
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    // the feet 1 cm above the slope (the uphill pair at x = +0.18 highest)
    let z = 0.18 * theta.tan() + 0.32 + 0.01;
    at(&mut sim, Vector3::new(0.0, 0.0, z));
    let (rise, depth) = run(&mut sim, 1.0);
    let p1 = base(&sim);
    let (rise2, depth2) = run(&mut sim, 1.0);
    let p2 = base(&sim);
    assert!((p2 - p1).norm() < 1e-3, "it moved from {p1} to {p2}");
    assert!(sim.v().norm() < 1e-2, "v = {}", sim.v());
    assert!(depth.max(depth2) < 1e-3, "penetration");
    assert!(rise.max(rise2) < 1e-3, "the energy rose");
    // on the slope, not through it: the seat stands 0.32 m above the terrain
    // at its feet (tilted by θ: within a centimetre)
    assert!((p2.z - 0.32 - p2.x * theta.tan()).abs() < 0.02, "{p2}");
}

#[test]
fn a_stool_dropped_on_a_box_step_rests_on_it() {
    let mut model = load("stool.urdf", true);
    let h = 0.1;
    obstacle(
        &mut model,
        "step",
        Shape::Box {
            size: [1.0, 1.0, h],
        },
        Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, h / 2.0)),
        1.0,
    );
    // the ground too: the step stands on it
    let mut sim = Simulation::new(model, SimOptions::default()).unwrap();
    at(&mut sim, Vector3::new(0.0, 0.0, h + 0.32 + 0.05));
    let (rise, depth) = run(&mut sim, 1.5);
    let p = base(&sim);
    assert!((p.z - (h + 0.32)).abs() < 1e-3, "{p}");
    assert!(sim.v().norm() < 1e-2, "v = {}", sim.v());
    assert!(depth < 1e-3, "penetration {depth} m");
    assert!(rise < 1e-3, "the energy rose by {rise} J");
    // the step, not the ground, carries it
    let mut on_step = 0.0;
    for (link, f) in sim.link_contact_forces() {
        if link == "step" {
            on_step -= f.force.z;
        }
    }
    assert!((on_step - 2.4 * 9.81).abs() < 1e-3, "{on_step}");
}

#[test]
fn a_start_inside_an_obstacle_is_a_start_violation() {
    // the stool's four foot spheres (r = 2 cm, 0.32 m below the seat) started
    // 3 cm deep in the box step: each an overlap of 3 cm with "step"
    let mut model = load("stool.urdf", true);
    let h = 0.1;
    obstacle(
        &mut model,
        "step",
        Shape::Box {
            size: [1.0, 1.0, h],
        },
        Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, h / 2.0)),
        1.0,
    );
    let mut sim = Simulation::new(model, SimOptions::default()).unwrap();
    at(&mut sim, Vector3::new(0.0, 0.0, h + 0.32 - 0.03));
    let v = sim.start_violations();
    let overlaps: Vec<_> = v
        .iter()
        .filter_map(|v| match v {
            urdyn::sim::Violation::Overlap { a, b, depth } => {
                Some((a.as_str(), b.as_str(), *depth))
            }
            _ => None,
        })
        .collect();
    assert_eq!(overlaps.len(), 4, "{v:?}");
    for (a, b, depth) in overlaps {
        assert!(a.starts_with("leg_") && b == "step", "{a} {b}");
        assert!((depth - 0.03).abs() < 1e-9, "{depth}");
    }
    // and the same stool resting on the step starts clean
    at(&mut sim, Vector3::new(0.0, 0.0, h + 0.32));
    assert!(
        sim.start_violations().is_empty(),
        "{:?}",
        sim.start_violations()
    );
}

/// The overlap of the fold arm's post and lower link at the state of `sim`,
/// computed independently of the pipeline: parry's contact query on the two
/// boxes placed by forward kinematics (positive: penetration depth).
fn post_lower_overlap(sim: &Simulation) -> f64 {
    use parry3d_f64::math::{Pose, Rot3, Vector as PVec};
    use parry3d_f64::shape::Cuboid;
    let model = &sim.model;
    let mut data = urdyn::model::Data::new(model);
    urdyn::dynamics_f64::forward_kinematics(model, &mut data, sim.q()).unwrap();
    let pose = |m: &Se3<f64>| {
        let r = nalgebra::UnitQuaternion::from_matrix(&m.rot);
        Pose::from_parts(
            PVec::new(m.trans.x, m.trans.y, m.trans.z),
            Rot3::from_xyzw(r.i, r.j, r.k, r.w),
        )
    };
    let lower = model.frame_index("lower").unwrap();
    let f = &model.frames[lower];
    let o_m_lower = data.o_m_i[f.body]
        .compose(&f.placement)
        .compose(&Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, -0.2)));
    let post = Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, 0.25));
    let c = parry3d_f64::query::contact(
        &pose(&post),
        &Cuboid::new(PVec::new(0.03, 0.03, 0.25)),
        &pose(&o_m_lower),
        &Cuboid::new(PVec::new(0.02, 0.02, 0.2)),
        0.0,
    )
    .unwrap();
    c.map_or(0.0, |c| (-c.dist).max(0.0))
}

/// The fold arm falling limp for 1.5 s: the deepest post–lower overlap.
fn fold_arm_overlap(self_collision: bool) -> f64 {
    let mut model = load("fold_arm.urdf", false);
    model.collision_filter.self_collision = vec![self_collision];
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    let mut worst = 0.0f64;
    let e0 = sim.energy();
    while sim.time() < 1.5 {
        sim.step().unwrap();
        worst = worst.max(post_lower_overlap(&sim));
        assert!(
            sim.energy() - e0 < 1e-3,
            "the energy rose at t = {}",
            sim.time()
        );
    }
    worst
}

#[test]
fn an_arm_falling_limp_never_penetrates_itself() {
    let with = fold_arm_overlap(true);
    assert!(with < 2e-3, "self-collision on: overlap {with} m");
    // the test can fail: without self-collision the link passes through the post
    let without = fold_arm_overlap(false);
    assert!(without > 2e-2, "self-collision off: overlap {without} m");
}

#[test]
fn self_pairs_overlapping_at_the_start_are_dropped_with_their_depth() {
    // the lower link bent back through the post at the start: dropped
    let mut model = load("fold_arm.urdf", false);
    model.collision_filter.self_collision = vec![true];
    let opts = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut sim = Simulation::new(model, opts).unwrap();
    assert!(sim.dropped_pairs().is_empty(), "{:?}", sim.dropped_pairs());
    // shoulder at 90°: upper points down, the lower link inside the post
    let q = DVector::from_vec(vec![std::f64::consts::FRAC_PI_2, 0.0]);
    let v = DVector::zeros(2);
    sim.set_state(&q, &v).unwrap();
    let d = sim.dropped_pairs();
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!((d[0].a.as_str(), d[0].b.as_str()), ("post", "lower"));
    assert!(d[0].depth > 1e-3, "{}", d[0]);
    assert!(
        d[0].to_string().contains("\"post\" and \"lower\""),
        "{}",
        d[0]
    );
    // no contact between them: it stays inside, no push
    for _ in 0..50 {
        sim.step().unwrap();
    }
    assert!(sim
        .contact_points()
        .iter()
        .all(|p| p.other_geom == usize::MAX));
}
