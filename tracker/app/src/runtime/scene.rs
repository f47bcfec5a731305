//! What a tracker is built from: the rig and the objects with their first poses, whichever source shows them.

use super::config::ObjectConfig;
use drivers::recording::{CameraRig, ModelInfo, Recording};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use std::path::PathBuf;

/// One object to track.
#[derive(Debug, Clone)]
pub struct SceneObject {
    /// Name (topics, CSV rows).
    pub name: String,
    /// OBJ mesh, metres.
    pub mesh: PathBuf,
    /// BOP-style model information when the recording has it.
    pub info: Option<ModelInfo>,
    /// First pose: time on the event camera's clock (microseconds) and `T_cam_obj`.
    pub first_pose: (i64, Isometry3<f64>),
}

/// What a tracker is built from: the rig and the objects with their first poses.
#[derive(Debug, Clone)]
pub struct TrackerScene {
    /// Cameras and `T_event_depth`.
    pub rig: CameraRig,
    /// Objects, in output order.
    pub objects: Vec<SceneObject>,
    /// The recording being replayed, if any.
    pub recording: Option<Recording>,
}

/// The first pose `T_cam_obj` an `[[objects]]` entry gives.
pub fn pose_of(o: &ObjectConfig) -> Isometry3<f64> {
    let [x, y, z, w] = o.orientation;
    Isometry3::from_parts(
        Translation3::new(o.position[0], o.position[1], o.position[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
    )
}
