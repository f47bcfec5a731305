//! A tracker tick allocates nothing on the heap in steady state (DESIGN section 3): counted with a global
//! allocator wrapper around the system allocator (every thread, so the `render-ahead` and object threads count
//! too), over event, depth and plain ticks, each followed by `prepare_next_tick` as in the runtime, for one
//! object and for two objects on two threads, and with steps between ticks.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::recording::Recording;
use eventtrack6d_tests::tick_fixture::{mug_recording, steady_tracker_of};
use scene::render::CpuRenderer;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use tracker::track::DepthHandling;
use tracker::track::{
    ExecutionConfig, LateDepthConfig, PoseTracker, TrackerConfig, TrackerCounters, TrackingMethod,
};

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Counts the heap allocations (every thread) of 11 steady-state ticks (the fewest of up to three windows) of a
/// tracker of `objects` objects (the mug and copies of it beside it), each followed by `prepare_next_tick`, after
/// warming every buffer up. Depth frames arrive `depth_late_us` after their exposure (0: with their tick).
fn allocations_of_steady_ticks(
    rec: &Recording,
    config: TrackerConfig,
    objects: usize,
    depth_late_us: i64,
) -> (usize, TrackerCounters) {
    let mut s = steady_tracker_of(rec.clone(), config, Box::new(CpuRenderer::new()), objects);
    let mut out = Vec::with_capacity(4 * objects);
    let events: Vec<_> = (0..2000u16)
        .map(|i| drivers::event::CdEvent {
            t_us: s.last_tick.t_us,
            x: 500 + i % 200,
            y: 300 + i / 200,
            polarity: i % 3 == 0,
        })
        .collect();
    // Warm up every buffer (depth ticks and plain ticks), then count. A render made ahead that is still on the
    // helper thread when the next round starts cannot lend its slot, so the pool (at most sixteen slots) can
    // grow by one now and then: ten rounds let it settle.
    let mut depth_tick = s.last_tick;
    depth_tick.depth_frame = Some(s.depth.index);
    // One tick, each followed by `prepare_next_tick` as in the runtime: with a depth frame or a plain one.
    let step = |s: &mut eventtrack6d_tests::tick_fixture::SteadyTracker,
                out: &mut Vec<_>,
                with_depth: bool| {
        s.tracker.push_events(&events);
        out.clear();
        if with_depth {
            s.tracker.push_depth(
                depth_tick.t_us - depth_late_us,
                &mut s.depth,
                DepthHandling::Now,
            );
            s.tracker.tick(&depth_tick, out);
        } else {
            s.tracker.tick(&s.last_tick, out);
        }
        s.tracker.prepare_next_tick();
    };
    for _ in 0..10 {
        step(&mut s, &mut out, true);
        step(&mut s, &mut out, false);
    }
    // Count up to three windows of eleven ticks and keep the fewest: an allocation made by every tick shows in
    // each window, while the pool's bounded growth when the machine is loaded (a helper thread descheduled for a
    // whole tick) shows in one window and not in the next.
    let mut fewest = usize::MAX;
    for _ in 0..3 {
        ALLOCATIONS.store(0, Ordering::SeqCst);
        COUNTING.store(true, Ordering::SeqCst);
        for k in 0..10 {
            step(&mut s, &mut out, k % 4 == 0);
        }
        // Let the helpers finish what they were given while counting.
        out.clear();
        s.tracker.tick(&s.last_tick, &mut out);
        COUNTING.store(false, Ordering::SeqCst);
        assert_eq!(out.len(), objects);
        fewest = fewest.min(ALLOCATIONS.load(Ordering::SeqCst));
        if fewest == 0 {
            break;
        }
    }
    (fewest, s.tracker.counters())
}

/// Counts the heap allocations of 24 steady ticks at 120 Hz (a depth exposure every fourth) whose frames arrive 20
/// ms late, so that each is tracked again from its exposure, after 48 such ticks of warm-up.
fn allocations_of_retracking_ticks(
    rec: &Recording,
    deferred: bool,
    config: TrackerConfig,
) -> (usize, TrackerCounters) {
    let mut s = steady_tracker_of(rec.clone(), config, Box::new(CpuRenderer::new()), 1);
    let first = s.last_tick;
    let tick_at = |k: u64| drivers::timeline::Tick {
        index: first.index + k,
        t_us: first.t_us + k as i64 * 8_333,
        depth_frame: k.is_multiple_of(4).then_some(k / 4),
        synthesized: false,
    };
    let mut out = Vec::with_capacity(4);
    let mut events: Vec<drivers::event::CdEvent> = Vec::with_capacity(2000);
    let mut step = |s: &mut eventtrack6d_tests::tick_fixture::SteadyTracker, k: u64| {
        let tick = tick_at(k);
        events.clear();
        events.extend((0..2000u16).map(|i| drivers::event::CdEvent {
            t_us: tick.t_us - 8_000 + i64::from(i) * 4,
            x: 500 + i % 200,
            y: 300 + i / 200,
            polarity: i % 3 == 0,
        }));
        s.tracker.push_events(&events);
        if k >= 3 && k % 4 == 3 {
            // The frame exposed three ticks ago (25 ms) arrives now.
            if deferred {
                // Carried at this tick, tracked again in `prepare_next_tick`.
                s.tracker.push_depth(
                    tick_at(k - 3).t_us,
                    &mut s.depth,
                    DepthHandling::AfterNextTick,
                );
            } else {
                s.tracker
                    .push_depth(tick_at(k - 3).t_us, &mut s.depth, DepthHandling::Now);
            }
        }
        out.clear();
        s.tracker.tick(&tick, &mut out);
        s.tracker.prepare_next_tick();
    };
    for k in 1..=48 {
        step(&mut s, k);
    }
    ALLOCATIONS.store(0, Ordering::SeqCst);
    COUNTING.store(true, Ordering::SeqCst);
    for k in 49..=72 {
        step(&mut s, k);
    }
    COUNTING.store(false, Ordering::SeqCst);
    (ALLOCATIONS.load(Ordering::SeqCst), s.tracker.counters())
}

#[test]
fn steady_state_ticks_do_not_allocate() {
    let dir = tempfile::tempdir().unwrap();
    let rec = mug_recording(dir.path(), 0.25);
    for method in TrackingMethod::ALL {
        let config = method.configure(&TrackerConfig::default());
        let (n, _) = allocations_of_steady_ticks(&rec, config, 1, 0);
        assert_eq!(
            n, 0,
            "{method}: {n} heap allocations in 11 steady-state ticks"
        );
    }
    // Two objects stepped on two threads (the object thread is started once and woken every tick).
    let config = TrackerConfig {
        execution: ExecutionConfig {
            object_threads: 2,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let (n, _) = allocations_of_steady_ticks(&rec, config, 2, 0);
    assert_eq!(
        n, 0,
        "two objects on two threads: {n} heap allocations in 11 steady-state ticks"
    );
    // Depth frames 20 ms late, carried from their exposure (not tracked again): registered at the pose history's
    // estimate, aligned there and carried.
    let carrying = TrackerConfig {
        late_depth: LateDepthConfig {
            retrack_late_depth: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let (n, counters) = allocations_of_steady_ticks(&rec, carrying, 1, 20_000);
    assert!(counters.depth_frames_late >= 13, "{counters:?}");
    assert_eq!(
        n, 0,
        "late depth frames: {n} heap allocations in 11 steady-state ticks"
    );
    // Late frames tracked again from their exposure: states saved, events logged and wound back and forth.
    for deferred in [false, true] {
        let (n, counters) =
            allocations_of_retracking_ticks(&rec, deferred, TrackerConfig::default());
        assert!(counters.late_frames_retracked >= 17, "{counters:?}");
        // The first frame's exposure tick was the fixture's, before any state was saved.
        assert_eq!(counters.late_frames_not_retracked, 1, "{counters:?}");
        assert_eq!(
            n, 0,
            "late depth frames tracked again (deferred: {deferred}): {n} heap allocations in 24 steady-state ticks"
        );
    }
    // Steps between ticks, as the events of each period come, and planned again while tracking again from late
    // depth frames (every moving object gets the most steps here). In this test, not beside it: the allocation
    // counter counts every thread of the process, a test running in parallel included.
    let mut config = TrackerConfig::default();
    config.inner_steps.inner_step_px = 1e-6;
    let before = steady_tracker_of(rec.clone(), config.clone(), Box::new(CpuRenderer::new()), 1)
        .tracker
        .counters();
    for deferred in [false, true] {
        let (n, counters) = allocations_of_retracking_ticks(&rec, deferred, config.clone());
        assert!(
            counters.inner_steps >= before.inner_steps + 72,
            "{before:?} {counters:?}"
        );
        assert!(counters.late_frames_retracked >= 17, "{counters:?}");
        assert_eq!(
            n, 0,
            "steps between ticks (deferred: {deferred}): {n} heap allocations in 24 steady-state ticks"
        );
    }
}
