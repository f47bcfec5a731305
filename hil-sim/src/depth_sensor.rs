//! A RealSense-like depth sensor: depth rendered at the exposure, axial noise growing with depth squared,
//! 1 mm quantisation, invalid pixels at depth discontinuities and out of range, optional dropped frames.
//!
//! Stereo depth error: `sigma(z) = z^2 * subpixel / (focal_px * baseline)` (Intel's RMS-error model for the
//! D400 series; D435i: baseline 50 mm, subpixel about 0.08).

use crate::rng::SeedRng;

/// Parameters of the depth sensor model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthSensorModel {
    /// Focal length of the depth image, pixels.
    pub focal_px: f64,
    /// Stereo baseline, metres.
    pub baseline_m: f64,
    /// RMS disparity error, pixels.
    pub subpixel: f64,
    /// Closest measurable depth, metres.
    pub min_range_m: f64,
    /// Farthest measurable depth, metres.
    pub max_range_m: f64,
    /// A pixel whose 4-neighbour differs in depth by more than `edge_fraction * z` is invalid (stereo fails at
    /// depth discontinuities).
    pub edge_fraction: f64,
    /// Probability that a whole frame is dropped (not delivered).
    pub frame_drop_probability: f64,
}

impl DepthSensorModel {
    /// The D435i at 848x480 (focal length about 425 px at 87 degrees horizontal field of view).
    pub fn d435i(focal_px: f64) -> Self {
        Self {
            focal_px,
            baseline_m: 0.050,
            subpixel: 0.08,
            min_range_m: 0.2,
            max_range_m: 6.0,
            edge_fraction: 0.04,
            frame_drop_probability: 0.0,
        }
    }

    /// Standard deviation of the depth error at `z_m`, metres.
    pub fn sigma_m(&self, z_m: f64) -> f64 {
        z_m * z_m * self.subpixel / (self.focal_px * self.baseline_m)
    }

    /// Whether the frame is dropped (draws from `rng`).
    pub fn drops_frame(&self, rng: &mut SeedRng) -> bool {
        self.frame_drop_probability > 0.0 && rng.uniform() < self.frame_drop_probability
    }

    /// Turns rendered depth (metres, 0 = no surface, row-major `width x height`) into what the sensor reports,
    /// in millimetres (0 = invalid).
    pub fn measure(
        &self,
        depth_m: &[f32],
        width: u32,
        height: u32,
        rng: &mut SeedRng,
        out_mm: &mut Vec<u16>,
    ) {
        let (w, h) = (width as usize, height as usize);
        out_mm.clear();
        out_mm.resize(w * h, 0);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let z = f64::from(depth_m[i]);
                if !(z >= self.min_range_m && z <= self.max_range_m) {
                    continue;
                }
                let tol = self.edge_fraction * z;
                let neighbours = [
                    (x > 0).then(|| i - 1),
                    (x + 1 < w).then(|| i + 1),
                    (y > 0).then(|| i - w),
                    (y + 1 < h).then(|| i + w),
                ];
                let edge = neighbours
                    .iter()
                    .flatten()
                    .any(|&j| (f64::from(depth_m[j]) - z).abs() > tol);
                if edge {
                    continue;
                }
                let noisy = z + self.sigma_m(z) * rng.normal();
                out_mm[i] = (noisy * 1000.0).round().clamp(1.0, 65535.0) as u16;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_statistics_match_the_model() {
        let m = DepthSensorModel::d435i(425.0);
        let mut rng = SeedRng::new(5);
        for z in [0.5f32, 1.0, 2.0] {
            let depth = vec![z; 200 * 200];
            let mut out = Vec::new();
            m.measure(&depth, 200, 200, &mut rng, &mut out);
            let vals: Vec<f64> = out.iter().map(|&u| f64::from(u) * 1e-3).collect();
            let n = vals.len() as f64;
            let mean = vals.iter().sum::<f64>() / n;
            let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
            let expect = m.sigma_m(f64::from(z));
            // Quantisation adds 1/12 mm^2 of variance.
            let expect_q = (expect * expect + 1e-6 / 12.0).sqrt();
            assert!((mean - f64::from(z)).abs() < 3e-4, "z {z}: mean {mean}");
            assert!(
                (sd / expect_q - 1.0).abs() < 0.05,
                "z {z}: sd {sd} vs model {expect_q}"
            );
        }
        // Depth squared: 4x the error at twice the distance.
        assert!((m.sigma_m(2.0) / m.sigma_m(1.0) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn discontinuities_and_out_of_range_are_invalid() {
        let m = DepthSensorModel::d435i(425.0);
        let mut rng = SeedRng::new(1);
        // Left half at 0.6 m, right half at 1.2 m, one pixel too close and one too far.
        let mut depth = vec![0.6f32; 10 * 4];
        for y in 0..4 {
            for x in 5..10 {
                depth[y * 10 + x] = 1.2;
            }
        }
        depth[0] = 0.1;
        depth[39] = 9.0;
        let mut out = Vec::new();
        m.measure(&depth, 10, 4, &mut rng, &mut out);
        assert_eq!(out[0], 0);
        assert_eq!(out[39], 0);
        for y in 0..4 {
            assert_eq!(out[y * 10 + 4], 0, "edge pixel left of the step");
            assert_eq!(out[y * 10 + 5], 0, "edge pixel right of the step");
            assert!(out[y * 10 + 2] > 550 && out[y * 10 + 2] < 650);
        }
    }
}
