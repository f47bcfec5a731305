//! The real Prophesee recordings in `../shared/data/samples/` decode cleanly.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::{EventBuffer, EventCounter, Geometry};
use drivers::formats::any::EventFormat;
use drivers::raw::RawReader;
use std::path::PathBuf;

fn sample(name: &str) -> PathBuf {
    let shared = std::env::var_os("EVENTTRACK6D_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared"));
    let path = shared.join("data/samples").join(name);
    assert!(
        path.is_file(),
        "this test needs the shared sample recordings: {} is missing. Clone the repository with `../shared` \
         beside it (or set EVENTTRACK6D_SHARED to the shared folder).",
        path.display()
    );
    path
}

#[test]
fn evt3_gen41_sample_decodes_with_zero_anomalies() {
    let mut r = RawReader::open(&sample("evk3_gen41_evt3.raw")).unwrap();
    assert_eq!(r.header().format, EventFormat::Evt3);
    assert_eq!(r.header().geometry, Some(Geometry::new(1280, 720)));
    let mut c = EventCounter::new();
    r.read_all(&mut c).unwrap();
    assert_eq!(r.anomalies().total(), 0, "{:?}", r.anomalies());
    assert_eq!(c.cd_events(), 219_596);
    let span = c.t_last_us().unwrap() - c.t_first_us().unwrap();
    assert!(
        (8_000..9_500).contains(&span),
        "duration {span} us, expected about 8.8 ms"
    );
}

#[test]
fn evt3_sample_decodes_identically_in_any_chunking() {
    let path = sample("evk3_gen41_evt3.raw");
    let mut whole = EventBuffer::new();
    RawReader::open(&path)
        .unwrap()
        .read_all(&mut whole)
        .unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let offset = RawReader::open(&path).unwrap().header().data_offset as usize;
    for chunk in [1usize, 3, 4095, 128 * 1024 + 7] {
        let mut d = drivers::formats::evt3::Evt3Decoder::new(Some(Geometry::new(1280, 720)));
        let mut b = EventBuffer::new();
        for c in bytes[offset..].chunks(chunk) {
            d.decode(c, &mut b);
        }
        d.finish();
        assert_eq!(b, whole, "chunk size {chunk}");
    }
}

#[test]
fn evt2_gen3_sample_decodes_with_zero_anomalies() {
    let mut r = RawReader::open(&sample("gen3_evt2.raw")).unwrap();
    assert_eq!(r.header().format, EventFormat::Evt2);
    assert_eq!(r.header().geometry, Some(Geometry::new(640, 480)));
    let mut c = EventCounter::new();
    r.read_all(&mut c).unwrap();
    assert_eq!(r.anomalies().total(), 0, "{:?}", r.anomalies());
    let span = c.t_last_us().unwrap() - c.t_first_us().unwrap();
    assert!(
        (90_000..100_000).contains(&span),
        "duration {span} us, expected about 96 ms"
    );
    assert!(c.cd_events() > 400_000, "{} events", c.cd_events());
}
