//! The broad phase's member loop ([`PairContact::broad`]): each moving
//! member's world pose, box centre, travel (the speculative margin), box and
//! placed sphere or capsule, from the body poses and its own last pose only
//! — and on a team of threads ([`BroadTeam`], a [`Side`] of the ground's
//! job, src/contact/ground/team.rs), by ranges of members, the sweep and
//! the pairs' lists after on the calling thread. A member writes only its
//! own entries, with the same arithmetic on any thread: the same boxes, bit
//! for bit (docs/theory.md §"Islands", threads).

use super::super::ground::Side;
use super::super::narrow::prim::Round;
use super::super::travel::{margin, moved_from};
use super::{world_at, Member, PairContact};
use crate::spatial::Se3;
use nalgebra::Vector3;
use std::sync::Mutex;

/// Moving members a thread takes at once.
const CHUNK: usize = 128;

/// The fewest moving members whose loop is shared: below it the loop (a
/// few hundred instructions a member) is too short to be worth the wait
/// for a worker's chunk before the sweep, and runs here with the sweep.
const MIN_MEMBERS: usize = 512;

/// One member's entries.
pub(super) struct Placed<'a> {
    pub travel: &'a mut f64,
    pub lo: &'a mut [f64; 3],
    pub hi: &'a mut [f64; 3],
    pub round: &'a mut Option<Round>,
    pub pose: &'a mut Se3<f64>,
    pub centre: &'a mut Vector3<f64>,
}

/// Places member `m` (its box's `radius`; its placement the identity when
/// `at_body`) at the body poses `o_m_i`:
/// `step` = (the travel's scale, 0 for none; whether it is measured), `tv`
/// = (δ, c) of the margin max(δ, c·s).
#[inline(always)]
pub(super) fn place(
    m: &Member,
    o_m_i: &[Se3<f64>],
    (stepped, measure): (f64, bool),
    (delta, factor): (f64, f64),
    (radius, at_body): (f64, bool),
    out: Placed<'_>,
) {
    let w = world_at(m, o_m_i, at_body);
    let c = w.act_point(&m.shape.mid);
    // the speculative margin: max(δ, c·s), s how far the member
    // moved in the last step (docs/theory.md §"Speculative margin")
    if stepped > 0.0 && measure {
        let s = moved_from(out.centre, &c, out.pose, &w, radius);
        *out.travel = s * stepped;
    }
    let (lo, hi) = super::box_of(m, &w, &c, margin(delta, factor, *out.travel));
    (*out.lo, *out.hi) = (lo, hi);
    if m.shape.round.is_some() {
        *out.round = Round::of(&m.shape, &w);
    }
    *out.pose = w;
    *out.centre = c;
}

/// The member entries as raw pointers (with their lengths) for the threads.
#[derive(Clone, Copy)]
struct Shared {
    members: (*const Member, usize),
    radii: (*const f64, usize),
    at_body: (*const bool, usize),
    moving: (*const usize, usize),
    travel: (*mut f64, usize),
    lo: (*mut [f64; 3], usize),
    hi: (*mut [f64; 3], usize),
    rounds: (*mut Option<Round>, usize),
    poses: (*mut Se3<f64>, usize),
    centres: (*mut Vector3<f64>, usize),
}
// SAFETY: `moving` is strictly increasing (checked when made), so the chunks
// of its entries, each handed out once, are disjoint sets of members, and a
// member's entries are written only by the thread of its chunk; `members`,
// `radii`, `at_body` and `moving` are only read; every pointer is of a vector of the
// pairs borrowed mutably by the [`BroadTeam`] for as long as it lives, and
// not resized while it does.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// The broad phase as side work of the ground's job: the member chunks on
/// every thread, then the rest ([`PairContact::broad_rest`]) on the calling
/// thread.
pub(crate) struct BroadTeam<'a> {
    pairs: Mutex<&'a mut PairContact>,
    sh: Shared,
    o_m_i: &'a [Se3<f64>],
    step: (f64, bool),
    tv: (f64, f64),
    chunks: usize,
}

impl PairContact {
    /// The broad phase at the body poses `o_m_i` as side work of a job
    /// ([`BroadTeam`]): what precedes the member loop is done here.
    pub(crate) fn broad_team<'a>(&'a mut self, o_m_i: &'a [Se3<f64>]) -> BroadTeam<'a> {
        let step = self.broad_begin();
        let n = self.members.len();
        let ok = self.moving.windows(2).all(|w| w[0] < w[1]);
        let chunks = match ok && self.moving.len() >= MIN_MEMBERS {
            true => self.moving.len().div_ceil(CHUNK),
            false => 0,
        };
        let (ts, delta, factor) = self.travel.split();
        let sh = Shared {
            members: (self.members.as_ptr(), n),
            radii: (self.radii.as_ptr(), self.radii.len()),
            at_body: (self.at_body.as_ptr(), self.at_body.len()),
            moving: (self.moving.as_ptr(), if ok { self.moving.len() } else { 0 }),
            travel: (ts.as_mut_ptr(), ts.len()),
            lo: (self.sap.lo.as_mut_ptr(), self.sap.lo.len()),
            hi: (self.sap.hi.as_mut_ptr(), self.sap.hi.len()),
            rounds: (self.rounds.as_mut_ptr(), self.rounds.len()),
            poses: (self.poses.as_mut_ptr(), self.poses.len()),
            centres: (self.centres.as_mut_ptr(), self.centres.len()),
        };
        BroadTeam {
            pairs: Mutex::new(self),
            sh,
            o_m_i,
            step,
            tv: (delta, factor),
            chunks,
        }
    }
}

impl Side for BroadTeam<'_> {
    fn items(&self) -> usize {
        self.chunks
    }

    fn item(&self, k: usize) {
        let sh = self.sh;
        let (a, b) = (k.saturating_mul(CHUNK), (k + 1).saturating_mul(CHUNK));
        for i in a..b.min(sh.moving.1) {
            // SAFETY: i < the length of `moving` (checked by the range), a
            // vector only read while the team runs (see `Shared`)
            let k = unsafe { *sh.moving.0.add(i) };
            let lens = [
                sh.members.1,
                sh.radii.1,
                sh.at_body.1,
                sh.travel.1,
                sh.lo.1,
                sh.hi.1,
                sh.rounds.1,
                sh.poses.1,
                sh.centres.1,
            ];
            if lens.iter().any(|&l| k >= l) {
                continue;
            }
            // SAFETY: k within every vector (checked above); member k is
            // this chunk's alone (`moving` strictly increasing, see `Shared`)
            let (m, radius, out) = unsafe {
                (
                    &*sh.members.0.add(k),
                    (*sh.radii.0.add(k), *sh.at_body.0.add(k)),
                    Placed {
                        travel: &mut *sh.travel.0.add(k),
                        lo: &mut *sh.lo.0.add(k),
                        hi: &mut *sh.hi.0.add(k),
                        round: &mut *sh.rounds.0.add(k),
                        pose: &mut *sh.poses.0.add(k),
                        centre: &mut *sh.centres.0.add(k),
                    },
                )
            };
            place(m, self.o_m_i, self.step, self.tv, radius, out);
        }
    }

    fn rest(&self) {
        let mut p = match self.pairs.lock() {
            Ok(p) => p,
            Err(e) => e.into_inner(),
        };
        if self.chunks == 0 {
            // (no chunks, a small scene's: the member loop here)
            p.broad_members(self.o_m_i, self.step);
        }
        p.broad_rest();
    }
}
