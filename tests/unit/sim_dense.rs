//! The tests of `src/sim/solver/dense.rs`: the subspace step's strided LDLᵀ,
//! from scratch and grown from a kept leading block, and its solve, against
//! the bits of `dynamics::linalg`'s (docs/theory.md §"Constraint solve").

use urdyn::dynamics::linalg;
use urdyn::testing::solver::{ldlt_dropping, ldlt_dropping_solve};

/// W = Y Yᵀ (m × m, row i at `i * ld`) of a pseudo-random m × k `Y`;
/// k < m gives rows dependent on earlier ones (pivots dropped).
fn gram(m: usize, k: usize, ld: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let y: Vec<f64> = (0..m * k).map(|_| next()).collect();
    let mut w = vec![f64::NAN; ld * ld];
    for i in 0..m {
        for j in 0..=i {
            let mut s = 0.0;
            for t in 0..k {
                s += y[i * k + t] * y[j * k + t];
            }
            w[i * ld + j] = s;
        }
    }
    w
}

fn lower(a: &[f64], ld: usize, m: usize) -> Vec<u64> {
    (0..m)
        .flat_map(|i| (0..=i).map(move |j| a[i * ld + j].to_bits()))
        .collect()
}

/// The strided factor (from scratch, and with a factored leading block
/// kept) and its solve give the library's bits, dropped pivots included.
#[test]
fn strided_and_appended_factor_match_the_library_bits() {
    let ld = 16;
    let mut drops = 0;
    for (m, k, seed) in [
        (16, 16, 1),
        (16, 11, 2),
        (13, 9, 3),
        (9, 12, 4),
        (16, 5, 5),
        (3, 3, 6),
        (4, 2, 7),
        (5, 5, 8),
        (6, 4, 9),
        (7, 7, 10),
        (7, 5, 11),
        (8, 8, 12),
        (8, 6, 13),
        (9, 9, 14),
        (10, 7, 15),
        (11, 11, 16),
        (12, 8, 17),
    ] {
        let w = gram(m, k, ld, seed);
        // the library on the packed copy
        let mut packed = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..=i {
                packed[i * m + j] = w[i * ld + j];
            }
        }
        linalg::ldlt_dropping(&mut packed, m, DROP);
        let want = lower(&packed, m, m);
        drops += (0..m).filter(|&i| packed[i * m + i] == 0.0).count();
        let mut full = w.clone();
        ldlt_dropping(&mut full, ld, m, 0, DROP);
        assert_eq!(lower(&full, ld, m), want, "m {m} k {k}");
        for p in [1, 3, m / 2, m - 1] {
            // rows p.. appended to the factor of the leading p
            let mut grown = w.clone();
            ldlt_dropping(&mut grown, ld, p, 0, DROP);
            ldlt_dropping(&mut grown, ld, m, p, DROP);
            assert_eq!(lower(&grown, ld, m), want, "m {m} k {k} p {p}");
        }
        let b: Vec<f64> = (0..m).map(|i| (i as f64 * 0.37).sin()).collect();
        let (mut x, mut xl) = (b.clone(), b);
        ldlt_dropping_solve(&full, ld, m, &mut x);
        linalg::ldlt_dropping_solve(&packed, m, &mut xl);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x), bits(&xl), "m {m} k {k}");
    }
    // the cases hold dependent rows, whose pivots were dropped
    assert!(drops >= 10, "{drops}");
}

const DROP: f64 = 1e-6;
