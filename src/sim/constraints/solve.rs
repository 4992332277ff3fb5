//! The solve of the assembled rows, island by island (src/sim/islands.rs):
//! the velocity impulses (warm-started projected Gauss–Seidel), the
//! energy-safe exit of a solve stopped by its cap, and the position pass,
//! each on one island's rows and dofs, so that no cost grows with the square
//! of the scene; then what the impulses do (forces, warm starts).

use super::super::islands::{Island, Islands};
use super::super::parallel::{self, Team};
use super::super::solver::{IslandOut, Scratch};
use super::*;
use std::sync::atomic::{AtomicUsize, Ordering};

impl Constraints {
    /// Solves the assembled rows given the factor `l` of H̃ (column-major, lower
    /// triangle) and the free velocity `vfree`, for a step `h`: the velocity
    /// impulses λ (warm-started), then, where a row is violated, the position
    /// pass. Writes the warm starts, the joint rows' generalized force and the
    /// contact forces.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        model: &Model,
        points: &[ContactPoint],
        f: &MassFactor,
        vfree: &DVector<f64>,
        h: f64,
        iterations: usize,
        tol: f64,
        relaxation: f64,
        solver: Solver,
    ) -> Impulses<'_> {
        self.clear_forces();
        // torsion and rolling rows (spin.rs) couple a point's rotation to its
        // normal: a step with them may take twice the sweeps before the cap
        let iterations = iterations * if self.counts.spin > 0 { 2 } else { 1 };
        let rows = &mut self.rows;
        // Y rows = R⁻ᵀ jᵣ (H̃ = RᵀR, each over its path): W = J H̃⁻¹ Jᵀ = Y Yᵀ,
        // the solver works on Δv' = R Δv with uᵣ = cᵣ + yᵣ·Δv' (on the team
        // by ranges of rows where they are many)
        rows.form_on(f, vfree.as_slice(), self.team.as_deref());
        let all = [(0, 0, rows.n)];
        let whole = Island {
            runs: &all,
            dofs: &[],
        };
        let mut sweeps = 0;
        if solver == Solver::Pgs {
            // each island on its own (on several threads: docs/theory.md
            // §"Islands"), every island's result independent of the others'
            self.islands.group(rows);
            let written = rows.take_written();
            let (mut lam, mut up) = written;
            let dv = self.dv.as_mut_slice();
            let args = (iterations, tol, relaxation);
            // every island's warm start, made in the grouping: the first
            // solves take it ([`Islands::warm`]), every entry of Δv' written;
            // else Δv' from zeros (a dof on no island's rows stays 0)
            let mut given = false;
            if let Some(w) = self.islands.warm()
                && w.len() == dv.len()
            {
                dv.copy_from_slice(w);
                given = true;
            } else {
                dv.fill(0.0);
            }
            // every island, then those a left-out contact that failed its
            // check joined (src/sim/islands/split.rs), until none fails
            let mut a_ready = false;
            let mut first = true;
            loop {
                let todo = self.islands.todo();
                if self.isl_sweeps.len() < todo.len() {
                    self.isl_sweeps.resize(todo.len(), 0);
                }
                let done = &mut self.isl_sweeps[..todo.len()];
                let (isl, order) = (&self.islands, &mut self.order);
                let sizes = todo.iter().map(|&i| isl.get(i).rows());
                // (worth a dispatch where the cut takes enough sweeps off this
                // thread: at the last solve's sweeps per row)
                let least = (MIN_WORK as f64 / self.per_row.max(1.0)) as usize;
                let cut = |t: &&Arc<Team>| parallel::cut(sizes, t.threads(), least, order);
                let team = self.team.as_ref().filter(cut);
                match team {
                    Some(team) => {
                        // a = R v* for the threads' energy-safe exits, before them
                        if !a_ready {
                            f.apply_r(vfree.as_slice(), &mut self.a);
                            a_ready = true;
                        }
                        par_islands(
                            team,
                            rows,
                            (&self.islands, todo, &self.order),
                            &mut self.scratch,
                            done,
                            (&mut lam, &mut up, &mut *dv),
                            (&self.a[..], iterations, tol, relaxation),
                            given && first,
                        )
                    }
                    None => {
                        let mut out = IslandOut {
                            lambda: &mut lam,
                            u_prev: &mut up,
                            sm: &mut self.scratch[0],
                            warm_given: false,
                        };
                        // a = R v* only if an island's energy-safe exit needs it
                        let mut a = FreeR::Lazy(f, vfree.as_slice(), &mut self.a[..], a_ready);
                        for (&i, s) in todo.iter().zip(done.iter_mut()) {
                            let isl = self.islands.get(i);
                            out.warm_given = given && first;
                            *s = solve_island(rows, &mut out, &isl, dv, &mut a, args);
                        }
                        a_ready = a.ready();
                    }
                }
                let (mut rows_all, mut work) = (0, 0);
                for (&i, &s) in todo.iter().zip(self.isl_sweeps.iter()) {
                    let r = self.islands.get(i).rows();
                    (rows_all, work) = (rows_all + r, work + r * s);
                    self.work += (r * s) as u64;
                    sweeps = sweeps.max(s);
                }
                if first && rows_all > 0 {
                    self.per_row = work as f64 / rows_all as f64;
                }
                if !self.islands.join_failed(rows, dv, tol) {
                    break;
                }
                first = false;
            }
            rows.put_written((lam, up));
        } else {
            // Newton: the whole scene at once; a solve stopped by the cap is
            // scaled onto the exact solution's energy bound, never swept
            let dv = self.dv.as_mut_slice();
            dv.fill(0.0);
            let mut s = self.newton.solve(rows, f, dv, iterations, tol);
            if s >= iterations {
                f.apply_r(vfree.as_slice(), &mut self.a);
                let (mut lam, mut up) = rows.take_written();
                let mut out = IslandOut {
                    lambda: &mut lam,
                    u_prev: &mut up,
                    sm: &mut self.scratch[0],
                    warm_given: false,
                };
                let d = self.dv.as_mut_slice();
                s += energy_safe_exit(rows, &mut out, &whole, None, &self.a, d, 0, tol);
                rows.put_written((lam, up));
            }
            self.work += (whole.rows() * s) as u64;
            sweeps = s;
        }
        let pgs = solver == Solver::Pgs;
        fn dofs<'a>(pgs: bool, isl: &Island<'a>) -> Option<&'a [usize]> {
            pgs.then_some(isl.dofs)
        }
        // the position pass, only on the islands where something is violated
        // (it reads neither Δv' nor Δv: Δv = R⁻¹ Δv' is taken after it,
        // with w = R⁻¹ w' in the same pass over the factor)
        let pushing = self.counts.violated > 0;
        if pushing {
            self.push.as_mut_slice().fill(0.0);
            rows.mu[..rows.n].fill(0.0);
            let (rp, wc) = (&self.row_point, &self.warm_contact);
            let (jr, fj, wj) = (&self.joint_rows, self.first_joint_row, &self.warm_joint);
            let warm = self.pos_warm.gather(rows.n, rp, points, wc, fj, jr, wj);
            // on the islands of every contact: the left-out ones on an island
            // the pass pushes join it first (src/sim/islands/split.rs), as a
            // pushed body often closes a left-out point's gap
            if pgs {
                self.islands.join_pushed(rows);
            }
            let count = if pgs { self.islands.len() } else { 1 };
            for i in 0..count {
                let isl = if pgs { self.islands.get(i) } else { whole };
                if pgs && !isl.runs.iter().any(|&(_, s, e)| rows.violated(s, e)) {
                    continue;
                }
                let dw = self.push.as_mut_slice();
                let d = dofs(pgs, &isl);
                let s = rows.solve_position_runs(isl.runs, d, dw, iterations, tol, Some(warm));
                self.work += (isl.rows() * s) as u64;
            }
            // Δv = R⁻¹ Δv', w = R⁻¹ w'
            f.half_solve2(self.dv.as_mut_slice(), self.push.as_mut_slice());
        } else {
            // Δv = R⁻¹ Δv'
            f.half_solve(self.dv.as_mut_slice());
        }
        if let Some(l) = self.loops.as_mut() {
            l.read(rows);
        }
        // joint rows: warm starts (λ, and the position pass's μ of a limit
        // where it ran and pushed) and generalized force
        for w in self.warm_joint.iter_mut() {
            *w = [0.0; 5];
        }
        self.tau_written |= !self.joint_rows.is_empty();
        for (k, &(d, which)) in self.joint_rows.iter().enumerate() {
            let r = self.first_joint_row + k;
            let lam = rows.lambda[r];
            self.warm_joint[d][which as usize] = lam;
            let mu = match pushing {
                true => rows.mu[..rows.n].get(r).copied().unwrap_or(0.0),
                false => 0.0,
            };
            if which > 0 && mu > 0.0 {
                self.warm_joint[d][PosWarm::limit_entry(which)] = mu;
            }
            let iv = model.dof_v(d);
            let jv = joint_entry(rows, r, iv);
            self.tau_joint[iv] += jv * lam / h;
        }
        // contact rows: warm starts by slot, forces
        for &k in &self.warm_slots {
            if let Some(w) = self.warm_contact.get_mut(k) {
                *w = [0.0; 4];
            }
        }
        self.warm_slots.clear();
        for (c, &pi) in self.row_point.iter().enumerate() {
            let rn = 3 * c;
            let (ln, l1, l2) = (rows.lambda[rn], rows.lambda[rn + 1], rows.lambda[rn + 2]);
            let Some(pt) = points.get(pi) else {
                continue;
            };
            if let Some(w) = self.warm_contact.get_mut(pt.slot) {
                // (the position pass's μ only where it ran and pushed)
                let mu = match pushing {
                    true => rows.mu[..rows.n].get(rn).copied().unwrap_or(0.0),
                    false => 0.0,
                };
                *w = [ln, l1, l2, if mu > 0.0 { mu } else { 0.0 }];
                self.warm_slots.push(pt.slot);
            }
            if ln > 0.0 {
                // F = (λₙ n + λₜ₁ t₁ + λₜ₂ t₂)/Δt on `body`, −F on `other`
                let f = if pt.normal == Vector3::z() {
                    Vector3::new(l1, l2, ln) / h
                } else {
                    let (t1, t2) = tangents(&pt.normal);
                    (pt.normal * ln + t1 * l1 + t2 * l2) / h
                };
                if let Some(fb) = self.fext.get_mut(pt.body) {
                    *fb += Force::at_point(f, &pt.point);
                }
                if pt.other != 0 {
                    if let Some(fb) = self.fext.get_mut(pt.other) {
                        *fb += Force::at_point(-f, &pt.point);
                    }
                }
                self.contact_forces.push(ContactForce {
                    point: *pt,
                    force: f,
                });
            }
        }
        // torsional and rolling friction torques
        self.spin
            .add_torques(rows, points, &self.row_point, &mut self.fext, h);
        Impulses {
            dv: &self.dv,
            push: if pushing { Some(&self.push) } else { None },
            tau_joint: &self.tau_joint,
            sweeps,
        }
    }
}

/// J's entry of joint row `r` at its dof `iv`: the last of its path
/// (`MassFactor::path_of(iv)` ends at `iv`), else found by [`Rows::entry`].
#[inline]
fn joint_entry(rows: &Rows, r: usize, iv: usize) -> f64 {
    let (ps, pl) = rows.path[r];
    let last = (pl.checked_sub(1), rows.table().get(ps + pl.wrapping_sub(1)));
    match last {
        (Some(t), Some(&d)) if d == iv && t < rows.stride => rows.j[r * rows.stride + t],
        _ => rows.entry(r, iv),
    }
}

/// (ΔKE of the impulse, the exact solution's bound Σ λᵣ max(bᵣ, 0), a·d, ‖d‖²)
/// for the factored Δv' = `d` (a = R v*: the kinetic energy after the impulse
/// is ½‖a + d‖² in the H̃-norm), the impulses `lambda`.
/// Over the island's rows and `dofs` (`None`: every dof).
fn impulse_work(
    rows: &Rows,
    lambda: &[f64],
    isl: &Island<'_>,
    dofs: Option<&[usize]>,
    a: &[f64],
    d: &[f64],
) -> (f64, f64, f64, f64) {
    let (mut ad, mut dd) = (0.0, 0.0);
    match dofs {
        Some(ks) => {
            for &k in ks {
                let (ak, dk) = (a[k], d[k]);
                ad += ak * dk;
                dd += dk * dk;
            }
        }
        None => {
            for (ak, dk) in a.iter().zip(d) {
                ad += ak * dk;
                dd += dk * dk;
            }
        }
    }
    let mut allow = 0.0;
    for r in isl.each_row() {
        if matches!(rows.kind[r], RowKind::Normal | RowKind::Unilateral) {
            allow += lambda[r] * rows.b[r].max(0.0);
        }
    }
    (ad + 0.5 * dd, allow, ad, dd)
}

/// What every island's solve reads besides the rows: the sweep cap,
/// tolerance and over-relaxation.
type IslandArgs = (usize, f64, f64);

/// a = R v* (the free velocity's kinetic energy is ½‖a‖²), read only by an
/// energy-safe exit: computed before the solve (`Ready`), or at the first
/// exit that needs it (`Lazy`: the factor, v*, the buffer, whether done).
enum FreeR<'a> {
    Ready(&'a [f64]),
    Lazy(&'a MassFactor, &'a [f64], &'a mut [f64], bool),
}

impl FreeR<'_> {
    /// a is computed.
    fn ready(&self) -> bool {
        matches!(self, FreeR::Ready(_) | FreeR::Lazy(_, _, _, true))
    }
    /// a, computed here the first time for a `Lazy` one.
    fn get(&mut self) -> &[f64] {
        match self {
            FreeR::Ready(a) => a,
            FreeR::Lazy(f, v, a, done) => {
                if !*done {
                    f.apply_r(v, a);
                    *done = true;
                }
                a
            }
        }
    }
}

/// One island's velocity solve: warm-started PGS on its rows, written into
/// `out` and `dv` (on its dofs only); a solve stopped by its cap, or one that
/// took a subspace step (whose projection of a large step is not checked by
/// the sweeps' test alone), is held to the exact solution's energy bound.
/// Returns its sweeps.
fn solve_island(
    rows: &Rows,
    out: &mut IslandOut<'_>,
    isl: &Island<'_>,
    dv: &mut [f64],
    a: &mut FreeR<'_>,
    (iterations, tol, relax): IslandArgs,
) -> usize {
    let dofs = Some(isl.dofs);
    let (mut s, polished) = rows.sweeps(out, isl.runs, dofs, dv, iterations, tol, relax);
    if s >= iterations || polished {
        s += energy_safe_exit(rows, out, isl, dofs, a.get(), dv, iterations, tol);
    }
    s
}

/// Every row's impulse and last velocity and Δv', each thread's scratch and
/// each island's sweeps, shared by the threads solving islands at once
/// ([`par_islands`]).
#[derive(Clone, Copy)]
struct Shared {
    lambda: (*mut f64, usize),
    u_prev: (*mut f64, usize),
    dv: (*mut f64, usize),
    scratch: (*mut Scratch, usize),
    sweeps: (*mut usize, usize),
}
// SAFETY: the threads given a `Shared` read and write only the rows (of
// `lambda`, `u_prev`), dofs (of `dv`) and sweeps of the islands they took,
// and their own scratch: islands share no row and no dof
// (src/sim/islands.rs), an island is taken once (an atomic counter) and a
// thread has one scratch, so no element is touched by two threads.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// The islands `todo` of `islands` solved on the threads of `team`, each
/// thread taking the next island of `order` (largest first,
/// [`parallel::cut`]) until none is left; each island's result (its
/// impulses, its Δv', its sweeps in `sweeps`) is the one a single thread
/// computes, whichever thread takes it (bit for bit: nothing an island reads
/// is written by another).
#[allow(clippy::too_many_arguments)]
fn par_islands(
    team: &Team,
    rows: &Rows,
    (islands, todo, order): (&Islands, &[usize], &[(usize, usize)]),
    scratch: &mut [Scratch],
    sweeps: &mut [usize],
    (lambda, u_prev, dv): (&mut [f64], &mut [f64], &mut [f64]),
    (a, iterations, tol, relax): (&[f64], usize, f64, f64),
    given: bool,
) {
    let args = (iterations, tol, relax);
    let count = sweeps.len().min(todo.len());
    let sh = Shared {
        lambda: (lambda.as_mut_ptr(), lambda.len()),
        u_prev: (u_prev.as_mut_ptr(), u_prev.len()),
        dv: (dv.as_mut_ptr(), dv.len()),
        scratch: (scratch.as_mut_ptr(), scratch.len()),
        sweeps: (sweeps.as_mut_ptr(), count),
    };
    let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    team.run(&|k| {
        let sh = sh;
        if k >= sh.scratch.1 {
            return;
        }
        // SAFETY: see `Shared`; the pointers and lengths are those of live
        // slices borrowed for the whole of `run`, and thread k alone takes
        // scratch k (k < its length, checked)
        let (lambda, u_prev, dv, sm) = unsafe {
            (
                std::slice::from_raw_parts_mut(sh.lambda.0, sh.lambda.1),
                std::slice::from_raw_parts_mut(sh.u_prev.0, sh.u_prev.1),
                std::slice::from_raw_parts_mut(sh.dv.0, sh.dv.1),
                &mut *sh.scratch.0.add(k),
            )
        };
        let mut out = IslandOut {
            lambda,
            u_prev,
            sm,
            warm_given: false,
        };
        let mut a = FreeR::Ready(a);
        loop {
            let t = next.fetch_add(1, Ordering::Relaxed);
            let Some(&(_, j)) = order.get(t) else { break };
            let Some(&i) = todo.get(j).filter(|_| j < sh.sweeps.1) else {
                done.fetch_add(1, Ordering::Release);
                continue;
            };
            let isl = islands.get(i);
            out.warm_given = given;
            let s = solve_island(rows, &mut out, &isl, dv, &mut a, args);
            // SAFETY: j < the sweeps' length (checked); island j taken here alone
            unsafe { *sh.sweeps.0.add(j) = s };
            done.fetch_add(1, Ordering::Release);
        }
    });
    // (an island left undone: its thread panicked, as `run` lets it)
    assert!(
        done.load(Ordering::Acquire) >= order.len(),
        "a thread of the islands' solve panicked"
    );
}

/// A solve stopped by the sweep cap may leave an iterate that adds kinetic
/// energy, which the exact solution never does: its impulses change the kinetic
/// energy by λᵀu − ½λᵀWλ ≤ Σ λᵣ max(bᵣ, 0) (complementarity on the unilateral
/// rows, maximal dissipation on the friction rows). While the iterate exceeds
/// that bound, more plain sweeps run (up to 4× the cap); if it still does, the
/// impulses are scaled by the largest s ≤ 1 that meets it (a scaled impulse
/// stays inside every cone and box). `a` = R v*. Returns the extra sweeps.
#[allow(clippy::too_many_arguments)]
fn energy_safe_exit(
    rows: &Rows,
    out: &mut IslandOut<'_>,
    isl: &Island<'_>,
    dofs: Option<&[usize]>,
    a: &[f64],
    d: &mut [f64],
    iterations: usize,
    tol: f64,
) -> usize {
    let nv = rows.nv;
    if a.len() < nv || d.len() < nv {
        return 0;
    }
    let budget = 4 * iterations;
    let mut extra = 0;
    // (the work of the impulses as they stand: computed again only after
    // sweeps moved them)
    let mut now = impulse_work(rows, out.lambda, isl, dofs, a, d);
    loop {
        let (work, allow, _, _) = now;
        if work <= allow || extra >= budget {
            break;
        }
        let (it, _) = rows.sweeps(out, isl.runs, dofs, d, 10, tol, 1.0);
        extra += it;
        now = impulse_work(rows, out.lambda, isl, dofs, a, d);
        if it < 10 {
            break;
        }
    }
    let (work, allow, ad, dd) = now;
    if work <= allow || dd <= 0.0 {
        return extra;
    }
    // ΔKE(s) = s a·d + ½ s² ‖d‖² ≤ s·allow ⇐ s ≤ 2(allow − a·d)/‖d‖²
    let s = (2.0 * (allow - ad) / dd).clamp(0.0, 1.0);
    match dofs {
        Some(ks) => ks.iter().for_each(|&k| d[k] *= s),
        None => d[..nv].iter_mut().for_each(|x| *x *= s),
    }
    for r in isl.each_row() {
        out.lambda[r] *= s;
    }
    // the scaling opened the loops: their rows put back exactly, an
    // H̃-orthogonal projection that only lowers the kinetic energy
    // (src/sim/solver/loop_block.rs)
    rows.close_loops(out, isl.runs, d);
    extra
}
