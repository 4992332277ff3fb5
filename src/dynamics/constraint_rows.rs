//! The constraint rows' kinematics (mechanisms.md §"Semantics"; docs/theory.md
//! §"Constrained dynamics"): J_c, whose rows are the world motions of the
//! constraints' sides, `[v + ω × p; ω]` (`point`: 3 linear rows, `frame`: also 3
//! angular, `joint`: q̇₁ − ratio · q̇₂), the velocity-product term γ_c of
//! J_c q̈ + γ_c (the sides' classical accelerations at q̈ = 0), and each
//! constraint's violation. Shared by the constrained dynamics, its derivatives and
//! the simulation's loop rows.

use super::{check_sizes, DynamicsError};
use crate::model::{
    dispatch_joint, Attachment, ConstraintKind, Constraints, Data, DimensionError, JointModel,
    Model,
};
use crate::spatial::ops::madd;
use crate::spatial::Motion;
use nalgebra::{DMatrix, DVector, Vector3};

/// A side's world pose.
#[inline]
pub(crate) fn side_point(data: &Data, s: &Attachment) -> Vector3<f64> {
    data.o_m_i[s.body].act_point(&s.local.trans)
}

/// Adds `sign` times the side's rows (3 linear; with `frame` 3 angular) at
/// `row` of `jc`: column k of each joint on the body's path is the world
/// motion `⁰X̂ S` read at the side's point p, `[v + ω × p; ω]`
/// (docs/theory.md §"Frame Jacobian").
fn add_side_rows(
    model: &Model,
    data: &Data,
    s: &Attachment,
    sign: f64,
    frame: bool,
    row: usize,
    jc: &mut DMatrix<f64>,
) {
    let p = side_point(data, s);
    let m = jc.nrows();
    let jc = jc.as_mut_slice();
    let mut b = s.body;
    while b != 0 {
        let om = &data.o_m_i[b];
        // the joint's world columns `⁰X̂ S` through its joint model (a
        // coordinate axis picks a column of the rotation)
        dispatch_joint!(&model.joints[b], model.placement_identity[b], jm => {
            let iv = jm.joint().iv;
            for k in 0..jm.nv() {
                let sw = jm.subspace_in(k, om);
                let lin = sw.lin + sw.ang.cross(&p);
                let col = &mut jc[(iv + k) * m + row..(iv + k) * m + row + if frame { 6 } else { 3 }];
                for r in 0..3 {
                    col[r] = madd(sign, lin[r], col[r]);
                    if frame {
                        col[3 + r] = madd(sign, sw.ang[r], col[3 + r]);
                    }
                }
            }
        });
        b = model.parent[b];
    }
}

/// J_c into `jc` (zeroed first) from `data.o_m_i`.
pub(crate) fn jacobian_rows(model: &Model, data: &Data, c: &Constraints, jc: &mut DMatrix<f64>) {
    jc.as_mut_slice().fill(0.0);
    let mut row = 0;
    for con in &c.items {
        match &con.kind {
            ConstraintKind::Joint {
                v1, second, ratio, ..
            } => {
                jc[(row, *v1)] += 1.0;
                if let Some((_, v2)) = second {
                    jc[(row, *v2)] -= ratio;
                }
            }
            kind => {
                let frame = *kind == ConstraintKind::Frame;
                add_side_rows(model, data, &con.a, 1.0, frame, row, jc);
                add_side_rows(model, data, &con.b, -1.0, frame, row, jc);
            }
        }
        row += con.rows();
    }
}

/// The classical acceleration `[p̈; ω̇]` of a side's point p from its body's
/// world velocity `ov` and acceleration `oa` (spatial, at the world origin,
/// without gravity): p̈ = a + α × p + ω × ṗ, ṗ = v + ω × p (docs/theory.md
/// §"Classical acceleration").
#[inline]
pub(crate) fn classical(
    ov: &Motion<f64>,
    oa: &Motion<f64>,
    p: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let pdot = ov.lin + ov.ang.cross(p);
    (oa.lin + oa.ang.cross(p) + ov.ang.cross(&pdot), oa.ang)
}

/// γ_c into `gamma` from each body's world velocity `ov` and velocity-product
/// acceleration `oa0` (q̈ = 0, no gravity), given through closures.
pub(crate) fn bias_rows(
    data: &Data,
    c: &Constraints,
    ov: impl Fn(usize) -> Motion<f64>,
    oa0: impl Fn(usize) -> Motion<f64>,
    gamma: &mut DVector<f64>,
) {
    let mut row = 0;
    for con in &c.items {
        match con.kind {
            ConstraintKind::Joint { .. } => gamma[row] = 0.0,
            ref kind => {
                let frame = *kind == ConstraintKind::Frame;
                let side = |s: &Attachment| {
                    if s.body == 0 {
                        return (Vector3::zeros(), Vector3::zeros());
                    }
                    classical(&ov(s.body), &oa0(s.body), &side_point(data, s))
                };
                let (l1, a1) = side(&con.a);
                let (l2, a2) = side(&con.b);
                for r in 0..3 {
                    gamma[row + r] = l1[r] - l2[r];
                    if frame {
                        gamma[row + 3 + r] = a1[r] - a2[r];
                    }
                }
            }
        }
        row += con.rows();
    }
}

/// J_c (rows × nv, columns as v) at q into `out` (mechanisms.md §"Semantics").
pub fn constraint_jacobian(
    model: &Model,
    data: &mut Data,
    constraints: &Constraints,
    q: &DVector<f64>,
    out: &mut DMatrix<f64>,
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[], None)?;
    DimensionError::check("constraint jacobian rows", constraints.rows(), out.nrows())?;
    DimensionError::check("constraint jacobian columns", model.nv, out.ncols())?;
    super::forward_kinematics_unkeyed(model, data, q);
    jacobian_rows(model, data, constraints, out);
    Ok(())
}

/// Each constraint's violation at q (mechanisms.md: m for `point`, the larger of
/// distance and angle for `frame`, the signed residual for `joint`) into `out`.
pub fn constraint_violation(
    model: &Model,
    data: &mut Data,
    constraints: &Constraints,
    q: &DVector<f64>,
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    check_sizes(model, q, &[], None)?;
    DimensionError::check("violation entries", constraints.items.len(), out.len())?;
    super::forward_kinematics_unkeyed(model, data, q);
    constraints.violation(data, q.as_slice(), out);
    Ok(())
}
