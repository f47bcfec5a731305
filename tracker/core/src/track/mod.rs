//! Per-object pose tracking: the interface the runtime drives ([`PoseTracker`]) and what it produces
//! ([`PoseEstimate`]).
//!
//! The runtime feeds a tracker in time order: events (camera clock, microseconds) with timestamps up to a tick,
//! then the depth frame exposed at that tick (if any), then [`PoseTracker::tick`], which appends one estimate per
//! tracked object.

mod clock;
mod config;
mod depth_transport;
mod drive;
mod estimate;
mod eventtrack;
mod fallback_check;
mod foreground_map;
mod hold;
mod object;
mod pose_search;
mod redetect;
mod validate;

pub use clock::TickClock;
pub use config::{
    CorrespondConfig, DepthUse, ExecutionConfig, InnerStepConfig, LateDepthConfig,
    MAX_DEPTH_AGE_LIMIT_MS, ModalityConfig, MotionConfig, OptimiserConfig, QualityConfig,
    RoiConfig, SafetyNetConfig, TrackerConfig, TrackerParameterKeys, TrackingMethod,
};
pub use depth_transport::DepthTransport;
pub use drive::{
    MAX_OVERDUE_EVENTS, OfflineStats, OfflineTiming, PulseHold, TickDriver, track_recording,
    track_recording_timed,
};
pub use estimate::{PoseEstimate, ReportedState, TrackingState};
pub use eventtrack::{EventTrack6d, TrackError, TrackedObject, TrackerCounters, TrackingRig};
pub use fallback_check::{
    DepthFallbackCheck, FALLBACK_TRACE_HEADER, FallbackCandidate, FallbackRule, FallbackStart,
};
pub use hold::HoldPoseTracker;
pub use redetect::RedetectConfig;
pub use validate::{InvalidParameter, validate};

use drivers::event::CdEvent;
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;
use nalgebra::Isometry3;

/// What a tracker does with a depth frame that arrives after its exposure's tick (one on time is used at its
/// tick in every case).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthHandling {
    /// Everything now: EventTrack6D tracks the ticks since the exposure again with the frame at once, so the
    /// next tick starts from estimates as if it had come on time.
    Now,
    /// The next tick carries the frame from its exposure (the cheap way), and the ticks since the exposure are
    /// tracked again once that tick's poses are out ([`PoseTracker::prepare_next_tick`]): for a frame that
    /// arrives just before a tick, whose work would delay it.
    AfterNextTick,
    /// The next tick carries the frame from its exposure and nothing is tracked again: for a caller that has
    /// fallen behind (counted in `late_frames_not_retracked`).
    CarryOnly,
}

/// A multi-object pose tracker driven tick by tick. Implementations must not allocate per tick in steady state and
/// must never block: the runtime calls them from the tracker thread.
pub trait PoseTracker: Send {
    /// Names of the tracked objects; [`PoseEstimate::object`] indexes this list.
    fn objects(&self) -> &[String];
    /// Events in time order (non-decreasing `t_us`), all at or before the next tick.
    fn push_events(&mut self, events: &[CdEvent]);
    /// The depth frame exposed at time `t_us` (the depth-exposure tick), in the depth camera's pixels, handled as
    /// `handling` says. It may arrive after that tick (a live depth camera's latency: EventTrack6D then tracks the
    /// ticks since the exposure again with it, or uses it at the next tick, up to
    /// [`crate::track::LateDepthConfig::max_depth_age_ms`] after the exposure). A tracker that keeps the frame takes it without a
    /// copy and leaves its previous frame in `frame` (for the caller to reuse or drop); one that does not leaves
    /// `frame` as it is.
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling);
    /// Estimates every object's pose at `tick` and appends one [`PoseEstimate`] per object to `out`.
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>);
    /// The earliest tick time (microseconds) whose estimate, already returned by [`Self::tick`], the tracker has
    /// revised since the last call, if it did (EventTrack6D: a late depth frame made it track the ticks since its
    /// exposure again). The revised poses are [`Self::pose_at`] those ticks; quality and state stay as returned.
    /// Ask after `push_depth`, `tick` and `prepare_next_tick`.
    fn take_revision(&mut self) -> Option<i64> {
        None
    }
    /// Work for the next tick that need not delay this tick's poses (EventTrack6D: start its renders,
    /// [`crate::track::ExecutionConfig::prefetch_renders`]); call it once the tick's poses are published. Skipping it changes no
    /// pose, only when the work is done.
    fn prepare_next_tick(&mut self) {}
    /// The pose of object `object` at any time `t_us` (interpolated between ticks, extrapolated at most one tick
    /// period past the last one); `None` before the first tick or for an unknown object.
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate>;
    /// The reconstructed event state (intensity `I_t`, time surface), for overlays; `None` if the tracker keeps
    /// none.
    fn event_surface(&self) -> Option<&crate::recon::EventSurface> {
        None
    }
    /// The hardware the tracker renders on; `None` if it renders nothing.
    fn render_device(&self) -> Option<scene::render::RenderDevice> {
        None
    }
    /// What the tracker did so far (re-detections, depth fallbacks, render errors, dropped re-detection places);
    /// `None` if it keeps no counters.
    fn tracker_counters(&self) -> Option<TrackerCounters> {
        None
    }
    /// Appends to `out` the depth safety-net checks of the latest tick, one per object that ran one (at fresh
    /// depth frames); nothing if the tracker has no safety net.
    fn depth_fallback_checks(&self, out: &mut Vec<DepthFallbackCheck>) {
        let _ = out;
    }
    /// Re-seeds object `object` at `pose` (`T_cam_obj`, the event camera's frame) as its estimate at `t_us` (an
    /// operator's or a detector's placement, or a reset to the first pose): the next tick refines from there with
    /// no motion assumed, and the object is `tracking` again. Tracking again from late depth frames exposed before
    /// the re-seed is given up (it would bring back the estimates the re-seed replaced). Returns why not for an
    /// unknown object, a pose that is not finite, or a tracker that cannot be re-seeded.
    fn reseed(&mut self, object: usize, t_us: i64, pose: Isometry3<f64>) -> Result<(), String> {
        let _ = (object, t_us, pose);
        Err("this tracker cannot be re-seeded".into())
    }
}
