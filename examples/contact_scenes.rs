//! Steps per second of the pair-contact scenes of tests/contact_pairs.rs
//! (dt = 1 ms, semi-implicit Euler, the defaults): a ball rolling down a static
//! ramp, the fold arm falling limp with self-collision, a stool dropped on a
//! box step (with the ground), a stool on a 10° height field, a ball in a
//! non-convex bowl mesh. Prints a markdown table.
//!
//! `cargo run --release --features tools --example contact_scenes`

use nalgebra::{DVector, Matrix3, Rotation3, Vector3};
use std::time::Instant;
use urdyn::model::{CollisionGeom, Model, Shape, OBSTACLE};
use urdyn::sim::{SimOptions, Simulation};
use urdyn::spatial::Se3;

fn load(name: &str, floating_base: bool) -> Model {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::load_file(
        root.join("tests/urdf").join(name),
        urdyn::LoadOptions { floating_base },
    )
    .expect("a test URDF")
}

fn obstacle(model: &mut Model, name: &str, shape: Shape, pose: Se3<f64>) {
    model.collisions.push(CollisionGeom {
        link: name.to_string(),
        body: 0,
        placement: pose,
        shape,
        trimesh: true,
        friction: 1.0,
        model: OBSTACLE,
    });
}

fn place(sim: &mut Simulation, p: Vector3<f64>) {
    let mut q = sim.q().clone();
    q[0] = p.x;
    q[1] = p.y;
    q[2] = p.z;
    let v = DVector::zeros(sim.v().len());
    sim.set_state(&q, &v).expect("a state");
}

fn bowl(path: &std::path::Path, r: f64, rings: usize, seg: usize) {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "v 0 0 {}", -r);
    for k in 1..=rings {
        let polar = std::f64::consts::PI - k as f64 * std::f64::consts::FRAC_PI_2 / rings as f64;
        for j in 0..seg {
            let az = std::f64::consts::TAU * j as f64 / seg as f64;
            let _ = writeln!(
                s,
                "v {} {} {}",
                r * polar.sin() * az.cos(),
                r * polar.sin() * az.sin(),
                r * polar.cos()
            );
        }
    }
    let v = |k: usize, j: usize| 2 + (k - 1) * seg + (j % seg);
    for j in 0..seg {
        let _ = writeln!(s, "f 1 {} {}", v(1, j), v(1, j + 1));
    }
    for k in 1..rings {
        for j in 0..seg {
            let _ = writeln!(s, "f {} {} {}", v(k, j), v(k + 1, j), v(k + 1, j + 1));
            let _ = writeln!(s, "f {} {} {}", v(k, j), v(k + 1, j + 1), v(k, j + 1));
        }
    }
    std::fs::write(path, s).expect("a temporary file");
}

fn main() {
    let no_ground = SimOptions {
        ground: None,
        ..Default::default()
    };
    let mut scenes: Vec<(&str, Simulation)> = Vec::new();
    // a ball on a 20° ramp
    {
        let theta = 20f64.to_radians();
        let mut m = load("ball.urdf", true);
        let n = Vector3::new(theta.sin(), 0.0, theta.cos());
        let rot: Matrix3<f64> = Rotation3::from_axis_angle(&Vector3::y_axis(), theta).into_inner();
        obstacle(
            &mut m,
            "ramp",
            Shape::Box {
                size: [60.0, 1.0, 0.1],
            },
            Se3::new(rot, -n * 0.05),
        );
        let mut sim = Simulation::new(m, no_ground.clone()).expect("ramp");
        place(&mut sim, n * 0.1);
        scenes.push(("ball rolling down a ramp", sim));
    }
    // the fold arm with self-collision
    {
        let mut m = load("fold_arm.urdf", false);
        m.collision_filter.self_collision = vec![true];
        scenes.push((
            "arm falling limp, self-collision",
            Simulation::new(m, no_ground.clone()).expect("arm"),
        ));
    }
    // a stool on a box step, with the ground
    {
        let mut m = load("stool.urdf", true);
        obstacle(
            &mut m,
            "step",
            Shape::Box {
                size: [1.0, 1.0, 0.1],
            },
            Se3::new(Matrix3::identity(), Vector3::new(0.0, 0.0, 0.05)),
        );
        let mut sim = Simulation::new(m, SimOptions::default()).expect("step");
        place(&mut sim, Vector3::new(0.0, 0.0, 0.47));
        scenes.push(("stool on a box step", sim));
    }
    // a stool on a 10° height field
    {
        let theta = 10f64.to_radians();
        let mut m = load("stool.urdf", true);
        let heights = (0..9)
            .map(|_| {
                (0..9)
                    .map(|j| (-2.0 + 0.5 * j as f64) * theta.tan())
                    .collect()
            })
            .collect();
        obstacle(
            &mut m,
            "hill",
            Shape::HeightField {
                heights,
                size: [4.0, 4.0],
            },
            Se3::identity(),
        );
        let mut sim = Simulation::new(m, no_ground.clone()).expect("hill");
        place(&mut sim, Vector3::new(0.0, 0.0, 0.18 * theta.tan() + 0.33));
        scenes.push(("stool on a 10° height field", sim));
    }
    // a ball in a bowl mesh (768 triangles)
    let dir = std::env::temp_dir().join(format!("urdyn_bowl_{}.obj", std::process::id()));
    bowl(&dir, 0.5, 12, 32);
    {
        let mut m = load("ball.urdf", true);
        obstacle(
            &mut m,
            "bowl",
            Shape::Mesh {
                filename: dir.display().to_string(),
                scale: [1.0; 3],
            },
            Se3::identity(),
        );
        let mut sim = Simulation::new(m, no_ground).expect("bowl");
        place(&mut sim, Vector3::new(0.02, 0.0, -0.3));
        scenes.push(("ball in a non-convex bowl", sim));
    }
    let _ = std::fs::remove_file(&dir);
    println!("| scene | steps/s | contacts (last step) | deepest penetration (m) |");
    println!("| --- | --- | --- | --- |");
    for (name, mut sim) in scenes {
        let t_end = 3.0;
        let mut deepest: f64 = 0.0;
        let start = Instant::now();
        while sim.time() < t_end - 1e-9 {
            if sim.step().is_err() {
                break;
            }
            deepest = deepest.max(sim.penetration());
        }
        let wall = start.elapsed().as_secs_f64();
        println!(
            "| {name} | {:.0} | {} | {:.2e} |",
            sim.steps as f64 / wall,
            sim.contact_points().len(),
            deepest
        );
    }
}
