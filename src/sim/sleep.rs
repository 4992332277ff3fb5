//! Islands and sleep (scene.md §"Large scenes: islands and sleep").
//!
//! The models of a scene (the trees of the model) are grouped each step into
//! islands: two trees are in one island when a contact point of the last
//! detection (a point within the contact margin) joins their bodies; the
//! world, obstacles and trees without degrees of freedom join nothing. An
//! island sleeps when, for `sleep_time` without a break, every point of every
//! collision shape of its trees moved slower than `sleep_velocity`: the speed
//! of a shape's points is bounded by |v_c| + |ω| r over the shape's bounding
//! sphere (centre c, radius r; a body without shapes: its centre of mass and
//! r = 0.1 m), so the test never lets an island sleep early. A sleeping
//! tree's q is frozen and its v is exactly zero; its shapes are not searched
//! for contact among themselves or with the static world (its last contact
//! points are kept, frozen, for `contacts` and `penetration`). It wakes,
//! whole, when a contact point joins one of its bodies to an awake body, or
//! when the forcing or the state is set. A tree with a fixed base, a nonzero
//! applied torque or wrench, a servo, or its own `"sleep": false` never
//! sleeps, nor does an island holding one.

use super::ContactForce;
use crate::contact::ContactPoint;
use crate::model::Model;
use crate::spatial::Force;
use nalgebra::{DVector, Vector3};

mod frozen;
pub(crate) use frozen::Frozen;
mod ranges;
pub(super) use ranges::{copy_range, zero_range};
mod step;
mod still;

/// "No tree": the world body.
const WORLD: usize = usize::MAX;

/// The sleep state of a simulation's trees.
#[derive(Clone, Debug)]
pub(crate) struct Sleep {
    /// Sleep is on (`SimOptions::sleep`).
    pub on: bool,
    /// m/s.
    pub(super) v_tol: f64,
    /// s.
    t_tol: f64,
    /// Each body's tree (`WORLD` for body 0).
    pub tree_of_body: Vec<usize>,
    /// Per tree: it never sleeps (fixed base, no dofs, its own `"sleep": false`).
    pub(super) never: Vec<bool>,
    /// Per tree: it has degrees of freedom (it counts in `awake`).
    pub(super) has_dof: Vec<bool>,
    /// Bounding spheres of the collision shapes, tree after tree: (body,
    /// centre in the body frame, radius), those another one holds left out
    /// (`still::drop_held`), then the tree's bodies without one (the world
    /// excluded), ascending, each with its centre of mass and 0.1 m.
    spheres: Vec<(usize, Vector3<f64>, f64)>,
    /// Per tree: its spheres, a range of `spheres` (the speed test reads
    /// these, not the model's trees).
    tree_spheres: Vec<(usize, usize)>,
    /// Per awake tree: its island's root this step (scratch of `after_step`,
    /// found once after the unions and read by the sleep and doze verdicts).
    pub(super) root: Vec<usize>,
    /// The trees not asleep, ascending (the per-step loops run over these).
    pub(super) awake_trees: Vec<usize>,
    /// Per tree: how long it has been still (s).
    pub(super) still: Vec<f64>,
    /// Per tree: asleep.
    pub asleep: Vec<bool>,
    /// Per body: its tree is asleep (the detection's skip mask).
    pub body_asleep: Vec<bool>,
    /// Union-find parents (per tree) of this step's islands.
    pub(super) parent: Vec<usize>,
    /// Pairs of bodies an active loop constraint joins (one island).
    pub joins: Vec<(usize, usize)>,
    /// Per tree: the island it fell asleep in (its root tree).
    island: Vec<usize>,
    /// Per awake tree: its verdicts this step (`still::MAY_SLEEP`,
    /// `still::MAY_DOZE`; scratch of `after_step`).
    verdict: Vec<u8>,
    /// The configuration the sleeping trees are held at.
    pub q_frozen: DVector<f64>,
    /// The sleeping islands' last contact points and forces.
    pub frozen_points: Frozen<ContactPoint>,
    pub frozen_forces: Frozen<ContactForce>,
    /// The masked (sleeping or dozing) bodies' kept contact wrenches (per
    /// body: set when the body falls asleep or begins to doze).
    pub(super) frozen_body: Vec<Force>,
    /// The last solve's contact forces and wrenches with the frozen ones
    /// (in use while anything sleeps). The forces' list is made when first
    /// read after a step ([`Sleep::forces`]), not at every step: a sleeping
    /// pile's frozen forces copied every step cost more than the rest of its
    /// bookkeeping (a lock: `Simulation` is `Sync`).
    all_forces: std::sync::OnceLock<Vec<ContactForce>>,
    /// The body wrenches to report, made when first read after a step
    /// ([`Sleep::body_forces`]): the masked bodies' kept ones, the others'
    /// the last solve's; `composed` is the mask when the step ended
    /// ([`Sleep::compose`]).
    all_body: std::sync::OnceLock<Vec<Force>>,
    composed: Vec<bool>,
    /// v plus the position pass's pseudo-velocity (scratch: a point pushed out
    /// of a penetration is moving).
    pub vw: DVector<f64>,
    /// Awake trees with dofs at the end of the last step.
    pub awake: usize,
    /// Σ awake over the steps, and the steps.
    pub awake_sum: f64,
    pub steps: u64,
    /// Everything wakes at the next step (the forcing or the state was set).
    pub wake_pending: bool,
    pub(super) any_asleep: bool,
    /// Per island root: it may sleep (scratch).
    may: Vec<bool>,
    /// Per tree: asleep or dozing (the factor's mask, `super::doze`).
    pub(super) masked: Vec<bool>,
    /// The quiet islands' multirate step (`super::doze`).
    pub(super) doze: super::doze::Doze,
}

impl Sleep {
    /// The sleep state of `model`: `spheres` the collision shapes' bounding
    /// spheres, `never_names` the scene models that never sleep.
    pub fn new(
        model: &Model,
        on: bool,
        v_tol: f64,
        t_tol: f64,
        spheres: Vec<(usize, Vector3<f64>, f64)>,
        never_names: &[String],
    ) -> Self {
        let nt = model.trees.len();
        let mut tree_of_body = vec![WORLD; model.nbodies];
        let mut never = vec![false; nt];
        let mut has_dof = vec![false; nt];
        for (t, tree) in model.trees.iter().enumerate() {
            for b in tree.bodies.clone() {
                if let Some(x) = tree_of_body.get_mut(b) {
                    *x = t;
                }
            }
            has_dof[t] = !tree.v.is_empty();
            never[t] = tree.free.is_none() || tree.v.is_empty() || never_names.contains(&tree.name);
        }
        let mut has_sphere = vec![false; model.nbodies];
        for s in &spheres {
            if let Some(h) = has_sphere.get_mut(s.0) {
                *h = true;
            }
        }
        let awake = has_dof.iter().filter(|&&d| d).count();
        // spheres grouped by tree (a tree's bodies are one range), the world's
        // (an obstacle's) last: they move nothing
        let mut spheres = spheres;
        let tree_key = |b: usize| tree_of_body.get(b).copied().unwrap_or(WORLD);
        spheres.sort_by_key(|s| tree_key(s.0));
        still::drop_held(&mut spheres, tree_key);
        let mut bounds = Vec::with_capacity(spheres.len());
        let mut tree_spheres = vec![(0, 0); nt];
        let mut i = 0;
        for (t, tree) in model.trees.iter().enumerate() {
            let s = bounds.len();
            while i < spheres.len() && tree_key(spheres[i].0) == t {
                bounds.push(spheres[i]);
                i += 1;
            }
            for b in tree.bodies.clone() {
                if b == 0 || has_sphere.get(b) != Some(&false) {
                    continue;
                }
                if let Some(i) = model.inertias.get(b) {
                    bounds.push((b, i.com, 0.1));
                }
            }
            tree_spheres[t] = (s, bounds.len());
        }
        Self {
            on,
            v_tol,
            t_tol,
            tree_of_body,
            never,
            has_dof,
            spheres: bounds,
            tree_spheres,
            root: (0..nt).collect(),
            awake_trees: (0..nt).collect(),
            still: vec![0.0; nt],
            asleep: vec![false; nt],
            body_asleep: vec![false; model.nbodies],
            parent: (0..nt).collect(),
            joins: Vec::new(),
            island: vec![0; nt],
            verdict: vec![0; nt],
            q_frozen: DVector::zeros(model.nq),
            frozen_points: Frozen::default(),
            frozen_forces: Frozen::default(),
            frozen_body: vec![Force::zero(); model.nbodies],
            all_forces: std::sync::OnceLock::new(),
            all_body: std::sync::OnceLock::new(),
            composed: vec![false; model.nbodies],
            vw: DVector::zeros(model.nv),
            awake,
            awake_sum: 0.0,
            steps: 0,
            wake_pending: false,
            any_asleep: false,
            may: vec![true; nt],
            masked: vec![false; nt],
            doze: super::doze::Doze::new(model, on),
        }
    }

    /// Per tree: asleep, when any tree sleeps (`None`: every tree is awake).
    pub fn sleeping_trees(&self) -> Option<&[bool]> {
        (self.on && (self.any_asleep || self.doze.any)).then_some(&self.masked[..])
    }

    /// The awake trees with dofs now.
    fn count_awake(&self) -> usize {
        self.awake_trees
            .iter()
            .filter(|&&t| self.has_dof[t])
            .count()
    }

    /// The trees not asleep, listed anew after trees fell asleep or woke.
    fn list_awake(&mut self) {
        self.awake_trees.clear();
        let asleep = &self.asleep;
        self.awake_trees
            .extend((0..asleep.len()).filter(|&t| !asleep[t]));
    }

    /// The trees not asleep, ascending.
    pub fn awake_trees(&self) -> &[usize] {
        &self.awake_trees
    }

    /// Wakes every sleeping tree; true when one woke.
    pub fn wake_all(&mut self, model: &Model) -> bool {
        self.wake_pending = false;
        let mut woke = self.undoze_all(model);
        for t in 0..self.asleep.len() {
            if self.asleep[t] {
                self.wake_tree(model, t);
                woke = true;
            }
        }
        self.frozen_points.clear();
        self.frozen_forces.clear();
        self.any_asleep = false;
        self.list_awake();
        self.awake = self.count_awake();
        woke
    }

    fn wake_tree(&mut self, model: &Model, t: usize) {
        self.asleep[t] = false;
        self.masked[t] = false;
        self.still[t] = 0.0;
        for b in model.trees[t].bodies.clone() {
            self.body_asleep[b] = false;
        }
    }

    /// Wakes the sleeping islands that a point joins to an awake body (the
    /// point's other side awake, or a body of an awake tree); true when one woke.
    pub fn wake_touched(&mut self, model: &Model, points: &[ContactPoint]) -> bool {
        if !self.any_asleep {
            return false;
        }
        let mut woke = false;
        // (a point with neither body asleep or dozing, `body_asleep`, wakes
        // nothing: most of them, looked at by that mask alone)
        for p in points {
            let masked = |b: usize| self.body_asleep.get(b) == Some(&true);
            if !(masked(p.body) || masked(p.other)) {
                continue;
            }
            let (ta, tb) = (self.tree(p.body), self.tree(p.other));
            for (s, o) in [(ta, tb), (tb, ta)] {
                if s != WORLD && self.asleep[s] && (o == WORLD || !self.asleep[o]) {
                    let isl = self.island[s];
                    for t in 0..self.asleep.len() {
                        if self.asleep[t] && self.island[t] == isl {
                            self.wake_tree(model, t);
                        }
                    }
                    woke = true;
                }
            }
        }
        if woke {
            self.drop_unmasked_frozen();
            self.any_asleep = self.asleep.iter().any(|&a| a);
            self.list_awake();
            self.awake = self.count_awake();
        }
        woke
    }

    /// The frozen points and forces of bodies no longer asleep or dozing
    /// (`body_asleep`) dropped: their detection finds them anew.
    pub(super) fn drop_unmasked_frozen(&mut self) {
        let masked = &self.body_asleep;
        let keep = |b: usize| masked.get(b) == Some(&true);
        self.frozen_points.retain_bodies(keep);
        self.frozen_forces.retain_bodies(keep);
    }

    /// Whether a point of `points` has a side asleep or dozing (else
    /// [`Sleep::wake_touched`] and [`Sleep::undoze_touched`] have nothing
    /// to do: each skips such a point).
    pub fn touches_masked(&self, points: &[ContactPoint]) -> bool {
        if !self.any_asleep && !self.doze.any {
            return false;
        }
        let masked = &self.body_asleep[..];
        let m = |b: usize| masked.get(b) == Some(&true);
        points.iter().any(|p| m(p.body) | m(p.other))
    }

    fn tree(&self, body: usize) -> usize {
        self.tree_of_body.get(body).copied().unwrap_or(WORLD)
    }

    pub(super) fn find(&mut self, t: usize) -> usize {
        still::find(&mut self.parent, t)
    }

    /// One step's bookkeeping after a step of `h` (s): each awake tree's largest
    /// point speed from the bodies' velocities `body_v` (body frame: linear at
    /// the body origin, angular), the islands of `points`, and the islands
    /// still for `sleep_time` put to sleep (`forced[t]`: tree t is driven
    /// now and cannot sleep). Sleeping trees' v are set to zero and their q
    /// kept; their points and forces move to the frozen lists (removed from
    /// `points`). Returns whether an island fell asleep.
    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
    pub fn after_step(
        &mut self,
        model: &Model,
        h: f64,
        body_v: &[crate::spatial::Motion<f64>],
        forced: &[bool],
        q: &DVector<f64>,
        v: &mut DVector<f64>,
        points: &mut Vec<ContactPoint>,
        forces: &[ContactForce],
        body_forces: &[Force],
    ) -> bool {
        self.steps += 1;
        if !self.on {
            self.awake_sum += self.awake as f64;
            return false;
        }
        // each awake tree's largest point speed, its still time, its
        // verdicts, its own island (the per-root flags set true)
        let awake_trees = std::mem::take(&mut self.awake_trees);
        let mut may = std::mem::take(&mut self.may);
        let mut may_doze = std::mem::take(&mut self.doze.may);
        let doze_on = self.doze.on && self.joins.is_empty();
        let dozing = self.still_pass(
            &awake_trees,
            h,
            body_v,
            forced,
            doze_on,
            &mut may,
            &mut may_doze,
        );
        self.link_dozing(&awake_trees);
        // islands: trees joined by a contact point or a loop constraint
        let joins = std::mem::take(&mut self.joins);
        self.join_islands(points, &joins);
        self.joins = joins;
        // an island sleeps when every tree in it may, and begins to doze
        // when every tree in it may (`begin_doze`): the root (an awake tree)
        // collects the verdicts (true: may). (The doze verdict is taken
        // before the islands that fall asleep leave the awake list: an
        // island sleeps whole, its root with it, so what its trees say of
        // their root is never read.)
        // (the unions are done: each tree's root is found once, kept in
        // `root` for the verdicts here and in `begin_doze`; `any`: the
        // verdicts' union, no island may when no tree may, its root among them)
        let mut any = 0;
        let nt = self.parent.len();
        let (verdict, root) = (&self.verdict[..nt], &mut self.root[..nt]);
        for &t in &awake_trees {
            if t >= nt {
                continue;
            }
            let r = still::find(&mut self.parent, t);
            root[t] = r;
            let v = verdict[t];
            any |= v;
            if v & still::MAY_SLEEP == 0 {
                may[r] = false;
            }
            if v & still::MAY_DOZE == 0 {
                may_doze[r] = false;
            }
        }
        self.doze.may = may_doze;
        let mut slept = false;
        let mut dozed_slept = 0;
        let sleepers = match any & still::MAY_SLEEP {
            0 => &[][..],
            _ => &awake_trees[..],
        };
        for &t in sleepers {
            if !self.has_dof[t] {
                continue;
            }
            let r = self.root[t];
            if !may[r] {
                continue;
            }
            slept = true;
            let dozed = std::mem::take(&mut self.doze.left[t]) > 0;
            self.doze.slept[t] = dozed;
            dozed_slept += dozed as usize;
            self.asleep[t] = true;
            self.masked[t] = true;
            self.island[t] = r;
            let tree = &model.trees[t];
            for k in tree.v.clone() {
                v[k] = 0.0;
            }
            for k in tree.q.clone() {
                self.q_frozen[k] = q[k];
            }
            for b in tree.bodies.clone() {
                self.body_asleep[b] = true;
                // (a dozing body's: those kept when it began to doze)
                if !dozed {
                    self.frozen_body[b] = body_forces.get(b).copied().unwrap_or(Force::zero());
                }
            }
        }
        self.may = may;
        self.awake_trees = awake_trees;
        if slept {
            self.list_awake();
            self.any_asleep = true;
            let asleep = &self.body_asleep;
            let sleeping = |b: usize| asleep.get(b) == Some(&true);
            // (a dozing tree's forces are among the frozen ones already)
            let dozed = &self.doze.slept;
            let tree = |b: usize| self.tree_of_body.get(b).copied().unwrap_or(WORLD);
            for f in forces {
                let b = f.point.body;
                if sleeping(b) && dozed.get(tree(b)) != Some(&true) {
                    self.frozen_forces.push(*f);
                }
            }
            let frozen = &mut self.frozen_points;
            points.retain(|p| {
                if sleeping(p.body) {
                    frozen.push(*p);
                    false
                } else {
                    true
                }
            });
            self.awake = self.count_awake();
        }
        if dozed_slept > 0 {
            self.doze.slept.iter_mut().for_each(|d| *d = false);
        }
        // (the trees that doze on: those that dozed, less those that fell asleep)
        let may_begin = any & still::MAY_DOZE != 0;
        let dozing = dozing > dozed_slept;
        self.begin_doze(model, q, v, points, forces, body_forces, may_begin, dozing);
        self.awake_sum += self.awake as f64;
        slept
    }

    /// Holds the sleeping trees where they fell asleep, at rest.
    pub fn hold(&self, model: &Model, q: &mut DVector<f64>, v: &mut DVector<f64>) {
        if !self.any_asleep {
            return;
        }
        // (a tree's coordinates are one range: one slice fill and one copy,
        // not a bounds test an entry)
        for (tree, _) in model.trees.iter().zip(&self.asleep).filter(|&(_, &a)| a) {
            zero_range(v, tree.v.clone());
            copy_range(q, &self.q_frozen, tree.q.clone());
        }
    }

    /// Every tree with dofs sleeps: a step has nothing to do.
    pub fn all_asleep(&self) -> bool {
        self.on && self.any_asleep && self.awake == 0
    }

    /// Counts a step that had nothing to do.
    pub fn count_idle_step(&mut self) {
        self.steps += 1;
        self.awake_sum += self.awake as f64;
    }

    /// The step ends: the contact forces and body wrenches to report are
    /// left to be made at their first read ([`Sleep::forces`],
    /// [`Sleep::body_forces`]: nothing they are made of changes before the
    /// next step's solve and its `compose`), from the mask kept here.
    /// (Made eagerly, the awake bodies' wrenches were copied at every step:
    /// the body wrench of each awake body the last solve's, `body`, each
    /// masked one's its kept one, the world's the solve's.)
    pub fn compose(&mut self) {
        if !self.any_asleep && !self.doze.any {
            return;
        }
        self.all_forces.take();
        self.all_body.take();
        self.composed.copy_from_slice(&self.body_asleep);
    }
    /// The contact forces to report: `awake` (the last solve's) joined with
    /// the frozen ones while anything sleeps.
    /// (`awake`: the last solve's, those [`Sleep::compose`] was given.)
    pub fn forces<'a>(&'a self, awake: &'a [ContactForce]) -> &'a [ContactForce] {
        if self.any_asleep || self.doze.any {
            self.all_forces.get_or_init(|| {
                // (the last solve's forces on islands that fell asleep after
                // it are the frozen ones already)
                let asleep = &self.body_asleep;
                let awake_body = |b: usize| asleep.get(b) != Some(&true);
                let mut all = Vec::with_capacity(awake.len() + self.frozen_forces.len());
                all.extend(awake.iter().filter(|f| awake_body(f.point.body)));
                all.extend_from_slice(&self.frozen_forces);
                all
            })
        } else {
            awake
        }
    }
    /// The body contact wrenches to report (as [`Sleep::forces`]).
    pub fn body_forces<'a>(&'a self, awake: &'a [Force]) -> &'a [Force] {
        if self.any_asleep || self.doze.any {
            self.all_body.get_or_init(|| {
                // (a body masked when the step ended: its kept wrench; a
                // body of no tree but the world: none, as it never had one)
                let get = |b: usize| awake.get(b).copied().unwrap_or(Force::zero());
                let tree = &self.tree_of_body;
                (0..self.frozen_body.len())
                    .map(|b| match b {
                        0 => get(0),
                        _ if self.composed[b] || tree[b] == WORLD => self.frozen_body[b],
                        _ => get(b),
                    })
                    .collect()
            })
        } else {
            awake
        }
    }

    /// Per body: asleep, when any tree sleeps (empty: every body is awake).
    pub fn bodies_asleep(&self) -> &[bool] {
        if self.on && (self.any_asleep || self.doze.any) {
            &self.body_asleep
        } else {
            &[]
        }
    }

    /// Whether tree `t` sleeps.
    pub fn tree_asleep(&self, t: usize) -> bool {
        self.asleep.get(t).copied().unwrap_or(false)
    }

    /// The mean awake count over the steps (the count now before any step).
    pub fn mean_awake(&self) -> f64 {
        if self.steps == 0 {
            self.awake as f64
        } else {
            self.awake_sum / self.steps as f64
        }
    }
}
