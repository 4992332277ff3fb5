//! A tree's coordinates, one range of q or v, copied or zeroed: a lone free
//! body's seven q and six v (every dozing tree's, most sleeping ones') as
//! fixed-length arrays, moved in registers rather than by a call to the C
//! library's `memcpy`/`memset` (hundreds of calls a step on a sleeping or
//! dozing pile); other lengths by the slice copy and fill.

use nalgebra::DVector;

/// `to = from` (slices of one length), seven and six entries as arrays.
#[inline(always)]
fn copy_short(to: &mut [f64], from: &[f64]) {
    if let (Ok(t), Ok(f)) = (
        <&mut [f64; 7]>::try_from(&mut *to),
        <&[f64; 7]>::try_from(from),
    ) {
        *t = *f;
    } else if let (Ok(t), Ok(f)) = (
        <&mut [f64; 6]>::try_from(&mut *to),
        <&[f64; 6]>::try_from(from),
    ) {
        *t = *f;
    } else {
        to.copy_from_slice(from);
    }
}

/// `to[r] = from[r]` (a range out of either: nothing copied): a tree's
/// coordinates, one range of q or v.
#[inline]
pub(in crate::sim) fn copy_range(
    to: &mut DVector<f64>,
    from: &DVector<f64>,
    r: std::ops::Range<usize>,
) {
    if let (Some(t), Some(f)) = (to.as_mut_slice().get_mut(r.clone()), from.as_slice().get(r)) {
        copy_short(t, f);
    }
}

/// `x[r] = +0` (a range out of `x`: nothing written).
#[inline]
pub(in crate::sim) fn zero_range(x: &mut DVector<f64>, r: std::ops::Range<usize>) {
    let Some(s) = x.as_mut_slice().get_mut(r) else {
        return;
    };
    if let Ok(s) = <&mut [f64; 6]>::try_from(&mut *s) {
        *s = [0.0; 6];
    } else {
        s.fill(0.0);
    }
}
