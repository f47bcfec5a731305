//! The range along the line of sight from the depth frames ([`tracker::track::MotionConfig::range_from_depth`]):
//! between two depth frames the events barely see an object move towards or away from the camera, so the
//! prediction extrapolates the depth frames' ranges there. These tests track a short fast depth motion of the mug
//! with and without it, and an estimate put behind the object with and without the range alignment at depth frames
//! ([`tracker::track::CorrespondConfig::align_range_at_depth`]).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eventtrack6d_tests::shipped_params::ticks_only;
use eventtrack6d_tests::tick_fixture::{mug_estimates, mug_recording, replay_started_off};
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use nalgebra::Translation3;
use scene::render::CpuRenderer;
use std::path::Path;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::track::{MotionConfig, PoseEstimate, TrackerConfig};

/// A `seconds`-long fast motion of the mug towards and away from the camera (about 2 m/s), seed 3.
fn depth_motion_recording(dir: &Path, seconds: f64) -> Recording {
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Mug),
        MotionProfile::DepthVariation,
        SpeedLevel::Fast,
        seconds,
        3,
    );
    generate(&cfg, dir, |_| {}).expect("generating the depth-motion recording");
    Recording::open(dir).expect("opening the depth-motion recording")
}

/// Tracks `rec` from the mug's first ground-truth pose with `range_from_depth` set as given; every estimate.
fn track(rec: &Recording, range_from_depth: bool) -> Vec<PoseEstimate> {
    let base = ticks_only();
    let config = TrackerConfig {
        motion: MotionConfig {
            range_from_depth,
            ..base.motion
        },
        ..base
    };
    mug_estimates(rec, config)
}

/// Mean absolute error of the estimates' range (the centre's distance from the camera; the mug's origin here)
/// against the truth, metres, over the ticks that have no depth frame of their own.
fn mean_range_error_between_depth_frames(rec: &Recording, estimates: &[PoseEstimate]) -> f64 {
    let gt = PoseTrack::from_samples(rec.ground_truth.as_deref().expect("ground truth"), "mug");
    let depth_us: Vec<i64> = recording_ticks(rec)
        .expect("ticks")
        .iter()
        .filter(|t| t.depth_frame.is_some())
        .map(|t| t.t_us)
        .collect();
    assert!(depth_us.len() > 5, "{} depth frames", depth_us.len());
    let between: Vec<f64> = estimates
        .iter()
        .filter(|e| !depth_us.contains(&e.t_us))
        .map(|e| {
            let g = gt
                .interpolated_at(e.t_us)
                .expect("ground truth at the tick");
            (g.translation.vector.norm() - e.pose.translation.vector.norm()).abs()
        })
        .collect();
    assert!(
        between.len() > 20,
        "{} ticks between depth frames",
        between.len()
    );
    between.iter().sum::<f64>() / between.len() as f64
}

/// On a fast motion along the line of sight, the range extrapolated from the depth frames keeps the estimate
/// nearer the object between depth frames than the velocity the ticks measured does.
#[test]
fn ranges_from_depth_frames_follow_motion_along_the_line_of_sight() {
    let dir = tempfile::tempdir().unwrap();
    let rec = depth_motion_recording(&dir.path().join("depth"), 0.6);
    let by_velocity = track(&rec, false);
    let by_depth = track(&rec, true);
    assert_eq!(by_velocity.len(), by_depth.len());
    let (e_velocity, e_depth) = (
        mean_range_error_between_depth_frames(&rec, &by_velocity),
        mean_range_error_between_depth_frames(&rec, &by_depth),
    );
    eprintln!(
        "mean range error between depth frames: by velocity {:.1} mm, from depth frames {:.1} mm",
        e_velocity * 1e3,
        e_depth * 1e3
    );
    assert!(
        e_depth < 0.7 * e_velocity,
        "{e_depth} against {e_velocity} m"
    );
}

/// The range error (metres) of each tick of the mug of `rec` started `behind` metres farther along its line of
/// sight than its first pose.
fn range_errors_started_behind(rec: &Recording, config: TrackerConfig, behind: f64) -> Vec<f64> {
    let mut errors = Vec::new();
    replay_started_off(
        rec,
        "mug",
        |pose, _| {
            let ray = pose.translation.vector.normalize();
            Translation3::from(ray * behind) * pose
        },
        (config, Box::new(CpuRenderer::new()), 0),
        |truth, e| {
            errors.push((truth.translation.vector.norm() - e.pose.translation.vector.norm()).abs())
        },
    );
    errors
}

/// An estimate several centimetres farther than the object (as an object approaching fast is by the first depth
/// frame, the events barely seeing it come nearer) sees the object's surface nearer than its own by more than the
/// depth term's `occlusion_gap`: the depth term alone takes it for an occluder and leaves the estimate there; the
/// range alignment at depth frames puts the estimate on it.
#[test]
fn at_a_depth_frame_the_estimate_is_moved_onto_the_range_it_measures() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(dir.path(), 0.3);
    let with = range_errors_started_behind(&rec, TrackerConfig::default(), 0.06);
    let mut off = TrackerConfig::default();
    off.correspond.align_range_at_depth = false;
    let without = range_errors_started_behind(&rec, off, 0.06);
    assert!(
        without[0] > 0.04,
        "without: {:.3} m at the first tick",
        without[0]
    );
    let worst = with.iter().copied().fold(0.0, f64::max);
    assert!(with[0] < 0.005, "with: {:.3} m at the first tick", with[0]);
    assert!(worst < 0.01, "with: up to {worst:.3} m");
}
