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
