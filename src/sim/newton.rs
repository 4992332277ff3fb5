//! The primal Newton solver (MuJoCo's default, in this engine's velocity-level
//! time stepping): the alternative to projected Gauss–Seidel ([`super::solver`])
//! that `SimOptions::solver = Solver::Newton` selects, kept for measurement
//! (docs/theory.md §"Constraint solve"; the comparison is in
//! benches/solver_compare.md).
//!
//! In the factored velocity x = R(v⁺ − v*) (H̃ = RᵀR, so the kinetic term is
//! ½‖x‖²) and with the rows' y = R⁻ᵀj, c = J v* ([`Rows::form`]), it minimises
//!
//!   φ(x) = ½‖x‖² + Σ_f ½ D_f min(0, e_f)² + Σ_box h_F(e_b),   e = c + y·x − b,
//!
//! where f runs over the *facets* of the constraints: a joint limit is one facet,
//! a contact with friction μ four (the pyramid edges u_n − b_n ± μ u_t1,
//! u_n − b_n ± μ u_t2, MuJoCo's default pyramidal cone), and joint friction F a
//! Huber cost h_F (quadratic ½De² for |e| ≤ F/D, then F|e| − F²/2D: at most F·Δt of
//! impulse). D_f = 1/(ρ W_ff) with W_ff = ‖y_f‖² (a soft constraint, as MuJoCo's
//! impedance makes every constraint; ρ small: nearly hard). φ is convex and
//! piecewise quadratic: Newton's step solves (I + Σ_active D y yᵀ) δ = −∇φ (one
//! dense Cholesky), an exact line search along δ follows the piecewise-linear
//! φ'(α), and a step whose active set does not change is the last. The impulses
//! are λ_f = −D_f min(0, e_f); a contact's normal impulse is the sum of its four,
//! its tangent impulses μ(λ₊ − λ₋).

use super::factor::MassFactor;
use super::solver::{RowKind, Rows};
use crate::dynamics::linalg::{chol_solve_slice, cholesky_fast};
use nalgebra::DMatrix;

/// The regularisation ρ: R_f = ρ W_ff (MuJoCo's impedance d = 0.9–0.95 is
/// ρ = (1 − d)/d ≈ 0.05–0.1; this engine keeps constraints nearly hard and lets
/// the position pass remove what a soft constraint lets through).
const RHO: f64 = 1e-6;

/// One facet: the row it comes from and how it combines the contact's rows.
#[derive(Clone, Copy, Debug)]
struct Facet {
    /// The row (a contact's normal row, or a joint limit's row).
    row: usize,
    /// 0: the row itself; 1, 2: tangent k with sign `sign`.
    tangent: usize,
    sign: f64,
    mu: f64,
    d: f64,
}

/// The preallocated work of the Newton solver.
#[derive(Clone, Debug)]
pub struct Newton {
    nv: usize,
    facets: Vec<Facet>,
    /// Box rows (joint friction): (row, D, F).
    boxes: Vec<(usize, f64, f64)>,
    hess: DMatrix<f64>,
    chol: DMatrix<f64>,
    grad: Vec<f64>,
    delta: Vec<f64>,
    /// Per facet / box: e at x and its rate along δ.
    e: Vec<f64>,
    de: Vec<f64>,
    eb: Vec<f64>,
    deb: Vec<f64>,
    yf: Vec<f64>,
    active: Vec<bool>,
    active_prev: Vec<bool>,
}

impl Newton {
    /// Room for `cap` rows of an nv-dof model.
    pub fn new(nv: usize, cap: usize) -> Self {
        Self {
            nv,
            facets: Vec::with_capacity(2 * cap),
            boxes: Vec::with_capacity(cap),
            hess: DMatrix::zeros(nv, nv),
            chol: DMatrix::zeros(nv, nv),
            grad: vec![0.0; nv],
            delta: vec![0.0; nv],
            e: Vec::with_capacity(2 * cap),
            de: Vec::with_capacity(2 * cap),
            eb: Vec::with_capacity(cap),
            deb: Vec::with_capacity(cap),
            yf: vec![0.0; nv],
            active: Vec::with_capacity(3 * cap),
            active_prev: Vec::with_capacity(3 * cap),
        }
    }

    /// Solves the formed rows: Δv' = x into `dx` (length nv), the impulses into
    /// `rows.lambda`. Returns the Newton iterations.
    pub fn solve(
        &mut self,
        rows: &mut Rows,
        f: &MassFactor,
        dx: &mut [f64],
        max_iter: usize,
        tol: f64,
    ) -> usize {
        let _ = f;
        let table = rows.take_table();
        let it = self.solve_on(rows, &table, dx, max_iter, tol);
        rows.put_table(table);
        it
    }

    /// [`Newton::solve`] on the rows' path table `table` (taken out of them).
    fn solve_on(
        &mut self,
        rows: &mut Rows,
        table: &[usize],
        dx: &mut [f64],
        max_iter: usize,
        tol: f64,
    ) -> usize {
        let nv = self.nv;
        let n = rows.n;
        if dx.len() < nv || rows.nv != nv {
            return 0;
        }
        // the facets and boxes of the rows
        self.facets.clear();
        self.boxes.clear();
        let mut r = 0;
        while r < n {
            match rows.kind[r] {
                RowKind::Normal
                    if r + 2 < n && matches!(rows.kind[r + 1], RowKind::Tangent { .. }) =>
                {
                    let mu = match rows.kind[r + 1] {
                        RowKind::Tangent { mu, .. } => mu,
                        _ => 0.0,
                    };
                    for (tangent, sign) in [(1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)] {
                        let w = rows.w[r]
                            + mu * mu * rows.w[r + tangent]
                            + 2.0 * sign * mu * rows.w_block[r][tangent - 1];
                        self.facets.push(Facet {
                            row: r,
                            tangent,
                            sign,
                            mu,
                            d: if w > 1e-14 { 1.0 / (RHO * w) } else { 0.0 },
                        });
                    }
                    r += 3;
                    continue;
                }
                RowKind::Normal | RowKind::Unilateral => {
                    let w = rows.w[r];
                    self.facets.push(Facet {
                        row: r,
                        tangent: 0,
                        sign: 0.0,
                        mu: 0.0,
                        d: if w > 1e-14 { 1.0 / (RHO * w) } else { 0.0 },
                    });
                }
                RowKind::Box { limit } => {
                    let w = rows.w[r];
                    if w > 1e-14 {
                        self.boxes.push((r, 1.0 / (RHO * w), limit));
                    }
                }
                RowKind::Bilateral => {
                    // a loop row: a box without bounds
                    let w = rows.w[r];
                    if w > 1e-14 {
                        self.boxes.push((r, 1.0 / (RHO * w), f64::INFINITY));
                    }
                }
                _ => {}
            }
            r += 1;
        }
        let path = |r: usize| {
            let (s, l) = rows.path[r];
            &table[s..s + l]
        };
        // x from the warm start: x = Σ λ y
        let x = &mut dx[..nv];
        x.iter_mut().for_each(|v| *v = 0.0);
        for r in 0..n {
            let l = rows.lambda[r];
            if l != 0.0 {
                for (t, &k) in path(r).iter().enumerate() {
                    x[k] += l * rows.y[r * rows.stride + t];
                }
            }
        }
        // a facet's y (compact over its row's path) and its c − b
        let facet_y = |fa: &Facet, out: &mut [f64]| -> f64 {
            let r = fa.row;
            let l = rows.path[r].1;
            let st = rows.stride;
            let (yn, rest) = rows.y[r * st..].split_at(st);
            out[..l].copy_from_slice(&yn[..l]);
            let mut c = rows.c[r] - rows.b[r];
            if fa.tangent > 0 {
                let k = fa.tangent;
                let yt = &rest[(k - 1) * st..(k - 1) * st + l];
                let s = fa.sign * fa.mu;
                for (o, &y) in out[..l].iter_mut().zip(yt) {
                    *o += s * y;
                }
                c += s * rows.c[r + k];
            }
            c
        };
        let dot = |y: &[f64], p: &[usize], v: &[f64]| -> f64 {
            y.iter().zip(p).map(|(a, &k)| a * v[k]).sum()
        };
        let mut it = 0;
        // the active set (quadratic pieces) of each facet and box, this iteration
        // and the last (preallocated: no allocation a step)
        self.active.clear();
        while it < max_iter {
            it += 1;
            // e, gradient, Hessian at x
            self.hess.fill(0.0);
            for k in 0..nv {
                self.hess[(k, k)] = 1.0;
                self.grad[k] = x[k];
            }
            self.e.clear();
            std::mem::swap(&mut self.active, &mut self.active_prev);
            self.active.clear();
            for fa in &self.facets {
                let c = facet_y(fa, &mut self.yf);
                let p = path(fa.row);
                let l = p.len();
                let e = c + dot(&self.yf[..l], p, x);
                self.e.push(e);
                let on = e < 0.0 && fa.d > 0.0;
                self.active.push(on);
                if on {
                    for (a, &ka) in p.iter().enumerate() {
                        let ga = fa.d * self.yf[a];
                        self.grad[ka] += ga * e;
                        for (b, &kb) in p.iter().enumerate().take(a + 1) {
                            // lower triangle (row ≥ column): paths ascend
                            self.hess[(ka, kb)] += ga * self.yf[b];
                        }
                    }
                }
            }
            self.eb.clear();
            for &(r, d, lim) in &self.boxes {
                let p = path(r);
                let y = &rows.y[r * rows.stride..r * rows.stride + p.len()];
                let e = rows.c[r] - rows.b[r] + dot(y, p, x);
                self.eb.push(e);
                let quad = (d * e).abs() <= lim;
                self.active.push(quad);
                let slope = if quad { d * e } else { lim * e.signum() };
                for (a, &ka) in p.iter().enumerate() {
                    self.grad[ka] += slope * y[a];
                    if quad {
                        for (b, &kb) in p.iter().enumerate().take(a + 1) {
                            self.hess[(ka, kb)] += d * y[a] * y[b];
                        }
                    }
                }
            }
            let gnorm = self.grad.iter().map(|g| g * g).sum::<f64>().sqrt();
            if gnorm <= tol || it > 1 && self.active == self.active_prev {
                break;
            }
            // δ = −(I + Σ D y yᵀ)⁻¹ ∇φ (the factorisation reads the lower triangle)
            if cholesky_fast(&self.hess, &mut self.chol).is_err() {
                break;
            }
            for k in 0..nv {
                self.delta[k] = -self.grad[k];
            }
            chol_solve_slice(self.chol.as_slice(), nv, &mut self.delta);
            // exact line search: φ'(α) = x·δ + α‖δ‖² + Σ D min(0, e + α de) de + boxes
            self.de.clear();
            for fa in &self.facets {
                facet_y(fa, &mut self.yf);
                let p = path(fa.row);
                self.de.push(dot(&self.yf[..p.len()], p, &self.delta));
            }
            self.deb.clear();
            for &(r, _, _) in &self.boxes {
                let p = path(r);
                let y = &rows.y[r * rows.stride..r * rows.stride + p.len()];
                self.deb.push(dot(y, p, &self.delta));
            }
            let xd: f64 = x.iter().zip(&self.delta).map(|(a, b)| a * b).sum();
            let dd: f64 = self.delta.iter().map(|a| a * a).sum();
            let slope = |alpha: f64| -> (f64, f64) {
                let (mut g, mut h) = (xd + alpha * dd, dd);
                for (i, fa) in self.facets.iter().enumerate() {
                    let e = self.e[i] + alpha * self.de[i];
                    if e < 0.0 {
                        g += fa.d * e * self.de[i];
                        h += fa.d * self.de[i] * self.de[i];
                    }
                }
                for (i, &(_, d, lim)) in self.boxes.iter().enumerate() {
                    let e = self.eb[i] + alpha * self.deb[i];
                    if (d * e).abs() <= lim {
                        g += d * e * self.deb[i];
                        h += d * self.deb[i] * self.deb[i];
                    } else {
                        g += lim * e.signum() * self.deb[i];
                    }
                }
                (g, h)
            };
            // φ' is increasing and piecewise linear: Newton from α = 1 with a bracket
            let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
            let mut alpha = 1.0;
            for _ in 0..30 {
                let (g, h) = slope(alpha);
                if g.abs() <= 1e-14 * (1.0 + dd) {
                    break;
                }
                if g > 0.0 {
                    hi = alpha;
                } else {
                    lo = alpha;
                }
                let mut next = if h > 0.0 { alpha - g / h } else { f64::NAN };
                if !(next > lo && next < hi) {
                    next = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * alpha
                    };
                }
                if (next - alpha).abs() <= 1e-12 * alpha.max(1.0) {
                    alpha = next;
                    break;
                }
                alpha = next;
            }
            for k in 0..nv {
                x[k] += alpha * self.delta[k];
            }
            // a full step inside one quadratic piece (no facet or box crossed a
            // breakpoint) lands on the minimum: done without another evaluation
            let same_piece = alpha == 1.0
                && self
                    .e
                    .iter()
                    .zip(&self.de)
                    .all(|(&e, &de)| (e < 0.0) == (e + de < 0.0))
                && self.boxes.iter().enumerate().all(|(i, &(_, d, lim))| {
                    let (e0, e1) = (self.eb[i], self.eb[i] + self.deb[i]);
                    ((d * e0).abs() <= lim) == ((d * e1).abs() <= lim) && (e0 >= 0.0) == (e1 >= 0.0)
                });
            if same_piece {
                break;
            }
        }
        // the impulses from e at the final x
        self.e.clear();
        for fa in &self.facets {
            let c = facet_y(fa, &mut self.yf);
            let p = path(fa.row);
            self.e.push(c + dot(&self.yf[..p.len()], p, x));
        }
        self.eb.clear();
        for &(r, _, _) in &self.boxes {
            let p = path(r);
            let y = &rows.y[r * rows.stride..r * rows.stride + p.len()];
            self.eb.push(rows.c[r] - rows.b[r] + dot(y, p, x));
        }
        for r in 0..n {
            rows.lambda[r] = 0.0;
        }
        for (i, fa) in self.facets.iter().enumerate() {
            let l = if self.e.get(i).is_some_and(|&e| e < 0.0) {
                -fa.d * self.e[i]
            } else {
                0.0
            };
            rows.lambda[fa.row] += l;
            if fa.tangent > 0 {
                rows.lambda[fa.row + fa.tangent] += fa.sign * fa.mu * l;
            }
        }
        for (i, &(r, d, lim)) in self.boxes.iter().enumerate() {
            let e = self.eb.get(i).copied().unwrap_or(0.0);
            rows.lambda[r] = (-d * e).clamp(-lim, lim);
        }
        it
    }
}
