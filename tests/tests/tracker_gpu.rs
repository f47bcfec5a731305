//! EventTrack6D with the wgpu renderer on a replayed mug shake: renders prefetched for the next tick
//! (`prefetch_renders`) are taken by most ticks and change no pose, state or quality.
//!
//! Needs a Vulkan adapter (lavapipe on CI, as `render_gpu.rs`); without one it fails, naming the package.

use eventtrack6d_tests::tick_fixture::mug_recording;
use tracker::eval::{PoseTrack, recording_ticks};
use tracker::render::{RendererKind, create_renderer};
use tracker::track::{
    EventTrack6d, TrackerConfig, TrackerCounters, recording_object, recording_rig, track_recording,
};

/// Pose bits, quality bits and state of every estimate of a replay, and the tracker's counters.
/// One estimate: time, pose bits (translation, quaternion), quality bits, state.
type Estimate = (i64, [u64; 7], u32, String);

fn replay(prefetch: bool) -> (Vec<Estimate>, TrackerCounters) {
    let dir = std::env::temp_dir().join("eventtrack6d-tracker-gpu-test");
    let recording = mug_recording(&dir, 0.5);
    let gt = recording.ground_truth.clone().expect("ground truth");
    let track = PoseTrack::from_samples(&gt, "mug");
    let first = recording_ticks(&recording).expect("ticks")[0];
    let pose = track.interpolated_at(first.t_us).expect("first pose");
    let object = recording_object(&recording, "mug", first.t_us, pose).expect("model");
    let rig = recording_rig(&recording).expect("rig");
    let renderer = create_renderer(RendererKind::Gpu).unwrap_or_else(|e| {
        panic!("no GPU renderer ({e}): install mesa-vulkan-drivers (lavapipe), as .ci/setup does")
    });
    let config = TrackerConfig {
        prefetch_renders: prefetch,
        ..TrackerConfig::default()
    };
    let mut tracker = EventTrack6d::new(config, rig, vec![object], renderer).expect("tracker");
    let mut out = Vec::new();
    track_recording(
        &recording,
        &mut tracker,
        first.t_us,
        |_, estimates, _| {
            for e in estimates {
                let (t, q) = (e.pose.translation.vector, e.pose.rotation.coords);
                let bits = [t.x, t.y, t.z, q.x, q.y, q.z, q.w].map(f64::to_bits);
                out.push((e.t_us, bits, e.quality.to_bits(), format!("{:?}", e.state)));
            }
        },
        |_| {},
    )
    .expect("replay");
    (out, tracker.counters())
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
    assert!(counters.renders_prefetched <= counters.ticks + 8);
    assert!(
        counters.prefetched_renders_used * 10 >= counters.ticks * 9,
        "{} of {} ticks took a prefetched render",
        counters.prefetched_renders_used,
        counters.ticks
    );
}
