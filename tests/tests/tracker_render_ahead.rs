//! EventTrack6D with the CPU renderer on a replayed mug shake: with `prefetch_renders` (the default) each next
//! ROI is rendered ahead on the `render-ahead` helper thread, most ticks take that render, and no pose, state or
//! quality changes; without it the tracker renders on its own thread only. With several object threads, each
//! renders its own objects ahead.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d::runtime::build_tracker;
use eventtrack6d::runtime::setup::recording_scene;
use eventtrack6d_tests::tick_fixture::{
    EstimateBits, mug_and_can_recording, mug_recording, replay_bits,
};
use scene::render::{CpuRenderer, RendererKind};
use tracker::track::{
    ExecutionConfig, TrackerConfig, TrackerCounters, TrackingMethod, track_recording,
};

fn replay(config: TrackerConfig) -> (Vec<EstimateBits>, TrackerCounters) {
    let dir = std::env::temp_dir().join("eventtrack6d-tracker-ahead-test");
    let recording = mug_recording(&dir, 0.5);
    replay_bits(&recording, config, Box::new(CpuRenderer::new()))
}

#[test]
fn renders_ahead_change_no_estimate_and_most_ticks_take_them() {
    let (with, counters) = replay(TrackerConfig::default());
    let (without, plain) = replay(TrackerConfig {
        execution: ExecutionConfig {
            prefetch_renders: false,
            ..Default::default()
        },
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
    // A step between ticks prefetches the render for its object as a tick does.
    assert!(
        counters.renders_prefetched <= counters.ticks + counters.inner_steps + 8,
        "{counters:?}"
    );
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

/// Every estimate's bits and the counters of a two-object replay (a mug shaken behind a can) stepped on two
/// threads (`object_threads = 2`), with or without renders ahead.
fn replay_two_objects(prefetch: bool) -> (Vec<(i64, usize, [u64; 7])>, TrackerCounters) {
    let dir = std::env::temp_dir().join("eventtrack6d-tracker-ahead-two-objects");
    let rec = mug_and_can_recording(&dir);
    let scene = recording_scene(&rec, &[]).expect("scene");
    let config = TrackerConfig {
        execution: ExecutionConfig {
            prefetch_renders: prefetch,
            object_threads: 2,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let timeline = rec.meta.trigger.timeline_config();
    let mut tracker = build_tracker(
        "eventtrack6d",
        RendererKind::Cpu,
        &config,
        &scene,
        &timeline,
    )
    .expect("tracker");
    let mut out = Vec::new();
    track_recording(
        &rec,
        tracker.as_mut(),
        scene.objects[0].first_pose.0,
        |_, estimates, _| {
            for e in estimates {
                let (t, q) = (e.pose.translation.vector, e.pose.rotation.coords);
                let bits = [t.x, t.y, t.z, q.x, q.y, q.z, q.w].map(f64::to_bits);
                out.push((e.t_us, e.object, bits));
            }
        },
        |_| {},
    )
    .expect("replay");
    (out, tracker.tracker_counters().expect("counters"))
}

#[test]
fn with_two_object_threads_each_renders_its_own_objects_ahead() {
    let (with, counters) = replay_two_objects(true);
    let (without, plain) = replay_two_objects(false);
    assert_eq!(plain.renders_prefetched, 0);
    assert_eq!(with.len(), without.len());
    assert!(with.len() > 100, "{} estimates", with.len());
    assert_eq!(with, without, "an estimate differs with renders ahead");
    println!(
        "{} ticks, {} renders ahead, {} used",
        counters.ticks, counters.renders_prefetched, counters.prefetched_renders_used
    );
    // Both objects' renders are made ahead (one each per tick, two while the pattern of periods is unknown),
    // and most are taken: the second thread's object too.
    assert!(counters.renders_prefetched >= 2 * (counters.ticks - 1));
    assert!(
        counters.prefetched_renders_used * 10 >= 2 * counters.ticks * 9,
        "{} of {} object steps took a render made ahead",
        counters.prefetched_renders_used,
        2 * counters.ticks
    );
}
