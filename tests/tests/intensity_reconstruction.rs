//! The tracker reconstructs the intensity `I_t` only where something reads it (the intensity term, or overlays
//! through `intensity.always`); at the defaults it keeps the latest event times alone. The poses do not depend on
//! whether `I_t` is kept.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eventtrack6d_tests::tick_fixture::mug_recording;
use scene::render::CpuRenderer;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::{EventTrack6d, PoseEstimate, TrackerConfig, track_recording};

/// Every estimate of a replay with `config`, and whether the tracker's surface kept `I_t`.
fn run(recording: &Recording, config: TrackerConfig) -> (Vec<PoseEstimate>, bool) {
    let truth = PoseTrack::from_samples(recording.ground_truth.as_deref().unwrap(), "mug");
    let first = recording_ticks(recording).unwrap()[0].t_us;
    let mug = recording_object(
        recording,
        "mug",
        first,
        truth.interpolated_at(first).unwrap(),
    )
    .unwrap();
    let rig = recording_rig(recording).unwrap();
    let mut tracker =
        EventTrack6d::new(config, rig, vec![mug], Box::new(CpuRenderer::new())).unwrap();
    let mut out = Vec::new();
    track_recording(
        recording,
        &mut tracker,
        first,
        |_, estimates, _| out.extend_from_slice(estimates),
        |_| {},
    )
    .unwrap();
    assert!(tracker.event_surface().events() > 10_000);
    (out, tracker.event_surface().reconstructs_intensity())
}

#[test]
fn intensity_is_kept_only_when_read_and_poses_do_not_depend_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let recording = mug_recording(dir.path(), 0.3);
    let (plain, kept) = run(&recording, TrackerConfig::default());
    assert!(!kept, "the defaults read no I_t");

    let mut always = TrackerConfig::default();
    always.intensity.always = true;
    let (with_intensity, kept) = run(&recording, always);
    assert!(kept);
    assert!(plain.len() > 30);
    assert_eq!(plain.len(), with_intensity.len());
    for (a, b) in plain.iter().zip(&with_intensity) {
        assert_eq!(a.pose, b.pose, "tick {}", a.t_us);
        assert_eq!(a.quality.to_bits(), b.quality.to_bits());
        assert_eq!(a.state, b.state);
    }

    let mut read = TrackerConfig::default();
    read.intensity_term.weight = 0.5;
    let (_, kept) = run(&recording, read);
    assert!(kept, "the intensity term reads I_t");
}
