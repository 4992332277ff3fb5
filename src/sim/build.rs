//! Setting up a [`Simulation`]: options checked, contact shapes built, every
//! buffer of a step sized here (none allocated in a step).

use super::*;

/// The most threads [`SimOptions::threads`] may ask for: far more than a
/// step's islands use, and few enough to start (100000 aborted the process
/// as each thread's stack guard could not be mapped).
pub const MAX_THREADS: usize = 1024;

/// The joint springs of `model` (an MJCF joint's `stiffness` about its
/// `springref`, on hinge and slide joints) as servo gains and targets, `None`
/// when there is none (or joint dynamics are off).
fn joint_springs(model: &Model, on: bool) -> Option<(DVector<f64>, DVector<f64>)> {
    if !on
        || !model
            .dofs
            .iter()
            .any(|d| d.stiffness > 0.0 && d.kind.nv() == 1)
    {
        return None;
    }
    let mut kp = DVector::zeros(model.nv);
    let mut q_ref = model.neutral();
    for d in &model.dofs {
        if d.kind.nv() == 1 && d.stiffness.is_finite() && d.stiffness > 0.0 {
            kp[d.iv] = d.stiffness;
            q_ref[d.iq] = d.springref;
        }
    }
    Some((kp, q_ref))
}

impl ContactParams {
    /// The contact parameters of a scene's ground, as `urdyn simulate SCENE.json`,
    /// Python's `Simulation(scene)` and `rollout(scene)` read them: the defaults
    /// with the ground's friction, and its torsion and rolling where the file
    /// sets them (scene.md; none without a ground).
    pub fn of_scene_ground(ground: Option<&crate::scene::Ground>) -> Self {
        let mut contact = Self::default();
        if let Some(g) = ground {
            contact.friction = g.friction;
            contact.torsion = g.torsion.unwrap_or(contact.torsion);
            contact.rolling = g.rolling.unwrap_or(contact.rolling);
        }
        contact
    }
}

impl SimOptions {
    /// The options `urdyn simulate MODEL.xml` runs an MJCF world with
    /// (mjcf.md §"What the file becomes"): `<option timestep>` as the step (the
    /// defaults' where the file's is 0), the world's upward plane as the ground
    /// with the plane's friction (no ground without one), and the speculative
    /// margin of MuJoCo's large steps ([`ContactParams::TRAVEL`], docs/theory.md
    /// §"Speculative margin"); everything else the defaults'. The CLI sets its
    /// options (`--dt`, `--integrator`, `--no-sleep`, …) over these.
    pub fn of_mjcf_world(world: &crate::mjcf::World) -> Self {
        let ground = crate::mjcf::ground_of(world);
        let defaults = Self::default();
        let mut contact = ContactParams::default();
        if let Some(g) = &ground {
            contact.friction = g.friction;
        }
        contact.travel_factor = ContactParams::TRAVEL;
        Self {
            dt: if world.timestep > 0.0 {
                world.timestep
            } else {
                defaults.dt
            },
            ground: ground.as_ref().map(|g| g.height),
            contact,
            ..defaults
        }
    }

    /// The options `urdyn simulate SCENE.json`, Python's `Simulation(scene)` and
    /// `rollout(scene)` run a scene with (scene.md): its ground's height, and
    /// its contact parameters as [`ContactParams::of_scene_ground`] reads them
    /// (friction, torsion, rolling; no ground without one), its sleep and
    /// threads settings as [`SimOptions::with_islands`] reads them with no
    /// caller's override; everything else the defaults'. Callers set their own
    /// options (`--dt`, `--integrator`, …) over these.
    pub fn of_scene(scene: &crate::scene::Scene) -> Self {
        Self {
            ground: scene.ground.map(|g| g.height),
            contact: ContactParams::of_scene_ground(scene.ground.as_ref()),
            ..Self::default()
        }
        .with_islands(Some(&scene.spec), None, None)
    }

    /// Sleep and island threads (scene.md §"Large scenes") as `urdyn simulate`,
    /// Python's `Simulation(...)` and `rollout(...)` read them: the caller's
    /// `sleep` / `threads` (`--no-sleep`, `--threads`, `sleep=`, `threads=`)
    /// over a scene file's `"sleep"` / `"threads"`, over these options'; the
    /// file's `"sleep_velocity"`, `"sleep_time"` and its models with
    /// `"sleep": false` over these options'. `scene` `None` (a model alone):
    /// the caller's over these options'.
    pub fn with_islands(
        self,
        scene: Option<&crate::scene::SceneSpec>,
        sleep: Option<bool>,
        threads: Option<usize>,
    ) -> Self {
        let Some(spec) = scene else {
            return Self {
                sleep: sleep.unwrap_or(self.sleep),
                threads: threads.unwrap_or(self.threads),
                ..self
            };
        };
        Self {
            sleep: sleep.or(spec.sleep).unwrap_or(self.sleep),
            sleep_velocity: spec.sleep_velocity.unwrap_or(self.sleep_velocity),
            sleep_time: spec.sleep_time.unwrap_or(self.sleep_time),
            threads: threads.or(spec.threads).unwrap_or(self.threads),
            never_sleep: spec
                .models
                .iter()
                .filter(|m| m.sleep == Some(false))
                .map(|m| m.name.clone())
                .collect(),
            ..self
        }
    }
}

impl Simulation {
    /// Sets up a simulation of `model` at its neutral configuration, at rest.
    /// Contact shapes (and meshes) are built here when `opts.ground` is set and a
    /// moving link has collision geometry.
    pub fn new(model: Model, opts: SimOptions) -> Result<Self, SimError> {
        Self::build(model, opts, None)
    }

    /// [`Simulation::new`] followed by [`Simulation::set_state`]`(q, v)`, except
    /// that contacts are looked for once, at `q`, not first at the neutral
    /// configuration too: there a scene's models all sit at the origin, every
    /// pair of them overlaps, and that one detection costs O(N²) (33 s and
    /// 0.8 GB for a 1024-object mixed pile). What it left in the pairs' caches
    /// (parry's last normals of pairs overlapping at both poses) is not there:
    /// no trajectory of benches/scenes changes by a bit (tests/islands.rs
    /// checks a mixed pile). A model with loop constraints of its own (MJCF
    /// equalities, placed at the construction's state) is set up as `new` then
    /// `set_state` do.
    pub fn new_at(
        model: Model,
        opts: SimOptions,
        q: &DVector<f64>,
        v: &DVector<f64>,
    ) -> Result<Self, SimError> {
        if !model.equalities.items.is_empty() {
            let mut sim = Self::new(model, opts)?;
            sim.set_state(q, v)?;
            return Ok(sim);
        }
        Self::build(model, opts, Some((q, v)))
    }

    fn build(
        model: Model,
        opts: SimOptions,
        start: Option<(&DVector<f64>, &DVector<f64>)>,
    ) -> Result<Self, SimError> {
        let positive = |x: f64, name: &str| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(SimError::Invalid(format!(
                    "{name} must be a positive number (got {x})"
                )))
            }
        };
        positive(opts.dt, "--dt")?;
        positive(opts.tol, "--tol")?;
        positive(opts.limit_push_speed, "limit_push_speed")?;
        positive(opts.contact.max_push_speed, "contact.max_push_speed")?;
        positive(opts.sleep_velocity, "sleep_velocity")?;
        if !(opts.sleep_time.is_finite() && opts.sleep_time >= 0.0) {
            return Err(SimError::Invalid(format!(
                "sleep_time must be a non-negative number (got {})",
                opts.sleep_time
            )));
        }
        let w = opts.solver_relaxation;
        if !(w > 0.0 && w < 2.0) {
            return Err(SimError::Invalid(format!(
                "solver_relaxation must lie in (0, 2) (got {w})"
            )));
        }
        let f = opts.contact.friction;
        if !(f.is_finite() && f >= 0.0) {
            return Err(SimError::Invalid(format!(
                "--friction must be a non-negative number (got {f})"
            )));
        }
        let a = opts.armature;
        if !(a.is_finite() && a >= 0.0) {
            return Err(SimError::Invalid(format!(
                "--armature must be a non-negative number (got {a})"
            )));
        }
        if opts.threads > MAX_THREADS {
            return Err(SimError::Invalid(format!(
                "threads (--threads, a scene's \"threads\", Python's threads=) must be at most {MAX_THREADS} (got {})",
                opts.threads
            )));
        }
        crate::dynamics::check_massless(&model)?;
        // the ground, obstacles and pairs of bodies (none of them: no contact work)
        let contact = Collision::build(&model, opts.ground, opts.contact, &opts.package_paths)?;
        let integrator = opts
            .integrator
            .unwrap_or(Integrator::default_for(contact.is_some()));
        let (nq, nv) = (model.nq, model.nv);
        let mut damping = DVector::zeros(nv);
        let mut armature = DVector::zeros(nv);
        let mut effort = vec![f64::INFINITY; nv];
        for (d, _, iv) in model.dof_indices() {
            let info = &model.dofs[d];
            // --armature on every joint, plus the model's own (an MJCF joint's
            // `armature`: MuJoCo's qM diagonal)
            armature[iv] = a + info.armature.max(0.0);
            if opts.joint_dynamics {
                damping[iv] = if info.damping.is_finite() {
                    info.damping.max(0.0)
                } else {
                    0.0
                };
                if let Some(e) = info.limits.effort {
                    if e > 0.0 {
                        effort[iv] = e;
                    }
                }
            }
        }
        let max_points = contact.as_ref().map_or(0, |c| c.max_points());
        let pair_points = contact
            .as_ref()
            .and_then(|c| c.pairs.as_ref())
            .map_or(0, |p| p.max_points());
        let mass_factor = factor::MassFactor::new(&model);
        let nslots = contact.as_ref().map_or(0, |c| c.nslots);
        let row_params = RowParams {
            joint_dynamics: opts.joint_dynamics,
            restitution: opts.contact.restitution,
            gravity: model.gravity.norm(),
            beta: opts.contact.baumgarte,
            contact_push_cap: opts.contact.max_push_speed,
            limit_push_cap: opts.limit_push_speed,
            contact_slop: opts.contact.slop,
            limit_slop: 1e-4,
            // torsional and rolling friction: rows of the PGS solve (the
            // Newton solver keeps to the Coulomb cone)
            torsion: if opts.solver == Solver::Pgs {
                opts.contact.torsion
            } else {
                0.0
            },
            rolling: if opts.solver == Solver::Pgs {
                opts.contact.rolling
            } else {
                0.0
            },
        };
        let total_mass: f64 = model.inertias.iter().skip(1).map(|i| i.mass).sum();
        let scale = total_mass * model.gravity.norm();
        let has_damping = damping.iter().any(|&d| d > 0.0);
        let has_armature = armature.iter().any(|&x| x > 0.0);
        let springs = joint_springs(&model, opts.joint_dynamics);
        let spheres = contact.as_ref().map_or(Vec::new(), |c| c.body_spheres());
        let sleep = sleep::Sleep::new(
            &model,
            opts.sleep,
            opts.sleep_velocity,
            opts.sleep_time,
            spheres,
            &opts.never_sleep,
        );
        let mut sim = Self {
            sleep,
            sleep_forced: vec![false; model.trees.len()],
            integrator,
            dt: opts.dt,
            tol: opts.tol,
            t: 0.0,
            q: model.neutral(),
            v: DVector::zeros(nv),
            tau_applied: DVector::zeros(nv),
            damping,
            armature,
            effort,
            has_damping,
            has_armature,
            data: Data::new(&model),
            cons: Constraints::new(
                &model,
                &mass_factor,
                max_points,
                pair_points,
                nslots,
                opts.solver == Solver::Newton,
            ),
            contact,
            points: Vec::with_capacity(max_points),
            fk_valid: false,
            row_params,
            mass: MassWork {
                f: mass_factor,
                vfree: DVector::zeros(nv),
                tau: DVector::zeros(nv),
                vtot: DVector::zeros(nv),
                frame_dofs: (model.dofs.iter().enumerate())
                    .filter(|(_, d)| matches!(d.kind, JointKind::Free | JointKind::Planar))
                    .map(|(k, _)| k)
                    .collect(),
            },
            smooth: SmoothWork {
                data: Data::new(&model),
                qn: model.neutral(),
                vv: DVector::zeros(nv),
                tau: DVector::zeros(nv),
                tau_c: DVector::zeros(nv),
                y: DVector::zeros(nq + nv),
                y_new: DVector::zeros(nq + nv),
                y_stage: DVector::zeros(nq + nv),
                k: (0..13).map(|_| DVector::zeros(nq + nv)).collect(),
                h_next: opts.dt,
                fsal_ok: false,
            },
            servo: servo::Servo::new(&model, &model.neutral()),
            sensors: sensors::Sensors::new(nq, nv),
            forcing_changed: true,
            energy_now: None,
            guard: EnergyGuard {
                reference: None,
                v_ref: DVector::zeros(nv),
                recovering_until: None,
                scale,
                springs: model
                    .dofs
                    .iter()
                    .any(|d| d.stiffness > 0.0 && d.stiffness.is_finite() && d.kind.nv() == 1),
            },
            steps: 0,
            rejected: 0,
            rhs_evals: 0,
            pgs_sweeps: 0,
            rows_total: 0,
            opts,
            model: Arc::new(model),
            deriv: Default::default(),
        };
        if let Some((kp, q_ref)) = springs {
            // joint springs (MJCF `stiffness`/`springref`) are servos without
            // damping gain: τ = k (springref − q), integrated implicitly
            sim.set_targets(&q_ref, None)?;
            sim.set_gains(&kp, &DVector::zeros(nv))?;
        }
        sim.cons.set_threads(sim.opts.threads);
        match start {
            // set_state's checks and state_changed, once
            Some((q, v)) => sim.set_state(q, v)?,
            None => sim.state_changed(),
        }
        // the model's own loop constraints (MJCF <equality>): src/sim/equalities.rs
        sim.set_model_equalities()?;
        Ok(sim)
    }
}
