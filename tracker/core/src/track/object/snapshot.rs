//! An object's tracking state at one tick, without its per-tick buffers: saved at depth-exposure ticks so that a
//! depth frame arriving late can be put in place at its exposure and the ticks since tracked again.

use super::ObjectTrack;
use super::history::PoseHistory;
use super::quality_window::QualityWindow;
use crate::recon::{CarriedDepth, MovingNeighbourhood};
use crate::track::estimate::{ReportedState, TrackingState};
use crate::track::fallback_check::DepthFallbackCheck;
use nalgebra::{Isometry3, Vector6};
use scene::geometry::Roi;

/// Everything of an [`ObjectTrack`] that one tick hands to the next. The rest of the track (render target, model
/// view, event and depth images) is rebuilt at every tick. Saving into a snapshot that has held a state before
/// reuses its buffers.
#[derive(Debug, Clone)]
pub(crate) struct ObjectSnapshot {
    pose: Isometry3<f64>,
    t_us: i64,
    previous: Option<(i64, Isometry3<f64>)>,
    velocity: Vector6<f64>,
    predicted: Isometry3<f64>,
    anchor: Option<(i64, Isometry3<f64>)>,
    anchor_before: Option<(i64, Isometry3<f64>)>,
    quality: f32,
    state: TrackingState,
    reported: ReportedState,
    low_ticks: u32,
    recent_quality: QualityWindow,
    fallbacks: u64,
    redetections: u64,
    fallback_check: Option<DepthFallbackCheck>,
    depth_fit: f64,
    visibility: f64,
    depth_frames_used: u32,
    first_us: i64,
    history: PoseHistory,
    late_frame: Option<(i64, Isometry3<f64>)>,
    late_motion: Option<(i64, Isometry3<f64>)>,
    late_depth_unplaced: u64,
    roi: Option<Roi>,
    carried: CarriedDepth,
    neighbourhood: MovingNeighbourhood,
}

impl ObjectSnapshot {
    /// The state of `track` now.
    pub fn of(track: &ObjectTrack) -> Self {
        let mut snapshot = Self {
            pose: Isometry3::identity(),
            t_us: 0,
            previous: None,
            velocity: Vector6::zeros(),
            predicted: Isometry3::identity(),
            anchor: None,
            anchor_before: None,
            quality: 0.0,
            state: TrackingState::Tracking,
            reported: ReportedState::new(TrackingState::Tracking),
            low_ticks: 0,
            recent_quality: QualityWindow::new(0),
            fallbacks: 0,
            redetections: 0,
            fallback_check: None,
            depth_fit: 0.0,
            visibility: 0.0,
            depth_frames_used: 0,
            first_us: 0,
            history: PoseHistory::new(),
            late_frame: None,
            late_motion: None,
            late_depth_unplaced: 0,
            roi: None,
            carried: CarriedDepth::new(),
            neighbourhood: MovingNeighbourhood::new(),
        };
        track.save(&mut snapshot);
        snapshot
    }
}

impl ObjectTrack {
    /// Saves this track's state into `snapshot`, reusing its buffers.
    pub fn save(&self, snapshot: &mut ObjectSnapshot) {
        let s = snapshot;
        s.pose = self.pose;
        s.t_us = self.t_us;
        s.previous = self.previous;
        s.velocity = self.velocity;
        s.predicted = self.predicted;
        s.anchor = self.anchor;
        s.anchor_before = self.anchor_before;
        s.quality = self.quality;
        s.state = self.state;
        s.reported = self.reported;
        s.low_ticks = self.low_ticks;
        s.recent_quality.clone_from(&self.recent_quality);
        s.fallbacks = self.fallbacks;
        s.redetections = self.redetections;
        s.fallback_check = self.fallback_check;
        s.depth_fit = self.depth_fit;
        s.visibility = self.visibility;
        s.depth_frames_used = self.depth_frames_used;
        s.first_us = self.first_us;
        s.history.clone_from(&self.history);
        s.late_frame = self.late_frame;
        s.late_motion = self.late_motion;
        s.late_depth_unplaced = self.late_depth_unplaced;
        s.roi = self.roi;
        s.carried.clone_from(&self.carried);
        s.neighbourhood.clone_from(&self.neighbourhood);
    }

    /// Puts this track back in the state `snapshot` saved (buffers reused); the per-tick buffers are left as they
    /// are, since the next tick rebuilds them.
    pub fn restore(&mut self, snapshot: &ObjectSnapshot) {
        let s = snapshot;
        self.pose = s.pose;
        self.t_us = s.t_us;
        self.previous = s.previous;
        self.velocity = s.velocity;
        self.predicted = s.predicted;
        self.anchor = s.anchor;
        self.anchor_before = s.anchor_before;
        self.quality = s.quality;
        self.state = s.state;
        self.reported = s.reported;
        self.low_ticks = s.low_ticks;
        self.recent_quality.clone_from(&s.recent_quality);
        self.fallbacks = s.fallbacks;
        self.redetections = s.redetections;
        self.fallback_check = s.fallback_check;
        self.depth_fit = s.depth_fit;
        self.visibility = s.visibility;
        self.depth_frames_used = s.depth_frames_used;
        self.first_us = s.first_us;
        self.history.clone_from(&s.history);
        self.late_frame = s.late_frame;
        self.late_motion = s.late_motion;
        self.late_depth_unplaced = s.late_depth_unplaced;
        self.roi = s.roi;
        self.carried.clone_from(&s.carried);
        self.neighbourhood.clone_from(&s.neighbourhood);
    }
}
