//! The rows' second-order terms of the analytic step Jacobians (docs/theory.md
//! §"Transition Jacobians", §"Loops and the position pass in the step
//! Jacobians"): how the row Jacobians J(q) move with q, for the contact points
//! and the loop constraints' bilateral rows, as `∂(Jᵀλ)/∂q` (an n × n matrix for
//! given impulses λ) and `(∂J/∂q δq) x` (an m × n matrix for a given velocity
//! x); and the loop rows' velocity product γ = J̇ v differentiated, ∂γ/∂q and
//! ∂γ/∂v, which the position pass's target −½hγ brings into the step.

use crate::contact::{tangents, ContactPoint};
use crate::dynamics::constraint_dynamics::side_point;
use crate::model::{Attachment, ConstraintKind};
use crate::sim::solver::{RowKind, Rows};
use crate::sim::Simulation;
use crate::spatial::Motion;
use nalgebra::{DMatrix, DVector, Vector3};

/// ∂(S_c at p)/∂q_k for the columns c, k of a point's path (root first):
/// `d[a·len + b]` is d/dq_{cols[b]} of column cols[a]'s point velocity,
/// `dang[a·len + b]` of its angular velocity.
pub(super) struct PointTerms {
    /// (v index, depth of its joint on the path).
    pub cols: Vec<(usize, usize)>,
    pub d: Vec<Vector3<f64>>,
    pub dang: Vec<Vector3<f64>>,
}

/// The second-order terms of a material point `p` of `body` (moving with its
/// `anchor`: p itself for a vertex, the centre above a sphere's lowest point):
/// the world column S_c of each ancestor dof varies as S_k × S_c for k on the
/// same joint or an ancestor's, and the point moves by S_k at the anchor.
pub(super) fn point_second_derivatives(
    sim: &Simulation,
    body: usize,
    p: &Vector3<f64>,
    anchor: &Vector3<f64>,
) -> PointTerms {
    let model = &sim.model;
    let mut chain = Vec::new();
    let mut b = body;
    while b != 0 {
        chain.push(b);
        b = model.parent[b];
    }
    chain.reverse();
    let mut cols = Vec::new();
    let mut s: Vec<Motion> = Vec::new();
    for (depth, &b) in chain.iter().enumerate() {
        let j = &model.joints[b];
        let o = sim.data.o_m_i[b];
        for c in 0..j.nv().min(6) {
            cols.push((j.iv + c, depth));
            s.push(o.act_motion(&j.subspace_column(c)));
        }
    }
    let len = cols.len();
    let mut d = vec![Vector3::zeros(); len * len];
    let mut dang = vec![Vector3::zeros(); len * len];
    for a in 0..len {
        let sc = &s[a];
        for bb in 0..len {
            let sk = &s[bb];
            let mut t = Vector3::zeros();
            if cols[bb].1 <= cols[a].1 {
                // S_k × S_c at p: (ω_k × v_c + v_k × ω_c) + (ω_k × ω_c) × p
                let ang = sk.ang.cross(&sc.ang);
                t += sk.ang.cross(&sc.lin) + sk.lin.cross(&sc.ang) + ang.cross(p);
                dang[a * len + bb] = ang;
            }
            // the point's own motion: ω_c × δp, δp = v_k + ω_k × anchor
            let dp = sk.lin + sk.ang.cross(anchor);
            t += sc.ang.cross(&dp);
            d[a * len + bb] = t;
        }
    }
    PointTerms { cols, d, dang }
}

/// The active loop constraints and the first of their rows in the step's rows
/// (bilateral rows, appended after every other row in the set's order); `None`
/// when the rows do not read so.
pub(super) fn loop_rows(sim: &Simulation, rows: &Rows) -> Option<Vec<(usize, usize)>> {
    let Some(l) = sim.cons.loops.as_ref() else {
        return Some(Vec::new());
    };
    let first = (0..rows.n).find(|&r| rows.kind[r] == RowKind::Bilateral)?;
    let mut out = Vec::new();
    let mut r = first;
    for k in 0..l.set.items.len() {
        if l.active[k] {
            out.push((k, r));
            r += l.row_basis(k).1;
        }
    }
    let all_bilateral = (first..rows.n).all(|r| rows.kind[r] == RowKind::Bilateral);
    (r == rows.n && all_bilateral).then_some(out)
}

/// Adds the second-order terms of the rows for impulses `lam` (one per row)
/// and velocity `x`: `gc += ∂(Jᵀλ)/∂q` (n × n) and `jq += (∂J/∂q) x` (m × n,
/// column k the rows' velocity change when dof k moves), over the contact
/// points (`points`, the step's) and the loop rows (`loops`, [`loop_rows`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn add_second_order(
    sim: &Simulation,
    points: &[ContactPoint],
    loops: &[(usize, usize)],
    lam: &[f64],
    x: &DVector<f64>,
    gc: &mut DMatrix<f64>,
    jq: &mut DMatrix<f64>,
) {
    for (ci, &pi) in sim.cons.row_points().iter().enumerate() {
        let Some(pt) = points.get(pi) else { continue };
        let rn = 3 * ci;
        // the rows (n, t₁, t₂): the ground's (z, x, y), an obstacle's own
        let (t1, t2) = tangents(&pt.normal);
        let f = pt.normal * lam[rn] + t1 * lam[rn + 1] + t2 * lam[rn + 2];
        let anchor = pt.point + pt.normal * sim.rolling_radius(pt);
        let t = point_second_derivatives(sim, pt.body, &pt.point, &anchor);
        for (a, &(ca, _)) in t.cols.iter().enumerate() {
            for (b, &(cb, _)) in t.cols.iter().enumerate() {
                let d = t.d[a * t.cols.len() + b];
                gc[(ca, cb)] += d.dot(&f);
                let wd = d * x[ca];
                jq[(rn, cb)] += wd.dot(&pt.normal);
                jq[(rn + 1, cb)] += wd.dot(&t1);
                jq[(rn + 2, cb)] += wd.dot(&t2);
            }
        }
    }
    let Some(l) = sim.cons.loops.as_ref() else {
        return;
    };
    for &(k, r0) in loops {
        let c = &l.set.items[k];
        let frame = match c.kind {
            ConstraintKind::Joint { .. } => continue,
            ConstraintKind::Frame => true,
            ConstraintKind::Point => false,
        };
        // the step's rows are the constraint's world rows along its kept
        // directions E (sim/loops.rs): λ_world = E λ, their J_q rows Eᵀ(world)
        let m = c.rows();
        let (e, kept) = l.row_basis(k);
        let mut lw = [0.0; 6];
        for (i, x) in lw.iter_mut().enumerate().take(m) {
            *x = (0..kept).map(|t| e[t * m + i] * lam[r0 + t]).sum();
        }
        let mut jw = DMatrix::<f64>::zeros(m, jq.ncols());
        for (side, sign) in [(&c.a, 1.0), (&c.b, -1.0)] {
            if side.body == 0 {
                continue;
            }
            let p = side_point(&sim.data, side);
            let t = point_second_derivatives(sim, side.body, &p, &p);
            let f = Vector3::new(lw[0], lw[1], lw[2]) * sign;
            let tq = if frame {
                Vector3::new(lw[3], lw[4], lw[5]) * sign
            } else {
                Vector3::zeros()
            };
            let len = t.cols.len();
            for (a, &(ca, _)) in t.cols.iter().enumerate() {
                for (b, &(cb, _)) in t.cols.iter().enumerate() {
                    let (d, da) = (t.d[a * len + b], t.dang[a * len + b]);
                    gc[(ca, cb)] += d.dot(&f) + da.dot(&tq);
                    for i in 0..3 {
                        jw[(i, cb)] += sign * d[i] * x[ca];
                        if frame {
                            jw[(3 + i, cb)] += sign * da[i] * x[ca];
                        }
                    }
                }
            }
        }
        project_rows(e, kept, &jw, r0, jq);
    }
}

/// Adds world rows `w` (a constraint's `m` rows) along its kept directions
/// `e` (column-major m × kept) into rows `r0..r0 + kept` of `out`.
pub(super) fn project_rows(
    e: &[f64],
    kept: usize,
    w: &DMatrix<f64>,
    r0: usize,
    out: &mut DMatrix<f64>,
) {
    let m = w.nrows();
    for t in 0..kept {
        for c in 0..w.ncols() {
            out[(r0 + t, c)] += (0..m).map(|i| e[t * m + i] * w[(i, c)]).sum::<f64>();
        }
    }
}

/// ∂γ/∂q and ∂γ/∂v of the loop rows (γ = J̇ v, the rows' classical
/// acceleration at q̈ = 0) into rows `r0..` of `gq`, `gv`, from the world
/// velocities and accelerations `data.deriv_ov`, `data.deriv_oa` of an inverse
/// dynamics derivative pass at (q, v, 0) (gravity, a uniform world
/// acceleration, cancels in every difference below). The closed forms are the
/// constrained dynamics' (docs/theory.md §"Constrained dynamics", `∂A/∂q`,
/// `∂A/∂v` at q̈ = 0).
pub(super) fn loop_gamma_derivatives(
    sim: &Simulation,
    loops: &[(usize, usize)],
    gq: &mut DMatrix<f64>,
    gv: &mut DMatrix<f64>,
) {
    let Some(l) = sim.cons.loops.as_ref() else {
        return;
    };
    for &(k, r0) in loops {
        let c = &l.set.items[k];
        let frame = match c.kind {
            ConstraintKind::Joint { .. } => continue,
            ConstraintKind::Frame => true,
            ConstraintKind::Point => false,
        };
        let m = c.rows();
        let (e, kept) = l.row_basis(k);
        let (mut gqw, mut gvw) = (
            DMatrix::<f64>::zeros(m, gq.ncols()),
            DMatrix::<f64>::zeros(m, gv.ncols()),
        );
        for (side, sign) in [(&c.a, 1.0), (&c.b, -1.0)] {
            side_gamma_terms(sim, side, sign, frame, 0, &mut gqw, &mut gvw);
        }
        project_rows(e, kept, &gqw, r0, gq);
        project_rows(e, kept, &gvw, r0, gv);
    }
}

/// One side's rows of ∂γ/∂q, ∂γ/∂v (see [`loop_gamma_derivatives`]): with the
/// side's point p on body b and each column j of its path (world motion sⱼ on
/// body mⱼ, parent λ), `∂⁰v̂_b/∂qⱼ = sⱼ × (⁰v̂_b − ⁰v̂_λ)`,
/// `∂⁰â_b/∂qⱼ = sⱼ × (⁰â_b − ⁰â_λ) − (sⱼ × ⁰v̂_λ) × (⁰v̂_b − ⁰v̂_λ)`,
/// `∂⁰â_b/∂q̇ⱼ = sⱼ × (⁰v̂_b − ⁰v̂ₘ − ⁰v̂_λ)`, through p̈ = a + α × p + ω × ṗ.
#[allow(clippy::too_many_arguments)]
fn side_gamma_terms(
    sim: &Simulation,
    side: &Attachment,
    sign: f64,
    frame: bool,
    row: usize,
    gq: &mut DMatrix<f64>,
    gv: &mut DMatrix<f64>,
) {
    let (model, data) = (&*sim.model, &sim.data);
    let b = side.body;
    if b == 0 {
        return;
    }
    let p = side_point(data, side);
    let (ov, oa) = (&data.deriv_ov, &data.deriv_oa);
    let (ovb, oab) = (ov[b], oa[b]);
    let (omega, alpha) = (ovb.ang, oab.ang);
    let pdot = ovb.lin + omega.cross(&p);
    let mut m = b;
    while m != 0 {
        let joint = &model.joints[m];
        let pm = model.parent[m];
        let (ovp, oap) = (ov[pm], oa[pm]);
        for kk in 0..joint.nv() {
            let sj = data.o_m_i[m].act_motion(&joint.subspace_column(kk));
            let cj = joint.iv + kk;
            let dp = sj.lin + sj.ang.cross(&p);
            let dvb = ovb - ovp;
            let dov = sj.cross(&dvb);
            let doa = sj.cross(&(oab - oap)) - sj.cross(&ovp).cross(&dvb);
            let dpdd = doa.lin
                + doa.ang.cross(&p)
                + alpha.cross(&dp)
                + dov.ang.cross(&pdot)
                + omega.cross(&(dov.lin + dov.ang.cross(&p) + omega.cross(&dp)));
            let dav = sj.cross(&(ovb - ov[m] - ovp));
            let dpdv = dav.lin
                + dav.ang.cross(&p)
                + sj.ang.cross(&pdot)
                + omega.cross(&(sj.lin + sj.ang.cross(&p)));
            for i in 0..3 {
                gq[(row + i, cj)] += sign * dpdd[i];
                gv[(row + i, cj)] += sign * dpdv[i];
                if frame {
                    gq[(row + 3 + i, cj)] += sign * doa.ang[i];
                    gv[(row + 3 + i, cj)] += sign * dav.ang[i];
                }
            }
        }
        m = pm;
    }
}

/// The residual φ of each row of loop constraint `k` at the current poses
/// (`data.o_m_i`), as the step's position target reads it (sim/loops.rs).
pub(super) fn loop_residual(sim: &Simulation, k: usize) -> [f64; 6] {
    let Some(l) = sim.cons.loops.as_ref() else {
        return [0.0; 6];
    };
    crate::sim::loops::residual(&l.set.items[k], &sim.data, sim.q.as_slice())
}
