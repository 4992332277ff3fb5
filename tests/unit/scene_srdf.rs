//! The tests of `src/scene/srdf.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::scene::srdf::parse_srdf;

#[test]
fn reads_pairs_and_poses() {
    let s = parse_srdf(
        r#"<?xml version="1.0"?><robot name="r">
        <group name="g"><joint name="a"/></group>
        <group_state name="home" group="g"><joint name="a" value="0.5"/>
          <joint name="root_joint" value="0 0 1 0 0 0 1"/></group_state>
        <disable_collisions link1="x" link2="y" reason="Adjacent"/></robot>"#,
    )
    .unwrap();
    assert_eq!(s.disabled, vec![("x".to_string(), "y".to_string())]);
    let p = s.pose("home").unwrap();
    assert_eq!(p[0], ("a".to_string(), vec![0.5]));
    assert_eq!(p[1].1.len(), 7);
    assert!(s.pose("away").is_none());
}

#[test]
fn refuses_entities_and_bad_values() {
    assert!(parse_srdf("<!DOCTYPE r [<!ENTITY e \"x\">]><robot/>").is_err());
    let e = parse_srdf(
        r#"<robot><group_state name="h"><joint name="a" value="x"/></group_state></robot>"#,
    )
    .unwrap_err();
    assert!(e.contains("\"a\"") && e.contains("\"x\""), "{e}");
    assert!(parse_srdf("<robot><disable_collisions link1=\"a\"/></robot>").is_err());
}
