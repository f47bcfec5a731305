//! Per-object pose tracking: the interface the runtime drives ([`PoseTracker`]) and what it produces
//! ([`PoseEstimate`]).
//!
//! The runtime feeds a tracker in time order: events (camera clock, microseconds) with timestamps up to a tick,
//! then the depth frame exposed at that tick (if any), then [`PoseTracker::tick`], which appends one estimate per
//! tracked object.

mod config;
mod depth_transport;
mod estimate;
mod eventtrack;
mod fallback_check;
mod hold;
mod object;
mod offline;
mod redetect;
mod validate;

pub use config::{DepthUse, MAX_DEPTH_AGE_LIMIT_MS, QualityConfig, TrackerConfig, TrackingMethod};
pub use depth_transport::DepthTransport;
pub use estimate::{PoseEstimate, ReportedState, TrackingState};
pub use eventtrack::{EventTrack6d, TrackError, TrackedObject, TrackerCounters, TrackingRig};
pub use fallback_check::{
    DepthFallbackCheck, FALLBACK_TRACE_HEADER, FallbackCandidate, FallbackRule, FallbackStart,
};
pub use hold::HoldPoseTracker;
pub use offline::{OfflineStats, OfflineTiming, track_recording, track_recording_timed};
pub use redetect::RedetectConfig;
pub use validate::InvalidParameter;

use drivers::event::CdEvent;
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;

/// A multi-object pose tracker driven tick by tick. Implementations must not allocate per tick in steady state and
/// must never block: the runtime calls them from the tracker thread.
pub trait PoseTracker: Send {
    /// Names of the tracked objects; [`PoseEstimate::object`] indexes this list.
    fn objects(&self) -> &[String];
    /// Events in time order (non-decreasing `t_us`), all at or before the next tick.
    fn push_events(&mut self, events: &[CdEvent]);
    /// The depth frame exposed at time `t_us` (the depth-exposure tick), in the depth camera's pixels; it may
    /// arrive after that tick (a live depth camera's latency: EventTrack6D then tracks the ticks since the
    /// exposure again with it, here, or uses it at the next tick, up to [`TrackerConfig::max_depth_age_ms`] after
    /// the exposure). A tracker
    /// that keeps the frame takes it without a copy and leaves its previous frame in `frame` (for the caller to
    /// reuse or drop); one that does not leaves `frame` as it is.
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame);
    /// Like [`Self::push_depth`] for a frame that arrives just before a tick: what the frame costs beyond that
    /// tick's own use of it is left until [`Self::prepare_next_tick`], after the tick's poses are out
    /// (EventTrack6D: the tick carries a late frame from its exposure, and the ticks since the exposure are
    /// tracked again afterwards). By default the same as `push_depth`.
    fn push_depth_deferred(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.push_depth(t_us, frame);
    }
    /// Like [`Self::push_depth`] for a caller that has fallen behind: the frame is used only the cheap way, and
    /// nothing it could cost beyond that is done (EventTrack6D: the next tick carries a late frame from its
    /// exposure and nothing is tracked again; counted in `late_frames_not_retracked`). By default the same as
    /// `push_depth`.
    fn push_depth_carried(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.push_depth(t_us, frame);
    }
    /// Estimates every object's pose at `tick` and appends one [`PoseEstimate`] per object to `out`.
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>);
    /// Work for the next tick that need not delay this tick's poses (EventTrack6D: start its renders,
    /// [`TrackerConfig::prefetch_renders`]); call it once the tick's poses are published. Skipping it changes no
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
}
