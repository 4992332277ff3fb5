//! [`Rows::form`] on the team's threads: the rows cut into ranges at rows
//! where the serial walk is sure to begin a block (found without forming
//! anything), each range walked by one thread with the serial code. A block
//! writes only its own rows, so the ranges write apart and every value is
//! the serial form's, bit for bit, whichever thread forms it.

use super::super::super::parallel::Team;
use super::super::{MassFactor, Rows};
use super::Former;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Rows × stride (a bound on the rows' path entries) from which the form
/// goes to the team: ~400 contacts of a pile's (12-dof paths), a form of
/// ~0.3 M instructions, several times a worker's wake-up. The piles of 16
/// and 64 and the robot scenes stay below (their form is tens of µs).
pub(super) const MIN_WORK: usize = 14_400;

/// The most threads a form job uses (each its own scratch `lanes`, `PARTS`
/// × stride entries in all: [`Rows::new`]); a thread beyond takes nothing.
pub(in super::super) const PARTS: usize = 8;

/// Ranges a thread (the caller takes what a late worker leaves).
const PER_THREAD: usize = 4;

/// The most ranges.
const RANGES: usize = 4 * PARTS;

/// Where every thread's [`Former`] writes: the rows' fields as raw parts.
#[derive(Clone, Copy)]
struct Shared {
    y: (*mut f64, usize),
    c: (*mut f64, usize),
    w: (*mut f64, usize),
    w_block: (*mut [f64; 3], usize),
    is_block: (*mut bool, usize),
    winv: (*mut f64, usize),
    lanes: (*mut [f64; 4], usize),
}
// SAFETY: a thread given a `Shared` writes only the rows of the ranges it
// took (each range taken once, an atomic counter) and its own part of
// `lanes` (thread k: entries k·stride.., k < PARTS): a range's blocks write
// only their own rows' entries of y, c, w, w_block, is_block and
// winv (a block never reaches past its range's end: [`Former::walk`]'s
// `end`, and ranges begin at block starts, `cuts`), so no element is
// written by two threads, and none that one writes is read by another.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// Whether the serial walk ([`Former::walk`] from row 0) begins a block at
/// row `r`, seen from the rows alone: `r` is 0 or `n`, or rows `r − 3..r`
/// are a contact that is not paired with one at `r` (not a contact, or on
/// another path). The block that holds row `r − 1` then ends at `r`: it
/// begins at `r − 1` (one row), at `r − 3` (that contact, alone: no pair
/// with `r`) or at `r − 6` (a pair with it); no block can begin at `r − 5`,
/// `r − 4`, `r − 2`, `r − 1` and reach `r` (those are tangent rows, or rows
/// a contact's rows at `r − 3` keep from being a contact's first).
fn starts_block(rows: &Rows, r: usize) -> bool {
    let n = rows.n;
    if r == 0 || r >= n {
        return true;
    }
    if r < 3 || !rows.is_contact(r - 3) {
        return false;
    }
    if !rows.is_contact(r) {
        return true;
    }
    let path = |q: usize| {
        let (s, l) = rows.path[q];
        rows.table.get(s..s + l)
    };
    path(r - 3) != path(r)
}

/// Forms the rows on `team` (threads ≥ 2): returns false, nothing done, where
/// the rows do not cut into two ranges or more (the caller forms them on
/// this thread).
pub(super) fn form(rows: &mut Rows, f: &MassFactor, vfree: &[f64], team: &Team) -> bool {
    let (n, st) = (rows.n, rows.stride);
    let threads = team.threads().min(PARTS);
    let want = (threads * PER_THREAD).min(RANGES);
    // the cuts: each the first block start at or after its share of the rows
    let mut cuts = [0usize; RANGES + 1];
    let mut m = 0;
    for i in 1..want {
        let mut r = (i * n / want).max(cuts[m] + 1);
        while !starts_block(rows, r) {
            r += 1;
        }
        if r >= n {
            break;
        }
        m += 1;
        cuts[m] = r;
    }
    m += 1;
    cuts[m] = n;
    if m < 2 || rows.lanes.len() < threads * st {
        return false;
    }
    let cuts = &cuts[..=m];
    let Rows {
        kind,
        path,
        table,
        j,
        y,
        c,
        w,
        w_block,
        is_block,
        winv,
        lanes,
        ..
    } = rows;
    let (kind, path, table, j) = (&kind[..], &path[..], &table[..], &j[..]);
    let sh = Shared {
        y: (y.as_mut_ptr(), y.len()),
        c: (c.as_mut_ptr(), c.len()),
        w: (w.as_mut_ptr(), w.len()),
        w_block: (w_block.as_mut_ptr(), w_block.len()),
        is_block: (is_block.as_mut_ptr(), is_block.len()),
        winv: (winv.as_mut_ptr(), winv.len()),
        lanes: (lanes.as_mut_ptr(), lanes.len()),
    };
    let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    team.run(&|k| {
        let sh = sh;
        if k >= threads {
            return;
        }
        // SAFETY: see `Shared`; the pointers and lengths are those of live
        // slices borrowed (mutably, by `rows`) for the whole of `run`, and
        // thread k alone takes lanes k·st..(k + 1)·st (within their length:
        // k < threads, checked above against `lanes`)
        let mut fm = unsafe {
            Former {
                st,
                end: n,
                kind,
                path,
                table,
                j,
                y: std::slice::from_raw_parts_mut(sh.y.0, sh.y.1),
                c: std::slice::from_raw_parts_mut(sh.c.0, sh.c.1),
                w: std::slice::from_raw_parts_mut(sh.w.0, sh.w.1),
                w_block: std::slice::from_raw_parts_mut(sh.w_block.0, sh.w_block.1),
                is_block: std::slice::from_raw_parts_mut(sh.is_block.0, sh.is_block.1),
                winv: std::slice::from_raw_parts_mut(sh.winv.0, sh.winv.1),
                lanes: std::slice::from_raw_parts_mut(sh.lanes.0.add(k * st), st),
            }
        };
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let (Some(&a), Some(&b)) = (cuts.get(i), cuts.get(i + 1)) else {
                break;
            };
            fm.walk(f, vfree, a, b);
            fm.invert(a, b);
            done.fetch_add(1, Ordering::Release);
        }
    });
    // (a range left undone: its thread panicked, as `run` lets it; the
    // serial form makes every row again, the same values)
    done.load(Ordering::Acquire) >= m
}
