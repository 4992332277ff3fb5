//! Property tests of the spatial algebra (proptest): structured forms against the
//! 6x6 matrices, group identities and invariants (formerly `src/spatial/tests.rs`).
use proptest::prelude::*;
use urdyn::nalgebra::{self, Matrix6, Vector3, Vector6};
use urdyn::spatial::*;

fn v3() -> impl Strategy<Value = Vector3<f64>> {
    (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64).prop_map(|(a, b, c)| Vector3::new(a, b, c))
}
fn se3() -> impl Strategy<Value = Se3<f64>> {
    (v3(), -3.0..3.0f64, -1.5..1.5f64, -3.0..3.0f64, v3())
        .prop_map(|(_, r, p, y, t)| Se3::new(rpy_to_matrix(r, p, y), t))
}
fn motion() -> impl Strategy<Value = Motion<f64>> {
    (v3(), v3()).prop_map(|(a, l)| Motion::new(a, l))
}
fn force() -> impl Strategy<Value = Force<f64>> {
    (v3(), v3()).prop_map(|(a, l)| Force::new(a, l))
}
/// A physically valid inertia: positive principal moments obeying the triangle
/// inequality, in a random orientation.
fn inertia() -> impl Strategy<Value = Inertia<f64>> {
    (
        0.1..5.0f64,
        v3(),
        0.1..2.0f64,
        0.1..2.0f64,
        0.0..1.0f64,
        -3.0..3.0f64,
        -1.5..1.5f64,
        -3.0..3.0f64,
    )
        .prop_map(|(m, c, a, b, t, r, p, y)| {
            let lo = (a - b).abs();
            let cc = lo + t * (a + b - lo); // |a-b| <= c <= a+b
            let d = nalgebra::Matrix3::from_diagonal(&Vector3::new(a, b, cc.max(1e-3)));
            let rot = rpy_to_matrix(r, p, y);
            Inertia::new(m, c, rot * d * rot.transpose())
        })
}
fn close6(a: &Matrix6<f64>, b: &Matrix6<f64>) -> bool {
    (a - b).amax() <= 1e-12 * (1.0 + b.amax())
}
fn closev(a: &Vector6<f64>, b: &Vector6<f64>) -> bool {
    (a - b).amax() <= 1e-12 * (1.0 + b.amax())
}

proptest! {
    #[test]
    fn transform_structured_matches_matrix(x in se3(), m in motion(), f in force()) {
        prop_assert!(closev(&x.act_motion(&m).to_vector(), &(x.to_motion_matrix() * m.to_vector())));
        prop_assert!(closev(&x.act_force(&f).to_vector(), &(x.to_force_matrix() * f.to_vector())));
        let xi = x.inverse();
        prop_assert!(closev(&x.inv_act_motion(&m).to_vector(), &(xi.to_motion_matrix() * m.to_vector())));
        prop_assert!(closev(&x.inv_act_force(&f).to_vector(), &(xi.to_force_matrix() * f.to_vector())));
        // X* = X^-T
        prop_assert!(close6(&x.to_force_matrix(), &xi.to_motion_matrix().transpose()));
    }

    #[test]
    fn transform_times_inverse_is_identity(x in se3(), y in se3()) {
        prop_assert!(close6(&(x.to_motion_matrix() * x.inverse().to_motion_matrix()), &Matrix6::identity()));
        prop_assert!(close6(&x.compose(&y).to_motion_matrix(), &(x.to_motion_matrix() * y.to_motion_matrix())));
        prop_assert!(close6(&x.inv_compose(&y).to_motion_matrix(), &(x.inverse().to_motion_matrix() * y.to_motion_matrix())));
    }

    #[test]
    fn cross_products_match_matrices(a in motion(), b in motion(), f in force()) {
        prop_assert!(closev(&a.cross(&b).to_vector(), &(a.cross_matrix() * b.to_vector())));
        prop_assert!(closev(&a.cross_force(&f).to_vector(), &(a.cross_force_matrix() * f.to_vector())));
        // (v×)ᵀ = −(v×*)
        prop_assert!(close6(&a.cross_matrix().transpose(), &(-a.cross_force_matrix())));
        // v × v = 0
        prop_assert!(a.cross(&a).to_vector().amax() < 1e-14);
    }

    #[test]
    fn inertia_structured_matches_matrix(i in inertia(), v in motion()) {
        prop_assert!(closev(&i.mul_motion(&v).to_vector(), &(i.to_matrix() * v.to_vector())));
        // symmetric, and vᵀ I v > 0 for a valid inertia and v != 0
        prop_assert!(close6(&i.to_matrix(), &i.to_matrix().transpose()));
        if v.to_vector().norm() > 1e-3 {
            prop_assert!(v.dot(&i.mul_motion(&v)) > 0.0);
        }
    }

    #[test]
    fn inertia_transform_roundtrip_and_congruence(i in inertia(), x in se3()) {
        let j = x.act_inertia(&i);
        let back = x.inv_act_inertia(&j);
        prop_assert!(close6(&back.to_matrix(), &i.to_matrix()));
        // I_a = X* I_b X⁻¹
        let expect = x.to_force_matrix() * i.to_matrix() * x.inverse().to_motion_matrix();
        prop_assert!(close6(&j.to_matrix(), &expect));
    }

    #[test]
    fn power_is_frame_invariant(x in se3(), m in motion(), f in force()) {
        let p = m.dot(&f);
        let q = x.act_motion(&m).dot(&x.act_force(&f));
        prop_assert!((p - q).abs() <= 1e-12 * (1.0 + p.abs()));
    }

    #[test]
    fn inertia_sum_is_matrix_sum(a in inertia(), b in inertia(), x in se3()) {
        let b2 = x.act_inertia(&b);
        prop_assert!(close6(&a.add(&b2).to_matrix(), &(a.to_matrix() + b2.to_matrix())));
    }
}

#[test]
fn parallel_axis_point_mass() {
    // docs/theory.md §"Spatial inertia": a point mass m at c has
    // I = m (|c|² 1 − c cᵀ) about the origin.
    let c = Vector3::new(0.3, -0.2, 0.5);
    let i: Inertia<f64> = Inertia::new(2.0, c, nalgebra::Matrix3::zeros());
    let expect: nalgebra::Matrix3<f64> =
        (nalgebra::Matrix3::identity() * c.norm_squared() - c * c.transpose()) * 2.0;
    assert!((i.inertia_origin() - expect).amax() < 1e-15);
}

#[test]
fn rpy_matches_axis_composition() {
    let (r, p, y) = (0.3, -0.7, 1.1);
    let expect =
        axis_angle(&Vector3::z(), y) * axis_angle(&Vector3::y(), p) * axis_angle(&Vector3::x(), r);
    assert!((rpy_to_matrix(r, p, y) - expect).amax() < 1e-15);
}

proptest! {
    /// The multiply-add kernels of `ops` against nalgebra's operators (equal up to
    /// the rounding of the fused products on an FMA build, bit-equal otherwise).
    #[test]
    fn ops_kernels_match_nalgebra(a in v3(), b in v3(), x in se3(), y in se3()) {
        use urdyn::spatial::ops::*;
        let close = |p: &Vector3<f64>, q: &Vector3<f64>| (p - q).norm() <= 1e-14 * (1.0 + q.norm());
        prop_assert!(close(&cross(&a, &b), &a.cross(&b)));
        prop_assert!(close(&add_cross(&b, &a, &b), &(b + a.cross(&b))));
        prop_assert!(close(&mat_vec(&x.rot, &a), &(x.rot * a)));
        prop_assert!(close(&add_mat_vec(&b, &x.rot, &a), &(b + x.rot * a)));
        prop_assert!(close(&mat_tr_vec(&x.rot, &a), &(x.rot.transpose() * a)));
        prop_assert!(close(&axpy(&a, &b, 0.7), &(a + b * 0.7)));
        prop_assert!((dot(&a, &b) - a.dot(&b)).abs() <= 1e-14 * (1.0 + a.norm() * b.norm()));
        prop_assert!((mat_mat(&x.rot, &y.rot) - x.rot * y.rot).norm() <= 1e-14);
        prop_assert!((mat_tr_mat(&x.rot, &y.rot) - x.rot.transpose() * y.rot).norm() <= 1e-14);
        let m = madd(a.x, b.x, a.y);
        if cfg!(target_feature = "fma") {
            prop_assert_eq!(m, a.x.mul_add(b.x, a.y));
        } else {
            prop_assert_eq!(m, a.x * b.x + a.y);
        }
    }
}
