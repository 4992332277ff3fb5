//! The replay page of an MJCF world (mjcf.md: "the replay page draws every geom
//! with its `rgba` or material"): each geom's colour is its `rgba` (own or from
//! its class), else its material's when the geom's is MuJoCo's default grey
//! (MuJoCo's renderer); shapes and placements are the file's; `simulate --html`
//! and `view` write the page for an MJCF file.

use std::path::Path;
use urdyn::cli::view::{self, VisualShape};

const XML: &str = r#"<mujoco>
  <asset>
    <material name="red" rgba="1 0 0 1"/>
    <material name="blue" rgba="0 0 1 0.5"/>
  </asset>
  <default>
    <default class="c"><geom material="blue"/></default>
    <default class="d"><geom rgba="0 1 0 1"/></default>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1"/>
    <geom name="wall" type="plane" size="2 3 1" pos="1 0 1" zaxis="1 0 0"/>
    <body name="b" pos="0 0 1">
      <freejoint/>
      <geom name="a" size=".1" material="red"/>
      <geom name="own" size=".1" material="red" rgba="0.2 0.3 0.4 1" pos="0.3 0 0"/>
      <geom name="cls" class="c" type="ellipsoid" size=".1 .2 .3" pos="0 0.3 0"/>
      <geom name="dcls" class="d" material="red" type="capsule" fromto="0 0 0 0 0 0.4" size="0.05"/>
      <geom name="plain" type="box" size=".1 .2 .3" pos="0 0 -0.3"/>
      <geom name="hidden" type="box" size=".1 .1 .1" rgba="1 1 1 0"/>
    </body>
  </worldbody>
</mujoco>"#;

#[test]
fn mjcf_page_draws_every_geom_in_mujocos_colour() {
    let world = urdyn::mjcf::compile_str(XML, "colours.xml", Path::new(".")).unwrap();
    let model = urdyn::mjcf::load_str(XML, "colours.xml", Path::new(".")).unwrap();
    let g = view::mjcf::geometry(&model, &world, "colours.xml");
    // the floor is the ground (the page draws it), the transparent box is invisible
    assert_eq!(g.visuals.len(), 6, "{:?}", g.visuals);
    let rgba: Vec<[f64; 4]> = g.visuals.iter().map(|v| v.rgba).collect();
    assert_eq!(rgba[0], [0.5, 0.5, 0.5, 1.0], "the wall: default grey");
    assert_eq!(
        rgba[1],
        [1.0, 0.0, 0.0, 1.0],
        "material red over the default grey"
    );
    assert_eq!(rgba[2], [0.2, 0.3, 0.4, 1.0], "own rgba over the material");
    assert_eq!(rgba[3], [0.0, 0.0, 1.0, 0.5], "the class's material");
    assert_eq!(
        rgba[4],
        [0.0, 1.0, 0.0, 1.0],
        "the class's rgba over the material"
    );
    assert_eq!(rgba[5], [0.5, 0.5, 0.5, 1.0]);
    assert_eq!(g.visuals[0].shape, VisualShape::Box([4.0, 6.0, 1e-3]));
    assert_eq!(g.visuals[0].body, 0);
    assert_eq!(g.visuals[1].shape, VisualShape::Sphere { radius: 0.1 });
    assert_eq!(
        g.visuals[3].shape,
        VisualShape::Ellipsoid {
            radii: [0.1, 0.2, 0.3]
        }
    );
    assert_eq!(
        g.visuals[4].shape,
        VisualShape::Capsule {
            radius: 0.05,
            length: 0.4
        }
    );
    assert_eq!(g.visuals[5].shape, VisualShape::Box([0.2, 0.4, 0.6]));
    // placements on the free body: the capsule's centre halfway up its fromto
    assert!(g.visuals[1..].iter().all(|v| v.body == 1));
    assert!((g.visuals[4].placement.trans.z - 0.2).abs() < 1e-12);
    assert!((g.visuals[2].placement.trans.x - 0.3).abs() < 1e-12);
}

#[test]
fn mjcf_simulate_html_and_view_write_the_page() {
    let dir = std::env::temp_dir().join(format!("urdyn_mjcf_view_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/dm_control/cartpole.xml");
    let (csv, page, page2) = (dir.join("t.csv"), dir.join("p.html"), dir.join("v.html"));
    let args = urdyn::cli::simulate::SimulateArgs {
        duration: 0.2,
        out: Some(csv.clone()),
        html: Some(page.clone()),
        ..urdyn::cli::simulate::SimulateArgs::new(&model)
    };
    urdyn::cli::simulate::run(&args).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("\"kind\":\"capsule\"") || html.contains("\"kind\": \"capsule\""));
    let s = view::run(&view::ViewArgs {
        urdf: model.clone(),
        traj: csv,
        floating_base: false,
        package_path: Vec::new(),
        out: page2.clone(),
    })
    .unwrap();
    assert!(s.frames > 1);
    assert!(std::fs::metadata(&page2).unwrap().len() > 1000);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A unit cube centred at (0.5, 0.5, 0.5) as OBJ text (8 vertices, 12 triangles).
const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

#[test]
fn mjcf_page_draws_mesh_geoms_from_their_files_scaled_in_their_colour() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("m")).unwrap();
    std::fs::write(dir.path().join("m/cube.obj"), CUBE_OBJ).unwrap();
    let xml = r#"<mujoco>
  <compiler meshdir="m"/>
  <asset>
    <mesh name="long" file="cube.obj" scale="2 1 1"/>
    <mesh file="cube.obj"/>
  </asset>
  <worldbody>
    <body name="b" pos="0 0 1">
      <freejoint/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <geom type="mesh" mesh="long" rgba="1 0.5 0 1"/>
      <geom type="mesh" mesh="cube" pos="0 0 2" rgba="0 0 1 1"/>
      <geom type="mesh" mesh="cube" pos="0 0 4"/>
    </body>
  </worldbody>
</mujoco>"#;
    let world = urdyn::mjcf::compile_str(xml, "meshes.xml", dir.path()).unwrap();
    let model = urdyn::mjcf::load_str(xml, "meshes.xml", dir.path()).unwrap();
    let g = view::mjcf::geometry(&model, &world, "meshes.xml");
    assert!(g.warnings.is_empty(), "{:?}", g.warnings);
    // two distinct (file, scale) meshes, the cube's shared by two geoms
    assert_eq!(g.meshes.len(), 2);
    let shapes: Vec<_> = g.visuals.iter().map(|v| v.shape.clone()).collect();
    assert_eq!(
        shapes,
        [
            VisualShape::Mesh(0),
            VisualShape::Mesh(1),
            VisualShape::Mesh(1)
        ]
    );
    // the file's 12 triangles, the scale along x only
    assert_eq!(g.meshes[0].triangles.len(), 12);
    let ext = |k: usize, a: usize| {
        let xs = g.meshes[k].vertices.iter().map(|v| v[a]);
        xs.clone().fold(f64::NEG_INFINITY, f64::max) - xs.fold(f64::INFINITY, f64::min)
    };
    assert_eq!([ext(0, 0), ext(0, 1), ext(0, 2)], [2.0, 1.0, 1.0]);
    assert_eq!([ext(1, 0), ext(1, 1), ext(1, 2)], [1.0, 1.0, 1.0]);
    // the geom's colour (MuJoCo's default grey where it gives none), its pose
    let rgba: Vec<[f64; 4]> = g.visuals.iter().map(|v| v.rgba).collect();
    assert_eq!(
        rgba,
        [
            [1.0, 0.5, 0.0, 1.0],
            [0.0, 0.0, 1.0, 1.0],
            [0.5, 0.5, 0.5, 1.0]
        ]
    );
    assert!((g.visuals[2].placement.trans.z - 4.0).abs() < 1e-12);
    assert!(g.visuals.iter().all(|v| v.body == 1));
}

#[test]
fn mjcf_page_of_a_menagerie_style_arm_draws_its_stl_meshes() {
    // The Panda's collision STLs, one mesh geom a body (explicit inertials).
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mjcf/meshes/panda.xml");
    let (model, world) = urdyn::mjcf::load_file_with_world(&file).unwrap();
    let g = view::mjcf::geometry(&model, &world, "panda.xml");
    assert!(g.warnings.is_empty(), "{:?}", g.warnings);
    assert_eq!(g.meshes.len(), 9);
    assert_eq!(g.visuals.len(), 9);
    let stl = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/robots/example-robot-data/robots/panda_description/meshes/collision");
    for (k, name) in ["link0", "link1", "link2"].iter().enumerate() {
        let m = urdyn::mesh::load_mesh(&stl.join(format!("{name}.stl")), [1.0; 3]).unwrap();
        assert_eq!(g.visuals[k].shape, VisualShape::Mesh(k));
        assert_eq!(g.meshes[k].triangles.len(), m.triangles.len(), "{name}");
    }
    assert_eq!(g.visuals[1].rgba, [0.95, 0.45, 0.1, 1.0]);
}

#[test]
fn a_mesh_geom_gives_its_body_the_solid_it_bounds() {
    // cube.obj is the unit cube [0, 1]³. Scaled to 2 × 1 × 1, turned 90° about z and
    // raised by 1, at density 500 it is a 1000 kg box centred at R (1, ½, ½) + (0, 0, 1)
    // = (−½, 1, 1½), its moments m (b² + c²)/12 = 1000·2/12 and 1000·5/12 swapped in
    // x and y by the turn. As a shell of mass 3 (inertia="shell"), the unit cube is
    // six plates of ½ kg: I = 5/18 M s² about each axis through its centre.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cube.obj"), CUBE_OBJ).unwrap();
    std::fs::write(
        dir.path().join("flat.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let xml = r#"<mujoco><asset>
        <mesh name="long" file="cube.obj" scale="2 1 1"/>
        <mesh name="skin" file="cube.obj" inertia="shell"/>
      </asset><worldbody>
      <body name="solid"><freejoint/>
        <geom type="mesh" mesh="long" density="500" pos="0 0 1" euler="0 0 90"/></body>
      <body name="shell" pos="3 0 0"><freejoint/><geom type="mesh" mesh="skin" mass="3"/></body>
      </worldbody></mujoco>"#;
    let w = urdyn::mjcf::compile_str(xml, "m.xml", dir.path()).unwrap();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
    let solid = &w.bodies[1];
    assert!(near(solid.mass, 1000.0), "{}", solid.mass);
    for (k, c) in [-0.5, 1.0, 1.5].into_iter().enumerate() {
        assert!(near(solid.com[k], c), "{}", solid.com);
    }
    let want = [
        1000.0 * 5.0 / 12.0,
        1000.0 * 2.0 / 12.0,
        1000.0 * 5.0 / 12.0,
    ];
    for r in 0..3 {
        for c in 0..3 {
            let x = if r == c { want[r] } else { 0.0 };
            assert!(
                (solid.inertia[(r, c)] - x).abs() < 1e-9,
                "{}",
                solid.inertia
            );
        }
    }
    let shell = &w.bodies[2];
    assert!(near(shell.mass, 3.0), "{}", shell.mass);
    assert!((shell.com - nalgebra::Vector3::new(0.5, 0.5, 0.5)).norm() < 1e-12);
    for r in 0..3 {
        assert!(
            near(shell.inertia[(r, r)], 5.0 / 18.0 * 3.0),
            "{}",
            shell.inertia
        );
    }
    // a flat mesh bounds no solid: an error naming the geom's mesh
    let flat = r#"<mujoco><asset><mesh file="flat.obj"/></asset><worldbody>
      <body><freejoint/><geom type="mesh" mesh="flat"/></body></worldbody></mujoco>"#;
    let e = urdyn::mjcf::compile_str(flat, "m.xml", dir.path()).unwrap_err();
    assert!(e.to_string().contains("mesh \"flat\""), "{e}");
}
