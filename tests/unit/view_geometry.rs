//! The tests of `src/cli/view/geometry.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::cli::view::{simplify, Geometry, VisualShape};
use urdyn::mesh::TriMesh;
use urdyn::nalgebra::Vector3;
use urdyn::testing::view::{bounds, triangle_limit, DEFAULT_RGBA};
use urdyn::LoadOptions;

/// A UV sphere of radius 1 with about 2·n² triangles.
fn sphere(n: usize) -> TriMesh {
    let mut m = TriMesh::default();
    for i in 0..=n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..n {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
            m.vertices.push(Vector3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    for i in 0..n {
        for j in 0..n {
            let (a, b) = ((i * n + j) as u32, (i * n + (j + 1) % n) as u32);
            let (c, d) = (a + n as u32, b + n as u32);
            m.triangles.push([a, b, d]);
            m.triangles.push([a, d, c]);
        }
    }
    m
}

#[test]
fn triangle_limit_fills_the_budget_from_below() {
    // Under the budget: the per-mesh cap.
    assert_eq!(triangle_limit(&[10, 20, 30], 100, 1000), 100);
    // 10 and 20 kept whole; the other two share 120 - 30 = 90: L = 45,
    // and Σ min(n, 45) = 10 + 20 + 45 + 45 = 120.
    assert_eq!(triangle_limit(&[500, 10, 20, 80], 1000, 120), 45);
    // The cap first: 60 000 counts as 20 000.
    assert_eq!(triangle_limit(&[60_000, 100], 20_000, 20_100), 20_000);
    // A tiny budget still leaves a box's worth.
    assert_eq!(triangle_limit(&[1000, 1000], 1000, 4), 12);
    // Brute force: the largest L with Σ min(nᵢ, L) ≤ total.
    let counts = [3, 900, 77, 4000, 1200, 50];
    for total in [100, 1000, 3000, 6000] {
        let best = (0..=4000)
            .filter(|&l| counts.iter().map(|&n: &usize| n.min(l)).sum::<usize>() <= total)
            .max()
            .unwrap();
        assert_eq!(
            triangle_limit(&counts, 4000, total),
            best.max(12),
            "{total}"
        );
    }
}

#[test]
fn simplify_stays_under_the_limit_and_on_the_shape() {
    let m = sphere(200);
    assert!(m.triangles.len() > 70_000);
    let s = simplify(&m, 5_000);
    assert!(
        s.triangles.len() <= 5_000 && s.triangles.len() > 1_000,
        "{}",
        s.triangles.len()
    );
    // Cluster means lie inside the sphere, near its surface; the bounding box
    // is nearly kept; every index is valid.
    for v in &s.vertices {
        assert!(v.norm() <= 1.0 + 1e-12 && v.norm() > 0.9, "{}", v.norm());
    }
    let (lo, hi) = bounds(&s);
    assert!((hi - lo).iter().all(|e| *e > 1.9), "{lo} {hi}");
    assert!(s
        .triangles
        .iter()
        .flatten()
        .all(|&i| (i as usize) < s.vertices.len()));
    // A mesh under the limit is kept as it is.
    assert_eq!(simplify(&m, 100_000), m);
}

#[test]
fn collision_geometry_where_a_link_has_no_visual_and_material_colours() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("r.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="r">
<material name="red"><color rgba="1 0 0 1"/></material>
<link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin xyz="0 0 1"/><geometry><box size="1 2 3"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
<visual><origin xyz="0 0.5 0"/><geometry><sphere radius="0.25"/></geometry><material name="red"/></visual>
<visual><geometry><cylinder radius="0.1" length="2"/></geometry><material name="x"><color rgba="0 0 1 0.5"/></material></visual>
<collision><geometry><sphere radius="9"/></geometry></collision></link>
<joint name="f" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0 0 2"/></joint>
<link name="c"><visual><geometry><box size="1 1 1"/></geometry></visual></link>
</robot>"#,
    )
    .unwrap();
    let model = urdyn::load_file(&urdf, LoadOptions::default()).unwrap();
    let g = Geometry::load(&model, &urdf, &[]).unwrap();
    let v: Vec<_> = g
        .visuals
        .iter()
        .map(|v| (v.link.as_str(), v.shape.clone(), v.rgba, v.placement.trans))
        .collect();
    assert_eq!(v.len(), 4, "{v:?}");
    assert_eq!(v[0].0, "a");
    assert_eq!(v[0].1, VisualShape::Box([1.0, 2.0, 3.0]));
    assert_eq!(v[0].2, DEFAULT_RGBA);
    assert_eq!(v[1].1, VisualShape::Sphere { radius: 0.25 });
    assert_eq!(v[1].2, [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(v[2].2, [0.0, 0.0, 1.0, 0.5]);
    // c is welded to b: its box sits on b's body, 2 m up.
    assert_eq!(v[3].0, "c");
    let body_b = model.frames[model.frame_index("b").unwrap()].body;
    assert_eq!(g.visuals[3].body, body_b);
    assert!((v[3].3 - Vector3::new(0.0, 0.0, 2.0)).norm() < 1e-12);
    assert!((v[1].3 - Vector3::new(0.0, 0.5, 0.0)).norm() < 1e-12);
}
