//! A contact's three rows in one pass of the sweeps (pgs.rs): the normal's
//! projected Gauss–Seidel step, then the tangent pair's from the velocity
//! the normal's change left, slid onto the friction disc when it leaves it
//! (docs/theory.md §"Constraint solve").
//!
//! The visit is one chain of dependent operations from the contact's dots to
//! its update of Δv', which the next contact on the same body reads at once:
//! its latency is the sweeps' time. Two of its factors are exact 1.0 on
//! nearly every visit — `live` (a row no impulse can move keeps 0: ×1 on a
//! live row) and `relax` in a plain sweep — and are left out of the chain
//! there (`LIVE`, `PLAIN`: x·1 = x bit for bit), each a copy of the same text.

use super::super::dot3::dot3_at;
use super::super::kernels::{axpy3_path, pinned_until, slide_onto_cone, Path};
use super::super::loop_block::{BlockRows, LoopBlock};
use super::super::RowKind;
use super::{measure, most};

/// What a contact's visit reads, fixed over a solve: the rows (read-only)
/// and the sweep's settings.
pub(super) struct Fixed<'a> {
    /// Y's rows, `st` apart.
    pub y: &'a [f64],
    /// The rows' stride in `y`.
    pub st: usize,
    /// Each row's path in `table` (start, length).
    pub paths: &'a [(usize, usize)],
    /// The paths' dofs.
    pub table: &'a [usize],
    /// The rows' kinds (μ on a contact's first tangent).
    pub kinds: &'a [RowKind],
    /// Wᵣᵣ (the block's reduced W' when it is in the solve).
    pub w: &'a [f64],
    /// A contact's (W_n1, W_n2, W_12).
    pub w_block: &'a [[f64; 3]],
    /// 1/Wᵣᵣ, 0 on a row no impulse can move.
    pub winv: &'a [f64],
    /// The rows' free velocities.
    pub c: &'a [f64],
    /// The rows' targets.
    pub b: &'a [f64],
    /// The loop block when it is in the solve.
    pub lb: Option<&'a LoopBlock>,
    /// The rows as the loop block reads them.
    pub view: &'a BlockRows<'a>,
    /// Rows pinned at a bound are marked for skipping ([`pinned_until`]).
    pub skip: bool,
}

/// What the sweep's visits write besides λ and Δv'.
pub(super) struct Carry<'a> {
    /// Every row's velocity at its last update.
    pub u_prev: &'a mut [f64],
    /// Up to which `drift` a pinned row stays so (`SKIP` only).
    pub until: &'a mut [f64],
    /// The sweep's convergence measure so far.
    pub change: f64,
    /// A bound on ‖Δv'‖ since the first row was pinned.
    pub drift: f64,
    /// Some row is pinned.
    pub armed: bool,
}

/// x·(1 if row r can move, else 0): x itself when every row of the contact
/// is live (`LIVE`: x·1 = x, bit for bit).
#[inline(always)]
fn live<const LIVE: bool>(winv: &[f64], r: usize, x: f64) -> f64 {
    if LIVE {
        x
    } else {
        x * if winv[r] != 0.0 { 1.0 } else { 0.0 }
    }
}

/// The visit of the contact whose rows are r, r + 1, r + 2 (its normal and
/// tangent pair): λ and Δv' (`dv`) updated, its measure in `carry`. `LIVE`:
/// every one of the three rows has 1/Wᵣᵣ ≠ 0; `PLAIN`: `relax` is 1 (the
/// same bits as the general visit either way).
///
/// # Safety
/// r + 2 < n (the rows' count); row r's path lies in `table` and is at most
/// `st` long, its dofs < `dv.len()`; `y` holds n·`st` entries (the sweeps'
/// checks, `Rows::sweeps_as`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) unsafe fn visit<const SKIP: bool, const LIVE: bool, const PLAIN: bool>(
    f: &Fixed<'_>,
    r: usize,
    relax: f64,
    first: bool,
    tol: f64,
    lambda: &mut [f64],
    dv: &mut [f64],
    carry: &mut Carry<'_>,
) {
    debug_assert!(!PLAIN || relax == 1.0);
    debug_assert!(!LIVE || (r..r + 3).all(|q| f.winv[q] != 0.0));
    let (y, st, w, winv, c, b) = (f.y, f.st, f.w, f.winv, f.c, f.b);
    // SAFETY: the caller's (row r's path in `table`)
    let p = unsafe {
        let (s, l) = *f.paths.get_unchecked(r);
        f.table.get_unchecked(s..s + l)
    };
    // the three dots side by side over their rows of y (each a sum from 0
    // in path order)
    // SAFETY: the caller's: (r + 2)·st + len ≤ n·st ≤ y.len(), the path's
    // dofs < dv.len()
    let [dn, d1, d2] = unsafe { dot3_at(y, r * st, st, p, dv) };
    let [wn1, wn2, w12] = f.w_block[r];
    let (wnn, w11, w22) = (w[r], w[r + 1], w[r + 2]);
    let on = lambda[r];
    let un = c[r] + dn;
    // λₙ ← max(0, λₙ − ω (uₙ − bₙ)/Wₙₙ)
    let step = if PLAIN {
        (un - b[r]) * winv[r]
    } else {
        relax * (un - b[r]) * winv[r]
    };
    let nn = live::<LIVE>(winv, r, (on - step).max(0.0));
    let dln = nn - on;
    lambda[r] = nn;
    let (o1, o2) = (lambda[r + 1], lambda[r + 2]);
    // uₜ = cₜ + yₜ·Δv' + Δλₙ Wₙₜ (the normal's change through the block)
    let u1 = c[r + 1] + d1 + dln * wn1;
    let u2 = c[r + 2] + d2 + dln * wn2;
    if on == 0.0 && nn == 0.0 && o1 == 0.0 && o2 == 0.0 {
        // an inactive contact that stays so (λₙ = 0, uₙ ≥ bₙ): μλₙ = 0 pins
        // both tangents at 0, nothing moves, and each row's measure is its
        // residual 0; only the velocities are kept for the next sweep's
        // measure (the tangents may keep a zero of the other sign)
        carry.u_prev[r] = un;
        carry.u_prev[r + 1] = u1;
        carry.u_prev[r + 2] = u2;
        if SKIP && f.skip {
            carry.until[r] = pinned_until(carry.drift, un - b[r], un, wnn);
            carry.armed |= carry.until[r] > f64::NEG_INFINITY;
        }
        return;
    }
    let mu = match f.kinds[r + 1] {
        RowKind::Tangent { mu, .. } => mu,
        _ => 0.0,
    };
    // λₜ ← λₜ − uₜ/Wₜₜ, row by row
    let mut t1 = live::<LIVE>(winv, r + 1, o1 - u1 * winv[r + 1]);
    let mut t2 = live::<LIVE>(winv, r + 2, o2 - u2 * winv[r + 2]);
    let lim = mu * nn;
    if t1 * t1 + t2 * t2 > lim * lim {
        // w̄ = (W₁₁ + W₂₂)/2 + √(((W₁₁ − W₂₂)/2)² + W₁₂²)
        let half = 0.5 * (w11 - w22);
        let wbar = 0.5 * (w11 + w22) + (half * half + w12 * w12).sqrt();
        let (s1, s2) = slide_onto_cone(o1, o2, u1, u2, wbar, lim);
        t1 = live::<LIVE>(winv, r + 1, s1);
        t2 = live::<LIVE>(winv, r + 2, s2);
    }
    lambda[r + 1] = t1;
    lambda[r + 2] = t2;
    let (dl1, dl2) = (t1 - o1, t2 - o2);
    if dln != 0.0 || dl1 != 0.0 || dl2 != 0.0 {
        // Δv' += Δλₙ yₙ + Δλ₁ y₁ + Δλ₂ y₂ over the path
        let l = p.len();
        // SAFETY: r + 2 < n and l ≤ st (the caller's), and y holds n·st
        // entries
        let yr = |q: usize| unsafe { y.get_unchecked(q * st..q * st + l) };
        let at = Path::of(p);
        let ys = [yr(r), yr(r + 1), yr(r + 2)];
        // SAFETY: each of ys is l = the path's length
        unsafe { axpy3_path([dln, dl1, dl2], ys, at, dv) };
        if SKIP && carry.armed {
            carry.drift += dln.abs() * wnn.sqrt() + dl1.abs() * w11.sqrt() + dl2.abs() * w22.sqrt();
        }
        if let Some(lb) = f.lb {
            lb.follow(f.view, r, &[dln, dl1, dl2], lambda, dv);
        }
    }
    let up = &mut carry.u_prev[r..r + 3];
    if carry.change > tol {
        // a sweep over `tol` already stays over whatever its other rows
        // measure (`change` only grows): their velocities kept for the next,
        // no measure
        (up[0], up[1], up[2]) = (un, u1, u2);
    } else {
        let mut change = carry.change;
        change = most(change, measure(first, (dln * wnn).abs(), un, &mut up[0]));
        change = most(change, measure(first, (dl1 * w11).abs(), u1, &mut up[1]));
        change = most(change, measure(first, (dl2 * w22).abs(), u2, &mut up[2]));
        carry.change = change;
    }
}
