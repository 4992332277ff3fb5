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

    /// Shape `k` travelled `s` in the last step.
    #[inline]
    pub fn set(&mut self, k: usize, s: f64) {
        if let Some(x) = self.s.get_mut(k) {
            *x = s;
        }
    }

    /// Shape `k`'s margin, max(δ, c·s).
    #[inline]
    pub fn margin(&self, k: usize) -> f64 {
        margin(
            self.delta,
            self.factor,
            self.s.get(k).copied().unwrap_or(0.0),
        )
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

/// The farthest any point within `radius` of a point p of a body moved down
/// (−z): from (z₀, r₀) to (z, r), z the height of p and r the third row of
/// the body's rotation: z₀ − z + |r − r₀|·radius (the height of x is
/// r·x + t_z, so its change is Δr·(x − p) + Δz).
#[inline]
pub(crate) fn dropped(then: &[f64; 4], z: f64, r: [f64; 3], radius: f64) -> f64 {
    let d = [r[0] - then[1], r[1] - then[2], r[2] - then[3]];
    then[0] - z + (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * radius
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3, Unit};

    #[test]
    fn the_margin_grows_only_past_delta() {
        assert_eq!(margin(0.005, 2.0, f64::NAN), 0.005);
        assert_eq!(margin(0.005, 2.0, 0.0025), 0.005);
        assert_eq!(margin(0.005, 2.0, -1.0), 0.005);
        assert_eq!(margin(0.005, 2.0, 0.004), 0.008);
    }

    #[test]
    fn moved_and_dropped_bound_every_point() {
        // random poses: no point within the radius moves farther (or further
        // down) than the bounds, and a point on the sphere comes close to them
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..200 {
            let pose = |rnd: &mut dyn FnMut() -> f64| {
                let axis = Unit::new_normalize(Vector3::new(rnd(), rnd(), rnd()));
                let r: Matrix3<f64> = Rotation3::from_axis_angle(&axis, 3.0 * rnd()).into_inner();
                Se3::new(r, Vector3::new(rnd(), rnd(), rnd()))
            };
            let (w0, w) = (pose(&mut rnd), pose(&mut rnd));
            let mid = Vector3::new(rnd(), rnd(), rnd()) * 0.3;
            let radius = 0.2;
            let m = moved(&w0, &w, &mid, radius);
            let p0 = w0.act_point(&mid);
            let p = w.act_point(&mid);
            let then = [p0.z, w0.rot[(2, 0)], w0.rot[(2, 1)], w0.rot[(2, 2)]];
            let down = dropped(
                &then,
                p.z,
                [w.rot[(2, 0)], w.rot[(2, 1)], w.rot[(2, 2)]],
                radius,
            );
            for _ in 0..400 {
                let u = Vector3::new(rnd(), rnd(), rnd());
                let x = mid + u.normalize() * radius * rnd().abs();
                let dx = w.act_point(&x) - w0.act_point(&x);
                assert!(dx.norm() <= m + 1e-12, "{} > {m}", dx.norm());
                assert!(-dx.z <= down + 1e-12, "{} > {down}", -dx.z);
            }
            // the bound on the drop is reached: at p − radius·Δr/|Δr|
            let dr = w.rot.row(2) - w0.rot.row(2);
            let x = mid - dr.transpose().normalize() * radius;
            let dx = w.act_point(&x) - w0.act_point(&x);
            assert!((-dx.z - down).abs() < 1e-12, "{} {down}", -dx.z);
        }
    }
}
