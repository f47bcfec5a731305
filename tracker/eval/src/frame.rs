//! Scoring one pose estimate against ground truth: all errors and the per-frame recalls (the paper's per-frame AR).

use super::pose_error::{add, add_s, mspd, mssd};
use super::recall::{average_recall, mspd_recall, mssd_recall, vsd_recall, vsd_taus};
use super::vsd::VsdRenderer;
use nalgebra::{Isometry3, Point3};
use scene::geometry::PinholeCamera;
use scene::mesh::{Mesh, Symmetry};
use scene::render::RenderError;
use std::sync::Arc;
use tracker::recording::symmetry_transforms;

/// At most this many model vertices are used as metric points (BOP uses all vertices; larger meshes are thinned
/// with an even stride to keep evaluation time bounded).
pub const MAX_MODEL_POINTS: usize = 4000;

/// Coarse meshes (fewer vertices than this) get seeded area-uniform surface samples added to their vertices up
/// to this count: BOP's models are dense, and on a low-poly mesh a nearest-vertex ADD-S degenerates into ADD.
pub const MIN_MODEL_POINTS: usize = 1000;

/// An object model prepared for evaluation.
#[derive(Debug, Clone)]
pub struct EvalModel {
    /// Object name.
    pub name: String,
    /// Diameter, metres (from `models_info.json`).
    pub diameter: f64,
    /// Metric points: mesh vertices (plus surface samples on coarse meshes), object frame, metres.
    pub points: Vec<Point3<f64>>,
    /// Symmetry transforms including identity, object frame (see [`symmetry_transforms`]).
    pub symmetries: Vec<Isometry3<f64>>,
    /// The mesh, for VSD rendering.
    pub mesh: Arc<Mesh>,
}

impl EvalModel {
    /// Prepares `mesh` with the given diameter (metres) and declared symmetries; metric points as described at
    /// [`MAX_MODEL_POINTS`] and [`MIN_MODEL_POINTS`].
    pub fn new(name: &str, mesh: Arc<Mesh>, diameter: f64, symmetries: &[Symmetry]) -> Self {
        let verts = mesh.positions();
        let stride = verts.len().div_ceil(MAX_MODEL_POINTS).max(1);
        let mut points: Vec<Point3<f64>> = verts
            .iter()
            .step_by(stride)
            .map(|p| Point3::new(p.x as f64, p.y as f64, p.z as f64))
            .collect();
        if points.len() < MIN_MODEL_POINTS {
            let extra = mesh.sample_surface_seeded(MIN_MODEL_POINTS - points.len(), 0x5eed);
            points.extend(extra.iter().map(|s| s.position));
        }
        Self {
            name: name.to_string(),
            diameter,
            points,
            symmetries: symmetry_transforms(symmetries),
            mesh,
        }
    }
}

/// All errors of one estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseErrors {
    /// ADD, metres.
    pub add: f64,
    /// ADD-S, metres.
    pub add_s: f64,
    /// MSSD, metres.
    pub mssd: f64,
    /// MSPD, pixels of the evaluation camera (unscaled).
    pub mspd_px: f64,
    /// VSD error at each tau of [`vsd_taus`], unitless 0-1.
    pub vsd: Vec<f64>,
}

impl PoseErrors {
    /// The errors of a missing estimate: every distance infinite, every VSD error 1.
    pub fn missing() -> Self {
        Self {
            add: f64::INFINITY,
            add_s: f64::INFINITY,
            mssd: f64::INFINITY,
            mspd_px: f64::INFINITY,
            vsd: vec![1.0; vsd_taus().len()],
        }
    }
}

/// The score of one evaluated frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameScore {
    /// Evaluation time, microseconds.
    pub t_us: i64,
    /// Whether the frame is a depth-exposure tick (evaluated in the 30 Hz protocol).
    pub depth_tick: bool,
    /// The errors.
    pub errors: PoseErrors,
    /// VSD recall, 0-1.
    pub recall_vsd: f64,
    /// MSSD recall, 0-1.
    pub recall_mssd: f64,
    /// MSPD recall, 0-1.
    pub recall_mspd: f64,
    /// AR of this frame: mean of the three recalls, 0-1.
    pub ar: f64,
}

/// The cameras a recording's poses are evaluated in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvalCameras {
    /// The camera the poses are expressed in (MSPD projects into it), the event camera.
    pub pose_camera: PinholeCamera,
    /// The depth camera (VSD renders into it).
    pub depth_camera: PinholeCamera,
    /// `T_depth_pose`: maps pose-camera coordinates into the depth camera frame, metres.
    pub depth_from_pose: Isometry3<f64>,
}

/// Scores poses of one object: holds the model, the cameras and a VSD renderer.
pub struct FrameEvaluator {
    model: EvalModel,
    cameras: EvalCameras,
    vsd: VsdRenderer,
}

impl FrameEvaluator {
    /// An evaluator of `model` seen through `cameras`.
    pub fn new(model: EvalModel, cameras: EvalCameras) -> Result<Self, RenderError> {
        let vsd = VsdRenderer::new(model.mesh.clone())?;
        Ok(Self {
            model,
            cameras,
            vsd,
        })
    }

    /// The model.
    pub fn model(&self) -> &EvalModel {
        &self.model
    }

    /// Every error of `est` (None = no estimate) against `gt`, both `T_cam_obj` in the pose camera; `depth_test` is
    /// the measured depth image of the depth camera (metres, 0 = none) or None to use the ground-truth render.
    pub fn errors(
        &mut self,
        est: Option<&Isometry3<f64>>,
        gt: &Isometry3<f64>,
        depth_test: Option<&[f32]>,
    ) -> Result<PoseErrors, RenderError> {
        let Some(est) = est else {
            return Ok(PoseErrors::missing());
        };
        let m = &self.model;
        let c = &self.cameras;
        let vsd = self.vsd.vsd(
            &(c.depth_from_pose * est),
            &(c.depth_from_pose * gt),
            depth_test,
            &c.depth_camera,
            m.diameter,
        )?;
        Ok(PoseErrors {
            add: add(est, gt, &m.points),
            add_s: add_s(est, gt, &m.points),
            mssd: mssd(est, gt, &m.points, &m.symmetries),
            mspd_px: mspd(est, gt, &c.pose_camera, &m.points, &m.symmetries),
            vsd,
        })
    }

    /// Scores one frame at `t_us` (see [`FrameEvaluator::errors`]).
    pub fn score(
        &mut self,
        t_us: i64,
        depth_tick: bool,
        est: Option<&Isometry3<f64>>,
        gt: &Isometry3<f64>,
        depth_test: Option<&[f32]>,
    ) -> Result<FrameScore, RenderError> {
        let errors = self.errors(est, gt, depth_test)?;
        Ok(score_errors(
            t_us,
            depth_tick,
            errors,
            self.model.diameter,
            self.cameras.pose_camera.width,
        ))
    }
}

/// Turns errors into a frame score: BOP recalls with MSSD thresholds scaled by `diameter` (metres) and MSPD errors
/// scaled by `640 / image_width`.
pub fn score_errors(
    t_us: i64,
    depth_tick: bool,
    errors: PoseErrors,
    diameter: f64,
    image_width: u32,
) -> FrameScore {
    let recall_vsd = vsd_recall(&errors.vsd);
    let recall_mssd = mssd_recall(errors.mssd, diameter);
    let recall_mspd = mspd_recall(errors.mspd_px, image_width);
    FrameScore {
        t_us,
        depth_tick,
        recall_vsd,
        recall_mssd,
        recall_mspd,
        ar: average_recall(recall_vsd, recall_mssd, recall_mspd),
        errors,
    }
}
