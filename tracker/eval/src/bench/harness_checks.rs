//! The harness's own checks, run beside the trackers: `static` (the first pose held: the floor any tracker must
//! beat) and `gt-noise` (ground truth with seeded Gaussian noise: scores must fall as the noise grows).

use super::method::{Method, MethodInput};
use crate::sequence::EvalError;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tracker::recording::PoseRecord;

/// Holds the first pose forever: the floor any tracker must beat.
#[derive(Debug, Clone, Default)]
pub struct StaticMethod;

impl Method for StaticMethod {
    fn name(&self) -> &str {
        "static"
    }
    fn track(&mut self, input: &MethodInput<'_>) -> Result<Vec<PoseRecord>, EvalError> {
        let (t0, pose) = input.first_pose;
        Ok(input
            .ticks
            .iter()
            .filter(|t| t.t_us >= t0)
            .map(|t| record(t.t_us, input.object, pose, 1.0))
            .collect())
    }
}

/// Ground truth at every tick plus independent Gaussian noise: translation with `sigma_m` metres per axis and a
/// rotation by an axis-angle vector with `sigma_rad` radians per component. Seeded: repeatable.
#[derive(Debug, Clone)]
pub struct GtNoiseMethod {
    name: String,
    /// Translation noise standard deviation per axis, metres.
    pub sigma_m: f64,
    /// Rotation noise standard deviation per axis-angle component, radians.
    pub sigma_rad: f64,
    seed: u64,
}

impl GtNoiseMethod {
    /// Default noise: 5 mm, 2 degrees.
    pub const DEFAULT_MM: f64 = 5.0;
    /// Default rotation noise, degrees.
    pub const DEFAULT_DEG: f64 = 2.0;

    /// A method adding `sigma_mm` millimetres and `sigma_deg` degrees of noise; `name` is its report name.
    pub fn new(name: &str, sigma_mm: f64, sigma_deg: f64, seed: u64) -> Self {
        Self {
            name: name.into(),
            sigma_m: sigma_mm / 1000.0,
            sigma_rad: sigma_deg.to_radians(),
            seed,
        }
    }
}

fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    // Box-Muller.
    let u1: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn name_hash(s: &str) -> u64 {
    // FNV-1a: a stable per-object seed offset.
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

impl Method for GtNoiseMethod {
    fn name(&self) -> &str {
        &self.name
    }
    fn track(&mut self, input: &MethodInput<'_>) -> Result<Vec<PoseRecord>, EvalError> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ name_hash(input.object));
        let mut out = Vec::with_capacity(input.ticks.len());
        for t in input.ticks {
            let Some(gt) = input.oracle.interpolated_at(t.t_us) else {
                continue;
            };
            let dt = Vector3::from_fn(|_, _| gaussian(&mut rng) * self.sigma_m);
            let dr = Vector3::from_fn(|_, _| gaussian(&mut rng) * self.sigma_rad);
            let noisy = Isometry3::from_parts(
                Translation3::from(gt.translation.vector + dt),
                UnitQuaternion::from_scaled_axis(dr) * gt.rotation,
            );
            out.push(record(t.t_us, input.object, noisy, 1.0));
        }
        Ok(out)
    }
}

fn record(t_us: i64, object: &str, pose: Isometry3<f64>, quality: f64) -> PoseRecord {
    PoseRecord {
        t_us,
        object: object.into(),
        pose,
        quality,
        state: "tracking".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_has_unit_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let xs: Vec<f64> = (0..20000).map(|_| gaussian(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }
}
