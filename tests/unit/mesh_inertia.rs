//! The tests of `src/mesh/inertia.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::mesh::{mass_properties, MeshInertia, TriMesh};
use urdyn::nalgebra::Vector3;

/// A box of half sizes `h` centred at `c`, its 12 triangles wound
/// outward, or every other one flipped (`flip`).
fn cuboid(h: [f64; 3], c: [f64; 3], flip: bool) -> TriMesh {
    let mut vertices = Vec::new();
    for k in 0..8 {
        let s = |bit: usize, i: usize| if k >> bit & 1 == 1 { h[i] } else { -h[i] };
        vertices.push(Vector3::new(s(0, 0) + c[0], s(1, 1) + c[1], s(2, 2) + c[2]));
    }
    // faces by their 4 corners, counter-clockwise seen from outside
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for (i, q) in quads.iter().enumerate() {
        triangles.push([q[0], q[1], q[2]]);
        if flip && i % 2 == 0 {
            triangles.push([q[0], q[3], q[2]]);
        } else {
            triangles.push([q[0], q[2], q[3]]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1e-12)
}

#[test]
fn a_closed_box_is_the_solid_by_every_rule() {
    let (h, c) = ([0.1, 0.2, 0.3], [0.5, -0.25, 2.0]);
    let v = 8.0 * h[0] * h[1] * h[2];
    // the box's closed form: V (b² + c²)/3 with half sizes
    let want = [
        v * (h[1] * h[1] + h[2] * h[2]) / 3.0,
        v * (h[0] * h[0] + h[2] * h[2]) / 3.0,
        v * (h[0] * h[0] + h[1] * h[1]) / 3.0,
    ];
    for rule in [MeshInertia::Legacy, MeshInertia::Exact, MeshInertia::Convex] {
        let m = mass_properties(&cuboid(h, c, false), rule).unwrap();
        assert!(close(m.volume, v), "{rule:?}: {}", m.volume);
        assert!(
            (m.com - Vector3::from(c)).norm() < 1e-14,
            "{rule:?}: {}",
            m.com
        );
        for k in 0..3 {
            assert!(
                close(m.inertia[(k, k)], want[k]),
                "{rule:?} {k}: {}",
                m.inertia
            );
        }
        assert!(m.inertia[(0, 1)].abs() < 1e-16 && m.inertia[(1, 2)].abs() < 1e-16);
    }
    // legacy takes a misoriented face's pyramid positive: the same box
    let m = mass_properties(&cuboid(h, c, true), MeshInertia::Legacy).unwrap();
    assert!(close(m.volume, v));
    // exact counts it negative: two flipped halves of faces cancel
    let m = mass_properties(&cuboid(h, c, true), MeshInertia::Exact).unwrap();
    assert!(m.volume > 0.0 && m.volume < 0.9 * v, "{}", m.volume);
}

#[test]
fn a_shell_box_is_six_plates() {
    let (h, c) = ([0.1, 0.2, 0.3], [0.0, 0.0, 0.0]);
    let m = mass_properties(&cuboid(h, c, false), MeshInertia::Shell).unwrap();
    let (a, b, cc) = (h[0], h[1], h[2]);
    let area = 8.0 * (a * b + b * cc + a * cc);
    assert!(close(m.volume, area));
    // about x: the two plates normal to x (area 4bc each, Iₓ = A(b²+c²)/3),
    // the two normal to y (4ac at distance b: A(c²/3 + b²)), the two normal
    // to z (4ab at distance c: A(b²/3 + c²))
    let ix = 2.0 * 4.0 * b * cc * (b * b + cc * cc) / 3.0
        + 2.0 * 4.0 * a * cc * (cc * cc / 3.0 + b * b)
        + 2.0 * 4.0 * a * b * (b * b / 3.0 + cc * cc);
    assert!(
        close(m.inertia[(0, 0)], ix),
        "{} vs {ix}",
        m.inertia[(0, 0)]
    );
}

#[test]
fn an_open_box_has_a_legacy_volume_and_no_exact_one() {
    // the box without its top (two triangles)
    let mut open = cuboid([0.1, 0.1, 0.1], [0.0; 3], false);
    open.triangles.truncate(10);
    let legacy = mass_properties(&open, MeshInertia::Legacy).unwrap();
    assert!(legacy.volume > 0.0);
    // a flat mesh has no volume by any solid rule
    let flat = TriMesh {
        vertices: vec![Vector3::zeros(), Vector3::x(), Vector3::y()],
        triangles: vec![[0, 1, 2]],
    };
    assert!(mass_properties(&flat, MeshInertia::Legacy).is_err());
}
