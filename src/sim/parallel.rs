//! A fixed team of threads for the step's parallel work (the islands'
//! velocity solve, src/sim/constraints/solve.rs, and the pairs' narrow
//! phase, src/contact/pairs/visit.rs): the calling thread and
//! `n − 1` workers started once, sharing a job's items through the job's own
//! counter.
//!
//! Built for a step that dispatches a short job (tens of µs to a few ms)
//! hundreds of times a second on a loaded machine: the caller works on the
//! job itself from the start (no hand-off to a pool and back) and waits only
//! for the items a worker has already taken (a worker that comes late, asleep
//! or descheduled, finds the job closed and the caller never waits for it); a
//! worker sleeps right after a job ([`SPIN`]) and a dispatch wakes it; a
//! caller held up by a worker descheduled mid-item runs its next jobs alone
//! ([`COOL`]). docs/theory.md §"Islands".

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A job, as the workers see it: a pointer to the caller's closure (alive
/// while the job is open, and until every worker that took it is done:
/// [`Team::run`] closes it and waits).
#[derive(Clone, Copy)]
struct Job(*const (dyn Fn(usize) + Sync));
// SAFETY: the closure is `Sync` (its parts may run on any thread at once), and
// the pointer is dereferenced only by a worker counted in `active`, which
// `Team::run`, owning the borrow, waits to see at 0 before it returns.
unsafe impl Send for Job {}

/// What the caller and the workers share.
struct Inner {
    /// The open job (`None`: none, or closed by the caller).
    job: Mutex<Option<Job>>,
    /// Jobs so far: a worker looks for a job when this moves past the last it saw.
    epoch: AtomicU64,
    /// Workers running a part of the open or just-closed job (counted up under `job`'s lock).
    active: AtomicUsize,
    /// Workers asleep (waiting on `wake`): only then does a dispatch take the lock to wake them.
    sleeping: AtomicUsize,
    wake: Condvar,
    /// A job is running (a second caller, e.g. a clone of the simulation on
    /// another thread, runs its job alone).
    busy: AtomicBool,
    stop: AtomicBool,
    /// Jobs left that the caller runs alone ([`COOL`]).
    cool: AtomicU32,
    /// The cool-down's back-off: the next one runs `COOL_MIN << level` jobs alone.
    level: AtomicU32,
}

/// The caller and `n − 1` worker threads.
pub(crate) struct Team {
    inner: Arc<Inner>,
    workers: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Team({} threads)", self.threads())
    }
}

/// How long a worker spins on the job counter after a job before it
/// sleeps: none (a few hundred spins). Round 27's 0.1 ms made two
/// threads slower than one at load ~5 and gained nothing near quiet; round
/// 28 measured spin 0 as fast as or faster than 0.1 ms at load ~6 on every
/// pile (benches/pile_results.md). A job's dispatch wakes a sleeping worker;
/// the caller never waits for one that has not begun.
const SPIN: Duration = Duration::ZERO;

/// The most jobs a caller runs alone after a worker held it up (its wait at
/// the close longer than half its own part and than [`STALL`]: on a loaded
/// machine, a worker descheduled in the middle of an item), before it shares
/// again. The first hold-up costs [`COOL_MIN`] jobs alone, each one that
/// follows the next shared job twice as many, up to `COOL`; a shared job
/// closed without one halves it back. Round 29 measured round 28's fixed 64
/// (at any wait over half the caller's part) keeping 66–98 % of the jobs
/// off the worker (load 6–9): a short wait at the close of a short job (a worker's wake-up,
/// the tail of its last item) is common, and each cost 64 jobs alone
/// (benches/pile_results.md, round 29 threads).
const COOL: u32 = 64;

/// The cool-down's first length (jobs alone).
const COOL_MIN: u32 = 4;

/// A wait at a job's close that can be a descheduled worker (a scheduler's
/// slice is a millisecond or more), not a wake-up or an item's tail (tens of
/// µs): below it the caller keeps sharing.
const STALL: Duration = Duration::from_micros(200);

impl Team {
    /// The caller and `threads − 1` workers; `None` with fewer than two
    /// threads, or when a worker cannot be started.
    pub fn new(threads: usize) -> Option<Self> {
        if threads < 2 {
            return None;
        }
        let inner = Arc::new(Inner {
            job: Mutex::new(None),
            epoch: AtomicU64::new(0),
            active: AtomicUsize::new(0),
            sleeping: AtomicUsize::new(0),
            wake: Condvar::new(),
            busy: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            cool: AtomicU32::new(0),
            level: AtomicU32::new(0),
        });
        let mut team = Team {
            inner,
            workers: Vec::with_capacity(threads - 1),
        };
        for part in 1..threads {
            let inner = Arc::clone(&team.inner);
            let h = std::thread::Builder::new()
                .name(format!("urdyn-{part}"))
                .spawn(move || work(&inner, part));
            match h {
                Ok(h) => team.workers.push(h),
                // (dropping `team` stops the workers started so far)
                Err(_) => return None,
            }
        }
        Some(team)
    }

    /// The threads of a job: the caller and the workers.
    pub fn threads(&self) -> usize {
        self.workers.len() + 1
    }

    /// Runs `f(0)` on this thread and `f(k)` on each worker k (from 1 to
    /// threads − 1) that takes the job before `f(0)` returns; returns when every part
    /// begun has finished. A worker may come late and skip the job, so `f`
    /// shares its items through its own counter: any set of parts that
    /// includes part 0 does all of them. A panic of part 0 is resumed here; a
    /// worker's part that panics leaves its items undone, so `f` must see to
    /// that (the islands' solve counts its items done).
    pub fn run(&self, f: &(dyn Fn(usize) + Sync)) {
        let inner = &*self.inner;
        let cool = inner.cool.load(Ordering::Relaxed);
        if cool > 0 {
            // a worker held this thread up lately (descheduled mid-item on
            // a loaded machine): the next jobs alone
            inner.cool.store(cool - 1, Ordering::Relaxed);
            f(0);
            return;
        }
        if inner.busy.swap(true, Ordering::Acquire) {
            // another caller's job is on the workers: this one alone
            f(0);
            return;
        }
        // SAFETY (of the lifetime's erasure): see `Job`; the job is closed and
        // every worker that took it is waited for below, before `f`'s borrow ends
        let job: *const (dyn Fn(usize) + Sync + '_) = f;
        let job = Job(unsafe { std::mem::transmute(job) });
        if let Ok(mut g) = inner.job.lock() {
            *g = Some(job);
        }
        inner.epoch.fetch_add(1, Ordering::SeqCst);
        if inner.sleeping.load(Ordering::SeqCst) > 0 {
            // (the lock orders this notify after a sleeper's check of the epoch)
            let _g = inner.job.lock();
            inner.wake.notify_all();
        }
        let start = Instant::now();
        let mine = catch_unwind(AssertUnwindSafe(|| f(0)));
        let own = start.elapsed();
        // closed: a worker not yet in finds nothing; those in are waited for
        match inner.job.lock() {
            Ok(mut g) => *g = None,
            Err(p) => *p.into_inner() = None,
        }
        crate::contact::pairs::spin_until(|| inner.active.load(Ordering::Acquire) == 0);
        // a wait longer than half this thread's own part and than a wake-up:
        // a worker's item took far longer than its share (descheduled), not
        // a job's tail; the cool-down doubles while hold-ups follow each other
        let wait = start.elapsed().saturating_sub(own);
        let level = inner.level.load(Ordering::Relaxed);
        if wait > own / 2 && wait > STALL {
            inner
                .cool
                .store((COOL_MIN << level).min(COOL), Ordering::Relaxed);
            inner.level.store(
                (level + 1).min((COOL / COOL_MIN).ilog2()),
                Ordering::Relaxed,
            );
        } else if level > 0 {
            inner.level.store(level - 1, Ordering::Relaxed);
        }
        inner.busy.store(false, Ordering::Release);
        if let Err(e) = mine {
            std::panic::resume_unwind(e);
        }
    }
}

/// The team as the contact layer sees it (the pairs' narrow phase,
/// src/contact/pairs/visit.rs).
impl crate::contact::pairs::Runner for Team {
    fn threads(&self) -> usize {
        Team::threads(self)
    }
    fn run(&self, f: &(dyn Fn(usize) + Sync)) {
        Team::run(self, f)
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.inner.stop.store(true, Ordering::SeqCst);
        {
            let _g = self.inner.job.lock();
            self.inner.wake.notify_all();
        }
        for h in self.workers.drain(..) {
            let _ = h.join();
        }
    }
}

/// Worker `part`'s loop: wait for a new epoch (spinning, then asleep), take
/// the job if it is still open, run its part.
fn work(inner: &Inner, part: usize) {
    let mut seen = inner.epoch.load(Ordering::Acquire);
    loop {
        let mut spins = 0u32;
        let since = Instant::now();
        loop {
            if inner.stop.load(Ordering::Acquire) {
                return;
            }
            let e = inner.epoch.load(Ordering::Acquire);
            if e != seen {
                seen = e;
                break;
            }
            spins = spins.wrapping_add(1);
            if spins % 128 != 0 {
                std::hint::spin_loop();
                continue;
            }
            if since.elapsed() < SPIN {
                continue;
            }
            // asleep until a job or the team's drop (then the checks above
            // take it)
            let Ok(mut g) = inner.job.lock() else { return };
            inner.sleeping.fetch_add(1, Ordering::SeqCst);
            while inner.epoch.load(Ordering::SeqCst) == seen && !inner.stop.load(Ordering::SeqCst) {
                g = match inner.wake.wait(g) {
                    Ok(g) => g,
                    Err(_) => return,
                };
            }
            inner.sleeping.fetch_sub(1, Ordering::SeqCst);
        }
        // the job, if still open, counted in `active` under the lock (so the
        // caller's close then wait sees this worker)
        let job = match inner.job.lock() {
            Ok(g) => (*g).inspect(|_| {
                inner.active.fetch_add(1, Ordering::AcqRel);
            }),
            Err(_) => return,
        };
        if let Some(Job(f)) = job {
            // SAFETY: see `Job`: counted in `active`, which `run` waits on
            let f = unsafe { &*f };
            // (a panic leaves the part's items undone: the job's own count)
            let _ = catch_unwind(AssertUnwindSafe(|| f(part)));
            inner.active.fetch_sub(1, Ordering::AcqRel);
        }
    }
}

/// The jobs of `sizes` (j their index) into `order` as (size, j), largest
/// first (ties by index: the same order for the same sizes), the order
/// threads take them in. Returns whether sharing them among `parts` threads
/// is worth a dispatch: whether handing each, largest first, to the thread
/// with the least so far (a bound on what taking them in `order` does)
/// takes at least `min_gain` off the largest share, the work of one thread.
pub(crate) fn cut(
    sizes: impl Iterator<Item = usize>,
    parts: usize,
    min_gain: usize,
    order: &mut Vec<(usize, usize)>,
) -> bool {
    order.clear();
    order.extend(sizes.enumerate().map(|(j, s)| (s, j)));
    let parts = parts.clamp(1, 8);
    let total: usize = order.iter().map(|&(s, _)| s).sum();
    if parts < 2 || order.len() < 2 || total < min_gain {
        return false;
    }
    order.sort_unstable_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
    let mut load = [0usize; 8];
    for &(s, _) in order.iter() {
        let mut k = 0;
        for p in 1..parts {
            if load[p] < load[k] {
                k = p;
            }
        }
        load[k] += s;
    }
    let most = load.iter().copied().max().unwrap_or(total);
    total - most >= min_gain
}
