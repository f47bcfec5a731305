//! Steps between ticks ([`tracker::track::InnerStepConfig`]): a fast object is refined again as its events
//! arrive, so each refinement starts from an estimate at most one step old. These tests track a short fast shake
//! of the mug with and without them.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::CdEvent;
use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use eventtrack6d_tests::shipped_params::ticks_only;
use eventtrack6d_tests::tick_fixture::{fast_mug_recording, mug_tracker};
use scene::render::CpuRenderer;
use tracker::recording::PoseTrack;
use tracker::track::{
    DepthHandling, EventTrack6d, InnerStepConfig, OfflineTiming, PoseEstimate, PoseTracker,
    TrackerConfig, track_recording_timed,
};

/// The tracker configuration with steps between ticks every `step_px` pixels (0: off), the other options as
/// `config/tracker/ticks-only.toml` sets them, so that only the steps differ from one refinement per tick.
fn config(step_px: f64) -> TrackerConfig {
    let base = ticks_only();
    TrackerConfig {
        inner_steps: InnerStepConfig {
            inner_step_px: step_px,
            ..base.inner_steps
        },
        ..base
    }
}

/// A tracker of the recording's mug from its first ground-truth pose, and the time of that pose.
fn first_pose_tracker(rec: &Recording, config: TrackerConfig) -> (EventTrack6d, i64) {
    mug_tracker(rec, config, Box::new(CpuRenderer::new()), 1)
}

/// Tracks `rec` with `tracker`, depth frames `latency_us` after their exposure; returns every estimate.
fn track(
    rec: &Recording,
    tracker: &mut dyn PoseTracker,
    first_us: i64,
    latency_us: i64,
) -> Vec<PoseEstimate> {
    let mut out = Vec::new();
    let timing = OfflineTiming {
        start_us: first_us,
        depth_latency_us: latency_us,
        depth_jitter_us: 0,
    };
    track_recording_timed(
        rec,
        tracker,
        timing,
        |_, e, _| out.extend_from_slice(e),
        |_| {},
    )
    .expect("replay");
    out
}

/// Mean distance between the estimated and true positions, metres.
fn mean_error(rec: &Recording, estimates: &[PoseEstimate]) -> f64 {
    let gt = PoseTrack::from_samples(rec.ground_truth.as_deref().expect("ground truth"), "mug");
    let total: f64 = estimates
        .iter()
        .map(|e| {
            let g = gt
                .interpolated_at(e.t_us)
                .expect("ground truth at the tick");
            (g.translation.vector - e.pose.translation.vector).norm()
        })
        .sum();
    total / estimates.len() as f64
}

/// Hands the events on in pieces of `piece` events, as a live camera's transfers cut them.
struct Pieces {
    tracker: EventTrack6d,
    piece: usize,
}

impl PoseTracker for Pieces {
    fn objects(&self) -> &[String] {
        self.tracker.objects()
    }
    fn push_events(&mut self, events: &[CdEvent]) {
        for chunk in events.chunks(self.piece) {
            self.tracker.push_events(chunk);
        }
    }
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling) {
        self.tracker.push_depth(t_us, frame, handling);
    }
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.tracker.tick(tick, out);
    }
    fn prepare_next_tick(&mut self) {
        self.tracker.prepare_next_tick();
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.tracker.pose_at(object, t_us)
    }
}

/// On a fast shake, steps between ticks run between most ticks and the estimate stays nearer the mug than with
/// the ticks alone; the steps land in the pose history, so `pose_at` between two ticks answers from them.
#[test]
fn steps_between_ticks_keep_nearer_a_fast_object() {
    let dir = tempfile::tempdir().unwrap();
    let rec = fast_mug_recording(&dir.path().join("fast"), 0.8);
    let (mut ticks_only, first_us) = first_pose_tracker(&rec, config(0.0));
    let alone = track(&rec, &mut ticks_only, first_us, 0);
    let (mut stepping, _) = first_pose_tracker(&rec, config(6.0));
    let stepped = track(&rec, &mut stepping, first_us, 0);
    assert_eq!(alone.len(), stepped.len());
    assert_eq!(ticks_only.counters().inner_steps, 0);
    let c = stepping.counters();
    assert_eq!(c.ticks, stepped.len() as u64, "{c:?}");
    assert!(
        c.inner_steps >= c.ticks,
        "a fast object should get steps between most ticks: {c:?}"
    );
    assert!(c.inner_steps <= 3 * c.ticks, "{c:?}");
    let (e_alone, e_stepped) = (mean_error(&rec, &alone), mean_error(&rec, &stepped));
    eprintln!(
        "mean position error: ticks alone {:.1} mm, with steps between {:.1} mm ({} steps over {} ticks)",
        e_alone * 1e3,
        e_stepped * 1e3,
        c.inner_steps,
        c.ticks
    );
    assert!(e_stepped < 0.8 * e_alone, "{e_stepped} against {e_alone} m");
    // Between the last two ticks, the history holds the steps' own estimates, not an interpolation.
    let (a, b) = (&stepped[stepped.len() - 2], &stepped[stepped.len() - 1]);
    let mid = (a.t_us + b.t_us) / 2;
    let between = stepping.pose_at(0, mid).expect("pose between ticks");
    let interpolated = scene::geometry::se3::interpolate(&a.pose, &b.pose, 0.5);
    assert!(
        (between.pose.translation.vector - interpolated.translation.vector).norm() > 1e-6,
        "pose_at between ticks is a plain interpolation"
    );
}

/// A step between ticks runs once an event after its time has come, on the events up to its time: however the
/// events are cut into pieces, every estimate is the same bit for bit.
#[test]
fn steps_between_ticks_do_not_depend_on_how_the_events_are_cut() {
    let dir = tempfile::tempdir().unwrap();
    let rec = fast_mug_recording(&dir.path().join("fast"), 0.8);
    let (mut whole, first_us) = first_pose_tracker(&rec, config(6.0));
    let reference = track(&rec, &mut whole, first_us, 0);
    assert!(whole.counters().inner_steps > 0);
    for piece in [1, 977] {
        let (tracker, _) = first_pose_tracker(&rec, config(6.0));
        let mut pieces = Pieces { tracker, piece };
        let cut = track(&rec, &mut pieces, first_us, 0);
        assert_eq!(cut, reference, "events in pieces of {piece}");
        assert_eq!(
            pieces.tracker.counters(),
            whole.counters(),
            "pieces of {piece}"
        );
    }
}

/// With depth frames 20 ms late, the tracker goes back to the exposure and tracks again, the steps between ticks
/// planned again from the new estimates: every arrival tick gives the on-time estimate bit for bit.
#[test]
fn tracking_again_plans_the_steps_between_ticks_again() {
    let dir = tempfile::tempdir().unwrap();
    let rec = fast_mug_recording(&dir.path().join("fast"), 0.8);
    let (mut on_time_tracker, first_us) = first_pose_tracker(&rec, config(6.0));
    let on_time = track(&rec, &mut on_time_tracker, first_us, 0);
    let (mut late_tracker, _) = first_pose_tracker(&rec, config(6.0));
    let late = track(&rec, &mut late_tracker, first_us, 20_000);
    let c = late_tracker.counters();
    assert!(c.late_frames_retracked >= 15, "{c:?}");
    assert_eq!(c.late_frames_not_retracked, 0, "{c:?}");
    assert!(c.inner_steps > 0, "{c:?}");
    let identical = late
        .iter()
        .zip(&on_time)
        .filter(|(l, o)| {
            assert_eq!(l.t_us, o.t_us);
            l.pose == o.pose
        })
        .count() as u64;
    // Every arrival tick (the ticks between lack the frame still in transit).
    assert!(
        identical >= c.late_frames_retracked,
        "{identical} identical estimates, {} frames tracked again",
        c.late_frames_retracked
    );
}
