//! Depth-only checks of a pose hypothesis against the latest depth image: the agreeing fraction of model points,
//! a depth-only refinement, the re-detection probe and the silhouette agreement.

use super::{ObjectTrack, TickInputs, add_prior};
use crate::geometry::PinholeCamera;
use crate::refine::{DepthTermStats, NormalEquations, StepBounds, apply_step, solve_step};
use crate::track::config::TrackerConfig;
use nalgebra::{Isometry3, Vector6};

impl ObjectTrack {
    /// Fraction of the model's visible points that agree with `self.depth_now` at `pose`, and the term's counts.
    pub(super) fn depth_fit_at(
        &self,
        pose: &Isometry3<f64>,
        roi_camera: &PinholeCamera,
        config: &TrackerConfig,
    ) -> (f64, DepthTermStats) {
        let mut scratch = NormalEquations::default();
        let s = config.depth_term.accumulate(
            &self.view,
            pose,
            &self.center_obj,
            roi_camera,
            &self.depth_now,
            &mut scratch,
        );
        (s.inliers as f64 / s.points.max(1) as f64, s)
    }

    /// Depth-only refinement from `start` against `self.depth_now` (what `depth30` does at a depth frame): the
    /// refined pose with its agreeing fraction and counts.
    pub(super) fn refine_on_depth(
        &self,
        start: Isometry3<f64>,
        roi_camera: &PinholeCamera,
        config: &TrackerConfig,
    ) -> (f64, Isometry3<f64>, DepthTermStats) {
        let bounds = StepBounds {
            max_rotation: config.max_step_rotation_deg.to_radians(),
            max_translation: config.max_step_translation_diameters * self.diameter,
        };
        let prior_t = 1.0 / (config.prior_translation_m * config.prior_translation_m);
        let prior_r = 1.0 / config.prior_rotation_rad().powi(2);
        let mut pose = start;
        let mut offset = Vector6::zeros();
        for _ in 0..config.iterations {
            let mut ne = NormalEquations::default();
            config.depth_term.accumulate(
                &self.view,
                &pose,
                &self.center_obj,
                roi_camera,
                &self.depth_now,
                &mut ne,
            );
            add_prior(&mut ne, &offset, prior_t, prior_r);
            let Some(step) = solve_step(&ne, config.damping, &bounds) else {
                break;
            };
            offset += step;
            pose = apply_step(&pose, &self.center_obj, &step);
        }
        let (fit, stats) = self.depth_fit_at(&pose, roi_camera, config);
        (fit, pose, stats)
    }

    /// Checks the hypothesis `self.predicted` against the fresh depth frame of `inputs` (re-detection): registers
    /// the frame around it and refines on depth only from it, using the render the caller made at it in
    /// `self.target`. Returns the agreeing fraction and the refined pose; `None` without a depth frame, ROI or
    /// visible model.
    pub fn probe_depth(
        &mut self,
        inputs: &TickInputs<'_>,
        config: &TrackerConfig,
    ) -> Option<(f64, Isometry3<f64>)> {
        let roi = self.roi?;
        let frame = inputs.depth?;
        let roi_camera = inputs.camera.crop(&roi);
        let start = self.predicted;
        self.view.extract(
            &self.target,
            &roi_camera,
            self.label,
            &start,
            config.max_surface_points,
            config.max_contour_points,
        );
        if self.view.surface.is_empty() {
            return None;
        }
        self.carry_depth_from(frame, inputs.depth_rig, inputs.t_us, config);
        self.carried
            .render(&start, &roi_camera, &mut self.depth_now);
        let (fit, pose, _) = self.refine_on_depth(start, &roi_camera, config);
        Some((fit, pose))
    }

    /// How well the silhouette in `self.target` (rendered at `pose`) matches what the fresh depth image in
    /// `self.depth_now` shows at the object's depth: pixels where model and measurement agree in depth, over
    /// pixels where either the model is or a measurement lies within half a diameter of the centre's depth (an
    /// intersection over union, in [0, 1]). Re-detection ranks places by it: unlike the agreeing fraction of model
    /// points, it stays low for a pose that shows only a small part of the object where the depth sees all of it.
    pub fn silhouette_agreement(&self, pose: &Isometry3<f64>, config: &TrackerConfig) -> f64 {
        let c = self.center_at(pose);
        let band = 0.5 * self.diameter;
        let noise = config.depth_term;
        let tolerance = 3.0 * (noise.sigma_0 + noise.sigma_z2 * c.z * c.z) + 0.005;
        let (mut agree, mut union) = (0usize, 0usize);
        let rendered = self.target.depth().iter().zip(self.target.mask());
        for (&zm, (&zr, &label)) in self.depth_now.z.iter().zip(rendered) {
            let model = label == self.label;
            let measured = zm > 0.0 && (f64::from(zm) - c.z).abs() < band;
            union += usize::from(model || measured);
            agree += usize::from(model && zm > 0.0 && f64::from((zm - zr).abs()) < tolerance);
        }
        agree as f64 / union.max(1) as f64
    }
}
