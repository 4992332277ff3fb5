//! A row's entries walked from its last to its first with constant bounds (the
//! compiler unrolls them): the kernels of [`super::MassFactor`]'s row folds.

/// `f(t, j[t])` for t from the last entry of `a` to the first (`a`, `j` of
/// equal length: a row's multipliers beside their dofs, from the nearest ancestor to the root): each entry's own update, in the same order; a
/// row of up to 11 unrolled (constant bounds), as [`MassFactor::fold_row`].
#[inline(always)]
pub(super) fn scatter_row(a: &[f64], j: &[usize], mut f: impl FnMut(usize, usize)) {
    let n = a.len().min(j.len());
    macro_rules! unrolled {
        ($($n:literal)*) => {
            match n {
                $($n => {
                    let j = &j[..$n];
                    for t in (0..$n).rev() {
                        f(t, j[t]);
                    }
                })*
                _ => {
                    for t in (0..n).rev() {
                        f(t, j[t]);
                    }
                }
            }
        };
    }
    unrolled!(0 1 2 3 4 5 6 7 8 9 10 11);
}

/// [`MassFactor::fold_row`] on `N` entries (`a[..N]`, `j[..N]`), the last first.
#[inline(always)]
pub(super) fn fold_n<const N: usize, T>(
    a: &[f64],
    j: &[usize],
    init: T,
    f: impl Fn(T, f64, usize) -> T,
) -> T {
    let (a, j) = (&a[..N], &j[..N]);
    let mut acc = init;
    for t in (0..N).rev() {
        acc = f(acc, a[t], j[t]);
    }
    acc
}
