//! Doze: a multirate step for the quiet islands of a run with sleep on
//! (issue #30; scene.md §"Large scenes: islands and sleep").
//!
//! An island that could sleep but for time (every tree in it may sleep: not
//! `never`, not driven, and each still, slower than `sleep_velocity`, for at
//! least [`T_DOZE`]) dozes: for the next [`N_DOZE`] − 1 steps its trees are
//! masked as a sleeping island's are (left out of detection, of the factor and
//! of the bias pass; their contact points and forces kept aside with the frozen
//! ones for `contacts`, `penetration` and the forces), and each such step holds
//! their velocity and integrates their configuration, q ← q ⊕ h v (the model's
//! own free-joint integration, `integrate_free`). Then they take a full step
//! (found by detection, in the rows and the solve) and may doze again.
//!
//! Holding v is the exact step at an equilibrium (gravity and support
//! cancel) and drifts by at most N_DOZE·h·sleep_velocity otherwise (8 µm at
//! 1 ms and 1e-3 m/s, far inside the contact margin: no contact appears
//! unseen between full steps). The last solve's Δv is not replayed: it holds
//! the velocity-cancelling part −(v + h g) and its replay diverges.
//!
//! A dozing tree is awake: it counts in `awake`, `sleeping` is false for it,
//! its still time runs on (its speed is held below the threshold), and its
//! island falls asleep when that time reaches `sleep_time`, as an awake one
//! does. It takes a full step at once when an awake body that does not doze
//! touches it (a contact point joins them, the path `wake_touched` takes for
//! a sleeping island) and when the forcing or the state is set (`wake`).
//! Nothing but the step count and the state decides: the run is as
//! deterministic as without it.

use super::sleep::{copy_range, Sleep};
use super::ContactForce;
use crate::contact::ContactPoint;
use crate::model::configuration::integrate_free;
use crate::model::Model;
use crate::spatial::Force;
use nalgebra::DVector;

/// How long (s) every tree of an island is still before it dozes: a tossed
/// ball at its apex or a pendulum at a turning point is slow for a few ms only.
pub(super) const T_DOZE: f64 = 0.05;
/// A tree dozes only while its speed at a full step is below this fraction
/// of `sleep_velocity`: a slowly creeping one, whose speed crosses the
/// threshold now and then, is tested at every step.
pub(super) const DOZE_SPEED: f64 = 0.5;
/// A dozing island takes a full step every `N_DOZE` steps.
pub(super) const N_DOZE: u32 = 8;

/// The dozing state of a simulation's trees.
#[derive(Clone, Debug)]
pub(crate) struct Doze {
    /// Doze is on (sleep on, and not turned off by [`super::Simulation::set_doze`]).
    pub on: bool,
    /// Per tree: dozing steps left (0: not dozing).
    pub left: Vec<u32>,
    /// Per tree: it stopped dozing before this step's detection (it takes a
    /// full step before it may doze again).
    fresh: Vec<bool>,
    /// Per tree: its island's root when it began to doze.
    root: Vec<usize>,
    /// The velocity the dozing trees are held at.
    v_held: DVector<f64>,
    /// Some tree dozes.
    pub any: bool,
    /// Per tree: one body on a free joint, nothing else, with primitive
    /// collision shapes only (only these doze). Seen in the robots sweep,
    /// round 21, not understood yet: a jointed tree dozing leaves its rest
    /// (go2, solo, borinot moving 0.2–1.9 in their last second), and a mesh
    /// hull (hector's quadrotor) finds one ground point too high at its first
    /// full step after a doze and falls 56 µm into the ground.
    lone: Vec<bool>,
    /// Per lone tree: its free joint's first q and v coordinates when its q
    /// and v are that joint's seven and six (`None` else: the tree's ranges
    /// are read from the model). Read by `doze_step` in place of the tree
    /// and its joint, two scattered records of the model a dozing tree.
    at: Vec<Option<(usize, usize)>>,
    /// Per island root: it may doze (scratch of `after_step`, read by
    /// `begin_doze`).
    pub(super) may: Vec<bool>,
    /// Tree-steps taken dozing.
    pub tree_steps: u64,
    /// Per tree: it fell asleep dozing at this step (scratch of `after_step`).
    pub slept: Vec<bool>,
    /// The contact slots of the islands that began to doze at this step's
    /// end (their warm starts are kept: `Constraints::hold_warm`), and per
    /// slot whether it is one of them (grown to the largest slot seen; all
    /// false again after `hold_warm`: [`Doze::unhold`]).
    pub new_slots: Vec<usize>,
    pub held: Vec<bool>,
}

impl Doze {
    pub fn new(model: &Model, on: bool) -> Self {
        let (nt, nv) = (model.trees.len(), model.nv);
        let mesh = |b: usize| {
            model
                .collisions
                .iter()
                .any(|g| g.body == b && matches!(g.shape, crate::model::Shape::Mesh { .. }))
        };
        let lone = model
            .trees
            .iter()
            .map(|t| {
                t.free.is_some()
                    && t.bodies.len() == 1
                    && t.v.len() == 6
                    && !t.bodies.clone().any(mesh)
            })
            .collect();
        let at = model
            .trees
            .iter()
            .zip(&lone)
            .map(|(t, &l)| {
                let f = t.free.and_then(|f| model.free_joints.get(f))?;
                (l && t.q == (f.iq..f.iq + 7) && t.v == (f.iv..f.iv + 6)).then_some((f.iq, f.iv))
            })
            .collect();
        Self {
            on,
            lone,
            at,
            left: vec![0; nt],
            fresh: vec![false; nt],
            root: (0..nt).collect(),
            v_held: DVector::zeros(nv),
            any: false,
            may: vec![false; nt],
            tree_steps: 0,
            slept: vec![false; nt],
            new_slots: Vec::new(),
            held: Vec::new(),
        }
    }
}

impl Doze {
    /// `held` all false again (after `Constraints::hold_warm` read it).
    pub fn unhold(&mut self) {
        for &k in &self.new_slots {
            if let Some(h) = self.held.get_mut(k) {
                *h = false;
            }
        }
    }

    /// Whether tree `t` (awake and not dozing, `never` sleeping or `forced`
    /// now, `still` for that long at `speed` this step) lets its island doze:
    /// it may sleep, is one lone free body, and has been still for [`T_DOZE`]
    /// below [`DOZE_SPEED`]; it did not just stop dozing and does not doze now.
    /// (`Sleep::after_step`'s verdicts, collected on each island's root.)
    #[inline]
    pub(super) fn may_begin(
        &self,
        t: usize,
        never: bool,
        forced: bool,
        still: f64,
        speed: f64,
        v_tol: f64,
    ) -> bool {
        !(never
            || !self.lone[t]
            || forced
            || still < T_DOZE
            || !(speed < DOZE_SPEED * v_tol)
            || self.fresh[t]
            || self.left[t] > 0)
    }
}

impl Sleep {
    /// Tree `t` stops dozing (it takes a full step next).
    fn undoze_tree(&mut self, model: &Model, t: usize) {
        self.doze.left[t] = 0;
        self.doze.fresh[t] = true;
        self.masked[t] = false;
        for b in model.trees[t].bodies.clone() {
            self.body_asleep[b] = false;
        }
    }

    /// After trees stopped dozing: their kept points and forces dropped (their
    /// detection finds them anew), the flags recounted.
    fn after_undoze(&mut self) {
        self.drop_unmasked_frozen();
        self.doze.any = self.doze.left.iter().any(|&l| l > 0);
    }

    /// Every dozing tree stops dozing; true when one did.
    pub(super) fn undoze_all(&mut self, model: &Model) -> bool {
        if !self.doze.any {
            return false;
        }
        for t in 0..self.doze.left.len() {
            if self.doze.left[t] > 0 {
                self.undoze_tree(model, t);
            }
        }
        self.after_undoze();
        true
    }

    /// The dozing islands that a point joins to a body neither asleep nor
    /// dozing stop dozing; true when one did (their contacts are to be found).
    pub(super) fn undoze_touched(&mut self, model: &Model, points: &[ContactPoint]) -> bool {
        if !self.doze.any {
            return false;
        }
        let mut woke = false;
        // (a pair's points come one after another: a repeat of the last pair
        // finds what that pair found, its island undozed already)
        let mut last = (usize::MAX, usize::MAX);
        // (a point with neither body masked, `body_asleep`, has no dozing
        // side: most of them, looked at by that mask alone)
        for p in points {
            let masked = |b: usize| self.body_asleep.get(b) == Some(&true);
            if !(masked(p.body) || masked(p.other)) {
                continue;
            }
            if (p.body, p.other) == last {
                continue;
            }
            last = (p.body, p.other);
            let (ta, tb) = (self.tree_of(p.body), self.tree_of(p.other));
            for (s, o) in [(ta, tb), (tb, ta)] {
                let dozing = |t: Option<usize>| t.is_some_and(|t| self.doze.left[t] > 0);
                if !dozing(s) || o.is_none() || dozing(o) {
                    continue;
                }
                let Some(s) = s else { continue };
                let r = self.doze.root[s];
                for t in 0..self.doze.left.len() {
                    if self.doze.left[t] > 0 && self.doze.root[t] == r {
                        self.undoze_tree(model, t);
                    }
                }
                woke = true;
            }
        }
        if woke {
            self.after_undoze();
        }
        woke
    }

    /// Every awake tree with dofs dozes: a step has no dynamics to compute.
    pub(super) fn all_dozing(&self) -> bool {
        self.doze.any
            && self
                .awake_trees
                .iter()
                .all(|&t| !self.has_dof[t] || self.doze.left[t] > 0)
    }

    /// Every awake tree dozes and dozes on after the next step (none runs
    /// out in it), and no contact point is listed: the next step has nothing
    /// to find or solve (`Simulation::dozing_step`).
    pub(super) fn quiet_dozing(&self, points: &[ContactPoint]) -> bool {
        self.doze.any
            && points.is_empty()
            && self.awake_trees.iter().all(|&t| self.doze.left[t] >= 2)
    }

    /// A body's tree (`None`: the world or an obstacle).
    fn tree_of(&self, body: usize) -> Option<usize> {
        self.tree_of_body
            .get(body)
            .copied()
            .filter(|&t| t < self.asleep.len())
    }

    /// The dozing trees joined to their island's root (their points are kept
    /// aside: the islands they doze in stand).
    pub(super) fn link_dozing(&mut self, awake_trees: &[usize]) {
        if !self.doze.any {
            return;
        }
        for &t in awake_trees {
            if self.doze.left[t] > 0 {
                let (ra, rb) = (self.find(t), self.find(self.doze.root[t]));
                if ra != rb {
                    self.parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
    }

    /// The dozing trees' step of `h` (after the step, before its detection):
    /// v held, q ← q ⊕ h v; then each counts the step, and those whose dozing
    /// steps ran out are unmasked (this detection finds them: their next step
    /// is full).
    pub(super) fn doze_step(
        &mut self,
        model: &Model,
        h: f64,
        q: &mut DVector<f64>,
        v: &mut DVector<f64>,
    ) {
        if !self.doze.any {
            return;
        }
        // (a dozing tree is one body on a free joint, `Doze::lone`: its step
        // is that joint's q ⊕ h v from where its last one left it)
        let d = &mut self.doze;
        let mut ended = false;
        // (a dozing tree is awake: the awake ones are listed)
        for &t in &self.awake_trees {
            if d.left[t] == 0 {
                continue;
            }
            // (a tree's coordinates are one range: slice copies; a lone
            // tree's are its joint's, `Doze::at`, the model not read)
            let (rq, rv, joint) = match d.at.get(t) {
                Some(&Some((iq, iv))) => (iq..iq + 7, iv..iv + 6, Some((iq, iv))),
                _ => {
                    let tree = &model.trees[t];
                    let f = tree.free.and_then(|f| model.free_joints.get(f));
                    (tree.q.clone(), tree.v.clone(), f.map(|f| (f.iq, f.iv)))
                }
            };
            copy_range(v, &d.v_held, rv);
            copy_range(q, &self.q_frozen, rq.clone());
            if let Some((iq, iv)) = joint {
                integrate_free(q, v, h, iq, iv);
            }
            copy_range(&mut self.q_frozen, q, rq);
            d.tree_steps += 1;
            d.left[t] -= 1;
            ended |= d.left[t] == 0;
        }
        if ended {
            for t in 0..self.doze.left.len() {
                if self.doze.left[t] == 0 && self.masked[t] && !self.asleep[t] {
                    self.undoze_tree(model, t);
                }
            }
            self.after_undoze();
        }
    }

    /// At the end of `after_step`: the islands that could sleep but for time
    /// (each tree may sleep and has been still for [`T_DOZE`]: [`Doze::may_begin`],
    /// collected on each island's root by `after_step` in `doze.may`) begin to
    /// doze for the next `N_DOZE` − 1 steps; their points and forces are kept aside.
    /// (`may`: some awake tree lets its island doze, else none begins;
    /// `dozing`: some awake tree dozes now.)
    #[allow(clippy::too_many_arguments)]
    pub(super) fn begin_doze(
        &mut self,
        model: &Model,
        q: &DVector<f64>,
        v: &DVector<f64>,
        points: &mut Vec<ContactPoint>,
        forces: &[ContactForce],
        body_forces: &[Force],
        may: bool,
        dozing: bool,
    ) {
        self.doze.new_slots.clear();
        if !self.doze.on || !self.joins.is_empty() {
            self.doze.fresh.iter_mut().for_each(|f| *f = false);
            return;
        }
        if !may {
            // (no island begins: `any` is whether a tree dozes on)
            self.doze.fresh.iter_mut().for_each(|f| *f = false);
            self.doze.any = dozing;
            return;
        }
        let awake_trees = std::mem::take(&mut self.awake_trees);
        // (a dozing tree is awake: `any` is whether one of the awake trees
        // dozes after this step)
        let (mut began, mut any) = (false, false);
        for &t in &awake_trees {
            let r = self.root[t];
            if !self.doze.may[r] || !self.has_dof[t] {
                any |= self.doze.left[t] > 0;
                continue;
            }
            began = true;
            any = true;
            self.doze.left[t] = N_DOZE - 1;
            self.doze.root[t] = r;
            self.masked[t] = true;
            let tree = &model.trees[t];
            copy_range(&mut self.doze.v_held, v, tree.v.clone());
            copy_range(&mut self.q_frozen, q, tree.q.clone());
            for b in tree.bodies.clone() {
                self.body_asleep[b] = true;
                self.frozen_body[b] = body_forces.get(b).copied().unwrap_or(Force::zero());
            }
        }
        self.doze.fresh.iter_mut().for_each(|f| *f = false);
        self.awake_trees = awake_trees;
        // (trees that fell asleep at this step dozed no longer: not listed)
        self.doze.any = any;
        if !began {
            return;
        }
        let masked = &self.body_asleep;
        let dozing = |b: usize| masked.get(b) == Some(&true);
        let asleep = &self.asleep;
        let tree_of = &self.tree_of_body;
        let new = |b: usize| {
            dozing(b)
                && tree_of
                    .get(b)
                    .is_some_and(|&t| asleep.get(t) == Some(&false))
        };
        // (the forces of the last solve: no dozing tree had rows in it)
        for f in forces {
            if new(f.point.body) {
                self.frozen_forces.push(*f);
            }
        }
        let frozen = &mut self.frozen_points;
        let slots = &mut self.doze.new_slots;
        let held = &mut self.doze.held;
        points.retain(|p| {
            if new(p.body) {
                frozen.push(*p);
                slots.push(p.slot);
                if held.len() <= p.slot {
                    held.resize(p.slot + 1, false);
                }
                if let Some(h) = held.get_mut(p.slot) {
                    *h = true;
                }
                false
            } else {
                true
            }
        });
    }
}

impl super::Simulation {
    /// The awake models with degrees of freedom now (cli.md's `awake`).
    pub fn awake(&self) -> usize {
        self.sleep.awake
    }
    /// The mean of [`Simulation::awake`] over the steps taken.
    pub fn mean_awake(&self) -> f64 {
        self.sleep.mean_awake()
    }
    /// Whether the scene model `name` sleeps (`None`: no such model; a lone
    /// URDF's one model is named "").
    pub fn sleeping(&self, name: &str) -> Option<bool> {
        let t = self.model.trees.iter().position(|t| t.name == name)?;
        Some(self.sleep.tree_asleep(t))
    }
    /// Wakes every sleeping island now, and every dozing one takes a full
    /// step (their contacts are found anew).
    pub fn wake(&mut self) {
        if self.sleep.wake_all(&self.model) {
            // (the energy guard's C computed ahead left the sleeping trees
            // out, `Sleep::bodies_asleep`: not the step's)
            self.data.step_bias_ok = false;
            self.refresh_contacts();
        }
    }

    /// Turns the multirate step of quiet islands on or off (on by default
    /// with sleep; off, a run is the one without it: the A/B of issue #30).
    /// Dozing trees take a full step now.
    pub fn set_doze(&mut self, on: bool) {
        self.sleep.doze.on = on && self.sleep.on;
        if self.sleep.undoze_all(&self.model) {
            self.data.step_bias_ok = false;
            self.refresh_contacts();
        }
    }
    /// Whether the scene model `name` dozes now (`None`: no such model).
    pub fn dozing(&self, name: &str) -> Option<bool> {
        let t = self.model.trees.iter().position(|t| t.name == name)?;
        Some(self.sleep.doze.left.get(t).is_some_and(|&l| l > 0))
    }
    /// The tree-steps taken dozing so far.
    pub fn doze_steps(&self) -> u64 {
        self.sleep.doze.tree_steps
    }
}
