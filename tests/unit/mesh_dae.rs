//! The mesh readers' tests (formerly `src/mesh/tests.rs`).

use std::path::Path;
use urdyn::mesh::*;
use urdyn::nalgebra::Vector3;
use urdyn::testing::mesh::read_dae_colored;

/// Positions of a COLLADA document (`src/mesh/mod.rs`'s module doc).
fn read_dae_positions(text: &str) -> Result<Vec<[f64; 3]>, String> {
    read_dae(text).map(|(p, _)| p)
}

/// Positions of a COLLADA document and the triangles of the placed geometries'
/// primitives.
fn read_dae(text: &str) -> Result<(Vec<[f64; 3]>, Vec<[u32; 3]>), String> {
    read_dae_colored(text).map(|d| (d.positions, d.triangles))
}

#[test]
fn dae_positions_and_unit() {
    let dae = r##"<?xml version="1.0"?>
<COLLADA><asset><unit meter="0.001"/></asset>
<library_geometries><geometry><mesh>
<source id="pos"><float_array id="pos-array" count="6">1 2 3 4 5 6</float_array></source>
<source id="nrm"><float_array id="nrm-array" count="3">0 0 1</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#pos"/></vertices>
</mesh></geometry></library_geometries></COLLADA>"##;
    let p = read_dae_positions(dae).unwrap();
    assert_eq!(p.len(), 2);
    assert!((p[1][2] - 0.006).abs() < 1e-15);
}

/// A document with one triangle geometry `tri` (points (1,0,0), (0,2,0),
/// (0,0,3)) and `scene` as its `<library_visual_scenes>` content.
fn dae_with_scene(scene: &str) -> String {
    format!(
        r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="1"/><up_axis>Y_UP</up_axis></asset>
<library_geometries><geometry id="tri"><mesh>
<source id="tri-pos"><float_array id="tri-pos-array" count="9">1 0 0 0 2 0 0 0 3</float_array></source>
<vertices id="tri-v"><input semantic="POSITION" source="#tri-pos"/></vertices>
</mesh></geometry>
<geometry id="unused"><mesh>
<source id="u-pos"><float_array id="u-pos-array" count="3">100 100 100</float_array></source>
<vertices id="u-v"><input semantic="POSITION" source="#u-pos"/></vertices>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">{scene}</visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#S"/></scene>
</COLLADA>"##
    )
}

fn assert_points(got: &[[f64; 3]], want: &[[f64; 3]]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        for k in 0..3 {
            assert!((g[k] - w[k]).abs() < 1e-12, "{got:?} != {want:?}");
        }
    }
}

#[test]
fn dae_matrix_scale_and_translation() {
    // Millimetres scaled to metres and moved, as anymal_foot.dae does
    // (plus a translation); the never-placed geometry is left out.
    let dae = dae_with_scene(
        r##"<node id="cam"><matrix>1 0 0 7 0 1 0 8 0 0 1 9 0 0 0 1</matrix></node>
<node id="n"><matrix sid="transform">0.001 0 0 0.5
 0 0.001 0 -0.25
 0 0 0.001 2
 0 0 0 1</matrix>
<instance_geometry url="#tri"><bind_material/></instance_geometry></node>"##,
    );
    let p = read_dae_positions(&dae).unwrap();
    assert_points(
        &p,
        &[[0.501, -0.25, 2.0], [0.5, -0.248, 2.0], [0.5, -0.25, 2.003]],
    );
    // The unit applies after the node transform, translation included.
    let dae = dae.replace(r#"meter="1""#, r#"meter="0.5""#);
    let p = read_dae_positions(&dae).unwrap();
    assert_points(
        &p,
        &[
            [0.2505, -0.125, 1.0],
            [0.25, -0.124, 1.0],
            [0.25, -0.125, 1.0015],
        ],
    );
}

#[test]
fn dae_nested_nodes_compose_in_order() {
    // parent: translate then rotate 90° about z; child: translate (1,0,0).
    // world = T(10,0,0) · Rz(90°) · T(1,0,0), so p -> (10 - (y), x + 1, z).
    let dae = dae_with_scene(
        r##"<node id="a"><translate>10 0 0</translate><rotate>0 0 1 90</rotate>
<node id="b"><translate>1 0 0</translate><instance_geometry url="#tri"/></node>
</node>"##,
    );
    let p = read_dae_positions(&dae).unwrap();
    assert_points(&p, &[[10.0, 2.0, 0.0], [8.0, 1.0, 0.0], [10.0, 1.0, 3.0]]);
    // Other order inside one node: rotate, then translate (in the rotated frame).
    let dae = dae_with_scene(
        r##"<node id="a"><rotate>0 0 1 90</rotate><translate>1 0 0</translate><scale>2 2 2</scale>
<instance_geometry url="#tri"/></node>"##,
    );
    let p = read_dae_positions(&dae).unwrap();
    assert_points(&p, &[[0.0, 3.0, 0.0], [-4.0, 1.0, 0.0], [0.0, 1.0, 6.0]]);
}

#[test]
fn dae_geometry_placed_twice_gives_both() {
    let dae = dae_with_scene(
        r##"<node id="a"><translate>0 0 1</translate><instance_geometry url="#tri"/></node>
<node id="b"><translate>0 0 -1</translate><instance_geometry url="#tri"/></node>"##,
    );
    let p = read_dae_positions(&dae).unwrap();
    assert_points(
        &p,
        &[
            [1.0, 0.0, 1.0],
            [0.0, 2.0, 1.0],
            [0.0, 0.0, 4.0],
            [1.0, 0.0, -1.0],
            [0.0, 2.0, -1.0],
            [0.0, 0.0, 2.0],
        ],
    );
}

#[test]
fn dae_instance_node_and_chosen_scene() {
    let dae = r##"<COLLADA>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa">1 2 3</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
</mesh></geometry></library_geometries>
<library_nodes><node id="lib"><scale>2 2 2</scale><instance_geometry url="#g"/></node></library_nodes>
<library_visual_scenes>
<visual_scene id="first"><node><instance_geometry url="#g"/></node></visual_scene>
<visual_scene id="second"><node><translate>0 0 10</translate><instance_node url="#lib"/></node></visual_scene>
</library_visual_scenes>
<scene><instance_visual_scene url="#second"/></scene></COLLADA>"##;
    assert_points(&read_dae_positions(dae).unwrap(), &[[2.0, 4.0, 16.0]]);
    // Without <scene>, the first visual scene.
    let first = dae.replace(
        r##"<scene><instance_visual_scene url="#second"/></scene>"##,
        "",
    );
    assert_points(&read_dae_positions(&first).unwrap(), &[[1.0, 2.0, 3.0]]);
    // A scene that places nothing: every POSITION array, untransformed.
    let none = dae.replace(r##"<instance_node url="#lib"/>"##, "");
    assert_points(&read_dae_positions(&none).unwrap(), &[[1.0, 2.0, 3.0]]);
    // An <instance_node> cycle is an error, not a hang.
    let cycle = dae.replace(
        r##"<instance_geometry url="#g"/></node></library_nodes>"##,
        r##"<instance_geometry url="#g"/><instance_node url="#lib"/></node></library_nodes>"##,
    );
    let e = read_dae_positions(&cycle).unwrap_err();
    assert!(e.contains("instance_node"), "{e}");
}

#[test]
fn dae_bad_scene_graphs_are_errors() {
    let cases: &[(&str, &str)] = &[
        (
            r##"<node id="n"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0</matrix><instance_geometry url="#tri"/></node>"##,
            "<matrix> has 15 numbers, expected 16",
        ),
        (
            r##"<node id="n"><matrix/><instance_geometry url="#tri"/></node>"##,
            "<matrix> has 0 numbers",
        ),
        (
            r##"<node id="n"><translate>1 x 2</translate><instance_geometry url="#tri"/></node>"##,
            "<translate>: \"x\" is not a number",
        ),
        (
            r##"<node id="n"><scale>1 inf 2</scale><instance_geometry url="#tri"/></node>"##,
            "<scale> has a non-finite number",
        ),
        (
            r##"<node id="n"><rotate>0 0 0 30</rotate><instance_geometry url="#tri"/></node>"##,
            "<rotate> has a zero axis",
        ),
        (
            r##"<node id="n"><rotate>0 0 1 NaN</rotate><instance_geometry url="#tri"/></node>"##,
            "<rotate> has a non-finite number",
        ),
        (
            r##"<node id="n"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1</matrix><instance_geometry url="#tri"/></node>"##,
            "<matrix>: the last row is not 0 0 0 1",
        ),
        (
            r##"<node id="n"><instance_geometry url="#nowhere"/></node>"##,
            "<instance_geometry url=\"#nowhere\"> names no geometry",
        ),
        (
            r##"<node id="n"><instance_geometry url="other.dae#tri"/></node>"##,
            "only references inside the file",
        ),
        (
            r##"<node id="n"><instance_geometry/></node>"##,
            "<instance_geometry> has no url",
        ),
        (
            r##"<node id="n"><instance_node url="#nowhere"/></node>"##,
            "<instance_node url=\"#nowhere\"> names no node",
        ),
        (
            r##"<node id="n"><skew>45 1 0 0 0 1 0</skew><node><instance_geometry url="#tri"/></node></node>"##,
            "node \"n\": <skew> is not read",
        ),
    ];
    for (scene, want) in cases {
        let e = read_dae_positions(&dae_with_scene(scene)).unwrap_err();
        assert!(e.contains(want), "{scene}: {e}");
        if scene.contains("<matrix") {
            assert!(e.contains("node \"n\""), "{e}");
        }
    }
    // A scene url that names no scene; a bad unit.
    let e =
        read_dae_positions(&dae_with_scene("").replace("url=\"#S\"", "url=\"#T\"")).unwrap_err();
    assert!(
        e.contains("<instance_visual_scene url=\"#T\"> names no visual_scene"),
        "{e}"
    );
    let e =
        read_dae_positions(&dae_with_scene("").replace("meter=\"1\"", "meter=\"-2\"")).unwrap_err();
    assert!(e.contains("<unit meter=\"-2\">"), "{e}");
    // A camera node with a bad-free <lookat> and no geometry is fine.
    let ok = dae_with_scene(
        r##"<node id="cam"><lookat>0 0 1 0 0 0 0 1 0</lookat><instance_camera url="#c"/></node>
<node id="n"><instance_geometry url="#tri"/></node>"##,
    );
    assert_eq!(read_dae_positions(&ok).unwrap().len(), 3);
}

#[test]
fn dae_empty_float_array_is_empty_not_missing() {
    // anymal_hip_l.dae has `<float_array id=".." count="0"/>` geometries.
    let dae = dae_with_scene(r##"<node><instance_geometry url="#e"/><instance_geometry url="#tri"/></node>"##)
        .replace(
            "</library_geometries>",
            r##"<geometry id="e"><mesh><source id="e-pos"><float_array id="e-pos-array" count="0"/></source>
<vertices id="e-v"><input semantic="POSITION" source="#e-pos"/></vertices></mesh></geometry></library_geometries>"##,
        );
    assert_eq!(read_dae_positions(&dae).unwrap().len(), 3);
}

#[test]
fn dae_triangles_of_placed_polylists() {
    // A unit square as one quad (polylist, normals interleaved: stride 2) and
    // one triangle, placed twice: the second copy's indices start at 4.
    let dae = r##"<COLLADA><asset><unit meter="0.5"/></asset>
<library_geometries><geometry id="sq"><mesh>
<source id="p"><float_array id="pa">0 0 0 1 0 0 1 1 0 0 1 0</float_array></source>
<source id="n"><float_array id="na">0 0 1</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<polylist count="1"><input semantic="VERTEX" source="#v" offset="0"/>
<input semantic="NORMAL" source="#n" offset="1"/><vcount>4</vcount><p>0 0 1 0 2 0 3 0</p></polylist>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>3 2 1</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">
<node><instance_geometry url="#sq"/></node>
<node><translate>0 0 2</translate><instance_geometry url="#sq"/></node>
</visual_scene></library_visual_scenes></COLLADA>"##;
    let (p, t) = read_dae(dae).unwrap();
    assert_eq!(p.len(), 8);
    assert_eq!(p[6], [0.5, 0.5, 1.0]);
    assert_eq!(
        t,
        vec![
            [0, 1, 2],
            [0, 2, 3],
            [3, 2, 1],
            [4, 5, 6],
            [4, 6, 7],
            [7, 6, 5]
        ]
    );
    // The positions are those load_vertices reads.
    assert_eq!(read_dae_positions(dae).unwrap(), p);
    // An index past the positions is an error naming the primitive.
    let bad = dae.replace("<p>3 2 1</p>", "<p>3 2 9</p>");
    let e = read_dae(&bad).unwrap_err();
    assert!(e.contains("<triangles>: vertex index 9"), "{e}");
    // A position no primitive indexes is dropped (from the vertices and from
    // the triangles' numbering), in every placed copy.
    let extra = dae
        .replace("0 1 0</float_array>", "0 1 0 5 5 5</float_array>")
        .replace("<p>3 2 1</p>", "<p>3 2 1</p><p></p>");
    let (p2, t2) = read_dae(&extra).unwrap();
    assert_eq!((p2, t2), (p.clone(), t.clone()));
    // Without primitives a geometry's every position is kept.
    let bare = extra
        .split("<polylist")
        .next()
        .map(|head| {
            format!(
                "{head}</mesh>{}",
                extra.split("</triangles>\n</mesh>").nth(1).unwrap_or("")
            )
        })
        .unwrap();
    let (p3, t3) = read_dae(&bare).unwrap();
    assert_eq!((p3.len(), t3.len()), (10, 0), "{bare}");
}

#[test]
fn dae_triangle_colours_from_bound_materials() {
    // Two primitives: "A" bound to material red (effect colour 1 0 0 1),
    // "B" naming material id blue directly (no binding; effect colour without
    // alpha), and a third whose effect has a texture (no colour).
    let dae = r##"<COLLADA><asset><unit meter="1"/></asset>
<library_effects>
<effect id="red-fx"><profile_COMMON><technique sid="c"><phong>
<emission><color>0 0 0 1</color></emission><diffuse><color sid="diffuse">1 0 0 1</color></diffuse>
</phong></technique></profile_COMMON></effect>
<effect id="blue-fx"><profile_COMMON><technique sid="c"><lambert><diffuse><color>0 0 0.5</color></diffuse></lambert></technique></profile_COMMON></effect>
<effect id="tex-fx"><profile_COMMON><technique sid="c"><lambert><diffuse><texture texture="img"/></diffuse></lambert></technique></profile_COMMON></effect>
</library_effects>
<library_materials>
<material id="red"><instance_effect url="#red-fx"/></material>
<material id="blue"><instance_effect url="#blue-fx"/></material>
<material id="tex"><instance_effect url="#tex-fx"/></material>
</library_materials>
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa">0 0 0 1 0 0 1 1 0 0 1 0</float_array></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles material="A" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
<polylist material="blue" count="1"><input semantic="VERTEX" source="#v" offset="0"/><vcount>4</vcount><p>0 1 2 3</p></polylist>
<triangles material="tex" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 2 3</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="S">
<node><instance_geometry url="#g"><bind_material><technique_common>
<instance_material symbol="A" target="#red"/><instance_material symbol="tex" target="#tex"/>
</technique_common></bind_material></instance_geometry></node>
<node><translate>0 0 1</translate><instance_geometry url="#g"/></node>
</visual_scene></library_visual_scenes></COLLADA>"##;
    let d = read_dae_colored(dae).unwrap();
    let red = Some([1.0, 0.0, 0.0, 1.0]);
    let blue = Some([0.0, 0.0, 0.5, 1.0]);
    // first copy: red, blue ×2 (the quad), none; the second copy has no
    // bindings: "A" names no material, "blue" still does, "tex" has no colour
    assert_eq!(
        d.colors,
        vec![red, blue, blue, None, None, blue, blue, None]
    );
    assert_eq!(d.colors.len(), d.triangles.len());
    // the same triangles as read_dae gives
    assert_eq!(read_dae(dae).unwrap().1, d.triangles);
}

#[test]
fn stl_and_obj_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let stl = dir.path().join("t.stl");
    std::fs::write(
        &stl,
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n\
         facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
    )
    .unwrap();
    let m = load_mesh(&stl, [2.0, 1.0, 1.0]).unwrap();
    assert_eq!(m.vertices.len(), 4);
    assert_eq!(m.triangles.len(), 2);
    // The second triangle is (1,0,0), (1,1,0), (0,1,0), x scaled by 2.
    let corners: Vec<_> = m.triangles[1]
        .iter()
        .map(|&i| m.vertices[i as usize])
        .collect();
    assert_eq!(corners[0], Vector3::new(2.0, 0.0, 0.0));
    assert_eq!(corners[1], Vector3::new(2.0, 1.0, 0.0));
    assert_eq!(corners[2], Vector3::new(0.0, 1.0, 0.0));
    assert_eq!(load_vertices(&stl, [2.0, 1.0, 1.0]).unwrap(), m.vertices);

    let obj = dir.path().join("q.obj");
    std::fs::write(&obj, "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 5\nv 1 0 5\nv 0 1 5\nf 5 6 7\n").unwrap();
    let m = load_mesh(&obj, [1.0; 3]).unwrap();
    assert_eq!(m.vertices.len(), 7);
    assert_eq!(m.triangles.len(), 3);
    // The quad's two triangles cover its area (1), the last triangle is z = 5.
    let area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        (b - a).cross(&(c - a)).norm() / 2.0
    };
    assert!((area(&m.triangles[0]) + area(&m.triangles[1]) - 1.0).abs() < 1e-12);
    assert!(m.triangles[2]
        .iter()
        .all(|&i| m.vertices[i as usize].z == 5.0));
}

#[test]
fn missing_file_names_it() {
    let e = load_vertices(Path::new("/nonexistent/foot.stl"), [1.0; 3]).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/foot.stl"));
}
