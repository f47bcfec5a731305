//! The CPU one 120 Hz tick period costs the tracker on a fast object (a 0.8 s fast mug shake, about 2 m/s, 160x160
//! ROI): the events of the period handed over (with the steps between ticks they set off),
//! the depth frame at a depth-exposure tick, the tick and `prepare_next_tick`, as the runtime runs them. Each sample
//! is the CPU time of every thread of the process (the tracker's and the `render-ahead` thread) over consecutive
//! periods of the recording, replayed from its first pose again when it ends (the new tracker is not timed).
//! `defaults`: steps between ticks; `ticks_only`: one refinement per tick, as `config/tracker/ticks-only.toml`
//! sets it. A second group times the depth-frame periods of a mug being searched for, with and without the
//! whole-pose search.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use drivers::event::{CdEvent, EventBuffer};
use drivers::recording::{DepthFrame, Recording};
use drivers::timeline::Tick;
use eventtrack6d_tests::cpu_time::process_cpu_ns;
use eventtrack6d_tests::shipped_params::ticks_only;
use eventtrack6d_tests::tick_fixture::{fast_mug_recording, mug_tracker};
use scene::render::CpuRenderer;
use std::time::Duration;
use tracker::recording::recording_ticks;
use tracker::track::{DepthHandling, EventTrack6d, PoseTracker, TrackerConfig};

/// One tick period of the recording: its events, its tick and the depth frame exposed at it.
struct Period {
    events: Vec<CdEvent>,
    tick: Tick,
    depth: Option<DepthFrame>,
}

/// Every tick period of `rec` from its first tick on.
fn periods(rec: &Recording) -> Vec<Period> {
    let mut all = EventBuffer::new();
    rec.events()
        .expect("events")
        .read_all(&mut all)
        .expect("decoding the events");
    let ticks = recording_ticks(rec).expect("ticks");
    let mut rest = &all.cd[..];
    ticks
        .iter()
        .map(|tick| {
            let split = rest.partition_point(|e| e.t_us <= tick.t_us);
            let events = rest[..split].to_vec();
            rest = &rest[split..];
            let depth = tick
                .depth_frame
                .map(|n| rec.depth_frame(n).expect("depth frame"));
            Period {
                events,
                tick: *tick,
                depth,
            }
        })
        .collect()
}

/// Hands period `p` to `tracker` as the runtime does (its events, its depth frame through `spare`, the tick,
/// `prepare_next_tick`), the estimates into `out`.
fn replay(
    tracker: &mut EventTrack6d,
    p: &Period,
    spare: &mut Option<DepthFrame>,
    out: &mut Vec<tracker::track::PoseEstimate>,
) {
    tracker.push_events(&p.events);
    if let (Some(frame), Some(spare)) = (p.depth.as_ref(), spare.as_mut()) {
        spare.clone_from(frame);
        tracker.push_depth(p.tick.t_us, spare, DepthHandling::Now);
    }
    out.clear();
    tracker.tick(&p.tick, out);
    tracker.prepare_next_tick();
}

/// Replays `periods` of `rec` into trackers with `config`, timing each period's CPU.
fn bench_periods(
    c: &mut Criterion,
    label: &str,
    rec: &Recording,
    periods: &[Period],
    config: &TrackerConfig,
) {
    let fresh =
        || -> EventTrack6d { mug_tracker(rec, config.clone(), Box::new(CpuRenderer::new()), 1).0 };
    let mut tracker = fresh();
    let mut next = 0;
    let mut told = false;
    let mut out = Vec::with_capacity(4);
    let mut spare = periods[0].depth.clone();
    c.bench_function(&format!("cpu_of_fast_period_{label}_160"), |b| {
        b.iter_custom(|iters| {
            let mut total = 0;
            for _ in 0..iters {
                if next == periods.len() {
                    if !told {
                        let counters = tracker.counters();
                        eprintln!(
                            "{label}: {} steps between {} ticks",
                            counters.inner_steps, counters.ticks
                        );
                        told = true;
                    }
                    tracker = fresh();
                    next = 0;
                }
                let start = process_cpu_ns();
                replay(&mut tracker, &periods[next], &mut spare, &mut out);
                total += process_cpu_ns().saturating_sub(start);
                next += 1;
            }
            Duration::from_nanos(total)
        })
    });
}

fn fast_periods(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("eventtrack6d-fast-period-bench");
    let rec = fast_mug_recording(&dir, 0.8);
    let periods = periods(&rec);
    bench_periods(c, "defaults", &rec, &periods, &TrackerConfig::default());
    bench_periods(c, "ticks_only", &rec, &periods, &ticks_only());
}

/// The CPU of the depth-exposure periods while the mug is searched for: the tracker is re-seeded 15 cm
/// beside the mug and turned 120 degrees at the first tick, so every depth frame plans a re-detection search (and
/// checks its first places) until it is found; every 24 periods it is re-seeded again. Only the periods with a
/// depth frame are timed (the others are replayed untimed). `pose_search`: the defaults; `no_pose_search`:
/// `pose_search_views = 0`.
fn search_periods(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("eventtrack6d-fast-period-bench");
    let rec = fast_mug_recording(&dir, 0.8);
    let periods = periods(&rec);
    let gt = rec.ground_truth.clone().expect("ground truth");
    let truth = tracker::recording::PoseTrack::from_samples(&gt, "mug");
    for (label, views) in [("pose_search", None), ("no_pose_search", Some(0))] {
        let mut config = TrackerConfig::default();
        if let Some(v) = views {
            config.redetect.pose_search_views = v;
        }
        let fresh = || -> EventTrack6d {
            let (mut t, first_us) =
                mug_tracker(&rec, config.clone(), Box::new(CpuRenderer::new()), 1);
            let pose = truth.interpolated_at(first_us).expect("first pose");
            let turn = nalgebra::UnitQuaternion::from_axis_angle(
                &nalgebra::Vector3::x_axis(),
                120f64.to_radians(),
            );
            let lost = nalgebra::Isometry3::from_parts(
                nalgebra::Translation3::from(
                    pose.translation.vector + nalgebra::Vector3::new(0.15, 0.0, 0.0),
                ),
                turn * pose.rotation,
            );
            t.reseed(0, first_us, lost).expect("re-seed");
            t
        };
        let mut tracker = fresh();
        let mut next = 0;
        let mut out = Vec::with_capacity(4);
        let mut spare = periods[0].depth.clone();
        c.bench_function(&format!("cpu_of_search_depth_period_{label}_160"), |b| {
            b.iter_custom(|iters| {
                let mut total = 0;
                let mut timed = 0;
                while timed < iters {
                    if next == periods.len().min(24) {
                        tracker = fresh();
                        next = 0;
                    }
                    let depth = next > 0 && periods[next].depth.is_some();
                    let start = process_cpu_ns();
                    replay(&mut tracker, &periods[next], &mut spare, &mut out);
                    if depth {
                        total += process_cpu_ns().saturating_sub(start);
                        timed += 1;
                    }
                    next += 1;
                }
                Duration::from_nanos(total)
            })
        });
    }
}

criterion_group!(benches, fast_periods, search_periods);
criterion_main!(benches);
