//! The per-tick ROS 2 outputs beside the poses: TF, detections and the tracking state as diagnostics, built from a
//! tick's estimates into reused buffers.

use crate::publish::TickPoses;
use crate::publish::ros2::diagnostic::{
    DiagnosticArray, DiagnosticStatus, encode_diagnostic_array, level,
};
use crate::publish::ros2::tf::{TransformStamped, encode_tf_message};
use crate::publish::ros2::vision::{
    Detection3D, Detection3DArray, ObjectHypothesisWithPose, encode_detection3d_array,
};
use crate::publish::ros2::{Header, Pose, RosTime};
use nalgebra::Point3;
use std::sync::{Arc, Mutex};
use tracker::track::TrackingState;

/// An object as the outputs describe it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectOutput {
    /// Name (topics, detection ids, class ids).
    pub name: String,
    /// The mesh's axis-aligned bounding box in the object frame, metres: (min, max). Zero-sized at the origin when
    /// not known.
    pub bounds: ([f64; 3], [f64; 3]),
}

impl ObjectOutput {
    /// An object with no known bounds.
    pub fn named(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            bounds: ([0.0; 3], [0.0; 3]),
        }
    }
}

/// The latest control outcome of each object, in words (shared with the control callbacks).
pub type LastControl = Arc<Mutex<Vec<Option<String>>>>;

/// What the per-tick outputs describe, and how.
pub(super) struct OutputContent {
    /// Objects in tracker order.
    pub objects: Vec<ObjectOutput>,
    /// TF child frame per object.
    pub child_frames: Vec<String>,
    /// `header.frame_id`: the camera frame.
    pub frame_id: String,
    /// The node's name (diagnostic status names are `<node>: <object>`).
    pub node_name: String,
    /// Each object's latest control outcome.
    pub last_control: LastControl,
}

/// Stamp of a time on the camera's clock: `t_us * 1000 + offset`.
pub(super) fn stamp_of(t_us: i64, ros_time_offset_ns: i64) -> Result<RosTime, String> {
    t_us.checked_mul(1000)
        .and_then(|ns| ns.checked_add(ros_time_offset_ns))
        .ok_or_else(|| format!("pose time {t_us} us + offset overflows i64 nanoseconds"))
        .and_then(|ns| RosTime::from_nanos(ns).map_err(|e| e.to_string()))
}

impl OutputContent {
    /// TF of a tick: one transform per object that is not lost.
    pub fn tf(
        &self,
        poses: &TickPoses<'_>,
        offset_ns: i64,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        let mut transforms = Vec::with_capacity(poses.estimates.len());
        for e in poses.estimates {
            if e.state == TrackingState::Lost {
                continue;
            }
            let p = Pose::from_isometry(&e.pose);
            transforms.push(TransformStamped {
                header: Header::new(stamp_of(e.t_us, offset_ns)?, &self.frame_id),
                child_frame_id: self.child_frames.get(e.object).cloned().unwrap_or_default(),
                translation: p.position,
                rotation_xyzw: p.orientation_xyzw,
            });
        }
        encode_tf_message(out, &transforms);
        Ok(())
    }

    /// Detections of a tick: one per object, the quality as the score, the box centred on the mesh's bounds.
    pub fn detections(
        &self,
        poses: &TickPoses<'_>,
        offset_ns: i64,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        let header = Header::new(stamp_of(poses.tick.t_us, offset_ns)?, &self.frame_id);
        let mut detections = Vec::with_capacity(poses.estimates.len());
        for e in poses.estimates {
            let object = self
                .objects
                .get(e.object)
                .cloned()
                .unwrap_or_else(|| ObjectOutput::named("?"));
            let (min, max) = object.bounds;
            let centre_obj = Point3::new(
                0.5 * (min[0] + max[0]),
                0.5 * (min[1] + max[1]),
                0.5 * (min[2] + max[2]),
            );
            let mut centre = Pose::from_isometry(&e.pose);
            let c = e.pose * centre_obj;
            centre.position = [c.x, c.y, c.z];
            detections.push(Detection3D {
                header: Header::new(stamp_of(e.t_us, offset_ns)?, &self.frame_id),
                results: vec![ObjectHypothesisWithPose {
                    class_id: object.name.clone(),
                    score: f64::from(e.quality),
                    pose: Pose::from_isometry(&e.pose),
                    covariance: [0.0; 36],
                }],
                bbox_center: centre,
                bbox_size: [max[0] - min[0], max[1] - min[1], max[2] - min[2]],
                id: object.name,
            });
        }
        encode_detection3d_array(out, &Detection3DArray { header, detections });
        Ok(())
    }

    /// The tracking state of a tick: one status per object.
    pub fn diagnostics(
        &self,
        poses: &TickPoses<'_>,
        offset_ns: i64,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        let header = Header::new(stamp_of(poses.tick.t_us, offset_ns)?, &self.frame_id);
        let last = self
            .last_control
            .lock()
            .map(|l| l.clone())
            .unwrap_or_default();
        let mut status = Vec::with_capacity(poses.estimates.len());
        for e in poses.estimates {
            let name = self.objects.get(e.object).map_or("?", |o| o.name.as_str());
            let state = e.state.as_str();
            let mut values = vec![
                ("object".to_owned(), name.to_owned()),
                ("state".to_owned(), state.to_owned()),
                ("quality".to_owned(), e.quality.to_string()),
                ("t_us".to_owned(), e.t_us.to_string()),
            ];
            if let Some(Some(control)) = last.get(e.object) {
                values.push(("last_control".to_owned(), control.clone()));
            }
            status.push(DiagnosticStatus {
                level: match e.state {
                    TrackingState::Tracking => level::OK,
                    TrackingState::Degraded => level::WARN,
                    TrackingState::Lost => level::ERROR,
                },
                name: format!("{}: {name}", self.node_name),
                message: state.to_owned(),
                hardware_id: self.frame_id.clone(),
                values,
            });
        }
        encode_diagnostic_array(out, &DiagnosticArray { header, status });
        Ok(())
    }
}
