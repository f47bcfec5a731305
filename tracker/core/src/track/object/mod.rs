//! One tracked object's state and its per-tick refinement.

mod depth_check;
mod history;
mod late_depth;
mod motion;
mod outcome;
mod placement;
mod quality_window;
mod refine;
mod snapshot;

use super::config::TrackerConfig;
use super::estimate::{ReportedState, TrackingState};
use super::fallback_check::DepthFallbackCheck;
use crate::recon::{CarriedDepth, DepthImage, DepthRig, EventSurface, MovingNeighbourhood};
use crate::refine::{EventEdges, IntensityEdges, ModelView, NormalEquations, apply_step};
use drivers::recording::DepthFrame;
pub use history::PoseHistory;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use quality_window::QualityWindow;
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::Symmetry;
use scene::render::RenderTarget;
pub(crate) use snapshot::ObjectSnapshot;

/// Longest time, seconds, the motion model extrapolates an estimate (12 ticks at 120 Hz). Ticks are 8.3 ms apart,
/// also across the short trigger gaps the timeline bridges; after a longer pause (a trigger outage) the object
/// starts where its velocity would have taken it in this time, and the refinement and re-detection go on from there.
pub const MAX_PREDICTION_S: f64 = 0.1;

/// A tracked object: its model, its state and the buffers its refinement reuses every tick.
#[derive(Debug)]
pub(crate) struct ObjectTrack {
    pub label: u16,
    pub diameter: f64,
    pub center_obj: Vector3<f64>,
    pub aabb_min: Vector3<f64>,
    pub aabb_max: Vector3<f64>,
    /// Continuous symmetry axes (unit, object frame): the velocity keeps no spin about them.
    spin_axes: Vec<Vector3<f64>>,
    /// Latest estimate and its time.
    pub pose: Isometry3<f64>,
    pub t_us: i64,
    /// Estimate before the latest, for interpolation.
    pub previous: Option<(i64, Isometry3<f64>)>,
    /// Smoothed velocity of the centre (m/s) and angular velocity (rad/s), camera frame.
    pub velocity: Vector6<f64>,
    pub predicted: Isometry3<f64>,
    /// The estimate at the latest fresh depth frame's exposure (time, pose).
    anchor: Option<(i64, Isometry3<f64>)>,
    /// The estimate at the depth frame before `anchor` (time, pose): with it, the motion between the last two depth
    /// frames, which the events since cannot have changed.
    anchor_before: Option<(i64, Isometry3<f64>)>,
    pub quality: f32,
    /// This tick's state (the tracker's own decisions use it).
    pub state: TrackingState,
    /// The state reported to consumers: `state` with a delayed recovery.
    pub reported: ReportedState,
    low_ticks: u32,
    /// Quality of the recent ticks (the mean-quality `lost` rule).
    recent_quality: QualityWindow,
    /// Depth frames at which the depth-only hypothesis replaced the event-driven estimate.
    pub fallbacks: u64,
    /// Depth frames at which re-detection moved the object.
    pub redetections: u64,
    /// The safety-net check of the latest refinement; `None` if that tick ran none.
    pub fallback_check: Option<DepthFallbackCheck>,
    /// Fraction of the used model points the depth agreed with at the latest depth frame.
    depth_fit: f64,
    /// Fraction of the model points the depth measured (not hidden, not missing) at the latest depth frame.
    visibility: f64,
    depth_frames_used: u32,
    /// Time of the first pose, microseconds (the hold before the first depth frame is counted from it).
    first_us: i64,
    /// Recent estimates: where the object was when a depth frame that arrives late was exposed.
    history: PoseHistory,
    /// At a tick that uses a depth frame exposed at an earlier tick, from [`Self::prepare_depth`] to the
    /// refinement: its exposure time and the estimate then.
    late_frame: Option<(i64, Isometry3<f64>)>,
    /// At a tick that used a depth frame exposed at an earlier tick: the exposure time and the camera-frame
    /// motion `T_predicted * T_exposure^-1` the frame's object points were carried by; `None` otherwise.
    late_motion: Option<(i64, Isometry3<f64>)>,
    /// A late frame's depth around the object where it was at the exposure, in that ROI's camera.
    late_depth: DepthImage,
    /// Late depth frames this object could not use: its history did not reach back to their exposure.
    pub late_depth_unplaced: u64,
    pub roi: Option<Roi>,
    pub target: RenderTarget,
    view: ModelView,
    carried: CarriedDepth,
    /// The previous depth frame's moved surfaces around the object, for the safety net's motion check.
    neighbourhood: MovingNeighbourhood,
    depth_now: DepthImage,
    edges: EventEdges,
    intensity_edges: IntensityEdges,
}

/// Per-tick inputs shared by every object.
pub(crate) struct TickInputs<'a> {
    pub t_us: i64,
    pub dt_s: f64,
    pub depth: Option<&'a DepthFrame>,
    /// Exposure of `depth`, microseconds: `t_us`, or earlier for a frame that arrived after its own tick.
    pub depth_exposed_us: i64,
    pub surface: &'a EventSurface,
    pub camera: &'a PinholeCamera,
    pub depth_rig: &'a DepthRig,
}

impl ObjectTrack {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        label: u16,
        diameter: f64,
        aabb_min: Vector3<f64>,
        aabb_max: Vector3<f64>,
        pose: Isometry3<f64>,
        t_us: i64,
        symmetries: &[Symmetry],
        config: &TrackerConfig,
    ) -> Self {
        let n = config.roi_size as usize;
        let spin_axes = symmetries
            .iter()
            .filter_map(|s| match s {
                Symmetry::Continuous { axis, .. } => Some(axis.into_inner()),
                Symmetry::Discrete(_) => None,
            })
            .collect();
        Self {
            label,
            diameter,
            center_obj: (aabb_min + aabb_max) * 0.5,
            aabb_min,
            aabb_max,
            spin_axes,
            pose,
            t_us,
            previous: None,
            velocity: Vector6::zeros(),
            predicted: pose,
            anchor: None,
            anchor_before: None,
            quality: 1.0,
            state: TrackingState::Tracking,
            reported: ReportedState::new(TrackingState::Tracking),
            low_ticks: 0,
            recent_quality: QualityWindow::new(config.quality.lost_mean_ticks as usize),
            fallbacks: 0,
            fallback_check: None,
            redetections: 0,
            depth_fit: 1.0,
            visibility: 1.0,
            depth_frames_used: 0,
            first_us: t_us,
            history: PoseHistory::new(),
            late_frame: None,
            late_motion: None,
            late_depth: DepthImage {
                width: config.roi_size,
                height: config.roi_size,
                z: Vec::with_capacity(n * n),
            },
            late_depth_unplaced: 0,
            roi: None,
            target: RenderTarget::with_capacity(config.roi_size, config.roi_size),
            view: ModelView::with_capacity(config.max_surface_points, config.max_contour_points),
            carried: CarriedDepth::new(),
            neighbourhood: MovingNeighbourhood::new(),
            depth_now: DepthImage {
                width: config.roi_size,
                height: config.roi_size,
                z: Vec::with_capacity(n * n),
            },
            edges: EventEdges::default(),
            intensity_edges: IntensityEdges::default(),
        }
    }

    /// A scratch track for checking places where this object might be (re-detection): the same model with buffers
    /// of its own, so that a check leaves this track's buffers (its carried depth above all) as they were.
    pub fn probe(&self, config: &TrackerConfig) -> Self {
        let mut probe = Self::new(
            self.label,
            self.diameter,
            self.aabb_min,
            self.aabb_max,
            self.pose,
            self.t_us,
            &[],
            config,
        );
        probe.spin_axes.clone_from(&self.spin_axes);
        probe
    }

    /// Takes over the motion state of `track`, the object this scratch track probes for (buffers untouched).
    pub fn follow(&mut self, track: &Self) {
        self.pose = track.pose;
        self.t_us = track.t_us;
        self.previous = track.previous;
        self.velocity = track.velocity;
        self.predicted = track.predicted;
        self.anchor = track.anchor;
        self.anchor_before = track.anchor_before;
        self.quality = track.quality;
        self.state = track.state;
        self.reported = track.reported;
        self.low_ticks = track.low_ticks;
        self.recent_quality.clone_from(&track.recent_quality);
        self.depth_fit = track.depth_fit;
        self.visibility = track.visibility;
        self.depth_frames_used = track.depth_frames_used;
    }

    /// The recent estimates, oldest first.
    pub fn history(&self) -> &PoseHistory {
        &self.history
    }

    /// The object's centre in the camera frame at `pose`.
    pub fn center_at(&self, pose: &Isometry3<f64>) -> Point3<f64> {
        pose * Point3::from(self.center_obj)
    }

    /// Predicts the pose `dt_s` after the latest estimate (constant velocity about the centre, for at most
    /// [`MAX_PREDICTION_S`]).
    pub fn predict(&mut self, dt_s: f64, config: &TrackerConfig) {
        self.predicted = self.prediction(dt_s, config);
    }

    /// The pose `dt_s` after the latest estimate that [`Self::predict`] would predict. The motion model
    /// extrapolates at most [`MAX_PREDICTION_S`]: after a longer pause in the ticks the velocity says nothing
    /// about where the object went.
    pub fn prediction(&self, dt_s: f64, config: &TrackerConfig) -> Isometry3<f64> {
        if config.prediction && self.state != TrackingState::Lost {
            let dt_s = dt_s.min(MAX_PREDICTION_S);
            let mut xi = self.velocity * (dt_s * config.prediction_gain);
            if !config.predict_rotation {
                xi.fixed_rows_mut::<3>(3).fill(0.0);
            }
            apply_step(&self.pose, &self.center_obj, &xi)
        } else {
            self.pose
        }
    }

    /// The ROI around the predicted pose, if the object is in front of the camera. At a depth exposure
    /// (`depth_due`) with the extrapolated depth fallback on, it is widened to also hold the object where the
    /// previous depth pose carried on at the measured velocity puts it, so the depth image covers that start too.
    pub fn update_roi(
        &mut self,
        camera: &PinholeCamera,
        config: &TrackerConfig,
        t_us: i64,
        depth_due: bool,
    ) -> Option<Roi> {
        self.roi = self.roi_at(&self.predicted, camera, config, t_us, depth_due);
        self.roi
    }

    /// The ROI [`Self::update_roi`] would choose at `t_us` if `predicted` were the prediction.
    pub fn roi_at(
        &self,
        predicted: &Isometry3<f64>,
        camera: &PinholeCamera,
        config: &TrackerConfig,
        t_us: i64,
        depth_due: bool,
    ) -> Option<Roi> {
        let mut c = self.center_at(predicted);
        let mut scale = config.roi_scale;
        if depth_due
            && config.depth_fallback_extrapolate
            && config.depth_fallback_margin >= 0.0
            && config.roi_widen_at_depth
            && let Some((t_anchor, anchor)) = self.anchor
        {
            let span = (t_us - t_anchor).max(0) as f64 * 1e-6;
            let start = apply_step(&anchor, &self.center_obj, &(self.velocity * span));
            let other = self.center_at(&start);
            let gap = (other - c).norm();
            if gap.is_finite() && gap > 0.1 * self.diameter {
                c = Point3::from((c.coords + other.coords) * 0.5);
                scale += gap / self.diameter;
            }
        }
        // Behind the camera: no ROI (checked here so the lost path does not build an error message per tick).
        if !(c.z > 1e-3 && c.coords.iter().all(|v| v.is_finite())) {
            return None;
        }
        Roi::around_object(camera, &c, self.diameter, scale, config.roi_size).ok()
    }

    /// Image speed of the object's outline predicted from the velocity, full-image pixels per second.
    fn image_speed(&self, camera: &PinholeCamera) -> f64 {
        let c = self.center_at(&self.predicted);
        let z = c.z.max(0.05);
        let v = self.velocity;
        let lateral = (v[0] * v[0] + v[1] * v[1]).sqrt() + (v[2].abs() * self.diameter * 0.5 / z);
        let angular = Vector3::new(v[3], v[4], v[5]).norm() * self.diameter * 0.5;
        camera.fx * (lateral + angular) / z
    }

    /// Takes the depth of `frame` (exposed at `t_us`) around the prediction as the depth `D_0` carried to the
    /// following ticks (a sphere reaching past the ROI), every point static until it is split.
    pub fn carry_depth_from(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        t_us: i64,
        config: &TrackerConfig,
    ) {
        let predicted = self.predicted;
        self.register_between(frame, rig, &predicted, &predicted, t_us, config);
    }

    /// Takes the depth of `frame` (exposed at `t_us`) as the new `D_0`, every point static for now: a sphere
    /// reaching past the ROI around the object at both `then` and `now`, which lie apart when the frame is used
    /// later than it was exposed.
    fn register_between(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        then: &Isometry3<f64>,
        now: &Isometry3<f64>,
        t_us: i64,
        config: &TrackerConfig,
    ) {
        let c_then = self.center_at(then);
        let c_now = self.center_at(now);
        let c = Point3::from((c_then.coords + c_now.coords) * 0.5);
        let radius = 0.6 * config.roi_scale * self.diameter + 0.08 + 0.5 * (c_now - c_then).norm();
        self.carried.register(frame, rig, &c, radius, t_us);
    }
}

/// Adds the prior towards the refinement's start: `offset` is the increment accumulated so far, `prior_t` and
/// `prior_r` the inverse variances of translation (1/m^2) and rotation (1/rad^2).
fn add_prior(ne: &mut NormalEquations, offset: &Vector6<f64>, prior_t: f64, prior_r: f64) {
    for k in 0..6 {
        let w = if k < 3 { prior_t } else { prior_r };
        ne.h[(k, k)] += w;
        ne.g[k] += w * offset[k];
    }
}

/// `pose` if its translation is finite and in front of the camera (over 1 mm), `fallback` otherwise: a pose
/// composed from estimates that a degenerate step left unusable.
fn in_front_or(pose: Isometry3<f64>, fallback: Isometry3<f64>) -> Isometry3<f64> {
    if pose.translation.vector.iter().all(|v| v.is_finite()) && pose.translation.z > 1e-3 {
        pose
    } else {
        fallback
    }
}

/// Re-normalises the rotation (drift from repeated composition).
fn normalise(pose: Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(pose.translation.vector),
        UnitQuaternion::new_normalize(*pose.rotation.quaternion()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let mut o = ObjectTrack::new(1, 0.13, -half, half, pose, 0, &[], &config);
        let q = config.quality;
        // 30 % in view, agreeing well: quality 0.7 x (0.4 + 0.6 x 0.3) = 0.406, below `degraded_below` only
        // because of the hiding (0.7 at full visibility).
        o.state = TrackingState::Degraded;
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
        o.state = TrackingState::Lost;
        o.quality = 0.9;
        assert!(o.needs_search(&q));
        o.state = TrackingState::Tracking;
        o.quality = 0.1;
        assert!(!o.needs_search(&q));
    }

    #[test]
    fn the_prediction_reaches_no_further_than_its_horizon() {
        let config = TrackerConfig::default();
        let half = Vector3::new(0.05, 0.05, 0.05);
        let start = Isometry3::translation(0.0, 0.0, 0.6);
        let mut track = ObjectTrack::new(1, 0.1, -half, half, start, 0, &[], &config);
        track.velocity = Vector6::new(2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let x = |dt: f64| track.prediction(dt, &config).translation.x;
        // One tick: 2 m/s x 8.3 ms x the prediction gain.
        assert!((x(1.0 / 120.0) - 2.0 / 120.0 * config.prediction_gain).abs() < 1e-12);
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
        let mut track = ObjectTrack::new(1, 0.1, -half, half, at(0.0), 0, &[], &config);
        // The previous depth pose 33 ms ago at x = 0, moving at 3 m/s along x: the extrapolated start is
        // 10 cm (one diameter) away from a prediction that stayed at x = 0.
        track.anchor = Some((0, at(0.0)));
        track.velocity = Vector6::new(3.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        track.predicted = at(0.0);
        let t = 33_333;
        let extrapolated = Point3::new(0.1, 0.0, 0.6);
        let plain = track.update_roi(&camera, &config, t, true).unwrap();
        assert!(!contains(&plain, &camera, &extrapolated, 0.0));
        config.roi_widen_at_depth = true;
        let between = track.update_roi(&camera, &config, t, false).unwrap();
        assert_eq!(between, plain, "only depth exposures widen");
        let wide = track.update_roi(&camera, &config, t, true).unwrap();
        // Half a diameter (50 px at 0.6 m) of the object on either side fits in the ROI.
        for p in [Point3::new(0.0, 0.0, 0.6), extrapolated] {
            assert!(contains(&wide, &camera, &p, 40.0), "{wide:?} misses {p:?}");
        }
    }
}
