//! The time-stepping step (semi-implicit Euler with implicit damping and the
//! velocity-level constraint impulses), docs/theory.md §"Simulation".
//!
//! H̃ = H + A + h·D, v* = v + h H̃⁻¹(τ − C(q, v) − D v),
//! v⁺ = v* + H̃⁻¹Jᵀλ, q⁺ = q ⊕ h (v⁺ + w)
//! (λ the impulses, w the position pass's pseudo-velocity: [`super::super::constraints`]).

use super::solve_rows;
use crate::dynamics::{aba_lone_placed, bias, bias_at_placements_ahead, forward_dynamics};
use crate::model::configuration::integrate_rotate_held;
use crate::sim::{SimError, Simulation};
use nalgebra::{DVector, Vector3};

impl Simulation {
    /// One step of length `h` from (q, v); `rows`: the assembled constraint
    /// rows are not empty.
    pub(in crate::sim) fn euler_step(&mut self, h: f64, rows: bool) -> Result<(), SimError> {
        // v* = v + h H̃⁻¹(τ − C − D v); without rows, damping or armature H̃ = H
        // and the engine's forward dynamics (ABA or CRBA + LTDL) is fastest
        self.free_velocity(h, rows || self.has_damping || self.has_armature)?;
        for f in &self.model.free_joints {
            add_frame_rate(&mut self.mass.vfree, &self.v, h, f.iv);
        }
        for &k in &self.mass.frame_dofs {
            let Some(d) = self.model.dofs.get(k) else {
                continue;
            };
            match d.kind {
                crate::model::JointKind::Free => {
                    add_frame_rate(&mut self.mass.vfree, &self.v, h, d.iv)
                }
                crate::model::JointKind::Planar => {
                    // ω = (0, 0, ω_z), v_lin = (vx, vy, 0): h ω × v_lin
                    let (vx, vy, w) = (self.v[d.iv], self.v[d.iv + 1], self.v[d.iv + 2]);
                    self.mass.vfree[d.iv] -= h * w * vy;
                    self.mass.vfree[d.iv + 1] += h * w * vx;
                }
                _ => {}
            }
        }
        self.rhs_evals += 1;
        // v⁺ = v* + H̃⁻¹Jᵀλ; the configuration moves by v⁺ + w
        if rows {
            let imp = solve_rows(
                &mut self.cons,
                &self.model,
                &self.points,
                &self.mass,
                &self.opts,
                h,
            );
            self.pgs_sweeps += imp.sweeps as u64;
            // v⁺ = v* + dv and v⁺ + w in one pass (the copies' and sums'
            // operations, entry by entry)
            crate::sim::step::plus_into(&mut self.v, &self.mass.vfree, imp.dv);
            match imp.push {
                Some(w) => crate::sim::step::plus_into(&mut self.mass.vtot, &self.v, w),
                None => self.mass.vtot.copy_from(&self.v),
            }
            self.rows_total += self.cons.rows_len() as u64;
        } else {
            self.cons.clear_forces();
            self.v.copy_from(&self.mass.vfree);
            self.mass.vtot.copy_from(&self.v);
        }
        // (a sleeping tree's free joints left out: `Sleep::hold` puts their q
        // and v back after the step)
        let held = match self.sleep.sleeping_trees() {
            Some(_) => &self.sleep.body_asleep[..],
            None => &[],
        };
        // q ⊕ h vtot, and the base's linear velocity, found in the start frame
        // R, expressed in the new frame R⁺ = R exp(h ω_total) (one pass)
        integrate_rotate_held(
            &self.model,
            &mut self.q,
            &mut self.v,
            &self.mass.vtot,
            h,
            held,
        );
        Ok(())
    }

    /// The free velocity v* = v + h H̃⁻¹(sat(τ) − C(q, v) − D v) into
    /// `mass.vfree`, with H̃ = H + A + h D factored into `mass.f` when `dense`
    /// (needed for constraint rows, damping or armature), else by the engine's
    /// forward dynamics (H̃ = H). No frame-rate term.
    pub(in crate::sim) fn free_velocity(&mut self, h: f64, dense: bool) -> Result<(), SimError> {
        if self.servo.active {
            return self.servo_free_velocity(h);
        }
        let nv = self.model.nv;
        let mut tau = std::mem::replace(&mut self.mass.tau, DVector::zeros(0));
        // C(q, v) when `dense` (it reads q and v only); when forward
        // kinematics ran at this q (the last step's contact refresh), its
        // joint placements are reused (and the energy guard's pass at this
        // state, when it ran one)
        let c = dense.then(|| {
            if self.fk_valid && self.v.len() == nv {
                Ok(bias_at_placements_ahead(
                    &self.model,
                    &mut self.data,
                    &self.q,
                    &self.v,
                ))
            } else {
                bias(&self.model, &mut self.data, &self.q, &self.v, None)
            }
        });
        // sat(τ) (kept as the servo's applied force) − D v − C in one pass
        let c_ok = match &c {
            Some(Ok(c)) => Some(c.as_slice()),
            _ => None,
        };
        free_force(
            tau.as_mut_slice(),
            self.tau_applied.as_slice(),
            self.effort.as_slice(),
            self.servo.applied.as_mut_slice(),
            self.damping.as_slice(),
            self.v.as_slice(),
            c_ok,
        );
        let free = if let Some(c) = c {
            c.map(|_| ())
                .map_err(SimError::from)
                .and_then(|_| self.factor_mass(h))
                .map(|_| self.mass.f.solve(&mut tau))
        } else {
            // lone free bodies with the placements of forward kinematics at
            // this q (the last step's contact refresh): ABA's one pass, q̈
            // written over τ
            let lone = if self.fk_valid {
                aba_lone_placed(
                    &self.model,
                    &mut self.data,
                    self.v.as_slice(),
                    tau.as_mut_slice(),
                )
            } else {
                None
            };
            match lone {
                Some(r) => r.map_err(SimError::from),
                None => forward_dynamics(&self.model, &mut self.data, &self.q, &self.v, &tau, None)
                    .map(|a| tau.copy_from(a))
                    .map_err(SimError::from),
            }
        };
        if free.is_ok() {
            // v* = h a·1 + 1·v (`axpy`'s products and sum over a copy of v,
            // in one pass)
            let (vf, a, v) = (
                self.mass.vfree.as_mut_slice(),
                tau.as_slice(),
                self.v.as_slice(),
            );
            debug_assert!(vf.len() == a.len() && vf.len() == v.len());
            for ((o, &a), &v) in vf.iter_mut().zip(a).zip(v) {
                *o = h * a * 1.0 + 1.0 * v;
            }
        }
        self.mass.tau = tau;
        free
    }
}

/// Semi-implicit Euler on the free joint works in the frame fixed at the step's
/// start: the base's linear velocity changes there by the classical acceleration
/// a_lin + ω × v_lin (the spatial body-frame acceleration misses the frame's own
/// rotation); it is rotated into the new frame after the position update. Done
/// this way the rotation of the body-frame velocity is exact and adds no energy.
/// `iv`: the free joint's first velocity coordinate.
#[inline]
pub(in crate::sim) fn add_frame_rate(
    v_new: &mut DVector<f64>,
    v_old: &DVector<f64>,
    h: f64,
    iv: usize,
) {
    // (through slices of the joint's six entries: one bounds test, not nine)
    let (Some(&[x, y, z, wx, wy, wz]), Some([nx, ny, nz])) = (
        v_old.as_slice().get(iv..iv + 6),
        v_new.as_mut_slice().get_mut(iv..iv + 3),
    ) else {
        return;
    };
    let w = Vector3::new(wx, wy, wz);
    let vl = Vector3::new(x, y, z);
    let d = w.cross(&vl) * h;
    *nx += d.x;
    *ny += d.y;
    *nz += d.z;
}

/// `out = sat(τ) − D v − C` (`c`: C, or none), `applied = sat(τ)`, entry by
/// entry with the operations of the passes it stands for (τ clamped to
/// ±effort by two tests, copied, then x − d v, then x − c), all slices nv
/// long.
#[inline(always)]
fn free_force(
    out: &mut [f64],
    tau: &[f64],
    effort: &[f64],
    applied: &mut [f64],
    damping: &[f64],
    v: &[f64],
    c: Option<&[f64]>,
) {
    let n = out.len();
    debug_assert!([
        tau.len(),
        effort.len(),
        applied.len(),
        damping.len(),
        v.len()
    ]
    .iter()
    .all(|&l| l == n));
    // (an effort limit is +∞ or positive, build.rs: no test of the bounds)
    let sat = |t: f64, e: f64| {
        let mut x = t;
        if x < -e {
            x = -e;
        }
        if x > e {
            x = e;
        }
        x
    };
    let (tau, effort, applied, damping, v) = (
        &tau[..n],
        &effort[..n],
        &mut applied[..n],
        &damping[..n],
        &v[..n],
    );
    match c {
        Some(c) => {
            let c = &c[..n];
            for k in 0..n {
                let x = sat(tau[k], effort[k]);
                applied[k] = x;
                out[k] = x - damping[k] * v[k] - c[k];
            }
        }
        None => {
            for k in 0..n {
                let x = sat(tau[k], effort[k]);
                applied[k] = x;
                out[k] = x - damping[k] * v[k];
            }
        }
    }
}
