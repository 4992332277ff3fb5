//! The narrow phase's visit of a detection's pairs ([`PairContact::detect`]):
//! each pair's query and points, on the calling thread, or in chunks of
//! consecutive pairs on a team of threads ([`Runner`]), each chunk's points
//! and live pairs put back in visiting order. A pair's query reads the
//! members' poses (shared, read only) and writes only its own state (its
//! manifolds, separating axis, slot keys) and its thread's scratch, so every
//! point is the one the calling thread alone computes, bit for bit, whichever
//! thread visits its pair. docs/theory.md §"Islands" (threads).

use super::apart::{apart_along, still_apart_at, Apart};
use super::order::assign_slots;
use super::{Member, Pair, PairContact, NO_KEY};
use crate::contact::fetch::prefetch;
use crate::contact::narrow::prim::{round_points_at, Round};
use crate::contact::narrow::{face_points, parry_points, reduce_pair, FaceScratch, Raw};
use crate::contact::shapes::from_pvec;
use crate::contact::travel::Travel;
use crate::contact::ContactPoint;
use crate::spatial::Se3;
use nalgebra::Vector3;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Runs a job's parts on several threads: the contact layer's view of the
/// simulation's team (src/sim/parallel.rs; contact names nothing above it).
pub(crate) trait Runner: Sync {
    /// The threads of a job (the caller's included).
    fn threads(&self) -> usize;
    /// Runs `f(0)` on this thread and `f(k)` on the other threads that come
    /// before it returns (a late one may not): `f` shares its items through
    /// its own counter, so that part 0 alone does all of them.
    fn run(&self, f: &(dyn Fn(usize) + Sync));
}

/// Waits on this thread until `done()` holds: a spin, giving the core
/// away every 64 tries (the team's waits for its parts: a job's close,
/// a barrier between a job's stages).
#[inline]
pub(crate) fn spin_until(done: impl Fn() -> bool) {
    let mut spins = 0u32;
    while !done() {
        spins = spins.wrapping_add(1);
        if spins % 64 == 0 {
            std::thread::yield_now();
        } else {
            std::hint::spin_loop();
        }
    }
}

/// Pairs a chunk: a thread takes a chunk at a time (one atomic add), and
/// the stepping thread waits for at most one chunk of the worker's.
const CHUNK: usize = 32;

/// The fewest pairs of a visit that goes to the team: under that, the
/// queries (1–3 µs a touching pair) cost no more than a worker's wake-up.
const MIN_PAIRS: usize = 192;

/// One thread's scratch: a query's raw points, the face path's scratch
/// and its stamp.
#[derive(Clone, Default)]
pub(super) struct Query {
    raw: Vec<Raw>,
    face: FaceScratch,
    stamp: u32,
}

impl Query {
    pub(super) fn with_room(room: usize) -> Self {
        Query {
            raw: Vec::with_capacity(room),
            ..Query::default()
        }
    }
}

/// One chunk's output: its pairs' points and live pairs, in visiting order,
/// and its queries.
#[derive(Clone, Default)]
pub(super) struct ChunkOut {
    points: Vec<ContactPoint>,
    live: Vec<(u64, u32)>,
    queries: u64,
}

/// What every pair's query reads: the members, their poses at this
/// detection, the margins, the sleeping bodies.
struct Frame<'a> {
    members: &'a [Member],
    poses: &'a [Se3<f64>],
    centres: &'a [Vector3<f64>],
    radii: &'a [f64],
    rounds: &'a [Option<Round>],
    travel: &'a Travel,
    asleep: &'a [bool],
    max_points: usize,
}

/// Where one pair's visit writes: the points, the live pairs, the queries.
struct Sink<'a> {
    out: &'a mut Vec<ContactPoint>,
    live: &'a mut Vec<(u64, u32)>,
    queries: &'a mut u64,
}

/// The pairs `visit` and the team's share of them, with every pair's state
/// written through raw pointers ([`Shared`]).
#[derive(Clone, Copy)]
struct Shared {
    pairs: (*mut Pair, usize),
    keys: (*mut u64, usize),
    chunks: (*mut ChunkOut, usize),
    queries: (*mut Query, usize),
}
// SAFETY: the threads given a `Shared` write only the pairs (and their
// `max_points` keys) of the chunks they took, those chunks' outputs and their
// own query scratch: a chunk is taken once (an atomic counter), a pair is
// visited once (checked before the dispatch: the visit's ords strictly
// increase and each is its pair's own) and a thread has one scratch, so no
// element is touched by two threads. `Pair` is `Send` (checked below).
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

const _: () = {
    const fn send<T: Send>() {}
    send::<Pair>();
    send::<ChunkOut>();
    send::<Query>();
};

impl PairContact {
    /// The narrow phase of every pair of `self.visit` (`self.hits`: its
    /// boxes overlap), its points appended to `out`, the pairs that hold
    /// anything after it into `self.live`; on `run`'s threads when there
    /// are enough pairs.
    pub(crate) fn visit_pairs(
        &mut self,
        out: &mut Vec<ContactPoint>,
        asleep: &[bool],
        run: Option<&dyn Runner>,
    ) {
        self.live.clear();
        let frame = Frame {
            members: &self.members,
            poses: &self.poses,
            centres: &self.centres,
            radii: &self.radii,
            rounds: &self.rounds,
            travel: &self.travel,
            asleep,
            max_points: self.max_points,
        };
        let n = self.visit.len();
        let (visit, hits, dropped) = (&self.visit[..], &self.hits[..], &self.dropped[..]);
        let team = run.filter(|r| r.threads() > 1 && n >= MIN_PAIRS && n == hits.len());
        // each pair once: the ords strictly increase, each its pair's
        let ords = &self.ords;
        let once = |v: &[(u64, u32)]| {
            v.windows(2).all(|w| w[0].0 < w[1].0)
                && v.iter().all(|&(o, p)| ords.get(p as usize) == Some(&o))
        };
        let Some(team) = team.filter(|_| once(visit)) else {
            if self.queries_scratch.is_empty() {
                self.queries_scratch.push(Query::with_room(super::RAW_ROOM));
            }
            let mut sink = Sink {
                out,
                live: &mut self.live,
                queries: &mut self.queries,
            };
            let q = &mut self.queries_scratch[0];
            let (pairs, keys) = (&mut self.pairs, &mut self.keys);
            let maxp = self.max_points;
            for (vi, (&(ord, pi), &hit)) in visit.iter().zip(hits).enumerate() {
                let pi = pi as usize;
                // the pair four visits on fetched now (a pile's pairs lie far
                // apart in memory: a cache miss each), while this one is worked
                if let Some(&(_, ahead)) = visit.get(vi + 4) {
                    fetch_ahead(pairs, keys, ahead as usize, maxp);
                }
                let (Some(pair), Some(keys)) =
                    (pairs.get_mut(pi), keys.get_mut(pi * maxp..(pi + 1) * maxp))
                else {
                    continue;
                };
                let drop = dropped.get(pi).copied().unwrap_or(false);
                visit_one(&frame, (ord, pi), hit && !drop, pair, keys, q, &mut sink);
            }
            return;
        };
        let chunks = n.div_ceil(CHUNK);
        if self.chunks.len() < chunks {
            self.chunks.resize(chunks, ChunkOut::default());
        }
        while self.queries_scratch.len() < team.threads() {
            self.queries_scratch.push(Query::with_room(super::RAW_ROOM));
        }
        for c in &mut self.chunks[..chunks] {
            c.points.clear();
            c.live.clear();
            c.queries = 0;
        }
        let maxp = self.max_points;
        let sh = Shared {
            pairs: (self.pairs.as_mut_ptr(), self.pairs.len()),
            keys: (self.keys.as_mut_ptr(), self.keys.len()),
            chunks: (self.chunks.as_mut_ptr(), chunks),
            queries: (
                self.queries_scratch.as_mut_ptr(),
                self.queries_scratch.len(),
            ),
        };
        let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
        team.run(&|k| {
            let sh = sh;
            if k >= sh.queries.1 {
                return;
            }
            // SAFETY: see `Shared`; thread k alone takes scratch k (k < its
            // length, checked), the pointer that of a live slice borrowed for
            // the whole of `run`
            let q = unsafe { &mut *sh.queries.0.add(k) };
            loop {
                let c = next.fetch_add(1, Ordering::Relaxed);
                if c >= sh.chunks.1 {
                    break;
                }
                // SAFETY: c < the chunks' length (checked), chunk c taken here alone
                let co = unsafe { &mut *sh.chunks.0.add(c) };
                let mut sink = Sink {
                    out: &mut co.points,
                    live: &mut co.live,
                    queries: &mut co.queries,
                };
                let end = ((c + 1) * CHUNK).min(n);
                for vi in c * CHUNK..end {
                    let (Some(&(ord, pi)), Some(&hit)) = (visit.get(vi), hits.get(vi)) else {
                        continue;
                    };
                    let pi = pi as usize;
                    if pi >= sh.pairs.1 || (pi + 1) * maxp > sh.keys.1 {
                        continue;
                    }
                    // SAFETY: pair pi (and its keys) in bounds (checked) and
                    // visited once, here (see `Shared`)
                    let (pair, keys) = unsafe {
                        (
                            &mut *sh.pairs.0.add(pi),
                            std::slice::from_raw_parts_mut(sh.keys.0.add(pi * maxp), maxp),
                        )
                    };
                    let drop = dropped.get(pi).copied().unwrap_or(false);
                    visit_one(&frame, (ord, pi), hit && !drop, pair, keys, q, &mut sink);
                }
                done.fetch_add(1, Ordering::Release);
            }
        });
        // (a chunk left undone: its thread panicked, as `run` lets it)
        assert!(
            done.load(Ordering::Acquire) >= chunks,
            "a thread of the narrow phase panicked"
        );
        for c in &self.chunks[..chunks] {
            out.extend_from_slice(&c.points);
            self.live.extend_from_slice(&c.live);
            self.queries += c.queries;
        }
    }
}

/// Pair `p`'s state and keys fetched into the cache ahead of its visit.
#[inline]
fn fetch_ahead(pairs: &[Pair], keys: &[u64], p: usize, maxp: usize) {
    if let Some(x) = pairs.get(p) {
        prefetch(x);
    }
    if let Some(k) = keys.get(p * maxp) {
        prefetch(k);
    }
}

/// One pair's visit (`hit`: its boxes overlap and it is not dropped): a
/// pair not hit forgets its points; one hit is live, and queried unless
/// both its bodies are still; its points reduced and given its slots.
fn visit_one(
    fr: &Frame<'_>,
    (ord, pi): (u64, usize),
    hit: bool,
    pair: &mut Pair,
    keys: &mut [u64],
    q: &mut Query,
    sink: &mut Sink<'_>,
) {
    if !hit {
        pair.apart = None;
        if keys[0] != NO_KEY || !pair.manifolds.is_empty() {
            keys.fill(NO_KEY);
            pair.manifolds.clear();
        }
        return;
    }
    sink.live.push((ord, pi as u32));
    let still = |b: usize| b == 0 || fr.asleep.get(b) == Some(&true);
    let (Some(ma), Some(mb)) = (fr.members.get(pair.a), fr.members.get(pair.b)) else {
        return;
    };
    if still(ma.body) && still(mb.body) {
        return;
    }
    let (wa, wb) = (&fr.poses[pair.a], &fr.poses[pair.b]);
    let margin = fr.travel.pair_margin(pair.a, pair.b);
    *sink.queries += 1;
    q.raw.clear();
    if let (Some(ra), Some(rb)) = (&fr.rounds[pair.a], &fr.rounds[pair.b]) {
        // two spheres or capsules: their closed form (no manifold,
        // never a separating axis: `parry_points`' first case)
        round_points_at(ra, rb, margin, &mut q.raw);
        pair.manifolds.clear();
        pair.workspace = None;
        pair.axis = Vector3::zeros();
        pair.apart = None;
    } else {
        // a hull on a box's face or a flat height field: the plane
        // contact where it is the exact one (`face`), else parry
        let plane = match pair.face {
            Some(hull_is_a) => {
                q.stamp = q.stamp.wrapping_add(1).max(1);
                face_points(
                    &ma.shape,
                    &mb.shape,
                    wa,
                    wb,
                    hull_is_a,
                    margin,
                    fr.max_points,
                    &mut q.face,
                    &mut q.raw,
                    q.stamp,
                )
            }
            None => false,
        };
        // two convex shapes apart along last step's axis by more than
        // the margin: no point, no parry query
        let convex = ma.shape.convex && mb.shape.convex;
        let (ca, cb) = (&fr.centres[pair.a], &fr.centres[pair.b]);
        let now_a = (ca, wa, fr.radii[pair.a]);
        let now_b = (cb, wb, fr.radii[pair.b]);
        let apart = convex
            && (still_apart_at(pair.apart.as_ref(), now_a, now_b, margin) || {
                let gap = apart_along(&pair.axis, ma, mb, wa, wb);
                pair.apart = (gap > margin).then_some(Apart {
                    gap,
                    ca: *ca,
                    ra: wa.rot,
                    cb: *cb,
                    rb: wb.rot,
                });
                gap > margin
            });
        if !plane && !apart {
            parry_points(
                &ma.shape,
                &mb.shape,
                wa,
                wb,
                margin,
                &mut pair.manifolds,
                &mut pair.workspace,
                &mut q.raw,
            );
            // parry's last direction (a's frame, from a toward b): its
            // separating axis when apart, else the contact normal
            pair.axis = match pair.manifolds.first() {
                Some(m) if convex && pair.manifolds.len() == 1 => {
                    let n = from_pvec(m.local_n1);
                    let l = n.norm();
                    if l > 0.5 && l.is_finite() {
                        n / l
                    } else {
                        Vector3::zeros()
                    }
                }
                _ => Vector3::zeros(),
            };
        }
    }
    if q.raw.is_empty() {
        // no point: every slot free (`assign_slots` of none)
        keys.fill(NO_KEY);
        return;
    }
    let out = &mut *sink.out;
    let start = out.len();
    // the moving side first: a static a (an obstacle or a fixed
    // model's welded link) against a moving b swaps sides
    let swap = ma.body == 0;
    let (first, second) = if swap { (mb, ma) } else { (ma, mb) };
    let sign = if swap { -1.0 } else { 1.0 };
    reduce_pair(&q.raw, fr.max_points, out, |r| ContactPoint {
        shape: pi,
        slot: 0,
        body: first.body,
        point: r.point,
        gap: r.gap,
        geom: first.geom,
        other: second.body,
        other_geom: second.geom,
        normal: r.normal * sign,
        friction: pair.friction,
        fresh: true,
        key: r.key,
    });
    assign_slots(pair.slot_base, keys, &mut out[start..]);
}
