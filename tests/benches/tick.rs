//! One full tracker tick (reconstruction + refinement) at a 160x160 ROI on one core, after replaying a generated
//! mug shake: a plain 120 Hz tick (carried depth + events) and a depth-exposure tick (registration of the new
//! frame + refinement), with the CPU renderer on the tracker's thread alone (`cpu`), the CPU renderer rendering
//! ahead on a second thread as by default (`cpu_ahead`), and the wgpu renderer. The `render_in_*` benches time only the
//! renderer's calls inside the same ticks, so a tick's cost splits into rendering and everything else. The
//! `paced/*_at_120hz` benches run the same ticks one tick period apart, as a live stream does. The `cpu_of_tick_*`
//! benches report the CPU time of every thread of the process per back-to-back tick instead of wall time.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use eventtrack6d_tests::cpu_time::process_cpu_ns;
use eventtrack6d_tests::render_hook::HookedRenderer;
use eventtrack6d_tests::tick_fixture::{SteadyTracker, mug_recording, steady_tracker};
use scene::render::{CpuRenderer, RenderAhead, Renderer, RendererKind, create_renderer};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use tracker::track::DepthHandling;
use tracker::track::{ExecutionConfig, PoseTracker, TrackerConfig};

/// Adds the wall time from its creation to its drop to `spent_ns`: held by [`HookedRenderer`] around one render.
struct RenderTimer {
    start: Instant,
    spent_ns: Arc<AtomicU64>,
}

impl Drop for RenderTimer {
    fn drop(&mut self) {
        let ns = u64::try_from(self.start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.spent_ns.fetch_add(ns, Ordering::Relaxed);
    }
}

fn bench_tracker(c: &mut Criterion, label: &str, s: &mut SteadyTracker) {
    let mut out = Vec::with_capacity(4);
    let tick = s.last_tick;
    c.bench_function(&format!("tick_{label}_160"), |b| {
        b.iter(|| {
            out.clear();
            s.tracker.tick(&tick, &mut out);
            s.tracker.prepare_next_tick();
        })
    });
    let mut depth_tick = s.last_tick;
    depth_tick.depth_frame = Some(s.depth.index);
    c.bench_function(&format!("depth_tick_{label}_160"), |b| {
        b.iter(|| {
            s.tracker
                .push_depth(depth_tick.t_us, &mut s.depth, DepthHandling::Now);
            out.clear();
            s.tracker.tick(&depth_tick, &mut out);
            s.tracker.prepare_next_tick();
        })
    });
}

/// The tick period of the tracker's 120 Hz timeline.
const TICK_PERIOD: Duration = Duration::from_nanos(8_333_333);

/// The same ticks as [`bench_tracker`] at the pace of a live 120 Hz stream: each tick starts one tick period after
/// the previous one started, and only the tick call is timed, as the runtime's latency counts it (the runtime
/// publishes the poses, then calls `prepare_next_tick`, which is not timed here). Between ticks the tracker idles,
/// so a renderer that prefetches ([`tracker::track::ExecutionConfig::prefetch_renders`]) has rendered the next ROI
/// by then; caches also cool down between ticks, as in the runtime. The back-to-back benches time `tick` and
/// `prepare_next_tick` together: all of a tick's work, none of it hidden.
///
/// With `render_spent_ns` (the counter of a [`timed_tracker`]), each sample is the time spent in the renderer's
/// calls during those ticks instead (`render_in_` benches).
fn bench_paced(
    c: &mut Criterion,
    label: &str,
    s: &mut SteadyTracker,
    render_spent_ns: Option<&AtomicU64>,
) {
    let mut group = c.benchmark_group("paced");
    group
        .sampling_mode(criterion::SamplingMode::Flat)
        .sample_size(20)
        .warm_up_time(Duration::from_millis(50))
        .measurement_time(Duration::from_secs(4));
    let mut out = Vec::with_capacity(4);
    let tick = s.last_tick;
    let mut depth_tick = s.last_tick;
    depth_tick.depth_frame = Some(s.depth.index);
    for depth in [false, true] {
        let name = format!(
            "{}{}tick_{label}_160_at_120hz",
            if render_spent_ns.is_some() {
                "render_in_"
            } else {
                ""
            },
            if depth { "depth_" } else { "" }
        );
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                if let Some(r) = render_spent_ns {
                    r.store(0, Ordering::Relaxed);
                }
                let mut next = Instant::now();
                for _ in 0..iters {
                    next += TICK_PERIOD;
                    std::thread::sleep(next.saturating_duration_since(Instant::now()));
                    if depth {
                        s.tracker
                            .push_depth(depth_tick.t_us, &mut s.depth, DepthHandling::Now);
                    }
                    out.clear();
                    let start = Instant::now();
                    s.tracker
                        .tick(if depth { &depth_tick } else { &tick }, &mut out);
                    spent += start.elapsed();
                    // After the poses are out, as the runtime does: not part of the tick's latency.
                    s.tracker.prepare_next_tick();
                }
                match render_spent_ns {
                    Some(r) => Duration::from_nanos(r.load(Ordering::Relaxed)),
                    None => spent,
                }
            })
        });
    }
    group.finish();
}

/// The CPU time the same back-to-back ticks as [`bench_tracker`] cost, summed over every thread of the process
/// (the tracker's, and the renderer's helpers: the render-ahead thread, or lavapipe's rasteriser and queue
/// threads). On a machine with `n` cores a back-to-back tick cannot take less wall time than this divided by `n`.
fn bench_cpu_of_tick(c: &mut Criterion, label: &str, s: &mut SteadyTracker) {
    let mut out = Vec::with_capacity(4);
    let tick = s.last_tick;
    c.bench_function(&format!("cpu_of_tick_{label}_160"), |b| {
        b.iter_custom(|iters| {
            let start = process_cpu_ns();
            for _ in 0..iters {
                out.clear();
                s.tracker.tick(&tick, &mut out);
                s.tracker.prepare_next_tick();
            }
            Duration::from_nanos(process_cpu_ns().saturating_sub(start))
        })
    });
}

/// Times only the renderer's share of the same ticks as [`bench_tracker`]: each sample is the summed wall time of
/// the render calls made by `iters` ticks.
fn bench_render_share(c: &mut Criterion, label: &str, mut s: SteadyTracker, spent_ns: &AtomicU64) {
    let mut out = Vec::with_capacity(4);
    let tick = s.last_tick;
    c.bench_function(&format!("render_in_tick_{label}_160"), |b| {
        b.iter_custom(|iters| {
            spent_ns.store(0, Ordering::Relaxed);
            for _ in 0..iters {
                out.clear();
                s.tracker.tick(&tick, &mut out);
                s.tracker.prepare_next_tick();
            }
            Duration::from_nanos(spent_ns.load(Ordering::Relaxed))
        })
    });
    let mut depth_tick = s.last_tick;
    depth_tick.depth_frame = Some(s.depth.index);
    c.bench_function(&format!("render_in_depth_tick_{label}_160"), |b| {
        b.iter_custom(|iters| {
            spent_ns.store(0, Ordering::Relaxed);
            for _ in 0..iters {
                s.tracker
                    .push_depth(depth_tick.t_us, &mut s.depth, DepthHandling::Now);
                out.clear();
                s.tracker.tick(&depth_tick, &mut out);
                s.tracker.prepare_next_tick();
            }
            Duration::from_nanos(spent_ns.load(Ordering::Relaxed))
        })
    });
}

/// A steady tracker on `rec` with `config` whose renderer `inner` adds its render time to the returned counter
/// (the time the tracker's thread spends in it: for a renderer that renders ahead, the wait and the swap).
fn timed_tracker(
    rec: &drivers::recording::Recording,
    inner: Box<dyn Renderer + Send>,
    config: TrackerConfig,
) -> (SteadyTracker, Arc<AtomicU64>) {
    let spent_ns = Arc::new(AtomicU64::new(0));
    let counter = Arc::clone(&spent_ns);
    let timed = HookedRenderer::new(inner, move || RenderTimer {
        start: Instant::now(),
        spent_ns: Arc::clone(&counter),
    });
    let s = steady_tracker(rec.clone(), config, Box::new(timed));
    (s, spent_ns)
}

fn ticks(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("eventtrack6d-tick-bench");
    let rec = mug_recording(&dir, 0.5);
    // `cpu`: the CPU renderer on the tracker's thread alone (one core, `prefetch_renders = false`).
    let one_thread = TrackerConfig {
        execution: ExecutionConfig {
            prefetch_renders: false,
            ..Default::default()
        },
        ..TrackerConfig::default()
    };
    let cpu: Box<dyn Renderer + Send> = Box::new(CpuRenderer::new());
    let mut s = steady_tracker(rec.clone(), one_thread.clone(), cpu);
    bench_tracker(c, "cpu", &mut s);
    bench_cpu_of_tick(c, "cpu", &mut s);
    bench_paced(c, "cpu", &mut s, None);
    let (mut s, spent) = timed_tracker(&rec, Box::new(CpuRenderer::new()), one_thread.clone());
    bench_paced(c, "cpu", &mut s, Some(&spent));
    bench_render_share(c, "cpu", s, &spent);
    // `cpu_ahead`: the defaults, with which the tracker renders each next ROI ahead on the `render-ahead` thread.
    let mut s = steady_tracker(
        rec.clone(),
        TrackerConfig::default(),
        Box::new(CpuRenderer::new()),
    );
    bench_tracker(c, "cpu_ahead", &mut s);
    bench_cpu_of_tick(c, "cpu_ahead", &mut s);
    bench_paced(c, "cpu_ahead", &mut s, None);
    let counts = s.tracker.counters();
    eprintln!(
        "cpu_ahead ticks: {} renders ahead, {} used",
        counts.renders_prefetched, counts.prefetched_renders_used
    );
    // The timer wraps the renderer that renders ahead, so it times the tick thread's wait and swap.
    let ahead = RenderAhead::new(Box::new(CpuRenderer::new()));
    let (mut s, spent) = timed_tracker(&rec, Box::new(ahead), TrackerConfig::default());
    bench_paced(c, "cpu_ahead", &mut s, Some(&spent));
    // `cpu_simplified`: as `cpu`, rendering the mug's mesh simplified (1,896 triangles: rendered as loaded by default,
    // `render_mesh_simplify_above`).
    let mut simplified = one_thread;
    simplified.execution.render_mesh_simplify_above = 0;
    let mut s = steady_tracker(rec.clone(), simplified, Box::new(CpuRenderer::new()));
    bench_tracker(c, "cpu_simplified", &mut s);
    match create_renderer(RendererKind::Gpu) {
        Ok(gpu) => {
            eprintln!("gpu renderer: {}", gpu.device());
            let mut s = steady_tracker(rec.clone(), TrackerConfig::default(), gpu);
            bench_tracker(c, "gpu", &mut s);
            bench_cpu_of_tick(c, "gpu", &mut s);
            bench_paced(c, "gpu", &mut s, None);
            let counts = s.tracker.counters();
            eprintln!(
                "gpu ticks: {} renders prefetched, {} used",
                counts.renders_prefetched, counts.prefetched_renders_used
            );
            match create_renderer(RendererKind::Gpu) {
                Ok(gpu) => {
                    let (mut s, spent) = timed_tracker(&rec, gpu, TrackerConfig::default());
                    bench_paced(c, "gpu", &mut s, Some(&spent));
                    bench_render_share(c, "gpu", s, &spent);
                }
                Err(e) => eprintln!("gpu render-share bench skipped: {e}"),
            }
            // `gpu_simplified`: the mug's mesh simplified (`render_mesh_simplify_above`).
            let simplified = TrackerConfig {
                execution: ExecutionConfig {
                    render_mesh_simplify_above: 0,
                    ..Default::default()
                },
                ..TrackerConfig::default()
            };
            match (
                create_renderer(RendererKind::Gpu),
                create_renderer(RendererKind::Gpu),
            ) {
                (Ok(gpu), Ok(timed_gpu)) => {
                    let mut s = steady_tracker(rec.clone(), simplified.clone(), gpu);
                    bench_tracker(c, "gpu_simplified", &mut s);
                    drop(s);
                    let (s, spent) = timed_tracker(&rec, timed_gpu, simplified);
                    bench_render_share(c, "gpu_simplified", s, &spent);
                }
                (Err(e), _) | (_, Err(e)) => eprintln!("gpu simplified-mesh benches skipped: {e}"),
            }
        }
        Err(e) => eprintln!("gpu tick bench skipped: {e}"),
    }
}

criterion_group!(benches, ticks);
criterion_main!(benches);
