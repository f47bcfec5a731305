//! A tracker in steady state on a short generated recording, for the per-tick benchmark and the no-allocation
//! test: the recording is replayed up to its last tick, after which the caller can repeat ticks at will. And the
//! bits of every estimate of such a replay, for tests that check an option changes no estimate.

use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use hil_sim::generate::{Companion, GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use nalgebra::{Isometry3, Translation3};
use scene::render::Renderer;
use std::path::Path;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::{
    EventTrack6d, OfflineTiming, PoseEstimate, PoseTracker, TrackerConfig, TrackerCounters,
    track_recording, track_recording_timed,
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

/// Generates a `seconds`-long fast shake of the mug (about 2 m/s, reversing within tens of milliseconds) into
/// `dir` (reused if already there), seed 1.
pub fn fast_mug_recording(dir: &Path, seconds: f64) -> Recording {
    if Recording::open(dir).is_err() {
        let cfg = GenerateConfig::new(
            ObjectSource::Library(ObjectKind::Mug),
            MotionProfile::Shake,
            SpeedLevel::Fast,
            seconds,
            1,
        );
        generate(&cfg, dir, |_| {}).expect("generating the fast fixture recording");
    }
    Recording::open(dir).expect("opening the fast fixture recording")
}

/// Generates a 0.5 s scene into `dir` (reused if already there): the library mug shaken at moderate speed, and a can
/// on its own moderate shake 15 cm nearer the camera (`hil-sim generate --with can:translation`), seed 5.
pub fn mug_and_can_recording(dir: &Path) -> Recording {
    if Recording::open(dir).is_err() {
        let mut cfg = GenerateConfig::new(
            ObjectSource::Library(ObjectKind::Mug),
            MotionProfile::Shake,
            SpeedLevel::Moderate,
            0.5,
            5,
        );
        cfg.companions.push(
            Companion::parse(
                "can:translation",
                0,
                MotionProfile::Shake,
                SpeedLevel::Moderate,
            )
            .expect("companion spec"),
        );
        generate(&cfg, dir, |_| {}).expect("generating the two-object recording");
    }
    Recording::open(dir).expect("opening the two-object recording")
}

/// Replays `recording` into a tracker (`config`, `renderer`) from the first ground-truth pose to the end.
pub fn steady_tracker(
    recording: Recording,
    config: TrackerConfig,
    renderer: Box<dyn Renderer + Send>,
) -> SteadyTracker {
    steady_tracker_of(recording, config, renderer, 1)
}

/// [`steady_tracker`] of `objects` objects: the recording's mug and `objects - 1` copies of it that are not there,
/// 15 cm apart beside it (each steps, renders and is refined like the mug; they drift where nothing supports them).
pub fn steady_tracker_of(
    recording: Recording,
    config: TrackerConfig,
    renderer: Box<dyn Renderer + Send>,
    objects: usize,
) -> SteadyTracker {
    let (mut tracker, first_t_us) = mug_tracker(&recording, config, renderer, objects);
    track_recording(&recording, &mut tracker, first_t_us, |_, _, _| {}, |_| {}).expect("replay");
    let ticks = recording_ticks(&recording).expect("ticks");
    let last_tick = *ticks.last().expect("ticks");
    let depth_index = recording
        .depth_frames
        .last()
        .copied()
        .expect("depth frames");
    let depth = recording.depth_frame(depth_index).expect("depth frame");
    assert_eq!(tracker.objects().len(), objects.max(1));
    SteadyTracker {
        tracker,
        last_tick,
        depth,
        recording,
    }
}

/// One estimate of a replay, bit for bit: time (microseconds), pose bits (translation, quaternion), quality bits and
/// state.
pub type EstimateBits = (i64, [u64; 7], u32, String);

/// Replays `recording` (its mug from the ground truth's first pose) through EventTrack6D with `config` and
/// `renderer`, as `eventtrack6d track` does; returns every estimate's bits and the tracker's counters.
pub fn replay_bits(
    recording: &Recording,
    config: TrackerConfig,
    renderer: Box<dyn Renderer + Send>,
) -> (Vec<EstimateBits>, TrackerCounters) {
    let (mut tracker, first_t_us) = mug_tracker(recording, config, renderer, 1);
    let mut out = Vec::new();
    track_recording(
        recording,
        &mut tracker,
        first_t_us,
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

/// A tracker of `recording`'s mug from its ground-truth pose at the first tick, with `objects - 1` copies of it
/// beside it, and that tick's time (microseconds).
pub fn mug_tracker(
    recording: &Recording,
    config: TrackerConfig,
    renderer: Box<dyn Renderer + Send>,
    objects: usize,
) -> (EventTrack6d, i64) {
    let gt = recording
        .ground_truth
        .clone()
        .expect("fixture has ground truth");
    let track = PoseTrack::from_samples(&gt, "mug");
    let first = recording_ticks(recording).expect("ticks")[0];
    let pose = track.interpolated_at(first.t_us).expect("first pose");
    let mug = recording_object(recording, "mug", first.t_us, pose).expect("model");
    let copies = (1..objects).map(|k| {
        let mut copy = mug.clone();
        copy.name = format!("mug-copy-{k}");
        copy.first_pose = Translation3::new(-0.15 * k as f64, 0.0, 0.0) * pose;
        copy
    });
    let all = std::iter::once(mug.clone()).chain(copies).collect();
    let rig = recording_rig(recording).expect("rig");
    let tracker = EventTrack6d::new(config, rig, all, renderer).expect("tracker");
    (tracker, first.t_us)
}

/// Every estimate of `recording` tracked offline from the mug's first ground-truth pose with `config` and the CPU
/// renderer, the depth frames on time.
pub fn mug_estimates(recording: &Recording, config: TrackerConfig) -> Vec<PoseEstimate> {
    let (mut tracker, first_us) = mug_tracker(
        recording,
        config,
        Box::new(scene::render::CpuRenderer::new()),
        1,
    );
    let timing = OfflineTiming {
        start_us: first_us,
        depth_latency_us: 0,
        depth_jitter_us: 0,
    };
    let mut out = Vec::new();
    track_recording_timed(
        recording,
        &mut tracker,
        timing,
        |_, e, _| out.extend_from_slice(e),
        |_| {},
    )
    .expect("replay");
    out
}

/// Tracks `rec` offline with `tracker` as `bench` does, from `timing`, and returns every estimate as its pose CSV
/// row (in output order) and what the offline driver did: the reference the runtime's runs are compared against.
pub fn offline_pose_rows(
    rec: &Recording,
    tracker: &mut dyn PoseTracker,
    timing: tracker::track::OfflineTiming,
) -> (Vec<String>, tracker::track::OfflineStats) {
    let names = tracker.objects().to_vec();
    let mut rows = Vec::new();
    let stats = tracker::track::track_recording_timed(
        rec,
        tracker,
        timing,
        |_, estimates, _| {
            rows.extend(estimates.iter().map(|e| {
                tracker::recording::PoseRow {
                    t_us: e.t_us,
                    object: &names[e.object],
                    pose: &e.pose,
                    quality: e.quality,
                    state: e.state.as_str(),
                }
                .to_string()
            }));
        },
        |_| {},
    )
    .expect("offline tracking");
    (rows, stats)
}

/// What a replay tracks with: configuration, renderer, and the depth frames' latency after their exposure
/// (microseconds).
pub type TrackerSetup = (TrackerConfig, Box<dyn Renderer + Send>, i64);

/// Replays `recording` into a tracker of the object `name` alone, started at `start(true first pose, diameter in
/// metres)`, calling `each_tick(truth, estimate)` at every tick; returns the tracker after the last tick.
pub fn replay_started_off(
    recording: &Recording,
    name: &str,
    start: impl FnOnce(Isometry3<f64>, f64) -> Isometry3<f64>,
    (config, renderer, latency_us): TrackerSetup,
    mut each_tick: impl FnMut(&Isometry3<f64>, &PoseEstimate),
) -> EventTrack6d {
    let gt = recording.ground_truth.clone().expect("ground truth");
    let truth = PoseTrack::from_samples(&gt, name);
    let ticks = recording_ticks(recording).expect("ticks");
    let first = ticks[0].t_us;
    let pose = truth.interpolated_at(first).expect("first pose");
    let mut object = recording_object(recording, name, first, pose).expect("model");
    object.first_pose = start(pose, object.diameter);
    let rig = recording_rig(recording).expect("rig");
    let mut tracker = EventTrack6d::new(config, rig, vec![object], renderer).expect("tracker");
    let timing = OfflineTiming {
        start_us: first,
        depth_latency_us: latency_us,
        depth_jitter_us: 0,
    };
    track_recording_timed(
        recording,
        &mut tracker,
        timing,
        |tick, estimates, _| {
            let truth_now: Isometry3<f64> = truth.interpolated_at(tick.t_us).expect("truth");
            each_tick(&truth_now, &estimates[0]);
        },
        |_| {},
    )
    .expect("replay");
    tracker
}
