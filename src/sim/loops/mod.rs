//! Loop constraints in a simulation (mechanisms.md §"Simulation"): each
//! `point`, `frame` or `joint` constraint adds bilateral rows (λ unbounded) to
//! the same impulse solve as contact and joint limits ([`super::solver`]), at
//! the velocity level (target J v⁺ = 0), and the position pass removes their
//! drift as it removes penetration (docs/theory.md §"Loops in the simulation").
//!
//! Position target of a loop row (w the position pass's pseudo-velocity,
//! q⁺ = q ⊕ h(v⁺ + w)): the step's configuration change leaves the row's
//! residual φ(q⁺) ≈ φ + h J(v⁺ + w) + ½h² γ with γ = J̇ v (the rows' velocity
//! product, the same γ_c as the constrained dynamics'); with J v⁺ = 0 the
//! target J w = −φ/h − ½hγ leaves a third-order residual. The −φ/h part is
//! capped (a start far off the constraint closes at a capped rate: gently,
//! without entering v).

mod project;
mod residual;

pub(in crate::sim) use residual::residual;

use super::factor::MassFactor;
use super::solver::{RowKind, Rows};
use crate::dynamics::constraint_dynamics::{bias_rows, jacobian_rows};
use crate::model::{ConstraintKind, Constraints as LoopSet, Data, Model};
use crate::spatial::Motion;
use nalgebra::{DMatrix, DVector, Vector3};

/// A loop row direction whose singular value is below this fraction of its
/// constraint's largest is dependent on the others and left out of the step
/// ([`Loops::directions`]).
const DEPENDENT: f64 = 1e-3;

/// The force a loop constraint exerted in the last step (world frame): on
/// `link1` at its point (the reaction on `link2`), or the generalized force on
/// `joint1` of a `joint` constraint.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopForce {
    /// The constraint's name.
    pub name: String,
    /// Force (N), world axes (zero for a `joint` constraint).
    pub force: Vector3<f64>,
    /// Torque (N·m), world axes (`frame` only; zero for `point`).
    pub torque: Vector3<f64>,
    /// A `joint` constraint's generalized force on joint1 (N·m or N).
    pub generalized: f64,
}

/// The loop constraints of a simulation and their per-step work.
#[derive(Clone, Debug)]
pub(crate) struct Loops {
    /// The constraints (held world anchors placed at the start).
    pub set: LoopSet,
    /// Whether each constraint takes part.
    pub active: Vec<bool>,
    jc: DMatrix<f64>,
    gamma: DVector<f64>,
    /// Each constraint's first row in the step's rows (None: inactive).
    row_of: Vec<Option<usize>>,
    /// Each constraint's first row in `jc`.
    first: Vec<usize>,
    /// Warm start and last impulse of each of the set's rows (world axes).
    lambda: Vec<f64>,
    /// Per constraint: the directions its rows took in the last step (the
    /// principal directions of its rows kept, each of `c.rows()` entries, in
    /// order), as a column-major `rows × kept` block.
    basis: Vec<Vec<f64>>,
    /// Per constraint: the directions kept in the last step.
    kept: Vec<usize>,
    /// The last step's length (for forces λ/h).
    h: f64,
    ov: Vec<Motion<f64>>,
    oa0: Vec<Motion<f64>>,
    dense: Vec<f64>,
    /// The passive run's reference energy (None: not yet, or driven, or
    /// closing a violated start).
    e_ref: Option<f64>,
    /// Scratch: each constraint's violation.
    viol: Vec<f64>,
    /// Per set row (the first `kept` of each constraint, along its kept
    /// directions): the residual the step's position target aims at, eᵀφ + h·close
    /// (0 unless a violated start closes at the capped rate).
    aim: Vec<f64>,
    /// The projection's scratch (project.rs).
    proj: project::Scratch,
}

impl Loops {
    /// Constraint `k`'s row directions in the last step: its world rows'
    /// principal directions kept (column-major, `c.rows() × kept`) and how
    /// many (the step Jacobians map world-row terms onto the step's rows).
    pub(in crate::sim) fn row_basis(&self, k: usize) -> (&[f64], usize) {
        (&self.basis[k], self.kept[k])
    }

    /// The loops of `set` on `model`.
    pub fn new(model: &Model, set: LoopSet) -> Self {
        let m = set.rows();
        let mut first = Vec::with_capacity(set.items.len());
        let mut r = 0;
        for c in &set.items {
            first.push(r);
            r += c.rows();
        }
        Self {
            active: vec![true; set.items.len()],
            row_of: vec![None; set.items.len()],
            first,
            jc: DMatrix::zeros(m, model.nv),
            gamma: DVector::zeros(m),
            lambda: vec![0.0; m],
            basis: set
                .items
                .iter()
                .map(|c| vec![0.0; c.rows() * c.rows()])
                .collect(),
            kept: vec![0; set.items.len()],
            h: 0.0,
            ov: vec![Motion::zero(); model.nbodies],
            oa0: vec![Motion::zero(); model.nbodies],
            dense: vec![0.0; model.nv],
            e_ref: None,
            viol: vec![0.0; set.items.len()],
            aim: vec![0.0; m],
            proj: project::Scratch::new(m, model.nv),
            set,
        }
    }

    /// Rows the set can add to a step.
    pub fn rows(&self) -> usize {
        self.set.rows()
    }

    /// Forgets the warm starts.
    pub fn reset_warm_start(&mut self) {
        self.lambda.iter_mut().for_each(|x| *x = 0.0);
    }

    /// Each body's world spatial velocity and velocity-product acceleration
    /// (q̈ = 0, no gravity) at (q, v), from `data.o_m_i`: v_i = v_λ + S_i q̇_i,
    /// a_i = a_λ + v_i × S_i q̇_i (world-frame S_i moves with body i).
    fn velocities(&mut self, model: &Model, data: &Data, v: &DVector<f64>) {
        for i in 1..model.nbodies {
            let j = &model.joints[i];
            let mut sv = Motion::zero();
            for k in 0..j.nv() {
                let s = data.o_m_i[i].act_motion(&j.subspace_column(k));
                let x = v[j.iv + k];
                sv.lin += s.lin * x;
                sv.ang += s.ang * x;
            }
            let p = model.parent[i];
            let mut vi = self.ov[p];
            vi.lin += sv.lin;
            vi.ang += sv.ang;
            let c = vi.cross(&sv);
            let mut ai = self.oa0[p];
            ai.lin += c.lin;
            ai.ang += c.ang;
            if matches!(j.kind, crate::model::JointKind::Free) {
                // The step moves a free joint's origin on a straight line
                // (p += h R v, R ← R exp(hω): integrate_config), not on the
                // constant-twist screw whose acceleration R(ω × v) a = 0 means:
                // the subtree's second-order term is γ's less R(ω × v)
                // (docs/theory.md §"Loops in the simulation").
                let r = data.o_m_i[i].rot;
                let vl = Vector3::new(v[j.iv], v[j.iv + 1], v[j.iv + 2]);
                let w = Vector3::new(v[j.iv + 3], v[j.iv + 4], v[j.iv + 5]);
                ai.lin -= r * w.cross(&vl);
            }
            self.ov[i] = vi;
            self.oa0[i] = ai;
        }
    }

    /// The rows of the active constraints appended to `rows` at (q, v) for a
    /// step `h` (`data.o_m_i`: world poses at q): J, target 0, position target
    /// (module doc). `cap`: the largest rate (m/s, rad/s) at which a violation
    /// is closed. Returns (rows added, whether any position target is set).
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        &mut self,
        rows: &mut Rows,
        model: &Model,
        data: &Data,
        q: &DVector<f64>,
        v: &DVector<f64>,
        f: &MassFactor,
        h: f64,
        cap: f64,
    ) -> (usize, bool) {
        self.h = h;
        jacobian_rows(model, data, &self.set, &mut self.jc);
        self.velocities(model, data, v);
        let (ov, oa0) = (&self.ov, &self.oa0);
        bias_rows(data, &self.set, |b| ov[b], |b| oa0[b], &mut self.gamma);
        let body_path = |b: usize| {
            if b == 0 {
                return (0, 0);
            }
            let jb = &model.joints[b];
            f.path_of((jb.iv + jb.nv()).saturating_sub(1))
        };
        let (mut added, mut violated) = (0, false);
        for (k, c) in self.set.items.iter().enumerate() {
            self.row_of[k] = None;
            if !self.active[k] {
                continue;
            }
            let path = match &c.kind {
                ConstraintKind::Joint { v1, second, .. } => {
                    let a = f.path_of(*v1);
                    match second {
                        Some((_, v2)) => rows.union_path(a, f.path_of(*v2)),
                        None => a,
                    }
                }
                _ => rows.union_path(body_path(c.a.body), body_path(c.b.body)),
            };
            let phi = residual(c, data, q.as_slice());
            let first = self.first[k];
            let m = c.rows();
            let kept = directions(&self.jc, first, m, &mut self.basis[k]);
            self.kept[k] = kept;
            let start = rows.n;
            let mut full = true;
            for t in 0..kept {
                let e = &self.basis[k][t * m..(t + 1) * m];
                let along = |x: &[f64]| e.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
                let warm = along(&self.lambda[first..first + m]);
                let Some(r) = rows.push(RowKind::Bilateral, 0.0, warm, path) else {
                    full = false;
                    break;
                };
                for (d, x) in self.dense.iter_mut().enumerate() {
                    *x = (0..m).map(|i| e[i] * self.jc[(first + i, d)]).sum();
                }
                rows.gather(r, &mut self.dense);
                let close = (-along(&phi[..m]) / h).clamp(-cap, cap);
                self.aim[first + t] = along(&phi[..m]) + h * close;
                let gamma = along(&self.gamma.as_slice()[first..first + m]);
                rows.bpos[r] = close - 0.5 * h * gamma;
                violated |= rows.bpos[r] != 0.0;
            }
            if !full {
                rows.pop(rows.n - start);
                break;
            }
            self.row_of[k] = Some(start);
            added += kept;
        }
        (added, violated)
    }

    /// Reads the step's impulses back (warm starts, forces), in world axes.
    pub fn read(&mut self, rows: &Rows) {
        for (k, c) in self.set.items.iter().enumerate() {
            let (first, m) = (self.first[k], c.rows());
            let out = &mut self.lambda[first..first + m];
            out.iter_mut().for_each(|x| *x = 0.0);
            let Some(r) = self.row_of[k] else {
                continue;
            };
            for t in 0..self.kept[k] {
                let l = rows.lambda[r + t];
                for (i, x) in out.iter_mut().enumerate() {
                    *x += self.basis[k][t * m + i] * l;
                }
            }
        }
    }

    /// The force of each constraint in the last step (λ/h, world).
    pub fn forces(&self) -> Vec<LoopForce> {
        let h = if self.h > 0.0 { self.h } else { 1.0 };
        self.set
            .items
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let l = &self.lambda[self.first[k]..self.first[k] + c.rows()];
                let mut out = LoopForce {
                    name: c.name.clone(),
                    force: Vector3::zeros(),
                    torque: Vector3::zeros(),
                    generalized: 0.0,
                };
                match c.kind {
                    ConstraintKind::Joint { .. } => out.generalized = l[0] / h,
                    ConstraintKind::Point => out.force = Vector3::new(l[0], l[1], l[2]) / h,
                    ConstraintKind::Frame => {
                        out.force = Vector3::new(l[0], l[1], l[2]) / h;
                        out.torque = Vector3::new(l[3], l[4], l[5]) / h;
                    }
                }
                out
            })
            .collect()
    }

    /// The largest violation over the active constraints at the state whose
    /// forward kinematics `data` holds (mechanisms.md's measure).
    pub fn violation(&self, data: &Data, q: &DVector<f64>, out: &mut [f64]) -> f64 {
        self.set.violation(data, q.as_slice(), out);
        out.iter()
            .zip(&self.active)
            .filter(|(_, a)| **a)
            .fold(0.0, |m, (x, _)| m.max(x.abs()))
    }
}

/// The directions of a constraint's rows this step (its `m` rows from
/// `first` in `jc`) into `e` (column-major, m × kept); returns how many are kept. A `joint`
/// constraint keeps its row. A `point` or `frame` constraint's rows are
/// turned onto the principal directions of its Jacobian block J_k
/// (eigenvectors of J_k J_kᵀ, largest first), and a direction whose
/// singular value is below [`DEPENDENT`] times the largest is dropped: a
/// planar loop closed by a 3-D point has a row that is identically zero on
/// the closed mechanism and, off it, a tiny row nearly dependent on the
/// others, whose exact enforcement asks for unbounded impulses
/// (docs/theory.md §"Loops in the simulation").
fn directions(jc: &DMatrix<f64>, first: usize, m: usize, e: &mut [f64]) -> usize {
    if m == 1 {
        e[0] = 1.0;
        return 1;
    }
    let nv = jc.ncols();
    let g = DMatrix::from_fn(m, m, |i, j| {
        (0..nv)
            .map(|d| jc[(first + i, d)] * jc[(first + j, d)])
            .sum::<f64>()
    });
    let eig = nalgebra::SymmetricEigen::new(g);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let top = eig.eigenvalues[order[0]];
    let mut kept = 0;
    for &o in &order {
        let ev = eig.eigenvalues[o];
        if !(top > 0.0 && ev > DEPENDENT * DEPENDENT * top) {
            break;
        }
        for i in 0..m {
            e[kept * m + i] = eig.eigenvectors[(i, o)];
        }
        kept += 1;
    }
    kept
}

impl super::Simulation {
    /// Adds the loop constraints `set` (built against this simulation's model)
    /// to the run: held world anchors are placed where their side is in the
    /// current state (set the start first). Replaces any earlier set. Returns
    /// one line for each constraint the current state violates by more than
    /// 1 mm (mechanisms.md §"Simulation": the run closes it gently).
    pub fn set_constraints(&mut self, mut set: LoopSet) -> Result<Vec<String>, super::SimError> {
        for c in &set.items {
            let bodies = [c.a.body, c.b.body];
            if bodies.iter().any(|&b| b >= self.model.nbodies) {
                return Err(super::SimError::Invalid(format!(
                    "constraint \"{}\" names a body this model does not have",
                    c.name
                )));
            }
        }
        crate::dynamics::forward_kinematics_pass(&self.model, &mut self.data, &self.q);
        self.fk_valid = true;
        set.place_holds(&self.data);
        let loops = Loops::new(&self.model, set);
        let max_points = self.contact.as_ref().map_or(0, |c| c.max_points());
        let pair_points = self
            .contact
            .as_ref()
            .and_then(|c| c.pairs.as_ref())
            .map_or(0, |p| p.max_points());
        let nslots = self.contact.as_ref().map_or(0, |c| c.nslots);
        self.cons = super::constraints::Constraints::with_loops(
            &self.model,
            &self.mass.f,
            max_points,
            pair_points,
            nslots,
            self.opts.solver == super::Solver::Newton,
            Some(loops),
        );
        self.cons.set_threads(self.opts.threads);
        self.sleep.joins = self.loop_body_pairs();
        let mut out = vec![0.0; self.loop_count()];
        let mut lines = Vec::new();
        if let Some(l) = self.cons.loops.as_ref() {
            l.violation(&self.data, &self.q, &mut out);
            for (c, x) in l.set.items.iter().zip(&out) {
                if x.abs() > 1e-3 {
                    lines.push(format!(
                        "constraint \"{}\" ({}) is violated by {:.3e} at the start: the run closes it gently",
                        c.name,
                        c.kind_name(),
                        x.abs()
                    ));
                }
            }
        }
        if self.restart_loops() {
            // Closing a violated start moves energy in and out (the position
            // pass): the divergence test waits as for any violated start.
            self.guard.reference = None;
            self.guard.recovering_until = Some(self.t + 2.0);
        }
        Ok(lines)
    }

    /// At the start of a run (`set_constraints`, `set_state`): the passive
    /// energy reference taken from the state when its loops are closed, else
    /// dropped until they close; returns whether a loop is open (above 1e-6).
    pub(super) fn restart_loops(&mut self) -> bool {
        if self.loop_count() == 0 {
            return false;
        }
        let open = self.constraint_violation() > 1e-6;
        // cached: state_changed's divergence reference reads the same value
        let e = self.update_energy();
        if let Some(l) = self.cons.loops.as_mut() {
            l.e_ref = if open { None } else { Some(e) };
        }
        open
    }

    /// The loop constraint set's largest violation above 1e-3 while closing
    /// a violated start (the divergence test's recovery).
    pub(super) fn loops_recovering(&mut self) -> bool {
        self.loop_count() > 0 && self.constraint_violation() > 1e-3
    }

    /// The loop constraints of the run, if any.
    pub fn constraints(&self) -> Option<&LoopSet> {
        self.cons.loops.as_ref().map(|l| &l.set)
    }

    fn loop_count(&self) -> usize {
        self.cons.loops.as_ref().map_or(0, |l| l.set.items.len())
    }

    /// Whether the run has loop constraints.
    pub fn has_constraints(&self) -> bool {
        self.loop_count() > 0
    }

    /// Each loop constraint's force in the last step (world; λ/Δt), in the
    /// set's order; an inactive constraint's is zero.
    pub fn constraint_forces(&self) -> Vec<LoopForce> {
        self.cons.loops.as_ref().map_or(Vec::new(), |l| l.forces())
    }

    /// Switches the loop constraint `name` on or off (an unknown name is an
    /// error naming it). Switching one on wakes the run.
    pub fn set_constraint_active(&mut self, name: &str, on: bool) -> Result<(), super::SimError> {
        let l = self.cons.loops.as_mut().ok_or_else(|| {
            super::SimError::Invalid(format!("no constraint named \"{name}\": the run has none"))
        })?;
        let k = l
            .set
            .index(name)
            .ok_or_else(|| super::SimError::Invalid(format!("no constraint named \"{name}\"")))?;
        l.active[k] = on;
        self.sleep.joins = self.loop_body_pairs();
        self.wake();
        Ok(())
    }

    /// The largest violation over the active loop constraints now (m, rad; 0
    /// without constraints), and each constraint's in `out` when given.
    pub fn constraint_violation(&mut self) -> f64 {
        let n = self.loop_count();
        if n == 0 {
            return 0.0;
        }
        if !self.fk_valid {
            crate::dynamics::forward_kinematics_pass(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        let mut out = vec![0.0; n];
        self.cons
            .loops
            .as_ref()
            .map_or(0.0, |l| l.violation(&self.data, &self.q, &mut out))
    }

    /// A passive run with loops keeps its energy at or below the reference
    /// (docs/theory.md §"Loops in the simulation"): the time-stepping scheme's
    /// O(h) energy oscillation, which a closed chain's coupled rows do not damp,
    /// is clipped by scaling v (J v = 0 kept: the rows are linear in v) so that
    /// T + V never exceeds the energy of the first closed state, lowered to the
    /// lowest energy of the steps in contact since. The
    /// reference is dropped while driven (servo, torques) or while a violated
    /// start closes (violation above 1e-6), and taken afresh after.
    pub(super) fn clip_loop_energy(&mut self) {
        let passive = !self.servo.active && self.tau_applied.iter().all(|&x| x == 0.0);
        if !self.fk_valid {
            crate::dynamics::forward_kinematics_pass(&self.model, &mut self.data, &self.q);
            self.fk_valid = true;
        }
        let armature = self.armature_energy();
        let touching = !self.cons.contact_forces().is_empty();
        let Some(l) = self.cons.loops.as_mut() else {
            return;
        };
        let mut viol = std::mem::take(&mut l.viol);
        let worst = l.violation(&self.data, &self.q, &mut viol);
        l.viol = viol;
        if !passive || worst > 1e-6 {
            l.e_ref = None;
            return;
        }
        let ke =
            crate::dynamics::kinetic_energy_from_placements(&self.model, &mut self.data, &self.v)
                .unwrap_or(f64::NAN)
                + armature;
        let pe = crate::dynamics::potential_energy(&self.model, &self.data);
        let Some(e_ref) = l.e_ref else {
            l.e_ref = Some(ke + pe);
            return;
        };
        if ke + pe > e_ref && ke > 0.0 {
            let s = ((e_ref - pe).max(0.0) / ke).sqrt();
            self.v *= s;
            self.energy_now = None;
        } else if touching {
            // while something touches, the reference follows the lowest energy
            // so far (contact and friction only take energy out of a passive
            // run); without contact it stays (a conservative mechanism keeps
            // its energy, and lowering the reference at each dip of the
            // scheme's oscillation would damp it)
            l.e_ref = Some(e_ref.min(ke + pe));
        }
    }

    /// The trees (models of a scene) each active loop constraint joins, for
    /// the islands: pairs of bodies.
    pub(super) fn loop_body_pairs(&self) -> Vec<(usize, usize)> {
        let Some(l) = self.cons.loops.as_ref() else {
            return Vec::new();
        };
        l.set
            .items
            .iter()
            .zip(&l.active)
            .filter(|(_, a)| **a)
            .map(|(c, _)| match c.kind {
                ConstraintKind::Joint { v1, second, .. } => {
                    let body = |iv: usize| {
                        (1..self.model.nbodies)
                            .find(|&b| {
                                let j = &self.model.joints[b];
                                iv >= j.iv && iv < j.iv + j.nv()
                            })
                            .unwrap_or(0)
                    };
                    (body(v1), second.map_or(0, |(_, v2)| body(v2)))
                }
                _ => (c.a.body, c.b.body),
            })
            .collect()
    }
}
