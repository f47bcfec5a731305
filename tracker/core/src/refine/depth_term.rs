//! The depth modality: robust, occlusion-aware point-to-plane residuals between the model's visible surface at
//! the hypothesis and the reconstructed depth `D_t` (projective association in the ROI camera).

use super::modality::Modality;
use super::model_view::ModelView;
use super::normal_equations::NormalEquations;
use crate::recon::DepthImage;
use nalgebra::{Isometry3, Vector3};
use scene::geometry::PinholeCamera;

/// Parameters of the depth term.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields, default)]
pub struct DepthTerm {
    /// Noise model `sigma(z) = sigma_0 + sigma_z2 * z^2`, metres: constant part.
    pub sigma_0: f64,
    /// Quadratic part, 1/metre.
    pub sigma_z2: f64,
    /// A measurement nearer than the model by more than this (metres) is an occluder: the point is skipped.
    pub occlusion_gap: f64,
    /// Residuals beyond this (metres) are outliers (weight 0).
    pub max_residual: f64,
}

impl Default for DepthTerm {
    fn default() -> Self {
        Self {
            sigma_0: 0.0015,
            sigma_z2: 0.0025,
            occlusion_gap: 0.025,
            max_residual: 0.03,
        }
    }
}

/// What the depth term saw in one evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DepthTermStats {
    /// Model points considered.
    pub points: usize,
    /// Points with a measurement behind no occluder (used).
    pub measured: usize,
    /// Points hidden by a nearer measurement (occluder).
    pub occluded: usize,
    /// Used points whose residual is within two sigma.
    pub inliers: usize,
}

impl DepthTerm {
    /// Accumulates the residuals of `view` at `pose` against `depth` (seen by `camera`) into `ne`; `center_obj` is
    /// the object centre (object frame) the increment rotates about.
    pub fn accumulate(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        depth: &DepthImage,
        ne: &mut NormalEquations,
    ) -> DepthTermStats {
        self.evaluate(view, pose, camera, depth, Some((center_obj, ne)))
    }

    /// The counts [`Self::accumulate`] returns for `view` at `pose`, without building the equations.
    pub fn stats(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        depth: &DepthImage,
    ) -> DepthTermStats {
        self.evaluate(view, pose, camera, depth, None)
    }

    /// The counts, and with `equations` (the increment's centre, object frame, and where to add) the residuals.
    fn evaluate(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        depth: &DepthImage,
        equations: Option<(&Vector3<f64>, &mut NormalEquations)>,
    ) -> DepthTermStats {
        let mut stats = DepthTermStats {
            points: view.surface.len(),
            ..DepthTermStats::default()
        };
        let mut equations =
            equations.map(|(center, ne)| (pose * nalgebra::Point3::from(*center), ne));
        // One rotation matrix per evaluation: cheaper per point than rotating by the quaternion twice.
        let rotation = pose.rotation.to_rotation_matrix();
        let rotation = rotation.matrix();
        let translation = pose.translation.vector;
        let (ifx, ify) = (1.0 / camera.fx, 1.0 / camera.fy);
        for sp in &view.surface {
            let p = nalgebra::Point3::from(rotation * sp.position.coords + translation);
            if p.z <= 0.01 {
                continue;
            }
            let iz = 1.0 / p.z;
            let u = (camera.fx * p.x * iz + camera.cx).round() as i32;
            let v = (camera.fy * p.y * iz + camera.cy).round() as i32;
            let zm = f64::from(depth.at(u, v));
            if zm <= 0.0 {
                continue;
            }
            if zm < p.z - self.occlusion_gap {
                stats.occluded += 1;
                continue;
            }
            let n = rotation * sp.normal;
            let pm = nalgebra::Point3::new(
                (f64::from(u) - camera.cx) * ifx * zm,
                (f64::from(v) - camera.cy) * ify * zm,
                zm,
            );
            let r = n.dot(&(pm - p));
            stats.measured += 1;
            if r.abs() > self.max_residual {
                continue;
            }
            let sigma = self.sigma_0 + self.sigma_z2 * p.z * p.z;
            if r.abs() < 2.0 * sigma {
                stats.inliers += 1;
            }
            let Some((c, ne)) = equations.as_mut() else {
                continue;
            };
            // Huber weight at 1.5 sigma.
            let k = 1.5 * sigma;
            let robust = if r.abs() <= k { 1.0 } else { k / r.abs() };
            ne.add_point(&(-n), &(p - *c), r, robust / (sigma * sigma));
        }
        stats
    }
}

/// The depth term as a [`Modality`] for one refinement: the model's surface against `depth`, an image in
/// `camera` (the ROI's), with the counts of its latest accumulation.
#[derive(Debug)]
pub struct DepthModality<'a> {
    /// Whether it takes part in this refinement.
    pub active: bool,
    /// Parameters.
    pub term: &'a DepthTerm,
    /// The camera `depth` is an image of.
    pub camera: &'a PinholeCamera,
    /// The depth the model is compared with (`D_t`).
    pub depth: &'a DepthImage,
    /// Scale of the term in the sum (1 at a fresh depth frame, less for carried depth).
    pub weight: f64,
    /// The counts of the latest accumulation; `None` before the first.
    pub stats: Option<DepthTermStats>,
}

impl Modality for DepthModality<'_> {
    fn name(&self) -> &'static str {
        "depth"
    }

    fn is_active(&self) -> bool {
        self.active
    }

    fn weight(&self) -> f64 {
        self.weight
    }

    /// Depth points match by projection at every accumulation: nothing to do here.
    fn correspond(&mut self, _view: &ModelView, _pose: &Isometry3<f64>) {}

    fn accumulate(
        &mut self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        ne: &mut NormalEquations,
    ) {
        self.stats =
            Some(
                self.term
                    .accumulate(view, pose, center_obj, self.camera, self.depth, ne),
            );
    }
}
