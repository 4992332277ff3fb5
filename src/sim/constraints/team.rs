//! The contact rows on the team (threads ≥ 2, at least [`MIN_POINTS`]
//! points, rows of a pile's short stride): the same rows as
//! `Constraints::contacts` on one thread, bit for bit (docs/theory.md
//! §"Islands", threads). This thread first marks the bodies the points
//! reach and fixes each contact's place — its rows, handed out three at a
//! time in point order (stopping at capacity), and its dof path (a two-body
//! path is appended to the rows' table, so each depends on every earlier
//! one); then one job computes the marked bodies' world columns by ranges
//! of bodies and, once all are done, each contact's rows by ranges of
//! contacts: its warm start, [`super::free::plan`], the last assembly's
//! entries it must zero, its kinds and targets and J's entries
//! ([`super::point::write`]). A body's columns, a contact's rows: each
//! written by one thread, with the one-thread arithmetic.

use super::point::{self, PointInputs};
use super::{free, Constraints, RowCounts, RowParams, Team};
use crate::contact::ContactPoint;
use crate::model::Model;
use crate::sim::factor::MassFactor;
use crate::sim::solver::RowKind;
use crate::spatial::{Motion, Se3};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The fewest points whose rows go to the team: below it a dispatch's
/// wake-up (tens of µs on a loaded host) costs more than the worker's share
/// (~1 k instructions a point). The 256- and 1024-object piles have
/// 800–4,000 points a step; box_stack and the robots' scenes a few dozen.
pub(super) const MIN_POINTS: usize = 512;

/// Contacts a thread takes at once.
const CHUNK: usize = 64;

/// Bodies a thread takes at once (their world columns).
const BODY_CHUNK: usize = 128;

/// One contact's place, fixed before its rows are written.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fixed {
    /// The point (index into the step's points).
    pub pi: usize,
    /// Its normal row (the tangents follow).
    pub rn: usize,
    /// Its dof path (start, length in the rows' table).
    pub path: (usize, usize),
}

/// What the job writes, as raw pointers with their lengths: body i's world
/// columns `sw[i]` (each marked body once: `bodies` holds no body twice,
/// its stamp set as it is listed), and a contact's rows rn..rn + 3 of each
/// per-row vector (`j`: rows of `stride` entries), distinct for distinct
/// contacts (the pre-pass handed them out). No location is written by two
/// threads, and none read by a thread other than its writer before the
/// barrier that follows the columns.
#[derive(Clone, Copy)]
struct Shared {
    sw: (*mut [Motion; 6], usize),
    j: (*mut f64, usize),
    b: (*mut f64, usize),
    bpos: (*mut f64, usize),
    lambda: (*mut f64, usize),
    kind: (*mut RowKind, usize),
    path: (*mut (usize, usize), usize),
}
// SAFETY: see `Shared`; the pointers are those of slices borrowed mutably for
// the whole of `Team::run`, which returns only when every part has finished.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// A contact's rows rn..rn + 3 of one per-row vector.
///
/// SAFETY (of a call): rn + 3 ≤ `v.1` and the rows are this thread's alone.
#[inline(always)]
unsafe fn rows3<'a, T>(v: (*mut T, usize), rn: usize) -> &'a mut [T] {
    // SAFETY: the caller's
    unsafe { std::slice::from_raw_parts_mut(v.0.add(rn), 3) }
}

impl Constraints {
    /// `Constraints::contacts` on `team`: `x` = (model, poses, v, params, h).
    pub(super) fn contacts_on_team(
        &mut self,
        team: &Team,
        (model, o_m_i, v, p, h): (&Model, &[Se3<f64>], &[f64], &RowParams, f64),
        points: &[ContactPoint],
        f: &MassFactor,
        keep: usize,
        counts: &mut RowCounts,
    ) {
        // the bodies whose world columns the rows read (as `contacts` marks them)
        let stamp = self.sw_stamp;
        self.bodies.clear();
        for pt in points {
            for start in [pt.body, pt.other] {
                let mut i = start;
                while i != 0
                    && i < self.cols.len()
                    && i < o_m_i.len()
                    && i < self.sw.len()
                    && let Some(done) = self.sw_done.get_mut(i)
                    && *done != stamp
                {
                    *done = stamp;
                    self.bodies.push(i);
                    i = model.parent[i];
                }
            }
        }
        // each contact's place
        let heads = &self.heads;
        let body_path = |b: usize| {
            let (iv, nv) = heads.get(b).map_or((0, 0), |c| (c.iv, c.nv));
            f.path_of((iv + nv).saturating_sub(1))
        };
        let rows = &mut self.rows;
        self.fixed.clear();
        for (pi, pt) in points.iter().enumerate() {
            let path = if pt.other == 0 {
                body_path(pt.body)
            } else {
                rows.union_path(body_path(pt.body), body_path(pt.other))
            };
            let Some(rn) = rows.reserve_contact() else {
                break;
            };
            self.row_point.push(pi);
            counts.contacts += 1;
            self.fixed.push(Fixed { pi, rn, path });
        }
        let st = rows.stride;
        let parts = rows.contact_parts();
        let sh = Shared {
            sw: (self.sw.as_mut_ptr(), self.sw.len()),
            j: (parts.j.as_mut_ptr(), parts.j.len()),
            b: (parts.b.as_mut_ptr(), parts.b.len()),
            bpos: (parts.bpos.as_mut_ptr(), parts.bpos.len()),
            lambda: (parts.lambda.as_mut_ptr(), parts.lambda.len()),
            kind: (parts.kind.as_mut_ptr(), parts.kind.len()),
            path: (parts.path.as_mut_ptr(), parts.path.len()),
        };
        let tab = parts.table;
        let (bodies, cols, fixed) = (&self.bodies[..], &self.cols[..], &self.fixed[..]);
        let (heads, wc, parent) = (&self.heads[..], &self.warm_contact[..], &model.parent[..]);
        let nb = bodies.len().div_ceil(BODY_CHUNK);
        let nc = fixed.len().div_ceil(CHUNK);
        let (b_next, b_done, failed) = (
            AtomicUsize::new(0),
            AtomicUsize::new(0),
            AtomicBool::new(false),
        );
        let (next, done, violated) = (
            AtomicUsize::new(0),
            AtomicUsize::new(0),
            AtomicUsize::new(0),
        );
        team.run(&|_| {
            let sh = sh;
            // the world columns, by ranges of bodies
            loop {
                let k = b_next.fetch_add(1, Ordering::Relaxed);
                if k >= nb {
                    break;
                }
                let s = k.saturating_mul(BODY_CHUNK);
                let part = bodies.get(s..bodies.len().min(s.saturating_add(BODY_CHUNK)));
                // (a panic is counted done: the job is failed, after it too)
                let r = catch_unwind(AssertUnwindSafe(|| {
                    for &i in part.unwrap_or(&[]) {
                        let (Some(c), Some(o)) = (cols.get(i), o_m_i.get(i)) else {
                            continue;
                        };
                        if i >= sh.sw.1 {
                            continue;
                        }
                        // SAFETY: i < the columns' length (checked); body i
                        // listed once, in this chunk alone (see `Shared`)
                        let sw = unsafe { &mut *sh.sw.0.add(i) };
                        c.world(o, sw);
                    }
                }));
                if r.is_err() {
                    failed.store(true, Ordering::Relaxed);
                }
                b_done.fetch_add(1, Ordering::Release);
            }
            // every body's columns before any contact's rows
            crate::contact::pairs::spin_until(|| b_done.load(Ordering::Acquire) >= nb);
            if failed.load(Ordering::Relaxed) {
                return;
            }
            // SAFETY: no thread writes the columns any more (the barrier
            // above); the pointer and length are those of `self.sw`
            let sw = unsafe { std::slice::from_raw_parts(sh.sw.0, sh.sw.1) };
            let x = PointInputs {
                parent,
                heads,
                sw,
                v,
                p,
                h,
            };
            let (mut bad, mut frame) = (0, super::free::Frame::default());
            loop {
                let c = next.fetch_add(1, Ordering::Relaxed);
                if c >= nc {
                    break;
                }
                let s = c.saturating_mul(CHUNK);
                let part = fixed.get(s..fixed.len().min(s.saturating_add(CHUNK)));
                for fx in part.unwrap_or(&[]) {
                    let Some(pt) = points.get(fx.pi) else {
                        continue;
                    };
                    let rn = fx.rn;
                    let lens = [sh.b.1, sh.bpos.1, sh.lambda.1, sh.kind.1, sh.path.1];
                    if (rn + 3) * st > sh.j.1 || lens.iter().any(|&l| rn + 3 > l) {
                        continue;
                    }
                    // SAFETY: rows rn..rn + 3 inside every vector (checked
                    // above), contact fx's alone (`Shared`), for as long as
                    // `run` holds the borrow
                    let (j0, j1, j2, b, bpos, lambda, kind, path) = unsafe {
                        let r = sh.j.0.add(rn * st);
                        (
                            std::slice::from_raw_parts_mut(r, st),
                            std::slice::from_raw_parts_mut(r.add(st), st),
                            std::slice::from_raw_parts_mut(r.add(2 * st), st),
                            rows3(sh.b, rn),
                            rows3(sh.bpos, rn),
                            rows3(sh.lambda, rn),
                            rows3(sh.kind, rn),
                            rows3(sh.path, rn),
                        )
                    };
                    let warm = match pt.fresh {
                        true => [0.0; 3],
                        false => wc.get(pt.slot).map_or([0.0; 3], |w| [w[0], w[1], w[2]]),
                    };
                    // `contacts`' plan, stale entries and zeroing (the rows'
                    // last path read before it is written), then `push_contact`
                    let (ps, pl) = fx.path;
                    let on = tab.get(ps..ps + pl);
                    let plan = on.and_then(|on| free::plan(heads, on, st, pt));
                    let stale = match path.first() {
                        Some(&(_, l)) if rn + 3 <= keep => l,
                        _ => 0,
                    };
                    if plan.is_none() && rn + 3 <= keep {
                        // (`Rows::zero_contact` of a stride ≤ `Rows::GAP`)
                        for r in [&mut *j0, &mut *j1, &mut *j2] {
                            r.fill(0.0);
                        }
                    }
                    kind.copy_from_slice(&[
                        RowKind::Normal,
                        RowKind::Tangent {
                            normal: rn,
                            mu: pt.friction,
                        },
                        RowKind::Tangent2,
                    ]);
                    b.fill(0.0);
                    lambda.copy_from_slice(&warm);
                    bpos.fill(0.0);
                    path.fill(fx.path);
                    let on_path = on.unwrap_or(&[]);
                    let (bn, bp) =
                        point::write(&x, [j0, j1, j2], on_path, plan, stale, pt, &mut frame);
                    b[0] = bn;
                    bpos[0] = bp;
                    bad += usize::from(bp > 0.0);
                }
                done.fetch_add(1, Ordering::Release);
            }
            violated.fetch_add(bad, Ordering::Relaxed);
        });
        // (a chunk left undone: its thread panicked, as `run` lets it)
        assert!(
            !failed.into_inner() && done.load(Ordering::Acquire) >= nc,
            "a thread of the contact rows' assembly panicked"
        );
        counts.violated += violated.into_inner();
    }
}
