//! The runtime's replay and the offline driver behind `track` and `bench` hand the tracker the same input, so a
//! replayed recording gives the poses the benchmark scores, to the bit. Before the runtime held back the events
//! decoded inside a trigger pulse, they reached the tick stamped with the pulse's rising edge, and a replay of a
//! two-object scene scored 47 / 8 ADD-S where the benchmark scored 22 / 23. Both hand the tracker each depth frame
//! by moving it, not copying it.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d::runtime::setup::recording_scene;
use eventtrack6d::runtime::{self, Hooks, build_tracker};
use eventtrack6d_tests::replay_counters::assert_counters_match_offline;
use eventtrack6d_tests::shipped_params::ticks_only_toml;
use eventtrack6d_tests::tick_fixture::{
    mug_and_can_recording, mug_recording, offline_pose_rows, steady_tracker,
};
use scene::render::{CpuRenderer, RendererKind};
use tracker::recording::parse_pose_csv;
use tracker::track::{DepthHandling, OfflineTiming, PoseTracker, TrackerConfig, TrackerCounters};

/// A pushed depth frame moves into the tracker, which hands back the frame it held: the samples are never
/// copied (an 848x480 frame is 1.6 MB, on the depth tick's latency).
#[test]
fn a_pushed_depth_frame_moves_in_and_the_previous_one_comes_back() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(dir.path(), 0.1);
    let mut s = steady_tracker(rec, TrackerConfig::default(), Box::new(CpuRenderer::new()));
    let t_us = s.last_tick.t_us;
    let held = s.depth.index;
    let mut next = s.depth.clone();
    next.index = held + 1;
    let samples = next.depth_m.as_ptr();
    s.tracker.push_depth(t_us, &mut next, DepthHandling::Now);
    assert_eq!(next.index, held, "the frame the replay left in the tracker");
    assert_eq!(next.depth_m.len(), (next.width * next.height) as usize);
    assert_ne!(next.depth_m.as_ptr(), samples);
    s.tracker.push_depth(t_us, &mut next, DepthHandling::Now);
    assert_eq!(next.index, held + 1);
    assert_eq!(
        next.depth_m.as_ptr(),
        samples,
        "the same buffer, not a copy"
    );
}

/// By default the tracker also refines between ticks, as the events past each step's time arrive: in the
/// runtime they come in batches of 53 us, offline between two trigger edges at once, and the steps see the same
/// events either way. With `config/tracker/ticks-only.toml` it refines once per tick, and the replay and the
/// offline driver agree as well, counters and all.
#[test]
fn a_fast_replay_gives_the_offline_poses_exactly_with_or_without_steps_between_ticks() {
    let steps = replay_matches_offline(0, 0);
    assert!(steps.inner_steps >= steps.ticks, "{steps:?}");
    let dir = tempfile::tempdir().unwrap();
    let rec_dir = dir.path().join("rec");
    let rec = mug_and_can_recording(&rec_dir);
    let (ticks_only, _) =
        compare_replay_with_offline(dir.path(), &rec_dir, rec, 0, 0, &ticks_only_toml());
    assert_eq!(ticks_only.inner_steps, 0, "{ticks_only:?}");
    assert_eq!(ticks_only.ticks, steps.ticks);
}

/// With depth frames delivered 40 ms after their exposure (`[source] depth_latency_ms`, `track
/// --depth-latency-ms`), both hand each frame over before the same tick: the replay between two ticks, when the
/// stream reaches that time, the offline driver just before the tick after it. The tracker tracks again from
/// the exposure when the frame arrives, so the two give the same poses.
#[test]
fn a_fast_replay_with_late_depth_gives_the_offline_poses_exactly() {
    let counters = replay_matches_offline(40_000, 0);
    assert!(counters.depth_frames_late >= 10, "{counters:?}");
    assert_eq!(counters.depth_frames_late, counters.depth_frames);
    assert_eq!(counters.late_frames_retracked, counters.depth_frames);
}

/// A frame that falls due 50 us after a tick pulse rises (three tick periods and 50 us late) comes after that
/// pulse's falling edge: the tick it makes is stamped before the frame was due and runs without it, as offline.
#[test]
fn a_frame_due_inside_a_tick_pulse_comes_after_the_pulse_as_offline() {
    let counters = replay_matches_offline(25_050, 0);
    assert!(counters.depth_frames_late >= 10, "{counters:?}");
    // Tracked again from the exposure: the exposure tick and the three after it.
    assert_eq!(counters.ticks_retracked, 4 * counters.late_frames_retracked);
}

/// A latency that varies from frame to frame (20 ms plus up to 25 ms, drawn per frame from its exposure time):
/// both draw the same for each frame, so they still agree, and the frames land at different places between ticks.
#[test]
fn a_fast_replay_with_jittered_depth_latency_gives_the_offline_poses_exactly() {
    let counters = replay_matches_offline(20_000, 25_000);
    assert!(counters.depth_frames_late >= 10, "{counters:?}");
    // Tracked again over 3 to 6 ticks each (the exposure tick to the one before the arrival), not always the same.
    let per_frame = counters.ticks_retracked as f64 / counters.late_frames_retracked as f64;
    assert!(per_frame > 3.0 && per_frame < 6.0, "{counters:?}");
}

/// Trigger pulses missing from the stream (a depth-coded one, two in a row, a single one): the timeline places
/// a tick in each gap, and the runtime holds the events from the time a missing pulse was due until the next
/// pulse comes, so each tick placed in a gap sees only the events before it, as offline. Before the hold, the
/// runtime handed those events over at once and the ticks in the gaps saw up to a period of later events.
#[test]
fn a_fast_replay_with_missing_trigger_pulses_gives_the_offline_poses_exactly() {
    // Pulse 31 comes 45 us early (within the jitter tolerance), so the tick placed for pulse 30 lies before
    // the schedule's time for it.
    let summary_missing = replay_matches_offline_with(0, 0, &[8, 13, 14, 30], &[(31, -45)]);
    assert_eq!(summary_missing, 4);
}

/// A trigger clock 0.96 % slower than nominal (each pulse 80 us later than the last one's period), with a
/// phase-coded pulse missing: the replay numbers each depth frame from the latest phase-coded pulse, so the drift
/// never adds up to a tick, and the poses are the offline ones. Numbered from the first pulse with the nominal
/// period, the frames went out a tick early from about 0.4 s on here (after 42 s at 100 ppm).
#[test]
fn a_drifting_trigger_clock_keeps_the_depth_frames_on_their_ticks() {
    let drift: Vec<(usize, i64)> = (0..64).map(|k| (k, 80 * k as i64)).collect();
    let missing = replay_matches_offline_with(0, 0, &[20], &drift);
    assert_eq!(missing, 1);
}

/// Replays the two-object scene offline and through the runtime with depth frames `latency_us` late plus up to
/// `jitter_us`, checks both gave the same estimates and counters, and returns the counters.
fn replay_matches_offline(latency_us: i64, jitter_us: i64) -> TrackerCounters {
    let dir = tempfile::tempdir().unwrap();
    let rec_dir = dir.path().join("rec");
    let rec = mug_and_can_recording(&rec_dir);
    compare_replay_with_offline(dir.path(), &rec_dir, rec, latency_us, jitter_us, "").0
}

/// [`replay_matches_offline`] on a copy of the scene whose events lack the trigger pulses `dropped` and have the
/// pulses of `shifted` moved by their microseconds (counting rising edges on the tick channel from 0); returns
/// how many ticks the runtime's timeline synthesised.
fn replay_matches_offline_with(
    latency_us: i64,
    jitter_us: i64,
    dropped: &[usize],
    shifted: &[(usize, i64)],
) -> u64 {
    use drivers::event::EventBuffer;
    use drivers::raw::{RawReader, RawWriter};
    let dir = tempfile::tempdir().unwrap();
    let rec_dir = dir.path().join("rec");
    mug_and_can_recording(&rec_dir);
    let events = rec_dir.join("events.raw");
    let mut reader = RawReader::open(&events).unwrap();
    let thinned = rec_dir.join("events.thinned.raw");
    let mut writer = RawWriter::new(
        std::io::BufWriter::new(std::fs::File::create(&thinned).unwrap()),
        &reader.header().clone(),
    )
    .unwrap();
    // First the trigger edges, edited; then the events again, each edge written with the chunk it falls in,
    // so that a moved edge keeps the stream in time order.
    let (mut rising, mut dropping, mut removed) = (0usize, false, 0usize);
    let mut shift = 0i64;
    let mut edges = Vec::new();
    let mut batch = EventBuffer::new();
    let mut first_pass = RawReader::open(&events).unwrap();
    while first_pass.read_chunk(&mut batch).unwrap() {
        for mut e in batch.triggers.drain(..) {
            if e.channel == 0 {
                if e.rising {
                    dropping = dropped.contains(&rising);
                    shift = shifted
                        .iter()
                        .find(|(k, _)| *k == rising)
                        .map_or(0, |(_, us)| *us);
                    rising += 1;
                }
                e.t_us += shift;
                removed += usize::from(dropping);
                if dropping {
                    continue;
                }
            }
            edges.push(e);
        }
        batch.clear();
    }
    edges.sort_by_key(|e| e.t_us);
    let mut edges = edges.into_iter().peekable();
    while reader.read_chunk(&mut batch).unwrap() {
        let until = batch.cd.last().map_or(i64::MAX, |e| e.t_us);
        let mut chunk_edges = Vec::new();
        while let Some(e) = edges.next_if(|e| e.t_us <= until) {
            chunk_edges.push(e);
        }
        writer.write(&batch.cd, &chunk_edges).unwrap();
        batch.clear();
    }
    let rest: Vec<_> = edges.collect();
    writer.write(&[], &rest).unwrap();
    writer.finish().unwrap();
    assert_eq!(
        removed,
        2 * dropped.len(),
        "each dropped pulse loses both edges"
    );
    std::fs::rename(&thinned, &events).unwrap();
    let rec = drivers::recording::Recording::open(&rec_dir).unwrap();
    compare_replay_with_offline(dir.path(), &rec_dir, rec, latency_us, jitter_us, "").1
}

/// Tracks `rec` offline and through the runtime with the tracker parameters `params` (the keys of the runtime's
/// `[tracker.parameters]` table; empty for the defaults), checks both gave the same estimates and counters, and
/// returns the counters and how many ticks the runtime's timeline synthesised.
fn compare_replay_with_offline(
    dir: &std::path::Path,
    rec_dir: &std::path::Path,
    rec: drivers::recording::Recording,
    latency_us: i64,
    jitter_us: i64,
    params: &str,
) -> (TrackerCounters, u64) {
    let out_dir = dir.join("out");
    let config = replay_config(rec_dir, &out_dir, latency_us, jitter_us, params);
    let tracker_config = config.tracker.parameters.clone();
    // Offline, as `bench` runs it.
    let scene = recording_scene(&rec, &[]).unwrap();
    let mut tracker = build_tracker(
        "eventtrack6d",
        RendererKind::Cpu,
        &tracker_config,
        &scene,
        &rec.meta.trigger.timeline_config(),
    )
    .unwrap();
    let timing = OfflineTiming {
        start_us: scene.objects[0].first_pose.0,
        depth_latency_us: latency_us,
        depth_jitter_us: jitter_us,
    };
    let (offline, stats) = offline_pose_rows(&rec, tracker.as_mut(), timing);
    assert!(stats.ticks >= 50 && stats.depth_frames >= 11, "{stats:?}");
    let offline_counters = tracker.tracker_counters().expect("the tracker counts");

    // Through the runtime.
    let summary = runtime::run(&config, Hooks::default()).expect("the replay failed");
    assert_eq!(summary.queue.dropped_events, 0);
    let csv = std::fs::read_to_string(summary.outputs.csv.clone().unwrap()).unwrap();
    let replayed: Vec<&str> = csv.lines().skip(1).collect();

    assert_eq!(replayed.len(), offline.len());
    let moving = parse_pose_csv(&csv)
        .unwrap()
        .windows(4)
        .any(|w| (w[0].pose.translation.vector - w[2].pose.translation.vector).norm() > 1e-3);
    assert!(
        moving,
        "the scene must move for the comparison to mean anything"
    );
    for (r, o) in replayed.iter().zip(&offline) {
        assert_eq!(*r, o, "the replay's estimate differs from the offline one");
    }
    let replayed_counters = summary.tracker.expect("the run counts");
    assert_counters_match_offline(
        &replayed_counters,
        &offline_counters,
        tracker_config.inner_steps.max_inner_steps,
        scene.objects.len() as u64,
        latency_us + jitter_us > 0,
    );
    assert_eq!(
        summary.status["tracker"]["depth_frames"],
        offline_counters.depth_frames
    );
    assert!(summary.to_string().contains(&format!(
        "tracker:         {} steps between ticks, {} re-detections",
        replayed_counters.inner_steps, offline_counters.redetections
    )));
    assert_eq!(
        summary.source_stats.depth_frames, stats.depth_frames,
        "both delivered the same frames"
    );
    assert_eq!(
        summary.source_stats.depth_in_transit,
        stats.depth_frames_in_transit
    );
    // Each frame's age when it reached the tracker thread is the latency (on the camera clock), within the gap
    // between two events before it and the width of a tick pulse after it.
    assert_eq!(summary.depth_frame_age.samples, stats.depth_frames);
    assert_eq!(summary.depth_arrival.samples, stats.depth_frames);
    let latency = latency_us as f64;
    // A frame whose phase-coded pulse is missing goes out at the next pulse's falling edge: a tick period later
    // (up to 1 % longer on a slow trigger clock), after the pulse's width, from the schedule's exposure time.
    let missed = if summary.timeline.missing > 0 {
        10_000.0
    } else {
        0.0
    };
    for age in [
        summary.depth_frame_age.p50_us,
        summary.depth_frame_age.max_us,
    ] {
        let age = age.expect("ages recorded");
        assert!(
            (latency - 1000.0..=latency + jitter_us as f64 + 250.0 + missed).contains(&age),
            "a frame {latency} us late reached the tracker {age} us after its exposure"
        );
    }
    assert_eq!(
        summary.status["ingest"]["depth_frame_age_us"]["samples"],
        stats.depth_frames
    );
    assert!(summary.to_string().contains(&format!(
        "depth arrival:   {} frames, age p50 {:.1}",
        stats.depth_frames,
        summary.depth_frame_age.p50_us.unwrap_or(0.0) * 1e-3
    )));
    assert_eq!(summary.event_hold_overflows, 0);
    (offline_counters, summary.timeline.missing)
}

/// The runtime's configuration that replays `rec_dir` as fast as it can into a pose CSV under `out_dir`, in event
/// batches of 53 us so that batch edges fall everywhere, with depth frames `latency_us` late plus up to
/// `jitter_us` and the tracker parameters `params`.
fn replay_config(
    rec_dir: &std::path::Path,
    out_dir: &std::path::Path,
    latency_us: i64,
    jitter_us: i64,
    params: &str,
) -> runtime::config::Config {
    let toml = format!(
        r#"
[source]
kind = "replay"
pace = "fast"
depth_latency_ms = {}
depth_latency_jitter_ms = {}
[replay]
recording = "{}"
[tracker]
method = "eventtrack6d"
[tracker.parameters]
{}
[output]
dir = "{}"
[queue]
batch_us = 53
[sinks]
csv = true
zenoh = false
[can]
enabled = false
"#,
        latency_us as f64 * 1e-3,
        jitter_us as f64 * 1e-3,
        rec_dir.display(),
        params,
        out_dir.display()
    );
    runtime::config::from_toml(&toml, "replay.toml").unwrap()
}
