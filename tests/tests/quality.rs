//! The quality score is built from evidence measured at depth frames (depth agreement, visible fraction) and,
//! for fast motion, the event support of the outline. Between depth frames the depth evidence is held, so without
//! events the quality may change only at a depth frame: it must not rise at the ticks in between because the
//! visible fraction was forgotten (which made the state flicker `degraded` at every depth frame and `tracking`
//! at the three ticks after it). A re-detection moving the object between depth frames brings its place's
//! evidence with it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use scene::render::CpuRenderer;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::{EventTrack6d, ModalityConfig, TrackerConfig, track_recording};

#[test]
fn without_events_quality_changes_only_at_depth_frames() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::CrackerBox),
        MotionProfile::HandSwitch,
        SpeedLevel::Slow,
        1.0,
        7,
    );
    generate(&cfg, dir.path(), |_| {}).expect("generating the recording");
    let recording = Recording::open(dir.path()).expect("recording");
    let gt = recording.ground_truth.clone().expect("ground truth");
    let truth = PoseTrack::from_samples(&gt, "cracker_box");
    let ticks = recording_ticks(&recording).expect("ticks");
    let first = ticks[0].t_us;
    let pose = truth.interpolated_at(first).expect("first pose");
    let object = recording_object(&recording, "cracker_box", first, pose).expect("model");
    let rig = recording_rig(&recording).expect("rig");
    let config = TrackerConfig {
        modalities: ModalityConfig {
            events: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let mut tracker = EventTrack6d::new(config, rig, vec![object], Box::new(CpuRenderer::new()))
        .expect("tracker");

    let mut qualities = Vec::new();
    let mut depth_ticks = Vec::new();
    // Re-detection so far at each tick: a search checks its places over the ticks after its depth frame, and the
    // tick that moves the object to a place found has that place's depth evidence.
    let mut moved = Vec::new();
    let stats = track_recording(
        &recording,
        &mut tracker,
        first,
        |tick, estimates, tracker| {
            qualities.push(estimates[0].quality);
            depth_ticks.push(tick.depth_frame.is_some());
            moved.push(tracker.tracker_counters().map_or(0, |c| c.redetections));
        },
        |_| {},
    )
    .expect("replay");
    let redetections = moved.last().copied().unwrap_or(0) as usize;
    let depth_frames = stats.depth_frames as usize;
    let changes = qualities.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(
        qualities.len() >= 3 * depth_frames,
        "{} ticks for {depth_frames} depth frames",
        qualities.len()
    );
    // The visible fraction is below one at practically every frame (the sensor misses edges, the hand covers
    // part of the box), so the old behaviour changed the quality twice per frame.
    let below_one = qualities.iter().filter(|&&q| q < 0.999).count();
    assert!(below_one > qualities.len() / 2, "quality {qualities:?}");
    assert!(
        changes <= depth_frames + redetections,
        "quality changed {changes} times over {} ticks with {depth_frames} depth frames: {qualities:?}",
        qualities.len()
    );
    // And each change is at a depth frame's tick, not one after it, or at a tick that moved the object.
    for (i, w) in qualities.windows(2).enumerate() {
        if w[0] != w[1] {
            assert!(
                depth_ticks[i + 1] || moved[i + 1] > moved[i],
                "quality changed at tick {} ({} -> {}), which has no depth frame",
                i + 1,
                w[0],
                w[1]
            );
        }
    }
    assert!(changes > 0, "quality never changed: {qualities:?}");
}
