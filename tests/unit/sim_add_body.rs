//! The tests of `src/sim/constraints/tables.rs`'s `add_body`: one body's
//! entries of a contact's three rows, written where the row path holds each
//! of the body's dofs (in place when they lie back to back, else one by one);
//! and `src/sim/constraints/free.rs`'s rows of root free bodies, the same bits.

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

/// A root free body's world columns at the pose (rotation about `axis` by
/// `angle`, translation `t`): three linear (R eₖ) and three angular (R eₖ,
/// with t × R eₖ), as `act_column` makes them.
fn free_cols(axis: Vector3<f64>, angle: f64, t: Vector3<f64>) -> [Motion; 6] {
    let r = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
    let e = |k: usize| r * Vector3::ith(k, 1.0);
    let mut c = [Motion::new(Vector3::zeros(), Vector3::zeros()); 6];
    for k in 0..3 {
        c[k] = Motion::new(Vector3::zeros(), e(k));
        c[3 + k] = Motion::new(e(k), t.cross(&e(k)));
    }
    c
}

/// Bit for bit, zeros' signs included.
fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn free_rows_are_add_body_s_bits() {
    use urdyn::testing::constraints::free_rows;
    let poses = [
        // axis-aligned (exact zeros: the negated body's entries −0 before the sum)
        (Vector3::z(), 0.0, Vector3::new(0.0, 0.0, 0.5)),
        (
            Vector3::new(0.3, -0.7, 0.2),
            0.9,
            Vector3::new(1.25, -0.5, 0.1),
        ),
        (
            Vector3::x(),
            std::f64::consts::FRAC_PI_2,
            Vector3::new(-2.0, 0.0, 0.3),
        ),
    ];
    let p = Vector3::new(0.4, -0.25, 0.05);
    for (i, &(ax, an, t)) in poses.iter().enumerate() {
        let a = free_cols(ax, an, t);
        let a_at = |path: &[usize], iv, row: &dyn Fn(Vector3<f64>) -> [f64; 3]| {
            add_body_rows(path, path.len(), iv, &a, &p, row).0
        };
        // the ground: rows (z, x, y) of the point velocity; past the path zeroed
        let path: Vec<usize> = (0..6).collect();
        let want = a_at(&path, 0, &|vp| [vp.z, vp.x, vp.y]);
        let got = free_rows(&a, None, &p, &Vector3::z(), 7.5).expect("a free body's plan");
        for r in 0..3 {
            assert_eq!(
                bits(&got[r][..6]),
                bits(&want[r]),
                "pose {i} ground row {r}"
            );
            assert_eq!(
                bits(&got[r][6..]),
                bits(&[0.0; 6]),
                "pose {i} ground row {r}"
            );
        }
        // two bodies: J = J_a − J_b along (n, t₁, t₂)
        let (bx, bn, bt) = poses[(i + 1) % poses.len()];
        let b = free_cols(bx, bn, bt);
        for n in [
            Vector3::z(),
            Vector3::new(0.6, 0.0, 0.8),
            Vector3::new(-0.36, 0.48, 0.8),
        ] {
            let (t1, t2) = urdyn::contact::tangents(&n);
            let path: Vec<usize> = (0..12).collect();
            let wa = a_at(&path, 0, &|vp| [n.dot(&vp), t1.dot(&vp), t2.dot(&vp)]);
            let row_b = |vp: Vector3<f64>| [-n.dot(&vp), -t1.dot(&vp), -t2.dot(&vp)];
            let wb = add_body_rows(&path, 12, 6, &b, &p, &row_b).0;
            let got = free_rows(&a, Some(&b), &p, &n, -3.0).expect("two free bodies' plan");
            for r in 0..3 {
                let want: Vec<f64> = wa[r].iter().zip(&wb[r]).map(|(x, y)| x + y).collect();
                assert_eq!(bits(&got[r]), bits(&want), "pose {i} normal {n:?} row {r}");
            }
        }
    }
}
