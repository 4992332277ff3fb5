//! Spatial inertias in origin form, the form composite bodies add in
//! (docs/theory.md §"Spatial inertia", §"Composite-rigid-body algorithm").

use super::ops::{add_cross, axpy, dot, dot3, madd, mat_mat, mat_vec};
use super::{Axis, Force, Inertia, Motion, Scalar, Se3};
use nalgebra::{Matrix3, Vector3};

/// A spatial inertia in "origin form": mass `m`, first moment `h = m c` and the
/// rotational inertia `I_o = I_c − m c*c*` about the frame origin. Sums of such
/// inertias (composite bodies) are plain sums of the three parts, which is why the
/// CRBA keeps its composite inertias this way. As a 6x6 matrix
/// (angular first, docs/theory.md §"Spatial inertia") it is `[I_o, h*; h*ᵀ, m 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompositeInertia<T: Scalar = f64> {
    /// Mass `m`.
    pub m: T,
    /// First moment of mass `h = m c` about the frame origin.
    pub h: Vector3<T>,
    /// Rotational inertia `I_o` about the frame origin.
    pub io: Matrix3<T>,
}

impl<T: Scalar> CompositeInertia<T> {
    /// The zero inertia (no mass).
    #[inline(always)]
    pub fn zero() -> Self {
        Self {
            m: T::zero(),
            h: Vector3::zeros(),
            io: Matrix3::zeros(),
        }
    }
    /// From mass, centre of mass and central inertia (parallel-axis theorem,
    /// `I_o = I_c + m (|c|² 1 − c cᵀ)`, written out on the 6 distinct entries).
    #[inline(always)]
    pub fn from_inertia(i: &Inertia<T>) -> Self {
        let m = i.mass;
        let c = i.com;
        let h = c * m;
        let (hx, hy, hz) = (h.x, h.y, h.z);
        let ic = &i.inertia_c;
        let xx = madd(hz, c.z, madd(hy, c.y, ic[(0, 0)]));
        let yy = madd(hz, c.z, madd(hx, c.x, ic[(1, 1)]));
        let zz = madd(hy, c.y, madd(hx, c.x, ic[(2, 2)]));
        let xy = madd(-hx, c.y, ic[(0, 1)]);
        let xz = madd(-hx, c.z, ic[(0, 2)]);
        let yz = madd(-hy, c.z, ic[(1, 2)]);
        Self {
            m,
            h,
            io: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
        }
    }
    /// `Î v = [I_o ω + h × v; m v − h × ω]` for `v = [ω; v]`.
    #[inline(always)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        Force {
            ang: add_cross(&mat_vec(&self.io, &v.ang), &self.h, &v.lin),
            lin: add_cross(&(v.lin * self.m), &v.ang, &self.h),
        }
    }
    /// Adds another inertia in the same frame (a composite body).
    #[inline(always)]
    pub fn add_assign(&mut self, o: &Self) {
        self.m += o.m;
        self.h += o.h;
        self.io += o.io;
    }
    /// The inertia expressed in frame a, given `aMb` (this inertia in b):
    /// `m' = m`, `h' = R h + m t`,
    /// `I_o' = R I_o Rᵀ − (Rh)*t* − t*h'*` (points move as `p ↦ R p + t` in
    /// `I_o = −Σ mₖ pₖ* pₖ*`), using `a*b* = b aᵀ − (a·b) 1`.
    /// [`CompositeInertia::act`] for `x` whose rotation is a rotation about `ax`
    /// (`Joint::axis_rotation` in the model): `R I_o Rᵀ` mixes two rows and
    /// two columns (24 products instead of 45).
    #[inline(always)]
    pub fn act_ax(&self, x: &Se3<T>, ax: Option<Axis<T>>) -> Self {
        let Some(ax) = ax else {
            return self.act(x);
        };
        let rot = self.rotate_ax(&x.rot, &ax);
        let e = &rot.io;
        let io = [
            e[(0, 0)],
            e[(1, 1)],
            e[(2, 2)],
            e[(0, 1)],
            e[(0, 2)],
            e[(1, 2)],
        ];
        Self::shifted(self.m, rot.h, io, &x.trans)
    }

    /// The inertia turned by `r`, a rotation about `ax`, with no translation:
    /// `m' = m`, `h' = R h`, `I_o' = R I_o Rᵀ` (two rows and two columns mixed;
    /// [`CompositeInertia::act_ax`] is this followed by the translation's shift).
    #[inline(always)]
    pub fn rotate_ax(&self, r: &Matrix3<T>, ax: &Axis<T>) -> Self {
        let h = ax.rot_mul(r, &self.h);
        // M = R I_o by columns; R I_o Rᵀ = R Mᵀ (I_o symmetric), by columns.
        let io = &self.io;
        let m0 = ax.rot_mul(r, &io.column(0).into());
        let m1 = ax.rot_mul(r, &io.column(1).into());
        let m2 = ax.rot_mul(r, &io.column(2).into());
        let e0 = ax.rot_mul(r, &Vector3::new(m0.x, m1.x, m2.x));
        let e1 = ax.rot_mul(r, &Vector3::new(m0.y, m1.y, m2.y));
        let e2 = ax.rot_mul(r, &Vector3::new(m0.z, m1.z, m2.z));
        // column j of R I_o Rᵀ is e_j; entry (i, j) = e_j[i]
        let (xx, yy, zz, xy, xz, yz) = (e0.x, e1.y, e2.z, e1.x, e2.x, e2.y);
        Self {
            m: self.m,
            h,
            io: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
        }
    }
    /// The inertia expressed in frame a, given `aMb` (this inertia in b), for any
    /// rotation (see [`CompositeInertia::act_ax`] for the formula).
    #[inline(always)]
    pub fn act(&self, x: &Se3<T>) -> Self {
        let r = &x.rot;
        let rh = mat_vec(r, &self.h);
        // R I_o Rᵀ on the 6 distinct entries: M = R I_o, then rows of M · rows of R.
        let mm = mat_mat(r, &self.io);
        let e = |i: usize, j: usize| {
            dot3(
                mm[(i, 0)],
                mm[(i, 1)],
                mm[(i, 2)],
                r[(j, 0)],
                r[(j, 1)],
                r[(j, 2)],
            )
        };
        let io = [e(0, 0), e(1, 1), e(2, 2), e(0, 1), e(0, 2), e(1, 2)];
        Self::shifted(self.m, rh, io, &x.trans)
    }

    /// The translation by `t` that [`CompositeInertia::act`] and
    /// [`CompositeInertia::act_ax`] end with, from the rotated inertia's
    /// `rh = R h` and `R I_o Rᵀ` entries `[xx, yy, zz, xy, xz, yz]`:
    /// `h' = rh + m t`, `I_o'` as [`shift_entries`].
    #[inline(always)]
    fn shifted(m: T, rh: Vector3<T>, io: [T; 6], t: &Vector3<T>) -> Self {
        let h2 = axpy(&rh, t, m);
        let [xx, yy, zz, xy, xz, yz] = io;
        let (xx, yy, zz, xy, xz, yz) = shift_entries(xx, yy, zz, xy, xz, yz, t, &rh, &h2);
        Self {
            m,
            h: h2,
            io: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
        }
    }
}

/// The translation part of [`CompositeInertia::act`]: from the rotated `R I_o Rᵀ`
/// entries (xx, yy, zz, xy, xz, yz), `− t rhᵀ − h2 tᵀ + (rh·t + t·h2) 1` added
/// (`rh = R h`, `h2 = rh + m t`; the two outer products sum to a symmetric matrix).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn shift_entries<T: Scalar>(
    xx: T,
    yy: T,
    zz: T,
    xy: T,
    xz: T,
    yz: T,
    t: &Vector3<T>,
    rh: &Vector3<T>,
    h2: &Vector3<T>,
) -> (T, T, T, T, T, T) {
    let s = madd(t.z, h2.z, madd(t.y, h2.y, madd(t.x, h2.x, dot(rh, t))));
    // entry − (t[i] rh[j] + h2[i] t[j])
    let g = |e: T, i: usize, j: usize| madd(-h2[i], t[j], madd(-t[i], rh[j], e));
    (
        g(xx, 0, 0) + s,
        g(yy, 1, 1) + s,
        g(zz, 2, 2) + s,
        g(xy, 0, 1),
        g(xz, 0, 2),
        g(yz, 1, 2),
    )
}
