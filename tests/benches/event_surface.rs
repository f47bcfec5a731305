//! Integrating a recorded event stream into the tracker's full-sensor [`EventSurface`]: latest time and log
//! intensity per pixel, and latest time only (what the tracker keeps at its defaults, where nothing reads `I_t`).
//! The real-time runtime does this for every event on the tracker thread, outside the timed tick of the `tick`
//! bench; the input is the same generated mug shake (`tests/src/tick_fixture.rs`).

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use drivers::event::EventBuffer;
use eventtrack6d_tests::tick_fixture::mug_recording;
use tracker::recon::{EventSurface, IntensityFilterConfig};

fn integrate(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("eventtrack6d-tick-bench");
    let rec = mug_recording(&dir, 0.5);
    let mut reader = rec.events().expect("fixture events");
    let mut buffer = EventBuffer::default();
    while reader.read_chunk(&mut buffer).expect("fixture decodes") {}
    let events = buffer.cd;
    let cam = rec.rig.event_camera;
    let span_s = match (events.first(), events.last()) {
        (Some(a), Some(b)) => (b.t_us - a.t_us) as f64 * 1e-6,
        _ => 0.0,
    };
    eprintln!("{} events over {span_s:.3} s", events.len());
    let fresh = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    let mut group = c.benchmark_group("event_surface");
    group.sample_size(20);
    group.throughput(Throughput::Elements(events.len() as u64));
    group.bench_function("integrate_mug_shake_0_5s", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |surface| surface.integrate(&events),
            BatchSize::LargeInput,
        )
    });
    let times_only = EventSurface::latest_times_only(cam.width, cam.height);
    group.bench_function("integrate_times_only_mug_shake_0_5s", |b| {
        b.iter_batched_ref(
            || times_only.clone(),
            |surface| surface.integrate(&events),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, integrate);
criterion_main!(benches);
