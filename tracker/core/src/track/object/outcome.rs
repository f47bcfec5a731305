//! What a refinement leaves behind: the object's quality, state and velocity, its depth anchors and pose
//! history, and whether re-detection should search for it.

use super::{ObjectTrack, TickInputs, motion, normalise};
use crate::refine::DepthTermStats;
use crate::track::config::{QualityConfig, TrackerConfig};
use crate::track::estimate::TrackingState;
use nalgebra::{Isometry3, Vector6};

impl ObjectTrack {
    /// Whether re-detection should search for this object at a depth frame: it is `lost`, or `degraded` for
    /// more than being partly hidden. An object whose quality would reach `degraded_below` at full visibility
    /// (its depth agreement and event support are good, only the visible fraction is low) is not searched for:
    /// the hand holding it is an object-sized place at its depth, and searching from a good, half-hidden
    /// estimate moved the object onto the hand.
    pub fn needs_search(&self, q: &QualityConfig) -> bool {
        match self.state {
            TrackingState::Tracking => false,
            TrackingState::Lost => true,
            TrackingState::Degraded => {
                let unhidden = f64::from(self.quality) / visibility_factor(self.visibility);
                unhidden < f64::from(q.degraded_below)
            }
        }
    }

    /// Records the new estimate: quality, state, velocity and the pose history.
    pub(super) fn finish(
        &mut self,
        inputs: &TickInputs<'_>,
        pose: Isometry3<f64>,
        fresh_depth: Option<DepthTermStats>,
        event_support: Option<f64>,
        config: &TrackerConfig,
    ) {
        // Quality evidence: depth agreement and visibility at the last exposure (both held until the next one),
        // event support of the outline.
        if let Some(s) = fresh_depth {
            let used = s.measured.max(1) as f64;
            self.depth_fit = s.inliers as f64 / used;
            self.visibility = (s.measured as f64 / s.points.max(1) as f64).min(1.0);
        }
        let visibility = self.visibility;
        let in_view = self.roi.is_some() && self.view.visible_pixels > 0;
        let support = event_support.unwrap_or(1.0);
        let quality = if in_view {
            self.depth_fit * visibility_factor(visibility) * (0.6 + 0.4 * support)
        } else {
            0.0
        };
        self.quality = quality.clamp(0.0, 1.0) as f32;
        let q = config.quality;
        if self.quality < q.lost_below {
            self.low_ticks += 1;
        } else {
            self.low_ticks = 0;
        }
        self.recent_quality.push(self.quality);
        self.state = q.state(
            self.quality,
            self.low_ticks,
            self.recent_quality.full_mean(),
        );
        self.reported.update(self.state, q.recover_ticks);

        // Velocity: at a fresh depth frame from the motion since the previous one (anchored on depth, so a drift
        // the motion model itself introduced between frames is not fed back); otherwise from the last tick,
        // weighted less.
        let (reference, span, a) = match (fresh_depth.is_some(), self.anchor) {
            (true, Some((t0, p0))) if inputs.t_us > t0 => (
                p0,
                (inputs.t_us - t0) as f64 * 1e-6,
                config.velocity_smoothing_depth,
            ),
            _ => (self.pose, inputs.dt_s, config.velocity_smoothing),
        };
        if fresh_depth.is_some() {
            self.anchor_before = self.anchor;
            // A late frame anchors the estimate carried back to its exposure, by the motion its points were
            // carried by, so that anchors stay at exposures (the next frame's motion check compares frames).
            self.anchor = Some(match self.late_motion {
                Some((exposed_us, motion)) => (exposed_us, normalise(motion.inverse() * pose)),
                None => (inputs.t_us, pose),
            });
        }
        if span > 0.0 && self.state != TrackingState::Lost {
            let measured = self.observable_motion(&reference, &pose, span);
            let a = a.clamp(0.0, 1.0);
            let mut v = a * measured + (1.0 - a) * self.velocity;
            motion::cap_motion(&mut v, config);
            self.velocity = v;
        } else if self.state == TrackingState::Lost {
            self.velocity = Vector6::zeros();
        }
        if fresh_depth.is_some()
            && let Some((exposed_us, _)) = self.late_motion
        {
            // What the late frame changed at this tick, it changes since its exposure.
            self.history
                .correct_since(exposed_us, &normalise(self.predicted.inverse() * pose));
        }
        self.previous = Some((self.t_us, self.pose));
        self.pose = normalise(pose);
        self.t_us = inputs.t_us;
        self.history.push(self.t_us, self.pose);
    }
}

/// The factor quality gives the visible fraction `visibility` of the model, in [0.4, 1]: a hidden object is
/// trusted less, but a fully hidden one keeps 0.4 of what its depth and events say.
fn visibility_factor(visibility: f64) -> f64 {
    0.4 + 0.6 * visibility.clamp(0.0, 1.0)
}
