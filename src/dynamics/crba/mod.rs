//! The composite-rigid-body algorithm (CRBA) for the joint-space inertia matrix H(q).

use crate::model::{dispatch_joint, Data, JointModel, Model};
use crate::spatial::{Force, Motion, Scalar};
use nalgebra::{DVector, Vector3};

mod local;
use local::{crba_local_pass, local_pass, PackedSink};

/// The joint-space inertia matrix H(q) by the CRBA (Featherstone, RBDA §6.2),
/// written to `data.h` (the whole symmetric matrix; `data.li_m_i` is updated).
///
/// H is the matrix of docs/theory.md §"Equation of motion"; the course note builds
/// it from n inverse-dynamics calls (docs/theory.md §"Forward dynamics by inverse
/// dynamics"), the CRBA from composite bodies (docs/theory.md §"Composite-rigid-body
/// algorithm"): with `I^c_i` the inertia of body i's whole subtree, rigidly locked
/// (`I^c_i = Îᵢ + Σ_children ᵢX*ⱼ I^c_j ʲXᵢ`, inertias of docs/theory.md §"Spatial
/// inertia" moved as in §"Plücker transforms"), the column of joint i is
/// `F = I^c_i Sᵢ` (the force needed to accelerate the locked subtree along `Sᵢ`,
/// docs/theory.md §"Force recursion" with v = 0) and
///
/// `H[i, j] = Sⱼᵀ ʲXᵢ* F` for every ancestor-or-self j of i (docs/theory.md
/// §"Joint-force projection"), zero for unrelated pairs.
///
/// On chains of 16 or more coordinates without mimic joints, H's entries are formed
/// in the world frame (`crba_world`, oMᵢ from forward kinematics):
/// `H[j, k] = (⁰X̂ⱼ Sⱼ)ᵀ (⁰X̂ᵢ* I^c_i Sₖ)` is a 6-term dot product per entry, and
/// column k of the upper triangle is one contiguous sweep over j = 0..=k. The work
/// is O(n) transforms plus O(n²) dot products, with no force transported from
/// frame to frame.
///
/// On branching trees and short chains (`model.topology.crba_local`) the local-frame
/// variant runs instead (see `crba_local`): fewer instructions there.
///
/// Mimic joints: H = Gᵀ H_full G, where G maps the reduced velocities onto every
/// joint (`mult` on the leader's column). A joint's contribution therefore lands on
/// its leader's coordinate scaled by `mult` (already inside `S`), and when two
/// related joints share one coordinate their off-diagonal term lands on the
/// diagonal twice (H[k, k] gets `H_full[a, b] + H_full[b, a]`).
pub fn crba<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
) -> Result<&'d nalgebra::DMatrix<T>, super::DynamicsError> {
    super::check_sizes(model, q, &[], None)?;
    Ok(crba_dispatch(model, data, q, true))
}

/// [`crba`] for consumers that read one triangle: H's upper triangle (row ≤
/// column, with the diagonal) is written to `data.h`; the strict lower triangle
/// is left as it is (the world-frame variant skips the mirror copy, O(n²) memory
/// traffic on long chains; the others fill both anyway). This is the work of
/// Pinocchio's `crba`, which fills the upper triangle only; the tree-sparse LTDL
/// factorisation reads nothing else.
pub fn crba_upper<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
) -> Result<&'d nalgebra::DMatrix<T>, super::DynamicsError> {
    super::check_sizes(model, q, &[], None)?;
    Ok(crba_dispatch(model, data, q, false))
}

/// The variant of the model (mimic, local frames, world frame); `mirror`: fill
/// the lower triangle too (only the world-frame variant leaves it out).
pub(crate) fn crba_dispatch<'d, T: Scalar>(
    model: &Model<T>,
    data: &'d mut Data<T>,
    q: &DVector<T>,
    mirror: bool,
) -> &'d nalgebra::DMatrix<T> {
    if model.has_mimic {
        crba_mimic(model, data, q);
    } else if model.topology.crba_local {
        crba_local(model, data, q);
    } else {
        crba_world(model, data, q, mirror);
    }
    &data.h
}

/// The CRBA with mimic joints (H = Gᵀ H_full G, accumulated).
fn crba_mimic<T: Scalar>(model: &Model<T>, data: &mut Data<T>, q: &DVector<T>) {
    let nb = model.nbodies;
    let joints = &model.joints[..nb];
    let placements = &model.placements[..nb];
    let inertias = &model.inertias_origin[..nb];
    let parent = &model.parent[..nb];
    let li_m_i = &mut data.li_m_i[..nb];
    let ic = &mut data.crba_ic[..nb];
    let ident = &model.placement_identity[..nb];
    for i in 1..nb {
        let ax = joints[i].axis_rotation(ident[i]);
        li_m_i[i] = joints[i].placement_compose_ax(&placements[i], ax, q);
        ic[i] = inertias[i];
    }
    // Mimic joints accumulate into H (a joint's terms land on its leader's
    // coordinate), so H starts from zero.
    data.h.as_mut_slice().fill(T::zero());
    let h = &mut data.h;
    for i in (1..nb).rev() {
        let ji = &joints[i];
        let ici = ic[i];
        for ci in 0..ji.nv() {
            let ki = ji.iv + ci;
            // F = I^c_i S_i (column ci)
            let mut f = ici.mul_motion(&ji.subspace_column(ci));
            for cj in 0..=ci {
                let kj = ji.iv + cj;
                let val = ji.project_column(cj, &f);
                h[(ki, kj)] += val;
                if cj != ci {
                    h[(kj, ki)] += val;
                }
            }
            // Ancestors: F moves to each parent frame (ᵖX*ⱼ, docs/theory.md §"Plücker transforms").
            let mut j = i;
            while parent[j] != 0 {
                f = li_m_i[j].act_force(&f);
                j = parent[j];
                let jj = &joints[j];
                for cj in 0..jj.nv() {
                    let kj = jj.iv + cj;
                    let val = jj.project_column(cj, &f);
                    h[(ki, kj)] += val;
                    h[(kj, ki)] += val;
                }
            }
        }
        let p = parent[i];
        if p != 0 {
            let moved = ici.act(&li_m_i[i]);
            ic[p].add_assign(&moved);
        }
    }
}

/// The world-frame CRBA for models without mimic joints (Featherstone RBDA §6.2
/// with H's entries formed in the world frame, as Pinocchio's `crba-world`):
/// `H[j, k] = (⁰X̂ⱼ Sⱼ)ᵀ (⁰X̂ᵢ* I^c_i Sₖ)`, a 6-term dot product of world-frame
/// vectors, so no force is transported along the tree. The composite inertias are
/// accumulated in body frames (moved to the parent by `λ(i)Mi`, a rotation about
/// the joint axis for most joints: cheaper than moving every body inertia to the
/// world), and `F = I^c_i Sₖ` (a column of I^c_i for an axis-aligned joint) is
/// moved to the world once. Runs on chains only (`!model.topology.crba_local`):
/// coordinate k's ancestors are 0..k.
fn crba_world<T: Scalar>(model: &Model<T>, data: &mut Data<T>, q: &DVector<T>, mirror: bool) {
    debug_assert!(model.topology.h_dense, "crba_world runs on chains only");
    let nb = model.nbodies;
    let nv = model.nv;
    let q = q.as_slice();
    let joints = &model.joints[..nb];
    let placements = &model.placements[..nb];
    let inertias = &model.inertias_origin[..nb];
    let parent = &model.parent[..nb];
    let ident = &model.placement_identity[..nb];
    let li_m_i = &mut data.li_m_i[..nb];
    let o_m_i = &mut data.o_m_i[..nb];
    let ic = &mut data.crba_ic[..nb];
    // World-frame subspace columns, structure of arrays: S = (w, v).
    let fs = data.crba_f.as_mut_slice();
    let (sw0, fs) = fs.split_at_mut(nv);
    let (sw1, fs) = fs.split_at_mut(nv);
    let (sw2, fs) = fs.split_at_mut(nv);
    let (sv0, fs) = fs.split_at_mut(nv);
    let (sv1, sv2) = fs.split_at_mut(nv);
    let sv2 = &mut sv2[..nv];
    for i in 1..nb {
        let op = o_m_i[parent[i]];
        let (li, om) = dispatch_joint!(&joints[i], ident[i], jm => {
            let li = jm.placement(&placements[i], q);
            let om = jm.world_pose(&op, &li);
            let k0 = jm.joint().iv;
            for c in 0..jm.nv() {
                let s = jm.subspace_in(c, &om);
                let k = k0 + c;
                (sw0[k], sw1[k], sw2[k]) = (s.ang.x, s.ang.y, s.ang.z);
                (sv0[k], sv1[k], sv2[k]) = (s.lin.x, s.lin.y, s.lin.z);
            }
            (li, om)
        });
        li_m_i[i] = li;
        o_m_i[i] = om;
        ic[i] = inertias[i];
    }
    let hs = data.h.as_mut_slice();
    for i in (1..nb).rev() {
        let p = parent[i];
        let (head, tail) = ic.split_at_mut(i);
        let ici = tail[0];
        let om = &o_m_i[i];
        dispatch_joint!(&joints[i], ident[i], jm => {
            let k0 = jm.joint().iv;
            for c in 0..jm.nv() {
                let k = k0 + c;
                // F = ⁰X̂ᵢ* I^c_i S_k (world frame)
                let f = om.act_force(&jm.mul_subspace(&ici, c));
                let col = &mut hs[k * nv..(k + 1) * nv];
                // H[j, k] = S_jᵀ F for j = 0..=k (k's ancestors on a chain): column k
                // of the upper triangle, one contiguous, vectorisable sweep.
                project(
                    &f,
                    [&sw0[..=k], &sw1[..=k], &sw2[..=k]],
                    [&sv0[..=k], &sv1[..=k], &sv2[..=k]],
                    &mut col[..=k],
                );
            }
            // I^c_p += ₚX̂ᵢ* I^c_i ⁱX̂ₚ
            if p != 0 {
                head[p].add_assign(&ici.act_ax(&li_m_i[i], jm.rot_axis()));
            }
        });
    }
    // Mirror the upper triangle into the lower one.
    if mirror {
        mirror_blocked(hs, nv);
    }
}

/// `out[j] = Sⱼ · F` for motions stored as arrays (w, v) of equal length.
#[inline(never)]
fn project<T: Scalar>(f: &Force<T>, w: [&[T]; 3], v: [&[T]; 3], out: &mut [T]) {
    let len = out.len();
    let (w0, w1, w2) = (&w[0][..len], &w[1][..len], &w[2][..len]);
    let (v0, v1, v2) = (&v[0][..len], &v[1][..len], &v[2][..len]);
    for j in 0..len {
        let s = Motion::new(
            Vector3::new(w0[j], w1[j], w2[j]),
            Vector3::new(v0[j], v1[j], v2[j]),
        );
        out[j] = s.dot(f);
    }
}

/// Copies the strict upper triangle of the column-major n x n matrix `a` onto its
/// lower triangle, by 16 x 16 tiles (cache- and TLB-friendly for large n: a
/// 32-row band swept over all columns took 1.6x the time at n = 1000; writing
/// both triangles as dot products, no copy, took 1.2-1.5x at n = 50-200).
fn mirror_blocked<T: Scalar>(a: &mut [T], n: usize) {
    const B: usize = 16;
    let a = &mut a[..n * n];
    let mut jb = 0;
    while jb < n {
        let je = (jb + B).min(n);
        let mut ib = 0;
        while ib <= jb {
            let ie = (ib + B).min(n);
            for j in jb..je {
                for i in ib..ie.min(j) {
                    // SAFETY: i < j < n, so both i + j n and j + i n are < n², the
                    // length of `a` (sliced above).
                    unsafe {
                        *a.get_unchecked_mut(j + i * n) = *a.get_unchecked(i + j * n);
                    }
                }
            }
            ib += B;
        }
        jb += B;
    }
}

/// The local-frame CRBA (Featherstone RBDA §6.2 as written, Pinocchio's default
/// `crba`) for models without mimic joints: composite inertias moved to the parent
/// body by body, `F = I^c_i S_i` in body i's frame (a column of I^c_i for an
/// axis-aligned joint), then, as in Pinocchio, the forces of body i's whole
/// subtree (its coordinates are contiguous, `k..dof_subtree_end[k]`; kept in
/// `data.crba_fc`) are projected on `S_i` — one row of H — and carried
/// together to the parent frame by ᵖX*ᵢ. Each body's joint kind is matched once
/// ([`dispatch_joint!`]); with identity placement rotations (most robots' joints)
/// the moves are rotations about the joint axis ([`CompositeInertia::act_ax`],
/// `act_force_ax`).
fn crba_local<T: Scalar>(model: &Model<T>, data: &mut Data<T>, q: &DVector<T>) {
    crba_local_pass::<T, false, false>(model, data, q.as_slice());
}

/// [`crba`] (sizes checked by the caller) at the q whose joint placements
/// `data.li_m_i` already hold (forward kinematics ran at it): the local-frame
/// pass reads them instead of recomputing each joint's transform, and writes
/// both triangles of H, so it serves [`crba_upper`]'s callers too. Returns
/// false, computing nothing, where that variant does not run (mimic joints,
/// long chains): the caller then calls [`crba`] or [`crba_upper`].
pub(crate) fn crba_at_placements<T: Scalar>(model: &Model<T>, data: &mut Data<T>) -> bool {
    if model.has_mimic || !model.topology.crba_local {
        return false;
    }
    crba_local_pass::<T, true, false>(model, data, &[]);
    true
}

/// [`crba_at_placements`] that also writes H's entries on the tree pattern
/// into the upper triangle of `data.chol` (row ≤ column, the entries the
/// tree-sparse LTDL starts from, `ltdl::factor_placed`): no copy of H's
/// pattern before the factorisation. Returns false, computing nothing, where
/// that variant does not run.
pub(crate) fn crba_at_placements_factor<T: Scalar>(model: &Model<T>, data: &mut Data<T>) -> bool {
    if model.has_mimic || !model.topology.crba_local {
        return false;
    }
    crba_local_pass::<T, true, true>(model, data, &[]);
    true
}

/// H's entries on the tree pattern, packed per coordinate (the storage of the
/// step's tree-sparse factor, docs/theory.md §"Tree-sparse LTDL"): `H[i, k]`
/// for i an ancestor-or-self of k at `out[start[k] + len[i] − 1]`, where
/// `start[k]` is where k's path (root … k, `len[k]` coordinates) begins. No
/// nv × nv matrix is read or written (a scene of many models has an nv of
/// thousands, and H's columns a page each). `placed`: `data.li_m_i` holds the
/// joint placements at `q` (forward kinematics ran at it). The same local-frame
/// pass as [`crba`], so the entries are bit for bit those of `data.h`'s upper
/// triangle. Returns false, computing nothing, where that pass does not run
/// (mimic joints, long chains) or a size does not fit. `bodies`: only the
/// bodies of these ranges `[b0, b1)` (whole trees of a forest: a tree's
/// entries depend on its bodies alone; `None`: every body); the other trees'
/// entries are left as they were.
#[allow(clippy::too_many_arguments)]
pub(crate) fn crba_packed<T: Scalar>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &[T],
    placed: bool,
    out: &mut [T],
    start: &[usize],
    len: &[usize],
    bodies: Option<&[(usize, usize)]>,
) -> bool {
    let nv = model.nv;
    let fits = start.len() >= nv
        && len.len() >= nv
        && start[..nv]
            .iter()
            .zip(&len[..nv])
            .fold(true, |ok, (&s, &l)| ok & (l >= 1) & (s + l <= out.len()));
    if model.has_mimic || !model.topology.crba_local || !fits || (!placed && q.len() != model.nq) {
        return false;
    }
    // (fits: both hold nv entries; sliced so that an index below nv needs no test)
    let (start, len) = (&start[..nv], &len[..nv]);
    let sink = PackedSink {
        out,
        start,
        len,
        l0: 1,
        starts: &[],
    };
    let all = [(1, model.nbodies)];
    let bodies = bodies.unwrap_or(&all);
    if bodies.iter().any(|&(b0, b1)| b0 < 1 || b1 > model.nbodies) {
        return false;
    }
    if placed {
        local_pass::<T, true, _>(model, data, &[], bodies, sink);
    } else {
        local_pass::<T, false, _>(model, data, q, bodies, sink);
    }
    true
}

/// Whether `T` is `f64`: the shortcuts for exact zeros below compare values,
/// which for a number type carrying more than its value (a dual number's
/// derivative part) would not say the whole number is zero.
#[inline(always)]
pub(crate) fn is_f64<T: Scalar>() -> bool {
    std::any::TypeId::of::<T>() == std::any::TypeId::of::<f64>()
}
