//! The constants `assemble` reads each step, made once at construction: the
//! 1-DoF joints that may have rows, and each body's joint subspace columns in
//! its body frame with which of their parts are zero.

use crate::model::Model;
use crate::spatial::ops::{add_cross, mat_vec};
use crate::spatial::{Motion, Se3};
use nalgebra::{Matrix3, Vector3};

/// Adds one body's entries to a contact's three rows `j` (the path's
/// entries, `on_path` its dofs, ascending as every row path is, see
/// `Rows::union_path`): `row(vp)` for the point velocity vp at `p` of each of
/// the body's world columns `sw` (`bc`: the body-frame ones, which have no
/// angular part). `hi`: where the dofs of the body walked before, a
/// descendant, begin (the path's length for the first): the body's lie
/// before, back to back at its end on a body's own path to the root (tried
/// first; else found by bisection). Returns where the body's first dof lies
/// (its ancestors' lie before). Back to back (checked at both ends: the path
/// ascends), the entries are written in place, one bounds test a row; else
/// each is looked up.
#[inline(always)]
pub(super) fn add_body(
    j: [&mut [f64]; 3],
    on_path: &[usize],
    hi: usize,
    bc: &BodyHead,
    sw: &[Motion; 6],
    p: &Vector3<f64>,
    row: impl Fn(Vector3<f64>) -> [f64; 3],
) -> usize {
    let (iv, nv) = (bc.iv, bc.nv.min(6));
    let Some(last) = nv.checked_sub(1) else {
        return hi;
    };
    let guess = hi.wrapping_sub(nv);
    let t0 = match on_path.get(guess) {
        Some(&d) if d == iv => guess,
        _ => on_path.partition_point(|&d| d < iv),
    };
    let cols = bc.ang_zero.iter().zip(sw).take(nv);
    let [j0, j1, j2] = j;
    if on_path.get(t0 + last) == Some(&(iv + last))
        && on_path.get(t0) == Some(&iv)
        && let (Some(r0), Some(r1), Some(r2)) = (
            j0.get_mut(t0..t0 + nv),
            j1.get_mut(t0..t0 + nv),
            j2.get_mut(t0..t0 + nv),
        )
    {
        for ((((&az, s), x0), x1), x2) in cols.zip(r0).zip(r1).zip(r2) {
            let [a, b, e] = row(point_velocity(s, az, p));
            *x0 += a;
            *x1 += b;
            *x2 += e;
        }
        return t0;
    }
    for (k, (&az, s)) in cols.enumerate() {
        let col = iv + k;
        let t = on_path.partition_point(|&d| d < col);
        if on_path.get(t) == Some(&col)
            && let (Some(x0), Some(x1), Some(x2)) = (j0.get_mut(t), j1.get_mut(t), j2.get_mut(t))
        {
            let [a, b, e] = row(point_velocity(s, az, p));
            *x0 += a;
            *x1 += b;
            *x2 += e;
        }
    }
    t0
}

/// [`add_body`] for a body of the world columns `cols` (≤ 6: their own
/// body-frame ones) from dof `iv`, onto three zeroed rows as long as `path`
/// (the tests' hook, `urdyn::testing::constraints`).
pub(crate) fn add_body_rows(
    path: &[usize],
    hi: usize,
    iv: usize,
    cols: &[Motion],
    p: &Vector3<f64>,
    row: &dyn Fn(Vector3<f64>) -> [f64; 3],
) -> ([Vec<f64>; 3], usize) {
    let mut bc = BodyColumns {
        s: [Column::of(Motion::zero()); 6],
        nv: cols.len().min(6),
        iv,
        identity: false,
    };
    let mut sw = [Motion::zero(); 6];
    for ((c, w), &s) in bc.s.iter_mut().zip(&mut sw).zip(cols) {
        *c = Column::of(s);
        *w = s;
    }
    let mut j = [
        vec![0.0; path.len()],
        vec![0.0; path.len()],
        vec![0.0; path.len()],
    ];
    let [a, b, c] = &mut j;
    let t0 = add_body([a, b, c], path, hi, &BodyHead::of(&bc), &sw, p, row);
    (j, t0)
}

/// The point velocity `s.lin + s.ang × p` of world column `s`: a column
/// with no angular part (`ang_zero`: [`act_column`] left it +0) is `s.lin`,
/// the same values for a finite p but for the sign of a zero, which no row
/// keeps (J's entries are sums onto the +0 that `Rows::clear` left).
#[inline(always)]
fn point_velocity(s: &Motion, ang_zero: bool, p: &Vector3<f64>) -> Vector3<f64> {
    if ang_zero {
        s.lin
    } else {
        s.lin + s.ang.cross(p)
    }
}

/// What a 1-DoF joint's rows are built from (its [`crate::model::DofInfo`]'s
/// fields, copied once: the row loop reads these few, not every dof's whole entry).
#[derive(Clone, Copy, Debug)]
pub(super) struct JointRowSource {
    /// The dof's index in `model.dofs`.
    pub(super) d: usize,
    pub(super) iq: usize,
    pub(super) iv: usize,
    pub(super) friction: f64,
    pub(super) continuous: bool,
    pub(super) lower: Option<f64>,
    pub(super) upper: Option<f64>,
}

impl JointRowSource {
    /// The model's 1-DoF joints with friction or a position limit (the others
    /// never have a row), in dof order.
    pub(super) fn of(model: &Model) -> Vec<Self> {
        let mut out = Vec::new();
        for (d, info) in model.dofs.iter().enumerate() {
            if info.kind.nv() != 1 {
                continue;
            }
            let js = Self {
                d,
                iq: info.iq,
                iv: info.iv,
                friction: info.friction,
                continuous: info.continuous,
                lower: info.limits.lower,
                upper: info.limits.upper,
            };
            let limited = !js.continuous && (js.lower.is_some() || js.upper.is_some());
            if js.friction > 0.0 || limited {
                out.push(js);
            }
        }
        out
    }
}

/// A body's joint's motion subspace columns in the body frame
/// ([`crate::model::Joint::subspace_column`]), `nv` of them (none for the world).
#[derive(Clone, Copy, Debug)]
pub(super) struct BodyColumns {
    pub(super) s: [Column; 6],
    pub(super) nv: usize,
    /// The joint's first velocity coordinate.
    pub(super) iv: usize,
    /// The columns are S = 1, linear first (a free joint's): column k is
    /// (lin e_k, 0) for k < 3, (0, e_{k−3}) after ([`BodyColumns::world`]).
    pub(super) identity: bool,
}

/// What [`add_body`] reads of a body's joint besides its world columns: its
/// first velocity coordinate, its column count and which columns have no
/// angular part ([`BodyColumns`]' own, copied: one small entry a body, so a
/// contact's walk touches one cache line of it, not the six columns').
#[derive(Clone, Copy, Debug)]
pub(super) struct BodyHead {
    pub(super) iv: usize,
    pub(super) nv: usize,
    pub(super) ang_zero: [bool; 6],
    /// A root body (its parent the world) of six columns, the first three
    /// with no angular part and the last three with one (a free joint's):
    /// its contacts' entries are written by `free.rs`, not [`add_body`].
    pub(super) free: bool,
}

impl BodyHead {
    /// `c`'s head (`free` as if a root body's: the caller clears it for others).
    pub(super) fn of(c: &BodyColumns) -> Self {
        let ang_zero = c.s.map(|x| x.ang_zero);
        Self {
            iv: c.iv,
            nv: c.nv,
            ang_zero,
            free: c.nv == 6 && ang_zero == [true, true, true, false, false, false],
        }
    }
}

/// One subspace column, which of its parts are zero and which are a unit
/// axis.
#[derive(Clone, Copy, Debug)]
pub(super) struct Column {
    pub(super) s: Motion,
    pub(super) ang_zero: bool,
    pub(super) lin_zero: bool,
    /// k where the angular part is exactly the unit axis e_k.
    pub(super) ang_unit: Option<u8>,
    /// k where the linear part is exactly the unit axis e_k.
    pub(super) lin_unit: Option<u8>,
}

impl Column {
    /// Column `s`, its zero parts marked (exactly zero vectors), and its
    /// unit-axis parts (every column of a free joint's, S = 1).
    #[inline]
    pub(super) fn of(s: Motion) -> Self {
        Column {
            s,
            ang_zero: s.ang == Vector3::zeros(),
            lin_zero: s.lin == Vector3::zeros(),
            ang_unit: unit_axis(&s.ang),
            lin_unit: unit_axis(&s.lin),
        }
    }
}

/// k where `x` is exactly the unit axis e_k.
fn unit_axis(x: &Vector3<f64>) -> Option<u8> {
    (0..3u8).find(|&k| *x == Vector3::ith(usize::from(k), 1.0))
}

/// `R x` for a column part `x` of [`Column`]: the column k of `R` where `x`
/// is the unit axis e_k (`unit`), else [`mat_vec`]. The same values but for
/// the sign of a zero (the products by 0 and 1 are exact for a finite R:
/// each entry of R e_k is (±0 ± 0) + r, r itself unless r is a zero).
#[inline(always)]
fn rotate(r: &Matrix3<f64>, x: &Vector3<f64>, unit: Option<u8>) -> Vector3<f64> {
    match unit {
        Some(k) => {
            let k = usize::from(k.min(2));
            Vector3::new(r[(0, k)], r[(1, k)], r[(2, k)])
        }
        None => mat_vec(r, x),
    }
}

impl BodyColumns {
    pub(super) fn of(model: &Model, i: usize) -> Self {
        let mut cols = Self {
            s: [Column::of(Motion::zero()); 6],
            nv: 0,
            iv: 0,
            identity: false,
        };
        if let Some(j) = model.joints.get(i) {
            cols.iv = j.iv;
            cols.nv = if i == 0 { 0 } else { j.nv().min(6) };
            for (k, c) in cols.s.iter_mut().enumerate().take(cols.nv) {
                *c = Column::of(j.subspace_column(k));
            }
        }
        cols.identity = cols.nv == 6
            && (cols.s.iter().enumerate()).all(|(k, c)| match k < 3 {
                true => c.ang_zero && c.lin_unit == Some(k as u8),
                false => c.lin_zero && c.ang_unit == Some(k as u8 - 3),
            });
        cols
    }

    /// The world-frame columns `sw` at pose `o`: [`act_column`] of each
    /// (`nv` of them); S = 1 (`identity`) read off R, R's column k the
    /// linear column k's and the angular column k's ω' (the values
    /// [`act_column`] gives, [`rotate`]), v' = 0 + t × ω'.
    #[inline(always)]
    pub(super) fn world(&self, o: &Se3<f64>, sw: &mut [Motion; 6]) {
        if !self.identity {
            for (s, c) in sw.iter_mut().zip(&self.s).take(self.nv) {
                *s = act_column(o, c);
            }
            return;
        }
        let (r, zero) = (&o.rot, Vector3::zeros());
        for k in 0..3 {
            let ang = Vector3::new(r[(0, k)], r[(1, k)], r[(2, k)]);
            sw[k] = Motion {
                lin: ang,
                ang: zero,
            };
            sw[3 + k] = Motion {
                lin: add_cross(&zero, &o.trans, &ang),
                ang,
            };
        }
    }
}

/// `o.act_motion(&c.s)` (ω' = R ω, v' = R v + t × ω'), a zero part's
/// products left out and a unit axis's R e_k read off R ([`rotate`]): the
/// same values but for the sign of a zero, which no row keeps (J's entries
/// are sums onto the +0 that [`Rows::clear`] left; the spin rows' sums
/// start from 0 too).
#[inline(always)]
pub(super) fn act_column(o: &Se3<f64>, c: &Column) -> Motion {
    let ang = if c.ang_zero {
        Vector3::zeros()
    } else {
        rotate(&o.rot, &c.s.ang, c.ang_unit)
    };
    let lin = if c.lin_zero {
        Vector3::zeros()
    } else {
        rotate(&o.rot, &c.s.lin, c.lin_unit)
    };
    Motion {
        lin: if c.ang_zero {
            lin
        } else {
            add_cross(&lin, &o.trans, &ang)
        },
        ang,
    }
}
