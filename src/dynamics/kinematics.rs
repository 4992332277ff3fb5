use crate::model::joint::{dispatch_of, Dispatch, FreeJ};
use crate::model::{dispatch_keyed, Data, FrameId, JointModel, Model, NameError};
use crate::spatial::ops::mat_mat;
use crate::spatial::{rodrigues, sin_cos, skew, Scalar, Se3};
use nalgebra::DVector;

/// Forward kinematics of every body: `liMi = X_tree,i · X_J(q_i)` and
/// `oMi = oM_λ(i) · liMi`.
/// `q` must have nq entries (else the error, nothing computed).
pub fn forward_kinematics<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) -> Result<(), super::DynamicsError> {
    super::check_sizes(model, q, &[], None)?;
    forward_kinematics_unkeyed(model, data, q);
    Ok(())
}

/// [`forward_kinematics`] for callers whose `q` has nq entries by construction
/// and whose `data` was made by [`Data::new`] for this very model (the
/// simulation's own state and workspace): each joint's dispatch and an oblique
/// revolute axis's `k k` are read from `data` ([`Data::axis_k2`]) instead of
/// re-derived per body.
pub(crate) fn forward_kinematics_pass<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) {
    fk_pass::<T, true>(model, data, q);
}

/// [`forward_kinematics`] for callers whose `q` has nq entries by construction
/// and whose `data` may have been made for another model of the same size
/// (the public entry points': each joint's dispatch derived from the model).
pub(crate) fn forward_kinematics_unkeyed<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
) {
    fk_pass::<T, false>(model, data, q);
}

/// Forward kinematics; `KEYED`: the joints' dispatch and `k k` from `data`.
#[inline(always)]
fn fk_pass<T: Scalar, const KEYED: bool>(model: &Model<T>, data: &mut Data<T>, q: &DVector<T>) {
    let nb = model.nbodies;
    let q = q.as_slice();
    let joints = &model.joints[..nb];
    let parent = &model.parent[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let keys = if KEYED { &data.dispatch[..nb] } else { &[] };
    let k2s = if KEYED { &data.axis_k2[..nb] } else { &[] };
    let zt = &model.placement_zero_trans[..nb];
    let li_m_i = &mut data.li_m_i[..nb];
    let o_m_i = &mut data.o_m_i[..nb];
    // (a free body on the world at an identity placement: its joint's pose
    // M is λ(i)Mi and oMi as they are when `plain_pose` (I·M = M bit for bit);
    // the world's pose is the identity)
    let lone = KEYED && super::crba::is_f64::<T>() && o_m_i.first() == Some(&Se3::identity());
    for i in 1..nb {
        let op = o_m_i[parent[i]];
        if lone && parent[i] == 0 && ident[i] && zt[i] && matches!(keys[i].0, Dispatch::Free) {
            // M = X_J(q), the pose `FreeJ::placement` composes
            let m = FreeJ { j: &joints[i] }.joint_pose(q);
            if plain_pose(&m) {
                li_m_i[i] = m;
                o_m_i[i] = m;
                continue;
            }
        }
        let key = if KEYED {
            keys[i]
        } else {
            dispatch_of(&joints[i])
        };
        // The joint kind matched once per body (dispatch_keyed!).
        let (li, om) = match key {
            // a revolute joint about an oblique axis u: `λ(i)Mi`'s rotation
            // `X_tree.rot · R`, R = 1 + k s + k² (1 − c) (`Axis::rotate_right`,
            // `k k` made once). With an identity placement rotation the product
            // is R itself, bit for bit: its entry (r, c) is R[r][c] plus two
            // products of an exact zero with finite entries of R (or NaN with
            // NaN ones), which changes R[r][c] only if R[r][c] is −0; and no
            // entry of R is −0: each is 1 or +0 plus k s, then plus k² (1 − c),
            // and a sum whose first term is not −0 is not −0.
            (Dispatch::RevU(u), mult, off) if KEYED => {
                let (s, c) = sin_cos(mult * q[joints[i].iq] + off);
                let r = rodrigues(&skew(&u), &k2s[i], s, c);
                let xt = &placements[i];
                let rot = if ident[i] { r } else { mat_mat(&xt.rot, &r) };
                let li = Se3::new(rot, xt.trans);
                (li, op.compose(&li))
            }
            key => dispatch_keyed!(&joints[i], key, ident[i], jm => {
                let li = jm.placement(&placements[i], q);
                let om = jm.world_pose(&op, &li);
                (li, om)
            }),
        };
        li_m_i[i] = li;
        o_m_i[i] = om;
    }
}

/// Every entry of `m` finite and nonzero, by their product (finite and
/// nonzero only then: a zero factor makes it zero or NaN, an infinite one
/// infinite or NaN; an underflow or overflow of finite nonzero entries says
/// no). Then `I·m` and `m·I` (an identity pose's rotation exactly I, its
/// translation ±0) are `m` bit for bit: each entry is an entry of m plus
/// products of entries with ±0, which leave a nonzero value as it is (with or
/// without fused multiply–adds); only a zero's sign could differ.
#[inline(always)]
pub(crate) fn plain_pose<T: Scalar>(m: &Se3<T>) -> bool {
    let [c0, c1, c2] = m.rot.data.0;
    let t = &m.trans;
    let p = (c0[0] * c0[1] * c0[2])
        * (c1[0] * c1[1] * c1[2])
        * (c2[0] * c2[1] * c2[2])
        * (t.x * t.y * t.z);
    let a = p.abs();
    a > T::zero() && a.is_finite()
}

/// The world pose of every URDF link frame, `oMf = oMi · iMf`, from `data.o_m_i`
/// (call [`forward_kinematics`] first).
pub fn update_frames<T: Scalar>(model: &Model<T>, data: &mut Data<T>) {
    for (k, f) in model.frames.iter().enumerate() {
        // Most link frames are their body's frame (identity placement): copy.
        data.o_m_f[k] = if f.placement == Se3::identity() {
            data.o_m_i[f.body]
        } else {
            data.o_m_i[f.body].compose(&f.placement)
        };
    }
}

/// The world pose `⁰M_f = ⁰Mᵢ ⁱM_f` of one URDF link frame, from `data.o_m_i` (call
/// [`forward_kinematics`] first); an id the model does not have is an error.
pub fn frame_placement<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
) -> Result<Se3<T>, super::DynamicsError> {
    frame_pose(model, data, frame).map(|(_, m)| m)
}

/// The body of a link frame and its world pose `⁰M_f` from `data.o_m_i`, or the
/// error for an id the model does not have.
pub(crate) fn frame_pose<T: Scalar>(
    model: &Model<T>,
    data: &Data<T>,
    frame: FrameId,
) -> Result<(usize, Se3<T>), super::DynamicsError> {
    let f = model.frames.get(frame.0).ok_or(NameError::OutOfRange {
        kind: "frame",
        id: frame.0,
        len: model.frames.len(),
    })?;
    Ok((f.body, data.o_m_i[f.body].compose(&f.placement)))
}
