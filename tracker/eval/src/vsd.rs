//! Visible Surface Discrepancy (BOP `pose_error.vsd`) with the BOP 2019 visibility masks
//! (`visibility.estimate_visib_mask_gt/_est`, `visib_mode = "bop19"`).
//!
//! Depth images are row-major, metres along the optical axis, 0 = no measurement / nothing rendered.

use super::recall::{VSD_DELTA, vsd_taus};
use nalgebra::Isometry3;
use scene::geometry::PinholeCamera;
use scene::mesh::Mesh;
use scene::render::{CpuRenderer, MeshId, RenderError, RenderTarget, Renderer, Scene, SceneObject};
use std::sync::Arc;

/// Converts a depth image (metres along z) into distances from the camera centre (BOP
/// `misc.depth_im_to_dist_im_fast`), metres; 0 stays 0.
pub fn depth_to_distance(depth: &[f32], camera: &PinholeCamera) -> Vec<f32> {
    let w = camera.width as usize;
    depth
        .iter()
        .enumerate()
        .map(|(i, &d)| {
            if d <= 0.0 {
                return 0.0;
            }
            let x = ((i % w) as f64 - camera.cx) / camera.fx;
            let y = ((i / w) as f64 - camera.cy) / camera.fy;
            (d as f64 * (x * x + y * y + 1.0).sqrt()) as f32
        })
        .collect()
}

/// BOP 2019 visibility of a model distance image against the test distance image: a pixel is visible where the
/// model has a surface and it is not more than `delta` behind the test surface, or the test has no measurement.
fn visible(d_test: f32, d_model: f32, delta: f32) -> bool {
    d_model > 0.0 && (d_model - d_test <= delta || d_test == 0.0)
}

/// VSD errors (unitless, 0-1) for each of `taus` (fractions of `diameter`), step cost, from distance images of the
/// test scene, the estimate and the ground truth (same size). With no visible pixel at all every error is 1.
pub fn vsd_from_distances(
    dist_test: &[f32],
    dist_est: &[f32],
    dist_gt: &[f32],
    diameter: f64,
    taus: &[f64],
) -> Vec<f64> {
    let delta = VSD_DELTA as f32;
    let mut union = 0usize;
    let mut inter_dists = Vec::new();
    for ((&t, &e), &g) in dist_test.iter().zip(dist_est).zip(dist_gt) {
        let vis_gt = visible(t, g, delta);
        let vis_est = visible(t, e, delta) || (vis_gt && e > 0.0);
        if vis_gt || vis_est {
            union += 1;
        }
        if vis_gt && vis_est {
            inter_dists.push((g as f64 - e as f64).abs() / diameter);
        }
    }
    if union == 0 {
        return vec![1.0; taus.len()];
    }
    let complement = union - inter_dists.len();
    taus.iter()
        .map(|tau| {
            let costs = inter_dists.iter().filter(|d| **d >= *tau).count();
            (costs + complement) as f64 / union as f64
        })
        .collect()
}

/// Renders an object's depth for VSD with the project's CPU renderer, reusing its buffers.
pub struct VsdRenderer {
    renderer: CpuRenderer,
    mesh: MeshId,
    target: RenderTarget,
}

impl VsdRenderer {
    /// A renderer of `mesh` (object frame, metres).
    pub fn new(mesh: Arc<Mesh>) -> Result<Self, RenderError> {
        let mut renderer = CpuRenderer::new();
        let mesh = renderer.add_mesh(mesh)?;
        Ok(Self {
            renderer,
            mesh,
            target: RenderTarget::new(),
        })
    }

    /// Depth (metres, 0 = background) of the object at `pose` (`T_cam_obj`) seen by `camera`.
    pub fn depth(
        &mut self,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) -> Result<Vec<f32>, RenderError> {
        let objects = [SceneObject {
            mesh: self.mesh,
            pose: *pose,
            id: 1,
        }];
        self.renderer
            .render(&Scene::objects(&objects), camera, &mut self.target)?;
        Ok(self.target.depth().to_vec())
    }

    /// VSD errors at the BOP taus ([`vsd_taus`]) of `est` against `gt` in the test depth image `depth_test`
    /// (metres along z, `camera`'s size; `None` = no measured depth, the ground-truth render stands in).
    pub fn vsd(
        &mut self,
        est: &Isometry3<f64>,
        gt: &Isometry3<f64>,
        depth_test: Option<&[f32]>,
        camera: &PinholeCamera,
        diameter: f64,
    ) -> Result<Vec<f64>, RenderError> {
        let d_est = self.depth(est, camera)?;
        let d_gt = self.depth(gt, camera)?;
        let dist_est = depth_to_distance(&d_est, camera);
        let dist_gt = depth_to_distance(&d_gt, camera);
        let dist_test = match depth_test {
            Some(d) => depth_to_distance(d, camera),
            None => dist_gt.clone(),
        };
        Ok(vsd_from_distances(
            &dist_test,
            &dist_est,
            &dist_gt,
            diameter,
            &vsd_taus(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_surfaces_have_zero_error() {
        let d = [0.0, 1.0, 1.0, 0.0];
        let e = vsd_from_distances(&d, &d, &d, 0.1, &vsd_taus());
        assert!(e.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn hand_computed_vsd() {
        // Four pixels. Test depth measures 1.0 everywhere.
        // gt surface on pixels 0,1,2; est on 1,2,3 with pixel 2 off by 0.02 m.
        let test = [1.0f32; 4];
        let gt = [1.0, 1.0, 1.0, 0.0];
        let est = [0.0, 1.0, 1.02, 1.0];
        // visib_gt = {0,1,2}; visib_est = {1,3} U (gt-visible with est > 0 -> {1,2}) = {1,2,3}.
        // union 4, inter {1,2}; complement 2; dists/diam = {0, 0.2} with diameter 0.1.
        let e = vsd_from_distances(&test, &est, &gt, 0.1, &[0.1, 0.25]);
        assert!((e[0] - 3.0 / 4.0).abs() < 1e-6, "{e:?}");
        assert!((e[1] - 2.0 / 4.0).abs() < 1e-6, "{e:?}");
    }

    #[test]
    fn occluded_gt_pixels_are_not_visible() {
        // The test surface is 0.1 m in front of the model (an occluder): beyond delta, so invisible.
        let test = [0.9f32, 0.0];
        let gt = [1.0f32, 1.0];
        let est = [1.0f32, 1.0];
        // Pixel 0: invisible for both; pixel 1: test has no depth -> visible.
        let e = vsd_from_distances(&test, &est, &gt, 0.1, &[0.05]);
        assert_eq!(e, vec![0.0]);
        // Nothing visible at all -> error 1.
        assert_eq!(
            vsd_from_distances(&[0.5], &[1.0], &[1.0], 0.1, &[0.05]),
            vec![1.0]
        );
    }

    #[test]
    fn distance_grows_off_axis() {
        let cam = PinholeCamera::new(1.0, 1.0, 0.0, 0.0, 2, 1).unwrap();
        let d = depth_to_distance(&[1.0, 1.0], &cam);
        assert!((d[0] - 1.0).abs() < 1e-6);
        assert!((d[1] - 2f32.sqrt()).abs() < 1e-6);
    }
}
