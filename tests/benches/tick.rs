//! One full tracker tick (reconstruction + refinement) at a 160x160 ROI on one core, after replaying a generated
//! mug shake: a plain 120 Hz tick (carried depth + events) and a depth-exposure tick (registration of the new
//! frame + refinement), with the CPU renderer and the wgpu renderer.

use criterion::{Criterion, criterion_group, criterion_main};
use eventtrack6d_tests::tick_fixture::{SteadyTracker, mug_recording, steady_tracker};
use tracker::render::{CpuRenderer, Renderer, RendererKind, create_renderer};
use tracker::track::{PoseTracker, TrackerConfig};

fn bench_tracker(c: &mut Criterion, label: &str, mut s: SteadyTracker) {
    let mut out = Vec::with_capacity(4);
    let tick = s.last_tick;
    c.bench_function(&format!("tick_{label}_160"), |b| {
        b.iter(|| {
            out.clear();
            s.tracker.tick(&tick, &mut out);
        })
    });
    let mut depth_tick = s.last_tick;
    depth_tick.depth_frame = Some(s.depth.index);
    c.bench_function(&format!("depth_tick_{label}_160"), |b| {
        b.iter(|| {
            s.tracker.push_depth(depth_tick.t_us, &s.depth);
            out.clear();
            s.tracker.tick(&depth_tick, &mut out);
        })
    });
}

fn ticks(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("eventtrack6d-tick-bench");
    let rec = mug_recording(&dir, 0.5);
    let cpu: Box<dyn Renderer + Send> = Box::new(CpuRenderer::new());
    bench_tracker(
        c,
        "cpu",
        steady_tracker(rec.clone(), TrackerConfig::default(), cpu),
    );
    match create_renderer(RendererKind::Gpu) {
        Ok(gpu) => bench_tracker(c, "gpu", steady_tracker(rec, TrackerConfig::default(), gpu)),
        Err(e) => eprintln!("gpu tick bench skipped: {e}"),
    }
}

criterion_group!(benches, ticks);
criterion_main!(benches);
