//! A depth frame that arrived after its own tick: registered where the object was estimated at its exposure,
//! aligned there on depth alone, and its object part carried by the motion estimated since to the tick it is used
//! at. A late frame tells where the object was, not how it moved since: the events carry that.

use super::{ObjectTrack, TickInputs};
use crate::geometry::PinholeCamera;
use crate::recon::DepthRig;
use crate::track::config::TrackerConfig;
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3};

/// Margin around the object's box, metres, within which a late frame's points count as the object's when they are
/// carried to the tick (split at the pose aligned at the exposure).
const LATE_SPLIT_MARGIN_M: f64 = 0.01;

impl ObjectTrack {
    /// Registers `frame`, exposed at `exposed_us` when the object was estimated at `then`, as the new `D_0`: a
    /// sphere around the object then and at this tick's prediction, every point static for now. The refinement
    /// aligns and carries it ([`Self::carry_late_depth`]).
    pub(super) fn register_late_depth(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        exposed_us: i64,
        then: &Isometry3<f64>,
        config: &TrackerConfig,
    ) {
        let c_then = self.center_at(then);
        let c_now = self.center_at(&self.predicted);
        let c = Point3::from((c_then.coords + c_now.coords) * 0.5);
        let radius = 0.6 * config.roi_scale * self.diameter + 0.08 + 0.5 * (c_now - c_then).norm();
        self.carried.register(frame, rig, &c, radius, exposed_us);
        self.late_frame = Some((exposed_us, *then));
    }

    /// For a frame registered by [`Self::register_late_depth`]: refines the estimate at the exposure on the frame's
    /// depth alone (the model view of this tick's render, placed there), carries the points in the object's box
    /// at that pose by the motion estimated from the exposure to the prediction, and renders the result into
    /// `depth_now` in this tick's ROI. Returns the prediction corrected by what the alignment changed at the
    /// exposure, the pose the refinement starts from.
    pub(super) fn carry_late_depth(
        &mut self,
        inputs: &TickInputs<'_>,
        roi_camera: &PinholeCamera,
        config: &TrackerConfig,
    ) -> Isometry3<f64> {
        let Some((exposed_us, then)) = self.late_frame.take() else {
            return self.predicted;
        };
        let aligned = self.align_at_exposure(&then, inputs, config);
        let motion = self.predicted * then.inverse();
        self.carried.carry_object_part(
            &aligned,
            &motion,
            &self.aabb_min,
            &self.aabb_max,
            LATE_SPLIT_MARGIN_M,
        );
        self.late_motion = Some((exposed_us, motion));
        self.carried
            .render(&self.predicted, roi_camera, &mut self.depth_now);
        // `motion * aligned` = the prediction moved by the alignment's change at the exposure, in the object frame.
        let start = motion * aligned;
        if start.translation.vector.iter().all(|v| v.is_finite()) && start.translation.z > 1e-3 {
            start
        } else {
            self.predicted
        }
    }

    /// The estimate at the exposure `then`, refined on depth alone against the registered late frame in the ROI
    /// around it; `then` itself when the object was out of view then or the depth agrees no better after.
    fn align_at_exposure(
        &mut self,
        then: &Isometry3<f64>,
        inputs: &TickInputs<'_>,
        config: &TrackerConfig,
    ) -> Isometry3<f64> {
        let Some(roi) = self.roi_at(then, inputs.camera, config, inputs.t_us, false) else {
            return *then;
        };
        let camera = inputs.camera.crop(&roi);
        let mut image = std::mem::take(&mut self.late_depth);
        self.carried.render(then, &camera, &mut image);
        let (aligned, stats) = self.refine_on_depth_in(*then, &camera, &image, config);
        let before = config.depth_term.stats(&self.view, then, &camera, &image);
        self.late_depth = image;
        if super::depth_check::seen_agreement(&stats) >= super::depth_check::seen_agreement(&before)
        {
            aligned
        } else {
            *then
        }
    }
}
