//! The tests of `src/sim/factor.rs` and `src/sim/factor/elim.rs`: the step's
//! tree-sparse factor of H̃ = H(q) + diag (a dof and its parent eliminated
//! together where they form a chain) against H from the public CRBA.

use nalgebra::{DMatrix, DVector};
use std::path::PathBuf;
use urdyn::sim::factor::MassFactor;
use urdyn::{Data, Model};

fn mjcf(name: &str) -> Model {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    urdyn::mjcf::load_file(root.join("tests/fixtures/mjcf").join(name)).expect(name)
}

/// A q away from the symmetric default pose: each coordinate moved by a
/// fixed pattern (the quaternions renormalised by hand).
fn pose(m: &Model) -> DVector<f64> {
    let mut q: DVector<f64> = m.neutral();
    for k in 0..m.nq {
        q[k] += 0.3 * ((k as f64) * 1.7).sin();
    }
    for j in &m.joints[1..m.nbodies] {
        let at = match j.kind {
            urdyn::model::JointKind::Free => j.iq + 3,
            urdyn::model::JointKind::Spherical => j.iq,
            _ => continue,
        };
        let n = q.rows(at, 4).norm();
        for r in 0..4 {
            q[at + r] /= n;
        }
    }
    q
}

/// H̃ x = b solved with the packed factor agrees with a dense Cholesky of
/// H + diag (H from `crba`, every entry) to rounding, on trees whose dofs
/// are chains of pairs (humanoid_CMU: three hinges a body) and branches.
#[test]
fn the_paired_elimination_solves_what_the_dense_cholesky_solves() {
    for name in [
        "dm_control/humanoid_CMU.xml",
        "gymnasium/humanoid.xml",
        "gymnasium/ant.xml",
    ] {
        let m = mjcf(name);
        let q = pose(&m);
        let diag = |k: usize| 0.01 + 0.001 * k as f64;
        let mut f = MassFactor::new(&m);
        assert!(f.is_tree(), "{name}");
        let mut data = Data::new(&m);
        let r = f.factor_at(&m, &mut data, q.as_slice(), false, diag);
        assert_eq!(r, Some(Ok(())), "{name}");
        let mut h: DMatrix<f64> = urdyn::dynamics_f64::crba(&m, &mut Data::new(&m), &q)
            .expect("crba")
            .clone();
        for k in 0..m.nv {
            h[(k, k)] += diag(k);
        }
        let b = DVector::from_fn(m.nv, |k, _| ((k as f64) * 0.9).cos());
        let mut x = b.clone();
        f.solve(&mut x);
        let want = h.clone().cholesky().expect("H̃ positive definite").solve(&b);
        let err = (&x - &want).amax() / want.amax();
        assert!(err < 1e-10, "{name}: {err:e}");
        let res = (&h * &x - &b).amax() / b.amax();
        assert!(res < 1e-10, "{name}: residual {res:e}");
    }
}

/// A pivot that fails is reported by its dof, the highest failing one (the
/// elimination runs from the leaves in): a dof whose parent is the next dof
/// down (eliminated as a pair with its child) and one that is not.
#[test]
fn a_failed_pivot_names_its_dof_inside_a_pair_and_alone() {
    let m = mjcf("dm_control/humanoid_CMU.xml");
    let q = pose(&m);
    let nv = m.nv;
    // a dof k with a child k + 1 (a pair's parent) and one whose next dof is
    // not its child (a leaf)
    let parent_of_next = (6..nv - 1)
        .find(|&k| m.dof_parent[k + 1] == k)
        .expect("a chain");
    let leaf = (6..nv - 1)
        .find(|&k| m.dof_parent[k + 1] != k)
        .expect("a leaf");
    for bad in [parent_of_next, leaf, nv - 1] {
        let mut f = MassFactor::new(&m);
        let mut data = Data::new(&m);
        let diag = |k: usize| if k == bad { -1e6 } else { 0.0 };
        let r = f.factor_at(&m, &mut data, q.as_slice(), false, diag);
        assert_eq!(r, Some(Err(bad)), "dof {bad}");
    }
}
