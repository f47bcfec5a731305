//! EventTrack6D with the CPU renderer on a replayed mug shake: with `prefetch_renders` (the default) each next
//! ROI is rendered ahead on the `render-ahead` helper thread, most ticks take that render, and no pose, state or
//! quality changes; without it the tracker renders on its own thread only.

use eventtrack6d_tests::tick_fixture::{EstimateBits, mug_recording, replay_bits};
use tracker::render::CpuRenderer;
use tracker::track::{TrackerConfig, TrackerCounters, TrackingMethod};

fn replay(config: TrackerConfig) -> (Vec<EstimateBits>, TrackerCounters) {
    let dir = std::env::temp_dir().join("eventtrack6d-tracker-ahead-test");
    let recording = mug_recording(&dir, 0.5);
    replay_bits(&recording, config, Box::new(CpuRenderer::new()))
}

#[test]
fn renders_ahead_change_no_estimate_and_most_ticks_take_them() {
    let (with, counters) = replay(TrackerConfig::default());
    let (without, plain) = replay(TrackerConfig {
        prefetch_renders: false,
        ..TrackerConfig::default()
    });
    assert_eq!(plain.renders_prefetched, 0);
    assert!(with.len() > 50, "{} estimates", with.len());
    assert_eq!(with.len(), without.len());
    for (a, b) in with.iter().zip(&without) {
        assert_eq!(a, b, "estimate at {} us differs with renders ahead", a.0);
    }
    println!(
        "{} ticks, {} renders ahead, {} used",
        counters.ticks, counters.renders_prefetched, counters.prefetched_renders_used
    );
    assert!(counters.renders_prefetched >= counters.ticks - 1);
    assert!(counters.renders_prefetched <= counters.ticks + 8);
    assert!(
        counters.prefetched_renders_used * 10 >= counters.ticks * 9,
        "{} of {} ticks took a render made ahead",
        counters.prefetched_renders_used,
        counters.ticks
    );
}

#[test]
fn depth30_renders_nothing_ahead() {
    let config = TrackingMethod::Depth30.configure(&TrackerConfig::default());
    let (_, counters) = replay(config);
    assert!(counters.ticks > 50);
    assert_eq!(counters.renders_prefetched, 0);
}
