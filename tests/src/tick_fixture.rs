//! A tracker in steady state on a short generated recording, for the per-tick benchmark and the no-allocation
//! test: the recording is replayed up to its last tick, after which the caller can repeat ticks at will.

use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use std::path::Path;
use tracker::eval::{PoseTrack, recording_ticks};
use tracker::render::Renderer;
use tracker::track::{
    EventTrack6d, PoseTracker, TrackerConfig, recording_object, recording_rig, track_recording,
};

/// A warmed-up tracker and what to feed it for one more tick.
pub struct SteadyTracker {
    /// The tracker after replaying the recording.
    pub tracker: EventTrack6d,
    /// The last tick of the recording (repeat it: same time, same data).
    pub last_tick: Tick,
    /// A depth frame of the recording, for depth-exposure ticks.
    pub depth: DepthFrame,
    /// The recording (kept open for the temporary directory's lifetime of the caller).
    pub recording: Recording,
}

/// Generates a `seconds`-long moderate shake of the mug into `dir` (reused if already there).
pub fn mug_recording(dir: &Path, seconds: f64) -> Recording {
    if Recording::open(dir).is_err() {
        let cfg = GenerateConfig::new(
            ObjectSource::Library(ObjectKind::Mug),
            MotionProfile::Shake,
            SpeedLevel::Moderate,
            seconds,
            7,
        );
        generate(&cfg, dir, |_| {}).expect("generating the fixture recording");
    }
    Recording::open(dir).expect("opening the fixture recording")
}

/// Replays `recording` into a tracker (`config`, `renderer`) from the first ground-truth pose to the end.
pub fn steady_tracker(
    recording: Recording,
    config: TrackerConfig,
    renderer: Box<dyn Renderer + Send>,
) -> SteadyTracker {
    let gt = recording
        .ground_truth
        .clone()
        .expect("fixture has ground truth");
    let track = PoseTrack::from_samples(&gt, "mug");
    let ticks = recording_ticks(&recording).expect("ticks");
    let first = ticks[0];
    let pose = track.interpolated_at(first.t_us).expect("first pose");
    let object = recording_object(&recording, "mug", first.t_us, pose).expect("model");
    let rig = recording_rig(&recording).expect("rig");
    let mut tracker = EventTrack6d::new(config, rig, vec![object], renderer).expect("tracker");
    track_recording(&recording, &mut tracker, first.t_us, |_, _, _| {}, |_| {}).expect("replay");
    let last_tick = *ticks.last().expect("ticks");
    let depth_index = recording
        .depth_frames
        .last()
        .copied()
        .expect("depth frames");
    let depth = recording.depth_frame(depth_index).expect("depth frame");
    assert_eq!(tracker.objects().len(), 1);
    SteadyTracker {
        tracker,
        last_tick,
        depth,
        recording,
    }
}
