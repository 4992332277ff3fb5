//! One row's dot along its path and its update, and a tangent pair's update
//! (subspace.rs, position.rs), over any [`Dofs`]: a path of one or two runs
//! of six consecutive dofs ([`Path::of`], a free body's, two free bodies')
//! as [`Runs`] at the fixed length 6 or 12, read and written as slices of x
//! (whole-vector loads), any other path gathered
//! ([`super::super::kernels::Runs`]). Each entry the same
//! operations in the same order either way.

use super::super::kernels::Dofs;

/// `$run` with `$q` the dofs of the path `$p` ([`Path::of`]) and `$n` their
/// count, every slice named cut to `$n` (≤ its length: the caller's): one
/// run or two as [`Runs`] (6 or 12), any other path as it is (`$p.len()`).
macro_rules! by_runs {
    ($p:expr; $($s:ident),+; $q:ident, $n:ident => $run:expr) => {
        match $crate::sim::solver::kernels::Path::of($p) {
            $crate::sim::solver::kernels::Path::One(d) => {
                let ($q, $n) = (d, 6);
                $( let $s = &$s[..6]; )+
                $run
            }
            $crate::sim::solver::kernels::Path::Two(d) => {
                let ($q, $n) = (d, 12);
                $( let $s = &$s[..12]; )+
                $run
            }
            $crate::sim::solver::kernels::Path::Any(d) => {
                let ($q, $n) = (d, d.len());
                $( let $s = &$s[..$n]; )+
                $run
            }
        }
    };
}
pub(in crate::sim::solver) use by_runs;

/// `s0` + Σₜ yₜ x[pₜ] over `n` slots in path order (the scalar loop
/// `u += y x` from `u = s0`).
///
/// # Safety
/// `y` and `p` hold `n` entries; every dof of `p` is < `x.len()`.
#[inline(always)]
pub(in crate::sim::solver) unsafe fn dot_from<D: Dofs>(
    s0: f64,
    y: &[f64],
    p: D,
    n: usize,
    x: &[f64],
) -> f64 {
    // SAFETY: the caller's
    debug_assert!((0..n).all(|j| unsafe { p.at(j) } < x.len()));
    let mut u = s0;
    for j in 0..n {
        // SAFETY: the caller's
        u += y[j] * unsafe { *x.get_unchecked(p.at(j)) };
    }
    u
}

/// x[pₜ] += a yₜ over `n` slots (each entry one product and one sum).
///
/// # Safety
/// `y` and `p` hold `n` entries; every dof of `p` is < `x.len()`.
#[inline(always)]
pub(in crate::sim::solver) unsafe fn add<D: Dofs>(
    a: f64,
    y: &[f64],
    p: D,
    n: usize,
    x: &mut [f64],
) {
    // SAFETY: the caller's
    debug_assert!((0..n).all(|j| unsafe { p.at(j) } < x.len()));
    for j in 0..n {
        // SAFETY: the caller's
        unsafe { *x.get_unchecked_mut(p.at(j)) += a * y[j] };
    }
}

/// x[pₜ] = (x[pₜ] + a₀ y₀ₜ) + a₁ y₁ₜ over `n` slots (a tangent pair on
/// one path: the row-by-row order).
///
/// # Safety
/// `y0`, `y1` and `p` hold `n` entries; every dof of `p` is < `x.len()`.
#[inline(always)]
pub(in crate::sim::solver) unsafe fn add2<D: Dofs>(
    a: [f64; 2],
    y0: &[f64],
    y1: &[f64],
    p: D,
    n: usize,
    x: &mut [f64],
) {
    // SAFETY: the caller's
    debug_assert!((0..n).all(|j| unsafe { p.at(j) } < x.len()));
    for j in 0..n {
        // SAFETY: the caller's
        unsafe {
            let xk = x.get_unchecked_mut(p.at(j));
            *xk = (*xk + a[0] * y0[j]) + a[1] * y1[j];
        }
    }
}
