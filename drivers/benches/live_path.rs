//! The live camera's host-side data path without USB: 128 KiB transfers pushed by a producer thread (as libusb's
//! completion callback does) into the dropping `TransferRing`, taken and decoded by the consumer (as the live
//! source does). Throughput in CD events per second over a dense synthetic EVT 3.0 stream; the ring's memory is
//! its slots times the transfer size (32 MiB at the defaults).
//!
//! Run: `cargo bench -p eventtrack6d-drivers --bench live_path`.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drivers::event::{CdEvent, EventCounter};
use drivers::formats::evt3::{Evt3Decoder, Evt3Encoder};
use drivers::transfer_ring::TransferRing;
use std::sync::Arc;
use std::time::Duration;

const TRANSFER: usize = 128 * 1024;

/// Rows of half-filled pixels, 50 us apart: about 20 Mev/s of stream time, the density of a large moving edge.
fn stream() -> (Vec<u8>, u64) {
    let mut events = Vec::new();
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    for row in 0..20_000i64 {
        let y = (row % 720) as u16;
        for x in 0..1280u16 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            if s.is_multiple_of(3) {
                events.push(CdEvent {
                    t_us: row * 50,
                    x,
                    y,
                    polarity: s & 8 == 0,
                });
            }
        }
    }
    let mut bytes = Vec::new();
    Evt3Encoder::new().encode(&events, &[], &mut bytes).unwrap();
    (bytes, events.len() as u64)
}

fn ring_and_decoder(c: &mut Criterion) {
    let (bytes, events) = stream();
    let bytes = Arc::new(bytes);
    let mut g = c.benchmark_group("live_path");
    g.throughput(Throughput::Elements(events));
    g.sample_size(10);
    g.bench_function("ring_decode_128k_transfers", |b| {
        b.iter(|| {
            // 256 slots: the default 32 MiB ring. The producer waits when it is full instead of dropping, so
            // the figure is what the consumer sustains.
            let ring = Arc::new(TransferRing::new(256, TRANSFER));
            let producer = {
                let (ring, bytes) = (ring.clone(), bytes.clone());
                std::thread::spawn(move || {
                    for chunk in bytes.chunks(TRANSFER) {
                        while !ring.push(chunk) {
                            std::thread::yield_now();
                        }
                    }
                    ring.close();
                })
            };
            let mut decoder = Evt3Decoder::new(None);
            let mut counter = EventCounter::new();
            while let Some(chunk) = ring.pop(Duration::from_secs(1)) {
                decoder.decode(&chunk.bytes, &mut counter);
                ring.recycle(chunk);
            }
            producer.join().unwrap();
            assert_eq!(counter.positive + counter.negative, events);
        });
    });
    g.finish();
}

criterion_group!(benches, ring_and_decoder);
criterion_main!(benches);
