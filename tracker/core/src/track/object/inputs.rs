//! What one tick hands every object: its time, the depth frame it uses, the event state and the cameras.

use crate::recon::{DepthRig, EventSurface};
use drivers::recording::DepthFrame;
use scene::geometry::PinholeCamera;

/// Per-tick inputs shared by every object.
#[derive(Clone, Copy)]
pub(crate) struct TickInputs<'a> {
    /// Tick time, microseconds (event camera clock).
    pub t_us: i64,
    /// Seconds since the previous tick or step between ticks.
    pub dt_s: f64,
    /// Whether this is a step between ticks ([`crate::track::InnerStepConfig`]): it moves the estimate and its
    /// velocity, not its quality or state.
    pub inner: bool,
    /// The fraction of a tick period this object's step spans: 1 at a tick without steps between ticks, less at
    /// a step between ticks and at the tick after them (each spans only the time since its object's latest
    /// estimate).
    pub span: f64,
    /// At a tick after steps between ticks: the previous tick's time, microseconds. The velocity is measured
    /// over the whole tick period, from the estimate then (a step's span is too short to measure it well); steps
    /// between ticks leave it as it is.
    pub velocity_since_us: Option<i64>,
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
