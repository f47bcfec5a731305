//! The depth safety net's decision record (`PoseTracker::depth_fallback_checks`, written by `eventtrack6d track
//! --fallback-trace`) says what the tracker did: one check per object at each fresh depth frame after the first,
//! a replacement exactly when a candidate whose motion the surroundings do not contradict beat the estimate by the
//! margin, the published pose is then that candidate's, and the replacements add up to the tracker's counter.
//! The candidates refused for their motion were the wrong ones: farther from the truth than the estimate kept.
//! A depth frame that arrives late is checked at its exposure, where it shows the object: an estimate knocked off
//! the object there is replaced by a candidate near the truth.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::CdEvent;
use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use eventtrack6d_tests::shipped_params::ticks_only;
use eventtrack6d_tests::tick_fixture::mug_recording;
use hil_sim::generate::{GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use scene::render::CpuRenderer;
use tracker::recording::{PoseTrack, recording_ticks};
use tracker::recording::{recording_object, recording_rig};
use tracker::track::DepthHandling;
use tracker::track::{
    DepthFallbackCheck, EventTrack6d, FallbackRule, LateDepthConfig, OfflineTiming, PoseEstimate,
    PoseTracker, TrackerConfig, TrackerCounters, track_recording, track_recording_timed,
};

/// A marker held in a hand, translating at moderate speed for 1 s (seed 1031, the dev suite's marker
/// translation moderate): its safety net replaces the estimate several times, rightly and wrongly.
fn moving_marker() -> (tempfile::TempDir, Recording) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = GenerateConfig::new(
        ObjectSource::Library(ObjectKind::Marker),
        MotionProfile::Translation,
        SpeedLevel::Moderate,
        1.0,
        1031,
    );
    generate(&cfg, dir.path(), |_| {}).expect("generating the recording");
    let recording = Recording::open(dir.path()).expect("recording");
    (dir, recording)
}

/// The ground truth of `name` in `recording`, the first tick's time and a tracker with the default config started
/// there at the true pose.
fn tracker_from_truth(recording: &Recording, name: &str) -> (PoseTrack, i64, EventTrack6d) {
    tracker_from_truth_with(recording, name, TrackerConfig::default())
}

fn tracker_from_truth_with(
    recording: &Recording,
    name: &str,
    config: TrackerConfig,
) -> (PoseTrack, i64, EventTrack6d) {
    let gt = recording.ground_truth.clone().expect("ground truth");
    let truth = PoseTrack::from_samples(&gt, name);
    let first = recording_ticks(recording).expect("ticks")[0].t_us;
    let pose = truth.interpolated_at(first).expect("first pose");
    let object = recording_object(recording, name, first, pose).expect("model");
    let rig = recording_rig(recording).expect("rig");
    let tracker = EventTrack6d::new(config, rig, vec![object], Box::new(CpuRenderer::new()))
        .expect("tracker");
    (truth, first, tracker)
}

#[test]
fn the_fallback_record_matches_what_the_tracker_published() {
    let (_dir, recording) = moving_marker();
    let (truth, first, mut tracker) = tracker_from_truth(&recording, "marker");
    let rule = TrackerConfig::default().safety_net.fallback_rule();
    let motion_margin = rule.motion_margin;

    let mut checks = Vec::new();
    let mut ticks_with_check = Vec::new();
    let mut depth_ticks = 0usize;
    let mut replaced = 0u64;
    let mut kept = 0u64;
    // (candidate's distance to the truth, estimate's), metres, for each candidate refused for its motion.
    let mut refused = Vec::new();
    track_recording(
        &recording,
        &mut tracker,
        first,
        |tick, estimates, t| {
            depth_ticks += usize::from(tick.depth_frame.is_some());
            checks.clear();
            t.depth_fallback_checks(&mut checks);
            if tick.depth_frame.is_some() {
                // The first depth frame has no earlier one to start a candidate from.
                assert!(
                    checks.len() <= 1,
                    "tick {}: {} checks",
                    tick.index,
                    checks.len()
                );
            } else {
                assert!(checks.is_empty(), "tick {} has no depth frame", tick.index);
            }
            for c in &checks {
                ticks_with_check.push(tick.index);
                assert_eq!((c.t_us, c.tick_us), (tick.t_us, tick.t_us));
                assert_eq!(c.object, 0);
                check_decision(c, &rule, Some(&estimates[0].pose));
                let at = truth.interpolated_at(c.t_us).expect("truth at the check");
                let off = |p: &nalgebra::Isometry3<f64>| {
                    (p.translation.vector - at.translation.vector).norm()
                };
                for cand in c.candidates.iter().flatten() {
                    if !c.motion_allows(cand, motion_margin) {
                        refused.push((off(&cand.pose), off(&c.estimate)));
                    }
                }
                match c.replaced_by {
                    Some(_) => replaced += 1,
                    None => kept += 1,
                }
            }
        },
        |_| {},
    )
    .expect("tracking");

    // Every depth frame but the first is checked.
    assert!(depth_ticks >= 25, "{depth_ticks} depth frames in 1 s");
    assert_eq!(ticks_with_check.len(), depth_ticks - 1);
    assert_eq!(replaced, tracker.counters().depth_fallbacks);
    // The sequence exercises both outcomes.
    assert!(
        replaced >= 1 && kept >= 1,
        "replaced {replaced}, kept {kept}"
    );
    // The hand holding the marker offers more agreeing depth than the marker: the motion check refuses the
    // candidates that slid onto it. At least three in four refusals are of a candidate more than 1 cm farther
    // from the truth than the estimate kept, and none stops a recovery (a candidate within 5 mm of the truth
    // refused while the estimate is more than 3 cm off).
    assert!(
        refused.len() >= 10,
        "{} candidates refused for their motion",
        refused.len()
    );
    let wrong = refused
        .iter()
        .filter(|(cand, est)| *cand > est + 0.01)
        .count();
    assert!(
        wrong * 4 >= refused.len() * 3,
        "only {wrong} of {} refused candidates were the wrong ones: {refused:?}",
        refused.len()
    );
    for (cand, est) in &refused {
        assert!(
            !(*cand < 0.005 && *est > 0.03),
            "a candidate {:.1} mm off refused, the estimate kept {:.1} mm off",
            cand * 1e3,
            est * 1e3
        );
    }
}

/// One check is consistent with the rule and, when given, with the published pose.
fn check_decision(
    c: &DepthFallbackCheck,
    rule: &FallbackRule,
    published: Option<&nalgebra::Isometry3<f64>>,
) {
    let (margin, motion_margin) = (rule.margin, rule.motion_margin);
    let contradicted = c.estimate_contradicted(rule.estimate_motion_margin);
    assert!((0.0..=1.0).contains(&c.estimate_agreeing));
    let all: Vec<_> = c.candidates.iter().flatten().collect();
    assert!(!all.is_empty(), "a check without candidates");
    for cand in &all {
        assert!((0.0..=1.0).contains(&cand.agreeing));
        assert!(
            cand.motion_agreeing
                .is_none_or(|m| (0.0..=1.0).contains(&m))
        );
    }
    let candidates: Vec<_> = all
        .into_iter()
        .filter(|cand| c.motion_allows(cand, motion_margin))
        .collect();
    let best = candidates
        .iter()
        .map(|cand| cand.agreeing)
        .fold(f64::NEG_INFINITY, f64::max);
    let gap = |a: &nalgebra::Isometry3<f64>, b: &nalgebra::Isometry3<f64>| {
        (a.translation.vector - b.translation.vector).norm() + a.rotation.angle_to(&b.rotation)
    };
    match c.replaced_by {
        Some(k) => {
            let winner = c.candidates[k].expect("the replacing candidate is recorded");
            assert_eq!(
                winner.agreeing, best,
                "t {}: not the best candidate",
                c.t_us
            );
            assert!(
                contradicted || winner.agreeing > c.estimate_agreeing + margin,
                "t {}: a candidate no better than the estimate it replaced",
                c.t_us
            );
            assert!(
                c.motion_allows(&winner, motion_margin),
                "t {}: a refused candidate won",
                c.t_us
            );
            assert!(
                published.is_none_or(|p| gap(&winner.pose, p) < 1e-6),
                "t {}: published pose is not the replacing candidate's",
                c.t_us
            );
        }
        None => {
            assert!(
                best <= c.estimate_agreeing + margin,
                "t {}: a better candidate was ignored",
                c.t_us
            );
            assert!(
                !contradicted || candidates.is_empty(),
                "t {}: a contradicted estimate kept over an eligible candidate",
                c.t_us
            );
            assert!(
                published.is_none_or(|p| gap(&c.estimate, p) < 1e-6),
                "t {}: published pose is not the kept estimate",
                c.t_us
            );
        }
    }
}

/// The tracker, knocked off the object at one tick: its estimate there is moved by `KNOCK` (as events that slid
/// onto a neighbouring edge would leave it). Everything else is passed through.
struct KnockedOff {
    inner: EventTrack6d,
    /// The tick at whose time the estimate is replaced, microseconds.
    at_us: i64,
    last: Option<PoseEstimate>,
}

/// How far the estimate is moved, metres (camera x).
const KNOCK: f64 = 0.05;

impl PoseTracker for KnockedOff {
    fn objects(&self) -> &[String] {
        self.inner.objects()
    }
    fn push_events(&mut self, events: &[CdEvent]) {
        self.inner.push_events(events);
    }
    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling) {
        self.inner.push_depth(t_us, frame, handling);
    }
    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        let from = out.len();
        self.inner.tick(tick, out);
        if tick.t_us == self.at_us {
            let mut e = out[from];
            e.pose.translation.vector.x += KNOCK;
            assert!(self.inner.reset_pose(0, tick.t_us, e.pose));
            out[from] = e;
        }
        self.last = out.get(from).copied();
    }
    fn prepare_next_tick(&mut self) {
        self.inner.prepare_next_tick();
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.inner.pose_at(object, t_us)
    }
    fn tracker_counters(&self) -> Option<TrackerCounters> {
        Some(self.inner.counters())
    }
    fn depth_fallback_checks(&self, out: &mut Vec<DepthFallbackCheck>) {
        self.inner.depth_fallback_checks(out);
    }
}

/// Tracks `recording` with depth frames `latency_us` late and returns the safety net's checks, each checked as it
/// is reported: at most one per tick, reported with the tick the frame arrived at and made at its exposure (at
/// least the latency and less than the latency and a tick before), decided by the default rule.
fn late_checks(
    recording: &Recording,
    tracker: &mut dyn PoseTracker,
    first: i64,
    latency_us: i64,
) -> Vec<DepthFallbackCheck> {
    let rule = TrackerConfig::default().safety_net.fallback_rule();
    let timing = OfflineTiming {
        start_us: first,
        depth_latency_us: latency_us,
        depth_jitter_us: 0,
    };
    let mut checks = Vec::new();
    let mut all = Vec::new();
    track_recording_timed(
        recording,
        tracker,
        timing,
        |tick, _, t| {
            checks.clear();
            t.depth_fallback_checks(&mut checks);
            assert!(
                checks.len() <= 1,
                "tick {}: {} checks",
                tick.index,
                checks.len()
            );
            for c in &checks {
                assert_eq!(c.tick_us, tick.t_us);
                let age = tick.t_us - c.t_us;
                assert!(
                    (latency_us..latency_us + 8_400).contains(&age),
                    "tick {}: a check {age} us old",
                    tick.index
                );
                check_decision(c, &rule, None);
                all.push(*c);
            }
        },
        |_| {},
    )
    .expect("tracking");
    all
}

/// Depth frames 40 ms late on a moderate mug shake, carried from their exposure (`retrack_late_depth = false`):
/// each is checked at its exposure, against the estimate the pose history holds for then, by the same rule. An
/// estimate knocked 5 cm off at a depth exposure is found out by that frame when it arrives, and replaced there
/// by a candidate from the frame before. (At the tick the frame arrives at, its points are carried by the motion
/// estimated since, so they would agree with a wrong estimate.) One refinement per tick
/// (`config/tracker/ticks-only.toml`), so that the candidates start from a history of the ticks alone: steps
/// between ticks after the knock move the history the extrapolated candidate starts from (12 mm off then).
#[test]
fn late_frames_are_checked_at_their_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let recording = mug_recording(&dir.path().join("mug"), 1.0);
    let base = ticks_only();
    let carrying = TrackerConfig {
        late_depth: LateDepthConfig {
            retrack_late_depth: false,
            ..base.late_depth
        },
        ..base
    };
    let (truth, first, inner) = tracker_from_truth_with(&recording, "mug", carrying);
    // Knocked off at the 11th depth exposure.
    let knock = recording_ticks(&recording)
        .expect("ticks")
        .iter()
        .filter(|t| t.depth_frame.is_some())
        .nth(10)
        .expect("11 depth exposures")
        .t_us;
    let mut tracker = KnockedOff {
        inner,
        at_us: knock,
        last: None,
    };
    let checks = late_checks(&recording, &mut tracker, first, 40_000);
    let exposures: Vec<i64> = checks.iter().map(|c| c.t_us).collect();
    let at_knock = checks.iter().find(|c| c.t_us == knock).copied();

    let counters = tracker.inner.counters();
    assert_eq!(counters.depth_frames_late, counters.depth_frames);
    // The frame exposed just before the knock arrives after it, when the history no longer reaches back.
    assert!(counters.late_depth_unplaced >= 1, "{counters:?}");
    // Every placed frame is checked once but the first and those after a re-detection, which have no frame
    // before them to start a candidate from.
    let checked = exposures.len() as u64;
    let unchecked = 1 + counters.late_depth_unplaced + counters.redetections;
    assert!(
        checked < counters.depth_frames && checked + unchecked >= counters.depth_frames,
        "{checked} checks, {counters:?}"
    );
    assert!(exposures.windows(2).all(|w| w[1] > w[0]), "{exposures:?}");

    let c = at_knock.expect("the frame exposed at the knock was checked");
    let at = truth.interpolated_at(knock).expect("truth at the knock");
    let off = |p: &nalgebra::Isometry3<f64>| (p.translation.vector - at.translation.vector).norm();
    let k = c
        .replaced_by
        .unwrap_or_else(|| panic!("the knocked-off estimate was kept: {c:?}"));
    let winner = c.candidates[k].expect("the replacing candidate");
    eprintln!(
        "at the knock: estimate {:.1} mm off, replaced by the {} candidate {:.1} mm off",
        off(&c.estimate) * 1e3,
        winner.start.as_str(),
        off(&winner.pose) * 1e3
    );
    // The check's estimate is the knocked-off one refined on the frame's depth alone, which pulls it part of the
    // way back (24-49 mm off remain, depending on the motion before); the candidate is on the object.
    assert!(off(&c.estimate) > 0.02, "{c:?}");
    assert!(off(&winner.pose) < 0.01, "{c:?}");
    let last = tracker.last.expect("a last estimate");
    let end = truth.interpolated_at(last.t_us).expect("truth at the end");
    assert!(
        (last.pose.translation.vector - end.translation.vector).norm() < 0.02,
        "not back on the object by the end: {last:?}"
    );
}

/// Depth frames 20 ms late, tracked again from their exposure (the default): each frame's check is made at its
/// exposure tick as on time, and reported with the tick that tracked again, the one the frame arrived at.
#[test]
fn frames_tracked_again_report_their_check_at_the_arrival_tick() {
    let dir = tempfile::tempdir().unwrap();
    let recording = mug_recording(&dir.path().join("mug"), 1.0);
    let (_, first, mut tracker) = tracker_from_truth(&recording, "mug");
    let exposures: Vec<i64> = late_checks(&recording, &mut tracker, first, 20_000)
        .iter()
        .map(|c| c.t_us)
        .collect();
    let counters = tracker.counters();
    assert_eq!(
        counters.late_frames_retracked, counters.depth_frames,
        "{counters:?}"
    );
    // Every frame but the first (no frame before it to start a candidate from) is checked once.
    assert_eq!(
        exposures.len() as u64 + 1,
        counters.depth_frames,
        "{counters:?}"
    );
    assert!(exposures.windows(2).all(|w| w[1] > w[0]), "{exposures:?}");
}
