//! One step's constraints: the rows of ground contact (normal + Coulomb cone),
//! joint Coulomb friction and joint position limits at (q, v), their impulses
//! by [`solver`], and what those impulses do.
//!
//! With H̃ = H + A + Δt·D (A the armature, D the joint damping: damping is
//! implicit, see [`super`]) factored as L Lᵀ and the free velocity v*, the
//! impulses λ give the end-of-step velocity v⁺ = v* + H̃⁻¹Jᵀλ (the
//! time-stepping scheme of Stewart–Trinkle / Anitescu), and the position pass
//! a pseudo-velocity w = H̃⁻¹Jᵀμ that removes penetration and limit violations
//! at a capped rate without entering v (split impulse).
//!
//! Row targets (u = J v⁺, φ the signed gap: contact distance, or distance to a
//! joint limit):
//! - φ > 0: b = −φ/Δt (speculative: the gap may close within the step, not
//!   overshoot); φ ≤ 0: b = 0 (no push-out in the velocity: it would become
//!   kinetic energy); restitution e > 0 raises b to −e·u⁻ on fast impacts;
//! - position pass: b_pos = min(β(−φ − slop)/Δt, cap) where φ < −slop.

mod free;
mod joints;
mod point;
mod solve;
mod spin;
mod tables;
mod team;

use super::factor::MassFactor;
use super::islands::Islands;
use super::loops::Loops;
use super::newton::Newton;
use super::parallel::Team;
use super::solver::{PosWarm, RowKind, Rows, Scratch};
use super::{ContactForce, Solver};
use crate::contact::{tangents, ContactPoint};
use crate::model::{JointKind, Model};
use crate::spatial::{Force, Motion, Se3};
pub(crate) use free::free_rows;
use nalgebra::{DVector, Vector3};
use std::sync::Arc;
pub(crate) use tables::add_body_rows;
use tables::{BodyColumns, BodyHead, JointRowSource};

/// The least row-sweeps a parallel solve must take off this thread's share
/// (else the islands are solved here). A worker sleeps between jobs, so a
/// dispatch pays its wake-up: at 500 the 64-box pile went to the team on
/// about a third of its solves, the worker took 11 % of the work and two
/// threads ran 7 % slower than one (quiet A/B, benches/pile_results.md,
/// round 28); at 2000 it stays here, the 256- and 1024-object piles
/// (6,000–48,000 row-sweeps a solve) still go to the team.
const MIN_WORK: usize = 2000;

/// What the rows are built from, besides the state.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowParams {
    /// Joint friction and limits on.
    pub joint_dynamics: bool,
    /// Newton restitution coefficient e of ground impacts (0: inelastic).
    pub restitution: f64,
    /// |g| (for the restitution threshold).
    pub gravity: f64,
    /// Fraction of a violation removed per step by the position pass.
    pub beta: f64,
    /// Caps of the position pass's rate: contact (m/s), joint limit (rad/s or m/s).
    pub contact_push_cap: f64,
    /// The joint-limit cap (rad/s or m/s).
    pub limit_push_cap: f64,
    /// Violations below these are left alone (m, rad).
    pub contact_slop: f64,
    /// The joint-limit slop (rad or m).
    pub limit_slop: f64,
    /// Torsional friction coefficient (m; 0: no torsion rows), [`spin`].
    pub torsion: f64,
    /// Rolling friction coefficient (m; 0: no rolling rows), [`spin`].
    pub rolling: f64,
}

/// How many rows of each kind one assembly made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct RowCounts {
    /// Joint-friction rows (one per joint with URDF friction).
    pub friction: usize,
    /// Joint-limit rows (one per joint within reach of a limit).
    pub limits: usize,
    /// Contact points (three rows each: normal and two tangents).
    pub contacts: usize,
    /// Rows whose constraint is violated (position pass needed).
    pub violated: usize,
    /// Loop-constraint rows (bilateral).
    pub loops: usize,
    /// Torsional and rolling friction rows ([`spin`]).
    pub spin: usize,
}

impl RowCounts {
    /// All rows: friction + limits + 3 · contacts.
    pub fn total(&self) -> usize {
        self.friction + self.limits + 3 * self.contacts + self.loops + self.spin
    }
    /// Whether the step touches anything (a contact point or a joint limit):
    /// such a step is taken by the time-stepping scheme.
    pub fn touching(&self) -> bool {
        self.limits + self.contacts + self.loops > 0
    }
}

/// The solve's result: views into the workspace, valid until the next solve.
pub(crate) struct Impulses<'a> {
    /// H̃⁻¹Jᵀλ: v⁺ = v* + dv.
    pub dv: &'a DVector<f64>,
    /// The position pass's pseudo-velocity w (None: nothing violated).
    pub push: Option<&'a DVector<f64>>,
    /// Generalized force of the joint rows (friction, limits), Jᵀλ/Δt.
    pub tau_joint: &'a DVector<f64>,
    /// PGS sweeps used (velocity solve).
    pub sweeps: usize,
}

/// Preallocated rows, warm starts and results.
#[derive(Clone, Debug)]
pub(crate) struct Constraints {
    rows: Rows,
    /// (dof, which): which = 0 friction, 1 lower limit, 2 upper limit, per joint row.
    joint_rows: Vec<(usize, u8)>,
    /// The 1-DoF joints that may have rows (friction, or a limit), in dof order.
    jrows: Vec<JointRowSource>,
    /// The first joint row (contact triples come first).
    first_joint_row: usize,
    /// The contact point (index into the step's points) of each contact triple.
    row_point: Vec<usize>,
    /// The contacts whose rows the team writes ([`team`]), this step's.
    fixed: Vec<team::Fixed>,
    /// The bodies whose world columns the team computes ([`team`]).
    bodies: Vec<usize>,
    /// Warm-start impulses per contact slot (n, t1, t2, and the position
    /// pass's μ of the normal: solver/position.rs) and per joint (friction,
    /// lower, upper, and the position pass's μ of the lower and upper limit).
    warm_contact: Vec<[f64; 4]>,
    /// The slots of `warm_contact` written by the last solve (only these are cleared).
    warm_slots: Vec<usize>,
    warm_joint: Vec<[f64; 5]>,
    /// This step's warm starts of the points, gathered before the rows are
    /// built (the loads are independent there: their cache misses overlap).
    warm_points: Vec<[f64; 3]>,
    /// The position pass's start by row (gathered from `warm_contact`'s and
    /// `warm_joint`'s μ entries).
    pos_warm: PosWarm,
    /// World-frame motion subspace columns of each body (≤ 6), set this
    /// step where `sw_done` holds `sw_stamp`.
    sw: Vec<[Motion; 6]>,
    sw_done: Vec<u64>,
    /// Each body's joint's motion subspace columns in the body frame (the
    /// joint's constants: kind, axis, `mult`), the world-frame ones' source.
    cols: Vec<BodyColumns>,
    /// `cols`' first dofs, counts and zero angular parts (what the contacts'
    /// walks read, [`BodyHead`]).
    heads: Vec<BodyHead>,
    sw_stamp: u64,
    counts: RowCounts,
    dv: DVector<f64>,
    push: DVector<f64>,
    tau_joint: DVector<f64>,
    /// Some entry of `tau_joint` may be nonzero (a joint row's force added
    /// since it was last zeroed).
    tau_written: bool,
    fext: Vec<Force>,
    contact_forces: Vec<ContactForce>,
    /// R v* (the energy-safe exit's work).
    a: Vec<f64>,
    newton: Newton,
    /// Dense scratch of a contact's three Jacobian rows (3·nv, all zero
    /// between contacts: [`Rows::gather`] zeroes what it reads).
    jd: Vec<f64>,
    /// The loop constraints (none: a run without loops, untouched).
    pub loops: Option<Loops>,
    /// This step's islands of rows (the PGS solve's units).
    islands: Islands,
    /// The threads islands are solved on (`None`: this one).
    team: Option<Arc<Team>>,
    /// The islands of a parallel solve, largest first ([`parallel::cut`]).
    order: Vec<(usize, usize)>,
    /// Row-sweeps per row of the last solve's islands (its first round): the
    /// next solve's estimate of its work.
    per_row: f64,
    /// A subspace step's scratch for each thread (at least one).
    scratch: Vec<Scratch>,
    /// Torsional and rolling friction rows ([`spin`]).
    spin: spin::Spin,
    /// Each island's sweeps in the last solve.
    isl_sweeps: Vec<usize>,
    /// Rows times sweeps of every solve so far (velocity, energy-safe exit and
    /// position pass): the solve's work, independent of the machine.
    pub work: u64,
}

impl Constraints {
    /// Room for `max_points` contact points (`pair_points` of them between
    /// two bodies) and every joint's three rows; `f`: the factor the rows'
    /// paths index; `newton`: the Newton solver's dense work is needed (nv²).
    pub fn new(
        model: &Model,
        f: &MassFactor,
        max_points: usize,
        pair_points: usize,
        nslots: usize,
        newton: bool,
    ) -> Self {
        Self::with_loops(model, f, max_points, pair_points, nslots, newton, None)
    }

    /// [`Constraints::new`] with room for the rows of `loops` too.
    pub fn with_loops(
        model: &Model,
        f: &MassFactor,
        max_points: usize,
        pair_points: usize,
        nslots: usize,
        newton: bool,
        loops: Option<Loops>,
    ) -> Self {
        let ndof = model.dofs.len();
        let cap = (3 + spin::Spin::MAX_ROWS_PER_POINT) * max_points
            + 3 * ndof
            + loops.as_ref().map_or(0, |l| l.rows());
        let nv = model.nv;
        // a row's room: two bodies' paths to the root (a dense factor's are nv long)
        let longest = (0..nv).map(|d| f.path_of(d).1).max().unwrap_or(0);
        let mut rows = Rows::new(nv, cap, 2 * longest);
        rows.set_table(f.table(), pair_points);
        // the dofs of joints other than free ones: islands reaching one shed
        // their self-stress (solver/stress.rs)
        let mut jointed = vec![false; nv];
        for j in model.joints.iter().skip(1) {
            if j.kind != JointKind::Free {
                for x in jointed.iter_mut().skip(j.iv).take(j.nv()) {
                    *x = true;
                }
            }
        }
        rows.set_jointed(&jointed);
        let rows_scratch = rows.scratch();
        let cols: Vec<_> = (0..model.nbodies)
            .map(|i| BodyColumns::of(model, i))
            .collect();
        Self {
            rows,
            joint_rows: Vec::with_capacity(3 * ndof),
            jrows: JointRowSource::of(model),
            first_joint_row: 0,
            row_point: Vec::with_capacity(max_points),
            fixed: Vec::new(),
            bodies: Vec::new(),
            warm_contact: vec![[0.0; 4]; nslots],
            warm_slots: Vec::with_capacity(max_points),
            warm_joint: vec![[0.0; 5]; ndof],
            warm_points: Vec::with_capacity(max_points),
            pos_warm: PosWarm::new(cap),
            sw: vec![[Motion::zero(); 6]; model.nbodies],
            sw_done: vec![0; model.nbodies],
            heads: (cols.iter().enumerate())
                .map(|(i, c)| BodyHead {
                    free: BodyHead::of(c).free && model.parent.get(i) == Some(&0),
                    ..BodyHead::of(c)
                })
                .collect(),
            cols,
            sw_stamp: 0,
            counts: RowCounts::default(),
            dv: DVector::zeros(nv),
            push: DVector::zeros(nv),
            tau_joint: DVector::zeros(nv),
            tau_written: false,
            fext: vec![Force::zero(); model.nbodies],
            contact_forces: Vec::with_capacity(max_points),
            a: vec![0.0; nv],
            jd: vec![0.0; 3 * nv],
            newton: Newton::new(if newton { nv } else { 0 }, if newton { cap } else { 0 }),
            loops,
            islands: Islands::new(model, cap),
            team: None,
            order: Vec::new(),
            per_row: 1.0,
            scratch: vec![rows_scratch],
            spin: spin::Spin::new(max_points, nslots),
            isl_sweeps: vec![0; model.trees.len() + 1],
            work: 0,
        }
    }

    /// Solves the islands on `threads` threads (0: every core; 1: this
    /// thread, the default): the same results bit for bit whatever the count
    /// (scene.md §"Large scenes: islands and sleep"). A pool that cannot be
    /// started leaves the solve on this thread.
    pub fn set_threads(&mut self, threads: usize) {
        self.team = None;
        self.scratch.truncate(1);
        let n = match threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        let Some(team) = Team::new(n) else {
            return;
        };
        while self.scratch.len() < team.threads() {
            self.scratch.push(self.rows.scratch());
        }
        self.team = Some(Arc::new(team));
    }

    /// The team of threads (`None`: one thread), for the step's other
    /// parallel stages (the pairs' narrow phase).
    pub(crate) fn team(&self) -> Option<&Team> {
        self.team.as_deref()
    }

    /// Forgets the warm starts (a new state was set).
    pub fn reset_warm_start(&mut self) {
        // the self-stress shedding's count of solves goes with them
        self.rows.forget_solves();
        self.warm_contact.iter_mut().for_each(|w| *w = [0.0; 4]);
        self.spin.reset();
        if let Some(l) = self.loops.as_mut() {
            l.reset_warm_start();
        }
        self.warm_joint.iter_mut().for_each(|w| *w = [0.0; 5]);
        self.warm_slots.clear();
    }

    /// Keeps the warm starts of the slots flagged in `held` (per slot)
    /// through the next solves (a dozing island's contacts, kept aside until
    /// its next full step: `sim::doze`).
    pub fn hold_warm(&mut self, held: &[bool]) {
        self.warm_slots.retain(|&k| held.get(k) != Some(&true));
    }

    /// Forgets the last step's forces (a step taken without constraints).
    pub fn clear_forces(&mut self) {
        self.fext.iter_mut().for_each(|f| *f = Force::zero());
        self.contact_forces.clear();
        // (zeros already where no joint row added to it: a pile's steps)
        if self.tau_written {
            self.tau_joint.as_mut_slice().fill(0.0);
            self.tau_written = false;
        }
    }

    /// Rows of the last assembly.
    pub fn rows_len(&self) -> usize {
        self.rows.n
    }
    /// The contact points that carried force in the last solve, with their forces.
    pub fn contact_forces(&self) -> &[ContactForce] {
        &self.contact_forces
    }
    /// The contact wrench on each body from the last solve (world frame, at the
    /// world origin; entry 0 is the world).
    pub fn body_forces(&self) -> &[Force] {
        &self.fext
    }

    /// The rows of the last assembly and their impulses after the last solve
    /// (the step's derivatives read them, `sim/derivatives`).
    pub fn rows_view(&self) -> &Rows {
        &self.rows
    }
    /// The contact point (index into the step's points) of each contact triple.
    pub fn row_points(&self) -> &[usize] {
        &self.row_point
    }
    /// H̃⁻¹Jᵀλ of the last solve.
    pub fn impulse_velocity(&self) -> &DVector<f64> {
        &self.dv
    }
    /// The last solve's position-pass pseudo-velocity w, if it ran.
    pub fn push_velocity(&self) -> Option<&DVector<f64>> {
        (self.counts.violated > 0).then_some(&self.push)
    }

    /// Builds the rows at (q, v) for a step `h`: joint friction and limits
    /// (within 1 mm + 2|v|h of a limit), then three rows per contact point.
    /// `o_m_i` are the world poses at q (contact Jacobians are built from them).
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &mut self,
        model: &Model,
        o_m_i: &[Se3<f64>],
        q: &DVector<f64>,
        v: &DVector<f64>,
        points: &[ContactPoint],
        p: &RowParams,
        f: &MassFactor,
        h: f64,
    ) -> RowCounts {
        // the last solve's torsion and rolling impulses: warm starts
        self.spin.save(&self.rows);
        self.spin.torsion = p.torsion;
        self.spin.rolling = p.rolling;
        self.spin.touch = p.contact_slop.max(1e-6);
        self.pos_warm.set_beta(p.beta);
        let rows = &mut self.rows;
        // the last assembly's contact rows (the first rows) are zeroed one
        // contact at a time below, just before they are written again
        let keep = 3 * self.row_point.len();
        rows.clear_but(keep);
        self.joint_rows.clear();
        self.row_point.clear();
        let mut counts = RowCounts::default();
        // contact rows first: a sweep then meets the joint rows (friction,
        // limits) after the contacts have moved (talos_reduced, whose every
        // joint has friction, converged in fewer sweeps this way)
        if !points.is_empty() {
            self.sw_stamp = self.sw_stamp.wrapping_add(1).max(1);
            // on a team, the same rows by ranges of bodies and of contacts
            // ([`team`]); rows of a pile's stride only (their zeroing reads
            // no path)
            let team = match points.len() >= team::MIN_POINTS && rows.stride <= Rows::GAP {
                true => self.team.clone(),
                false => None,
            };
            if let Some(team) = team {
                let x = (model, o_m_i, v.as_slice(), p, h);
                self.contacts_on_team(&team, x, points, f, keep, &mut counts);
            } else {
                self.contacts(model, o_m_i, v, points, p, f, h, keep, &mut counts);
            }
            let rows = &mut self.rows;
            rows.zero_stale(keep);
            // torsional and rolling friction where a pair has few points
            let (sw, rp) = (&self.sw[..], &self.row_point[..]);
            counts.spin = self.spin.push(rows, model, sw, points, rp, &mut self.jd);
        } else {
            rows.zero_stale(keep);
        }
        self.first_joint_row = self.rows.n;
        self.assemble_joint_rows(q, v, p, f, h, &mut counts);
        self.counts = counts;
        counts
    }
}

/// The nearest common ancestor-or-self of bodies `a` and `b` (`parent[i] <
/// i`: the greater steps up until they meet), 0 (the world) for two trees or
/// where `parent` does not reach them.
#[inline]
fn common_ancestor(parent: &[usize], mut a: usize, mut b: usize) -> usize {
    while a != b {
        let x = if a > b { &mut a } else { &mut b };
        match parent.get(*x) {
            Some(&p) if p < *x => *x = p,
            _ => return 0,
        }
    }
    a
}

/// A row's velocity target for a gap φ: b = −φ/Δt while φ > 0 (speculative:
/// the gap may close within the step, not overshoot), else 0.
#[inline]
fn speculative(gap: f64, h: f64) -> f64 {
    if gap > 0.0 {
        -gap / h
    } else {
        0.0
    }
}

/// The position pass's target for a gap φ: b_pos = min(β(−φ − slop)/Δt, cap)
/// where φ < −slop, else 0.
#[inline]
fn pos_target(gap: f64, slop: f64, cap: f64, beta: f64, h: f64) -> f64 {
    if gap < -slop {
        (beta * (-gap - slop) / h).min(cap)
    } else {
        0.0
    }
}
