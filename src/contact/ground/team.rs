//! The ground detection on a team of threads ([`Runner`]): the shapes in
//! chunks of consecutive shapes, a thread taking a chunk at a time (one
//! atomic add), each chunk's points put back in shape order. A shape's search
//! reads its body's pose and the last detection's kept slots (read only until
//! the detection ends) and writes only its own travel and anchor and its
//! chunk's points and scratch, so every point is the one the calling thread
//! alone computes, bit for bit, in the same order (docs/theory.md §"Islands",
//! threads). A hull searched on its vertex graph shares the search's scratch
//! with every shape: a detection with one stays on one thread. The calling
//! thread first runs its side work (the pairs' broad phase, which touches
//! nothing of the ground's) while the worker takes chunks: the two stages at
//! once; the broad phase's member loop ([`Side`]'s items) first, on every
//! thread, its sweep on the calling thread after.

use super::{plain_points, reach, GroundContact, Plain, Runner};
use crate::contact::pairs::spin_until;
use crate::contact::ContactPoint;
use crate::spatial::Se3;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Work beside the ground's shapes in one job (the pairs' broad phase,
/// src/contact/pairs/members.rs): `items` any thread may run, each once,
/// then `rest` on the calling thread once every item is done.
pub(crate) trait Side: Sync {
    /// The items.
    fn items(&self) -> usize;
    /// Item `k` (< `items()`).
    fn item(&self, k: usize);
    /// What follows the items.
    fn rest(&self);
}

/// Every item of `side`, then its rest, on this thread.
pub(super) fn side_alone(side: &dyn Side) {
    for k in 0..side.items() {
        side.item(k);
    }
    side.rest();
}

/// The fewest shapes of a detection that goes to the team: under that, the
/// search (tens of ns a culled shape, a µs or so a touching one) costs
/// no more than a worker's wake-up.
const MIN_SHAPES: usize = 256;

/// Shapes a chunk.
const CHUNK: usize = 64;

/// One chunk's output: its shapes' points in shape order, its queries, and
/// its candidates' scratch.
#[derive(Clone, Debug, Default)]
pub(super) struct Part {
    points: Vec<ContactPoint>,
    scratch: Vec<ContactPoint>,
    queries: u64,
}

/// The chunks and the shapes' travel and anchors, written through raw
/// pointers by the threads of a job.
#[derive(Clone, Copy)]
struct Shared {
    parts: (*mut Part, usize),
    anchor: (*mut [f64; 4], usize),
    travel: (*mut f64, usize),
}
// SAFETY: a thread writes only the chunks it took (an atomic counter hands
// each out once) and, of the anchors and travels, only the entries of its
// chunks' shapes (a chunk's shapes are its own range): no element is written
// by two threads, and none read by another while the job runs.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl GroundContact {
    /// Whether a detection on a team of `threads` is worth its dispatch
    /// (enough shapes) and can be had (no hull; every shape its anchor and
    /// travel).
    pub(super) fn team_worth(&mut self, threads: usize) -> bool {
        let n = self.shapes.len();
        threads > 1
            && n >= MIN_SHAPES
            && !self.hulls
            && self.anchor.len() == n
            && self.cull.len() == n
            && self.travel.split().0.len() == n
    }

    /// [`Self::detect_serial`] on `run`'s threads (`team_worth`), the points
    /// into `out` in shape order; `side` run first by the calling thread
    /// (part 0), the chunks of shapes by every thread.
    pub(super) fn detect_team(
        &mut self,
        o_m_i: &[Se3<f64>],
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        run: &dyn Runner,
        step: (f64, bool),
        side: Option<&dyn Side>,
    ) {
        let n = self.shapes.len();
        let chunks = n.div_ceil(CHUNK);
        if self.parts.len() < chunks {
            self.parts.resize(chunks, Part::default());
        }
        for p in &mut self.parts[..chunks] {
            p.points.clear();
            p.queries = 0;
        }
        let (shapes, cull) = (&self.shapes[..], &self.cull[..]);
        let (ts, delta, c) = self.travel.split();
        let sh = Shared {
            parts: (self.parts.as_mut_ptr(), chunks),
            anchor: (self.anchor.as_mut_ptr(), self.anchor.len()),
            travel: (ts.as_mut_ptr(), ts.len()),
        };
        let cx = Plain {
            ground: self.ground,
            maxp: self.params.max_points_per_shape.max(1),
            slot_offset: &self.slot_offset,
            prev_flag: &self.prev_flag,
            reduce_dirs: &self.reduce_dirs,
        };
        let ground = self.ground;
        let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
        let (s_next, s_done, s_failed) = (
            AtomicUsize::new(0),
            AtomicUsize::new(0),
            AtomicBool::new(false),
        );
        run.run(&|part| {
            let sh = sh;
            // `side` first: its items on every thread that comes, then its
            // rest on the calling thread (part 0, which every job runs) once
            // they are done, while the others start on the chunks
            if let Some(f) = side {
                let items = f.items();
                loop {
                    let k = s_next.fetch_add(1, Ordering::Relaxed);
                    if k >= items {
                        break;
                    }
                    // (a panic is counted done, then resumed after the job)
                    if catch_unwind(AssertUnwindSafe(|| f.item(k))).is_err() {
                        s_failed.store(true, Ordering::Relaxed);
                    }
                    s_done.fetch_add(1, Ordering::Release);
                }
                if part == 0 {
                    spin_until(|| s_done.load(Ordering::Acquire) >= items);
                    if !s_failed.load(Ordering::Relaxed) {
                        f.rest();
                    }
                }
            }
            loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= sh.parts.1 {
                    break;
                }
                let (a, b) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
                if b > sh.anchor.1 || b > sh.travel.1 || b > shapes.len() || b > cull.len() {
                    continue;
                }
                // SAFETY: chunk k (< the chunks' length, checked) taken here
                // alone, and with it its shapes' anchors and travels a..b
                // (b within both lengths, checked); the pointers those of
                // live vectors borrowed for the whole of `run` (see `Shared`)
                let (part, anchors, travels) = unsafe {
                    (
                        &mut *sh.parts.0.add(k),
                        std::slice::from_raw_parts_mut(sh.anchor.0.add(a), b - a),
                        std::slice::from_raw_parts_mut(sh.travel.0.add(a), b - a),
                    )
                };
                let Part {
                    points,
                    scratch,
                    queries,
                } = part;
                let it = shapes[a..b].iter().zip(&cull[a..b]);
                for (j, ((s, cu), (anchor, t))) in
                    it.zip(anchors.iter_mut().zip(travels)).enumerate()
                {
                    let Some(o_m_b) = o_m_i.get(cu.body) else {
                        continue;
                    };
                    if asleep.get(cu.body) == Some(&true) {
                        continue;
                    }
                    let Some(margin) = reach(cu, o_m_b, ground, step, anchor, Some(t), (delta, c))
                    else {
                        continue;
                    };
                    let o_m_g = s.pose(o_m_b);
                    *queries += 1;
                    plain_points(s, a + j, &o_m_g, margin, &cx, scratch, points);
                }
                done.fetch_add(1, Ordering::Release);
            }
        });
        // (a chunk left undone: its thread panicked, as `run` lets it)
        assert!(
            done.load(Ordering::Acquire) >= chunks && !s_failed.into_inner(),
            "a thread of the ground detection or the broad phase panicked"
        );
        for p in &self.parts[..chunks] {
            out.extend_from_slice(&p.points);
            self.queries += p.queries;
        }
    }
}
