//! The configuration manifold: q ⊕ h v (free and spherical joints' unit
//! quaternions, planar joints' SE(2), body-frame velocities, every other joint
//! additive) and its rate q̇(q, v).
//!
//! A free joint's q is `[p, quaternion (x, y, z, w)]` and its v is `[v_lin, ω]` in
//! the child's own frame (Pinocchio's free flyer, docs/theory.md §"Floating
//! base"); a spherical joint's q is a quaternion, its v ω in the child frame; a
//! planar joint's q is `[x, y, θ]`, its v `[vx, vy, ω]` in the child frame
//! (docs/theory.md §"Spherical, planar and floating joints"); 1-DoF joints have
//! q̇ = v.

use super::lie::{
    exp_ad_inverse, joint_pose, joint_twist, se3_integrate, se3_log, se3_right_jacobian,
    tangent_rows,
};
use super::JointKind;
use super::Model;
use crate::spatial::{axis_angle, quat_to_matrix, sin_cos};
use nalgebra::{DMatrix, DVector, Matrix6, Vector3};

/// Every joint that owns coordinates, free roots included: `(kind, iq, iv)`.
fn coordinate_joints(model: &Model) -> impl Iterator<Item = (JointKind, usize, usize)> + '_ {
    model
        .free_joints
        .iter()
        .map(|f| (JointKind::Free, f.iq, f.iv))
        .chain(model.dofs.iter().map(|d| (d.kind, d.iq, d.iv)))
}

/// q ← q ⊕ h v, the semi-implicit step's: a free joint's p += h R v_lin and
/// quaternion ← quaternion ⊗ exp(h ω / 2) (renormalised); a spherical joint's
/// quaternion likewise; a planar joint's (x, y) += h R(θ) (vx, vy), θ += h ω;
/// 1-DoF joints += h v.
pub fn integrate_config(model: &Model, q: &mut DVector<f64>, v: &DVector<f64>, h: f64) {
    integrate_config_held(model, q, v, h, &[]);
}

/// [`integrate_config`] but for the free joints of the bodies flagged in
/// `held` (a sleeping tree's: the step puts its q back, `Sleep::hold`, so
/// its q ⊕ h v would be thrown away; `&[]`: none).
#[inline]
pub fn integrate_config_held(
    model: &Model,
    q: &mut DVector<f64>,
    v: &DVector<f64>,
    h: f64,
    held: &[bool],
) {
    // (the joints of `coordinate_joints` in its order, each kind matched by
    // reference and a 1-DoF joint's entry through slices: no copy of a kind,
    // no matrix index an entry)
    for f in &model.free_joints {
        if held.get(f.body) != Some(&true) {
            integrate_free(q, v, h, f.iq, f.iv);
        }
    }
    integrate_dofs(model, q, v, h);
}

/// [`integrate_config_held`] (q ⊕ h w) and [`rotate_base_velocity_held`]
/// (v's linear part turned by exp(−h ω), ω from `w`) in one pass over the
/// free joints: each joint's q ⊕ h w and its v's turn, their h ω and |h ω|
/// made once (the same numbers both made: the same products of the same
/// entries); then the other joints' as the two functions take them.
pub fn integrate_rotate_held(
    model: &Model,
    q: &mut DVector<f64>,
    v: &mut DVector<f64>,
    w: &DVector<f64>,
    h: f64,
    held: &[bool],
) {
    for f in &model.free_joints {
        if held.get(f.body) == Some(&true) {
            continue;
        }
        let (Some(qs), Some(&[vx, vy, vz, wx, wy, wz]), Some(vl)) = (
            q.as_mut_slice().get_mut(f.iq..f.iq + 7),
            w.as_slice().get(f.iv..f.iv + 6),
            v.as_mut_slice().get_mut(f.iv..f.iv + 3),
        ) else {
            continue;
        };
        let (wv, th) = free_q_step(qs, [vx, vy, vz, wx, wy, wz], h);
        if let Some(r) = turned_lin(Vector3::new(vl[0], vl[1], vl[2]), &wv, th) {
            vl.copy_from_slice(r.as_slice());
        }
    }
    integrate_dofs(model, q, w, h);
    rotate_dofs(model, v, w, h);
}

/// The joints of `model.dofs` in [`integrate_config_held`] (q ⊕ h v).
#[inline(always)]
fn integrate_dofs(model: &Model, q: &mut DVector<f64>, v: &DVector<f64>, h: f64) {
    for d in &model.dofs {
        let (iq, iv) = (d.iq, d.iv);
        match &d.kind {
            JointKind::Free => integrate_free(q, v, h, iq, iv),
            JointKind::Spherical => integrate_quat(q, v, h, iq, iv),
            JointKind::Planar => {
                let (s, c) = sin_cos(q[iq + 2]);
                let (vx, vy) = (v[iv], v[iv + 1]);
                q[iq] += h * (c * vx - s * vy);
                q[iq + 1] += h * (s * vx + c * vy);
                q[iq + 2] += h * v[iv + 2];
            }
            _ => q.as_mut_slice()[iq] += h * v.as_slice()[iv],
        }
    }
}

/// One free joint's q ⊕ h v, its q at `iq..iq + 7`, its v at `iv..iv + 6`
/// (out of range: left as is). [`integrate_config`]'s step for each free joint.
pub fn integrate_free(q: &mut DVector<f64>, v: &DVector<f64>, h: f64, iq: usize, iv: usize) {
    // (through the joint's slices: one bounds test each, not one an entry)
    let (Some(qs), Some(&[vx, vy, vz, wx, wy, wz])) = (
        q.as_mut_slice().get_mut(iq..iq + 7),
        v.as_slice().get(iv..iv + 6),
    ) else {
        return;
    };
    free_q_step(qs, [vx, vy, vz, wx, wy, wz], h);
}

/// One free joint's q (`qs`, seven entries) ⊕ h v (`v` = [v_lin, ω]):
/// p += h R v_lin, quaternion ⊗ exp(h ω / 2); returns h ω and |h ω|.
#[inline(always)]
fn free_q_step(qs: &mut [f64], v: [f64; 6], h: f64) -> (Vector3<f64>, f64) {
    let [vx, vy, vz, wx, wy, wz] = v;
    let (p, quat) = qs.split_at_mut(3);
    let r = quat_to_matrix(quat[0], quat[1], quat[2], quat[3]);
    let dp = r * Vector3::new(vx, vy, vz) * h;
    p[0] += dp.x;
    p[1] += dp.y;
    p[2] += dp.z;
    let w = Vector3::new(wx, wy, wz) * h;
    let th = w.norm();
    quat_turn(quat, &w, th);
    (w, th)
}

/// The quaternion `q[iq..iq + 4]` ← itself ⊗ exp(h ω / 2), ω = `v[iv..iv + 3]`
/// (renormalised; out of range: left as is).
fn integrate_quat(q: &mut DVector<f64>, v: &DVector<f64>, h: f64, iq: usize, iv: usize) {
    if let (Some(quat), Some(&[wx, wy, wz])) = (
        q.as_mut_slice().get_mut(iq..iq + 4),
        v.as_slice().get(iv..iv + 3),
    ) {
        quat_step(quat, [wx, wy, wz], h);
    }
}

/// `quat` (x, y, z, w; four entries) ← itself ⊗ exp(h ω / 2), renormalised.
#[inline]
fn quat_step(quat: &mut [f64], omega: [f64; 3], h: f64) {
    let w = Vector3::new(omega[0], omega[1], omega[2]) * h;
    let th = w.norm();
    quat_turn(quat, &w, th);
}

/// `quat` (x, y, z, w) ← itself ⊗ exp(w / 2), renormalised, for `th` = |w|.
#[inline(always)]
fn quat_turn(quat: &mut [f64], w: &Vector3<f64>, th: f64) {
    let (s, c) = if th > 1e-12 {
        let (s, c) = sin_cos(th / 2.0);
        (s / th, c)
    } else {
        (0.5 - th * th / 48.0, 1.0 - th * th / 8.0)
    };
    let (dx, dy, dz, dw) = (w.x * s, w.y * s, w.z * s, c);
    let [x, y, z, ww, ..] = *quat else {
        return;
    };
    quat[0] = ww * dx + x * dw + y * dz - z * dy;
    quat[1] = ww * dy - x * dz + y * dw + z * dx;
    quat[2] = ww * dz + x * dy - y * dx + z * dw;
    quat[3] = ww * dw - x * dx - y * dy - z * dz;
    normalize4(quat);
}

/// Re-expresses a free or planar joint's child-frame linear velocity after its
/// frame turned by exp(h ω) (ω from `w`): v_lin ← exp(−h ω) v_lin. With
/// [`integrate_config`] this makes a semi-implicit step rotate the velocity
/// exactly (no energy from the frame's own rotation).
pub fn rotate_base_velocity(model: &Model, v: &mut DVector<f64>, w: &DVector<f64>, h: f64) {
    rotate_base_velocity_held(model, v, w, h, &[]);
}

/// [`rotate_base_velocity`] but for the free joints of the bodies flagged in
/// `held` (a sleeping tree's: the step sets its v back to 0, `Sleep::hold`;
/// `&[]`: none).
#[inline]
pub fn rotate_base_velocity_held(
    model: &Model,
    v: &mut DVector<f64>,
    w: &DVector<f64>,
    h: f64,
    held: &[bool],
) {
    // (the joints of `coordinate_joints` in its order: the free roots, then
    // the others, the kinds matched by reference)
    let frees = model
        .free_joints
        .iter()
        .filter(|f| held.get(f.body) != Some(&true))
        .map(|f| (true, f.iv));
    for (free, iv) in frees {
        turn_joint(v, w, h, free, iv);
    }
    rotate_dofs(model, v, w, h);
}

/// The joints of `model.dofs` in [`rotate_base_velocity_held`].
#[inline(always)]
fn rotate_dofs(model: &Model, v: &mut DVector<f64>, w: &DVector<f64>, h: f64) {
    let others = model.dofs.iter().filter_map(|d| match &d.kind {
        JointKind::Free => Some((true, d.iv)),
        JointKind::Planar => Some((false, d.iv)),
        _ => None,
    });
    for (free, iv) in others {
        turn_joint(v, w, h, free, iv);
    }
}

/// One free (`free`) or planar joint's linear velocity at `iv` turned by
/// exp(−h ω) (ω from `w`: a free joint's three, a planar joint's one about z).
#[inline(always)]
fn turn_joint(v: &mut DVector<f64>, w: &DVector<f64>, h: f64, free: bool, iv: usize) {
    let (wv, n) = if free {
        (Vector3::new(w[iv + 3], w[iv + 4], w[iv + 5]) * h, 3)
    } else {
        (Vector3::new(0.0, 0.0, w[iv + 2] * h), 2)
    };
    let th = wv.norm();
    let vl = Vector3::new(v[iv], v[iv + 1], if n == 3 { v[iv + 2] } else { 0.0 });
    if let Some(vl) = turned_lin(vl, &wv, th) {
        for k in 0..n {
            v[iv + k] = vl[k];
        }
    }
}

/// `vl` turned by exp(−wv): exp(wv)ᵀ vl for `th` = |wv| > 0, else `None`
/// (no turn).
#[inline(always)]
fn turned_lin(vl: Vector3<f64>, wv: &Vector3<f64>, th: f64) -> Option<Vector3<f64>> {
    (th > 0.0).then(|| axis_angle(&(wv / th), th).transpose() * vl)
}

/// Writes q̇ into `dy[0..nq]`: a free joint's ṗ = R(q̂) v_lin (q̂ = `qn`,
/// normalised), a quaternion's rate ½ q ⊗ (ω, 0) with q read from `y`
/// unnormalised (the exact derivative of the ODE state), a planar joint's
/// (ẋ, ẏ) = R(θ) (vx, vy), θ̇ = ω; 1-DoF joints q̇ = v.
pub fn config_rate(
    model: &Model,
    qn: &DVector<f64>,
    y: &DVector<f64>,
    v: &DVector<f64>,
    dy: &mut DVector<f64>,
) {
    for (kind, iq, iv) in coordinate_joints(model) {
        match kind {
            JointKind::Free => {
                let r = quat_to_matrix(qn[iq + 3], qn[iq + 4], qn[iq + 5], qn[iq + 6]);
                let pd = r * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
                dy[iq] = pd.x;
                dy[iq + 1] = pd.y;
                dy[iq + 2] = pd.z;
                quat_rate(y, v, dy, iq + 3, iv + 3);
            }
            JointKind::Spherical => quat_rate(y, v, dy, iq, iv),
            JointKind::Planar => {
                let (s, c) = sin_cos(qn[iq + 2]);
                let (vx, vy) = (v[iv], v[iv + 1]);
                dy[iq] = c * vx - s * vy;
                dy[iq + 1] = s * vx + c * vy;
                dy[iq + 2] = v[iv + 2];
            }
            _ => dy[iq] = v[iv],
        }
    }
}

/// The quaternion rate ½ q ⊗ (ω, 0) of `y[iq..iq + 4]`, ω = `v[iv..iv + 3]`.
fn quat_rate(y: &DVector<f64>, v: &DVector<f64>, dy: &mut DVector<f64>, iq: usize, iv: usize) {
    let (x, yy, z, ww) = (y[iq], y[iq + 1], y[iq + 2], y[iq + 3]);
    let (wx, wy, wz) = (v[iv], v[iv + 1], v[iv + 2]);
    // (q ⊗ (ω,0)): vector = w ω + qv × ω, scalar = −qv·ω
    dy[iq] = 0.5 * (ww * wx + yy * wz - z * wy);
    dy[iq + 1] = 0.5 * (ww * wy + z * wx - x * wz);
    dy[iq + 2] = 0.5 * (ww * wz + x * wy - yy * wx);
    dy[iq + 3] = -0.5 * (x * wx + yy * wy + z * wz);
}

/// Normalises a free base's quaternion `q[3..7]` in place (a zero or non-finite
/// one is left as is).
pub fn normalize_quat(q: &mut DVector<f64>) {
    if q.len() < 7 {
        return;
    }
    normalize_quat_at(q, 3);
}

/// Normalises every free and spherical joint's quaternion in place (as
/// [`normalize_quat`]).
pub fn normalize_quats(model: &Model, q: &mut DVector<f64>) {
    for (kind, iq, _) in coordinate_joints(model) {
        match kind {
            JointKind::Free => normalize_quat_at(q, iq + 3),
            JointKind::Spherical => normalize_quat_at(q, iq),
            _ => {}
        }
    }
}

/// Normalises the quaternion `q[at..at + 4]` (a zero or non-finite one is left as is).
#[inline]
fn normalize_quat_at(q: &mut DVector<f64>, at: usize) {
    if let Some(quat) = q.as_mut_slice().get_mut(at..at + 4) {
        normalize4(quat);
    }
}

/// Normalises the quaternion of four entries `quat` (a zero or non-finite
/// one, or fewer entries, left as is).
#[inline]
fn normalize4(quat: &mut [f64]) {
    let Some(quat) = quat.get_mut(..4) else {
        return;
    };
    let n = (quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]).sqrt();
    if n > 0.0 && n.is_finite() {
        for x in quat {
            *x /= n;
        }
    }
}

// ---------------------------------------------------------------------------
// The manifold for tools: q ⊕ v, q₁ ⊖ q₀, neutral and random configurations,
// configurations by joint name (sizes checked, no panic).

use super::{DimensionError, NameError};

/// `q ⊕ v` (Pinocchio's `integrate`): a free joint moves along SE(3)'s
/// exponential by the body-frame twist `[v_lin; ω]`, `M ← M exp(v)` (p ← p + R V(ω)
/// v_lin, quaternion ← quaternion ⊗ exp(ω/2), docs/theory.md §"Derivatives"); a
/// spherical joint along SO(3)'s, a planar joint along SE(2)'s (θ ← θ + ω, not
/// wrapped); every other joint adds. Every joint through its own coordinates.
pub fn integrate(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let mut out = q.clone();
    for (kind, iq, iv) in coordinate_joints(model) {
        if tangent_rows(&kind).is_none() {
            out[iq] = q[iq] + v[iv];
            continue;
        }
        let (p0, u0) = joint_pose(&kind, q, iq);
        let (lin, w) = joint_twist(&kind, v, iv);
        let (p1, u1) = se3_integrate(&p0, &u0, &lin, &w);
        let c = u1.as_ref().coords;
        match kind {
            JointKind::Free => {
                for k in 0..3 {
                    out[iq + k] = p1[k];
                }
                for k in 0..4 {
                    out[iq + 3 + k] = c[k];
                }
            }
            JointKind::Spherical => {
                for k in 0..4 {
                    out[iq + k] = c[k];
                }
            }
            _ => {
                out[iq] = p1.x;
                out[iq + 1] = p1.y;
                out[iq + 2] = q[iq + 2] + v[iv + 2];
            }
        }
    }
    Ok(out)
}

/// `q₁ ⊖ q₀` (Pinocchio's `difference`): the v with [`integrate`]`(q₀, v) = q₁` — a
/// free, spherical or planar joint's `log(M₀⁻¹ M₁)` (the shorter rotation), every
/// other joint `q₁ − q₀`.
pub fn difference(
    model: &Model,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> Result<DVector<f64>, DimensionError> {
    DimensionError::check("q0", model.nq, q0.len())?;
    DimensionError::check("q1", model.nq, q1.len())?;
    let mut v = DVector::zeros(model.nv);
    for (kind, iq, iv) in coordinate_joints(model) {
        let Some(rows) = tangent_rows(&kind) else {
            v[iv] = q1[iq] - q0[iq];
            continue;
        };
        let (lin, w) = joint_log(&kind, q0, q1, iq);
        let x = [lin.x, lin.y, lin.z, w.x, w.y, w.z];
        for (k, &r) in rows.iter().enumerate() {
            v[iv + k] = x[r];
        }
    }
    Ok(v)
}

/// `log(M₀⁻¹ M₁)` of a multi-coordinate joint at `q[iq..]`.
fn joint_log(
    kind: &JointKind,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
    iq: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let (p0, u0) = joint_pose(kind, q0, iq);
    let (p1, u1) = joint_pose(kind, q1, iq);
    se3_log(&p0, &u0, &p1, &u1)
}

/// Writes a joint's rows and columns of the 6x6 `m` (SE(3)'s tangent) into `out`
/// at `(iv, iv)`.
fn put_block(out: &mut DMatrix<f64>, iv: usize, rows: &[usize], m: &Matrix6<f64>) {
    for (a, &r) in rows.iter().enumerate() {
        for (b, &c) in rows.iter().enumerate() {
            out[(iv + a, iv + b)] = m[(r, c)];
        }
    }
}

/// The Jacobians of [`integrate`] (Pinocchio's `dIntegrate`, tangent spaces on both
/// sides): `(∂(q ⊕ v)/∂q, ∂(q ⊕ v)/∂v)`, nv × nv. A free joint's blocks (linear
/// first) are `Ad(exp(v)⁻¹)` and the right Jacobian `Jexp(v)` of SE(3)
/// (docs/theory.md §"Derivatives"); a spherical or planar joint's are their rows
/// and columns of these; every other joint's entry is 1.
pub fn integrate_jacobians(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DimensionError> {
    DimensionError::check("q", model.nq, q.len())?;
    DimensionError::check("v", model.nv, v.len())?;
    let (mut jq, mut jv) = (
        DMatrix::zeros(model.nv, model.nv),
        DMatrix::zeros(model.nv, model.nv),
    );
    for (kind, _, iv) in coordinate_joints(model) {
        let Some(rows) = tangent_rows(&kind) else {
            jq[(iv, iv)] = 1.0;
            jv[(iv, iv)] = 1.0;
            continue;
        };
        let (lin, w) = joint_twist(&kind, v, iv);
        put_block(&mut jq, iv, rows, &exp_ad_inverse(&lin, &w));
        put_block(&mut jv, iv, rows, &se3_right_jacobian(&lin, &w));
    }
    Ok((jq, jv))
}

/// The Jacobians of [`difference`] (Pinocchio's `dDifference`):
/// `(∂(q₁ ⊖ q₀)/∂q₀, ∂(q₁ ⊖ q₀)/∂q₁)`, nv × nv. A free joint's blocks, with
/// `M = M₀⁻¹ M₁`: `−Jlog(M) Ad(M⁻¹)` and `Jlog(M)`, `Jlog = Jexp(log M)⁻¹`; a
/// spherical or planar joint's are their rows and columns of these; every other
/// joint's entries are −1 and 1.
pub fn difference_jacobians(
    model: &Model,
    q0: &DVector<f64>,
    q1: &DVector<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DimensionError> {
    DimensionError::check("q0", model.nq, q0.len())?;
    DimensionError::check("q1", model.nq, q1.len())?;
    let (mut j0, mut j1) = (
        DMatrix::zeros(model.nv, model.nv),
        DMatrix::zeros(model.nv, model.nv),
    );
    for (kind, iq, iv) in coordinate_joints(model) {
        let Some(rows) = tangent_rows(&kind) else {
            j0[(iv, iv)] = -1.0;
            j1[(iv, iv)] = 1.0;
            continue;
        };
        let (lin, w) = joint_log(&kind, q0, q1, iq);
        let jr = se3_right_jacobian(&lin, &w);
        let jlog = jr.try_inverse().unwrap_or_else(Matrix6::identity);
        let ad = exp_ad_inverse(&lin, &w);
        put_block(&mut j0, iv, rows, &(-jlog * ad));
        put_block(&mut j1, iv, rows, &jlog);
    }
    Ok((j0, j1))
}

/// A random configuration inside the joint limits (uniform; a continuous joint,
/// or one without limits, in [−π, π]; a free base at the origin with a uniformly
/// random orientation; a spherical joint a uniformly random rotation, a floating
/// joint one and a position in [−1, 1]³ m; a planar joint x, y in [−1, 1] m and
/// θ in [−π, π]), reproducible from `seed`.
pub fn random_configuration(model: &Model, seed: u64) -> DVector<f64> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    // splitmix64: a uniform number in [0, 1)
    let mut unit = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut q = model.neutral();
    let pi = std::f64::consts::PI;
    // Shoemake's uniform unit quaternion at q[at..at + 4]
    let quat = |q: &mut DVector<f64>, at: usize, unit: &mut dyn FnMut() -> f64| {
        let (u1, u2, u3) = (unit(), unit(), unit());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        q[at] = a * (2.0 * pi * u2).sin();
        q[at + 1] = a * (2.0 * pi * u2).cos();
        q[at + 2] = b * (2.0 * pi * u3).sin();
        q[at + 3] = b * (2.0 * pi * u3).cos();
    };
    for f in &model.free_joints {
        quat(&mut q, f.iq + 3, &mut unit);
    }
    for dof in &model.dofs {
        let iq = dof.iq;
        match dof.kind {
            JointKind::Free => {
                for k in 0..3 {
                    q[iq + k] = 2.0 * unit() - 1.0;
                }
                quat(&mut q, iq + 3, &mut unit);
            }
            JointKind::Spherical => quat(&mut q, iq, &mut unit),
            JointKind::Planar => {
                q[iq] = 2.0 * unit() - 1.0;
                q[iq + 1] = 2.0 * unit() - 1.0;
                q[iq + 2] = pi * (2.0 * unit() - 1.0);
            }
            _ => {
                let (lo, hi) = match (dof.limits.lower, dof.limits.upper) {
                    (Some(lo), Some(hi)) if lo < hi && !dof.continuous => (lo, hi),
                    _ => (-pi, pi),
                };
                q[iq] = lo + (hi - lo) * unit();
            }
        }
    }
    q
}

impl Model {
    /// The configuration with the named joints at the given positions and every
    /// other at [`Model::neutral`]. Keys are degrees of freedom (movable, non-mimic
    /// joints; a joint of several coordinates gets the value in its first); an
    /// unknown name is an error naming it and the nearest known one.
    pub fn configuration_from_names<'a>(
        &self,
        values: impl IntoIterator<Item = (&'a str, f64)>,
    ) -> Result<DVector<f64>, NameError> {
        let mut q = self.neutral();
        for (name, x) in values {
            q[self.q_index(name)?] = x;
        }
        Ok(q)
    }
    /// Every 1-DoF joint's position in `q` by joint name, in engine order.
    pub fn positions_by_name(&self, q: &DVector<f64>) -> Result<Vec<(&str, f64)>, DimensionError> {
        DimensionError::check("q", self.nq, q.len())?;
        Ok(self
            .dof_indices()
            .map(|(d, iq, _)| (self.dofs[d].name.as_str(), q[iq]))
            .collect())
    }
}
