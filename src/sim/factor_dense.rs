//! The dense factor's triangular substitutions (a mimic joint's or a short
//! chain's H̃ = L Lᵀ, [`super::factor::MassFactor`]): L x = b and Lᵀ x = b in
//! place, column-major L, its reciprocal diagonal given.

/// L x' = x in place for K vectors at once (forward substitution; L lower,
/// column-major n × n, `inv` its reciprocal diagonal). `N = 0`: the length `n`
/// at run time, else `N = n`. Does nothing when a length does not fit.
#[inline(always)]
pub(super) fn dense_forward<const N: usize, const K: usize>(
    l: &[f64],
    inv: &[f64],
    n: usize,
    x: [&mut [f64]; K],
) {
    let n = if N == 0 { n } else { N };
    if l.len() < n * n || inv.len() < n || x.iter().any(|x| x.len() < n) {
        return;
    }
    let mut x = x.map(|x| &mut x[..n]);
    let (l, inv) = (&l[..n * n], &inv[..n]);
    for k in 0..n {
        let mut xk = [0.0; K];
        for (a, xs) in xk.iter_mut().zip(x.iter_mut()) {
            *a = xs[k] * inv[k];
            xs[k] = *a;
        }
        let col = &l[k * n..(k + 1) * n];
        for i in k + 1..n {
            let lik = col[i];
            for (a, xs) in xk.iter().zip(x.iter_mut()) {
                xs[i] -= lik * a;
            }
        }
    }
}

/// Lᵀ x' = x in place (back substitution), as [`dense_forward`].
#[inline(always)]
pub(super) fn dense_backward<const N: usize>(l: &[f64], inv: &[f64], n: usize, x: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    if l.len() < n * n || inv.len() < n || x.len() < n {
        return;
    }
    let (l, inv, x) = (&l[..n * n], &inv[..n], &mut x[..n]);
    for k in (0..n).rev() {
        let col = &l[k * n..(k + 1) * n];
        let mut s = 0.0;
        for i in k + 1..n {
            s += x[i] * col[i];
        }
        x[k] = (x[k] - s) * inv[k];
    }
}
