//! Doze: a multirate step for the quiet islands of a run with sleep on
//! (issue #30; scene.md §"Large scenes: islands and sleep").
//!
//! An island that could sleep but for time (every tree in it may sleep: not
//! `never`, not driven, and each still, slower than `sleep_velocity`, for at
//! least [`T_DOZE`], or slower than [`GROW_SPEED`]·sleep_velocity for
//! [`T_REST`]) dozes: for the next [`N_DOZE`] − 1 steps its trees are
//! masked as a sleeping island's are (left out of detection, of the factor and
//! of the bias pass; their contact points and forces kept aside with the frozen
//! ones for `contacts`, `penetration` and the forces), and each such step holds
//! their velocity and integrates their configuration, q ← q ⊕ h v (the model's
//! own free-joint integration, `integrate_free`). Then they take a full step
//! (found by detection, in the rows and the solve) and may doze again. A full
//! step that finds the island as its doze left it (the same contact points,
//! every tree slower than [`GROW_SPEED`]·sleep_velocity) doubles its next
//! period, up to [`N_MAX`] = 32 steps; any other start of a doze is at
//! N_DOZE. A step in which every awake tree dozes on is that alone
//! (`Simulation::dozing_step`: no detection, rows or solve).
//!
//! Holding v is the exact step at an equilibrium (gravity and support
//! cancel) and drifts by at most N_DOZE·h·DOZE_SPEED·sleep_velocity (4 µm at
//! 1 ms and 1e-3 m/s) in a first period and N_MAX·h·GROW_SPEED·sleep_velocity
//! (0.64 µm, ≤ [`DRIFT`]) in a grown one: far inside the contact slop (0.1 mm)
//! and margin (5 mm), so no contact appears unseen between full steps. The
//! last solve's Δv is not replayed: it holds the velocity-cancelling part
//! −(v + h g) and its replay diverges.
//!
//! A dozing tree is awake: it counts in `awake`, `sleeping` is false for it,
//! its still time runs on (its speed is held below the threshold), and its
//! island falls asleep when that time reaches `sleep_time`, as an awake one
//! does. It takes a full step at once when an awake body that does not doze
//! touches it (a contact point joins them, the path `wake_touched` takes for
//! a sleeping island) and when the forcing or the state is set (`wake`).
//! Nothing but the step count and the state decides: the run is as
//! deterministic as without it.

use super::sleep::Sleep;
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
/// A dozing island takes a full step every `N_DOZE` steps at first.
pub(super) const N_DOZE: u32 = 8;
/// The longest period: each full step that ends a doze and finds its island
/// as it left it (the same contact points, every tree slower than
/// [`GROW_SPEED`]) doubles the island's next period, up to this many steps.
pub(super) const N_MAX: u32 = 32;
/// A period grows only while each tree's speed at the full step is below
/// this fraction of `sleep_velocity` (a box at rest in a pile: ~1e-6 m/s; a
/// creeping one stays at `N_DOZE`, where its blips are seen as before; with
/// 0.1 or no such bar the piles' mean awake rose by 1 to 6 %; with 0.05 a
/// stack of three boxes rocking at 3e-5 m/s took a kick at a full step after
/// a long doze and slept 0.2 s later; 0.02 keeps every one as it was).
pub(super) const GROW_SPEED: f64 = 0.02;
/// The farthest (m) a dozing tree drifts between full steps in a grown
/// period, N·h·GROW_SPEED·sleep_velocity (a period doubles only while this
/// holds): 0.64 µm at 1 ms, 1e-3 m/s and N_MAX, a 150th of the contact slop
/// (0.1 mm: nothing is pushed below it) and a 7800th of the contact margin
/// (5 mm): no contact appears or parts unseen between full steps. (At
/// `N_DOZE`, N·h·DOZE_SPEED·sleep_velocity = 4 µm.)
pub(super) const DRIFT: f64 = 1e-5;

/// A tree that has been slower than [`GROW_SPEED`]·sleep_velocity at every
/// step for this long (s) dozes without waiting for [`T_DOZE`]: at rest, not
/// at the turning point of a swing (there it is that slow for a step or two).
/// (0.01 and 0.02 s raised boxes 64's mean awake by 1.2–1.6 %, 0.03 s not.)
pub(super) const T_REST: f64 = 0.03;

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
    /// Per island root: it may doze (scratch).
    may: Vec<bool>,
    /// Per tree: the period of its last doze (steps).
    period: Vec<u32>,
    /// Per tree: its last doze ran its course (no touch, no wake) and its
    /// full step since is the one just taken.
    pub ran_out: Vec<bool>,
    /// Per tree: its contact points' signature when it began its last doze.
    sig: Vec<u64>,
    /// Per tree: its contact points' signature now (scratch).
    sig_now: Vec<u64>,
    /// Per island root: its next period (scratch).
    next: Vec<u32>,
    /// Per tree: how long it has been slower than GROW_SPEED·sleep_velocity (s).
    resting: Vec<f64>,
    /// Tree-steps taken dozing.
    pub tree_steps: u64,
    /// Per tree: it fell asleep dozing at this step (scratch of `after_step`).
    pub slept: Vec<bool>,
    /// The contact slots of the islands that began to doze at this step's
    /// end, sorted (their warm starts are kept: `Constraints::hold_warm`).
    pub new_slots: Vec<usize>,
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
        Self {
            on,
            lone,
            left: vec![0; nt],
            fresh: vec![false; nt],
            root: (0..nt).collect(),
            v_held: DVector::zeros(nv),
            any: false,
            may: vec![false; nt],
            period: vec![N_DOZE; nt],
            ran_out: vec![false; nt],
            sig: vec![0; nt],
            sig_now: vec![0; nt],
            next: vec![N_DOZE; nt],
            resting: vec![0.0; nt],
            tree_steps: 0,
            slept: vec![false; nt],
            new_slots: Vec::new(),
        }
    }
}

impl Doze {
    /// Tree `t` took a step of `h`, slower than GROW_SPEED·sleep_velocity
    /// (and not driven) or not.
    pub(super) fn rest(&mut self, t: usize, slow: bool, h: f64) {
        self.resting[t] = if slow { self.resting[t] + h } else { 0.0 };
    }
}

impl Sleep {
    /// Tree `t` stops dozing (it takes a full step next).
    fn undoze_tree(&mut self, model: &Model, t: usize) {
        self.doze.left[t] = 0;
        self.doze.fresh[t] = true;
        self.doze.ran_out[t] = false;
        self.masked[t] = false;
        for b in model.trees[t].bodies.clone() {
            self.body_asleep[b] = false;
        }
    }

    /// After trees stopped dozing: their kept points and forces dropped (their
    /// detection finds them anew), the flags recounted.
    fn after_undoze(&mut self) {
        let masked = &self.body_asleep;
        let keep = |b: usize| masked.get(b) == Some(&true);
        self.frozen_points.retain(|p| keep(p.body));
        self.frozen_forces.retain(|f| keep(f.point.body));
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
        for p in points {
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
            let tree = &model.trees[t];
            for k in tree.v.clone() {
                v[k] = d.v_held[k];
            }
            for k in tree.q.clone() {
                q[k] = self.q_frozen[k];
            }
            if let Some(f) = tree.free.and_then(|f| model.free_joints.get(f)) {
                integrate_free(q, v, h, f.iq, f.iv);
            }
            for k in tree.q.clone() {
                self.q_frozen[k] = q[k];
            }
            d.tree_steps += 1;
            d.left[t] -= 1;
            ended |= d.left[t] == 0;
        }
        if ended {
            for t in 0..self.doze.left.len() {
                if self.doze.left[t] == 0 && self.masked[t] && !self.asleep[t] {
                    self.undoze_tree(model, t);
                    self.doze.ran_out[t] = true;
                }
            }
            self.after_undoze();
        }
    }

    /// Each awake tree's contact signature (`Doze::sig_now`): a sum of its
    /// points' mixed slots (a stable identity of a point across steps).
    fn signatures(&mut self, awake_trees: &[usize], points: &[ContactPoint]) {
        for &t in awake_trees {
            self.doze.sig_now[t] = 0;
        }
        for p in points {
            // (splitmix64's finaliser: distinct slot sets give distinct sums)
            let mut z = (p.slot as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            for b in [p.body, p.other] {
                if let Some(t) = self.tree_of(b) {
                    self.doze.sig_now[t] = self.doze.sig_now[t].wrapping_add(z);
                }
            }
        }
    }

    /// At the end of `after_step` (a step of `h`): the islands that could
    /// sleep but for time (each tree may sleep and has been still for
    /// [`T_DOZE`]) begin to doze for their period's next N − 1 steps (N from
    /// `N_DOZE`, doubled up to `N_MAX` while they stay quiet); their points
    /// and forces are kept aside.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn begin_doze(
        &mut self,
        model: &Model,
        h: f64,
        forced: &[bool],
        q: &DVector<f64>,
        v: &DVector<f64>,
        points: &mut Vec<ContactPoint>,
        forces: &[ContactForce],
        body_forces: &[Force],
    ) {
        self.doze.new_slots.clear();
        if !self.doze.on || !self.joins.is_empty() {
            self.doze.fresh.iter_mut().for_each(|f| *f = false);
            return;
        }
        let awake_trees = std::mem::take(&mut self.awake_trees);
        let mut may = std::mem::take(&mut self.doze.may);
        for &t in &awake_trees {
            may[t] = true;
        }
        for &t in &awake_trees {
            let r = self.find(t);
            let d = &self.doze;
            if self.never[t]
                || !d.lone[t]
                || forced[t]
                || !((self.still[t] >= T_DOZE && self.speed[t] < DOZE_SPEED * self.v_tol)
                    || d.resting[t] >= T_REST)
                || d.fresh[t]
                || d.left[t] > 0
            {
                may[r] = false;
            }
        }
        // each island's period: doubled (up to N_MAX and the drift bound)
        // when every tree in it comes from a doze that ran its course and
        // its full step found the same contact points, else N_DOZE
        let any = awake_trees.iter().any(|&t| may[self.find(t)]);
        if any {
            self.signatures(&awake_trees, points);
        }
        let bar = GROW_SPEED * self.v_tol * h;
        let mut next = std::mem::take(&mut self.doze.next);
        for &t in awake_trees.iter().filter(|_| any) {
            let r = self.find(t);
            next[r] = u32::MAX;
        }
        for &t in awake_trees.iter().filter(|_| any) {
            let r = self.find(t);
            if !may[r] {
                continue;
            }
            let d = &self.doze;
            let quiet =
                d.ran_out[t] && d.sig_now[t] == d.sig[t] && self.speed[t] < GROW_SPEED * self.v_tol;
            let n = if quiet {
                let n = (2 * d.period[t]).min(N_MAX);
                if n as f64 * bar <= DRIFT {
                    n
                } else {
                    d.period[t].max(N_DOZE)
                }
            } else {
                N_DOZE
            };
            next[r] = next[r].min(n);
        }
        let mut began = false;
        for &t in &awake_trees {
            let r = self.find(t);
            if !may[r] {
                if !self.doze.fresh[t] {
                    self.doze.ran_out[t] = false;
                }
                continue;
            }
            if !self.has_dof[t] {
                continue;
            }
            began = true;
            self.doze.period[t] = next[r];
            self.doze.sig[t] = self.doze.sig_now[t];
            self.doze.ran_out[t] = false;
            self.doze.left[t] = next[r] - 1;
            self.doze.root[t] = r;
            self.masked[t] = true;
            let tree = &model.trees[t];
            for k in tree.v.clone() {
                self.doze.v_held[k] = v[k];
            }
            for k in tree.q.clone() {
                self.q_frozen[k] = q[k];
            }
            for b in tree.bodies.clone() {
                self.body_asleep[b] = true;
                self.all_body[b] = body_forces.get(b).copied().unwrap_or(Force::zero());
            }
        }
        self.doze.fresh.iter_mut().for_each(|f| *f = false);
        self.doze.may = may;
        self.doze.next = next;
        self.awake_trees = awake_trees;
        // (trees that fell asleep at this step dozed no longer)
        self.doze.any = self.doze.left.iter().any(|&l| l > 0);
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
        points.retain(|p| {
            if new(p.body) {
                frozen.push(*p);
                slots.push(p.slot);
                false
            } else {
                true
            }
        });
        slots.sort_unstable();
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
    /// The period (steps) of the doze the scene model `name` is in (`None`:
    /// no such model, or it does not doze now).
    pub fn doze_period(&self, name: &str) -> Option<u32> {
        let t = self.model.trees.iter().position(|t| t.name == name)?;
        let d = &self.sleep.doze;
        d.left.get(t).is_some_and(|&l| l > 0).then(|| d.period[t])
    }
    /// The tree-steps taken dozing so far.
    pub fn doze_steps(&self) -> u64 {
        self.sleep.doze.tree_steps
    }
}
