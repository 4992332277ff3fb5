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

/// A contact's three rows through the factor held as lanes
/// (`row_transform_lanes`: a chain, or two branches of one tree found once
/// for the path) take the bits of the three rows taken apart
/// (`row_transform3`, which looks up each dof's ancestors): on every chain of
/// humanoid_CMU and on every pair of its dofs on two branches (the union of
/// their paths, as a self-collision contact's).
#[test]
fn rows_as_lanes_take_the_bits_of_rows_apart_on_chains_and_two_branches() {
    let m = mjcf("dm_control/humanoid_CMU.xml");
    let q = pose(&m);
    let mut f = MassFactor::new(&m);
    let mut data = Data::new(&m);
    let diag = |k: usize| 0.01 + 0.001 * k as f64;
    assert_eq!(
        f.factor_at(&m, &mut data, q.as_slice(), false, diag),
        Some(Ok(()))
    );
    let nv = m.nv;
    // dof d and its ancestors, ascending
    let chain = |d: usize| {
        let mut p = vec![d];
        while let Some(&a) = p.last().and_then(|&k| m.dof_parent.get(k)) {
            if a == usize::MAX {
                break;
            }
            p.push(a);
        }
        p.reverse();
        p
    };
    let mut paths = Vec::new();
    let mut branches = 0;
    for a in 0..nv {
        paths.push(chain(a));
        for b in a + 1..nv {
            let (pa, pb) = (chain(a), chain(b));
            if pb.contains(&a) {
                continue;
            }
            let mut u: Vec<usize> = pa.iter().chain(&pb).copied().collect();
            u.sort_unstable();
            u.dedup();
            branches += 1;
            paths.push(u);
        }
    }
    assert!(branches > 100, "{branches} pairs on two branches");
    for (i, path) in paths.iter().enumerate() {
        let n = path.len();
        let row = |r: usize| -> Vec<f64> {
            (0..n)
                .map(|t| ((1 + i + 7 * r + 3 * t) as f64 * 0.37).sin())
                .collect()
        };
        let (mut y0, mut y1, mut y2) = (row(0), row(1), row(2));
        let mut lanes: Vec<[f64; 4]> = (0..n).map(|t| [y0[t], y1[t], y2[t], 0.0]).collect();
        f.row_transform3(path, &mut y0, &mut y1, &mut y2);
        assert!(f.row_transform_lanes(path, &mut lanes), "path {path:?}");
        for t in 0..n {
            let want = [y0[t], y1[t], y2[t]].map(f64::to_bits);
            let got = [lanes[t][0], lanes[t][1], lanes[t][2]].map(f64::to_bits);
            assert_eq!(got, want, "path {path:?}, entry {t}");
        }
    }
}
