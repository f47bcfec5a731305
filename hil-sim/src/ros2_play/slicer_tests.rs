use super::*;
use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
use drivers::formats::evt3::{Evt3Decoder, Evt3Encoder};
use proptest::prelude::*;

fn slice_all(bytes: &[u8], chunk: usize, slice_us: i64) -> Vec<Packet> {
    let mut slicer = Slicer::new(slice_us);
    let mut packets = Vec::new();
    for c in bytes.chunks(chunk.max(1)) {
        slicer
            .feed(c, &mut |p| {
                packets.push(p);
                Ok::<(), ()>(())
            })
            .unwrap();
    }
    packets.extend(slicer.finish());
    packets
}

fn word(kind: u16, payload: u16) -> [u8; 2] {
    ((kind << 12) | (payload & 0x0FFF)).to_le_bytes()
}

/// An EVT 3.0 stream with CD events every `step_us` and a trigger pulse every 1000 us, from `t0_us` for `len_us`.
fn encoded_stream(t0_us: i64, len_us: i64, step_us: i64) -> Vec<u8> {
    let mut cd = Vec::new();
    let mut t = t0_us;
    while t < t0_us + len_us {
        let k = (t / step_us) as u16;
        cd.push(CdEvent {
            t_us: t,
            x: k % 1280,
            y: (k / 7) % 720,
            polarity: k.is_multiple_of(3),
        });
        t += step_us;
    }
    let triggers: Vec<TriggerEdge> = (0..len_us / 1000)
        .flat_map(|i| {
            let rise = t0_us + i * 1000 + 3;
            [(rise, true), (rise + 100, false)]
        })
        .map(|(t_us, rising)| TriggerEdge {
            t_us,
            channel: 0,
            rising,
        })
        .collect();
    let mut out = Vec::new();
    Evt3Encoder::new().encode(&cd, &triggers, &mut out).unwrap();
    out
}

#[test]
fn cuts_before_the_time_word_that_reaches_the_window_end() {
    let mut s = Vec::new();
    s.extend(word(TIME_HIGH, 1)); // t = 4096
    s.extend(word(ADDR_Y, 5));
    s.extend(word(TIME_LOW, 10)); // 4106: first event's time
    s.extend(word(ADDR_X, 7));
    s.extend(word(TIME_LOW, 900)); // 4996 < 4096 + 1000
    s.extend(word(ADDR_X, 8));
    s.extend(word(TIME_LOW, 1000)); // 5096 = end: cut before
    s.extend(word(EXT_TRIGGER, 1));
    s.extend(word(TIME_LOW, 2500)); // 6596: cut before
    let packets = slice_all(&s, 3, 1000);
    assert_eq!(packets.len(), 3);
    assert_eq!(packets[0].bytes, s[..12]);
    assert_eq!(packets[0].start_us, Some(4096));
    assert_eq!(packets[0].first_event_us, Some(4106));
    assert_eq!(packets[0].end_us, Some(5096));
    assert_eq!(packets[1].bytes, s[12..16]);
    assert_eq!(packets[1].start_us, Some(5096));
    assert_eq!(packets[1].stamp_us(), 5096);
    assert_eq!(packets[1].end_us, Some(6596));
    assert_eq!(packets[2].bytes, s[16..]);
    assert_eq!(packets[2].first_event_us, None);
    assert_eq!(packets[2].stamp_us(), 6596);
}

#[test]
fn words_before_the_first_time_high_have_no_time_and_no_event() {
    let mut s = Vec::new();
    s.extend(word(ADDR_X, 1));
    s.extend(word(TIME_LOW, 5));
    s.extend(word(EXT_TRIGGER, 1));
    s.extend(word(TIME_HIGH, 2)); // 8192
    s.extend(word(TIME_LOW, 5));
    s.extend(word(EXT_TRIGGER, 1));
    let packets = slice_all(&s, 64, 1000);
    assert_eq!(packets.len(), 1);
    assert_eq!(packets[0].start_us, Some(8192));
    assert_eq!(packets[0].first_event_us, Some(8197));
}

#[test]
fn a_packet_of_time_words_only_is_not_cut_and_its_window_opens_at_its_first_other_word() {
    let mut s = Vec::new();
    s.extend(word(TIME_HIGH, 1)); // 4096
    s.extend(word(TIME_LOW, 3000)); // 7096: the window moves on, no cut
    s.extend(word(ADDR_Y, 1));
    s.extend(word(ADDR_X, 1));
    s.extend(word(TIME_LOW, 4000)); // 8096: cut
    s.extend(word(TIME_HIGH, 3)); // 12288: the next window moves on
    s.extend(word(EXT_TRIGGER, 0));
    let packets = slice_all(&s, 5, 1000);
    assert_eq!(packets.len(), 2);
    assert_eq!(packets[0].bytes, s[..8]);
    assert_eq!(packets[0].start_us, Some(7096));
    assert_eq!(packets[0].end_us, Some(8096));
    assert_eq!(packets[1].start_us, Some(12288));
    assert_eq!(packets[1].stamp_us(), 12288);
}

#[test]
fn a_trailing_odd_byte_ends_the_last_packet() {
    let mut s = Vec::new();
    s.extend(word(TIME_HIGH, 1));
    s.extend(word(EXT_TRIGGER, 1));
    s.push(0xAB);
    let packets = slice_all(&s, 1, 1000);
    assert_eq!(packets.len(), 1);
    assert_eq!(packets[0].bytes, s);
}

/// Slicing an encoded stream that crosses the 24-bit wrap: each packet's stamp is the time the drivers' decoder
/// gives its first record, every record of a packet lies within its window, and the windows follow each other.
#[test]
fn stamps_and_windows_agree_with_the_drivers_decoder_across_the_wrap() {
    let t0 = (1 << 24) - 30_000;
    let stream = encoded_stream(t0, 60_000, 7);
    let packets = slice_all(&stream, 4093, 1000);
    assert!(packets.len() >= 55, "{} packets", packets.len());
    let mut decoder = Evt3Decoder::new(None);
    let mut previous_end = None;
    for (i, p) in packets.iter().enumerate() {
        let mut b = EventBuffer::new();
        decoder.decode(&p.bytes, &mut b);
        let mut times: Vec<i64> = b.cd.iter().map(|e| e.t_us).collect();
        times.extend(b.triggers.iter().map(|e| e.t_us));
        let first = b.cd.first().map(|e| e.t_us).into_iter();
        let first = first
            .chain(b.triggers.first().map(|e| e.t_us))
            .min()
            .unwrap();
        assert_eq!(p.stamp_us(), first, "packet {i}");
        let start = p.start_us.unwrap();
        assert!(
            times.iter().all(|&t| t >= start && t < start + 1000),
            "packet {i}: window {start}, times {:?}..{:?}",
            times.iter().min(),
            times.iter().max()
        );
        if let Some(prev) = previous_end {
            assert!(start >= prev, "packet {i} starts before the previous ended");
            assert!(
                start < prev + 4096,
                "packet {i} starts long after the previous ended"
            );
        }
        previous_end = p.end_us;
    }
    assert!(packets.last().unwrap().end_us.unwrap() > 1 << 24);
    assert_eq!(decoder.anomalies().total(), 0);
}

fn any_word() -> impl Strategy<Value = u16> {
    prop_oneof![
        3 => (0u16..0x1000).prop_map(|p| (TIME_LOW << 12) | p),
        1 => (0u16..0x1000).prop_map(|p| (TIME_HIGH << 12) | p),
        6 => any::<u16>(),
    ]
}

proptest! {
    #[test]
    fn slices_concatenate_to_the_input_and_cut_at_word_boundaries(
        words in prop::collection::vec(any_word(), 0..600),
        odd in prop::option::of(any::<u8>()),
        chunk in 1usize..97,
        slice_us in 1i64..5000,
    ) {
        let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        bytes.extend(odd);
        let packets = slice_all(&bytes, chunk, slice_us);
        let joined: Vec<u8> = packets.iter().flat_map(|p| p.bytes.iter().copied()).collect();
        prop_assert_eq!(&joined, &bytes);
        let mut offset = 0;
        for (i, p) in packets.iter().enumerate() {
            prop_assert!(!p.bytes.is_empty());
            prop_assert_eq!(offset % 2, 0, "packet {} starts at an odd offset", i);
            offset += p.bytes.len();
            if i > 0 {
                // Every cut is right before a time word.
                let kind = u16::from_le_bytes([p.bytes[0], p.bytes.get(1).copied().unwrap_or(0)]) >> 12;
                prop_assert!(kind == TIME_HIGH || kind == TIME_LOW);
            }
        }
    }
}
