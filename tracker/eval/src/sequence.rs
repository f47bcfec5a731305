//! Evaluating a pose stream against a recording: ticks from the trigger timeline, ground truth at each tick,
//! per-frame scores, and the per-sequence summary at 120 Hz (every tick) and 30 Hz (depth-exposure ticks).

use super::frame::{EvalCameras, EvalModel, FrameEvaluator, FrameScore};
use super::recall::{AucLimit, auc};
use drivers::recording::{CameraRig, Recording, RecordingError};
use drivers::timeline::Tick;
use scene::mesh::{MeshLoadOptions, load_obj};
use std::sync::Arc;
use tracker::recording::{
    PoseTrack, SetupError, SymmetryError, camera_of, event_from_depth, symmetries_of,
};

/// Why a recording could not be evaluated.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The recording, its rig or its models could not be read.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// The ground truth of an object covers none of the recording's ticks (a damaged `events.raw` whose clock
    /// jumped, or a `groundtruth.csv` of another recording).
    #[error(
        "object `{object}`: its ground truth covers none of the recording's {ticks} ticks (is events.raw or \
         groundtruth.csv damaged? `eventtrack6d inspect` shows the event clock's span)"
    )]
    Uncovered {
        /// Object name.
        object: String,
        /// Ticks of the recording's trigger timeline.
        ticks: usize,
    },
    /// Rendering for VSD failed.
    #[error("rendering for VSD failed: {0}")]
    Render(#[from] scene::render::RenderError),
}

impl From<RecordingError> for EvalError {
    fn from(e: RecordingError) -> Self {
        Self::Setup(SetupError::Recording(e))
    }
}

impl From<SymmetryError> for EvalError {
    fn from(e: SymmetryError) -> Self {
        Self::Setup(SetupError::Symmetry(e))
    }
}

impl EvalError {
    /// An object's model is missing or unusable.
    pub fn model(object: &str, reason: String) -> Self {
        Self::Setup(SetupError::Model {
            object: object.into(),
            reason,
        })
    }
}

/// The evaluation cameras of a rig (poses in the event camera, VSD in the depth camera).
pub fn rig_cameras(rig: &CameraRig) -> Result<EvalCameras, EvalError> {
    Ok(EvalCameras {
        pose_camera: camera_of(&rig.event_camera, "event camera")?,
        depth_camera: camera_of(&rig.depth_camera, "depth camera")?,
        depth_from_pose: event_from_depth(rig).inverse(),
    })
}

/// The evaluation cameras of a recording ([`rig_cameras`] of its rig).
pub fn recording_cameras(rec: &Recording) -> Result<EvalCameras, EvalError> {
    rig_cameras(&rec.rig)
}

/// The evaluation model of `object` in `rec`: its mesh, `models_info.json` diameter and symmetries.
pub fn recording_model(rec: &Recording, object: &str) -> Result<EvalModel, EvalError> {
    let info = rec
        .model(object)
        .ok_or_else(|| EvalError::model(object, "not listed in models/models_info.json".into()))?;
    let loaded = load_obj(&rec.mesh_path(object), &MeshLoadOptions::default())
        .map_err(|e| EvalError::model(object, e.to_string()))?;
    let symmetries = symmetries_of(info)?;
    Ok(EvalModel::new(
        object,
        Arc::new(loaded.mesh),
        info.diameter_m,
        &symmetries,
    ))
}

/// The frame scores of one object over one recording.
#[derive(Debug, Clone)]
pub struct ObjectSequence {
    /// Object name.
    pub object: String,
    /// Object diameter, metres.
    pub diameter: f64,
    /// One score per tick, in time order.
    pub frames: Vec<FrameScore>,
}

/// Scores the predicted `track` of `object` at every tick of `ticks` (the held prediction at the tick time; a tick
/// before the first prediction scores as missing). Depth-exposure ticks use the measured depth frame for VSD.
pub fn evaluate_object(
    rec: &Recording,
    ticks: &[Tick],
    object: &str,
    track: &PoseTrack,
) -> Result<ObjectSequence, EvalError> {
    let samples = rec
        .ground_truth
        .as_ref()
        .ok_or_else(|| SetupError::NoGroundTruth(rec.dir().display().to_string()))?;
    let gt = PoseTrack::from_samples(samples, object);
    let model = recording_model(rec, object)?;
    let diameter = model.diameter;
    let mut evaluator = FrameEvaluator::new(model, recording_cameras(rec)?)?;
    let mut frames = Vec::with_capacity(ticks.len());
    for tick in ticks {
        let Some(gt_pose) = gt.interpolated_at(tick.t_us) else {
            continue; // no ground truth at this time: not evaluated
        };
        let depth = match tick.depth_frame {
            Some(n) if rec.depth_frames.contains(&n) => Some(rec.depth_frame(n)?.depth_m),
            _ => None,
        };
        let est = track.held_at(tick.t_us);
        frames.push(evaluator.score(
            tick.t_us,
            tick.depth_frame.is_some(),
            est.as_ref(),
            &gt_pose,
            depth.as_deref(),
        )?);
    }
    if frames.is_empty() && !ticks.is_empty() {
        return Err(EvalError::Uncovered {
            object: object.into(),
            ticks: ticks.len(),
        });
    }
    Ok(ObjectSequence {
        object: object.into(),
        diameter,
        frames,
    })
}

/// Summary scores of a set of frames, percent (0-100).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Summary {
    /// AUC of ADD-S.
    pub add_s: f64,
    /// AUC of ADD.
    pub add: f64,
    /// Mean per-frame AR.
    pub ar: f64,
    /// Number of frames.
    pub frames: usize,
}

/// Summarises `frames` of an object of `diameter` metres; `depth_only` keeps depth-exposure ticks only (the 30 Hz
/// protocol). AUC thresholds run to `limit`.
pub fn summarise(frames: &[&FrameScore], diameter: f64, limit: AucLimit) -> Summary {
    let max = limit.max_threshold(diameter);
    let adds: Vec<f64> = frames.iter().map(|f| f.errors.add_s).collect();
    let add_: Vec<f64> = frames.iter().map(|f| f.errors.add).collect();
    let ar = if frames.is_empty() {
        0.0
    } else {
        100.0 * frames.iter().map(|f| f.ar).sum::<f64>() / frames.len() as f64
    };
    Summary {
        add_s: auc(&adds, max),
        add: auc(&add_, max),
        ar,
        frames: frames.len(),
    }
}

impl ObjectSequence {
    /// Summary over every tick (120 Hz) or, with `depth_only`, over depth-exposure ticks (30 Hz).
    pub fn summary(&self, depth_only: bool, limit: AucLimit) -> Summary {
        let frames: Vec<&FrameScore> = self
            .frames
            .iter()
            .filter(|f| !depth_only || f.depth_tick)
            .collect();
        summarise(&frames, self.diameter, limit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_of_no_frames_is_zero() {
        let s = summarise(&[], 0.1, AucLimit::Diameter);
        assert_eq!((s.add_s, s.add, s.ar, s.frames), (0.0, 0.0, 0.0, 0));
    }
}
