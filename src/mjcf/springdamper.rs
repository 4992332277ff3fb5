//! `<joint springdamper="τ ζ">`: MuJoCo's compiler replaces the joint's stiffness and
//! damping by those of a mass-spring-damper with time constant τ and damping ratio ζ
//! about the joint's inertia at qpos0 (docs/theory.md §"MJCF springdamper"):
//! `k = m / (τ² ζ²)`, `b = 2 m / τ`, with `m = 1 / mean((H(qpos0) + A)⁻¹)ᵢᵢ` over the
//! joint's velocity coordinates (MuJoCo's `1 / dof_invweight0`, armature A included).
//! H is formed here by the composite-rigid-body recursion (the import layer does not
//! call the dynamics; the same recursion as `dynamics::crba`'s mimic variant).

use crate::model::Model;
use crate::spatial::CompositeInertia;
use nalgebra::DMatrix;

/// One joint's springdamper: its first dof in `model.dofs`, τ (s) and ζ.
pub(super) struct SpringDamper {
    pub dof: usize,
    pub timeconst: f64,
    pub dampratio: f64,
}

/// Sets the stiffness and damping of every listed joint's dofs; a model whose H at
/// qpos0 is not positive definite (massless joints, already warned about) keeps
/// the file's values.
pub(super) fn apply(model: &mut Model, list: &[SpringDamper]) {
    if list.is_empty() {
        return;
    }
    let Some(h) = inertia_at_neutral(model) else {
        return;
    };
    let Some(chol) = h.cholesky() else {
        return;
    };
    for sd in list {
        let d = &model.dofs[sd.dof];
        let n = model
            .joints
            .iter()
            .skip(1) // body 0's placeholder joint is not a joint
            .find(|j| j.iv == d.iv)
            .map_or(1, |j| j.nv())
            .min(model.nv.saturating_sub(d.iv));
        let mut inv = 0.0;
        for k in d.iv..d.iv + n {
            let mut e = nalgebra::DVector::zeros(model.nv);
            e[k] = 1.0;
            inv += chol.solve(&e)[k];
        }
        let mass = n as f64 / inv;
        if !(mass.is_finite() && mass > 0.0) {
            continue;
        }
        let (t, z) = (sd.timeconst, sd.dampratio);
        let dof = &mut model.dofs[sd.dof];
        dof.stiffness = mass / (t * t * z * z);
        dof.damping = 2.0 * mass / t;
    }
}

/// H(qpos0) + diag(armature) by the CRBA (local frames, Featherstone RBDA §6.2).
fn inertia_at_neutral(model: &Model) -> Option<DMatrix<f64>> {
    let nb = model.nbodies;
    let q = model.neutral();
    let mut li = vec![crate::spatial::Se3::identity(); nb];
    let mut ic: Vec<CompositeInertia<f64>> = model.inertias_origin[..nb].to_vec();
    for i in 1..nb {
        let ax = model.joints[i].axis_rotation(model.placement_identity[i]);
        li[i] = model.joints[i].placement_compose_ax(&model.placements[i], ax, &q);
    }
    let mut h: DMatrix<f64> = DMatrix::zeros(model.nv, model.nv);
    for i in (1..nb).rev() {
        let ji = &model.joints[i];
        for ci in 0..ji.nv() {
            let ki = ji.iv + ci;
            let mut f = ic[i].mul_motion(&ji.subspace_column(ci));
            let mut j = i;
            loop {
                let jj = &model.joints[j];
                for cj in 0..jj.nv() {
                    let kj = jj.iv + cj;
                    if j == i && cj > ci {
                        continue;
                    }
                    let val = jj.project_column(cj, &f);
                    h[(ki, kj)] += val;
                    if ki != kj {
                        h[(kj, ki)] += val;
                    }
                }
                if model.parent[j] == 0 {
                    break;
                }
                f = li[j].act_force(&f);
                j = model.parent[j];
            }
        }
        let p = model.parent[i];
        if p != 0 {
            let moved = ic[i].act(&li[i]);
            ic[p].add_assign(&moved);
        }
    }
    if let Some(a) = model.armature() {
        for k in 0..model.nv {
            h[(k, k)] += a[k];
        }
    }
    h.iter().all(|x| x.is_finite()).then_some(h)
}
