//! How the counters of a run fed from a stream (replay, ROS 2) may differ from those of the offline driver on the
//! same recording, where the poses are the same to the bit.

use tracker::track::TrackerCounters;

/// Checks that `run`'s counters are `offline`'s but for the steps between ticks and the renders each prefetched
/// for the objects it refines (`objects` of them).
///
/// With depth frames on time, only the steps planned after the last tick differ (at most `max_inner_steps`): the
/// stream hands over the events after that tick, which run them, and the offline driver stops at it. With late
/// depth frames (`late_depth`), the count of steps is not reproducible at all: a late frame's retrack plans the
/// period it arrives in again from the corrected velocity, the steps run before the arrival count by the old
/// plan and those after by the new one, so where in the period the frame arrives changes the count (not the
/// poses). Every other counter must be equal.
pub fn assert_counters_match_offline(
    run: &TrackerCounters,
    offline: &TrackerCounters,
    max_inner_steps: u32,
    objects: u64,
    late_depth: bool,
) {
    if !late_depth {
        let after_last_tick = run.inner_steps - offline.inner_steps;
        let renders_after = run.renders_prefetched - offline.renders_prefetched;
        assert!(
            after_last_tick <= u64::from(max_inner_steps)
                && renders_after <= after_last_tick * objects
                && run.prefetched_renders_used - offline.prefetched_renders_used == renders_after,
            "{run:?} against {offline:?}"
        );
    }
    assert_eq!(
        TrackerCounters {
            inner_steps: offline.inner_steps,
            renders_prefetched: offline.renders_prefetched,
            prefetched_renders_used: offline.prefetched_renders_used,
            ..*run
        },
        *offline
    );
}
