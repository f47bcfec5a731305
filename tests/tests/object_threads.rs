//! Several objects stepped on several threads: each thread renders with its own fork of the renderer, and the
//! poses, qualities and states are bit for bit those of the single-threaded tracker.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eventtrack6d_tests::render_hook::HookedRenderer;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use nalgebra::Translation3;
use scene::render::CpuRenderer;
use std::collections::HashSet;
use std::sync::{Arc, Mutex};
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::{EventTrack6d, ExecutionConfig, PoseEstimate, TrackerConfig, track_recording};

/// Every estimate of every tick, and the most threads that rendered within one tick.
fn run(recording: &Recording, threads: usize) -> (Vec<PoseEstimate>, usize) {
    let truth = PoseTrack::from_samples(recording.ground_truth.as_deref().unwrap(), "mug");
    let ticks = recording_ticks(recording).unwrap();
    let first = ticks[0].t_us;
    let pose = truth.interpolated_at(first).unwrap();
    let mug = recording_object(recording, "mug", first, pose).unwrap();
    // Two mugs that are not there: one 10 cm behind the real one and a little aside, which the real one hides in
    // part (so the renders carry the other objects' masks), and one beside them. Re-detection is off so that
    // neither is pulled onto the real mug.
    let mut behind = mug.clone();
    behind.name = "behind".into();
    behind.first_pose = Translation3::new(0.03, 0.0, 0.10) * pose;
    let mut beside = mug.clone();
    beside.name = "beside".into();
    beside.first_pose = Translation3::new(-0.15, 0.0, 0.0) * pose;
    // Renders made ahead would run on the `render-ahead` threads (tests/tests/tracker_render_ahead.rs): here every
    // render is made by the thread that steps the object.
    let mut config = TrackerConfig {
        execution: ExecutionConfig {
            object_threads: threads,
            prefetch_renders: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    config.redetect.enabled = false;
    let seen = Arc::new(Mutex::new(HashSet::new()));
    // Notes which threads render through it or its forks.
    let noted = seen.clone();
    let renderer = HookedRenderer::new(Box::new(CpuRenderer::new()), move || {
        noted.lock().unwrap().insert(std::thread::current().id());
    });
    let mut tracker = EventTrack6d::new(
        config,
        recording_rig(recording).unwrap(),
        vec![mug, behind, beside],
        Box::new(renderer),
    )
    .unwrap();
    let mut out = Vec::new();
    let mut most = 0;
    track_recording(
        recording,
        &mut tracker,
        first,
        |_, estimates, _| {
            out.extend_from_slice(estimates);
            let mut seen = seen.lock().unwrap();
            most = most.max(seen.len());
            seen.clear();
        },
        |_| {},
    )
    .unwrap();
    (out, most)
}

#[test]
fn objects_stepped_on_several_threads_give_the_single_threaded_poses() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Translation,
        SpeedLevel::Moderate,
        0.6,
        11,
    );
    generate(&cfg, dir.path(), |_| {}).unwrap();
    let recording = Recording::open(dir.path()).unwrap();

    let (one, threads_one) = run(&recording, 1);
    let (three, threads_three) = run(&recording, 3);
    assert_eq!(threads_one, 1);
    assert_eq!(threads_three, 3, "the objects were not spread over threads");
    assert_eq!(one.len(), three.len());
    assert!(one.len() >= 3 * 60, "{} estimates", one.len());
    for (a, b) in one.iter().zip(&three) {
        assert_eq!(
            (a.object, a.t_us, a.pose, a.quality, a.state),
            (b.object, b.t_us, b.pose, b.quality, b.state),
            "object {} at {} us",
            a.object,
            a.t_us
        );
    }
    // The real mug is followed (the comparison above is not of two failures): on average it stays far closer to
    // the truth than its first pose held still.
    let truth = PoseTrack::from_samples(recording.ground_truth.as_deref().unwrap(), "mug");
    let held = truth.interpolated_at(one[0].t_us).unwrap();
    let (mut tracked, mut still, mut n) = (0.0, 0.0, 0.0);
    for e in one.iter().filter(|e| e.object == 0) {
        let t = truth.interpolated_at(e.t_us).unwrap().translation.vector;
        tracked += (e.pose.translation.vector - t).norm();
        still += (held.translation.vector - t).norm();
        n += 1.0;
    }
    let (tracked, still) = (tracked / n, still / n);
    eprintln!("mean error {tracked:.4} m tracked, {still:.4} m held still");
    assert!(
        tracked < 0.25 * still,
        "mean error {tracked:.3} m tracked against {still:.3} m held still"
    );
}
