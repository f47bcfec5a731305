//! EventTrack6D's evaluation (DESIGN section 9): the BOP toolkit's pose errors (ADD, ADD-S, VSD, MSSD, MSPD) and
//! scores (AUC of ADD / ADD-S, BOP 2019 average recall), the per-recording evaluation protocol of the paper (every
//! 120 Hz tick, or depth-exposure ticks only), the benchmark harness with its methods (the tracker presets, the
//! harness baselines), its reports and plots, and overlay images.
//!
//! Poses are `T_cam_obj` in the event camera frame, metres; object points are in the object frame, metres.
//!
//! Depends on `drivers`, `scene` and the tracker (`tracker`); the application uses it for `eventtrack6d eval`,
//! `bench` and the demo's accuracy line. The product's real-time path does not.

pub mod bench;
mod bop;
mod frame;
mod kdtree;
mod overlay;
pub mod paired;
pub mod plot;
mod pose_error;
pub mod quality_report;
mod recall;
pub mod report;
pub mod seed_spread;
mod sequence;
mod vsd;

pub use bench::{InitNoise, TrackerMethod};
pub use bop::{BOP_CSV_HEADER, BopRow, format_bop_csv};
pub use frame::{
    EvalCameras, EvalModel, FrameEvaluator, FrameScore, MAX_MODEL_POINTS, MIN_MODEL_POINTS,
    PoseErrors, score_errors,
};
pub use kdtree::KdTree;
pub use overlay::{OverlayRenderer, OverlayWriter, overlay_strip};
pub use pose_error::{add, add_s, mspd, mssd};
pub use recall::{
    AUC_STEPS, AucLimit, VSD_DELTA, auc, average_recall, bop_fraction_thresholds, mspd_recall,
    mspd_thresholds_px, mssd_recall, recall_over, vsd_recall, vsd_taus,
};
pub use sequence::{
    EvalError, ObjectSequence, Summary, evaluate_object, recording_cameras, recording_model,
    rig_cameras, summarise,
};
pub use vsd::{VsdRenderer, depth_to_distance, vsd_from_distances};
