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
    /// Tracking state derived from the quality evidence.
    pub state: TrackingState,
}
