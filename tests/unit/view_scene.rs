//! The tests of `src/cli/view/scene.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::nalgebra::Vector3;
use urdyn::scene::HeightFieldSpec;
use urdyn::testing::view::height_field_mesh;

#[test]
fn height_field_surface_spans_the_grid() {
    let h = HeightFieldSpec {
        heights: vec![vec![0.0, 0.1, 0.2], vec![0.3, 0.4, 0.5]],
        size: [4.0, 2.0],
    };
    let m = height_field_mesh(&h);
    assert_eq!(m.vertices.len(), 6);
    assert_eq!(m.triangles.len(), 4);
    // corner (row 1, col 2): +x, +y, height 0.5
    assert_eq!(m.vertices[5], Vector3::new(2.0, 1.0, 0.5));
    assert_eq!(m.vertices[0], Vector3::new(-2.0, -1.0, 0.0));
    // every triangle faces up (counter-clockwise seen from +z)
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        assert!((b - a).cross(&(c - a)).z > 0.0);
    }
}
