//! Evaluating a pose stream against a recording: ticks from the trigger timeline, ground truth at each tick,
//! per-frame scores, and the per-sequence summary at 120 Hz (every tick) and 30 Hz (depth-exposure ticks).

use super::frame::{EvalCameras, EvalModel, FrameEvaluator, FrameScore};
use super::pose_csv::PoseRecord;
use super::recall::{AucLimit, auc};
use super::symmetry::{SymmetryError, symmetries_of};
use crate::geometry::{PinholeCamera, se3};
use crate::mesh::{MeshLoadOptions, load_obj};
use drivers::event::{EventSink, TriggerEdge};
use drivers::recording::{CameraIntrinsics, CameraRig, PoseSample, Recording, RecordingError};
use drivers::timeline::{Tick, TickIter};
use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion};
use std::sync::Arc;

/// Why a recording could not be evaluated.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The recording has no `groundtruth.csv`.
    #[error("{0}: recording has no ground truth (groundtruth.csv), so it cannot be evaluated")]
    NoGroundTruth(String),
    /// The trigger timeline of `events.raw` yields no tick.
    #[error("{0}: events.raw has no trigger ticks on the scheduled channel")]
    NoTicks(String),
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
    /// Rendering for VSD failed.
    #[error("rendering for VSD failed: {0}")]
    Render(#[from] crate::render::RenderError),
}

struct TriggerCollector(Vec<TriggerEdge>);

impl EventSink for TriggerCollector {
    fn cd(&mut self, _: drivers::event::CdEvent) {}
    fn cd_vector(&mut self, _: i64, _: u16, _: u16, _: u32, _: bool) {}
    fn trigger(&mut self, edge: TriggerEdge) {
        self.0.push(edge);
    }
}

/// The recording's 120 Hz ticks (trigger rising edges through [`drivers::timeline`]), in order.
pub fn recording_ticks(rec: &Recording) -> Result<Vec<Tick>, EvalError> {
    let mut reader = rec.events()?;
    let mut sink = TriggerCollector(Vec::new());
    reader.read_all(&mut sink).map_err(|e| RecordingError {
        path: rec.dir().join("events.raw"),
        problem: e.to_string(),
    })?;
    let ticks: Vec<Tick> =
        TickIter::new(rec.meta.trigger.timeline_config(), sink.0.into_iter()).collect();
    if ticks.is_empty() {
        return Err(EvalError::NoTicks(rec.dir().display().to_string()));
    }
    Ok(ticks)
}

/// A pose sample as an isometry (`T_cam_obj`, metres).
pub fn sample_pose(s: &PoseSample) -> Isometry3<f64> {
    let [x, y, z, w] = s.rotation_xyzw;
    let [tx, ty, tz] = s.translation;
    Isometry3::from_parts(
        Translation3::new(tx, ty, tz),
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
    )
}

/// A time-sorted pose track of one object.
#[derive(Debug, Clone, Default)]
pub struct PoseTrack {
    times: Vec<i64>,
    poses: Vec<Isometry3<f64>>,
}

impl PoseTrack {
    /// A track from `(t_us, pose)` pairs (sorted here; a later duplicate time replaces an earlier one).
    pub fn new(mut samples: Vec<(i64, Isometry3<f64>)>) -> Self {
        samples.sort_by_key(|s| s.0);
        samples.dedup_by(|later, earlier| {
            if later.0 == earlier.0 {
                earlier.1 = later.1;
                true
            } else {
                false
            }
        });
        let (times, poses) = samples.into_iter().unzip();
        Self { times, poses }
    }

    /// The track of `object` in tracker output rows.
    pub fn from_records(records: &[PoseRecord], object: &str) -> Self {
        Self::new(
            records
                .iter()
                .filter(|r| r.object == object)
                .map(|r| (r.t_us, r.pose))
                .collect(),
        )
    }

    /// The ground-truth track of `object`.
    pub fn from_samples(samples: &[PoseSample], object: &str) -> Self {
        Self::new(
            samples
                .iter()
                .filter(|s| s.object == object)
                .map(|s| (s.t_us, sample_pose(s)))
                .collect(),
        )
    }

    /// Whether the track has no pose.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Time of the first pose, microseconds.
    pub fn first(&self) -> Option<(i64, Isometry3<f64>)> {
        Some((*self.times.first()?, *self.poses.first()?))
    }

    /// The latest pose at or before `t_us` (what a consumer of the stream holds at that time).
    pub fn held_at(&self, t_us: i64) -> Option<Isometry3<f64>> {
        let i = self.times.partition_point(|t| *t <= t_us);
        (i > 0).then(|| self.poses[i - 1])
    }

    /// The pose at `t_us`, interpolated on SE(3) between the neighbouring samples; None outside the track.
    pub fn interpolated_at(&self, t_us: i64) -> Option<Isometry3<f64>> {
        let i = self.times.partition_point(|t| *t < t_us);
        if i < self.times.len() && self.times[i] == t_us {
            return Some(self.poses[i]);
        }
        if i == 0 || i == self.times.len() {
            return None;
        }
        let (t0, t1) = (self.times[i - 1], self.times[i]);
        let s = (t_us - t0) as f64 / (t1 - t0) as f64;
        Some(se3::interpolate(&self.poses[i - 1], &self.poses[i], s))
    }
}

fn camera_of(c: &CameraIntrinsics, camera: &'static str) -> Result<PinholeCamera, EvalError> {
    PinholeCamera::new(c.fx, c.fy, c.cx, c.cy, c.width, c.height).map_err(|e| EvalError::Camera {
        camera,
        reason: e.to_string(),
    })
}

/// `T_event_depth` of a rig: maps depth-camera points (metres) into the event camera's frame.
pub fn event_from_depth(rig: &CameraRig) -> Isometry3<f64> {
    let m = rig.t_event_depth;
    let r = Matrix3::new(
        m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2],
    );
    Isometry3::from_parts(
        Translation3::new(m[0][3], m[1][3], m[2][3]),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
    )
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
    let info = rec.model(object).ok_or_else(|| EvalError::Model {
        object: object.into(),
        reason: "not listed in models/models_info.json".into(),
    })?;
    let loaded = load_obj(&rec.mesh_path(object), &MeshLoadOptions::default()).map_err(|e| {
        EvalError::Model {
            object: object.into(),
            reason: e.to_string(),
        }
    })?;
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

/// The objects with ground truth in `rec`, sorted by name.
pub fn ground_truth_objects(rec: &Recording) -> Result<Vec<String>, EvalError> {
    let gt = rec
        .ground_truth
        .as_ref()
        .ok_or_else(|| EvalError::NoGroundTruth(rec.dir().display().to_string()))?;
    let mut names: Vec<String> = gt.iter().map(|s| s.object.clone()).collect();
    names.sort();
    names.dedup();
    Ok(names)
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
        .ok_or_else(|| EvalError::NoGroundTruth(rec.dir().display().to_string()))?;
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
    use nalgebra::Vector3;

    #[test]
    fn held_and_interpolated_poses() {
        let a = Isometry3::translation(0.0, 0.0, 1.0);
        let b = Isometry3::translation(0.1, 0.0, 1.0);
        // Out of order with a duplicate time: the later row for t = 100 wins.
        let track = PoseTrack::new(vec![
            (100, Isometry3::translation(9.0, 9.0, 9.0)),
            (0, a),
            (100, b),
        ]);
        assert!(track.held_at(-1).is_none());
        assert_eq!(track.held_at(0), Some(a));
        assert_eq!(track.held_at(99), Some(a));
        assert_eq!(track.held_at(1000), Some(b));
        let mid = track.interpolated_at(25).unwrap();
        assert!((mid.translation.vector - Vector3::new(0.025, 0.0, 1.0)).norm() < 1e-12);
        assert_eq!(track.interpolated_at(100), Some(b));
        assert!(track.interpolated_at(101).is_none());
        assert!(track.interpolated_at(-1).is_none());
        assert_eq!(track.first().map(|f| f.0), Some(0));
    }

    #[test]
    fn summary_of_no_frames_is_zero() {
        let s = summarise(&[], 0.1, AucLimit::Diameter);
        assert_eq!((s.add_s, s.add, s.ar, s.frames), (0.0, 0.0, 0.0, 0));
    }
}
