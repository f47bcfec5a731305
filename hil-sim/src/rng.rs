//! A small, fast, deterministic random generator for simulation (same seed, same stream on every machine).

use nalgebra::Vector3;
use std::f64::consts::TAU;

/// A small deterministic generator (xorshift64*), enough for choosing trajectory parameters.
#[derive(Debug, Clone)]
pub struct SeedRng(u64);

impl SeedRng {
    /// From a seed (any value).
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03 | 1)
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    }

    /// A uniformly distributed unit vector.
    pub fn unit_vector(&mut self) -> Vector3<f64> {
        let v = Vector3::new(self.normal(), self.normal(), self.normal());
        let n = v.norm();
        if n < 1e-9 { Vector3::z() } else { v / n }
    }
}
