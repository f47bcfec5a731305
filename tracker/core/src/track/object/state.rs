//! What one tick of an object hands to the next: its estimates and motion, its quality and state, the depth it
//! carries, and its counters. Saving and restoring it (to track again from a late depth frame's exposure) is a
//! clone; the per-tick buffers are in [`super::scratch::TickScratch`].

use super::history::PoseHistory;
use super::model::ObjectModel;
use super::quality_window::QualityWindow;
use super::range_track::RangeTrack;
use crate::recon::{CarriedDepth, MovingNeighbourhood};
use crate::refine::apply_step;
use crate::track::config::{QualityConfig, TrackerConfig};
use crate::track::estimate::{ReportedState, TrackingState};
use crate::track::fallback_check::DepthFallbackCheck;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use scene::geometry::{PinholeCamera, Roi};

/// Longest time, seconds, the motion model extrapolates an estimate (12 ticks at 120 Hz). Ticks are 8.3 ms apart,
/// also across the short trigger gaps the timeline bridges; after a longer pause (a trigger outage) the object
/// starts where its velocity would have taken it in this time, and the refinement and re-detection go on from there.
pub const MAX_PREDICTION_S: f64 = 0.1;

/// An object's tracking state between ticks.
#[derive(Debug)]
pub(crate) struct ObjectState {
    /// Latest estimate (`T_cam_obj`).
    pub pose: Isometry3<f64>,
    /// Time of the latest estimate, microseconds.
    pub t_us: i64,
    /// Estimate before the latest, for interpolation.
    pub previous: Option<(i64, Isometry3<f64>)>,
    /// Smoothed velocity of the centre (m/s) and angular velocity (rad/s), camera frame.
    pub velocity: Vector6<f64>,
    /// How much of [`Self::velocity`] is measured rather than the zero it started from, in `[0, 1]`: the sum of
    /// the smoothing weights of the measurements since the velocity was last reset.
    pub velocity_weight: f64,
    /// The pose predicted for the current tick.
    pub predicted: Isometry3<f64>,
    /// The estimate at the latest fresh depth frame's exposure (time, pose).
    pub anchor: Option<(i64, Isometry3<f64>)>,
    /// The estimate at the depth frame before `anchor` (time, pose): with it, the motion between the last two depth
    /// frames, which the events since cannot have changed.
    pub anchor_before: Option<(i64, Isometry3<f64>)>,
    /// The object's range at the latest depth frames' estimates, which the prediction extrapolates along the
    /// line of sight with [`crate::track::MotionConfig::range_from_depth`].
    pub ranges: RangeTrack,
    /// Quality of the latest estimate, 0 (lost) to 1.
    pub quality: f32,
    /// This tick's state (the tracker's own decisions use it).
    pub tracking: TrackingState,
    /// The state reported to consumers: `tracking` with a delayed recovery.
    pub reported: ReportedState,
    /// Consecutive ticks with quality below `lost_below`.
    pub low_ticks: u32,
    /// Quality of the recent ticks (the mean-quality `lost` rule).
    pub recent_quality: QualityWindow,
    /// Depth frames at which the depth-only hypothesis replaced the event-driven estimate.
    pub fallbacks: u64,
    /// Depth frames at which re-detection moved the object.
    pub redetections: u64,
    /// The safety-net check of the latest refinement; `None` if that tick ran none.
    pub fallback_check: Option<DepthFallbackCheck>,
    /// Fraction of the used model points the depth agreed with at the latest depth frame.
    pub depth_fit: f64,
    /// Fraction of the model points the depth measured (not hidden, not missing) at the latest depth frame.
    pub visibility: f64,
    /// Depth frames this object has used.
    pub depth_frames_used: u32,
    /// Time of the first pose, microseconds (the hold before the first depth frame is counted from it).
    pub first_us: i64,
    /// Recent estimates: where the object was when a depth frame that arrives late was exposed.
    pub history: PoseHistory,
    /// At a tick that uses a depth frame exposed at an earlier tick, from registering it to the refinement: its
    /// exposure time and the estimate then.
    pub late_frame: Option<(i64, Isometry3<f64>)>,
    /// At a tick that used a depth frame exposed at an earlier tick: the exposure time and the camera-frame
    /// motion `T_predicted * T_exposure^-1` the frame's object points were carried by; `None` otherwise.
    pub late_motion: Option<(i64, Isometry3<f64>)>,
    /// Late depth frames this object could not use: its history did not reach back to their exposure.
    pub late_depth_unplaced: u64,
    /// This tick's region of interest; `None` when out of view or its render failed.
    pub roi: Option<Roi>,
    /// The depth `D_0` of the latest depth frame, carried to the following ticks.
    pub carried: CarriedDepth,
    /// The previous depth frame's moved surfaces around the object, for the safety net's motion check.
    pub neighbourhood: MovingNeighbourhood,
}

impl Clone for ObjectState {
    fn clone(&self) -> Self {
        let mut state = Self::new(self.pose, self.t_us, 0);
        state.clone_from(self);
        state
    }

    /// Reuses this state's buffers (history, quality window, carried depth): saving a state into one that has held
    /// a state before does not allocate.
    fn clone_from(&mut self, source: &Self) {
        // Destructured so that a field added to the state and not copied here fails to compile.
        let Self {
            pose,
            t_us,
            previous,
            velocity,
            velocity_weight,
            predicted,
            anchor,
            anchor_before,
            ranges,
            quality,
            tracking,
            reported,
            low_ticks,
            recent_quality,
            fallbacks,
            redetections,
            fallback_check,
            depth_fit,
            visibility,
            depth_frames_used,
            first_us,
            history,
            late_frame,
            late_motion,
            late_depth_unplaced,
            roi,
            carried,
            neighbourhood,
        } = source;
        self.pose = *pose;
        self.t_us = *t_us;
        self.previous = *previous;
        self.velocity = *velocity;
        self.velocity_weight = *velocity_weight;
        self.predicted = *predicted;
        self.anchor = *anchor;
        self.anchor_before = *anchor_before;
        self.ranges = *ranges;
        self.quality = *quality;
        self.tracking = *tracking;
        self.reported = *reported;
        self.low_ticks = *low_ticks;
        self.recent_quality.clone_from(recent_quality);
        self.fallbacks = *fallbacks;
        self.redetections = *redetections;
        self.fallback_check = *fallback_check;
        self.depth_fit = *depth_fit;
        self.visibility = *visibility;
        self.depth_frames_used = *depth_frames_used;
        self.first_us = *first_us;
        self.history.clone_from(history);
        self.late_frame = *late_frame;
        self.late_motion = *late_motion;
        self.late_depth_unplaced = *late_depth_unplaced;
        self.roi = *roi;
        self.carried.clone_from(carried);
        self.neighbourhood.clone_from(neighbourhood);
    }
}

impl ObjectState {
    /// The state of an object first seen at `pose` at `t_us`, tracking, with a quality window of `quality_ticks`.
    pub fn new(pose: Isometry3<f64>, t_us: i64, quality_ticks: usize) -> Self {
        Self {
            pose,
            t_us,
            previous: None,
            velocity: Vector6::zeros(),
            velocity_weight: 0.0,
            predicted: pose,
            anchor: None,
            anchor_before: None,
            ranges: RangeTrack::default(),
            quality: 1.0,
            tracking: TrackingState::Tracking,
            reported: ReportedState::new(TrackingState::Tracking),
            low_ticks: 0,
            recent_quality: QualityWindow::new(quality_ticks),
            fallbacks: 0,
            redetections: 0,
            fallback_check: None,
            depth_fit: 1.0,
            visibility: 1.0,
            depth_frames_used: 0,
            first_us: t_us,
            history: PoseHistory::new(),
            late_frame: None,
            late_motion: None,
            late_depth_unplaced: 0,
            roi: None,
            carried: CarriedDepth::new(),
            neighbourhood: MovingNeighbourhood::new(),
        }
    }

    /// Takes over the motion, quality and depth-frame count of `other` (another state of the same object; a
    /// re-detection probe follows the object it probes for), leaving its own history, carried depth and counters.
    pub fn follow(&mut self, other: &Self) {
        self.pose = other.pose;
        self.t_us = other.t_us;
        self.previous = other.previous;
        self.velocity = other.velocity;
        self.velocity_weight = other.velocity_weight;
        self.predicted = other.predicted;
        self.anchor = other.anchor;
        self.anchor_before = other.anchor_before;
        self.ranges = other.ranges;
        self.quality = other.quality;
        self.tracking = other.tracking;
        self.reported = other.reported;
        self.low_ticks = other.low_ticks;
        self.recent_quality.clone_from(&other.recent_quality);
        self.depth_fit = other.depth_fit;
        self.visibility = other.visibility;
        self.depth_frames_used = other.depth_frames_used;
    }

    /// Predicts the pose `dt_s` after the latest estimate (constant velocity about the centre, for at most
    /// [`MAX_PREDICTION_S`]).
    pub fn predict(&mut self, model: &ObjectModel, dt_s: f64, config: &TrackerConfig) {
        self.predicted = self.prediction(model, dt_s, config);
    }

    /// The pose `dt_s` after the latest estimate that [`Self::predict`] would predict. The motion model
    /// extrapolates at most [`MAX_PREDICTION_S`]: after a longer pause in the ticks the velocity says nothing
    /// about where the object went.
    pub fn prediction(
        &self,
        model: &ObjectModel,
        dt_s: f64,
        config: &TrackerConfig,
    ) -> Isometry3<f64> {
        if config.motion.prediction && self.tracking != TrackingState::Lost {
            let t_us = self.t_us + (dt_s * 1e6).round() as i64;
            let dt_s = dt_s.min(MAX_PREDICTION_S);
            let mut xi = self.velocity * (dt_s * config.motion.prediction_gain);
            if !config.motion.predict_rotation {
                xi.fixed_rows_mut::<3>(3).fill(0.0);
            }
            let pose = apply_step(&self.pose, &model.center_obj, &xi);
            if config.motion.range_from_depth {
                self.at_depth_range(model, pose, t_us, config)
            } else {
                pose
            }
        } else {
            self.pose
        }
    }

    /// `pose` moved along the line of sight to its centre to the range the latest depth frames extrapolate to at
    /// `t_us` ([`RangeTrack::range_at`]); `pose` itself when they do not.
    fn at_depth_range(
        &self,
        model: &ObjectModel,
        mut pose: Isometry3<f64>,
        t_us: i64,
        config: &TrackerConfig,
    ) -> Isometry3<f64> {
        let Some(range) = self.ranges.range_at(
            t_us,
            config.motion.range_acceleration_share,
            config.motion.max_speed,
        ) else {
            return pose;
        };
        let c = model.center_at(&pose).coords;
        let norm = c.norm();
        if norm > 1e-3 && range > 1e-3 {
            pose.translation.vector += c * (range / norm - 1.0);
        }
        pose
    }

    /// The ROI around the predicted pose, if the object is in front of the camera. At a depth exposure
    /// (`depth_due`) with the extrapolated depth fallback on, it is widened to also hold the object where the
    /// previous depth pose carried on at the measured velocity puts it, so the depth image covers that start too.
    pub fn update_roi(
        &mut self,
        model: &ObjectModel,
        camera: &PinholeCamera,
        config: &TrackerConfig,
        t_us: i64,
        depth_due: bool,
    ) -> Option<Roi> {
        self.roi = self.roi_at(model, &self.predicted, camera, config, t_us, depth_due);
        self.roi
    }

    /// The ROI [`Self::update_roi`] would choose at `t_us` if `predicted` were the prediction.
    pub fn roi_at(
        &self,
        model: &ObjectModel,
        predicted: &Isometry3<f64>,
        camera: &PinholeCamera,
        config: &TrackerConfig,
        t_us: i64,
        depth_due: bool,
    ) -> Option<Roi> {
        let mut c = model.center_at(predicted);
        let mut scale = config.roi.roi_scale;
        if depth_due
            && config.safety_net.depth_fallback_extrapolate
            && config.safety_net.depth_fallback_margin >= 0.0
            && config.roi.roi_widen_at_depth
            && let Some((t_anchor, anchor)) = self.anchor
        {
            let span = (t_us - t_anchor).max(0) as f64 * 1e-6;
            let start = apply_step(&anchor, &model.center_obj, &(self.velocity * span));
            let other = model.center_at(&start);
            let gap = (other - c).norm();
            if gap.is_finite() && gap > 0.1 * model.diameter {
                c = Point3::from((c.coords + other.coords) * 0.5);
                scale += gap / model.diameter;
            }
        }
        // Behind the camera: no ROI (checked here so the lost path does not build an error message per tick).
        if !(c.z > 1e-3 && c.coords.iter().all(|v| v.is_finite())) {
            return None;
        }
        Roi::around_object(camera, &c, model.diameter, scale, config.roi.roi_size).ok()
    }

    /// Image speed of the object's outline predicted from the velocity, full-image pixels per second.
    pub fn image_speed(&self, model: &ObjectModel, camera: &PinholeCamera) -> f64 {
        self.image_speed_at(model, camera, &self.velocity)
    }

    /// Image speed of the object's outline at the prediction if it moved at `v` (centre m/s, angular rad/s),
    /// full-image pixels per second.
    pub fn image_speed_at(
        &self,
        model: &ObjectModel,
        camera: &PinholeCamera,
        v: &Vector6<f64>,
    ) -> f64 {
        let c = model.center_at(&self.predicted);
        let z = c.z.max(0.05);
        let lateral = (v[0] * v[0] + v[1] * v[1]).sqrt() + (v[2].abs() * model.diameter * 0.5 / z);
        let angular = Vector3::new(v[3], v[4], v[5]).norm() * model.diameter * 0.5;
        camera.fx * (lateral + angular) / z
    }

    /// Whether re-detection should search for this object at a depth frame: it is `lost`, or `degraded` for
    /// more than being partly hidden. An object whose quality would reach `degraded_below` at full visibility
    /// (its depth agreement and event support are good, only the visible fraction is low) is not searched for:
    /// the hand holding it is an object-sized place at its depth, and searching from a good, half-hidden
    /// estimate moved the object onto the hand.
    pub fn needs_search(&self, q: &QualityConfig) -> bool {
        match self.tracking {
            TrackingState::Tracking => false,
            TrackingState::Lost => true,
            TrackingState::Degraded => {
                let unhidden = f64::from(self.quality) / visibility_factor(self.visibility);
                unhidden < f64::from(q.degraded_below)
            }
        }
    }

    /// Moves the object to `pose`: the motion estimate, the depth anchor, the pose history and the recent mean
    /// quality are dropped. The run of poor ticks goes on: a place found is a hypothesis, and an object moved from
    /// one wrong place to another every depth frame still comes to say `lost` when its quality stays poor.
    pub fn relocate(&mut self, pose: Isometry3<f64>) {
        self.pose = normalise(pose);
        self.predicted = self.pose;
        self.velocity = Vector6::zeros();
        self.velocity_weight = 0.0;
        self.anchor = None;
        self.anchor_before = None;
        self.ranges.clear();
        self.recent_quality.clear();
        self.history.clear();
        self.redetections += 1;
    }

    /// Replaces the latest estimate (see [`crate::track::EventTrack6d::reset_pose`]).
    pub fn reset(&mut self, t_us: i64, pose: Isometry3<f64>) {
        self.previous = Some((self.t_us, self.pose));
        self.pose = normalise(pose);
        self.predicted = self.pose;
        self.t_us = t_us;
        self.history.clear();
        self.history.push(t_us, self.pose);
        self.low_ticks = 0;
        self.recent_quality.clear();
        self.tracking = TrackingState::Tracking;
        self.reported = ReportedState::new(TrackingState::Tracking);
    }

    /// Holds the latest estimate at `t_us` without refining (`depth30` between depth frames): pose, quality and
    /// state stay what the last refinement said.
    pub fn hold(&mut self, t_us: i64) {
        self.previous = Some((self.t_us, self.pose));
        self.t_us = t_us;
        self.history.push(t_us, self.pose);
    }
}

/// The factor quality gives the visible fraction `visibility` of the model, in [0.4, 1]: a hidden object is
/// trusted less, but a fully hidden one keeps 0.4 of what its depth and events say.
pub(crate) fn visibility_factor(visibility: f64) -> f64 {
    0.4 + 0.6 * visibility.clamp(0.0, 1.0)
}

/// Re-normalises the rotation (drift from repeated composition).
pub(crate) fn normalise(pose: Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(pose.translation.vector),
        UnitQuaternion::new_normalize(*pose.rotation.quaternion()),
    )
}

/// `pose` if its translation is finite and in front of the camera (over 1 mm), `fallback` otherwise: a pose
/// composed from estimates that a degenerate step left unusable.
pub(crate) fn in_front_or(pose: Isometry3<f64>, fallback: Isometry3<f64>) -> Isometry3<f64> {
    if pose.translation.vector.iter().all(|v| v.is_finite()) && pose.translation.z > 1e-3 {
        pose
    } else {
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn contains(roi: &Roi, camera: &PinholeCamera, p: &Point3<f64>, margin_px: f64) -> bool {
        let uv = camera.project(p).expect("in front");
        uv.x >= roi.x + margin_px
            && uv.y >= roi.y + margin_px
            && uv.x <= roi.x + roi.width - margin_px
            && uv.y <= roi.y + roi.height - margin_px
    }

    #[test]
    fn a_degraded_object_is_searched_for_only_when_more_than_hiding_degrades_it() {
        let config = TrackerConfig::default();
        let half = Vector3::new(0.05, 0.04, 0.02);
        let pose = Isometry3::translation(0.0, 0.0, 0.6);
        let _model = ObjectModel::new(1, 0.13, -half, half, &[]);
        let mut o = ObjectState::new(pose, 0, config.quality.lost_mean_ticks as usize);
        let q = config.quality;
        // 30 % in view, agreeing well: quality 0.7 x (0.4 + 0.6 x 0.3) = 0.406, below `degraded_below` only
        // because of the hiding (0.7 at full visibility).
        o.tracking = TrackingState::Degraded;
        o.visibility = 0.3;
        o.quality = 0.406;
        assert!(!o.needs_search(&q));
        // Same visibility, poor agreement: searched for.
        o.quality = 0.2;
        assert!(o.needs_search(&q));
        // Fully visible and degraded: searched for.
        o.visibility = 1.0;
        o.quality = 0.45;
        assert!(o.needs_search(&q));
        o.tracking = TrackingState::Lost;
        o.quality = 0.9;
        assert!(o.needs_search(&q));
        o.tracking = TrackingState::Tracking;
        o.quality = 0.1;
        assert!(!o.needs_search(&q));
    }

    #[test]
    fn the_prediction_reaches_no_further_than_its_horizon() {
        let config = TrackerConfig::default();
        let half = Vector3::new(0.05, 0.05, 0.05);
        let start = Isometry3::translation(0.0, 0.0, 0.6);
        let model = ObjectModel::new(1, 0.1, -half, half, &[]);
        let mut track = ObjectState::new(start, 0, 0);
        track.velocity = Vector6::new(2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let x = |dt: f64| track.prediction(&model, dt, &config).translation.x;
        // One tick: 2 m/s x 8.3 ms x the prediction gain.
        assert!((x(1.0 / 120.0) - 2.0 / 120.0 * config.motion.prediction_gain).abs() < 1e-12);
        // Past the horizon (ticks resuming after a trigger outage) the object is not flung away.
        assert_eq!(x(5.0), x(MAX_PREDICTION_S));
        assert!(x(5.0) < 0.11, "{}", x(5.0));
    }

    #[test]
    fn roi_at_a_depth_exposure_widens_to_the_extrapolated_start_only_when_asked() {
        let camera = PinholeCamera::new(600.0, 600.0, 639.5, 359.5, 1280, 720).unwrap();
        let mut config = TrackerConfig::default();
        let at = |x: f64| Isometry3::translation(x, 0.0, 0.6);
        let half = Vector3::new(0.05, 0.05, 0.05);
        let model = ObjectModel::new(1, 0.1, -half, half, &[]);
        let mut track = ObjectState::new(at(0.0), 0, 0);
        // The previous depth pose 33 ms ago at x = 0, moving at 3 m/s along x: the extrapolated start is
        // 10 cm (one diameter) away from a prediction that stayed at x = 0.
        track.anchor = Some((0, at(0.0)));
        track.velocity = Vector6::new(3.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        track.predicted = at(0.0);
        let t = 33_333;
        let extrapolated = Point3::new(0.1, 0.0, 0.6);
        let plain = track.update_roi(&model, &camera, &config, t, true).unwrap();
        assert!(!contains(&plain, &camera, &extrapolated, 0.0));
        config.roi.roi_widen_at_depth = true;
        let between = track
            .update_roi(&model, &camera, &config, t, false)
            .unwrap();
        assert_eq!(between, plain, "only depth exposures widen");
        let wide = track.update_roi(&model, &camera, &config, t, true).unwrap();
        // Half a diameter (50 px at 0.6 m) of the object on either side fits in the ROI.
        for p in [Point3::new(0.0, 0.0, 0.6), extrapolated] {
            assert!(contains(&wide, &camera, &p, 40.0), "{wide:?} misses {p:?}");
        }
    }
}
