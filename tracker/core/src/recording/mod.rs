//! What the tracker reads from a recording directory ([`drivers::recording`]) or a rig description: the tracking
//! rig (cameras and extrinsics), the tracked objects (mesh, diameter, symmetries), the trigger timeline's ticks,
//! ground-truth pose tracks, and the tracker's own pose CSV. Evaluation and the application build on these; nothing
//! here scores a pose.

mod ground_truth;
mod object;
mod pose_csv;
mod rig;
mod symmetry;

pub use ground_truth::{PoseTrack, ground_truth_objects, sample_pose};
pub use object::recording_object;
pub use pose_csv::{
    POSE_CSV_HEADER, POSE_STATES, PoseCsvError, PoseRecord, PoseRow, apply_revisions,
    format_pose_csv, parse_pose_csv,
};
pub use rig::{camera_of, event_from_depth, recording_rig, recording_ticks, tracking_rig};
pub use symmetry::{MAX_SYM_DISC_STEP, SymmetryError, symmetries_of, symmetry_transforms};

use drivers::recording::RecordingError;

/// Why a recording (or a rig description) cannot be set up for tracking.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The recording has no `groundtruth.csv`.
    #[error("{0}: recording has no ground truth (groundtruth.csv), so it cannot be evaluated")]
    NoGroundTruth(String),
    /// The trigger timeline of `events.raw` yields no tick.
    #[error("{0}: events.raw has no trigger ticks on the scheduled channel")]
    NoTicks(String),
    /// An object's model is missing or unusable.
    #[error("object {object}: {reason}")]
    Model {
        /// Object name.
        object: String,
        /// What is wrong.
        reason: String,
    },
    /// A camera of the recording has unusable intrinsics.
    #[error("{camera} intrinsics: {reason}")]
    Camera {
        /// Which camera (`event camera`, `depth camera`).
        camera: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Declared symmetries are invalid.
    #[error(transparent)]
    Symmetry(#[from] SymmetryError),
}
