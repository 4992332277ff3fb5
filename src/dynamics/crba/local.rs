//! The CRBA's local-frame pass and where it puts H's entries: the step's packed
//! tree-pattern storage or both triangles of the dense `H` (docs/theory.md
//! §"Tree-sparse LTDL").

use super::is_f64;
use crate::dynamics::rnea::act_force_ax;
use crate::model::joint::dispatch_of;
use crate::model::{dispatch_keyed, Data, JointModel, Model};
use crate::spatial::{Force, Scalar};

/// Where the local-frame pass puts H's entries: per body, [`RowSink::begin`]
/// with its joint's first coordinate and the number of its subtree's
/// coordinates (the per-body lookups done once there: the joint's depth, its
/// columns' starts), then [`RowSink::put`] per column.
pub(super) trait RowSink<T> {
    /// The joint of first coordinate `k0` whose subtree's coordinates are
    /// `k0..k0 + n` (the caller's promise: `k0 + n ≤ nv`).
    fn begin(&mut self, k0: usize, n: usize);
    /// `H[k0 + r, k0 + dc] = vals[r]` (dc < n, `vals` the joint's rows: k0 +
    /// vals.len() ≤ k0 + n).
    fn put(&mut self, dc: usize, vals: &[T]);
}

/// [`crba_packed`]'s storage: `H[i, k]` for i an ancestor-or-self of k at
/// `out[start[k] + len[i] − 1]`, the upper triangle only (row ≤ column: the
/// entries the factor reads, the lower ones their mirror).
pub(super) struct PackedSink<'a, T> {
    pub(super) out: &'a mut [T],
    pub(super) start: &'a [usize],
    pub(super) len: &'a [usize],
    /// The current joint's depth, len[k0] (≥ 1: `fits`).
    pub(super) l0: usize,
    /// The current joint's columns' starts, start[k0..k0 + n].
    pub(super) starts: &'a [usize],
}

impl<'a, T: Scalar> RowSink<T> for PackedSink<'a, T> {
    #[inline(always)]
    fn begin(&mut self, k0: usize, n: usize) {
        // (out of range: no column, every put a no-op)
        let (len, start): (&'a [usize], &'a [usize]) = (self.len, self.start);
        (self.l0, self.starts) = match (len.get(k0), start.get(k0..k0 + n)) {
            (Some(&l0), Some(starts)) => (l0, starts),
            _ => (1, &[][..]),
        };
    }
    #[inline(always)]
    fn put(&mut self, dc: usize, vals: &[T]) {
        // column c = k0 + dc's entries start at start[c]; row k0 + r (an
        // ancestor-or-self of c, a joint's coordinates one chain: depth
        // len[k0] − 1 + r) sits at start[c] + len[k0] − 1 + r
        let (Some(&s), l0) = (self.starts.get(dc), self.l0) else {
            return;
        };
        // a 1-dof joint's row (vals' length known where the pass is
        // compiled per joint model): its one entry, no run to cut
        if let [v] = vals {
            if let Some(x) = self.out.get_mut(s + l0 - 1) {
                *x = *v;
            }
            return;
        }
        // rows k0 + r ≤ c only
        let n = vals.len().min(dc + 1);
        let Some(x) = self.out.get_mut(s + l0 - 1..s + l0 - 1 + n) else {
            return;
        };
        // (the common lengths with constant bounds: no call to memcpy)
        match (x, &vals[..n]) {
            ([x], [v]) => *x = *v,
            (x @ [_, _, _, _, _, _], v @ [_, _, _, _, _, _]) => x.copy_from_slice(v),
            (x, v) => x.copy_from_slice(v),
        }
    }
}

/// [`crba_local_pass`]'s storage: both triangles of the nv x nv `H` (and with
/// `FACTOR` the upper one of the factor's matrix), by raw pointers.
struct DenseSink<T, const FACTOR: bool> {
    hp: *mut T,
    up: *mut T,
    nv: usize,
    /// The current joint's first coordinate and subtree size.
    k0: usize,
    n: usize,
}

impl<T: Scalar, const FACTOR: bool> RowSink<T> for DenseSink<T, FACTOR> {
    #[inline(always)]
    fn begin(&mut self, k0: usize, n: usize) {
        assert!(k0 + n <= self.nv, "subtree coordinates out of range");
        (self.k0, self.n) = (k0, n);
    }
    #[inline(always)]
    fn put(&mut self, dc: usize, vals: &[T]) {
        let (hp, up, nv, k0) = (self.hp, self.up, self.nv, self.k0);
        assert!(dc < self.n && vals.len() <= self.n, "rows out of range");
        let c = k0 + dc;
        for (r, &val) in vals.iter().enumerate() {
            let row = k0 + r;
            // SAFETY: row < nv and c < nv (asserted here and in begin: dc <
            // n, vals.len() ≤ n, k0 + n ≤ nv), so both row + c nv and c + row
            // nv are < nv² ≤ the length of H's storage (asserted by
            // crba_local_pass), and of the factor's with FACTOR (asserted
            // there); both outlive the pass.
            unsafe {
                *hp.add(row + c * nv) = val;
                *hp.add(c + row * nv) = val;
                if FACTOR {
                    // row is a coordinate of an ancestor-or-self of c's
                    // joint: row ≤ c, the upper triangle
                    *up.add(row + c * nv) = val;
                }
            }
        }
    }
}

/// The local-frame pass into `data.h` (both triangles); `PLACED`:
/// `data.li_m_i` holds the joint placements at q (then `q` is not read), else
/// they are computed from `q` and stored; `FACTOR`: the entries also into
/// `data.chol`'s upper triangle (the tree pattern's, row ≤ column).
pub(super) fn crba_local_pass<T: Scalar, const PLACED: bool, const FACTOR: bool>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &[T],
) {
    let nv = model.nv;
    let mut h = std::mem::replace(&mut data.h, nalgebra::DMatrix::zeros(0, 0));
    let mut u = if FACTOR {
        std::mem::replace(&mut data.chol, nalgebra::DMatrix::zeros(0, 0))
    } else {
        nalgebra::DMatrix::zeros(0, 0)
    };
    let hs = h.as_mut_slice();
    assert!(hs.len() >= nv * nv, "H is nv x nv");
    let hp = hs.as_mut_ptr();
    let us = u.as_mut_slice();
    assert!(!FACTOR || us.len() >= nv * nv, "the factor is nv x nv");
    let up = us.as_mut_ptr();
    let all = [(1, model.nbodies)];
    let sink = DenseSink::<T, FACTOR> {
        hp,
        up,
        nv,
        k0: 0,
        n: 0,
    };
    local_pass::<T, PLACED, _>(model, data, q, &all, sink);
    data.h = h;
    if FACTOR {
        data.chol = u;
    }
}

/// The local-frame pass: every entry `H[row, c]` on the tree pattern (row a
/// coordinate of a joint, c one of its subtree's; row < nv, c < nv) given to
/// `sink`, a joint's rows of one column at once ([`RowSink::put`], after
/// [`RowSink::begin`] for the body; the entries off the pattern are zero and
/// never given),
/// over the bodies of `bodies` (ranges `[b0, b1)` in 1..nb, each whole
/// subtrees of the world: every tree's bodies, or some trees' of a forest).
pub(super) fn local_pass<T: Scalar, const PLACED: bool, W: RowSink<T>>(
    model: &Model<T>,
    data: &mut Data<T>,
    q: &[T],
    bodies: &[(usize, usize)],
    mut sink: W,
) {
    let nb = model.nbodies;
    let nv = model.nv;
    let joints = &model.joints[..nb];
    let placements = &model.placements[..nb];
    let inertias = &model.inertias_origin[..nb];
    let parent = &model.parent[..nb];
    let ident = &model.placement_identity[..nb];
    let zt = &model.placement_zero_trans[..nb];
    let sub_end = &model.topology.dof_subtree_end[..nv];
    // (PLACED: each joint's dispatch as `data` holds it for the model)
    let keys = if PLACED { &data.dispatch[..nb] } else { &[] };
    let li_m_i = &mut data.li_m_i[..nb];
    let ic = &mut data.crba_ic[..nb];
    ic.copy_from_slice(inertias);
    // Subtree forces F = I^c S per coordinate.
    let fc = &mut data.crba_fc[..nv];
    // a child whose parent is the next body down (p = i − 1) hands its moved
    // composite inertia over in registers (the same sums in the same order, no
    // store read back at once; as the RNEA's backward pass)
    let mut carry = ic[0];
    let mut carry_to = 0;
    let exact = is_f64::<T>();
    for i in bodies.iter().flat_map(|&(b0, b1)| (b0..b1).rev()) {
        let p = parent[i];
        let (head, tail) = ic.split_at_mut(i);
        let mut ici = tail[0];
        if carry_to == i {
            ici.add_assign(&carry);
            // (PLACED, the simulation's: body i's composite inertia is read
            // nowhere after this, not stored back)
            if !PLACED {
                tail[0] = ici;
            }
        }
        carry_to = 0;
        let key = if PLACED {
            keys[i]
        } else {
            dispatch_of(&joints[i])
        };
        let li = dispatch_keyed!(&joints[i], key, ident[i], jm => {
            let li = if PLACED { li_m_i[i] } else { jm.placement(&placements[i], q) };
            let k0 = jm.joint().iv;
            let end = sub_end[k0];
            // F = I^c_i S_i for the joint's own columns (body i's frame)
            for c in 0..jm.nv() {
                fc[k0 + c] = jm.mul_subspace(&ici, c);
            }
            let fsub = &mut fc[k0..end];
            assert!(k0 + jm.nv() <= end && end <= nv, "subtree coordinates out of range");
            let nr = jm.nv();
            // H[k0 + r, c] = S_rᵀ F_c for every coordinate c of the subtree
            // (docs/theory.md §"Joint-force projection"; its mirror H[c, k0 + r])
            sink.begin(k0, end - k0);
            // (a macro, not a closure: inlined at each of its three sweeps)
            macro_rules! project {
                ($dc:expr, $f:expr) => {{
                    let mut vals = [T::zero(); 6];
                    for (r, x) in vals[..nr].iter_mut().enumerate() {
                        *x = jm.project_column(r, $f);
                    }
                    sink.put($dc, &vals[..nr]);
                }};
            }
            // each force projected, then (p ≠ 0) moved to the parent frame,
            // ᵖX̂ᵢ* F, in the same sweep (each force's arithmetic as before)
            let ax = jm.rot_axis();
            if p == 0 {
                for (dc, f) in fsub.iter().enumerate() {
                    project!(dc, f);
                }
            } else {
                // I^c_p += ₚX̂ᵢ* I^c_i ⁱX̂ₚ
                let moved = match ax {
                    // a joint frame at its parent's origin (a body's second and
                    // later joints in MJCF): the moves are rotations alone
                    // (exact: `Model::placement_zero_trans`)
                    Some(ax) if exact && zt[i] => {
                        for (dc, f) in fsub.iter_mut().enumerate() {
                            project!(dc, f);
                            *f = Force {
                                ang: ax.rot_mul(&li.rot, &f.ang),
                                lin: ax.rot_mul(&li.rot, &f.lin),
                            };
                        }
                        ici.rotate_ax(&li.rot, &ax)
                    }
                    _ => {
                        for (dc, f) in fsub.iter_mut().enumerate() {
                            project!(dc, f);
                            *f = act_force_ax(&li, ax, f);
                        }
                        ici.act_ax(&li, ax)
                    }
                };
                if p + 1 == i {
                    (carry, carry_to) = (moved, p);
                } else {
                    head[p].add_assign(&moved);
                }
            }
            li
        });
        // (PLACED: read from there, nothing to store)
        if !PLACED {
            li_m_i[i] = li;
        }
    }
}
