//! The speculative margin: a shape is searched within max(δ, c·s) of what it
//! can touch, s the distance it travelled in the last step (docs/theory.md
//! §"Speculative margin"). A shape that moves less than δ/c a step keeps δ.

use super::ContactParams;
use crate::spatial::Se3;
use nalgebra::Vector3;

/// Each shape's travel in the last step, and when the next detection
/// measures it.
#[derive(Clone, Debug)]
pub(crate) struct Travel {
    delta: f64,
    factor: f64,
    /// Per shape: its travel in the last step (0: static; NaN: not measured).
    s: Vec<f64>,
    fixed: Vec<bool>,
    /// The shapes' last poses are a detection's.
    posed: bool,
    /// > 0: the next detection follows a step, its travel scaled by this.
    stepped: f64,
}

impl Travel {
    /// The travel of shapes that are static where `fixed` says so.
    pub fn new(params: &ContactParams, fixed: Vec<bool>) -> Self {
        let mut t = Self {
            delta: params.margin,
            factor: params.travel_factor,
            s: Vec::new(),
            fixed,
            posed: false,
            stepped: 0.0,
        };
        t.forget();
        t
    }

    /// Back to the start: no travel measured, no pose held.
    pub fn forget(&mut self) {
        self.s = self
            .fixed
            .iter()
            .map(|&f| if f { 0.0 } else { f64::NAN })
            .collect();
        self.posed = false;
        self.stepped = 0.0;
    }

    /// The next detection follows a step (`scale`: the next step's length
    /// over this one's).
    pub fn stepped(&mut self, scale: f64) {
        self.stepped = scale;
    }

    /// A detection starts: the scale of the travel it measures (0: none,
    /// it does not follow a step or no pose is held); the poses it leaves
    /// are held.
    pub fn begin(&mut self) -> f64 {
        let scale = std::mem::take(&mut self.stepped);
        let posed = std::mem::replace(&mut self.posed, true);
        if posed {
            scale
        } else {
            0.0
        }
    }

    /// Whether the travel changes any margin: with the factor c = 0 (and
    /// δ ≥ 0) max(δ, c·s) is δ whatever s is, so the travel need not be
    /// measured (a URDF world's, a scene's: the margin is δ).
    #[inline]
    pub fn measures(&self) -> bool {
        self.factor != 0.0 || !(self.delta >= 0.0)
    }

    /// Every shape's travel (to be written apart: a detection on several
    /// threads, each its own shapes'), with δ and c: shape k's margin is
    /// [`margin`]`(δ, c, s[k])`.
    #[inline]
    pub fn split(&mut self) -> (&mut [f64], f64, f64) {
        (&mut self.s, self.delta, self.factor)
    }

    /// The margin of the pair of shapes `a` and `b`: max(δ, c·(s_a + s_b)).
    #[inline]
    pub fn pair_margin(&self, a: usize, b: usize) -> f64 {
        let s = |k: usize| self.s.get(k).copied().unwrap_or(0.0);
        margin(self.delta, self.factor, s(a) + s(b))
    }
}

/// The margin of a shape (or pair) that travelled `s` in the last step:
/// max(δ, c·s); δ when `s` is unknown (NaN: no step measured yet).
#[inline]
pub(crate) fn margin(delta: f64, c: f64, s: f64) -> f64 {
    let m = c * s;
    if m > delta {
        m
    } else {
        delta
    }
}

/// The farthest any point within `radius` of `mid` (a shape's frame) moved
/// from the pose `w0` to `w`: |Δc| + ‖R − R₀‖₂·radius, where for two
/// rotations ‖R − R₀‖₂ = 2 sin(θ/2) = ‖R − R₀‖_F/√2 (θ the angle of R R₀ᵀ).
#[inline]
pub(crate) fn moved(w0: &Se3<f64>, w: &Se3<f64>, mid: &Vector3<f64>, radius: f64) -> f64 {
    (w.act_point(mid) - w0.act_point(mid)).norm()
        + (w.rot - w0.rot).norm() * std::f64::consts::FRAC_1_SQRT_2 * radius
}

/// [`moved`] of a shape whose point `mid` was at `c0` (pose `w0`) and is at
/// `c` (pose `w`): the same value, from the points already placed.
#[inline]
pub(crate) fn moved_from(
    c0: &Vector3<f64>,
    c: &Vector3<f64>,
    w0: &Se3<f64>,
    w: &Se3<f64>,
    radius: f64,
) -> f64 {
    (c - c0).norm() + (w.rot - w0.rot).norm() * std::f64::consts::FRAC_1_SQRT_2 * radius
}

/// The farthest any point within `radius` of a point p of a body moved down
/// (−z): from (z₀, r₀) to (z, r), z the height of p and r the third row of
/// the body's rotation: z₀ − z + |r − r₀|·radius (the height of x is
/// r·x + t_z, so its change is Δr·(x − p) + Δz).
#[inline]
pub(crate) fn dropped(then: &[f64; 4], z: f64, r: [f64; 3], radius: f64) -> f64 {
    let d = [r[0] - then[1], r[1] - then[2], r[2] - then[3]];
    then[0] - z + (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * radius
}
