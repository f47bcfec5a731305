//! What a tracker says about one object at one instant.

use nalgebra::Isometry3;

/// How much a pose estimate can be trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrackingState {
    /// The object is tracked: residuals, visibility and event support are normal.
    Tracking,
    /// Still tracked, but evidence is weak (occluded, few valid depth pixels, little event support).
    Degraded,
    /// The tracker has lost the object; the pose is the last trusted one and must not be used for control.
    Lost,
}

impl TrackingState {
    /// Lower-case name as in pose CSVs and the status topic (`tracking`, `degraded`, `lost`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Tracking => "tracking",
            Self::Degraded => "degraded",
            Self::Lost => "lost",
        }
    }

    /// Wire code used on CAN: 0 tracking, 1 degraded, 2 lost.
    pub fn code(self) -> u8 {
        match self {
            Self::Tracking => 0,
            Self::Degraded => 1,
            Self::Lost => 2,
        }
    }
}

/// The state a tracker reports for one object: a worse state at once, a better one only after it held for a
/// number of consecutive ticks, so a consumer gating on `tracking` does not resume on a single good tick and the
/// report does not chatter while the evidence hovers at a threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReportedState {
    reported: TrackingState,
    better_ticks: u32,
}

impl ReportedState {
    /// Starts at `state`.
    pub fn new(state: TrackingState) -> Self {
        Self {
            reported: state,
            better_ticks: 0,
        }
    }

    /// The reported state.
    pub fn get(&self) -> TrackingState {
        self.reported
    }

    /// Takes this tick's state and returns the one to report: `state` if it is as bad or worse than the reported
    /// one; otherwise `state` once better states have held for `recover_ticks` ticks in a row (0 or 1: at once),
    /// the reported state until then.
    pub fn update(&mut self, state: TrackingState, recover_ticks: u32) -> TrackingState {
        if state.code() >= self.reported.code() {
            self.reported = state;
            self.better_ticks = 0;
        } else {
            self.better_ticks += 1;
            if self.better_ticks >= recover_ticks {
                self.reported = state;
                self.better_ticks = 0;
            }
        }
        self.reported
    }
}

/// One object's estimated pose at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEstimate {
    /// Index of the object in [`super::PoseTracker::objects`].
    pub object: usize,
    /// Time on the event camera's clock, microseconds.
    pub t_us: i64,
    /// `T_cam_obj`: object frame into the event camera frame (OpenCV convention), metres.
    pub pose: Isometry3<f64>,
    /// Confidence in `[0, 1]` (1 = residuals, visibility and event support all nominal).
    pub quality: f32,
    /// Tracking state derived from the quality evidence, as reported: worse at once, better only after it held
    /// for `[quality] recover_ticks` ticks (see [`ReportedState`]).
    pub state: TrackingState,
}

#[cfg(test)]
mod tests {
    use super::*;
    use TrackingState::{Degraded, Lost, Tracking};

    #[test]
    fn a_worse_state_is_reported_at_once_and_a_better_one_after_it_held() {
        let mut r = ReportedState::new(Tracking);
        assert_eq!(r.update(Degraded, 3), Degraded);
        // Two good ticks are not enough; a bad one in between starts the count again.
        assert_eq!(r.update(Tracking, 3), Degraded);
        assert_eq!(r.update(Tracking, 3), Degraded);
        assert_eq!(r.update(Degraded, 3), Degraded);
        assert_eq!(r.update(Tracking, 3), Degraded);
        assert_eq!(r.update(Tracking, 3), Degraded);
        assert_eq!(r.update(Tracking, 3), Tracking);
        assert_eq!(r.update(Lost, 3), Lost);
        // Any better state counts; the one reported is the latest.
        assert_eq!(r.update(Degraded, 3), Lost);
        assert_eq!(r.update(Tracking, 3), Lost);
        assert_eq!(r.update(Tracking, 3), Tracking);
        assert_eq!(r.get(), Tracking);
        // Staying as bad does not count towards recovery.
        for _ in 0..3 {
            assert_eq!(r.update(Lost, 3), Lost);
        }
        assert_eq!(r.update(Tracking, 3), Lost);
        // 0 or 1 reports every tick's state.
        assert_eq!(r.update(Lost, 1), Lost);
        assert_eq!(r.update(Tracking, 1), Tracking);
        assert_eq!(r.update(Degraded, 0), Degraded);
        assert_eq!(r.update(Tracking, 0), Tracking);
    }
}
