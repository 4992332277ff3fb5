//! The test of `src/sim/factor/chain6.rs`: a model of lone free bodies has its
//! mass factor's solves on fixed-size arrays; they must give the bits the
//! general loops give (the same bodies beside a hinged one, a model that is
//! not all lone free bodies and takes the general loops), and H̃⁻¹ b to
//! rounding.

use nalgebra::{DMatrix, DVector};
use urdyn::sim::factor::MassFactor;
use urdyn::{Data, Model};

/// Three free bodies with their centres of mass off their origins and
/// rotated inertias (every entry of a free body's 6 × 6 block non-zero).
const BODIES: &str = r#"
  <body name="a" pos="0 0 1"><freejoint/>
    <geom type="box" size="0.1 0.2 0.05" pos="0.03 -0.02 0.01" euler="10 20 30" mass="1.3"/></body>
  <body name="b" pos="1 0 1"><freejoint/>
    <geom type="box" size="0.2 0.1 0.1" mass="0.7"/>
    <geom type="sphere" size="0.05" pos="0.1 0.05 0" mass="0.2"/></body>
  <body name="c" pos="0 1 1" euler="40 0 10"><freejoint/>
    <geom type="capsule" size="0.05 0.2" pos="0 0.02 0.03" euler="0 30 0" mass="0.4"/></body>
"#;

/// A hinged body beside the free ones: a model that is not all lone free
/// bodies (its factor takes the general loops).
pub(super) const ARM: &str = r#"<body name="arm" pos="0 0 2"><joint type="hinge" axis="0 1 0"/>
  <geom type="capsule" size="0.05 0.3" mass="1"/></body>"#;

fn model(extra: &str) -> Model {
    let xml = format!("<mujoco><worldbody>{BODIES}{extra}</worldbody></mujoco>");
    urdyn::mjcf::load_str(&xml, "piles_chain6.xml", std::path::Path::new(".")).expect("mjcf")
}

/// The model's factor of H̃ = H(q) + [`diag`] at a pose q away from the
/// neutral one (the free bodies' coordinates the same in every model: they
/// come first), and q.
pub(super) fn factor(m: &Model) -> (MassFactor, DVector<f64>) {
    let mut q: DVector<f64> = m.neutral();
    for k in 0..m.nq {
        q[k] += 0.3 * ((k as f64) * 1.7).sin();
    }
    for b in 0..3 {
        let at = 7 * b + 3;
        let n = q.rows(at, 4).norm();
        for r in 0..4 {
            q[at + r] /= n;
        }
    }
    let mut f = MassFactor::new(m);
    let r = f.factor_at(m, &mut Data::new(m), q.as_slice(), false, diag);
    assert_eq!(r, Some(Ok(())));
    (f, q)
}

fn diag(k: usize) -> f64 {
    0.01 + 0.001 * k as f64
}

#[test]
fn lone_free_solves_take_the_general_loops_bits() {
    let lone = model("");
    let mixed = model(ARM);
    assert_eq!((lone.nv, mixed.nv), (18, 19));
    let (fl, fm) = (factor(&lone).0, factor(&mixed).0);
    let b = |n: usize| DVector::from_fn(n, |k, _| ((k as f64) * 0.9).cos() + 0.1);
    // solve
    let (mut xl, mut xm) = (b(18), b(19));
    fl.solve(&mut xl);
    fm.solve(&mut xm);
    // half_solve
    let (mut zl, mut zm) = (b(18), b(19));
    fl.half_solve(zl.as_mut_slice());
    fm.half_solve(zm.as_mut_slice());
    // half_solve2 (two vectors at once: each the bits of half_solve)
    let (mut zl2, mut wl2) = (b(18), b(18).map(|x| 2.0 * x - 0.3));
    let (mut zm2, mut wm2) = (b(19), b(19).map(|x| 2.0 * x - 0.3));
    fl.half_solve2(zl2.as_mut_slice(), wl2.as_mut_slice());
    fm.half_solve2(zm2.as_mut_slice(), wm2.as_mut_slice());
    // apply_r
    let (mut rl, mut rm) = (vec![0.0; 18], vec![0.0; 19]);
    fl.apply_r(b(18).as_slice(), &mut rl);
    fm.apply_r(b(19).as_slice(), &mut rm);
    for k in 0..18 {
        assert_eq!(xl[k].to_bits(), xm[k].to_bits(), "solve, dof {k}");
        assert_eq!(zl[k].to_bits(), zm[k].to_bits(), "half_solve, dof {k}");
        assert_eq!(rl[k].to_bits(), rm[k].to_bits(), "apply_r, dof {k}");
        assert_eq!(zl2[k].to_bits(), zm2[k].to_bits(), "half_solve2 z, dof {k}");
        assert_eq!(wl2[k].to_bits(), wm2[k].to_bits(), "half_solve2 w, dof {k}");
        assert_eq!(
            zl2[k].to_bits(),
            zl[k].to_bits(),
            "half_solve2 z = half_solve, dof {k}"
        );
    }
}

/// H̃ x = b solved on the arrays agrees with a dense Cholesky of H + diag
/// (H from the public CRBA) to rounding; R⁻¹ undoes R.
#[test]
fn lone_free_solve_is_the_dense_solve() {
    let m = model("");
    let (f, q) = factor(&m);
    let mut h: DMatrix<f64> = urdyn::dynamics_f64::crba(&m, &mut Data::new(&m), &q)
        .expect("crba")
        .clone();
    for k in 0..m.nv {
        h[(k, k)] += diag(k);
    }
    let b = DVector::from_fn(18, |k, _| ((k as f64) * 0.7).sin() + 0.2);
    let mut x = b.clone();
    f.solve(&mut x);
    let want = h.clone().cholesky().expect("H̃ positive definite").solve(&b);
    let err = (&x - &want).amax() / want.amax();
    assert!(err < 1e-10, "{err:e}");
    let mut z = vec![0.0; 18];
    f.apply_r(b.as_slice(), &mut z);
    f.half_solve(&mut z);
    for k in 0..18 {
        assert!(
            (z[k] - b[k]).abs() < 1e-12 * b.amax(),
            "dof {k}: {} vs {}",
            z[k],
            b[k]
        );
    }
}
