//! The simulation's bias pass with the kinetic energy (`rnea`'s
//! `bias_at_placements_energy`) on a model whose every body is a lone free
//! body on the world (box_stack's and the piles' models): one pass over the
//! bodies, writing C where the caller keeps it, no backward sweep and no
//! joint dispatch (docs/theory.md §"Recursive Newton–Euler", §"Bias forces").
//!
//! Per body the pass of `rnea_pass` (velocity pass, bias, energy, at forward
//! kinematics' placements) with the same operations in the same order, so the
//! same numbers bit for bit: v̂ᵢ = 0 + ŝᵢ q̇ᵢ (the world's zero velocity is not
//! moved into the body's frame there either), âᵢ = ᵢX̂₀ â₀ + v̂ᵢ × ŝᵢ q̇ᵢ,
//! f̂ᵢ = Îᵢ âᵢ + v̂ᵢ ×* Îᵢ v̂ᵢ, T += ½ v̂ᵢᵀ Îᵢ v̂ᵢ; then Cᵢ = 0 + ŝᵢᵀ f̂ᵢ, the
//! projection onto a zeroed C (a body's parent is the world: nothing is
//! handed down, so the backward sweep adds nothing else).

use crate::model::joint::FreeJ;
use crate::model::{Data, JointModel, Model};
use crate::spatial::{Force, Motion};

/// C(q, v) at forward kinematics' placements (`data.li_m_i`) into `c` (nv
/// entries) and the kinetic energy T returned, for a model with
/// `data.lone_free`; the bodies flagged in `skip` (a
/// sleeping tree's, at rest) left out: their C entries zero, their body
/// velocity zero. The body velocities are left in `data.v` (sleep reads
/// them through a dozing step); `data.a`, `data.f`, `data.tau` and
/// `data.bias`, scratch of the general pass nothing reads after it, are not
/// written. `None`, nothing computed, without `data.lone_free` or where a
/// length does not match.
pub(crate) fn lone_bias_energy(
    model: &Model<f64>,
    data: &mut Data<f64>,
    v: &[f64],
    skip: &[bool],
    c: &mut [f64],
) -> Option<f64> {
    let nb = model.nbodies;
    let (Some(joints), Some(inertias), Some(li_m_i), Some(vel), Some(massless)) = (
        model.joints.get(..nb),
        model.inertias.get(..nb),
        data.li_m_i.get(..nb),
        data.v.get_mut(..nb),
        data.massless.get(..nb),
    ) else {
        return None;
    };
    if !data.lone_free || c.len() != 6 * (nb - 1) || v.len() != c.len() {
        return None;
    }
    let mut ke = 0.0;
    // docs/theory.md §"Gravity": v̂₀ = 0, â₀ = [0; −g]
    vel[0] = Motion::zero();
    let a0 = Motion::new(nalgebra::Vector3::zeros(), -model.gravity);
    for (i, ci) in (1..nb).zip(c.chunks_exact_mut(6)) {
        if skip.get(i) == Some(&true) {
            vel[i] = Motion::zero();
            ci.fill(0.0);
            continue;
        }
        let jm = FreeJ { j: &joints[i] };
        // docs/theory.md §"Velocity recursion": v̂ᵢ = 0 + ŝᵢ q̇ᵢ
        let mut vi = Motion::zero();
        jm.add_motion(&mut vi, v);
        // docs/theory.md §"Acceleration recursion": âᵢ = ᵢX̂₀ â₀ + v̂ᵢ × ŝᵢ q̇ᵢ
        let mut ai = li_m_i[i].inv_act_motion(&a0);
        jm.add_cross_motion(&mut ai, &vi, v);
        vel[i] = vi;
        // docs/theory.md §"Force recursion": f̂ᵢ = Îᵢ âᵢ + v̂ᵢ ×* Îᵢ v̂ᵢ (a
        // massless body's zero), T += ½ v̂ᵢᵀ Îᵢ v̂ᵢ
        let mut fi = Force::zero();
        if !massless[i] {
            let inertia = &inertias[i];
            fi = inertia.mul_motion(&ai);
            let hi = inertia.mul_motion(&vi);
            fi += vi.cross_force(&hi);
            ke += vi.dot(&hi) * 0.5;
        }
        // docs/theory.md §"Joint-force projection": Cᵢ = 0 + ŝᵢᵀ f̂ᵢ
        for r in 0..3 {
            ci[r] = 0.0 + fi.lin[r];
            ci[3 + r] = 0.0 + fi.ang[r];
        }
    }
    Some(ke)
}
