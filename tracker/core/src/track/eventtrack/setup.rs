//! What a tracker is built from (the objects and the rig) and why building one can fail.

use crate::recon::DepthRig;
use crate::track::clock::TickClock;
use nalgebra::Isometry3;
use scene::geometry::PinholeCamera;
use scene::mesh::{Mesh, Symmetry};
use scene::render::RenderError;
use std::sync::Arc;

/// Why a tracker could not be built.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    /// No object to track.
    #[error("no object to track")]
    NoObjects,
    /// Too many objects for the renderer's mask labels.
    #[error("{0} objects: at most 65534 can be tracked")]
    TooManyObjects(usize),
    /// An object's first pose is unusable.
    #[error("object {object}: first pose is {reason}")]
    BadFirstPose {
        /// Object name.
        object: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// The renderer refused a mesh or could not render the object's first ROI.
    #[error("object {object}: {source}")]
    Render {
        /// Object name.
        object: String,
        /// The renderer's error.
        source: RenderError,
    },
}

/// An object to track: name, model and first pose.
#[derive(Debug, Clone)]
pub struct TrackedObject {
    /// Name (as in the recording's ground truth and on the wire).
    pub name: String,
    /// The CAD model, metres.
    pub mesh: Arc<Mesh>,
    /// Diameter, metres (from `models_info.json`, or the mesh's own).
    pub diameter: f64,
    /// Time of the first pose, microseconds on the event camera's clock.
    pub first_t_us: i64,
    /// First pose `T_cam_obj`, event camera frame.
    pub first_pose: Isometry3<f64>,
    /// Shape symmetries (object frame, from `models_info.json`; empty when unknown). A rotation about a continuous
    /// symmetry axis is invisible in shape, so the tracker keeps no spin about such an axis in its velocity.
    pub symmetries: Vec<Symmetry>,
}

/// The cameras a tracker works with, and the clock of the trigger that synchronises them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingRig {
    /// Event camera intrinsics (poses are in this camera's frame).
    pub event_camera: PinholeCamera,
    /// Depth camera and its extrinsics.
    pub depth: DepthRig,
    /// The trigger's tick rate.
    pub clock: TickClock,
}
