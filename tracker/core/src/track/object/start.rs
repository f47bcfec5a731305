//! What the correspond phase hands the optimise and assess phases: this tick's depth and where the optimisation
//! starts.

use crate::refine::DepthTermStats;
use nalgebra::Isometry3;

/// The depth a tick's refinement uses, prepared by [`super::correspond::prepare_depth`] before the ROI render is taken.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct TickDepth {
    /// A depth frame was registered as the new `D_0` at this tick (exposed now, or late and carried here).
    pub fresh: bool,
    /// Weight of the depth term (1 for a fresh frame, `carried_depth_weight` between frames, 0 without depth).
    pub weight: f64,
    /// `depth_now` holds `D_t` rendered at the predicted pose.
    pub at_predicted: bool,
}

/// Where the optimisation starts and what it uses, from [`super::correspond::correspond`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Start {
    /// The pose the optimisation starts from.
    pub pose: Isometry3<f64>,
    /// This tick's depth.
    pub depth: TickDepth,
    /// The depth frame used here was exposed at an earlier tick.
    pub late: bool,
    /// A late frame's depth counts at its exposure.
    pub late_fit: Option<DepthTermStats>,
    /// The events take part (the model shows an outline and events are on).
    pub use_events: bool,
    /// The event residuals take part (not contrast maximisation, which only moves the start).
    pub use_event_residuals: bool,
    /// The intensity-edge residuals take part.
    pub use_intensity: bool,
    /// The event window, seconds.
    pub window_s: f64,
}
