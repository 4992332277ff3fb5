//! A small deterministic generator shared by the tests (they need no rand
//! dependency): 64-bit LCG (Knuth's MMIX constants), top 53 bits as a uniform.

use nalgebra::DVector;

pub struct Lcg(pub u64);

#[allow(dead_code)] // each test binary uses its own subset
impl Lcg {
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
    pub fn vector(&mut self, n: usize, r: f64) -> DVector<f64> {
        DVector::from_fn(n, |_, _| self.uniform(-r, r))
    }
}
