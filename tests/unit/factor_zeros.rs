//! The test of `src/sim/factor/zeros.rs`: on a model of lone free bodies at
//! their centres of mass on their principal axes (H̃ diagonal, L all ±0), the
//! chain eliminations of the contact rows skip their steps on plain entries;
//! they must give the bits every step gives (the same bodies beside a hinged
//! one: a model that is not all lone free bodies, whose factor marks no zeros
//! and takes every step), on plain entries and on the entries that take the
//! steps (a −0 that a step turns +0, a +0, ±∞, NaN).

use super::piles_chain6::{factor, ARM};
use urdyn::sim::factor::MassFactor;
use urdyn::Model;

/// Three free bodies, each geom at its body's origin on its axes: every
/// off-diagonal entry of H a zero (some −0: the skew of a zero first moment).
const BODIES: &str = r#"
  <body name="a" pos="0 0 1"><freejoint/>
    <geom type="box" size="0.1 0.2 0.05" mass="1.3"/></body>
  <body name="b" pos="1 0 1" euler="40 0 10"><freejoint/>
    <geom type="sphere" size="0.05" mass="0.2"/></body>
  <body name="c" pos="0 1 1"><freejoint/>
    <geom type="cylinder" size="0.05 0.2" mass="0.4"/></body>
"#;

fn model(extra: &str) -> Model {
    let xml = format!("<mujoco><worldbody>{BODIES}{extra}</worldbody></mujoco>");
    urdyn::mjcf::load_str(&xml, "factor_zeros.xml", std::path::Path::new(".")).expect("mjcf")
}

/// The entries' cases: plain; a −0 at the root slot (the step of the leaf's
/// L entry −0 turns it +0); a +0; +∞; NaN; a −0 at the root slot among
/// negative entries (the steps of L's +0 entries turn it +0).
fn special(case: usize, k: usize, x: f64) -> f64 {
    match (case, k) {
        (1 | 5, 0) => -0.0,
        (2, 3) => 0.0,
        (3, 4) => f64::INFINITY,
        (4, 2) => f64::NAN,
        (5, _) => -x,
        _ => x,
    }
}

fn same(a: &[f64], b: &[f64], what: &str) {
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.to_bits(), y.to_bits(), "{what}, entry {k}: {x} vs {y}");
    }
}

#[test]
fn zero_chains_take_every_steps_bits() {
    let lone = model("");
    let mixed = model(ARM);
    let (fl, fm) = (factor(&lone).0, factor(&mixed).0);
    let path = |f: &MassFactor, dof: usize| {
        let (s, l) = f.path_of(dof);
        f.table()[s..s + l].to_vec()
    };
    // one body's chain and two bodies' chains (a and c), the same dofs in both models
    let (one, two) = (path(&fl, 5), [path(&fl, 5), path(&fl, 17)].concat());
    assert_eq!(
        (one.clone(), two.clone()),
        (path(&fm, 5), [path(&fm, 5), path(&fm, 17)].concat())
    );
    let x = |k: usize, i: usize| ((k * 7 + i * 3) as f64 * 0.37).sin() + 1.5;
    for case in 0..6 {
        // rows in six lanes on one chain and on two
        let rows6 = |n: usize| -> Vec<[f64; 6]> {
            (0..n)
                .map(|t| std::array::from_fn(|i| special(case, t * 6 + i, x(t, i))))
                .collect()
        };
        let (mut wl, mut wm) = (rows6(6), rows6(6));
        let (wl6, wm6): (&mut [[f64; 6]; 6], &mut [[f64; 6]; 6]) = (
            wl.as_mut_slice().try_into().unwrap(),
            wm.as_mut_slice().try_into().unwrap(),
        );
        assert!(fl.chain_lanes6::<6>(&one, wl6) && fm.chain_lanes6::<6>(&one, wm6));
        same(wl.as_flattened(), wm.as_flattened(), "chain_lanes6");
        let (mut vl, mut vm) = (rows6(12), rows6(12));
        assert!(fl.two_chain_lanes6::<6, 6>(&two, &mut vl));
        assert!(fm.two_chain_lanes6::<6, 6>(&two, &mut vm));
        same(vl.as_flattened(), vm.as_flattened(), "two_chain_lanes6");
        // two contacts' rows in four lanes on one chain (the AVX builds' pairs)
        let rows4 = |s: usize| -> [[f64; 4]; 6] {
            std::array::from_fn(|t| {
                std::array::from_fn(|i| special(case, s + t * 4 + i, x(t, i + s)))
            })
        };
        let (mut al, mut bl, mut am, mut bm) = (rows4(0), rows4(1), rows4(0), rows4(1));
        assert!(fl.chain_lanes2::<6>(&one, &mut al, &mut bl));
        assert!(fm.chain_lanes2::<6>(&one, &mut am, &mut bm));
        same(al.as_flattened(), am.as_flattened(), "chain_lanes2 w");
        same(bl.as_flattened(), bm.as_flattened(), "chain_lanes2 v");
    }
}
