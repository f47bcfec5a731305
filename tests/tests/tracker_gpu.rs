//! EventTrack6D with the wgpu renderer on a replayed mug shake: renders prefetched for the next tick
//! (`prefetch_renders`) are taken by most ticks and change no pose, state or quality.
//!
//! Needs a Vulkan adapter (lavapipe on CI, as `render_gpu.rs`); without one it fails, naming the package.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d_tests::tick_fixture::{EstimateBits, mug_recording, replay_bits};
use scene::render::{RendererKind, create_renderer};
use tracker::track::{ExecutionConfig, TrackerConfig, TrackerCounters};

fn replay(prefetch: bool) -> (Vec<EstimateBits>, TrackerCounters) {
    let dir = std::env::temp_dir().join("eventtrack6d-tracker-gpu-test");
    let recording = mug_recording(&dir, 0.5);
    let renderer = create_renderer(RendererKind::Gpu).unwrap_or_else(|e| {
        panic!("no GPU renderer ({e}): install mesa-vulkan-drivers (lavapipe), as .ci/setup does")
    });
    let config = TrackerConfig {
        execution: ExecutionConfig {
            prefetch_renders: prefetch,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    replay_bits(&recording, config, renderer)
}

#[test]
fn prefetched_renders_change_no_estimate_and_most_ticks_take_them() {
    let (with, counters) = replay(true);
    let (without, plain) = replay(false);
    assert_eq!(plain.renders_prefetched, 0);
    assert!(with.len() > 50, "{} estimates", with.len());
    assert_eq!(with.len(), without.len());
    for (a, b) in with.iter().zip(&without) {
        assert_eq!(
            a, b,
            "estimate at {} us differs with prefetched renders",
            a.0
        );
    }
    println!(
        "{} ticks, {} renders prefetched, {} used",
        counters.ticks, counters.renders_prefetched, counters.prefetched_renders_used
    );
    // One render per tick once the timeline's pattern of periods (8333, 8333, 8334 us) is known, two before (the
    // whole microseconds around the mean period). Misses would be the first tick, depth ticks whose ROI widens and
    // ticks after a re-detection moved the object.
    assert!(counters.renders_prefetched >= counters.ticks - 1);
    // A step between ticks prefetches the render for its object as a tick does.
    assert!(
        counters.renders_prefetched <= counters.ticks + counters.inner_steps + 8,
        "{counters:?}"
    );
    assert!(
        counters.prefetched_renders_used * 10 >= counters.ticks * 9,
        "{} of {} ticks took a prefetched render",
        counters.prefetched_renders_used,
        counters.ticks
    );
}
