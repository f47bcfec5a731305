// Shared by the decoder targets: decoding must not panic and must not depend on how the stream is chunked.
use drivers::event::{EventBuffer, Geometry};
use drivers::formats::any::{AnyDecoder, EventFormat};

pub fn check(format: EventFormat, data: &[u8]) {
    let Some((&cut_seed, bytes)) = data.split_first() else { return };
    let g = Some(Geometry::new(1280, 720));
    let mut whole = AnyDecoder::new(format, g);
    let mut a = EventBuffer::new();
    whole.decode(bytes, &mut a);
    whole.finish();
    let mut split = AnyDecoder::new(format, g);
    let mut b = EventBuffer::new();
    let step = usize::from(cut_seed % 13) + 1;
    for chunk in bytes.chunks(step) {
        split.decode(chunk, &mut b);
    }
    split.finish();
    assert_eq!(a, b, "chunking changed the decoded records");
    assert_eq!(whole.anomalies(), split.anomalies(), "chunking changed the anomaly counts");
    for e in &a.cd {
        assert!(e.x < 1280 && e.y < 720, "event outside the geometry escaped: {e:?}");
    }
}
