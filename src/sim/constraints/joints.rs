//! The joints' rows of a step (Coulomb friction |λ| ≤ F Δt, position limits
//! λ ≥ 0, after the contact rows) and the loop constraints' (after every
//! other row): the targets as in [`super`]'s account.

use super::{pos_target, speculative, Constraints, RowCounts, RowParams};
use crate::model::Model;
use crate::sim::factor::MassFactor;
use crate::sim::solver::{RowKind, Rows};
use nalgebra::DVector;

impl Constraints {
    /// Appends the 1-DoF joints' friction and limit rows at (q, v), counted
    /// in `counts` (contact rows come first: a sweep then meets the joint
    /// rows after the contacts have moved).
    pub(super) fn assemble_joint_rows(
        &mut self,
        q: &DVector<f64>,
        v: &DVector<f64>,
        p: &RowParams,
        f: &MassFactor,
        h: f64,
        counts: &mut RowCounts,
    ) {
        let rows = &mut self.rows;
        // joint rows: friction (|λ| ≤ F h), limits (λ ≥ 0)
        if p.joint_dynamics {
            // (the 1-DoF joints with friction or a limit, in dof order: `jrows`)
            for js in &self.jrows {
                let (d, iq, iv) = (js.d, js.iq, js.iv);
                let path = f.path_of(iv);
                if js.friction > 0.0 {
                    let kind = RowKind::Box {
                        limit: js.friction * h,
                    };
                    if let Some(r) = rows.push(kind, 0.0, self.warm_joint[d][0], path) {
                        add_joint_entry(rows, r, iv, 1.0);
                        self.joint_rows.push((d, 0));
                        counts.friction += 1;
                    }
                }
                if js.continuous {
                    continue;
                }
                let (qd, vd) = (q[iq], v[iv]);
                let margin = 1e-3 + 2.0 * vd.abs() * h;
                let sides = [(js.lower, 1.0, 1u8), (js.upper, -1.0, 2u8)];
                for (limit, sign, which) in sides {
                    let Some(l) = limit else { continue };
                    // φ = q − lower, or upper − q
                    let gap = sign * (qd - l);
                    if gap >= margin {
                        continue;
                    }
                    let w = self.warm_joint[d][which as usize];
                    if let Some(r) = rows.push(RowKind::Unilateral, speculative(gap, h), w, path) {
                        add_joint_entry(rows, r, iv, sign);
                        rows.bpos[r] = pos_target(gap, p.limit_slop, p.limit_push_cap, p.beta, h);
                        if rows.bpos[r] > 0.0 {
                            counts.violated += 1;
                        }
                        self.joint_rows.push((d, which));
                        counts.limits += 1;
                    }
                }
            }
        }
    }

    /// Appends the loop constraints' rows (after every other row, so that a
    /// run without loops is untouched) at (q, v); `data.o_m_i`: world poses at q.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_loops(
        &mut self,
        model: &Model,
        data: &crate::model::Data,
        q: &DVector<f64>,
        v: &DVector<f64>,
        p: &RowParams,
        f: &MassFactor,
        h: f64,
    ) -> RowCounts {
        if let Some(l) = self.loops.as_mut() {
            let cap = p.contact_push_cap.max(p.limit_push_cap);
            let (n, violated) = l.assemble(&mut self.rows, model, data, q, v, f, h, cap);
            self.counts.loops = n;
            if violated {
                self.counts.violated += 1;
            }
        }
        self.counts
    }
}

/// Adds `x` to J's entry of joint row `r` at its dof `iv`: the last of its
/// path (`MassFactor::path_of(iv)` ends at `iv`), else where [`Rows::add_entry`]
/// finds it.
#[inline]
fn add_joint_entry(rows: &mut Rows, r: usize, iv: usize, x: f64) {
    let (ps, pl) = rows.path[r];
    let last = (pl.checked_sub(1), rows.table().get(ps + pl.wrapping_sub(1)));
    match last {
        (Some(t), Some(&d)) if d == iv && t < rows.stride => rows.j[r * rows.stride + t] += x,
        _ => rows.add_entry(r, iv, x),
    }
}
