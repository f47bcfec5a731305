//! Decoding throughput: the real EVT3 sample and a dense synthetic 1280x720 stream.
//!
//! Run: `cargo bench -p eventtrack6d-drivers --bench decode`. Throughput is reported in CD events per second.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drivers::event::{CdEvent, EventBuffer, EventCounter, Geometry};
use drivers::formats::any::{AnyDecoder, AnyEncoder, EventFormat};
use drivers::formats::evt21::WordOrder;
use drivers::raw::RawHeader;
use std::hint::black_box;
use std::io::Cursor;
use std::path::PathBuf;

fn real_sample() -> Option<Vec<u8>> {
    let shared = std::env::var_os("EVENTTRACK6D_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared"));
    let bytes = std::fs::read(shared.join("data/samples/evk3_gen41_evt3.raw")).ok()?;
    let header = RawHeader::read(&mut Cursor::new(&bytes)).ok()?;
    Some(bytes[header.data_offset as usize..].to_vec())
}

/// 16 full-sensor sweeps: every row carries a pseudo-random half of its pixels at one timestamp, the way a
/// large moving edge or a flicker fills the sensor.
fn dense_events() -> Vec<CdEvent> {
    let mut events = Vec::new();
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    for sweep in 0..16i64 {
        for y in 0..720u16 {
            let t = sweep * 1000 + i64::from(y);
            for x in 0..1280u16 {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                if s & 1 == 1 {
                    events.push(CdEvent {
                        t_us: t,
                        x,
                        y,
                        polarity: sweep % 2 == 0,
                    });
                }
            }
        }
    }
    events
}

fn encode(format: EventFormat, events: &[CdEvent]) -> Vec<u8> {
    let mut out = Vec::new();
    AnyEncoder::new(format)
        .encode(events, &[], &mut out)
        .expect("synthetic events are encodable");
    out
}

fn bench_stream(c: &mut Criterion, name: &str, format: EventFormat, bytes: &[u8]) {
    let g = Geometry::new(1280, 720);
    let mut count = EventCounter::new();
    let mut d = AnyDecoder::new(format, Some(g));
    d.decode(bytes, &mut count);
    let n = count.cd_events();
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(n));
    group.bench_function("count", |b| {
        b.iter(|| {
            let mut d = AnyDecoder::new(format, Some(g));
            let mut sink = EventCounter::new();
            for chunk in bytes.chunks(128 * 1024) {
                d.decode(black_box(chunk), &mut sink);
            }
            black_box(sink.cd_events())
        })
    });
    let mut buf = EventBuffer::new();
    buf.cd.reserve(n as usize);
    group.bench_function("materialise", |b| {
        b.iter(|| {
            buf.clear();
            let mut d = AnyDecoder::new(format, Some(g));
            for chunk in bytes.chunks(128 * 1024) {
                d.decode(black_box(chunk), &mut buf);
            }
            black_box(buf.cd.len())
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    if let Some(bytes) = real_sample() {
        bench_stream(c, "evt3_real_gen41_sample", EventFormat::Evt3, &bytes);
    } else {
        eprintln!(
            "skipping the real-sample benchmark: ../shared/data/samples/evk3_gen41_evt3.raw not found"
        );
    }
    let dense = dense_events();
    bench_stream(
        c,
        "evt3_dense_1280x720",
        EventFormat::Evt3,
        &encode(EventFormat::Evt3, &dense),
    );
    bench_stream(
        c,
        "evt2_dense_1280x720",
        EventFormat::Evt2,
        &encode(EventFormat::Evt2, &dense),
    );
    let legacy = EventFormat::Evt21(WordOrder::Legacy);
    bench_stream(c, "evt21_dense_1280x720", legacy, &encode(legacy, &dense));
}

criterion_group! {
    name = decode;
    config = Criterion::default().sample_size(30);
    targets = benches
}
criterion_main!(decode);
