//! Property tests: random events and triggers -> encode -> decode in random chunkings -> identical.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
use drivers::formats::any::{AnyDecoder, AnyEncoder, EventFormat};
use drivers::formats::evt21::WordOrder;
use proptest::prelude::*;

/// Runs of events on one row at one time (as a moving edge produces), separated by time gaps that
/// include multi-second jumps so that time-base wraps are exercised.
fn cd_stream(max_gap: i64) -> impl Strategy<Value = Vec<CdEvent>> {
    let group = (
        prop_oneof![4 => Just(0i64), 4 => 1i64..50, 2 => 50i64..5_000, 1 => 0..max_gap],
        0u16..2048,
        any::<bool>(),
        0u16..2000,
        proptest::collection::vec(1u16..4, 0..20),
    );
    proptest::collection::vec(group, 0..200).prop_map(|groups| {
        let mut t = 0i64;
        let mut out = Vec::new();
        for (gap, y, polarity, x0, steps) in groups {
            t += gap;
            let mut x = x0;
            out.push(CdEvent {
                t_us: t,
                x,
                y,
                polarity,
            });
            for s in steps {
                x += s;
                if x >= 2048 {
                    break;
                }
                out.push(CdEvent {
                    t_us: t,
                    x,
                    y,
                    polarity,
                });
            }
        }
        out
    })
}

fn trigger_stream(max_channel: u8, max_gap: i64) -> impl Strategy<Value = Vec<TriggerEdge>> {
    proptest::collection::vec((0..max_gap, 0..=max_channel, any::<bool>()), 0..50).prop_map(|v| {
        let mut t = 0;
        v.into_iter()
            .map(|(gap, channel, rising)| {
                t += gap;
                TriggerEdge {
                    t_us: t,
                    channel,
                    rising,
                }
            })
            .collect()
    })
}

fn roundtrip(
    format: EventFormat,
    cd: &[CdEvent],
    triggers: &[TriggerEdge],
    cuts: &[usize],
) -> EventBuffer {
    let mut bytes = Vec::new();
    let mut enc = AnyEncoder::new(format);
    // Encode in two batches to exercise encoder state carried across calls.
    let half_t = cd.get(cd.len() / 2).map_or(0, |e| e.t_us);
    let (c1, c2) = cd.split_at(cd.partition_point(|e| e.t_us < half_t));
    let (t1, t2) = triggers.split_at(triggers.partition_point(|e| e.t_us < half_t));
    enc.encode(c1, t1, &mut bytes).unwrap();
    enc.encode(c2, t2, &mut bytes).unwrap();
    let mut dec = AnyDecoder::new(format, None);
    let mut out = EventBuffer::new();
    let mut rest = &bytes[..];
    for &c in cuts {
        let c = c.min(rest.len());
        dec.decode(&rest[..c], &mut out);
        rest = &rest[c..];
    }
    dec.decode(rest, &mut out);
    dec.finish();
    assert_eq!(dec.anomalies().total(), 0, "{:?}", dec.anomalies());
    out
}

fn cuts() -> impl Strategy<Value = Vec<usize>> {
    proptest::collection::vec(prop_oneof![0usize..3, 0usize..17, 0usize..4096], 0..40)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn evt3_roundtrip(cd in cd_stream(40_000_000), tr in trigger_stream(15, 40_000_000), cuts in cuts()) {
        let out = roundtrip(EventFormat::Evt3, &cd, &tr, &cuts);
        prop_assert_eq!(out.cd, cd);
        prop_assert_eq!(out.triggers, tr);
    }

    #[test]
    fn evt2_roundtrip(cd in cd_stream(20_000_000_000), tr in trigger_stream(31, 20_000_000_000), cuts in cuts()) {
        let out = roundtrip(EventFormat::Evt2, &cd, &tr, &cuts);
        prop_assert_eq!(out.cd, cd);
        prop_assert_eq!(out.triggers, tr);
    }

    #[test]
    fn evt21_legacy_roundtrip(cd in cd_stream(20_000_000_000), tr in trigger_stream(31, 20_000_000_000), cuts in cuts()) {
        let out = roundtrip(EventFormat::Evt21(WordOrder::Legacy), &cd, &tr, &cuts);
        prop_assert_eq!(out.cd, cd);
        prop_assert_eq!(out.triggers, tr);
    }

    #[test]
    fn evt21_little_roundtrip(cd in cd_stream(20_000_000_000), tr in trigger_stream(31, 1_000_000), cuts in cuts()) {
        let out = roundtrip(EventFormat::Evt21(WordOrder::Little), &cd, &tr, &cuts);
        prop_assert_eq!(out.cd, cd);
        prop_assert_eq!(out.triggers, tr);
    }

    /// Arbitrary bytes never panic any decoder, in any chunking, and decoding is chunking-independent.
    #[test]
    fn arbitrary_bytes_decode_independently_of_chunking(bytes in proptest::collection::vec(any::<u8>(), 0..2048), cuts in cuts()) {
        for format in [EventFormat::Evt3, EventFormat::Evt2, EventFormat::Evt21(WordOrder::Legacy)] {
            let mut whole = AnyDecoder::new(format, Some(drivers::event::Geometry::new(1280, 720)));
            let mut a = EventBuffer::new();
            whole.decode(&bytes, &mut a);
            whole.finish();
            let mut pieces = AnyDecoder::new(format, Some(drivers::event::Geometry::new(1280, 720)));
            let mut b = EventBuffer::new();
            let mut rest = &bytes[..];
            for &c in &cuts {
                let c = c.min(rest.len());
                pieces.decode(&rest[..c], &mut b);
                rest = &rest[c..];
            }
            pieces.decode(rest, &mut b);
            pieces.finish();
            prop_assert_eq!(&a, &b);
            prop_assert_eq!(whole.anomalies(), pieces.anomalies());
        }
    }
}

/// Whether `sub` appears in `all` in order (not necessarily contiguously).
fn is_subsequence(sub: &[CdEvent], all: &[CdEvent]) -> bool {
    let mut it = all.iter();
    sub.iter().all(|e| it.any(|a| a == e))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Bytes lost in transit (a dropped USB transfer): after `resynchronise` the decoder delivers only events
    /// of the original stream, in order, at their original times.
    #[test]
    fn evt3_after_a_gap_resynchronises_to_a_subsequence(
        cd in cd_stream(100_000),
        gap_at in 0usize..4096,
        gap_len in 1usize..200,
        cuts in cuts(),
    ) {
        use drivers::formats::evt3::{Evt3Decoder, Evt3Encoder};
        let mut bytes = Vec::new();
        Evt3Encoder::new().encode(&cd, &[], &mut bytes).unwrap();
        let at = gap_at.min(bytes.len());
        // A transfer carries whole 16-bit words, so what follows a gap starts on a word boundary.
        let end = ((at + gap_len) & !1).max(at).min(bytes.len());
        let mut dec = Evt3Decoder::new(None);
        let mut out = EventBuffer::new();
        let mut rest = &bytes[..at];
        for &c in &cuts {
            let c = c.min(rest.len());
            dec.decode(&rest[..c], &mut out);
            rest = &rest[c..];
        }
        dec.decode(rest, &mut out);
        // Only a real gap calls for resynchronising, which skips to the next TIME_HIGH and row.
        if end > at {
            dec.resynchronise();
        }
        dec.decode(&bytes[end..], &mut out);
        dec.finish();
        prop_assert!(is_subsequence(&out.cd, &cd), "decoded events that were never sent");
        if end == at {
            prop_assert_eq!(out.cd.len(), cd.len());
        }
    }
}
