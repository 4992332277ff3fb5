//! A state at which H is singular to working precision fails with an error naming
//! the state's index (eval-contract.md); the same model at a regular state evaluates.

use urdyn::cli::{eval, state};
use urdyn::LoadOptions;

/// A point mass on a prismatic slider carried by a revolute joint: at slider
/// position 0 the mass sits on the revolute axis and H's first row vanishes.
const URDF: &str = r#"<robot name="spinner">
  <link name="base"/>
  <link name="arm"/>
  <link name="bead"><inertial><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="spin" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="arm"/><child link="bead"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
</robot>"#;

#[test]
fn singular_state_is_an_error_naming_the_state() {
    let model = urdyn::load_str(URDF, "spinner.urdf", LoadOptions::default()).unwrap();
    let states = state::parse_states(
        r#"{"states": [{"q": {"slide": 0.5}}, {"q": {"slide": 0.0}}]}"#,
        "s.json",
    )
    .unwrap();
    let err = eval::evaluate(&model, &states, "spinner.urdf", "s.json")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s.json") && err.contains("states[1]") && err.contains("singular"),
        "{err}"
    );
    let ok = state::parse_states(r#"{"states": [{"q": {"slide": 0.5}}]}"#, "s.json").unwrap();
    let v = eval::evaluate(&model, &ok, "spinner.urdf", "s.json").unwrap();
    // H = diag(m x², m) at x = 0.5
    let h = &v["results"][0]["mass_matrix"];
    assert!((h[0][0].as_f64().unwrap() - 0.25).abs() < 1e-14);
    assert!((h[1][1].as_f64().unwrap() - 1.0).abs() < 1e-14);
}
