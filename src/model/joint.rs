//! Joint kinds and everything that depends on them, matched in this one place:
//! the joint transform `X_J(q)`, the motion subspace `S` (docs/theory.md §"Joints and
//! motion subspace"), the joint velocity `S q̇`, and the projection `Sᵀ f`
//! (docs/theory.md §"Joint-force projection").

use crate::dynamics::CompositeInertia;
use crate::spatial::ops::{axpy, cross, madd, mat_mat, mat_tr_vec, mat_vec};
use crate::spatial::{axis_angle, quat_to_matrix, sin_cos, Force, Motion, Scalar, Se3};
use nalgebra::{DVector, Matrix3, Matrix6, Vector3, Vector6};

/// A joint axis. Axis-aligned axes (most URDF axes are ±x, ±y, ±z) get their own
/// variants so that the transform and projections are specialised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis<T: Scalar = f64> {
    X,
    Y,
    Z,
    /// Any other unit vector (negative or oblique axes).
    Unit(Vector3<T>),
}

impl<T: Scalar> Axis<T> {
    /// Classifies a unit vector.
    pub fn from_unit(u: Vector3<T>) -> Self {
        let (z, o) = (T::zero(), T::one());
        if u == Vector3::new(o, z, z) {
            Axis::X
        } else if u == Vector3::new(z, o, z) {
            Axis::Y
        } else if u == Vector3::new(z, z, o) {
            Axis::Z
        } else {
            Axis::Unit(u)
        }
    }
    #[inline(always)]
    pub fn vector(&self) -> Vector3<T> {
        match self {
            Axis::X => Vector3::x(),
            Axis::Y => Vector3::y(),
            Axis::Z => Vector3::z(),
            Axis::Unit(u) => *u,
        }
    }
    /// `u · x`.
    #[inline(always)]
    pub fn dot(&self, x: &Vector3<T>) -> T {
        match self {
            Axis::X => x.x,
            Axis::Y => x.y,
            Axis::Z => x.z,
            Axis::Unit(u) => u.dot(x),
        }
    }
    /// The rotation by `q` about this axis.
    #[inline(always)]
    pub fn rotation(&self, q: T) -> Matrix3<T> {
        let (s, c) = sin_cos(q);
        let (z, o) = (T::zero(), T::one());
        match self {
            Axis::X => Matrix3::new(o, z, z, z, c, -s, z, s, c),
            Axis::Y => Matrix3::new(c, z, s, z, o, z, -s, z, c),
            Axis::Z => Matrix3::new(c, -s, z, s, c, z, z, z, o),
            Axis::Unit(u) => axis_angle(u, q),
        }
    }
    /// `m · R(q)` for the rotation by `q = atan2(s, c)` about this axis, without a
    /// full 3x3 product: an axis-aligned rotation mixes two columns of `m`
    /// (12 products instead of 27).
    #[inline(always)]
    pub fn rotate_right(&self, m: &Matrix3<T>, s: T, c: T) -> Matrix3<T> {
        let (c0, c1, c2) = (m.column(0), m.column(1), m.column(2));
        match self {
            Axis::X => Matrix3::from_columns(&[c0.into(), mix(c1, c, c2, s), mix(c2, c, c1, -s)]),
            Axis::Y => Matrix3::from_columns(&[mix(c0, c, c2, -s), c1.into(), mix(c0, s, c2, c)]),
            Axis::Z => Matrix3::from_columns(&[mix(c0, c, c1, s), mix(c1, c, c0, -s), c2.into()]),
            Axis::Unit(u) => {
                let k = crate::spatial::skew(u);
                mat_mat(m, &(Matrix3::identity() + k * s + k * k * (T::one() - c)))
            }
        }
    }
    /// `w × u`, with the zeros of an axis-aligned `u` left out.
    #[inline(always)]
    pub fn cross_from(&self, w: &Vector3<T>) -> Vector3<T> {
        let z = T::zero();
        match self {
            Axis::X => Vector3::new(z, w.z, -w.y),
            Axis::Y => Vector3::new(-w.z, z, w.x),
            Axis::Z => Vector3::new(w.y, -w.x, z),
            Axis::Unit(u) => w.cross(u),
        }
    }
    /// `x += (w × u) s`, touching the two components an axis-aligned `u` leaves
    /// non-zero (no products with zero).
    #[inline(always)]
    pub fn add_cross_scaled(&self, x: &mut Vector3<T>, w: &Vector3<T>, s: T) {
        match self {
            Axis::X => {
                x.y = madd(w.z, s, x.y);
                x.z = madd(-w.y, s, x.z);
            }
            Axis::Y => {
                x.x = madd(-w.z, s, x.x);
                x.z = madd(w.x, s, x.z);
            }
            Axis::Z => {
                x.x = madd(w.y, s, x.x);
                x.y = madd(-w.x, s, x.y);
            }
            Axis::Unit(u) => *x = axpy(x, &cross(w, u), s),
        }
    }
    /// `x += u s`, touching one component for an axis-aligned `u`.
    #[inline(always)]
    pub fn add_scaled(&self, x: &mut Vector3<T>, s: T) {
        match self {
            Axis::X => x.x += s,
            Axis::Y => x.y += s,
            Axis::Z => x.z += s,
            Axis::Unit(u) => *x = axpy(x, u, s),
        }
    }
    /// `R v` for a rotation `R` about this axis (read from `r`): 4 products for an
    /// axis-aligned axis, whose row and column through the axis are those of 1.
    #[inline(always)]
    pub fn rot_mul(&self, r: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self {
            Axis::X => Vector3::new(
                v.x,
                madd(r[(1, 2)], v.z, r[(1, 1)] * v.y),
                madd(r[(2, 2)], v.z, r[(2, 1)] * v.y),
            ),
            Axis::Y => Vector3::new(
                madd(r[(0, 2)], v.z, r[(0, 0)] * v.x),
                v.y,
                madd(r[(2, 2)], v.z, r[(2, 0)] * v.x),
            ),
            Axis::Z => Vector3::new(
                madd(r[(0, 1)], v.y, r[(0, 0)] * v.x),
                madd(r[(1, 1)], v.y, r[(1, 0)] * v.x),
                v.z,
            ),
            Axis::Unit(_) => mat_vec(r, v),
        }
    }
    /// `Rᵀ v` for a rotation `R` about this axis (read from `r`).
    #[inline(always)]
    pub fn rot_tr_mul(&self, r: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self {
            Axis::X => Vector3::new(
                v.x,
                madd(r[(2, 1)], v.z, r[(1, 1)] * v.y),
                madd(r[(2, 2)], v.z, r[(1, 2)] * v.y),
            ),
            Axis::Y => Vector3::new(
                madd(r[(2, 0)], v.z, r[(0, 0)] * v.x),
                v.y,
                madd(r[(2, 2)], v.z, r[(0, 2)] * v.x),
            ),
            Axis::Z => Vector3::new(
                madd(r[(1, 0)], v.y, r[(0, 0)] * v.x),
                madd(r[(1, 1)], v.y, r[(0, 1)] * v.x),
                v.z,
            ),
            Axis::Unit(_) => mat_tr_vec(r, v),
        }
    }
    /// `m R` for a rotation `R` about this axis (read from `r`): two columns of `m`
    /// mixed (12 products instead of 27).
    #[inline(always)]
    pub fn mul_rot(&self, m: &Matrix3<T>, r: &Matrix3<T>) -> Matrix3<T> {
        let (c0, c1, c2) = (m.column(0), m.column(1), m.column(2));
        match self {
            Axis::X => Matrix3::from_columns(&[
                c0.into(),
                mix(c1, r[(1, 1)], c2, r[(2, 1)]),
                mix(c1, r[(1, 2)], c2, r[(2, 2)]),
            ]),
            Axis::Y => Matrix3::from_columns(&[
                mix(c0, r[(0, 0)], c2, r[(2, 0)]),
                c1.into(),
                mix(c0, r[(0, 2)], c2, r[(2, 2)]),
            ]),
            Axis::Z => Matrix3::from_columns(&[
                mix(c0, r[(0, 0)], c1, r[(1, 0)]),
                mix(c0, r[(0, 1)], c1, r[(1, 1)]),
                c2.into(),
            ]),
            Axis::Unit(_) => mat_mat(m, r),
        }
    }
    /// `m · u` for a 3x3 matrix (a column for axis-aligned axes).
    #[inline(always)]
    pub fn mat_mul(&self, m: &Matrix3<T>) -> Vector3<T> {
        match self {
            Axis::X => m.column(0).into(),
            Axis::Y => m.column(1).into(),
            Axis::Z => m.column(2).into(),
            Axis::Unit(u) => mat_vec(m, u),
        }
    }
}

/// `a x + b y` for two columns of a 3x3 matrix (an axis rotation mixing them).
#[inline(always)]
fn mix<T: Scalar>(
    a: nalgebra::MatrixView3x1<'_, T>,
    x: T,
    b: nalgebra::MatrixView3x1<'_, T>,
    y: T,
) -> Vector3<T> {
    Vector3::new(
        madd(b[0], y, a[0] * x),
        madd(b[1], y, a[1] * x),
        madd(b[2], y, a[2] * x),
    )
}

/// The kind of a body's joint to its parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind<T: Scalar = f64> {
    /// 6-DoF free joint (floating base): q = [p; quaternion xyzw] (7), v = [v; ω] in the
    /// body frame (6), as Pinocchio's free flyer.
    Free,
    /// Rotation about an axis through the joint origin: `ŝ = [u; 0]` (docs/theory.md
    /// §"Joints and motion subspace").
    Revolute(Axis<T>),
    /// Translation along an axis: `ŝ = [0; u]` (docs/theory.md §"Joints and motion subspace").
    Prismatic(Axis<T>),
}

/// A body's joint: its kind, where its coordinates live, and how a mimic joint
/// follows its leader. A 1-DoF joint's own coordinate is
/// `q_j = mult · q[iq] + offset` and its velocity `mult · v[iv]` (`mult = 1`,
/// `offset = 0` unless it is a mimic joint, whose `iq`/`iv` are its leader's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint<T: Scalar = f64> {
    pub kind: JointKind<T>,
    pub iq: usize,
    pub iv: usize,
    pub mult: T,
    pub offset: T,
}

impl<T: Scalar> Joint<T> {
    /// Number of velocity coordinates this joint owns (0 for a mimic joint).
    pub fn nv(&self) -> usize {
        match self.kind {
            JointKind::Free => 6,
            _ => 1,
        }
    }
    /// Number of configuration coordinates.
    pub fn nq(&self) -> usize {
        match self.kind {
            JointKind::Free => 7,
            _ => 1,
        }
    }
    /// The joint transform `X_J(q)` (from the body frame to the joint's frame on the parent)
    /// and the joint velocity `v_J = S q̇` (body frame).
    #[inline(always)]
    pub fn calc(&self, q: &DVector<T>, v: Option<&DVector<T>>) -> (Se3<T>, Motion<T>) {
        match self.kind {
            JointKind::Free => {
                let i = self.iq;
                let m = Se3::new(
                    quat_to_matrix(q[i + 3], q[i + 4], q[i + 5], q[i + 6]),
                    Vector3::new(q[i], q[i + 1], q[i + 2]),
                );
                let vj = match v {
                    Some(v) => {
                        let k = self.iv;
                        Motion::new(
                            Vector3::new(v[k + 3], v[k + 4], v[k + 5]),
                            Vector3::new(v[k], v[k + 1], v[k + 2]),
                        )
                    }
                    None => Motion::zero(),
                };
                (m, vj)
            }
            JointKind::Revolute(ax) => {
                let qj = self.mult * q[self.iq] + self.offset;
                let m = Se3::from_rotation(ax.rotation(qj));
                let vj = match v {
                    Some(v) => {
                        Motion::new(ax.vector() * (self.mult * v[self.iv]), Vector3::zeros())
                    }
                    None => Motion::zero(),
                };
                (m, vj)
            }
            JointKind::Prismatic(ax) => {
                let qj = self.mult * q[self.iq] + self.offset;
                let m = Se3::from_translation(ax.vector() * qj);
                let vj = match v {
                    Some(v) => {
                        Motion::new(Vector3::zeros(), ax.vector() * (self.mult * v[self.iv]))
                    }
                    None => Motion::zero(),
                };
                (m, vj)
            }
        }
    }
    /// `S a` for the joint's generalized acceleration (scaled by `mult` for mimic joints).
    #[inline(always)]
    pub fn motion(&self, a: &DVector<T>) -> Motion<T> {
        match self.kind {
            JointKind::Free => {
                let k = self.iv;
                Motion::new(
                    Vector3::new(a[k + 3], a[k + 4], a[k + 5]),
                    Vector3::new(a[k], a[k + 1], a[k + 2]),
                )
            }
            JointKind::Revolute(ax) => {
                Motion::new(ax.vector() * (self.mult * a[self.iv]), Vector3::zeros())
            }
            JointKind::Prismatic(ax) => {
                Motion::new(Vector3::zeros(), ax.vector() * (self.mult * a[self.iv]))
            }
        }
    }
    /// `S` times a unit acceleration of velocity coordinate `k` of this joint.
    #[inline(always)]
    pub fn subspace_column(&self, k: usize) -> Motion<T> {
        let o = T::one();
        match self.kind {
            JointKind::Free => {
                let mut m = Motion::zero();
                if k < 3 {
                    m.lin[k] = o;
                } else {
                    m.ang[k - 3] = o;
                }
                m
            }
            JointKind::Revolute(ax) => Motion::new(ax.vector() * self.mult, Vector3::zeros()),
            JointKind::Prismatic(ax) => Motion::new(Vector3::zeros(), ax.vector() * self.mult),
        }
    }
    /// `Q += Gᵀ Sᵀ f` (docs/theory.md §"Joint-force projection"; a mimic joint adds
    /// `mult · Sᵀ f` to its leader).
    #[inline(always)]
    pub fn project_add(&self, f: &Force<T>, tau: &mut DVector<T>) {
        match self.kind {
            JointKind::Free => {
                let k = self.iv;
                for r in 0..3 {
                    tau[k + r] += f.lin[r];
                    tau[k + 3 + r] += f.ang[r];
                }
            }
            JointKind::Revolute(ax) => tau[self.iv] += self.mult * ax.dot(&f.ang),
            JointKind::Prismatic(ax) => tau[self.iv] += self.mult * ax.dot(&f.lin),
        }
    }
    /// `Sᵀ f` for velocity coordinate `k` of this joint (including `mult`).
    #[inline(always)]
    pub fn project_column(&self, k: usize, f: &Force<T>) -> T {
        match self.kind {
            JointKind::Free => {
                if k < 3 {
                    f.lin[k]
                } else {
                    f.ang[k - 3]
                }
            }
            JointKind::Revolute(ax) => self.mult * ax.dot(&f.ang),
            JointKind::Prismatic(ax) => self.mult * ax.dot(&f.lin),
        }
    }

    /// `λ(i)Mi = X_tree · X_J(q)` (the body's frame in its parent's), specialised per
    /// joint kind: a revolute joint rotates two columns of the placement's rotation
    /// ([`Axis::rotate_right`]) and keeps its translation; a prismatic joint keeps the
    /// rotation and moves the translation along `R u`.
    #[inline(always)]
    pub fn placement_compose(&self, xt: &Se3<T>, q: &DVector<T>) -> Se3<T> {
        match self.kind {
            JointKind::Free => xt.compose(&self.calc(q, None).0),
            JointKind::Revolute(ax) => {
                let (s, c) = sin_cos(self.mult * q[self.iq] + self.offset);
                Se3::new(ax.rotate_right(&xt.rot, s, c), xt.trans)
            }
            JointKind::Prismatic(ax) => {
                let qj = self.mult * q[self.iq] + self.offset;
                Se3::new(xt.rot, xt.trans + ax.mat_mul(&xt.rot) * qj)
            }
        }
    }
    /// The axis of `λ(i)Mi`'s rotation when it is a plain rotation about an
    /// axis-aligned joint axis: a revolute joint whose placement rotation is the
    /// identity (`placement_identity`, decided once at model load). `λ(i)Mi`'s
    /// rotation then has a row and a column of the identity, and [`Axis::rot_mul`],
    /// [`Axis::rot_tr_mul`], [`Axis::mul_rot`] apply it with 4 products a vector.
    #[inline(always)]
    pub fn axis_rotation(&self, placement_identity: bool) -> Option<Axis<T>> {
        match self.kind {
            JointKind::Revolute(ax @ (Axis::X | Axis::Y | Axis::Z)) if placement_identity => {
                Some(ax)
            }
            _ => None,
        }
    }
    /// [`Joint::placement_compose`] given [`Joint::axis_rotation`]: with an axis the
    /// rotation is built from `sin`/`cos` alone (no product with the placement's).
    #[inline(always)]
    pub fn placement_compose_ax(&self, xt: &Se3<T>, ax: Option<Axis<T>>, q: &DVector<T>) -> Se3<T> {
        let Some(ax) = ax else {
            return self.placement_compose(xt, q);
        };
        let (s, c) = sin_cos(self.mult * q[self.iq] + self.offset);
        let (z, o) = (T::zero(), T::one());
        let rot = match ax {
            Axis::X => Matrix3::new(o, z, z, z, c, -s, z, s, c),
            Axis::Y => Matrix3::new(c, z, s, z, o, z, -s, z, c),
            _ => Matrix3::new(c, -s, z, s, c, z, z, z, o),
        };
        Se3::new(rot, xt.trans)
    }
    /// `U = M S` for a 1-DoF joint and a 6x6 angular-first matrix `M` (ABA's
    /// `Uᵢ = Iᵢᴬ Sᵢ`): a column of `M` for an axis-aligned joint.
    #[inline(always)]
    pub fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T> {
        let (off, ax) = match self.kind {
            JointKind::Revolute(ax) => (0, ax),
            JointKind::Prismatic(ax) => (3, ax),
            JointKind::Free => return Vector6::zeros(),
        };
        let col = match ax {
            Axis::X => m.column(off).into(),
            Axis::Y => m.column(off + 1).into(),
            Axis::Z => m.column(off + 2).into(),
            Axis::Unit(u) => m.fixed_columns::<3>(off) * u,
        };
        col * self.mult
    }
    /// `Sᵀ x` for a 1-DoF joint and a 6-vector in angular-first order.
    #[inline(always)]
    pub fn subspace_dot6(&self, x: &Vector6<T>) -> T {
        let (off, ax) = match self.kind {
            JointKind::Revolute(ax) => (0, ax),
            JointKind::Prismatic(ax) => (3, ax),
            JointKind::Free => return T::zero(),
        };
        let d = match ax {
            Axis::X => x[off],
            Axis::Y => x[off + 1],
            Axis::Z => x[off + 2],
            Axis::Unit(u) => u.x * x[off] + u.y * x[off + 1] + u.z * x[off + 2],
        };
        d * self.mult
    }
    /// Column `k` of the motion subspace expressed in frame a, given `aMi` (body i in
    /// a): `ᵃX̂ᵢ Sₖ` (docs/theory.md §"Plücker transforms"); a revolute joint's is
    /// `[w; t × w]` with `w = R u` (a column of R for an axis-aligned joint), a
    /// prismatic joint's `[0; R u]`.
    #[inline(always)]
    pub fn subspace_in(&self, k: usize, m: &Se3<T>) -> Motion<T> {
        match self.kind {
            JointKind::Free => m.act_motion(&self.subspace_column(k)),
            JointKind::Revolute(ax) => {
                let w = ax.mat_mul(&m.rot) * self.mult;
                Motion::new(w, m.trans.cross(&w))
            }
            JointKind::Prismatic(ax) => {
                Motion::new(Vector3::zeros(), ax.mat_mul(&m.rot) * self.mult)
            }
        }
    }
    /// `m += S x` for the joint's coordinates in `x` (velocity or acceleration;
    /// `mult` included), one component per axis-aligned joint.
    #[inline(always)]
    pub fn add_motion(&self, m: &mut Motion<T>, x: &DVector<T>) {
        match self.kind {
            JointKind::Free => *m += self.motion(x),
            JointKind::Revolute(ax) => ax.add_scaled(&mut m.ang, self.mult * x[self.iv]),
            JointKind::Prismatic(ax) => ax.add_scaled(&mut m.lin, self.mult * x[self.iv]),
        }
    }
    /// `v × S q̇` (the velocity-product term of docs/theory.md §"Acceleration
    /// recursion") for body velocity `v`;
    /// `[ω × u; v × u] q̇` for a revolute joint, `[0; ω × u] q̇` for a prismatic one.
    #[inline(always)]
    pub fn cross_motion(&self, vi: &Motion<T>, qd: &DVector<T>) -> Motion<T> {
        match self.kind {
            JointKind::Free => vi.cross(&self.motion(qd)),
            JointKind::Revolute(ax) => {
                let x = self.mult * qd[self.iv];
                Motion::new(ax.cross_from(&vi.ang) * x, ax.cross_from(&vi.lin) * x)
            }
            JointKind::Prismatic(ax) => {
                let x = self.mult * qd[self.iv];
                Motion::new(Vector3::zeros(), ax.cross_from(&vi.ang) * x)
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Joint models: the joint kind matched once per body.
//
// The hot loops (RNEA, CRBA) match a body's joint kind once, in
// [`dispatch_joint!`], and run their body step on one of the zero-sized-axis
// types below; every helper of that step then works on a compile-time axis and
// transform shape, with no further `match` (the `Axis` methods fold on the
// constant axis). This is the one place besides `Joint`'s own methods where joint
// kinds are matched.

/// An axis known at compile time (`AxX`, `AxY`, `AxZ`) or carried as a unit vector
/// (`AxU`): `get` returns the [`Axis`], a constant for the zero-sized ones.
pub(crate) trait AxisOf<T: Scalar>: Copy {
    fn get(&self) -> Axis<T>;
}
#[derive(Clone, Copy)]
pub(crate) struct AxX;
#[derive(Clone, Copy)]
pub(crate) struct AxY;
#[derive(Clone, Copy)]
pub(crate) struct AxZ;
#[derive(Clone, Copy)]
pub(crate) struct AxU<T: Scalar>(pub Vector3<T>);
impl<T: Scalar> AxisOf<T> for AxX {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::X
    }
}
impl<T: Scalar> AxisOf<T> for AxY {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Y
    }
}
impl<T: Scalar> AxisOf<T> for AxZ {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Z
    }
}
impl<T: Scalar> AxisOf<T> for AxU<T> {
    #[inline(always)]
    fn get(&self) -> Axis<T> {
        Axis::Unit(self.0)
    }
}

/// One joint kind with everything the body steps need, specialised at compile time.
/// Velocity-like arguments (`x`, `tau`) are the model's full coordinate vectors.
pub(crate) trait JointModel<T: Scalar>: Copy {
    /// Number of velocity coordinates.
    const NV: usize;
    #[inline(always)]
    fn nv(&self) -> usize {
        Self::NV
    }
    /// The axis of `λ(i)Mi`'s rotation when it is a plain rotation about an
    /// axis-aligned joint axis (as [`Joint::axis_rotation`]), a compile-time
    /// constant for each joint model.
    fn rot_axis(&self) -> Option<Axis<T>>;
    /// `λ(i)Mi = X_tree · X_J(q)` (as [`Joint::placement_compose`]).
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T>;
    /// `oMi = oMλ(i) · λ(i)Mi` for `li` from [`JointModel::placement`]: with a
    /// plain rotation about the joint axis only two columns of `oRλ(i)` mix.
    #[inline(always)]
    fn world_pose(&self, op: &Se3<T>, li: &Se3<T>) -> Se3<T> {
        match self.rot_axis() {
            Some(ax) => Se3::new(ax.mul_rot(&op.rot, &li.rot), op.trans + op.rot * li.trans),
            None => op.compose(li),
        }
    }
    /// `m += S x` (as [`Joint::add_motion`]).
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]);
    /// `m += v × S x` (as [`Joint::cross_motion`]).
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]);
    /// `tau += Gᵀ Sᵀ f` (as [`Joint::project_add`]).
    fn project_add(&self, f: &Force<T>, tau: &mut [T]);
    /// `Sᵀ f` for velocity coordinate `c` of this joint (as [`Joint::project_column`]).
    fn project_column(&self, c: usize, f: &Force<T>) -> T;
    /// Column `c` of the motion subspace in frame a given `aMi` (as [`Joint::subspace_in`]).
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T>;
    /// `Î S` for column `c` of the motion subspace (a column of the 6x6 inertia
    /// for an axis-aligned joint).
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T>;
    /// `U = M S` for a 1-DoF joint and a 6x6 angular-first `M` (as [`Joint::mat6_subspace`]).
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T>;
    /// `Sᵀ x` for a 1-DoF joint and an angular-first 6-vector (as [`Joint::subspace_dot6`]).
    fn subspace_dot6(&self, x: &Vector6<T>) -> T;
    /// `m += S x` for a 1-DoF joint and a scalar `x` (`mult` included).
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T);
    /// The underlying joint (for the generic paths).
    fn joint(&self) -> &Joint<T>;
}

/// [`JointModel::mat6_subspace`] for a 1-DoF joint whose `S` sits in rows `off..off + 3`.
#[inline(always)]
fn mat6_col<T: Scalar>(m: &Matrix6<T>, off: usize, ax: Axis<T>, mult: T) -> Vector6<T> {
    let col: Vector6<T> = match ax {
        Axis::X => m.column(off).into(),
        Axis::Y => m.column(off + 1).into(),
        Axis::Z => m.column(off + 2).into(),
        Axis::Unit(u) => m.fixed_columns::<3>(off) * u,
    };
    col * mult
}
/// [`JointModel::subspace_dot6`] for a 1-DoF joint whose `S` sits in rows `off..off + 3`.
#[inline(always)]
fn dot6<T: Scalar>(x: &Vector6<T>, off: usize, ax: Axis<T>, mult: T) -> T {
    let d = match ax {
        Axis::X => x[off],
        Axis::Y => x[off + 1],
        Axis::Z => x[off + 2],
        Axis::Unit(u) => u.x * x[off] + u.y * x[off + 1] + u.z * x[off + 2],
    };
    d * mult
}

/// A revolute joint about axis `A`; `AXROT`: its placement rotation is the
/// identity (so `λ(i)Mi`'s rotation is a rotation about the axis-aligned `A`).
#[derive(Clone, Copy)]
pub(crate) struct RevoluteJ<'j, T: Scalar, A, const AXROT: bool> {
    pub ax: A,
    pub j: &'j Joint<T>,
}
/// A prismatic joint along axis `A`.
#[derive(Clone, Copy)]
pub(crate) struct PrismaticJ<'j, T: Scalar, A> {
    pub ax: A,
    pub j: &'j Joint<T>,
}
/// The 6-DoF free joint.
#[derive(Clone, Copy)]
pub(crate) struct FreeJ<'j, T: Scalar> {
    pub j: &'j Joint<T>,
}

impl<'j, T: Scalar, A: AxisOf<T>, const AXROT: bool> JointModel<T> for RevoluteJ<'j, T, A, AXROT> {
    const NV: usize = 1;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        if AXROT {
            Some(self.ax.get())
        } else {
            None
        }
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let (s, c) = sin_cos(self.j.mult * q[self.j.iq] + self.j.offset);
        let ax = self.ax.get();
        if AXROT {
            let (z, o) = (T::zero(), T::one());
            let rot = match ax {
                Axis::X => Matrix3::new(o, z, z, z, c, -s, z, s, c),
                Axis::Y => Matrix3::new(c, z, s, z, o, z, -s, z, c),
                _ => Matrix3::new(c, -s, z, s, c, z, z, z, o),
            };
            Se3::new(rot, xt.trans)
        } else {
            Se3::new(ax.rotate_right(&xt.rot, s, c), xt.trans)
        }
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        self.ax
            .get()
            .add_scaled(&mut m.ang, self.j.mult * x[self.j.iv]);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        let ax = self.ax.get();
        let s = self.j.mult * x[self.j.iv];
        ax.add_cross_scaled(&mut m.ang, &vi.ang, s);
        ax.add_cross_scaled(&mut m.lin, &vi.lin, s);
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        tau[self.j.iv] += self.j.mult * self.ax.get().dot(&f.ang);
    }
    #[inline(always)]
    fn project_column(&self, _c: usize, f: &Force<T>) -> T {
        self.j.mult * self.ax.get().dot(&f.ang)
    }
    #[inline(always)]
    fn subspace_in(&self, _c: usize, m: &Se3<T>) -> Motion<T> {
        let w = self.ax.get().mat_mul(&m.rot) * self.j.mult;
        Motion::new(w, m.trans.cross(&w))
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, _c: usize) -> Force<T> {
        let ax = self.ax.get();
        match ax {
            Axis::Unit(u) => ic.mul_motion(&Motion::new(u * self.j.mult, Vector3::zeros())),
            _ => Force {
                ang: ax.mat_mul(&ic.io) * self.j.mult,
                lin: ax.cross_from(&ic.h) * (-self.j.mult),
            },
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T> {
        mat6_col(m, 0, self.ax.get(), self.j.mult)
    }
    #[inline(always)]
    fn subspace_dot6(&self, x: &Vector6<T>) -> T {
        dot6(x, 0, self.ax.get(), self.j.mult)
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T) {
        self.ax.get().add_scaled(&mut m.ang, self.j.mult * x);
    }
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}

impl<'j, T: Scalar, A: AxisOf<T>> JointModel<T> for PrismaticJ<'j, T, A> {
    const NV: usize = 1;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let qj = self.j.mult * q[self.j.iq] + self.j.offset;
        Se3::new(xt.rot, xt.trans + self.ax.get().mat_mul(&xt.rot) * qj)
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        self.ax
            .get()
            .add_scaled(&mut m.lin, self.j.mult * x[self.j.iv]);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        let s = self.j.mult * x[self.j.iv];
        self.ax.get().add_cross_scaled(&mut m.lin, &vi.ang, s);
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        tau[self.j.iv] += self.j.mult * self.ax.get().dot(&f.lin);
    }
    #[inline(always)]
    fn project_column(&self, _c: usize, f: &Force<T>) -> T {
        self.j.mult * self.ax.get().dot(&f.lin)
    }
    #[inline(always)]
    fn subspace_in(&self, _c: usize, m: &Se3<T>) -> Motion<T> {
        Motion::new(
            Vector3::zeros(),
            self.ax.get().mat_mul(&m.rot) * self.j.mult,
        )
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, _c: usize) -> Force<T> {
        let ax = self.ax.get();
        match ax {
            Axis::Unit(u) => ic.mul_motion(&Motion::new(Vector3::zeros(), u * self.j.mult)),
            _ => Force {
                ang: ax.cross_from(&ic.h) * self.j.mult,
                lin: ax.vector() * (ic.m * self.j.mult),
            },
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T> {
        mat6_col(m, 3, self.ax.get(), self.j.mult)
    }
    #[inline(always)]
    fn subspace_dot6(&self, x: &Vector6<T>) -> T {
        dot6(x, 3, self.ax.get(), self.j.mult)
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T) {
        self.ax.get().add_scaled(&mut m.lin, self.j.mult * x);
    }
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}

impl<'j, T: Scalar> FreeJ<'j, T> {
    /// `S x` for the free joint's 6 coordinates of `x` (linear first in `x`).
    #[inline(always)]
    fn motion(&self, x: &[T]) -> Motion<T> {
        let x = &x[self.j.iv..self.j.iv + 6];
        Motion::new(
            Vector3::new(x[3], x[4], x[5]),
            Vector3::new(x[0], x[1], x[2]),
        )
    }
}

impl<'j, T: Scalar> JointModel<T> for FreeJ<'j, T> {
    const NV: usize = 6;
    #[inline(always)]
    fn rot_axis(&self) -> Option<Axis<T>> {
        None
    }
    #[inline(always)]
    fn placement(&self, xt: &Se3<T>, q: &[T]) -> Se3<T> {
        let q = &q[self.j.iq..self.j.iq + 7];
        let m = Se3::new(
            quat_to_matrix(q[3], q[4], q[5], q[6]),
            Vector3::new(q[0], q[1], q[2]),
        );
        xt.compose(&m)
    }
    #[inline(always)]
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]) {
        *m += self.motion(x);
    }
    #[inline(always)]
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]) {
        *m += vi.cross(&self.motion(x));
    }
    #[inline(always)]
    fn project_add(&self, f: &Force<T>, tau: &mut [T]) {
        let t = &mut tau[self.j.iv..self.j.iv + 6];
        for r in 0..3 {
            t[r] += f.lin[r];
            t[3 + r] += f.ang[r];
        }
    }
    #[inline(always)]
    fn project_column(&self, c: usize, f: &Force<T>) -> T {
        // S = 1 up to the order: linear coordinates first.
        if c < 3 {
            f.lin[c]
        } else {
            f.ang[c - 3]
        }
    }
    #[inline(always)]
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T> {
        if c < 3 {
            Motion::new(Vector3::zeros(), m.rot.column(c).into())
        } else {
            let w: Vector3<T> = m.rot.column(c - 3).into();
            Motion::new(w, m.trans.cross(&w))
        }
    }
    #[inline(always)]
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T> {
        // A column of the 6x6 inertia [I_o, h*; h*ᵀ, m 1] (linear coordinates first).
        if c < 3 {
            let ax = [Axis::X, Axis::Y, Axis::Z][c];
            let mut lin = Vector3::zeros();
            lin[c] = ic.m;
            Force::new(ax.cross_from(&ic.h), lin)
        } else {
            let ax = [Axis::X, Axis::Y, Axis::Z][c - 3];
            Force::new(ic.io.column(c - 3).into(), -ax.cross_from(&ic.h))
        }
    }
    #[inline(always)]
    fn mat6_subspace(&self, _m: &Matrix6<T>) -> Vector6<T> {
        Vector6::zeros()
    }
    #[inline(always)]
    fn subspace_dot6(&self, _x: &Vector6<T>) -> T {
        T::zero()
    }
    #[inline(always)]
    fn add_subspace_scaled(&self, _m: &mut Motion<T>, _x: T) {}
    #[inline(always)]
    fn joint(&self) -> &Joint<T> {
        self.j
    }
}

/// Runs `$body` with `$jm` bound to the [`JointModel`] of joint `$joint`
/// (`&Joint<T>`) whose placement rotation is the identity iff `$ident`: the joint
/// kind is matched here, once, and `$body` is compiled once per joint model.
macro_rules! dispatch_joint {
    ($joint:expr, $ident:expr, $jm:ident => $body:expr) => {{
        use $crate::model::joint::{
            AxU, AxX, AxY, AxZ, Axis, FreeJ, JointKind, PrismaticJ, RevoluteJ,
        };
        let j__ = $joint;
        match (&j__.kind, $ident) {
            (JointKind::Revolute(Axis::X), true) => {
                let $jm = RevoluteJ::<_, _, true> { ax: AxX, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::Y), true) => {
                let $jm = RevoluteJ::<_, _, true> { ax: AxY, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::Z), true) => {
                let $jm = RevoluteJ::<_, _, true> { ax: AxZ, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::X), false) => {
                let $jm = RevoluteJ::<_, _, false> { ax: AxX, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::Y), false) => {
                let $jm = RevoluteJ::<_, _, false> { ax: AxY, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::Z), false) => {
                let $jm = RevoluteJ::<_, _, false> { ax: AxZ, j: j__ };
                $body
            }
            (JointKind::Revolute(Axis::Unit(u)), _) => {
                let $jm = RevoluteJ::<_, _, false> {
                    ax: AxU(*u),
                    j: j__,
                };
                $body
            }
            (JointKind::Prismatic(Axis::X), _) => {
                let $jm = PrismaticJ { ax: AxX, j: j__ };
                $body
            }
            (JointKind::Prismatic(Axis::Y), _) => {
                let $jm = PrismaticJ { ax: AxY, j: j__ };
                $body
            }
            (JointKind::Prismatic(Axis::Z), _) => {
                let $jm = PrismaticJ { ax: AxZ, j: j__ };
                $body
            }
            (JointKind::Prismatic(Axis::Unit(u)), _) => {
                let $jm = PrismaticJ {
                    ax: AxU(*u),
                    j: j__,
                };
                $body
            }
            (JointKind::Free, _) => {
                let $jm = FreeJ { j: j__ };
                $body
            }
        }
    }};
}
pub(crate) use dispatch_joint;
