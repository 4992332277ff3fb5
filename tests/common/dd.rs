//! `DD`: double-double arithmetic (an unevaluated sum hi + lo of two f64, about
//! 106 bits, ~32 digits) as a nalgebra `RealField`, so that the engine's generic
//! algorithms run unchanged in higher precision for the stress tests.
//!
//! Exact to double-double precision: + − × ÷, `sqrt`, `sin`, `cos`, `sin_cos`,
//! `abs`, comparisons (the only operations the dynamics algorithms use). Every
//! other transcendental function is evaluated in f64 on the leading part (marked
//! `f64 precision` below): enough for the traits, never used by the algorithms.
#![allow(dead_code)]
// The constants are written as (f64 value, correction) pairs on purpose.
#![allow(clippy::approx_constant)]

use approx::{AbsDiffEq, RelativeEq, UlpsEq};
use nalgebra::{ComplexField, Field, RealField, SimdValue};
use num_traits::{FromPrimitive, Num, One, Signed, Zero};
use std::fmt;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

#[derive(Clone, Copy, Default, PartialEq)]
pub struct DD {
    pub hi: f64,
    pub lo: f64,
}

#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}
#[inline]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl DD {
    pub const fn from_f64(x: f64) -> Self {
        DD { hi: x, lo: 0.0 }
    }
    fn norm(hi: f64, lo: f64) -> Self {
        if !hi.is_finite() {
            return DD { hi, lo: 0.0 };
        }
        let (h, l) = quick_two_sum(hi, lo);
        DD { hi: h, lo: l }
    }
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
    fn mul_f64(self, b: f64) -> Self {
        let (p, e) = two_prod(self.hi, b);
        DD::norm(p, e + self.lo * b)
    }
    fn sqrt_dd(self) -> Self {
        if self.hi <= 0.0 {
            return if self.hi == 0.0 {
                DD::zero()
            } else {
                DD::from_f64(f64::NAN)
            };
        }
        if !self.hi.is_finite() {
            return self;
        }
        // One Newton step from the f64 root doubles the precision.
        let y = DD::from_f64(self.hi.sqrt());
        y + (self - y * y) / (y + y)
    }
    /// sin and cos of |r| ≤ π/4 by their Taylor series (terms to 1e-34).
    fn sin_cos_reduced(r: DD) -> (DD, DD) {
        let r2 = r * r;
        let mut term = r;
        let mut s = r;
        let mut k = 1.0;
        loop {
            term = -(term * r2) / DD::from_f64((k + 1.0) * (k + 2.0));
            k += 2.0;
            s += term;
            if term.hi.abs() < 1e-34 * s.hi.abs().max(1e-300) || k > 60.0 {
                break;
            }
        }
        let mut term = DD::one();
        let mut c = DD::one();
        let mut k = 0.0;
        loop {
            term = -(term * r2) / DD::from_f64((k + 1.0) * (k + 2.0));
            k += 2.0;
            c += term;
            if term.hi.abs() < 1e-34 || k > 60.0 {
                break;
            }
        }
        (s, c)
    }
    fn sin_cos_dd(self) -> (DD, DD) {
        if !self.hi.is_finite() {
            return (DD::from_f64(f64::NAN), DD::from_f64(f64::NAN));
        }
        // x = k π/2 + r with π/2 in double-double (exact enough for |x| < 1e6).
        let pio2 = DD {
            hi: 1.5707963267948966,
            lo: 6.123233995736766e-17,
        };
        let k = (self.hi / pio2.hi).round();
        let r = self - pio2.mul_f64(k);
        let (s, c) = DD::sin_cos_reduced(r);
        match (k as i64).rem_euclid(4) {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }
    fn f(x: f64) -> Self {
        DD::from_f64(x)
    }
}

impl fmt::Debug for DD {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "DD({:e} + {:e})", self.hi, self.lo)
    }
}
impl fmt::Display for DD {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.hi + self.lo)
    }
}
impl PartialOrd for DD {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        match self.hi.partial_cmp(&o.hi) {
            Some(std::cmp::Ordering::Equal) => self.lo.partial_cmp(&o.lo),
            x => x,
        }
    }
}

impl Add for DD {
    type Output = DD;
    #[inline(never)]
    fn add(self, b: DD) -> DD {
        let (s, e) = two_sum(self.hi, b.hi);
        if !s.is_finite() {
            return DD::f(s);
        }
        let (t, f) = two_sum(self.lo, b.lo);
        let (s, e) = quick_two_sum(s, e + t);
        DD::norm(s, e + f)
    }
}
impl Neg for DD {
    type Output = DD;
    #[inline]
    fn neg(self) -> DD {
        DD {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}
impl Sub for DD {
    type Output = DD;
    #[inline(never)]
    fn sub(self, b: DD) -> DD {
        self + (-b)
    }
}
impl Mul for DD {
    type Output = DD;
    #[inline(never)]
    fn mul(self, b: DD) -> DD {
        let (p, e) = two_prod(self.hi, b.hi);
        if !p.is_finite() {
            return DD::f(p);
        }
        DD::norm(p, e + (self.hi * b.lo + self.lo * b.hi))
    }
}
impl Div for DD {
    type Output = DD;
    #[inline(never)]
    fn div(self, b: DD) -> DD {
        let q1 = self.hi / b.hi;
        if !q1.is_finite() || b.hi == 0.0 {
            return DD::f(q1);
        }
        let r = self - b.mul_f64(q1);
        let q2 = r.hi / b.hi;
        let r = r - b.mul_f64(q2);
        let q3 = r.hi / b.hi;
        let (q1, q2) = quick_two_sum(q1, q2);
        DD { hi: q1, lo: q2 } + DD::f(q3)
    }
}
impl Rem for DD {
    type Output = DD;
    fn rem(self, b: DD) -> DD {
        let q = (self / b).trunc_dd();
        self - q * b
    }
}
impl DD {
    fn trunc_dd(self) -> DD {
        let h = self.hi.trunc();
        if h != self.hi {
            DD::f(h)
        } else {
            DD::norm(h, self.lo.trunc())
        }
    }
    fn floor_dd(self) -> DD {
        let h = self.hi.floor();
        if h != self.hi {
            DD::f(h)
        } else {
            DD::norm(h, self.lo.floor())
        }
    }
}
macro_rules! assign {
    ($t:ident, $f:ident, $op:tt) => {
        impl $t for DD {
            #[inline]
            fn $f(&mut self, b: DD) {
                *self = *self $op b;
            }
        }
    };
}
assign!(AddAssign, add_assign, +);
assign!(SubAssign, sub_assign, -);
assign!(MulAssign, mul_assign, *);
assign!(DivAssign, div_assign, /);
assign!(RemAssign, rem_assign, %);

impl Zero for DD {
    fn zero() -> Self {
        DD::f(0.0)
    }
    fn is_zero(&self) -> bool {
        self.hi == 0.0
    }
}
impl One for DD {
    fn one() -> Self {
        DD::f(1.0)
    }
}
impl Num for DD {
    type FromStrRadixErr = std::num::ParseFloatError;
    fn from_str_radix(s: &str, _radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        s.parse::<f64>().map(DD::f)
    }
}
impl Signed for DD {
    fn abs(&self) -> Self {
        if self.hi < 0.0 {
            -*self
        } else {
            *self
        }
    }
    fn abs_sub(&self, o: &Self) -> Self {
        if *self <= *o {
            DD::zero()
        } else {
            *self - *o
        }
    }
    fn signum(&self) -> Self {
        DD::f(self.hi.signum())
    }
    fn is_positive(&self) -> bool {
        self.hi > 0.0
    }
    fn is_negative(&self) -> bool {
        self.hi < 0.0
    }
}
impl FromPrimitive for DD {
    fn from_i64(n: i64) -> Option<Self> {
        let h = n as f64;
        Some(DD::norm(h, (n - h as i64) as f64))
    }
    fn from_u64(n: u64) -> Option<Self> {
        let h = n as f64;
        Some(DD::norm(h, (n as i128 - h as i128) as f64))
    }
    fn from_f64(x: f64) -> Option<Self> {
        Some(DD::f(x))
    }
    fn from_f32(x: f32) -> Option<Self> {
        Some(DD::f(x as f64))
    }
}

impl AbsDiffEq for DD {
    type Epsilon = DD;
    fn default_epsilon() -> DD {
        DD::f(f64::EPSILON * f64::EPSILON)
    }
    fn abs_diff_eq(&self, o: &Self, eps: DD) -> bool {
        (*self - *o).abs() <= eps
    }
}
impl RelativeEq for DD {
    fn default_max_relative() -> DD {
        DD::default_epsilon()
    }
    fn relative_eq(&self, o: &Self, eps: DD, max_rel: DD) -> bool {
        let d = (*self - *o).abs();
        d <= eps || d <= max_rel * self.abs().max(o.abs())
    }
}
impl UlpsEq for DD {
    fn default_max_ulps() -> u32 {
        4
    }
    fn ulps_eq(&self, o: &Self, eps: DD, _max_ulps: u32) -> bool {
        self.relative_eq(o, eps, DD::default_epsilon())
    }
}

impl SimdValue for DD {
    const LANES: usize = 1;
    type Element = DD;
    type SimdBool = bool;
    fn splat(v: DD) -> DD {
        v
    }
    fn extract(&self, _: usize) -> DD {
        *self
    }
    unsafe fn extract_unchecked(&self, _: usize) -> DD {
        *self
    }
    fn replace(&mut self, _: usize, v: DD) {
        *self = v
    }
    unsafe fn replace_unchecked(&mut self, _: usize, v: DD) {
        *self = v
    }
    fn select(self, cond: bool, other: DD) -> DD {
        if cond {
            self
        } else {
            other
        }
    }
}
impl Field for DD {}

impl simba::scalar::SubsetOf<DD> for DD {
    fn to_superset(&self) -> DD {
        *self
    }
    fn from_superset_unchecked(e: &DD) -> DD {
        *e
    }
    fn is_in_subset(_: &DD) -> bool {
        true
    }
}
impl simba::scalar::SubsetOf<DD> for f64 {
    fn to_superset(&self) -> DD {
        DD::f(*self)
    }
    fn from_superset_unchecked(e: &DD) -> f64 {
        e.to_f64()
    }
    fn is_in_subset(_: &DD) -> bool {
        true
    }
}
impl simba::scalar::SubsetOf<DD> for f32 {
    fn to_superset(&self) -> DD {
        DD::f(*self as f64)
    }
    fn from_superset_unchecked(e: &DD) -> f32 {
        e.to_f64() as f32
    }
    fn is_in_subset(_: &DD) -> bool {
        true
    }
}

/// f64 precision: a function of the leading part only.
macro_rules! lowprec {
    ($($name:ident),*) => {$(
        #[inline]
        fn $name(self) -> Self {
            DD::f(self.hi.$name())
        }
    )*};
}

impl ComplexField for DD {
    type RealField = DD;
    fn from_real(re: DD) -> Self {
        re
    }
    fn real(self) -> DD {
        self
    }
    fn imaginary(self) -> DD {
        DD::zero()
    }
    fn modulus(self) -> DD {
        Signed::abs(&self)
    }
    fn modulus_squared(self) -> DD {
        self * self
    }
    fn argument(self) -> DD {
        if self.hi >= 0.0 {
            DD::zero()
        } else {
            <DD as RealField>::pi()
        }
    }
    fn norm1(self) -> DD {
        Signed::abs(&self)
    }
    fn scale(self, f: DD) -> DD {
        self * f
    }
    fn unscale(self, f: DD) -> DD {
        self / f
    }
    fn floor(self) -> DD {
        self.floor_dd()
    }
    fn ceil(self) -> DD {
        -((-self).floor_dd())
    }
    fn round(self) -> DD {
        (self + DD::f(0.5)).floor_dd()
    }
    fn trunc(self) -> DD {
        self.trunc_dd()
    }
    fn fract(self) -> DD {
        self - self.trunc_dd()
    }
    fn mul_add(self, a: DD, b: DD) -> DD {
        self * a + b
    }
    fn abs(self) -> DD {
        Signed::abs(&self)
    }
    fn hypot(self, o: DD) -> DD {
        (self * self + o * o).sqrt_dd()
    }
    fn recip(self) -> DD {
        DD::one() / self
    }
    fn conjugate(self) -> DD {
        self
    }
    fn sin(self) -> DD {
        self.sin_cos_dd().0
    }
    fn cos(self) -> DD {
        self.sin_cos_dd().1
    }
    fn sin_cos(self) -> (DD, DD) {
        self.sin_cos_dd()
    }
    fn tan(self) -> DD {
        let (s, c) = self.sin_cos_dd();
        s / c
    }
    lowprec!(
        asin, acos, atan, sinh, cosh, tanh, asinh, acosh, atanh, log2, log10, ln, ln_1p, exp, exp2,
        exp_m1, cbrt
    );
    fn log(self, base: DD) -> DD {
        DD::f(self.hi.log(base.hi))
    }
    fn sqrt(self) -> DD {
        self.sqrt_dd()
    }
    fn powi(self, n: i32) -> DD {
        let mut r = DD::one();
        let mut b = if n < 0 { DD::one() / self } else { self };
        let mut k = n.unsigned_abs();
        while k > 0 {
            if k & 1 == 1 {
                r *= b;
            }
            b *= b;
            k >>= 1;
        }
        r
    }
    fn powf(self, n: DD) -> DD {
        DD::f(self.hi.powf(n.hi))
    }
    fn powc(self, n: DD) -> DD {
        self.powf(n)
    }
    fn is_finite(&self) -> bool {
        self.hi.is_finite() && self.lo.is_finite()
    }
    fn try_sqrt(self) -> Option<DD> {
        if self.hi >= 0.0 {
            Some(self.sqrt_dd())
        } else {
            None
        }
    }
}

macro_rules! consts {
    ($($name:ident = $hi:expr, $lo:expr;)*) => {$(
        fn $name() -> DD {
            DD { hi: $hi, lo: $lo }
        }
    )*};
}

impl RealField for DD {
    fn is_sign_positive(&self) -> bool {
        self.hi.is_sign_positive()
    }
    fn is_sign_negative(&self) -> bool {
        self.hi.is_sign_negative()
    }
    fn copysign(self, sign: DD) -> DD {
        if sign.hi.is_sign_negative() == self.hi.is_sign_negative() {
            self
        } else {
            -self
        }
    }
    fn max(self, o: DD) -> DD {
        if self >= o {
            self
        } else {
            o
        }
    }
    fn min(self, o: DD) -> DD {
        if self <= o {
            self
        } else {
            o
        }
    }
    fn clamp(self, lo: DD, hi: DD) -> DD {
        RealField::min(RealField::max(self, lo), hi)
    }
    fn atan2(self, o: DD) -> DD {
        DD::f(self.hi.atan2(o.hi))
    }
    fn min_value() -> Option<DD> {
        Some(DD::f(f64::MIN))
    }
    fn max_value() -> Option<DD> {
        Some(DD::f(f64::MAX))
    }
    consts! {
        pi = 3.141592653589793, 1.2246467991473532e-16;
        two_pi = 6.283185307179586, 2.4492935982947064e-16;
        frac_pi_2 = 1.5707963267948966, 6.123233995736766e-17;
        frac_pi_3 = 1.0471975511965979, -1.0720817664510912e-16;
        frac_pi_4 = 0.7853981633974483, 3.061616997868383e-17;
        frac_pi_6 = 0.5235987755982989, -5.360408832255456e-17;
        frac_pi_8 = 0.39269908169872414, 1.5308084989341915e-17;
        frac_1_pi = 0.3183098861837907, -1.9678676675182486e-17;
        frac_2_pi = 0.6366197723675814, -3.935735335036497e-17;
        frac_2_sqrt_pi = 1.1283791670955126, 1.533545961316588e-17;
        e = 2.718281828459045, 1.4456468917292502e-16;
        log2_e = 1.4426950408889634, 2.0355273740931033e-17;
        log10_e = 0.4342944819032518, 1.098319650216765e-17;
        ln_2 = 0.6931471805599453, 2.3190468138462996e-17;
        ln_10 = 2.302585092994046, -2.1707562233822494e-16;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dd_arithmetic_and_functions() {
        let third = DD::one() / DD::f(3.0);
        let back = third * DD::f(3.0) - DD::one();
        assert!(back.to_f64().abs() < 1e-31, "{back:?}");
        let two = DD::f(2.0).sqrt();
        assert!((two * two - DD::f(2.0)).to_f64().abs() < 1e-31);
        for x in [0.1, 0.7, 1.0, 2.5, -3.0, 10.0, 123.456, -1000.0] {
            let (s, c) = DD::f(x).sin_cos();
            let one = s * s + c * c - DD::one();
            assert!(one.to_f64().abs() < 1e-30, "{x}: {one:?}");
            assert!((s.to_f64() - x.sin()).abs() < 1e-15);
            assert!((c.to_f64() - x.cos()).abs() < 1e-15);
        }
        // sin(π/6) = 1/2 to double-double precision.
        let h = <DD as RealField>::frac_pi_6().sin() - DD::f(0.5);
        assert!(h.to_f64().abs() < 1e-31, "{h:?}");
    }
}
