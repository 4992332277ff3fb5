//! Joint kinds and everything that depends on them: the joint transform `X_J(q)`,
//! the motion subspace `S` (docs/theory.md §"Joints and motion subspace"), the
//! joint velocity `S q̇` and the projection `Sᵀ f` (docs/theory.md §"Joint-force
//! projection"). One file a joint kind (`revolute.rs`, `prismatic.rs`, `free.rs`,
//! `spherical.rs`, `planar.rs`),
//! each implementing [`JointModel`]; the kind is matched in one place,
//! [`dispatch_joint!`], and [`Joint`]'s methods run the same implementations.
//!
//! The hot loops (RNEA, CRBA, ABA) match a body's joint kind once, in
//! [`dispatch_joint!`], and run their body step on one of the joint models with a
//! compile-time axis (`AxisOf` in src/spatial/axis.rs): every helper of that step then works on a
//! constant axis and transform shape, with no further `match`.

mod free;
mod planar;
mod prismatic;
mod revolute;
mod spherical;

pub use crate::spatial::Axis;
pub(crate) use crate::spatial::{AxU, AxX, AxY, AxZ};
pub(crate) use free::FreeJ;
pub(crate) use planar::PlanarJ;
pub(crate) use prismatic::PrismaticJ;
pub(crate) use revolute::RevoluteJ;
pub(crate) use spherical::SphericalJ;

use crate::spatial::{CompositeInertia, Force, Motion, Scalar, Se3};
use nalgebra::{DVector, Matrix6, Vector3, Vector6};

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
    /// 3-DoF ball joint: q = unit quaternion xyzw (4), v = ω in the body frame (3),
    /// as Pinocchio's `JointModelSpherical`.
    Spherical,
    /// 3-DoF planar joint in the joint frame's xy plane: q = [x, y, θ], v = [vx, vy, ω]
    /// in the body frame, as Pinocchio's `JointModelPlanar` (another plane is folded
    /// into the placement at import).
    Planar,
}

impl<T: Scalar> JointKind<T> {
    /// Number of configuration coordinates (7 free, 4 spherical, 3 planar, else 1).
    pub fn nq(&self) -> usize {
        match self {
            JointKind::Free => 7,
            JointKind::Spherical => 4,
            JointKind::Planar => 3,
            _ => 1,
        }
    }
    /// Number of velocity coordinates (6 free, 3 spherical and planar, else 1).
    pub fn nv(&self) -> usize {
        match self {
            JointKind::Free => 6,
            JointKind::Spherical | JointKind::Planar => 3,
            _ => 1,
        }
    }
    /// The kind's name as URDF writes it: `floating`, `spherical`, `planar`,
    /// `revolute`, `prismatic`.
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Free => "floating",
            JointKind::Spherical => "spherical",
            JointKind::Planar => "planar",
            JointKind::Revolute(_) => "revolute",
            JointKind::Prismatic(_) => "prismatic",
        }
    }
}

/// A body's joint: its kind, where its coordinates live, and how a mimic joint
/// follows its leader. A 1-DoF joint's own coordinate is
/// `q_j = mult · q[iq] + offset` and its velocity `mult · v[iv]` (`mult = 1`,
/// `offset = 0` unless it is a mimic joint, whose `iq`/`iv` are its leader's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint<T: Scalar = f64> {
    /// The joint's kind (free, revolute, prismatic) and axis.
    pub kind: JointKind<T>,
    /// Index of its (leader's) first configuration coordinate in q.
    pub iq: usize,
    /// Index of its (leader's) first velocity coordinate in v.
    pub iv: usize,
    /// Mimic multiplier (1 for an ordinary joint).
    pub mult: T,
    /// Mimic offset, plus any rotation folded in from the placement (0 otherwise).
    pub offset: T,
}

impl<T: Scalar> Joint<T> {
    // Every operation below runs the joint model's own (the one the dynamics'
    // hot loops use), so each exists once, in revolute.rs, prismatic.rs, free.rs.

    /// Number of velocity coordinates this joint moves (1; 3 spherical, planar; 6 free).
    #[inline(always)]
    pub fn nv(&self) -> usize {
        dispatch_joint!(self, false, jm => jm.nv())
    }
    /// Number of configuration coordinates (1; 4 spherical; 3 planar; 7 free).
    #[inline(always)]
    pub fn nq(&self) -> usize {
        self.kind.nq()
    }
    /// The joint transform `X_J(q)` (from the body frame to the joint's frame on the
    /// parent) and the joint velocity `v_J = S q̇` (body frame), docs/theory.md
    /// §"Joints and motion subspace".
    #[inline(always)]
    pub fn calc(&self, q: &DVector<T>, v: Option<&DVector<T>>) -> (Se3<T>, Motion<T>) {
        dispatch_joint!(self, false, jm => {
            let x = jm.placement(&Se3::identity(), q.as_slice());
            let mut vj = Motion::zero();
            if let Some(v) = v {
                jm.add_motion(&mut vj, v.as_slice());
            }
            (x, vj)
        })
    }
    /// `S` times a unit acceleration of velocity coordinate `k` of this joint
    /// (`mult` included).
    #[inline(always)]
    pub fn subspace_column(&self, k: usize) -> Motion<T> {
        dispatch_joint!(self, false, jm => jm.subspace(k))
    }
    /// `Sᵀ f` for velocity coordinate `k` of this joint (`mult` included),
    /// docs/theory.md §"Joint-force projection".
    #[inline(always)]
    pub fn project_column(&self, k: usize, f: &Force<T>) -> T {
        dispatch_joint!(self, false, jm => jm.project_column(k, f))
    }
    /// `m += S x` for the joint's coordinates in `x` (velocity or acceleration;
    /// `mult` included).
    #[inline(always)]
    pub fn add_motion(&self, m: &mut Motion<T>, x: &DVector<T>) {
        dispatch_joint!(self, false, jm => jm.add_motion(m, x.as_slice()))
    }
    /// The axis of `λ(i)Mi`'s rotation when it is a plain rotation about an
    /// axis-aligned joint axis: a revolute joint whose placement rotation is the
    /// identity (`placement_identity`, decided once at model load). `λ(i)Mi`'s
    /// rotation then has a row and a column of the identity, and [`Axis::rot_mul`],
    /// [`Axis::rot_tr_mul`], [`Axis::mul_rot`] apply it with 4 products a vector.
    #[inline(always)]
    pub fn axis_rotation(&self, placement_identity: bool) -> Option<Axis<T>> {
        dispatch_joint!(self, placement_identity, jm => jm.rot_axis())
    }
    /// `λ(i)Mi = X_tree · X_J(q)` given [`Joint::axis_rotation`]: with an axis the
    /// rotation is built from `sin`/`cos` alone (no product with the placement's).
    #[inline(always)]
    pub fn placement_compose_ax(&self, xt: &Se3<T>, ax: Option<Axis<T>>, q: &DVector<T>) -> Se3<T> {
        dispatch_joint!(self, ax.is_some(), jm => jm.placement(xt, q.as_slice()))
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
    /// axis-aligned joint axis, a compile-time
    /// constant for each joint model.
    fn rot_axis(&self) -> Option<Axis<T>>;
    /// `λ(i)Mi = X_tree · X_J(q)`.
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
    /// `m += S x`.
    fn add_motion(&self, m: &mut Motion<T>, x: &[T]);
    /// `m += v × S x`.
    fn add_cross_motion(&self, m: &mut Motion<T>, vi: &Motion<T>, x: &[T]);
    /// `tau += Gᵀ Sᵀ f`.
    fn project_add(&self, f: &Force<T>, tau: &mut [T]);
    /// `Sᵀ f` for velocity coordinate `c` of this joint.
    fn project_column(&self, c: usize, f: &Force<T>) -> T;
    /// Column `c` of the motion subspace `S` in the body frame (`mult` included).
    fn subspace(&self, c: usize) -> Motion<T>;
    /// Column `c` of the motion subspace in frame a given `aMi`: `ᵃX̂ᵢ Sₖ`
    /// (docs/theory.md §"Plücker transforms").
    fn subspace_in(&self, c: usize, m: &Se3<T>) -> Motion<T>;
    /// `Î S` for column `c` of the motion subspace (a column of the 6x6 inertia
    /// for an axis-aligned joint).
    fn mul_subspace(&self, ic: &CompositeInertia<T>, c: usize) -> Force<T>;
    /// `U = M S` for a 1-DoF joint and a 6x6 angular-first `M`.
    fn mat6_subspace(&self, m: &Matrix6<T>) -> Vector6<T>;
    /// `Sᵀ x` for a 1-DoF joint and an angular-first 6-vector.
    fn subspace_dot6(&self, x: &Vector6<T>) -> T;
    /// `m += S x` for a 1-DoF joint and a scalar `x` (`mult` included).
    fn add_subspace_scaled(&self, m: &mut Motion<T>, x: T);
    /// For a 3-DoF joint whose `S` selects three entries of an angular-first
    /// 6-vector (spherical: ω; planar: vx, vy, ω_z): those entries, column by column.
    #[inline(always)]
    fn subspace_rows(&self) -> [usize; 3] {
        [0, 1, 2]
    }
    /// The underlying joint (for the generic paths).
    fn joint(&self) -> &Joint<T>;
}

/// [`JointModel::mat6_subspace`] for a 1-DoF joint whose `S` sits in rows `off..off + 3`.
#[inline(always)]
pub(super) fn mat6_col<T: Scalar>(m: &Matrix6<T>, off: usize, ax: Axis<T>, mult: T) -> Vector6<T> {
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
pub(super) fn dot6<T: Scalar>(x: &Vector6<T>, off: usize, ax: Axis<T>, mult: T) -> T {
    let d = match ax {
        Axis::X => x[off],
        Axis::Y => x[off + 1],
        Axis::Z => x[off + 2],
        Axis::Unit(u) => u.x * x[off] + u.y * x[off + 1] + u.z * x[off + 2],
    };
    d * mult
}

/// How [`dispatch_joint!`] runs a joint: its kind and axis, a negative
/// coordinate axis `−eₖ` (MJCF's `axis="0 -1 0"`, a URDF's `<axis xyz="0 -1
/// 0"/>`) folded onto `+eₖ`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Dispatch<T: Scalar> {
    RevX,
    RevY,
    RevZ,
    RevU(Vector3<T>),
    PriX,
    PriY,
    PriZ,
    PriU(Vector3<T>),
    Free,
    Spherical,
    Planar,
}

/// The joint's [`Dispatch`] and the `(mult, offset)` its 1-DoF joint model runs
/// with: a joint about or along `−eₖ` runs as the same joint on `+eₖ` with its
/// coordinate negated, `q_j = mult·q + offset` about `−eₖ` being
/// `−q_j = (−mult)·q + (−offset)` about `eₖ` (the same transform, and
/// `S = −eₖ·mult` the same column), so the body steps take the coordinate-axis
/// paths (docs/theory.md §"Joints and motion subspace").
#[inline(always)]
pub(crate) fn dispatch_of<T: Scalar>(j: &Joint<T>) -> (Dispatch<T>, T, T) {
    let (z, m) = (T::zero(), -T::one());
    // the coordinate axis of a unit axis −eₖ (0, 1, 2), else 3
    let negative = |u: &Vector3<T>| {
        if u.x == m && u.y == z && u.z == z {
            0
        } else if u.x == z && u.y == m && u.z == z {
            1
        } else if u.x == z && u.y == z && u.z == m {
            2
        } else {
            3
        }
    };
    let (key, neg) = match &j.kind {
        JointKind::Revolute(Axis::X) => (Dispatch::RevX, false),
        JointKind::Revolute(Axis::Y) => (Dispatch::RevY, false),
        JointKind::Revolute(Axis::Z) => (Dispatch::RevZ, false),
        JointKind::Revolute(Axis::Unit(u)) => match negative(u) {
            0 => (Dispatch::RevX, true),
            1 => (Dispatch::RevY, true),
            2 => (Dispatch::RevZ, true),
            _ => (Dispatch::RevU(*u), false),
        },
        JointKind::Prismatic(Axis::X) => (Dispatch::PriX, false),
        JointKind::Prismatic(Axis::Y) => (Dispatch::PriY, false),
        JointKind::Prismatic(Axis::Z) => (Dispatch::PriZ, false),
        JointKind::Prismatic(Axis::Unit(u)) => match negative(u) {
            0 => (Dispatch::PriX, true),
            1 => (Dispatch::PriY, true),
            2 => (Dispatch::PriZ, true),
            _ => (Dispatch::PriU(*u), false),
        },
        JointKind::Free => (Dispatch::Free, false),
        JointKind::Spherical => (Dispatch::Spherical, false),
        JointKind::Planar => (Dispatch::Planar, false),
    };
    if neg {
        (key, -j.mult, -j.offset)
    } else {
        (key, j.mult, j.offset)
    }
}

/// Runs `$body` with `$jm` bound to the [`JointModel`] of joint `$joint`
/// (`&Joint<T>`) whose placement rotation is the identity iff `$ident`: the joint
/// kind is matched here, once, and `$body` is compiled once per joint model.
macro_rules! dispatch_joint {
    ($joint:expr, $ident:expr, $jm:ident => $body:expr) => {{
        // the kind matched once (a negative coordinate axis folded onto the
        // positive one, `dispatch_of`)
        let jd__ = $joint;
        $crate::model::joint::dispatch_keyed!(
            jd__,
            $crate::model::joint::dispatch_of(jd__),
            $ident,
            $jm => $body
        )
    }};
}
pub(crate) use dispatch_joint;

/// [`dispatch_joint!`] with the joint's `dispatch_of` already known (`$key`,
/// e.g. [`crate::model::Data`]'s per-body copy made once for its model).
macro_rules! dispatch_keyed {
    ($joint:expr, $key:expr, $ident:expr, $jm:ident => $body:expr) => {{
        use $crate::model::joint::{
            AxU, AxX, AxY, AxZ, Dispatch, FreeJ, PlanarJ, PrismaticJ, RevoluteJ, SphericalJ,
        };
        let j__ = $joint;
        let (key__, mult__, off__) = $key;
        match (key__, $ident) {
            (Dispatch::RevX, true) => {
                let $jm = RevoluteJ::<_, _, true> {
                    ax: AxX,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevY, true) => {
                let $jm = RevoluteJ::<_, _, true> {
                    ax: AxY,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevZ, true) => {
                let $jm = RevoluteJ::<_, _, true> {
                    ax: AxZ,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevX, false) => {
                let $jm = RevoluteJ::<_, _, false> {
                    ax: AxX,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevY, false) => {
                let $jm = RevoluteJ::<_, _, false> {
                    ax: AxY,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevZ, false) => {
                let $jm = RevoluteJ::<_, _, false> {
                    ax: AxZ,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::RevU(u), _) => {
                let $jm = RevoluteJ::<_, _, false> {
                    ax: AxU(u),
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::PriX, _) => {
                let $jm = PrismaticJ {
                    ax: AxX,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::PriY, _) => {
                let $jm = PrismaticJ {
                    ax: AxY,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::PriZ, _) => {
                let $jm = PrismaticJ {
                    ax: AxZ,
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::PriU(u), _) => {
                let $jm = PrismaticJ {
                    ax: AxU(u),
                    j: j__,
                    mult: mult__,
                    offset: off__,
                };
                $body
            }
            (Dispatch::Free, _) => {
                let $jm = FreeJ { j: j__ };
                $body
            }
            (Dispatch::Spherical, _) => {
                let $jm = SphericalJ { j: j__ };
                $body
            }
            (Dispatch::Planar, _) => {
                let $jm = PlanarJ { j: j__ };
                $body
            }
        }
    }};
}
pub(crate) use dispatch_keyed;
