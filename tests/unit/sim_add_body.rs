//! The tests of `src/sim/constraints/tables.rs`'s `add_body`: one body's
//! entries of a contact's three rows, written where the row path holds each
//! of the body's dofs (in place when they lie back to back, else one by one).

use nalgebra::Vector3;
use urdyn::spatial::Motion;
use urdyn::testing::constraints::add_body_rows;

/// Three columns from dof 3: a linear one (no angular part) and two with
/// both parts; the point.
fn body() -> ([Motion; 3], Vector3<f64>) {
    let cols = [
        Motion::new(Vector3::zeros(), Vector3::new(0.3, -0.2, 0.9)),
        Motion::new(Vector3::new(0.1, 0.7, -0.4), Vector3::new(-0.5, 0.2, 0.6)),
        Motion::new(Vector3::new(-0.8, 0.05, 0.3), Vector3::new(0.4, 0.9, -0.1)),
    ];
    (cols, Vector3::new(0.25, -1.5, 0.75))
}

/// What column `k`'s rows hold: (x, −y, 2z) of its point velocity v + ω × p.
fn want(k: usize) -> [f64; 3] {
    let (cols, p) = body();
    let vp = cols[k].lin + cols[k].ang.cross(&p);
    [vp.x, -vp.y, 2.0 * vp.z]
}

fn rows(path: &[usize], hi: usize) -> ([Vec<f64>; 3], usize) {
    let (cols, p) = body();
    add_body_rows(path, hi, 3, &cols, &p, &|vp| [vp.x, -vp.y, 2.0 * vp.z])
}

#[test]
fn add_body_back_to_back_at_the_end_and_in_the_middle() {
    // at the end of what is left of the path (the first guess), and in its
    // middle (found by bisection)
    for (path, hi) in [(vec![0, 1, 3, 4, 5], 5), (vec![0, 3, 4, 5, 7, 9], 6)] {
        let (j, t0) = rows(&path, hi);
        assert_eq!(path[t0], 3, "{path:?}");
        for (t, &d) in path.iter().enumerate() {
            for (r, jr) in j.iter().enumerate() {
                let x = if (3..6).contains(&d) {
                    want(d - 3)[r]
                } else {
                    0.0
                };
                assert_eq!(jr[t], x, "path {path:?} dof {d} row {r}");
            }
        }
    }
}

#[test]
fn add_body_skips_a_dof_off_the_path() {
    // dof 4 is not on the path: dofs 3 and 5 are written one by one
    let path = [1, 3, 5, 8];
    let (j, t0) = rows(&path, path.len());
    assert_eq!(t0, 1);
    for (r, jr) in j.iter().enumerate() {
        assert_eq!(jr[..], [0.0, want(0)[r], want(2)[r], 0.0], "row {r}");
    }
}
