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
    sap_overlaps(&mut s, &mut table, &mut out, &mut Vec::new());
    out.sort();
    assert_eq!(out, vec![12, 23]);
    // moved apart in z: none
    sap_set(&mut s, 2, [1.5, 0.0, 5.0], [1.0; 3]);
    out.clear();
    sap_overlaps(&mut s, &mut table, &mut out, &mut Vec::new());
    assert!(out.is_empty(), "{out:?}");
    // a pair the filter forbids is not reported
    sap_set(&mut s, 2, [1.5, 0.0, 0.0], [1.0; 3]);
    table = table_new(4);
    for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 3), (2, 3)] {
        table_allow(&mut table, i, j);
        table_set(&mut table, i, j, (10 * i + j) as u32);
    }
    out.clear();
    sap_overlaps(&mut s, &mut table, &mut out, &mut Vec::new());
    assert_eq!(out, vec![23]);
    // a pair allowed but not made yet is reported by its shapes
    table_allow(&mut table, 1, 2);
    out.clear();
    let mut fresh = Vec::new();
    sap_overlaps(&mut s, &mut table, &mut out, &mut fresh);
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
        sap_overlaps(&mut s, &mut table, &mut out, &mut fresh);
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
            sap_overlaps(&mut s, &mut table, &mut out, &mut fresh);
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

/// The strips' sweep as round 38 made it (every finite y-extent's median by
/// a selection, the widest ordinary one as the strips' width, the ordinary
/// shapes by (strip, lower x), each strip merged with the next and every
/// later shape of the merged list tested, then the wide shapes against
/// all): its pairs in its order.
fn strips_reference(lo: &[[f64; 3]], hi: &[[f64; 3]]) -> Vec<(u32, u32)> {
    let n = lo.len();
    let meet = |i: usize, j: usize| {
        !(lo[j][1] > hi[i][1] || lo[i][1] > hi[j][1] || lo[j][2] > hi[i][2] || lo[i][2] > hi[j][2])
    };
    let mut ext: Vec<f64> = (0..n)
        .map(|i| hi[i][1] - lo[i][1])
        .filter(|e| e.is_finite())
        .collect();
    let mid = ext.len() / 2;
    let med = *ext.select_nth_unstable_by(mid, f64::total_cmp).1;
    let w = ext
        .iter()
        .copied()
        .filter(|&e| e <= 4.0 * med)
        .fold(0.0f64, f64::max);
    let w = if w > 0.0 { w } else { f64::INFINITY };
    let (mut strip, mut wide, mut ord) = (vec![0i64; n], Vec::new(), Vec::new());
    for i in 0..n {
        let s = (lo[i][1] / w).floor();
        let ordinary = hi[i][1] - lo[i][1] <= w && s.is_finite() && s.abs() <= 1e15;
        if ordinary {
            strip[i] = s as i64;
            ord.push(i);
        } else {
            wide.push(i);
        }
    }
    ord.sort_by(|&i, &j| {
        (strip[i], lo[i][0])
            .partial_cmp(&(strip[j], lo[j][0]))
            .unwrap()
    });
    let mut cand = Vec::new();
    let mut a = 0;
    while a < ord.len() {
        let s = strip[ord[a]];
        let b = a + ord[a..].iter().take_while(|&&i| strip[i] == s).count();
        let c = b + ord[b..].iter().take_while(|&&i| strip[i] == s + 1).count();
        let (mut i, mut j, mut merged) = (a, b, Vec::new());
        while i < b || j < c {
            if j >= c || (i < b && lo[ord[i]][0] <= lo[ord[j]][0]) {
                merged.push((ord[i], true));
                i += 1;
            } else {
                merged.push((ord[j], false));
                j += 1;
            }
        }
        for k in 0..merged.len() {
            let (i, in_s) = merged[k];
            for &(j, jn_s) in &merged[k + 1..] {
                if lo[j][0] > hi[i][0] {
                    break;
                }
                if (in_s || jn_s) && meet(i, j) {
                    cand.push((i as u32, j as u32));
                }
            }
        }
        a = b;
    }
    for &i in &wide {
        for j in 0..n {
            let skip = j == i || (wide.contains(&j) && j < i);
            if !skip && lo[j][0] <= hi[i][0] && lo[i][0] <= hi[j][0] && meet(i, j) {
                cand.push((i as u32, j as u32));
            }
        }
    }
    cand
}

#[test]
fn strips_find_the_pairs_in_the_order_of_round_38() {
    // boxes moving a little a step in a bin (the band about the last median
    // holds the new one) and now and then jumping (it does not): the pairs
    // not made yet come out in the order the sweep found them, which must be
    // round 38's sweep's (the order the pairs are made in)
    let (n, mut s) = (400, sap_new(400));
    // (every pair allowed, none made: each found one is `fresh`)
    let mut table = (0..n).fold(table_new(n), |mut t, i| {
        (i + 1..n).for_each(|j| table_allow(&mut t, i, j));
        t
    });
    let mut lcg = Lcg(4242);
    let walls = [
        ([-2.05, 0.0, 0.3], [0.05, 2.1, 0.3]),
        ([2.05, 0.0, 0.3], [0.05, 2.1, 0.3]),
        ([0.0, -2.05, 0.3], [2.0, 0.05, 0.3]),
        ([0.0, 2.05, 0.3], [2.0, 0.05, 0.3]),
    ];
    let mut boxes: Vec<([f64; 3], [f64; 3])> = (0..n)
        .map(|_| {
            let c = [
                4.0 * lcg.uniform(-0.5, 0.5),
                4.0 * lcg.uniform(-0.5, 0.5),
                lcg.uniform(0.0, 1.0),
            ];
            let h = 0.05 + 0.05 * lcg.uniform(0.0, 1.0);
            (c, [h, h * lcg.uniform(0.8, 1.2), h])
        })
        .collect();
    for step in 0..30 {
        for (i, b) in boxes.iter_mut().enumerate() {
            if i < 4 {
                *b = walls[i];
                continue;
            }
            let jump = if step % 10 == 9 { 0.3 } else { 0.003 };
            for k in 0..3 {
                b.0[k] += jump * lcg.uniform(-1.0, 1.0);
                b.1[k] *= 1.0 + jump * lcg.uniform(-0.1, 0.1);
            }
        }
        for (i, &(c, h)) in boxes.iter().enumerate().take(n - 1) {
            sap_set(&mut s, i, c, h);
        }
        let (mut out, mut fresh) = (Vec::new(), Vec::new());
        sap_overlaps(&mut s, &mut table, &mut out, &mut fresh);
        assert!(out.is_empty());
        let want = strips_reference(&s.lo, &s.hi);
        assert!(want.len() > 100, "{}", want.len());
        assert_eq!(fresh, want, "step {step}");
    }
}

#[test]
fn pair_lines_give_the_tables_entries_as_pairs_are_made_and_renumbered() {
    // boxes jostling in a bin; every pair allowed but those of shapes 5k and
    // 5k + 1 (never reported); each fresh pair made with the next index, and
    // every sixth step all made pairs renumbered (the lines hold stale
    // entries unless the writes empty them): each step's pairs are the
    // overlapping allowed ones with their current index
    let n = 300;
    let mut s = sap_new(n);
    let forbidden = |i: usize, j: usize| i / 5 == j / 5 && i.min(j) % 5 == 0 && i.abs_diff(j) == 1;
    let mut table = table_new(n);
    for i in 0..n {
        for j in i + 1..n {
            if !forbidden(i, j) {
                table_allow(&mut table, i, j);
            }
        }
    }
    let mut lcg = Lcg(77);
    let mut made = std::collections::BTreeMap::new();
    let mut next = 0u32;
    let mut boxes: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                lcg.uniform(-1.0, 1.0),
                lcg.uniform(-1.0, 1.0),
                lcg.uniform(0.0, 0.5),
            ]
        })
        .collect();
    for step in 0..40 {
        for c in boxes.iter_mut() {
            for x in c.iter_mut() {
                *x += 0.02 * lcg.uniform(-1.0, 1.0);
            }
        }
        for (i, &c) in boxes.iter().enumerate() {
            sap_set(&mut s, i, c, [0.06; 3]);
        }
        let (mut out, mut fresh) = (Vec::new(), Vec::new());
        sap_overlaps(&mut s, &mut table, &mut out, &mut fresh);
        let mut want: Vec<u32> = Vec::new();
        for (i, j) in strips_reference(&s.lo, &s.hi) {
            let key = (i.min(j) as usize, i.max(j) as usize);
            if let Some(&p) = made.get(&key) {
                want.push(p);
            } else {
                assert!(
                    forbidden(key.0, key.1)
                        || fresh
                            .iter()
                            .any(|&(a, b)| (a.min(b), a.max(b)) == (i.min(j), i.max(j)))
                );
            }
        }
        out.sort_unstable();
        want.sort_unstable();
        assert_eq!(out, want, "step {step}");
        for &(i, j) in &fresh {
            let key = (i.min(j) as usize, i.max(j) as usize);
            assert!(!forbidden(key.0, key.1) && !made.contains_key(&key));
            table_set(&mut table, key.0, key.1, next);
            made.insert(key, next);
            next += 1;
        }
        if step % 6 == 5 {
            for (&(i, j), p) in made.iter_mut() {
                *p += 100_000;
                table_set(&mut table, i, j, *p);
            }
        }
    }
    assert!(made.len() > 200, "{}", made.len());
}
