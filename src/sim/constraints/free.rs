//! A contact's three rows where its bodies are root bodies with a free
//! joint (every contact of a pile): each body's six entries a row written
//! side by side from its world columns, not walked column by column
//! ([`super::tables::add_body`]), the same values (the same bits).
//!
//! A free joint's world columns `sw` are three linear ones (no angular
//! part: the point velocity is the column's linear part) and three with an
//! angular part ω (point velocity v + ω × p); with those six point
//! velocities by component, a row's six entries are one product each, taken
//! six at a time. Each entry gets [`add_body`]'s operations in its order:
//! nalgebra's cross (ω_y p_z − ω_z p_y, …) added to v, nalgebra's dot
//! ((aₓvₓ + a_yv_y) + a_zv_z), negated for the second body, and summed onto
//! +0 (written `e + 0.0`: the rows are not zeroed first, see [`write`]).
//!
//! [`add_body`]: super::tables::add_body

use super::tables::BodyHead;
use crate::contact::{tangents, ContactPoint};
use crate::spatial::Motion;
use nalgebra::Vector3;

/// Where a contact's rows between root free bodies lie on its path.
#[derive(Clone, Copy, Debug)]
pub(super) enum Plan {
    /// A free body on the ground (normal +z): its dofs the whole path.
    Ground,
    /// Two free bodies: the first body's dofs at `a`, the other's at `b`
    /// (0 and 6, ascending by dof).
    Pair { a: usize, b: usize },
}

/// The plan of contact `pt` on `path` (its dofs, ascending; at most
/// `stride` of them), or `None` where its bodies are not root free bodies
/// whose dofs make up the path back to back (the general walk then):
/// [`plan_bodies`] of its bodies, a ground contact's only along +z.
#[inline]
pub(super) fn plan(
    heads: &[BodyHead],
    path: &[usize],
    stride: usize,
    pt: &ContactPoint,
) -> Option<Plan> {
    plan_bodies(heads, path, stride, pt.body, pt.other).filter(|p| p.holds(pt))
}

/// [`plan`] of every contact between bodies `a` and `other` (0: the
/// ground) on `path` but for the normal, which [`Plan::holds`] tests: a
/// pair's points share their bodies and path, so their plan is made once.
#[inline]
pub(super) fn plan_bodies(
    heads: &[BodyHead],
    path: &[usize],
    stride: usize,
    a: usize,
    other: usize,
) -> Option<Plan> {
    if path.len() > stride {
        return None;
    }
    let on = |b: usize, t: usize| {
        heads.get(b).is_some_and(|h| {
            h.free && path.get(t) == Some(&h.iv) && path.get(t + 5) == Some(&(h.iv + 5))
        })
    };
    let b = other;
    if b == 0 {
        return (path.len() == 6 && on(a, 0)).then_some(Plan::Ground);
    }
    let (ha, hb) = (heads.get(a)?, heads.get(b)?);
    let (ta, tb) = if ha.iv < hb.iv { (0, 6) } else { (6, 0) };
    (a != b && path.len() == 12 && on(a, ta) && on(b, tb)).then_some(Plan::Pair { a: ta, b: tb })
}

impl Plan {
    /// Whether the plan of `pt`'s bodies holds for `pt`: a ground contact's
    /// rows are written by components only along n = +z.
    #[inline(always)]
    pub(super) fn holds(self, pt: &ContactPoint) -> bool {
        match self {
            Plan::Ground => pt.normal == Vector3::z(),
            Plan::Pair { .. } => true,
        }
    }
}

/// The tangents of the last normal asked for (a pair's points share their
/// normal: its tangents are made once, not once a point; the same bits).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Frame {
    /// The normal's bits (none asked yet: `None`).
    n: Option<[u64; 3]>,
    t: (Vector3<f64>, Vector3<f64>),
}

impl Frame {
    /// [`tangents`] of `n`, kept for a normal of the same bits.
    #[inline(always)]
    pub(super) fn tangents(&mut self, n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let bits = [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()];
        if self.n != Some(bits) {
            self.n = Some(bits);
            self.t = tangents(n);
        }
        self.t
    }
}

/// Writes contact `pt`'s three rows `j` by `plan` (every entry of the path:
/// the entries' old values are overwritten, none read), `sw` each body's
/// world columns; `stale`: how many entries of each row the last assembly
/// may have left nonzero (a row is zero past its path), zeroed past the
/// path. False where a row or a body is missing: the rows are then zeroed
/// (their first `stale` entries), for the general walk.
#[inline(always)]
pub(super) fn write(
    plan: Plan,
    j: [&mut [f64]; 3],
    stale: usize,
    sw: &[[Motion; 6]],
    pt: &ContactPoint,
    frame: &mut Frame,
) -> bool {
    let [j0, j1, j2] = j;
    let pl = match plan {
        Plan::Ground => 6,
        Plan::Pair { .. } => 12,
    };
    let done = write_path(plan, [&mut *j0, &mut *j1, &mut *j2], sw, pt, frame);
    let from = if done { pl } else { 0 };
    // (nothing past the path when the last rows were no longer: a pile's
    // contact on the same bodies or a ground contact after a ground one)
    if stale <= from {
        return done;
    }
    for r in [j0, j1, j2] {
        let end = stale.min(r.len());
        if let Some(x) = r.get_mut(from.min(end)..end) {
            x.fill(0.0);
        }
    }
    done
}

/// [`write`]'s entries on the path.
#[inline(always)]
fn write_path(
    plan: Plan,
    j: [&mut [f64]; 3],
    sw: &[[Motion; 6]],
    pt: &ContactPoint,
    frame: &mut Frame,
) -> bool {
    let p = &pt.point;
    match plan {
        Plan::Ground => {
            let Some(s) = sw.get(pt.body) else {
                return false;
            };
            // rows n = z, t₁ = x, t₂ = y: the point velocity's components
            put(j, 0, s, p, |i, v, r| component([2, 0, 1][i], v, r))
        }
        Plan::Pair { a, b } => {
            let (Some(sa), Some(sb)) = (sw.get(pt.body), sw.get(pt.other)) else {
                return false;
            };
            let [j0, j1, j2] = j;
            if [&*j0, &*j1, &*j2].iter().any(|r| r.len() < 12) {
                return false;
            }
            // J = J_a − J_b along (n, t₁, t₂), n from b toward a
            let (n, (t1, t2)) = (pt.normal, frame.tangents(&pt.normal));
            let axes = [n, t1, t2];
            put([j0, j1, j2], a, sa, p, |i, v, r| {
                along::<false>(&axes[i], v, r)
            }) && put([j0, j1, j2], b, sb, p, |i, v, r| {
                along::<true>(&axes[i], v, r)
            })
        }
    }
}

/// The six point velocities at `p` of a free body's world columns `sw` by
/// component (`v[c][k]`: component c of column k's): [`super::tables`]'
/// `point_velocity` of each, side by side.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn velocities(sw: &[Motion; 6], p: &Vector3<f64>) -> [[f64; 6]; 3] {
    let mut v = [[0.0; 6]; 3];
    for (k, s) in sw.iter().enumerate() {
        for (c, vc) in v.iter_mut().enumerate() {
            vc[k] = s.lin[c];
        }
    }
    let mut w = [[0.0; 3]; 3];
    for (k, s) in sw[3..].iter().enumerate() {
        for (c, wc) in w.iter_mut().enumerate() {
            wc[k] = s.ang[c];
        }
    }
    let [wx, wy, wz] = w;
    let [vx, vy, vz] = &mut v;
    for k in 0..3 {
        // v + ω × p, nalgebra's cross (ω_y p_z − ω_z p_y, ω_z p_x − ω_x p_z, ω_x p_y − ω_y p_x)
        vx[3 + k] += wy[k] * p.z - wz[k] * p.y;
        vy[3 + k] += wz[k] * p.x - wx[k] * p.z;
        vz[3 + k] += wx[k] * p.y - wy[k] * p.x;
    }
    v
}

/// Row i's six entries at `t0` of `j[i]` are `row(i, v)` + 0.0 for the point
/// velocities `v` at `p` of `sw` ([`velocities`]; on x86_64 [`lanes::Vel`],
/// row i's `row` writing them). False, nothing written, where a row is too
/// short.
#[inline(always)]
fn put(
    j: [&mut [f64]; 3],
    t0: usize,
    sw: &[Motion; 6],
    p: &Vector3<f64>,
    row: impl Fn(usize, &Vel, &mut [f64; 6]),
) -> bool {
    let [j0, j1, j2] = j;
    let (Some(r0), Some(r1), Some(r2)) = (
        j0.get_mut(t0..t0 + 6)
            .and_then(|r| <&mut [f64; 6]>::try_from(r).ok()),
        j1.get_mut(t0..t0 + 6)
            .and_then(|r| <&mut [f64; 6]>::try_from(r).ok()),
        j2.get_mut(t0..t0 + 6)
            .and_then(|r| <&mut [f64; 6]>::try_from(r).ok()),
    ) else {
        return false;
    };
    let v = velocities(sw, p);
    for (i, r) in [r0, r1, r2].into_iter().enumerate() {
        row(i, &v, r);
    }
    true
}

/// The point velocities [`put`]'s rows read.
#[cfg(not(target_arch = "x86_64"))]
type Vel = [[f64; 6]; 3];

/// Row `r` = component `c` of the point velocities `v`, each + 0.0 (a
/// zero's sign as the sum onto the +0 of a zeroed row leaves it).
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn component(c: usize, v: &Vel, r: &mut [f64; 6]) {
    for (x, &e) in r.iter_mut().zip(&v[c.min(2)]) {
        *x = e + 0.0;
    }
}

/// Row `r` = the entries `a·v` of the six point velocities `v` along `a`
/// (nalgebra's dot, (aₓvₓ + a_yv_y) + a_zv_z), negated with `NEG`, each +
/// 0.0.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn along<const NEG: bool>(a: &Vector3<f64>, v: &Vel, r: &mut [f64; 6]) {
    for (k, x) in r.iter_mut().enumerate() {
        let d = a.x * v[0][k] + a.y * v[1][k] + a.z * v[2][k];
        let e = if NEG { -d } else { d };
        *x = e + 0.0;
    }
}

#[cfg(target_arch = "x86_64")]
use lanes::{along, component, velocities, Vel};

/// [`velocities`], [`component`] and [`along`] two columns a lane (SSE2):
/// per entry the same operations in the same order as the scalar forms.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use crate::spatial::Motion;
    use nalgebra::Vector3;
    use std::arch::x86_64::{
        __m128d, _mm_add_pd, _mm_mul_pd, _mm_set1_pd, _mm_set_pd, _mm_setzero_pd, _mm_storeu_pd,
        _mm_sub_pd, _mm_xor_pd,
    };

    /// The six point velocities by component, columns (0, 1), (2, 3), (4, 5)
    /// a register: `Vel(v)`, `v[c][h]` component c of columns 2h, 2h + 1.
    #[derive(Clone, Copy)]
    pub(super) struct Vel([[__m128d; 3]; 3]);

    /// The point velocities at `p` of a free body's world columns `sw`: the
    /// linear columns' `lin`, the angular ones' `lin + ω × p` (nalgebra's
    /// cross, ω_y p_z − ω_z p_y, …, added to `lin`).
    #[inline(always)]
    pub(super) fn velocities(sw: &[Motion; 6], p: &Vector3<f64>) -> Vel {
        let [s0, s1, s2, s3, s4, s5] = sw;
        // column 3's point velocity (alone in its register's high lane)
        let (w, l) = (&s3.ang, &s3.lin);
        let v3 = [
            l.x + (w.y * p.z - w.z * p.y),
            l.y + (w.z * p.x - w.x * p.z),
            l.z + (w.x * p.y - w.y * p.x),
        ];
        // SAFETY: SSE2 is part of x86_64; no memory is read or written
        // through a pointer here
        unsafe {
            let pair = |a: f64, b: f64| _mm_set_pd(b, a);
            let (px, py, pz) = (_mm_set1_pd(p.x), _mm_set1_pd(p.y), _mm_set1_pd(p.z));
            let (wx, wy, wz) = (
                pair(s4.ang.x, s5.ang.x),
                pair(s4.ang.y, s5.ang.y),
                pair(s4.ang.z, s5.ang.z),
            );
            let cross = [
                _mm_sub_pd(_mm_mul_pd(wy, pz), _mm_mul_pd(wz, py)),
                _mm_sub_pd(_mm_mul_pd(wz, px), _mm_mul_pd(wx, pz)),
                _mm_sub_pd(_mm_mul_pd(wx, py), _mm_mul_pd(wy, px)),
            ];
            let by = |c: usize| {
                [
                    pair(s0.lin[c], s1.lin[c]),
                    pair(s2.lin[c], v3[c]),
                    _mm_add_pd(pair(s4.lin[c], s5.lin[c]), cross[c]),
                ]
            };
            Vel([by(0), by(1), by(2)])
        }
    }

    /// Row `r` = component `c` (0 to 2) of the point velocities `v`, each +
    /// 0.0 (a zero's sign as the sum onto the +0 of a zeroed row leaves it).
    #[inline(always)]
    pub(super) fn component(c: usize, v: &Vel, r: &mut [f64; 6]) {
        let vc = &v.0[c.min(2)];
        // SAFETY: SSE2 is part of x86_64; each store is two entries at 0, 2
        // or 4 of the six of `r`
        unsafe {
            let zero = _mm_setzero_pd();
            for (h, &x) in vc.iter().enumerate() {
                _mm_storeu_pd(r.as_mut_ptr().add(2 * h), _mm_add_pd(x, zero));
            }
        }
    }

    /// Row `r` = the entries `a·v` of the six point velocities `v` along `a`
    /// (nalgebra's dot, (aₓvₓ + a_yv_y) + a_zv_z), negated with `NEG` (the
    /// sign bit flipped, as `-d`), each + 0.0.
    #[inline(always)]
    pub(super) fn along<const NEG: bool>(a: &Vector3<f64>, v: &Vel, r: &mut [f64; 6]) {
        // SAFETY: SSE2 is part of x86_64; each store is two entries at 0, 2
        // or 4 of the six of `r`
        unsafe {
            let (ax, ay, az) = (_mm_set1_pd(a.x), _mm_set1_pd(a.y), _mm_set1_pd(a.z));
            let (zero, sign) = (_mm_setzero_pd(), _mm_set1_pd(-0.0));
            let [vx, vy, vz] = &v.0;
            for h in 0..3 {
                let d = _mm_add_pd(
                    _mm_add_pd(_mm_mul_pd(ax, vx[h]), _mm_mul_pd(ay, vy[h])),
                    _mm_mul_pd(az, vz[h]),
                );
                let d = if NEG { _mm_xor_pd(d, sign) } else { d };
                _mm_storeu_pd(r.as_mut_ptr().add(2 * h), _mm_add_pd(d, zero));
            }
        }
    }
}

/// The tests' hook (`urdyn::testing::constraints::free_rows`): a contact's
/// three rows at `p` along `normal` on a root free body of world columns `a`
/// (dofs 0..6), against the ground (`b` None: `normal` must be +z) or a
/// second one of columns `b` (dofs 6..12), written by [`write`] over rows of
/// 12 entries all `stale` (the last assembly's entries); None where [`plan`]
/// declines.
pub(crate) fn free_rows(
    a: &[Motion; 6],
    b: Option<&[Motion; 6]>,
    p: &Vector3<f64>,
    normal: &Vector3<f64>,
    stale: f64,
) -> Option<[Vec<f64>; 3]> {
    let head = |iv: usize| BodyHead {
        iv,
        nv: 6,
        ang_zero: [true, true, true, false, false, false],
        free: true,
    };
    let heads = [head(0), head(0), head(6)];
    let sw = [[Motion::zero(); 6], *a, *b.unwrap_or(a)];
    let pt = ContactPoint {
        shape: 0,
        slot: 0,
        body: 1,
        point: *p,
        gap: 0.0,
        geom: 0,
        other: if b.is_some() { 2 } else { 0 },
        other_geom: 0,
        normal: *normal,
        friction: 1.0,
        fresh: true,
        key: 0,
    };
    let path: Vec<usize> = (0..if b.is_some() { 12 } else { 6 }).collect();
    let plan = plan(&heads, &path, 12, &pt)?;
    let mut j = [vec![stale; 12], vec![stale; 12], vec![stale; 12]];
    let [j0, j1, j2] = &mut j;
    write(plan, [j0, j1, j2], 12, &sw, &pt, &mut Frame::default()).then_some(j)
}
