use super::crba::is_f64;
use super::{check_sizes, DynamicsError};
use crate::model::joint::{dispatch_of, Dispatch};
use crate::model::{dispatch_keyed, Axis, Data, JointModel, Model};
use crate::spatial::ops::add_cross;
use crate::spatial::{Force, Motion, Scalar, Se3};
use nalgebra::DVector;

/// Recursive Newton–Euler inverse dynamics (docs/theory.md §"Recursive Newton–Euler"):
/// the generalized forces `Q = H(q) q̈ + C(q, q̇)` that produce `a`, written to
/// `data.tau` and returned.
/// Gravity enters as an upward acceleration of the world (docs/theory.md §"Gravity").
/// `fext`, if given, holds one external spatial force per body in the **world**
/// frame (`f̂ˣ`, docs/theory.md §"External forces"; entry 0, the world, is ignored).
pub fn rnea<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    a: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    check_sizes(model, q, &[("v", v), ("a", a)], fext)?;
    rnea_impl(model, data, q, Some(v), Some(a), true, fext);
    Ok(&data.tau)
}

/// `C(q, q̇)` = ID(q, q̇, 0) (docs/theory.md §"Bias forces"), gravity and external
/// forces included, written to `data.bias` and returned.
pub fn bias<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    fext: Option<&[Force<T>]>,
) -> Result<&'d DVector<T>, DynamicsError> {
    check_sizes(model, q, &[("v", v)], fext)?;
    bias_pass(model, data, q, v, fext);
    Ok(&data.bias)
}

/// [`bias`] for callers that checked the sizes already.
pub(crate) fn bias_pass<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: &DVector<T>,
    fext: Option<&[Force<T>]>,
) {
    rnea_impl(model, data, q, Some(v), None, true, fext);
    data.bias.copy_from(&data.tau);
}

/// [`bias`] (no external forces, sizes checked by the caller) at the q whose
/// joint placements `data.li_m_i` already hold (forward kinematics ran at it):
/// the pass reads them instead of recomputing each joint's transform.
pub(crate) fn bias_at_placements<T: Scalar>(model: &Model<T>, data: &mut Data<T>, v: &DVector<T>) {
    bias_pass_at_placements::<T, false>(model, data, v, &[]);
}

/// [`bias_at_placements`] that also returns the kinetic energy
/// `T = ½ Σ v̂ᵢᵀ Îᵢ v̂ᵢ` summed over the pass's body velocities, from the
/// products `Îᵢ v̂ᵢ` the pass forms anyway (in body order, as
/// [`super::kinetic_energy_from_placements`]; a massless body adds nothing).
/// The bodies flagged in `skip` (a sleeping tree's: all of a tree, at zero
/// velocity) are left out: their C entries zero, their body velocity,
/// acceleration and force zero; a body at rest adds ±0 to T, which leaves it
/// as it was (a sum from +0 is never −0).
pub(crate) fn bias_at_placements_energy<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    v: &DVector<T>,
    skip: &[bool],
) -> T {
    bias_pass_at_placements::<T, true>(model, data, v, skip)
}

/// C(q, v) at the placements into `data.bias`, and with `E` the kinetic
/// energy of the pass's body velocities (zero without).
#[inline(always)]
fn bias_pass_at_placements<T: Scalar, const E: bool>(
    model: &Model<T>,
    data: &mut Data<T>,
    v: &DVector<T>,
    skip: &[bool],
) -> T {
    // (a pass of its own with bodies to skip: the one without tests none)
    let ke = if E && !skip.is_empty() {
        rnea_pass::<T, true, false, false, true, E, true>(
            model,
            data,
            &[],
            v.as_slice(),
            &[],
            true,
            None,
            skip,
        )
    } else {
        rnea_pass::<T, true, false, false, true, E, false>(
            model,
            data,
            &[],
            v.as_slice(),
            &[],
            true,
            None,
            &[],
        )
    };
    data.bias.copy_from(&data.tau);
    ke
}

/// [`bias_at_placements`] for the simulation step at (q, v), into `data.bias`:
/// taken from `data.step_bias` when the energy guard computed it ahead at this
/// very state (`data.step_bias_q`, `data.step_bias_v` equal to q and v bit for
/// bit; the same pass from the same placements, so the same numbers), else
/// computed. Marks that the step wants it, so the guard computes it ahead.
pub(crate) fn bias_at_placements_ahead<'d>(
    model: &Model<f64>,
    data: &'d mut Data<f64>,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> &'d DVector<f64> {
    // bit for bit (`==` would take −0 for +0)
    // (over slices, no early exit: one vectorised pass)
    let same = |a: &DVector<f64>, b: &DVector<f64>| {
        let (a, b) = (a.as_slice(), b.as_slice());
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .fold(true, |s, (x, y)| s & (x.to_bits() == y.to_bits()))
    };
    let ahead = data.step_bias_ok && same(&data.step_bias_q, q) && same(&data.step_bias_v, v);
    if ahead {
        std::mem::swap(&mut data.bias, &mut data.step_bias);
    } else {
        bias_at_placements(model, data, v);
    }
    data.step_bias_ok = false;
    data.step_bias_wanted = true;
    &data.bias
}

/// The one RNEA pass behind every entry point. `v = None` means q̇ = 0, `a = None`
/// means q̈ = 0, `gravity = false` leaves the world unaccelerated.
pub(crate) fn rnea_impl<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &DVector<T>,
    v: Option<&DVector<T>>,
    a: Option<&DVector<T>>,
    gravity: bool,
    fext: Option<&[Force<T>]>,
) {
    // Monomorphised on whether external forces are given: the pass without them
    // carries no per-body test and no world poses.
    let (q, v, a) = (
        q.as_slice(),
        v.map(|x| x.as_slice()),
        a.map(|x| x.as_slice()),
    );
    match fext {
        Some(_) => rnea_variant::<T, true>(model, data, q, v, a, gravity, fext),
        None => rnea_variant::<T, false>(model, data, q, v, a, gravity, None),
    }
}

/// [`rnea_impl`] on slices, with external forces present iff `F`.
#[inline(always)]
fn rnea_variant<T: Scalar, const F: bool>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &[T],
    v: Option<&[T]>,
    a: Option<&[T]>,
    gravity: bool,
    fext: Option<&[Force<T>]>,
) {
    // Monomorphised on which of q̇, q̈ are present (no per-body test).
    match (v, a) {
        (Some(v), Some(a)) => {
            rnea_pass::<T, true, true, F, false, false, false>(
                model,
                data,
                q,
                v,
                a,
                gravity,
                fext,
                &[],
            );
        }
        (Some(v), None) => {
            rnea_pass::<T, true, false, F, false, false, false>(
                model,
                data,
                q,
                v,
                &[],
                gravity,
                fext,
                &[],
            );
        }
        (None, Some(a)) => {
            rnea_pass::<T, false, true, F, false, false, false>(
                model,
                data,
                q,
                &[],
                a,
                gravity,
                fext,
                &[],
            );
        }
        (None, None) => {
            rnea_pass::<T, false, false, F, false, false, false>(
                model,
                data,
                q,
                &[],
                &[],
                gravity,
                fext,
                &[],
            );
        }
    }
}

/// [`rnea_impl`] with q̇ present iff `V`, q̈ present iff `A` and external forces
/// read iff `F`; with `E` (the bias pass, `K`) the kinetic energy of the body
/// velocities is summed and returned (zero otherwise), and with `S` the bodies
/// flagged in `skip` left out (`bias_at_placements_energy`). The joint kind of
/// each body is matched once per sweep ([`dispatch_joint!`]); the body step is then
/// compiled per joint model, with the axis and transform shape known.
#[inline(always)]
fn rnea_pass<
    T: Scalar,
    const V: bool,
    const A: bool,
    const F: bool,
    const K: bool,
    const E: bool,
    const S: bool,
>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    a: &[T],
    gravity: bool,
    fext: Option<&[Force<T>]>,
    skip: &[bool],
) -> T {
    let mut ke = T::zero();
    let nb = model.nbodies;
    let parent = &model.parent[..nb];
    let joints = &model.joints[..nb];
    let placements = &model.placements[..nb];
    let ident = &model.placement_identity[..nb];
    let zt = &model.placement_zero_trans[..nb];
    let inertias = &model.inertias[..nb];
    // (K: each joint's dispatch as `data` holds it for the model, made once;
    // likewise whether each body is massless)
    let keys = if K { &data.dispatch[..nb] } else { &[] };
    let massless = if K { &data.massless[..nb] } else { &[] };
    let li_m_i = &mut data.li_m_i[..nb];
    let o_m_i = &mut data.o_m_i[..nb];
    let vel = &mut data.v[..nb];
    let acc = &mut data.a[..nb];
    let frc = &mut data.f[..nb];
    let exact = is_f64::<T>();
    // docs/theory.md §"Gravity": v̂₀ = 0, â₀ = [0; −g]
    vel[0] = Motion::zero();
    acc[0] = if gravity {
        Motion::new(nalgebra::Vector3::zeros(), -model.gravity)
    } else {
        Motion::zero()
    };
    // (S, with E: the bodies flagged in `skip`, a whole tree each, left out)
    let skipped = |i: usize| S && E && skip.get(i) == Some(&true);
    for i in 1..nb {
        if skipped(i) {
            vel[i] = Motion::zero();
            acc[i] = Motion::zero();
            frc[i] = Force::zero();
            continue;
        }
        let p = parent[i];
        let (vp, ap) = (vel[p], acc[p]);
        let key = if K { keys[i] } else { dispatch_of(&joints[i]) };
        // (the bias pass: a free body on the world moves the world's zero
        // velocity into its frame as zeros, each of its six velocity
        // components then added to one: the move is left out)
        let on_world = K && exact && p == 0 && matches!(key.0, Dispatch::Free);
        let (li, vi, ai) = dispatch_keyed!(&joints[i], key, ident[i], jm => {
            // ᵢXₚ at q, or (K) as forward kinematics left it at this q
            let li = if K { li_m_i[i] } else { jm.placement(&placements[i], q) };
            let ax = jm.rot_axis();
            // (the bias pass: a joint frame at its parent's origin moves
            // motions by its rotation alone, `Model::placement_zero_trans`)
            let rot = K && exact && ax.is_some() && zt[i];
            // docs/theory.md §"Velocity recursion": v̂ᵢ = ᵢX̂ₚ v̂ₚ + ŝᵢ q̇ᵢ
            let mut vi = Motion::zero();
            if V {
                if !on_world {
                    vi = move_motion(&li, ax, rot, &vp);
                }
                jm.add_motion(&mut vi, v);
            }
            // docs/theory.md §"Acceleration recursion": âᵢ = ᵢX̂ₚ âₚ + v̂ᵢ × ŝᵢ q̇ᵢ + ŝᵢ q̈ᵢ
            let mut ai = move_motion(&li, ax, rot, &ap);
            if V {
                jm.add_cross_motion(&mut ai, &vi, v);
            }
            if A {
                jm.add_motion(&mut ai, a);
            }
            (li, vi, ai)
        });
        // (K: read from there, nothing to store)
        if !K {
            li_m_i[i] = li;
        }
        vel[i] = vi;
        acc[i] = ai;
        // docs/theory.md §"Force recursion" (own part):
        // f̂ᵢ = Îᵢ âᵢ + v̂ᵢ ×* Îᵢ v̂ᵢ − ᵢX̂₀ f̂ᵢˣ
        let inertia = &inertias[i];
        // (the bias pass: a massless body's own force is zero, its products
        // with the zero inertia left out)
        let mut fi = Force::zero();
        if !(K && exact && massless[i]) {
            fi = inertia.mul_motion(&ai);
            if V {
                let hi = inertia.mul_motion(&vi);
                fi += vi.cross_force(&hi);
                // (E) T += ½ v̂ᵢᵀ Îᵢ v̂ᵢ (`Inertia::kinetic_energy`'s products)
                if E {
                    ke += vi.dot(&hi) * crate::spatial::lit(0.5);
                }
            }
        }
        if let (true, Some(fext)) = (F, fext) {
            let o_m = o_m_i[p].compose(&li);
            o_m_i[i] = o_m;
            if let Some(fx) = fext.get(i) {
                fi -= o_m.inv_act_force(fx);
            }
        }
        frc[i] = fi;
    }
    let tau = data.tau.as_mut_slice();
    tau.fill(T::zero());
    // A child whose parent is the next body down (p = i − 1, a chain) hands its
    // force over in registers, added when the parent is reached: the parent's
    // other children (higher indices) were added before it, so the sums are
    // the same in the same order, and the parent's force is not read back right
    // after a store of different width (a stalled store-to-load forward per body).
    let mut carry = Force::zero();
    let mut carry_to = 0;
    for i in (1..nb).rev() {
        // (a skipped body's tree is skipped whole: no force to or from it)
        if skipped(i) {
            continue;
        }
        let p = parent[i];
        let (head, tail) = frc.split_at_mut(i);
        let mut fi = tail[0];
        if carry_to == i {
            fi += carry;
            tail[0] = fi;
        }
        let li = &li_m_i[i];
        let key = if K { keys[i] } else { dispatch_of(&joints[i]) };
        dispatch_keyed!(&joints[i], key, ident[i], jm => {
            // docs/theory.md §"Joint-force projection": Qᵢ = ŝᵢᵀ f̂ᵢ (a mimic joint adds
            // to its leader's coordinate)
            jm.project_add(&fi, tau);
            // docs/theory.md §"Force recursion" (children part): f̂ₚ += ₚX̂ᵢ f̂ᵢ
            if p != 0 {
                let x = match jm.rot_axis() {
                    Some(ax) if K && exact && zt[i] => Force {
                        ang: ax.rot_mul(&li.rot, &fi.ang),
                        lin: ax.rot_mul(&li.rot, &fi.lin),
                    },
                    ax => act_force_ax(li, ax, &fi),
                };
                if p + 1 == i {
                    (carry, carry_to) = (x, p);
                } else {
                    head[p] += x;
                }
            }
        });
    }
    ke
}

/// `ᵢX̂ₚ x` given `li` = λ(i)Mi: by its rotation alone when `rot` (a joint
/// frame at its parent's origin, `ax` given), else [`inv_act_motion_ax`]
/// (a function, not a closure: inlined into the pass, no call per body).
#[inline(always)]
fn move_motion<T: Scalar>(li: &Se3<T>, ax: Option<Axis<T>>, rot: bool, x: &Motion<T>) -> Motion<T> {
    match ax {
        Some(ax) if rot => Motion {
            ang: ax.rot_tr_mul(&li.rot, &x.ang),
            lin: ax.rot_tr_mul(&li.rot, &x.lin),
        },
        _ => inv_act_motion_ax(li, ax, x),
    }
}

/// `m.inv_act_motion(x)`, with `m`'s rotation applied as a rotation about `ax`
/// when [`crate::model::Joint::axis_rotation`] gives one (same values, fewer products).
#[inline(always)]
pub(crate) fn inv_act_motion_ax<T: Scalar>(
    m: &Se3<T>,
    ax: Option<Axis<T>>,
    x: &Motion<T>,
) -> Motion<T> {
    match ax {
        None => m.inv_act_motion(x),
        Some(ax) => Motion {
            ang: ax.rot_tr_mul(&m.rot, &x.ang),
            lin: ax.rot_tr_mul(&m.rot, &add_cross(&x.lin, &x.ang, &m.trans)),
        },
    }
}

/// `m.act_force(f)`, with `m`'s rotation applied as a rotation about `ax` when given.
#[inline(always)]
pub(crate) fn act_force_ax<T: Scalar>(m: &Se3<T>, ax: Option<Axis<T>>, f: &Force<T>) -> Force<T> {
    match ax {
        None => m.act_force(f),
        Some(ax) => {
            let lin = ax.rot_mul(&m.rot, &f.lin);
            Force {
                ang: add_cross(&ax.rot_mul(&m.rot, &f.ang), &m.trans, &lin),
                lin,
            }
        }
    }
}
