//! What the tracker counts while it runs (in `track`'s closing lines, the runtime summary and its status).

/// Counters of what the tracker did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct TrackerCounters {
    /// Ticks processed.
    pub ticks: u64,
    /// Steps between ticks run ([`crate::track::InnerStepConfig`]), not counting those tracked again.
    pub inner_steps: u64,
    /// Depth frames used.
    pub depth_frames: u64,
    /// Depth frames not used: replaced by a newer frame before a tick, or older than `max_depth_age_ms` at the
    /// first tick after they arrived.
    pub depth_frames_unused: u64,
    /// Of the depth frames used, those used after their own exposure's tick (they arrived late; see
    /// `max_depth_age_ms`).
    pub depth_frames_late: u64,
    /// Of the late depth frames used, those the tracker tracked again from their exposure with
    /// ([`super::super::LateDepthConfig::retrack_late_depth`]).
    pub late_frames_retracked: u64,
    /// Ticks tracked again for them (their poses were out already).
    pub ticks_retracked: u64,
    /// Late depth frames used without tracking again: no state was saved at their exposure, the events since
    /// no longer fitted the log (`retrack_max_events`), or the runtime's tracker thread had fallen behind
    /// ([`crate::track::PoseTracker::push_depth_carried`]). Such a frame is carried from its exposure instead.
    pub late_frames_not_retracked: u64,
    /// Late depth frames an object could not use, summed over objects: its pose history did not reach back to
    /// the exposure (it was re-detected or reset since).
    pub late_depth_unplaced: u64,
    /// Renders that failed (the object keeps its prediction for that tick).
    pub render_errors: u64,
    /// Depth frames at which the depth-only hypothesis replaced an object's event-driven estimate (all objects).
    pub depth_fallbacks: u64,
    /// Depth frames at which re-detection moved an object that was not `tracking` (all objects).
    pub redetections: u64,
    /// Re-detection places checked (each a depth-only refinement and two renders).
    pub redetect_places_checked: u64,
    /// Re-detection places left unchecked: a newer depth frame replaced the one they were planned on, or a
    /// search planned more than the ticks until the next frame can check (the least likely left out).
    pub redetect_places_dropped: u64,
    /// Renders started at the end of a tick for the next one ([`crate::track::ExecutionConfig::prefetch_renders`]).
    pub renders_prefetched: u64,
    /// Of them, renders the next tick took (the others were rendered again: its request differed).
    pub prefetched_renders_used: u64,
}
