//! Re-detection at depth frames: a tracker started a diameter and a half away from the object (outside its ROI,
//! where the refinement alone cannot find it) is pulled back onto the object once the depth background shows
//! where it stands; with re-detection off it stays off until the object happens to move into its ROI.

use drivers::recording::Recording;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use nalgebra::{Isometry3, Translation3};
use tracker::eval::{PoseTrack, recording_ticks};
use tracker::render::CpuRenderer;
use tracker::track::{
    EventTrack6d, TrackerConfig, TrackingState, recording_object, recording_rig, track_recording,
};

/// Translation error (metres) and state at every tick, and the re-detection count.
fn run(recording: &Recording, config: TrackerConfig) -> (Vec<(f64, TrackingState)>, u64) {
    let gt = recording.ground_truth.clone().expect("ground truth");
    let truth = PoseTrack::from_samples(&gt, "mug");
    let ticks = recording_ticks(recording).expect("ticks");
    let first = ticks[0].t_us;
    let pose = truth.interpolated_at(first).expect("first pose");
    let object = recording_object(recording, "mug", first, pose).expect("model");
    // 1.5 diameters sideways: the ROI (1.2 diameters) does not even reach the object.
    let shift = 1.5 * object.diameter;
    let mut start = object.clone();
    start.first_pose = Translation3::new(shift, 0.0, 0.0) * pose;
    let rig = recording_rig(recording).expect("rig");
    let mut tracker =
        EventTrack6d::new(config, rig, vec![start], Box::new(CpuRenderer::new())).expect("tracker");
    let mut errors = Vec::new();
    track_recording(
        recording,
        &mut tracker,
        first,
        |tick, estimates, _| {
            let truth_now: Isometry3<f64> = truth.interpolated_at(tick.t_us).expect("truth");
            let e = &estimates[0];
            let error = (e.pose.translation.vector - truth_now.translation.vector).norm();
            errors.push((error, e.state));
        },
        |_| {},
    )
    .expect("replay");
    (errors, tracker.counters().redetections)
}

/// Ticks 12 to 40 (0.1 to 0.33 s): the object is still out of the frozen ROI's reach by itself.
const EARLY: std::ops::RangeInclusive<usize> = 12..=40;

#[test]
fn an_object_the_tracker_starts_off_is_found_again_from_the_depth_background() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::Translation,
        SpeedLevel::Moderate,
        1.5,
        11,
    );
    generate(&cfg, dir.path(), |_| {}).expect("generating the recording");
    let recording = Recording::open(dir.path()).expect("recording");

    // Without re-detection the estimate stays where it was put (`lost`) until the object happens to pass through
    // its ROI: it is still far off over the early ticks.
    let mut off = TrackerConfig::default();
    off.redetect.enabled = false;
    let (errors, redetections) = run(&recording, off);
    assert_eq!(redetections, 0);
    let nearest = errors[EARLY]
        .iter()
        .map(|(e, _)| *e)
        .fold(f64::INFINITY, f64::min);
    assert!(
        nearest > 0.05,
        "without re-detection the tracker came back early ({nearest:.3} m)"
    );

    // With it, the object is found within those ticks and tracked from then on.
    let (errors, redetections) = run(&recording, TrackerConfig::default());
    assert!(redetections >= 1, "no re-detection");
    let after = &errors[*EARLY.end()..];
    let worst = after.iter().map(|(e, _)| *e).fold(0.0, f64::max);
    assert!(
        worst < 0.02,
        "after tick {}: worst translation error {worst:.3} m",
        EARLY.end()
    );
    assert!(
        after.iter().all(|(_, s)| *s != TrackingState::Lost),
        "lost after re-detection"
    );
}
