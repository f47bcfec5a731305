//! What one tick hands every object: its time, the depth frame it uses, the event state and the cameras.

use crate::recon::{DepthRig, EventSurface};
use drivers::recording::DepthFrame;
use scene::geometry::PinholeCamera;

/// Per-tick inputs shared by every object.
pub(crate) struct TickInputs<'a> {
    /// Tick time, microseconds (event camera clock).
    pub t_us: i64,
    /// Seconds since the previous tick.
    pub dt_s: f64,
    /// The depth frame this tick uses, if any (in the depth camera's pixels).
    pub depth: Option<&'a DepthFrame>,
    /// Exposure of `depth`, microseconds: `t_us`, or earlier for a frame that arrived after its own tick.
    pub depth_exposed_us: i64,
    /// The event state (time surface, `I_t`).
    pub surface: &'a EventSurface,
    /// The full event camera.
    pub camera: &'a PinholeCamera,
    /// The depth camera and its extrinsics.
    pub depth_rig: &'a DepthRig,
}
