//! The step's configuration update differentiated (docs/theory.md
//! §"Transition Jacobians"): q⁺ = q ⊕ h (v⁺ + w) and a free base's velocity
//! rotated into its new frame, in the tangent space (SO(3)'s right Jacobian).

use super::TransitionJacobians;
use crate::sim::Simulation;
use crate::spatial::{axis_angle, skew};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

impl Simulation {
    /// [δq'; δv'] from δv⁺ and δ(v⁺ + w) (start frame) and the unperturbed
    /// `vtot` = v⁺ + w (which moves q) and `vplus` = v⁺, for the columns
    /// (δq, δv) (A) and δτ (B).
    pub(super) fn output_map(
        &self,
        vtot: &DVector<f64>,
        vplus: &DVector<f64>,
        dvtot: &DMatrix<f64>,
        dvplus: &DMatrix<f64>,
        h: f64,
    ) -> TransitionJacobians {
        let n = self.model.nv;
        let mut out = TransitionJacobians {
            a: DMatrix::zeros(2 * n, 2 * n),
            b: DMatrix::zeros(2 * n, n),
        };
        // column c of [A B]
        let put = |out: &mut TransitionJacobians, r: usize, c: usize, x: f64| {
            if c < 2 * n {
                out.a[(r, c)] = x;
            } else {
                out.b[(r, c - 2 * n)] = x;
            }
        };
        // joints: δq' = δq + h δv⁺, δv' = δv⁺ (column by column, contiguous)
        let (dt, dp) = (dvtot.as_slice(), dvplus.as_slice());
        if dt.len() == 3 * n * n && dp.len() == 3 * n * n {
            for c in 0..3 * n {
                let col = if c < 2 * n {
                    &mut out.a.as_mut_slice()[c * 2 * n..(c + 1) * 2 * n]
                } else {
                    &mut out.b.as_mut_slice()[(c - 2 * n) * 2 * n..(c - 2 * n + 1) * 2 * n]
                };
                let (top, bottom) = col.split_at_mut(n);
                for (t, &x) in top.iter_mut().zip(&dt[c * n..(c + 1) * n]) {
                    *t = h * x;
                }
                if c < n {
                    top[c] += 1.0;
                }
                bottom.copy_from_slice(&dp[c * n..(c + 1) * n]);
            }
        }
        if self.model.floating_base {
            // p' = p + h R l, R' = R Exp(h ω) (l, ω of v⁺ + w), v'_lin = Exp(h ω)ᵀ l⁺
            let (w, l) = (omega(vtot), lin(vtot));
            let th = (w * h).norm();
            let e = if th > 0.0 {
                axis_angle(&(w * h / th), th)
            } else {
                Matrix3::identity()
            };
            let et = e.transpose();
            let jr = right_jacobian(&(w * h));
            let vlin_new = et * lin(vplus);
            for c in 0..3 * n {
                let (dl_in, dth_in) = if c < 3 {
                    (unit(c), Vector3::zeros())
                } else if c < 6 {
                    (Vector3::zeros(), unit(c - 3))
                } else {
                    (Vector3::zeros(), Vector3::zeros())
                };
                let dlp = Vector3::new(dvplus[(0, c)], dvplus[(1, c)], dvplus[(2, c)]);
                let dlv = Vector3::new(dvtot[(0, c)], dvtot[(1, c)], dvtot[(2, c)]);
                let dwv = Vector3::new(dvtot[(3, c)], dvtot[(4, c)], dvtot[(5, c)]);
                // δl' = Eᵀ(δl + h δθ × l + h δl⁺), δθ' = Eᵀ δθ + J_r h δω
                let dl_out = et * (dl_in + dth_in.cross(&l) * h + dlv * h);
                let dth_out = et * dth_in + jr * dwv * h;
                // δv'_lin = Eᵀ δl⁺ + [v'_lin]× J_r h δω
                let dv_out = et * dlp + vlin_new.cross(&(jr * dwv * h));
                for i in 0..3 {
                    put(&mut out, i, c, dl_out[i]);
                    put(&mut out, 3 + i, c, dth_out[i]);
                    put(&mut out, n + i, c, dv_out[i]);
                }
            }
        }
        out
    }
}

fn omega(v: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}
fn lin(v: &DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}
fn unit(i: usize) -> Vector3<f64> {
    let mut e = Vector3::zeros();
    e[i] = 1.0;
    e
}

/// SO(3)'s right Jacobian: Exp(x + δ) ≈ Exp(x) Exp(J_r(x) δ).
fn right_jacobian(x: &Vector3<f64>) -> Matrix3<f64> {
    let th = x.norm();
    let k = skew(x);
    if th < 1e-8 {
        return Matrix3::identity() - k * 0.5 + k * k / 6.0;
    }
    Matrix3::identity() - k * ((1.0 - th.cos()) / (th * th))
        + k * k * ((th - th.sin()) / (th * th * th))
}
