//! The tests of `src/contact/broad.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use crate::common::lcg::Lcg;
use urdyn::testing::contact::{
    mask_pairs, sap_new, sap_overlaps, sap_set, table_allow, table_allowed, table_new, table_set,
};

#[test]
fn finds_exactly_the_overlapping_allowed_pairs() {
    // four unit spheres on the x axis at 0, 1.5, 3, 10: 0–1 and 1–2 overlap
    let mut s = sap_new(4);
    for (i, x) in [10.0, 0.0, 1.5, 3.0].into_iter().enumerate() {
        sap_set(&mut s, i, [x, 0.0, 0.0], [1.0; 3]);
    }
    // every pair allowed, pair index = 10·min + max
    let every = || {
        let mut t = table_new(4);
        for i in 0..4 {
            for j in i + 1..4 {
                table_allow(&mut t, i, j);
                table_set(&mut t, i, j, (10 * i + j) as u32);
            }
        }
        t
    };
    let mut table = every();
    let mut out = Vec::new();
    sap_overlaps(&mut s, &table, &mut out, &mut Vec::new());
    out.sort();
    assert_eq!(out, vec![12, 23]);
    // moved apart in z: none
    sap_set(&mut s, 2, [1.5, 0.0, 5.0], [1.0; 3]);
    out.clear();
    sap_overlaps(&mut s, &table, &mut out, &mut Vec::new());
    assert!(out.is_empty(), "{out:?}");
    // a pair the filter forbids is not reported
    sap_set(&mut s, 2, [1.5, 0.0, 0.0], [1.0; 3]);
    table = table_new(4);
    for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 3), (2, 3)] {
        table_allow(&mut table, i, j);
        table_set(&mut table, i, j, (10 * i + j) as u32);
    }
    out.clear();
    sap_overlaps(&mut s, &table, &mut out, &mut Vec::new());
    assert_eq!(out, vec![23]);
    // a pair allowed but not made yet is reported by its shapes
    table_allow(&mut table, 1, 2);
    out.clear();
    let mut fresh = Vec::new();
    sap_overlaps(&mut s, &table, &mut out, &mut fresh);
    assert_eq!(out, vec![23]);
    let fresh: Vec<_> = fresh.iter().map(|&(i, j)| (i.min(j), i.max(j))).collect();
    assert_eq!(fresh, vec![(1, 2)]);
}
#[test]
fn strips_find_exactly_the_overlapping_pairs() {
    // 300 boxes of assorted sizes over a 4 m floor, four long walls and a
    // box never set: the strips' pairs are those of a test of every pair
    let n = 305;
    let mut s = sap_new(n);
    let mut table = table_new(n);
    for i in 0..n {
        for j in i + 1..n {
            if (i + 2 * j) % 7 != 0 {
                table_allow(&mut table, i, j);
                if (i * j) % 3 == 0 {
                    table_set(&mut table, i, j, (i * n + j) as u32);
                }
            }
        }
    }
    let mut lcg = Lcg(12345);
    let mut rnd = || lcg.uniform(0.0, 1.0);
    let walls = [
        ([-2.05, 0.0, 0.3], [0.05, 2.1, 0.3]),
        ([2.05, 0.0, 0.3], [0.05, 2.1, 0.3]),
        ([0.0, -2.05, 0.3], [2.0, 0.05, 0.3]),
        ([0.0, 2.05, 0.3], [2.0, 0.05, 0.3]),
    ];
    for round in 0..3 {
        for i in 0..n - 1 {
            if i < 4 {
                sap_set(&mut s, i, walls[i].0, walls[i].1);
            } else if round == 0 || i % 3 == round {
                let c = [4.0 * rnd() - 2.0, 4.0 * rnd() - 2.0, rnd()];
                let h = 0.03 + 0.1 * rnd();
                sap_set(&mut s, i, c, [h, 0.5 * h + 0.05 * rnd(), h]);
            }
        }
        let (mut out, mut fresh) = (Vec::new(), Vec::new());
        sap_overlaps(&mut s, &table, &mut out, &mut fresh);
        let mut got: Vec<(usize, usize)> = fresh
            .iter()
            .map(|&(i, j)| ((i as usize).min(j as usize), (i as usize).max(j as usize)))
            .collect();
        got.extend(out.iter().map(|&p| (p as usize / n, p as usize % n)));
        got.sort();
        let mut want = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let (a, b, c, d) = (s.lo[i], s.hi[i], s.lo[j], s.hi[j]);
                let over = (0..3).all(|k| c[k] <= b[k] && a[k] <= d[k]);
                if over && table_allowed(&table, i, j) {
                    want.push((i, j));
                }
            }
        }
        assert!(want.len() > 40, "{}", want.len());
        assert_eq!(got, want, "round {round}");
    }
}

#[test]
fn masks_find_the_pairs_of_a_test_of_every_pair_in_order() {
    // a robot's self pairs (PairMasks, fewer than 64 shapes, every allowed
    // pair known): exactly the allowed pairs whose boxes overlap (touching
    // counts, as in the sweep), by l then h, on both of its paths (under 16
    // shapes a test of each allowed pair; from 16 every h at once)
    let mut lcg = Lcg(777);
    for n in [3usize, 15, 16, 17, 40, 64] {
        let mut s = sap_new(n);
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if (3 * i + j) % 5 != 0 {
                    // both orders, as a model's pair list may give them
                    pairs.push(if (i + j) % 2 == 0 { (i, j) } else { (j, i) });
                }
            }
        }
        for round in 0..4 {
            for i in 0..n {
                let c = [
                    lcg.uniform(-0.5, 0.5),
                    lcg.uniform(-0.3, 0.3),
                    lcg.uniform(0.0, 1.0),
                ];
                let h = [
                    lcg.uniform(0.05, 0.3),
                    lcg.uniform(0.05, 0.3),
                    lcg.uniform(0.05, 0.3),
                ];
                sap_set(&mut s, i, c, h);
            }
            if round == 3 && n > 2 {
                // two boxes exactly touching along x: found
                sap_set(&mut s, 0, [0.0, 0.0, 0.0], [0.1; 3]);
                sap_set(&mut s, 2, [0.2, 0.0, 0.0], [0.1; 3]);
            }
            let got = mask_pairs(n, &pairs, &s).expect("n <= 64");
            let mut want = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    let (a, b, c, d) = (s.lo[i], s.hi[i], s.lo[j], s.hi[j]);
                    let over = (0..3).all(|k| c[k] <= b[k] && a[k] <= d[k]);
                    if over && (3 * i + j) % 5 != 0 {
                        want.push((i, j));
                    }
                }
            }
            assert!(n < 16 || want.len() > 5, "n {n}: {}", want.len());
            if round == 3 && n > 2 {
                assert!(want.contains(&(0, 2)), "n {n}");
            }
            assert_eq!(got, want, "n {n}, round {round}");
        }
    }
    // more than 64 shapes: not for the masks
    assert!(mask_pairs(65, &[(0, 1)], &sap_new(65)).is_none());
}

#[test]
fn still_shapes_keep_their_pairs_as_some_move() {
    // the sweep tests only the pairs with a shape not still and takes the
    // others from the last sweep: over steps where a few shapes move (or
    // none), the pairs are still those of a test of every pair, on both
    // paths (one sweep under 64 shapes, strips from 64)
    for n in [30usize, 120] {
        let mut s = sap_new(n);
        let mut table = table_new(n);
        for i in 0..n {
            for j in i + 1..n {
                table_allow(&mut table, i, j);
                table_set(&mut table, i, j, (i * n + j) as u32);
            }
        }
        let mut lcg = Lcg(99 + n as u64);
        let side = if n < 64 { 0.8 } else { 1.6 };
        for round in 0..8 {
            for i in 0..n {
                // all at first, then a few (none in round 5)
                if round == 0 || (round != 5 && (i * 7 + round) % 11 == 0) {
                    let c = [
                        side * lcg.uniform(0.0, 1.0),
                        side * lcg.uniform(0.0, 1.0),
                        0.3 * lcg.uniform(0.0, 1.0),
                    ];
                    let h = 0.04 + 0.08 * lcg.uniform(0.0, 1.0);
                    sap_set(&mut s, i, c, [h, h, h]);
                }
            }
            let (mut out, mut fresh) = (Vec::new(), Vec::new());
            sap_overlaps(&mut s, &table, &mut out, &mut fresh);
            assert!(fresh.is_empty());
            let mut got: Vec<(usize, usize)> = out
                .iter()
                .map(|&p| (p as usize / n, p as usize % n))
                .collect();
            got.sort();
            let mut want = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    let (a, b, c, d) = (s.lo[i], s.hi[i], s.lo[j], s.hi[j]);
                    if (0..3).all(|k| c[k] <= b[k] && a[k] <= d[k]) {
                        want.push((i, j));
                    }
                }
            }
            assert!(want.len() > 10, "{}", want.len());
            assert_eq!(got, want, "n {n} round {round}");
        }
    }
}
