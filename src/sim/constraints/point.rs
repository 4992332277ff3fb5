//! The contact rows on this thread (`Constraints::contacts`), and one
//! contact point's three rows once their place is fixed (row index, dof
//! path, [`free::plan`], stale entries: `Constraints::assemble`'s loop, or
//! the team's pre-pass, [`super::team`]): J's entries on the path and the
//! normal's velocity and position targets. It reads the step's world
//! columns and writes only its own three rows, so points may be written in
//! any order, on any thread, with the same bits.

use super::free::{self, Frame, Plan};
use super::tables::{add_body, BodyHead};
use super::{common_ancestor, pos_target, speculative, Constraints, RowCounts, RowParams};
use crate::contact::ContactPoint;
use crate::model::Model;
use crate::sim::factor::MassFactor;
use crate::spatial::{Motion, Se3};
use nalgebra::{DVector, Vector3};

/// What every point's rows read besides the point.
#[derive(Clone, Copy)]
pub(super) struct PointInputs<'a> {
    /// The model's parent of each body.
    pub parent: &'a [usize],
    /// Each body's joint columns' heads ([`BodyHead`]).
    pub heads: &'a [BodyHead],
    /// The step's world-frame subspace columns of the bodies the points reach.
    pub sw: &'a [[Motion; 6]],
    /// The velocity (restitution's approach speed).
    pub v: &'a [f64],
    /// The row parameters.
    pub p: &'a RowParams,
    /// The step.
    pub h: f64,
}

/// Writes contact `pt`'s three rows `j0`, `j1`, `j2` on its path `on_path`
/// (entry t of a row is dof `on_path[t]`) by `plan` (root free bodies, the
/// rows written whole, the first `stale` entries of each zeroed past the
/// path) or by the general walk (onto rows zeroed before); returns the
/// normal's targets (b, b_pos).
#[inline(always)]
pub(super) fn write(
    x: &PointInputs<'_>,
    [j0, j1, j2]: [&mut [f64]; 3],
    on_path: &[usize],
    plan: Option<Plan>,
    stale: usize,
    pt: &ContactPoint,
    frame: &mut Frame,
) -> (f64, f64) {
    let at = &pt.point;
    if let Some(plan) = plan
        && free::write(plan, [&mut *j0, &mut *j1, &mut *j2], stale, x.sw, pt, frame)
    {
        // (written whole)
    } else if pt.other == 0 && pt.normal == Vector3::z() {
        // the ground: rows n = z, t₁ = x, t₂ = y: the point velocity
        // v_c + ω_c × p of each ancestor's world-frame subspace column c
        let (mut b, mut hi) = (pt.body, on_path.len());
        while b != 0
            && let (Some(bc), Some(sw)) = (x.heads.get(b), x.sw.get(b))
        {
            let j = [&mut *j0, &mut *j1, &mut *j2];
            hi = add_body(j, on_path, hi, bc, sw, at, |vp| [vp.z, vp.x, vp.y]);
            b = x.parent[b];
        }
    } else {
        // two bodies: J = J_a − J_b, the relative velocity of the
        // point on a and on b along (n, t₁, t₂), n from b toward a
        // (a common ancestor's columns cancel: x + (−x) = +0, the
        // entry as zeroed, so each walk stops at the first of them);
        // b's entries are −(n·vp), the values of n·(−vp) but for
        // the sign of a zero, which the sum onto +0 drops
        let (n, (t1, t2)) = (pt.normal, frame.tangents(&pt.normal));
        let lca = common_ancestor(x.parent, pt.body, pt.other);
        for (start, neg) in [(pt.body, false), (pt.other, true)] {
            let (mut b, mut hi) = (start, on_path.len());
            while b != lca
                && b != 0
                && let (Some(bc), Some(sw)) = (x.heads.get(b), x.sw.get(b))
            {
                let j = [&mut *j0, &mut *j1, &mut *j2];
                hi = add_body(j, on_path, hi, bc, sw, at, |vp| {
                    let r = [n.dot(&vp), t1.dot(&vp), t2.dot(&vp)];
                    if neg {
                        r.map(|x| -x)
                    } else {
                        r
                    }
                });
                b = x.parent[b];
            }
        }
    }
    // normal target: speculative; restitution only above the speed below
    // which a bounce of one step under gravity could gain energy:
    // |u| > 4 g h e / (1 − e²)
    let (p, h) = (x.p, x.h);
    let mut bn = speculative(pt.gap, h);
    let e = p.restitution;
    if e > 0.0 && e < 1.0 {
        // (`Rows::jdot` of the normal row: its entries on the path)
        let jr = &j0[..on_path.len().min(j0.len())];
        let un: f64 = (jr.iter().zip(on_path))
            .map(|(a, &k)| a * x.v.get(k).copied().unwrap_or(0.0))
            .sum();
        let vmin = (4.0 * p.gravity * h * e / (1.0 - e * e).max(1e-12)).max(1e-3);
        if un < -vmin && pt.gap < -un * h {
            bn = bn.max(-e * un);
        }
    }
    let bpos = pos_target(pt.gap, p.contact_slop, p.contact_push_cap, p.beta, h);
    (bn, bpos)
}

impl Constraints {
    /// The rows of `points` on this thread, in point order (as many as fit):
    /// the world columns of the bodies they reach, then each contact's place
    /// and its entries. `keep`: the last assembly's contact rows
    /// (`Rows::clear_but`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn contacts(
        &mut self,
        model: &Model,
        o_m_i: &[Se3<f64>],
        v: &DVector<f64>,
        points: &[ContactPoint],
        p: &RowParams,
        f: &MassFactor,
        h: f64,
        keep: usize,
        counts: &mut RowCounts,
    ) {
        // world-frame motion subspace columns of the bodies the points'
        // rows reach (each point's two bodies and their ancestors), once
        // (the columns in the body frame are the joint's constants, kept
        // from the start: `cols`); a point on the last one's two bodies
        // finds them done (a pair's points, a body's ground points, in a row)
        let mut last = None;
        for pt in points {
            if last.replace((pt.body, pt.other)) == Some((pt.body, pt.other)) {
                continue;
            }
            for start in [pt.body, pt.other] {
                let mut i = start;
                while i != 0
                    && let Some(done) = self.sw_done.get_mut(i)
                    && *done != self.sw_stamp
                    && let (Some(cols), Some(o), Some(sw)) =
                        (self.cols.get(i), o_m_i.get(i), self.sw.get_mut(i))
                {
                    *done = self.sw_stamp;
                    cols.world(o, sw);
                    i = model.parent[i];
                }
            }
        }
        self.warm_points.clear();
        let wc = &self.warm_contact;
        self.warm_points
            .extend(points.iter().map(|pt| match pt.fresh {
                true => [0.0; 3],
                false => wc.get(pt.slot).map_or([0.0; 3], |w| [w[0], w[1], w[2]]),
            }));
        let heads = &self.heads;
        let body_path = |b: usize| {
            let (iv, nv) = heads.get(b).map_or((0, 0), |c| (c.iv, c.nv));
            f.path_of((iv + nv).saturating_sub(1))
        };
        let x = PointInputs {
            parent: &model.parent,
            heads: &self.heads,
            sw: &self.sw,
            v: v.as_slice(),
            p,
            h,
        };
        let rows = &mut self.rows;
        let mut frame = Frame::default();
        // the points by runs on the same two bodies (a pair's points, a
        // body's ground points): a run's path and plan are its bodies', made
        // once (`union_path` would find the run's union as its last one)
        let mut run = (usize::MAX, usize::MAX);
        let mut path = (0, 0);
        let mut bodies_plan = None;
        for (pi, (pt, &warm)) in points.iter().zip(&self.warm_points).enumerate() {
            if run != (pt.body, pt.other) {
                run = (pt.body, pt.other);
                // the body's path to the root: its joint's last dof and every
                // ancestor; against another body, the union with that body's
                path = if pt.other == 0 {
                    body_path(pt.body)
                } else {
                    rows.union_path(body_path(pt.body), body_path(pt.other))
                };
                let (ps, pl) = path;
                bodies_plan = (rows.table().get(ps..ps + pl)).and_then(|on| {
                    free::plan_bodies(&self.heads, on, rows.stride, pt.body, pt.other)
                });
            }
            // root free bodies' rows are written whole ([`free`]): of the
            // last assembly's entries there, only those past the path are
            // zeroed (its length `stale`); any other's are zeroed first
            let (ps, pl) = path;
            let plan = bodies_plan.filter(|p| p.holds(pt));
            let stale = match rows.path.get(rows.n) {
                Some(&(_, l)) if rows.n + 3 <= keep => l,
                _ => 0,
            };
            if plan.is_none() && rows.n + 3 <= keep {
                rows.zero_contact(rows.n);
            }
            let Some(rn) = rows.push_contact(pt.friction, warm, path) else {
                break;
            };
            self.row_point.push(pi);
            counts.contacts += 1;
            // J's entries are added straight onto the rows' paths (zeroed
            // by `clear`): entry t of a row is dof path[t] (a path is
            // ascending: `add_body` finds a dof by bisection)
            let st = rows.stride;
            let (tab, jall) = rows.table_and_j();
            let on_path = tab.get(ps..ps + pl).unwrap_or(&[]);
            let (j0, rest) = jall[rn * st..(rn + 3) * st].split_at_mut(st);
            let (j1, j2) = rest.split_at_mut(st);
            let (bn, bpos) = write(&x, [j0, j1, j2], on_path, plan, stale, pt, &mut frame);
            rows.b[rn] = bn;
            rows.bpos[rn] = bpos;
            if bpos > 0.0 {
                counts.violated += 1;
            }
        }
    }
}
