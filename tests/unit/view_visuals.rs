//! The tests of `src/cli/view/visuals.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::model::Shape;
use urdyn::nalgebra::Vector3;
use urdyn::testing::view::read_visuals as read;

#[test]
fn pieces_materials_and_malformed_ones() {
    let d = read(
        r#"<robot name="r">
<material name="red"><color rgba="1 0 0 1"/></material>
<link name="a">
  <visual><origin xyz="1 2 3" rpy="0 0 1.5707963267948966"/>
<geometry><mesh filename="package://p/m.dae" scale="2 2 2"/></geometry>
<material name="red"><texture/></material></visual>
  <visual><geometry><sphere radius="oops"/></geometry></visual>
  <visual><origin quat_xyzw="0 0 0 1"/><geometry><cylinder radius="1" length="2"/></geometry>
<material name=""><color rgba="0 1 0 0.5"/></material></visual>
  <collision><geometry><box size="1 2 3"/></geometry></collision>
  <visual/>
</link>
<gazebo reference="a"><material>Gazebo/Red</material></gazebo>
<link name="b"/>
</robot>"#,
    )
    .unwrap();
    assert_eq!(d.materials.get("red"), Some(&[1.0, 0.0, 0.0, 1.0]));
    assert_eq!(d.links.len(), 2);
    let a = &d.links[0];
    assert_eq!(a.visuals.len(), 2);
    assert_eq!(
        a.visuals[0].shape,
        Shape::Mesh {
            filename: "package://p/m.dae".into(),
            scale: [2.0; 3]
        }
    );
    assert_eq!(a.visuals[0].material.as_deref(), Some("red"));
    assert_eq!(a.visuals[0].xyz, Vector3::new(1.0, 2.0, 3.0));
    // rpy (0, 0, π/2) maps x to y.
    assert!((a.visuals[0].rot * Vector3::x() - Vector3::y()).norm() < 1e-15);
    assert_eq!(
        a.visuals[1].shape,
        Shape::Cylinder {
            radius: 1.0,
            length: 2.0
        }
    );
    assert_eq!(a.visuals[1].color, Some([0.0, 1.0, 0.0, 0.5]));
    assert_eq!(a.visuals[1].material, None);
    assert_eq!(
        a.collisions[0].shape,
        Shape::Box {
            size: [1.0, 2.0, 3.0]
        }
    );
    assert_eq!(d.warnings.len(), 2, "{:?}", d.warnings);
    assert!(d.warnings[0].contains("link \"a\": <visual> <sphere radius=\"oops\">"));
    assert!(d.warnings[1].contains("has no <geometry>"));
}
