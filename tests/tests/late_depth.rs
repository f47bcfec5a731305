//! Depth frames that arrive after their own tick, as a live depth camera delivers them tens of milliseconds after
//! the exposure: the offline driver can delay them, and the tracker registers such a frame at the object's
//! estimate at its exposure and carries it to the tick it arrives at. Before, a frame more than half a tick late
//! was dropped, so any realistic latency left the tracker on events alone.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::CdEvent;
use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use eventtrack6d_tests::shipped_params::ticks_only;
use eventtrack6d_tests::tick_fixture::mug_recording;
use nalgebra::Isometry3;
use scene::geometry::se3;
use scene::render::CpuRenderer;
use std::path::Path;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::DepthHandling;
use tracker::track::{
    EventTrack6d, LateDepthConfig, OfflineStats, OfflineTiming, PoseEstimate, PoseTracker,
    TrackerConfig, TrackerCounters, track_recording_timed,
};

/// The moderate mug shake every test here tracks (1 s, generated once per test binary run into a temp dir).
fn recording(dir: &Path) -> Recording {
    mug_recording(&dir.join("mug"), 1.0)
}

/// Tracks the recording's mug from its first ground-truth pose with depth frames `latency_us` late; returns the
/// estimates, the tracker and the driver's counters.
fn track(
    rec: &Recording,
    config: TrackerConfig,
    latency_us: i64,
) -> (Vec<PoseEstimate>, EventTrack6d, OfflineStats) {
    let (mut tracker, first_us) = mug_tracker(rec, config);
    let mut out = Vec::new();
    let timing = OfflineTiming {
        start_us: first_us,
        depth_latency_us: latency_us,
        depth_jitter_us: 0,
    };
    let stats = track_recording_timed(
        rec,
        &mut tracker,
        timing,
        |_, e, _| out.extend_from_slice(e),
        |_| {},
    )
    .expect("replay");
    (out, tracker, stats)
}

/// A tracker of the recording's mug from its first ground-truth pose, and the time of that pose.
fn mug_tracker(rec: &Recording, config: TrackerConfig) -> (EventTrack6d, i64) {
    let gt = PoseTrack::from_samples(rec.ground_truth.as_deref().expect("ground truth"), "mug");
    let first = recording_ticks(rec).expect("ticks")[0];
    let pose = gt.interpolated_at(first.t_us).expect("first pose");
    let mug = recording_object(rec, "mug", first.t_us, pose).expect("model");
    let rig = recording_rig(rec).expect("rig");
    let tracker =
        EventTrack6d::new(config, rig, vec![mug], Box::new(CpuRenderer::new())).expect("tracker");
    (tracker, first.t_us)
}

/// Mean distance between the estimated and true positions over the estimates after `from_us`, metres.
fn mean_error(rec: &Recording, poses: &[(i64, Isometry3<f64>)], from_us: i64) -> f64 {
    let gt = PoseTrack::from_samples(rec.ground_truth.as_deref().expect("ground truth"), "mug");
    let errors: Vec<f64> = poses
        .iter()
        .filter(|(t, _)| *t >= from_us)
        .map(|(t, p)| {
            let g = gt.interpolated_at(*t).expect("ground truth at the tick");
            (g.translation.vector - p.translation.vector).norm()
        })
        .collect();
    assert!(errors.len() >= 40, "{} estimates scored", errors.len());
    errors.iter().sum::<f64>() / errors.len() as f64
}

fn timed(estimates: &[PoseEstimate]) -> Vec<(i64, Isometry3<f64>)> {
    estimates.iter().map(|e| (e.t_us, e.pose)).collect()
}

#[test]
fn late_frames_keep_the_object_tracked_where_dropping_them_loses_it() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let latency_us = 40_000;
    let (on_time, _, _) = track(&rec, TrackerConfig::default(), 0);
    let (late, late_tracker, stats) = track(&rec, TrackerConfig::default(), latency_us);
    let dropping = TrackerConfig {
        late_depth: LateDepthConfig {
            max_depth_age_ms: 0.0,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let (dropped, drop_tracker, _) = track(&rec, dropping, latency_us);

    // Every frame that arrived before the last tick was used, each after its own tick; none by the dropping one.
    let c: TrackerCounters = late_tracker.counters();
    assert!(stats.depth_frames >= 25, "{stats:?}");
    assert_eq!(c.depth_frames, stats.depth_frames, "{c:?}");
    assert_eq!(c.depth_frames_late, stats.depth_frames, "{c:?}");
    assert_eq!((c.depth_frames_unused, c.late_depth_unplaced), (0, 0));
    assert!(stats.depth_frames_in_transit >= 1, "{stats:?}");
    let d = drop_tracker.counters();
    assert_eq!((d.depth_frames, d.depth_frames_late), (0, 0), "{d:?}");
    assert_eq!(d.depth_frames_unused, stats.depth_frames, "{d:?}");

    let from = on_time[0].t_us + 200_000;
    let e_on_time = mean_error(&rec, &timed(&on_time), from);
    let e_late = mean_error(&rec, &timed(&late), from);
    let e_dropped = mean_error(&rec, &timed(&dropped), from);
    eprintln!(
        "mean position error after 0.2 s: on time {:.1} mm, 40 ms late {:.1} mm, late frames dropped {:.1} mm",
        e_on_time * 1e3,
        e_late * 1e3,
        e_dropped * 1e3
    );
    // Measured 12.7 mm against 46.9 mm (on time 2.5 mm; 26.0 mm late before the safety net moved to the exposure).
    assert!(
        e_late < 0.7 * e_dropped,
        "late frames should help: {e_late} against {e_dropped} m"
    );
    assert!(
        e_on_time <= e_late,
        "latency cannot make it better: {e_on_time} against {e_late} m"
    );
}

/// With frames 20 ms late, each arrives three ticks after its exposure: the tracker goes back to its state at the
/// exposure tick, tracks those ticks again with the frame in place, and so reaches the arrival tick with the very
/// estimate an on-time frame gives there. Carrying the frame from its exposure instead (the cheaper way) does not.
#[test]
fn tracking_again_from_the_exposure_reaches_the_on_time_estimate_at_each_arrival() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let (on_time, _, _) = track(&rec, TrackerConfig::default(), 0);
    let (late, tracker, stats) = track(&rec, TrackerConfig::default(), 20_000);
    let carrying = TrackerConfig {
        late_depth: LateDepthConfig {
            retrack_late_depth: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let (carried, carrying_tracker, _) = track(&rec, carrying, 20_000);
    let identical = |estimates: &[PoseEstimate]| {
        estimates
            .iter()
            .zip(&on_time)
            .filter(|(e, o)| {
                assert_eq!(e.t_us, o.t_us);
                e.pose == o.pose
            })
            .count() as u64
    };

    let c = tracker.counters();
    assert!(stats.depth_frames >= 25, "{stats:?}");
    assert_eq!(c.depth_frames_late, stats.depth_frames, "{c:?}");
    assert_eq!(c.late_frames_retracked, stats.depth_frames, "{c:?}");
    assert_eq!(c.late_frames_not_retracked, 0, "{c:?}");
    // Exposure tick and the two after it, again for every frame; each tick counted once.
    assert_eq!(c.ticks_retracked, 3 * stats.depth_frames, "{c:?}");
    assert_eq!(c.ticks, late.len() as u64, "{c:?}");
    // Every arrival tick is bit for bit the on-time estimate (the ticks between lack the frame still in transit).
    assert_eq!(identical(&late), stats.depth_frames);
    let k = carrying_tracker.counters();
    assert_eq!(
        (k.late_frames_retracked, k.ticks_retracked),
        (0, 0),
        "{k:?}"
    );
    assert!(
        identical(&carried) < 5,
        "{} carried estimates are on time's",
        identical(&carried)
    );

    let from = on_time[0].t_us + 200_000;
    let (e_on_time, e_late, e_carried) = (
        mean_error(&rec, &timed(&on_time), from),
        mean_error(&rec, &timed(&late), from),
        mean_error(&rec, &timed(&carried), from),
    );
    eprintln!(
        "mean position error after 0.2 s: on time {:.1} mm, 20 ms late {:.1} mm tracked again, {:.1} mm carried",
        e_on_time * 1e3,
        e_late * 1e3,
        e_carried * 1e3
    );
    assert!(e_late < e_carried, "{e_late} against {e_carried} m");
}

/// Drives an [`EventTrack6d`] and records, at each depth frame handed over, the tracker's counters just before
/// and just after.
struct ArrivalProbe {
    inner: EventTrack6d,
    arrivals: Vec<(TrackerCounters, TrackerCounters)>,
}

impl PoseTracker for ArrivalProbe {
    fn objects(&self) -> &[String] {
        self.inner.objects()
    }
    fn push_events(&mut self, events: &[CdEvent]) {
        self.inner.push_events(events);
    }
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling) {
        let before = self.inner.counters();
        self.inner.push_depth(t_us, frame, handling);
        self.arrivals.push((before, self.inner.counters()));
    }
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.inner.tick(tick, out);
    }
    fn prepare_next_tick(&mut self) {
        self.inner.prepare_next_tick();
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.inner.pose_at(object, t_us)
    }
}

/// A live depth camera's frame comes between two ticks: the tracker tracks the ticks since its exposure again
/// when it arrives, so that work is not in the next tick's latency. With tracking again off, the arrival
/// changes nothing until the tick.
#[test]
fn a_late_frame_is_tracked_again_when_it_arrives_not_at_the_next_tick() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(&dir.path().join("mug"), 0.5);
    for retrack_late_depth in [true, false] {
        let config = TrackerConfig {
            late_depth: LateDepthConfig {
                retrack_late_depth,
                ..Default::default()
            },
            ..TrackerConfig::default()
        };
        let (inner, first_us) = mug_tracker(&rec, config);
        let mut probe = ArrivalProbe {
            inner,
            arrivals: Vec::new(),
        };
        let timing = OfflineTiming {
            start_us: first_us,
            depth_latency_us: 20_000,
            depth_jitter_us: 0,
        };
        let stats =
            track_recording_timed(&rec, &mut probe, timing, |_, _, _| {}, |_| {}).expect("replay");
        assert!(stats.depth_frames >= 12, "{stats:?}");
        assert_eq!(probe.arrivals.len() as u64, stats.depth_frames);
        for (k, (before, after)) in probe.arrivals.iter().enumerate() {
            assert_eq!(after.ticks, before.ticks, "frame {k}: no tick counted");
            let retracked = after.late_frames_retracked - before.late_frames_retracked;
            if retrack_late_depth {
                // Its exposure tick and the two after it, now.
                assert_eq!(retracked, 1, "frame {k}: {after:?}");
                assert_eq!(
                    after.ticks_retracked - before.ticks_retracked,
                    3,
                    "frame {k}"
                );
                assert_eq!(after.depth_frames, before.depth_frames + 1, "frame {k}");
            } else {
                assert_eq!(
                    after, before,
                    "frame {k}: carried at the tick, nothing at arrival"
                );
            }
        }
        let c = probe.inner.counters();
        let expected = if retrack_late_depth {
            stats.depth_frames
        } else {
            0
        };
        assert_eq!(c.late_frames_retracked, expected, "{c:?}");
        assert_eq!(c.depth_frames, stats.depth_frames, "{c:?}");
    }
}

/// Hands every depth frame over deferred ([`DepthHandling::AfterNextTick`]), as the runtime does with one
/// that arrives just before a tick, or with `carry_only` to be carried only
/// ([`DepthHandling::CarryOnly`]), as it does when its thread has fallen behind.
struct DeferringDriver(EventTrack6d, bool);

impl PoseTracker for DeferringDriver {
    fn objects(&self) -> &[String] {
        self.0.objects()
    }
    fn push_events(&mut self, events: &[CdEvent]) {
        self.0.push_events(events);
    }
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, _handling: DepthHandling) {
        if self.1 {
            self.0.push_depth(t_us, frame, DepthHandling::CarryOnly);
        } else {
            self.0.push_depth(t_us, frame, DepthHandling::AfterNextTick);
        }
    }
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.0.tick(tick, out);
    }
    fn prepare_next_tick(&mut self) {
        self.0.prepare_next_tick();
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.0.pose_at(object, t_us)
    }
    fn tracker_counters(&self) -> Option<TrackerCounters> {
        Some(self.0.counters())
    }
}

/// A frame handed over deferred is carried at the tick it arrives before, and the ticks from its exposure to
/// that one are tracked again after it: every later tick is bit for bit what tracking again at arrival gives,
/// and only the arrival ticks differ.
#[test]
fn a_deferred_frame_is_carried_at_its_tick_and_tracked_again_after_it() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(&dir.path().join("mug"), 0.5);
    let (at_arrival, _, stats) = track(&rec, TrackerConfig::default(), 20_000);
    let (tracker, first_us) = mug_tracker(&rec, TrackerConfig::default());
    let mut deferring = DeferringDriver(tracker, false);
    let mut deferred = Vec::new();
    let mut arrivals = Vec::new();
    let timing = OfflineTiming {
        start_us: first_us,
        depth_latency_us: 20_000,
        depth_jitter_us: 0,
    };
    let mut frames_seen = 0;
    track_recording_timed(
        &rec,
        &mut deferring,
        timing,
        |tick, e, t| {
            let used = t.tracker_counters().map_or(0, |c| c.depth_frames);
            if used > frames_seen {
                arrivals.push(tick.t_us);
                frames_seen = used;
            }
            deferred.extend_from_slice(e);
        },
        |_| {},
    )
    .expect("replay");
    let c = deferring.0.counters();
    assert!(stats.depth_frames >= 12, "{stats:?}");
    assert_eq!(c.depth_frames, stats.depth_frames, "{c:?}");
    assert_eq!(c.depth_frames_late, stats.depth_frames, "{c:?}");
    assert_eq!(c.late_frames_retracked, stats.depth_frames, "{c:?}");
    assert_eq!(c.late_frames_not_retracked, 0, "{c:?}");
    // The exposure tick to the arrival tick, which carried the frame: four ticks each.
    assert_eq!(c.ticks_retracked, 4 * stats.depth_frames, "{c:?}");
    assert_eq!(arrivals.len() as u64, stats.depth_frames);
    assert_eq!(deferred.len(), at_arrival.len());
    let mut differing = 0;
    for (d, a) in deferred.iter().zip(&at_arrival) {
        assert_eq!(d.t_us, a.t_us);
        if arrivals.contains(&d.t_us) {
            differing += usize::from(d.pose != a.pose);
        } else {
            assert_eq!(d.pose, a.pose, "tick {}", d.t_us);
        }
    }
    // The arrival ticks used the frame carried from its exposure, not tracked again.
    assert!(
        differing * 2 > arrivals.len(),
        "{differing} of {} arrival ticks differ",
        arrivals.len()
    );
}

/// A frame handed over to be carried only is carried at its tick and never tracked again: the poses are the
/// carrying tracker's (`retrack_late_depth = false`) bit for bit, though states are saved and events logged.
#[test]
fn a_frame_carried_only_gives_the_carrying_poses() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(&dir.path().join("mug"), 0.5);
    let carrying = TrackerConfig {
        late_depth: LateDepthConfig {
            retrack_late_depth: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let (carried, _, stats) = track(&rec, carrying, 20_000);
    let (tracker, first_us) = mug_tracker(&rec, TrackerConfig::default());
    let mut driver = DeferringDriver(tracker, true);
    let mut poses = Vec::new();
    let timing = OfflineTiming {
        start_us: first_us,
        depth_latency_us: 20_000,
        depth_jitter_us: 0,
    };
    track_recording_timed(
        &rec,
        &mut driver,
        timing,
        |_, e, _| poses.extend_from_slice(e),
        |_| {},
    )
    .expect("replay");
    let c = driver.0.counters();
    assert!(stats.depth_frames >= 12, "{stats:?}");
    assert_eq!(c.late_frames_retracked, 0, "{c:?}");
    assert_eq!(c.late_frames_not_retracked, stats.depth_frames, "{c:?}");
    assert_eq!(c.depth_frames_late, stats.depth_frames, "{c:?}");
    assert_eq!(poses.len(), carried.len());
    for (p, q) in poses.iter().zip(&carried) {
        assert_eq!((p.t_us, p.pose), (q.t_us, q.pose));
    }
}

/// What a late frame corrects at its tick, it corrects since its exposure: the history `pose_at` answers from is
/// nearer the truth than the estimates reported at those ticks. Without latency it is the reported estimates.
#[test]
fn pose_at_answers_from_the_corrected_history() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let (on_time, tracker, _) = track(&rec, TrackerConfig::default(), 0);
    let recent = &on_time[on_time.len() - 40..];
    for e in recent {
        let p = tracker.pose_at(0, e.t_us).expect("a kept tick");
        assert_eq!(p.pose, e.pose, "at {} us", e.t_us);
    }
    // Between two ticks it interpolates them when no step between ticks ran there (with steps, it answers from
    // the steps: tests/tests/inner_steps.rs).
    let (on_time, tracker, _) = track(&rec, ticks_only(), 0);
    let recent = &on_time[on_time.len() - 40..];
    let (a, b) = (recent[10], recent[11]);
    let t = a.t_us + (b.t_us - a.t_us) / 3;
    let between = tracker.pose_at(0, t).unwrap().pose;
    let s = (t - a.t_us) as f64 / (b.t_us - a.t_us) as f64;
    let expected = se3::interpolate(&a.pose, &b.pose, s);
    assert!(
        (between.translation.vector - expected.translation.vector).norm() < 1e-9
            && between.rotation.angle_to(&expected.rotation) < 1e-9,
        "a third of the way between two ticks: {between:?} against {expected:?}"
    );

    let (late, tracker, _) = track(&rec, TrackerConfig::default(), 40_000);
    let recent = &late[late.len() - 40..];
    let reported = timed(recent);
    let history: Vec<(i64, Isometry3<f64>)> = recent
        .iter()
        .map(|e| (e.t_us, tracker.pose_at(0, e.t_us).unwrap().pose))
        .collect();
    let changed = reported
        .iter()
        .zip(&history)
        .filter(|(r, h)| r.1 != h.1)
        .count();
    assert!(changed >= 20, "{changed} of 40 recent ticks were corrected");
    let from = recent[0].t_us;
    let (e_reported, e_history) = (
        mean_error(&rec, &reported, from),
        mean_error(&rec, &history, from),
    );
    assert!(
        e_history < e_reported,
        "corrected history {e_history} m against reported {e_reported} m"
    );
}

/// Records when the offline driver hands over each depth frame.
#[derive(Default)]
struct DepthLog {
    names: Vec<String>,
    /// (exposure, tick time it arrived before)
    arrivals: Vec<(i64, Option<i64>)>,
    ticks: Vec<i64>,
}

impl PoseTracker for DepthLog {
    fn objects(&self) -> &[String] {
        &self.names
    }
    fn push_events(&mut self, _: &[CdEvent]) {}
    fn push_depth(&mut self, t_us: i64, _: &mut DepthFrame, _: DepthHandling) {
        self.arrivals.push((t_us, None));
    }
    fn tick(&mut self, tick: &Tick, _: &mut Vec<PoseEstimate>) {
        for a in self.arrivals.iter_mut().filter(|a| a.1.is_none()) {
            a.1 = Some(tick.t_us);
        }
        self.ticks.push(tick.t_us);
    }
    fn pose_at(&self, _: usize, _: i64) -> Option<PoseEstimate> {
        None
    }
}

#[test]
fn the_offline_driver_hands_each_frame_over_at_the_first_tick_that_late() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let exposures: Vec<i64> = recording_ticks(&rec)
        .unwrap()
        .iter()
        .filter(|t| t.depth_frame.is_some())
        .map(|t| t.t_us)
        .collect();
    for latency_us in [0, 8_000, 33_333, 40_000, 100_000] {
        let mut log = DepthLog::default();
        let timing = OfflineTiming {
            start_us: 0,
            depth_latency_us: latency_us,
            depth_jitter_us: 0,
        };
        let stats = track_recording_timed(&rec, &mut log, timing, |_, _, _| {}, |_| {}).unwrap();
        let delivered: Vec<i64> = log.arrivals.iter().map(|a| a.0).collect();
        assert_eq!(delivered, exposures[..delivered.len()], "in exposure order");
        assert_eq!(
            delivered.len() as u64 + stats.depth_frames_in_transit,
            exposures.len() as u64,
            "latency {latency_us}: every frame delivered or counted in transit"
        );
        for &(exposed, tick) in &log.arrivals {
            let tick = tick.expect("a tick followed");
            let first_late = *log
                .ticks
                .iter()
                .find(|&&t| t >= exposed + latency_us)
                .unwrap();
            assert_eq!(tick, first_late, "latency {latency_us}, exposure {exposed}");
        }
    }
}
