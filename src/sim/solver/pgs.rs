//! Projected Gauss–Seidel on W = Y Yᵀ (the velocity solve), with a
//! contact's three rows taken in one pass and the exact Coulomb slide onto
//! the friction disc.

use super::kernels::{pinned_until, slide_onto_cone, warm_rows};
use super::loop_block::{BlockRows, LoopBlock};
use super::subspace::{subspace_step, Solved, Subspace};
use super::{MassFactor, RowKind, Rows, SUBSPACE_MAX};
use contact::{visit, Carry, Fixed};

mod contact;

impl Rows {
    /// Projected Gauss–Seidel on W = Y Yᵀ, kept implicit: Δv' = Yᵀλ is carried
    /// along (in `dv`, length nv) so that a row's velocity is uᵣ = cᵣ + yᵣ·Δv',
    /// O(path length) a row; the caller recovers Δv = R⁻¹ Δv'. Stops when no
    /// row's velocity changes by more than `tol` (m/s or rad/s) in a sweep, or
    /// after `max_iter` sweeps; returns the sweeps. Rows with a (numerically)
    /// zero diagonal stay at 0. After three plain sweeps, the scalar rows
    /// (contact normals, joint friction and limits) are over-relaxed by `relax`
    /// ∈ (0, 2) (projected SOR, convergent for the positive semi-definite W in
    /// that range; 1 is plain Gauss–Seidel) until converged, then one plain
    /// sweep ends the solve; the tangent pairs, projected onto the friction
    /// disc, are never over-relaxed. A solve still unconverged after half of
    /// `max_iter` sweeps goes on with plain sweeps.
    pub fn solve(
        &mut self,
        f: &MassFactor,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> usize {
        let _ = f;
        let all = [(0, 0, self.n)];
        self.solve_runs(&all, None, dv, max_iter, tol, relax)
    }

    /// [`Rows::solve`] on the rows of `runs` only ((key, start, end): an
    /// island's rows, [`super::super::islands`]), whose Δv' lives on `dofs`
    /// (`None`: every dof): only those entries of `dv` are zeroed and written.
    pub(crate) fn solve_runs(
        &mut self,
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> usize {
        let mut lambda = std::mem::take(&mut self.lambda);
        let mut u_prev = std::mem::take(&mut self.u_prev);
        let mut sm = Scratch(std::mem::replace(&mut self.sm, Subspace::new(0, 0)));
        let mut out = IslandOut {
            lambda: &mut lambda,
            u_prev: &mut u_prev,
            sm: &mut sm,
            warm_given: false,
        };
        let (it, polished) = self.sweeps(&mut out, runs, dofs, dv, max_iter, tol, relax);
        self.lambda = lambda;
        self.u_prev = u_prev;
        self.sm = sm.0;
        self.polished = polished;
        it
    }

    /// Takes out what the sweeps write (impulses, each row's last velocity),
    /// so that several islands can be solved at once on the rows left
    /// read-only ([`Rows::sweeps`]); [`Rows::put_written`] puts them back.
    pub(crate) fn take_written(&mut self) -> (Vec<f64>, Vec<f64>) {
        (
            std::mem::take(&mut self.lambda),
            std::mem::take(&mut self.u_prev),
        )
    }
    /// Puts back what [`Rows::take_written`] took.
    pub(crate) fn put_written(&mut self, w: (Vec<f64>, Vec<f64>)) {
        (self.lambda, self.u_prev) = w;
    }
    /// A subspace step's scratch, one for each thread solving islands.
    pub(crate) fn scratch(&self) -> Scratch {
        Scratch(Subspace::new(self.nv, self.cap))
    }

    /// Projected Gauss–Seidel ([`Rows::solve`]) on the rows of `runs`, the
    /// rows read-only: it writes the impulses and row velocities in `out`
    /// (taken out of the rows, [`Rows::take_written`]) and `dv` on `dofs`
    /// only. Returns the sweeps and whether a subspace step was taken.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn sweeps(
        &self,
        out: &mut IslandOut<'_>,
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> (usize, bool) {
        // rows pinned at a bound skipped while provably still pinned
        // ([`pinned_until`]) on islands of a robot's joints, where joint
        // friction sits at its bound and self-collision pairs wait apart; on
        // free bodies' islands no row is armed: their contacts are nearly all
        // active, and the bookkeeping would cost more than it skips. Those
        // islands run the sweeps compiled without it (`SKIP` false: not one
        // test of it in their loop)
        let jointed = |d: &[usize]| d.iter().any(|&k| self.jointed.get(k) == Some(&true));
        if out.sm.0.until.len() >= self.n && self.any_jointed && dofs.is_none_or(jointed) {
            self.sweeps_as::<true>(out, runs, dofs, dv, max_iter, tol, relax)
        } else {
            self.sweeps_as::<false>(out, runs, dofs, dv, max_iter, tol, relax)
        }
    }

    /// [`Rows::sweeps`], pinned rows skipped if `SKIP` (and no loop block).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn sweeps_as<const SKIP: bool>(
        &self,
        out: &mut IslandOut<'_>,
        runs: &[(usize, usize, usize)],
        dofs: Option<&[usize]>,
        dv: &mut [f64],
        max_iter: usize,
        tol: f64,
        relax: f64,
    ) -> (usize, bool) {
        let table = &self.table[..];
        let (nv, n, st) = (self.nv, self.n, self.stride);
        if dv.len() < nv
            || self.y.len() < n * st
            || self.kind.len() < n
            || runs.iter().any(|&(_, s, e)| {
                e > n
                    || self.path[s..e]
                        .iter()
                        .any(|&(s, l)| s + l > table.len() || l > st)
            })
            || dofs.is_some_and(|d| d.iter().any(|&k| k >= nv))
            || out.lambda.len() < n
            || out.u_prev.len() < n
        {
            return (0, false);
        }
        let dv = &mut dv[..nv];
        let (y, paths) = (&self.y[..], &self.path[..n]);
        let (kinds, c, b) = (&self.kind[..n], &self.c[..n], &self.b[..n]);
        let contact = &self.is_block[..n];
        // no factor of an earlier solve's W_FF is reused (subspace.rs)
        out.sm.0.forget();
        // the loop rows as one exact block, every other row seen through them
        // (the reduced W', loop_block.rs): taken out for the solve
        // (without a bilateral row not even taken, none made: nothing to move)
        let mut own = self.bilateral.then(|| std::mem::take(&mut out.sm.0.loops));
        let view = BlockRows {
            st,
            y,
            paths,
            table,
        };
        let block = own
            .as_mut()
            .is_some_and(|lb| lb.prepare(&view, runs, kinds, &self.w[..n]));
        if let Some(lb) = own.as_mut().filter(|_| block) {
            let (w, wb, wi) = (&self.w[..n], &self.w_block[..n], &self.winv[..n]);
            lb.reduce(&view, runs, kinds, contact, w, wb, wi);
        }
        // (the block when it is in the solve)
        let lb: Option<&LoopBlock> = own.as_ref().filter(|_| block);
        let (w, w_block, winv) = match lb {
            Some(lb) => (&lb.wr[..n], &lb.wblockr[..n], &lb.winvr[..n]),
            None => (&self.w[..n], &self.w_block[..n], &self.winv[..n]),
        };
        let u_prev = &mut out.u_prev[..n];
        let lambda = &mut out.lambda[..n];
        // rows pinned at a bound skipped while provably still pinned
        // ([`pinned_until`]): `drift` bounds ‖Δv'‖ since the first was
        // (every entry of `until` is −∞ between solves)
        // (without `SKIP` not even taken: nothing of it live in the loop)
        let mut until = if SKIP {
            std::mem::take(&mut out.sm.0.until)
        } else {
            Vec::new()
        };
        let skip = SKIP && !block && until.len() >= n;
        // (only once some row is pinned: `armed`; never without `SKIP`)
        let (mut drift, mut armed) = (0.0, false);
        // SAFETY (unchecked reads in rdot/raxpy): every path lies in `table`
        // (checked above) and holds dof indices < nv; y holds n·stride entries and
        // a path is at most stride long.
        #[inline(always)]
        fn rdot(y: &[f64], r: usize, st: usize, p: &[usize], x: &[f64]) -> f64 {
            let mut s = 0.0;
            for (t, &k) in p.iter().enumerate() {
                s += unsafe { y.get_unchecked(r * st + t) * x.get_unchecked(k) };
            }
            s
        }
        #[inline(always)]
        fn raxpy(a: f64, y: &[f64], r: usize, st: usize, p: &[usize], x: &mut [f64]) {
            for (t, &k) in p.iter().enumerate() {
                unsafe { *x.get_unchecked_mut(k) += a * y.get_unchecked(r * st + t) };
            }
        }
        let path = |r: usize| {
            let (s, l) = paths[r];
            &table[s..s + l]
        };
        // Δv' from the warm start (given: already in `dv` on the island's
        // dofs, [`Rows::warm_velocity`])
        let given = std::mem::replace(&mut out.warm_given, false);
        match dofs {
            _ if given => {}
            Some(d) => d.iter().for_each(|&k| dv[k] = 0.0),
            None => dv.iter_mut().for_each(|x| *x = 0.0),
        }
        for &(_, s, e) in runs {
            if given {
                break;
            }
            // SAFETY: the paths and y checked above (rdot/raxpy's)
            unsafe { warm_rows(lambda, contact, paths, table, y, st, (s, e), dv) };
        }
        if let Some(lb) = lb {
            lb.solve(&view, Some(c), b, lambda, dv);
        }
        let mut it = 0;
        // plain sweeps first; a problem not solved in `PLAIN` sweeps is
        // over-relaxed, and once that has converged one plain sweep finishes it
        // (every row then leaves its own residual exactly 0 or projected, as
        // Gauss–Seidel does)
        const PLAIN: usize = 3;
        let mut finishing = false;
        let mut attempts = 0;
        let mut polished = false;
        let mut converged = false;
        // what a contact's visit reads (contact.rs)
        let fixed = Fixed {
            y,
            st,
            paths,
            table,
            kinds,
            w,
            w_block,
            winv,
            c,
            b,
            lb,
            view: &view,
            skip,
        };
        // every row of the island fits one subspace step
        let small = runs.iter().map(|&(_, s, e)| e - s).sum::<usize>() <= SUBSPACE_MAX;
        while it < max_iter {
            it += 1;
            let plain = it <= PLAIN || finishing || polished || 2 * it > max_iter || relax == 1.0;
            let relax = if plain { 1.0 } else { relax };
            let first = it == 1;
            let mut change: f64 = 0.0;
            for &(_, s, e) in runs {
                let mut r = s;
                while r < e {
                    let kind = kinds[r];
                    if contact[r] {
                        // (rows r..r + 3 are a contact's: form made it so;
                        // one test here spares the rows' reads theirs)
                        debug_assert!(r + 2 < n);
                        if r + 2 >= n {
                            break;
                        }
                        if SKIP && armed && drift < until[r] {
                            // an inactive contact that provably stays so:
                            // nothing moves, no measure (its velocity unknown:
                            // the next measure, if it wakes, is its residual)
                            u_prev[r] = f64::NAN;
                            u_prev[r + 1] = f64::NAN;
                            u_prev[r + 2] = f64::NAN;
                            r += 3;
                            continue;
                        }
                        // a contact's three rows in one pass over its path
                        // (contact.rs), the copy without `live`'s factors when
                        // all three rows are live, without `relax` in a plain
                        // sweep
                        let alive = winv[r] != 0.0 && winv[r + 1] != 0.0 && winv[r + 2] != 0.0;
                        let mut carry = Carry {
                            u_prev: &mut u_prev[..],
                            until: &mut until[..],
                            change,
                            drift,
                            armed,
                        };
                        let (l, dv) = (&mut lambda[..], &mut dv[..]);
                        // SAFETY: r is a row of `runs`, whose paths lie in
                        // `table` and are at most `st` long, their dofs < nv ≤
                        // dv.len() (checked above), and r + 2 < n (tested
                        // above); y holds n·st entries
                        unsafe {
                            match (alive, plain) {
                                (true, true) => visit::<SKIP, true, true>(
                                    &fixed, r, relax, first, tol, l, dv, &mut carry,
                                ),
                                (true, false) => visit::<SKIP, true, false>(
                                    &fixed, r, relax, first, tol, l, dv, &mut carry,
                                ),
                                (false, _) => visit::<SKIP, false, false>(
                                    &fixed, r, relax, first, tol, l, dv, &mut carry,
                                ),
                            }
                        }
                        (change, drift, armed) = (carry.change, carry.drift, carry.armed);
                        r += 3;
                        continue;
                    }
                    match kind {
                        RowKind::Bilateral if block => {
                            r += 1;
                            continue;
                        }
                        RowKind::Tangent { normal, mu } if r + 1 < e => {
                            let (p1, p2) = (path(r), path(r + 1));
                            let (w11, w22) = (w[r], w[r + 1]);
                            let u1 = c[r] + rdot(y, r, st, p1, dv);
                            let u2 = c[r + 1] + rdot(y, r + 1, st, p2, dv);
                            let (o1, o2) = (lambda[r], lambda[r + 1]);
                            let mut t1 = if w11 > 1e-14 { o1 - u1 / w11 } else { 0.0 };
                            let mut t2 = if w22 > 1e-14 { o2 - u2 / w22 } else { 0.0 };
                            let ln = lambda.get(normal).copied().unwrap_or(0.0);
                            let lim = mu * if ln > 0.0 { ln } else { 0.0 };
                            if t1 * t1 + t2 * t2 > lim * lim {
                                // the block's largest eigenvalue ≤ its trace
                                (t1, t2) = slide_onto_cone(o1, o2, u1, u2, w11 + w22, lim);
                            }
                            lambda[r] = t1;
                            lambda[r + 1] = t2;
                            let (d1, d2) = (t1 - o1, t2 - o2);
                            if d1 != 0.0 {
                                raxpy(d1, y, r, st, p1, dv);
                                drift += if SKIP && armed {
                                    d1.abs() * w11.sqrt()
                                } else {
                                    0.0
                                };
                            }
                            if d2 != 0.0 {
                                raxpy(d2, y, r + 1, st, p2, dv);
                                drift += if SKIP && armed {
                                    d2.abs() * w22.sqrt()
                                } else {
                                    0.0
                                };
                            }
                            if let Some(lb) = lb {
                                lb.follow(&view, r, &[d1, d2], lambda, dv);
                            }
                            change =
                                most(change, measure(first, (d1 * w11).abs(), u1, &mut u_prev[r]));
                            change = most(
                                change,
                                measure(first, (d2 * w22).abs(), u2, &mut u_prev[r + 1]),
                            );
                            r += 2;
                            continue;
                        }
                        RowKind::Tangent2 | RowKind::Tangent { .. } => {
                            r += 1;
                            continue;
                        }
                        _ => {}
                    }
                    if SKIP && armed && drift < until[r] {
                        // pinned at its bound, provably still (as a contact's)
                        u_prev[r] = f64::NAN;
                        r += 1;
                        continue;
                    }
                    let wrr = w[r];
                    let old = lambda[r];
                    let p = path(r);
                    let mut u = 0.0;
                    let new = if winv[r] != 0.0 {
                        u = c[r] + rdot(y, r, st, p, dv);
                        let x = old - relax * (u - b[r]) * winv[r];
                        match kind {
                            RowKind::Box { limit } => x.clamp(-limit, limit),
                            RowKind::Bilateral => x,
                            _ => x.max(0.0),
                        }
                    } else {
                        0.0
                    };
                    lambda[r] = new;
                    let d = new - old;
                    if d != 0.0 {
                        raxpy(d, y, r, st, p, dv);
                        if SKIP && armed {
                            drift += d.abs() * wrr.sqrt();
                        }
                        if let Some(lb) = lb.filter(|lb| lb.couples(r)) {
                            lb.follow(&view, r, &[d], lambda, dv);
                        }
                    } else if skip && winv[r] != 0.0 {
                        // held at a bound by its velocity: the margin it has
                        let slack = match kind {
                            RowKind::Box { limit } if limit > 0.0 && old == limit => b[r] - u,
                            RowKind::Box { limit } if limit > 0.0 && old == -limit => u - b[r],
                            RowKind::Unilateral | RowKind::Normal if old.to_bits() == 0 => u - b[r],
                            _ => f64::NAN,
                        };
                        until[r] = pinned_until(drift, slack, u, wrr);
                        armed |= until[r] > f64::NEG_INFINITY;
                    }
                    change = most(change, measure(first, (d * wrr).abs(), u, &mut u_prev[r]));
                    r += 1;
                }
            }
            if let Some(lb) = lb {
                // (rounding only: every update above kept the loop rows on target)
                change = most(change, lb.solve(&view, Some(c), b, lambda, dv));
            }
            if finishing || (change <= tol && plain) {
                converged = true;
                break;
            }
            if change <= tol {
                finishing = true;
            } else if it >= SUBSPACE_AFTER
                && attempts < SUBSPACE_TRIES
                && (attempts + 1 < SUBSPACE_TRIES || !small || it >= SUBSPACE_LAST)
                && it + 1 < max_iter
            {
                // slow linear convergence (coupled rows): solve the rows
                // the sweeps left free exactly, then let plain sweeps check
                // (on an island whose rows all fit one step, the last try
                // waits until the sweeps have settled which pairs stick and
                // which slide)
                attempts += 1;
                let rows = Solved {
                    n,
                    runs,
                    nv,
                    st,
                    y,
                    paths,
                    table,
                    kinds,
                    contact,
                    winv,
                    c,
                    b,
                    diag: (&self.w[..n], &self.w_block[..n]),
                };
                if subspace_step(&mut out.sm.0, &rows, lambda, dv) {
                    polished = true;
                    // Δv' moved outside `drift`: every row looked at again
                    if SKIP && armed {
                        for &(_, s, e) in runs {
                            until[s..e].fill(f64::NEG_INFINITY);
                        }
                        (drift, armed) = (0.0, false);
                    }
                    if let Some(lb) = lb {
                        lb.solve(&view, Some(c), b, lambda, dv);
                    }
                }
            }
        }
        // a converged island on joints: its self-stress shed (stress.rs)
        if converged && !block && self.sheds(dofs) {
            self.shed_self_stress(&mut out.sm.0, runs, lambda, dv, tol);
        }
        if let Some(lb) = own {
            out.sm.0.loops = lb;
        }
        if SKIP && armed {
            for &(_, s, e) in runs {
                until[s..e].fill(f64::NEG_INFINITY);
            }
        }
        if SKIP {
            out.sm.0.until = until;
        }
        (it, polished)
    }
}

/// A row's convergence measure: its own residual |Δλ|·Wᵣᵣ, or, when
/// smaller, how much its velocity moved since the last sweep (redundant
/// contacts can trade impulse among themselves for many sweeps while no
/// velocity changes: that is converged)
/// (on the first sweep the residual alone: `moved` taken as ∞; the
/// smaller of the two by one compare, `minsd`: a NaN `moved` leaves the
/// residual, as `f64::min` did)
#[inline(always)]
fn measure(first: bool, residual: f64, u: f64, prev: &mut f64) -> f64 {
    let moved = (u - *prev).abs();
    *prev = u;
    let moved = if first { f64::INFINITY } else { moved };
    if moved < residual {
        moved
    } else {
        residual
    }
}

/// The larger of a convergence measure `change` (never NaN) and `x`: as
/// `change.max(x)` (a NaN `x` leaves `change`), one compare.
#[inline(always)]
fn most(change: f64, x: f64) -> f64 {
    if x > change {
        x
    } else {
        change
    }
}

/// What one island's sweeps write besides Δv': the rows' impulses and last
/// velocities (whole-length, taken out of the rows; an island writes its own
/// rows only) and the subspace step's scratch.
pub(crate) struct IslandOut<'a> {
    /// Every row's impulse.
    pub lambda: &'a mut [f64],
    /// Every row's velocity at its last update.
    pub u_prev: &'a mut [f64],
    /// The subspace step's scratch.
    pub sm: &'a mut Scratch,
    /// `dv` holds the island's Δv' at its warm start already (the next
    /// sweeps skip making it, and clear this).
    pub warm_given: bool,
}

/// A subspace step's scratch ([`Rows::scratch`]).
#[derive(Clone, Debug)]
pub(crate) struct Scratch(pub(super) Subspace);

/// Sweeps before the first subspace step, and the most a solve takes.
const SUBSPACE_AFTER: usize = 2;
const SUBSPACE_TRIES: usize = 3;
/// The sweep from which a solve's last subspace step may be taken on an
/// island of at most [`SUBSPACE_MAX`] rows (the others follow sweeps 2 and 3;
/// larger islands try again at sweep 4). A free set picked that early often
/// has a pair the next sweeps move between sticking and sliding; on
/// Gymnasium's ant landing on four feet with its ankles on their limits (16
/// rows), a last step at sweep 4 left 10–20 sweeps of slow convergence a step,
/// one at sweep 7 finishes the solve (docs/theory.md §"Constraint solve").
const SUBSPACE_LAST: usize = 7;
