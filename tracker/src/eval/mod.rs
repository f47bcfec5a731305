//! Pose evaluation (DESIGN section 9): the BOP toolkit's pose errors (ADD, ADD-S, VSD, MSSD, MSPD) and scores
//! (AUC of ADD / ADD-S, BOP 2019 average recall), tracker pose files, the per-recording evaluation protocol of
//! the paper (every 120 Hz tick, or depth-exposure ticks only) and the benchmark's methods and report.
//!
//! Poses are `T_cam_obj` in the event camera frame, metres; object points are in the object frame, metres.

pub mod bench;
mod frame;
mod harness_checks;
mod kdtree;
pub mod plot;
mod pose_csv;
mod pose_error;
pub mod quality_report;
mod recall;
pub mod report;
pub mod seed_spread;
mod sequence;
mod symmetry;
mod vsd;

pub use frame::{
    EvalCameras, EvalModel, FrameEvaluator, FrameScore, MAX_MODEL_POINTS, MIN_MODEL_POINTS,
    PoseErrors, score_errors,
};
pub use kdtree::KdTree;
pub use pose_csv::{
    BOP_CSV_HEADER, BopRow, POSE_CSV_HEADER, PoseCsvError, PoseRecord, PoseRow, apply_revisions,
    format_bop_csv, format_pose_csv, parse_pose_csv,
};
pub use pose_error::{add, add_s, mspd, mssd};
pub use recall::{
    AUC_STEPS, AucLimit, VSD_DELTA, auc, average_recall, bop_fraction_thresholds, mspd_recall,
    mspd_thresholds_px, mssd_recall, recall_over, vsd_recall, vsd_taus,
};
pub use sequence::{
    EvalError, ObjectSequence, PoseTrack, Summary, evaluate_object, event_from_depth,
    ground_truth_objects, recording_cameras, recording_model, recording_ticks, rig_cameras,
    sample_pose, summarise,
};
pub use symmetry::{MAX_SYM_DISC_STEP, SymmetryError, symmetries_of, symmetry_transforms};
pub use vsd::{VsdRenderer, depth_to_distance, vsd_from_distances};
