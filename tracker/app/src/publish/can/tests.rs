//! Tests of the CAN layout, sinks and configuration (golden vectors, round trips, robustness, queue policy).

use super::candump::{self, CandumpClock, CandumpSink};
use super::layout::*;
use super::memory::MemorySink;
use super::socket::{FrameTransport, SocketCanSink, TransportOpener};
use super::{CanConfig, CanError};
use crate::publish::{PoseSink, TickPoses};
use drivers::timeline::Tick;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use proptest::prelude::*;
use std::f64::consts::FRAC_1_SQRT_2;
use std::io;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracker::track::{PoseEstimate, TrackingState};

/// Bitwise CRC-8/AUTOSAR straight from its definition (independent of the table-driven implementation).
fn crc8_reference(bytes: &[u8]) -> u8 {
    let mut c: u8 = 0xFF;
    for &b in bytes {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 {
                (c << 1) ^ 0x2F
            } else {
                c << 1
            };
        }
    }
    c ^ 0xFF
}

/// The golden pose: object 1, tick 0x1234, t = 5.000123 s, p = (0.12345, -0.5, 1.25) m, 90 deg about z,
/// quality 0.8, degraded.
fn golden_estimate() -> PoseEstimate {
    let rot =
        UnitQuaternion::new_unchecked(Quaternion::new(FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2));
    PoseEstimate {
        object: 1,
        t_us: 5_000_123,
        pose: Isometry3::from_parts(Translation3::new(0.12345, -0.5, 1.25), rot),
        quality: 0.8,
        state: TrackingState::Degraded,
    }
}

fn tick(index: u64) -> Tick {
    Tick {
        index,
        t_us: 5_000_000 + index as i64 * 8333,
        depth_frame: None,
        synthesized: false,
    }
}

#[test]
fn crc8_autosar_check_value() {
    // The catalogue check value of CRC-8/AUTOSAR over ASCII "123456789" is 0xDF.
    assert_eq!(crc8_autosar(b"123456789"), 0xDF);
    assert_eq!(crc8_reference(b"123456789"), 0xDF);
    assert_eq!(crc8_autosar(b""), 0x00); // 0xFF init ^ 0xFF xorout
    for len in 0..40u8 {
        let data: Vec<u8> = (0..len)
            .map(|i| i.wrapping_mul(37).wrapping_add(len))
            .collect();
        assert_eq!(crc8_autosar(&data), crc8_reference(&data));
    }
}

#[test]
fn golden_classic_frames() {
    let fields = PoseFields::from_estimate(&golden_estimate(), 0x1234);
    let mut out = [CanFrame::classic(0, false, &[]).unwrap(); CLASSIC_FRAMES];
    encode_classic(0x300, &fields, &mut out).unwrap();
    // Identifiers: base 0x300 + 4 * object 1 + frame kind 0..3.
    let ids: Vec<u32> = out.iter().map(|f| f.id).collect();
    assert_eq!(ids, [0x304, 0x305, 0x306, 0x307]);
    // Counter: tick 0x1234 mod 256 = 0x34 in byte 1 of every frame.
    // x = 0.12345 m / 1e-5 = 12345 = 0x003039 -> 39 30 00; y = -0.5 m -> -50000 = 0xFF3CB0 (24-bit) -> B0 3C FF.
    let f0 = [0x34, 0x39, 0x30, 0x00, 0xB0, 0x3C, 0xFF];
    // z = 1.25 m -> 125000 = 0x01E848 -> 48 E8 01; quality 0.8 / 0.004 = 200 = 0xC8; state degraded = 1; object 1.
    let f1 = [0x34, 0x48, 0xE8, 0x01, 0xC8, 0x01, 0x01];
    // q = (0, 0, sqrt(1/2), sqrt(1/2)): x = y = 0; z = round(0.70710678 * 32768) = 23170 = 0x5A82 -> 82 5A.
    let f2 = [0x34, 0x00, 0x00, 0x00, 0x00, 0x82, 0x5A];
    // w = 23170 -> 82 5A; t_us low 32 bits = 5000123 = 0x004C4BBB -> BB 4B 4C 00.
    let f3 = [0x34, 0x82, 0x5A, 0xBB, 0x4B, 0x4C, 0x00];
    // CRC-8/AUTOSAR over id (low byte, high byte) then bytes 1..8, from the bitwise reference, and as literals.
    let expected_crc = [0x02, 0x85, 0xE0, 0x25];
    for (i, (rest, id)) in [f0, f1, f2, f3]
        .iter()
        .zip([0x304u16, 0x305, 0x306, 0x307])
        .enumerate()
    {
        let mut crc_input = id.to_le_bytes().to_vec();
        crc_input.extend_from_slice(rest);
        assert_eq!(crc8_reference(&crc_input), expected_crc[i]);
        let mut frame = vec![expected_crc[i]];
        frame.extend_from_slice(rest);
        assert_eq!(out[i].data(), &frame[..], "frame {i} ({id:#X})");
        assert!(!out[i].fd && !out[i].extended);
    }
}

#[test]
fn golden_fd_frame() {
    let fields = PoseFields::from_estimate(&golden_estimate(), 0x1234);
    let mut out = CanFrame::classic(0, false, &[]).unwrap();
    encode_fd(0x300, &fields, &mut out).unwrap();
    // Identifier: base 0x300 + 0x40 + object 1 = 0x341; FD with bit-rate switch (flags 1).
    assert_eq!(out.id, 0x341);
    assert!(out.fd);
    assert_eq!(out.fd_flags, 1);
    #[rustfmt::skip]
    let rest: [u8; 47] = [
        0x34,                   // counter: tick 0x1234 mod 256
        0x01,                   // state: degraded
        0x01,                   // object index
        0x40, 0x1F,             // quality 0.8 / 0.0001 = 8000 = 0x1F40
        0x00, 0x00,             // reserved
        0xBB, 0x4B, 0x4C, 0x00, 0x00, 0x00, 0x00, 0x00, // t_us = 5000123 (i64)
        0x34, 0x12, 0x00, 0x00, // tick index 0x1234 (u32)
        0x3A, 0xE2, 0x01, 0x00, // x = 0.12345 m / 1e-6 = 123450 = 0x0001E23A
        0xE0, 0x5E, 0xF8, 0xFF, // y = -0.5 m -> -500000 = 0xFFF85EE0
        0xD0, 0x12, 0x13, 0x00, // z = 1.25 m -> 1250000 = 0x001312D0
        0x00, 0x00, 0x00, 0x00, // qx = 0
        0x00, 0x00, 0x00, 0x00, // qy = 0
        0xCD, 0x3C, 0x41, 0x2D, // qz = round(sqrt(1/2) * 2^30) = 759250125 = 0x2D413CCD
        0xCD, 0x3C, 0x41, 0x2D, // qw, same
    ];
    let mut crc_input = vec![0x41, 0x03];
    crc_input.extend_from_slice(&rest);
    assert_eq!(crc8_reference(&crc_input), 0x25);
    assert_eq!(out.data()[0], 0x25);
    assert_eq!(&out.data()[1..], &rest[..]);
}

#[test]
fn golden_candump_lines() {
    let fields = PoseFields::from_estimate(&golden_estimate(), 0x1234);
    let mut pose = EncodedPose::default();
    PoseEncoder {
        base_id: 0x300,
        fd: false,
    }
    .encode_into(&fields, &mut pose)
    .unwrap();
    let mut buf = Vec::new();
    candump::write_line(&mut buf, 5, 123, "can0", &pose.frames()[0]).unwrap();
    assert_eq!(
        String::from_utf8(buf).unwrap(),
        "(5.000123) can0 304#0234393000B03CFF\n"
    );
    PoseEncoder {
        base_id: 0x300,
        fd: true,
    }
    .encode_into(&fields, &mut pose)
    .unwrap();
    let mut buf = Vec::new();
    candump::write_line(&mut buf, 5, 123, "can1", &pose.frames()[0]).unwrap();
    let line = String::from_utf8(buf).unwrap();
    assert!(
        line.starts_with("(5.000123) can1 341##125340101401F0000BB4B4C"),
        "{line}"
    );
    assert_eq!(line.trim_end().len(), "(5.000123) can1 341##1".len() + 96);
}

fn roundtrip_check(
    est: &PoseEstimate,
    decoded: &DecodedPose,
    pos_tol: f64,
    quat_tol: f64,
    quality_tol: f64,
) {
    let t = est.pose.translation.vector;
    for (i, v) in [t.x, t.y, t.z].iter().enumerate() {
        assert!(
            (decoded.position[i] - v).abs() <= pos_tol,
            "position {i}: {} vs {v}",
            decoded.position[i]
        );
    }
    let q = est.pose.rotation.quaternion();
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    for (i, v) in [q.i, q.j, q.k, q.w].iter().enumerate() {
        assert!(
            (decoded.quaternion[i] - s * v).abs() <= quat_tol,
            "quaternion {i}"
        );
    }
    assert!(est.pose.rotation.angle_to(&decoded.isometry().rotation) <= 8.0 * quat_tol);
    assert!((decoded.quality - f64::from(est.quality)).abs() <= quality_tol);
    assert_eq!(decoded.state, est.state.code());
    assert_eq!(decoded.object, est.object);
    assert_eq!(decoded.t_us_low32, est.t_us as u32);
}

fn arb_estimate() -> impl Strategy<Value = PoseEstimate> {
    (
        0usize..MAX_OBJECTS,
        any::<i64>(),
        proptest::array::uniform3(-80.0f64..80.0),
        proptest::array::uniform4(-1.0f64..1.0),
        0.0f32..=1.0,
        0u8..3,
    )
        .prop_filter("non-degenerate quaternion", |(_, _, _, q, _, _)| {
            q.iter().map(|c| c * c).sum::<f64>() > 1e-3
        })
        .prop_map(|(object, t_us, p, q, quality, state)| PoseEstimate {
            object,
            t_us,
            pose: Isometry3::from_parts(
                Translation3::new(p[0], p[1], p[2]),
                UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
            ),
            quality,
            state: [
                TrackingState::Tracking,
                TrackingState::Degraded,
                TrackingState::Lost,
            ][usize::from(state)],
        })
}

proptest! {
    #[test]
    fn classic_roundtrip_within_resolution(est in arb_estimate(), tick_index in any::<u64>(), base in 0u16..=MAX_BASE_ID) {
        let mut pose = EncodedPose::default();
        PoseEncoder { base_id: base, fd: false }
            .encode_into(&PoseFields::from_estimate(&est, tick_index), &mut pose)
            .unwrap();
        let mut asm = Assembler::new(base);
        let mut got = None;
        for (i, f) in pose.frames().iter().enumerate() {
            let r = asm.push(f).unwrap();
            prop_assert_eq!(r.is_some(), i == CLASSIC_FRAMES - 1);
            got = got.or(r);
        }
        let d = got.unwrap();
        prop_assert_eq!(d.counter, tick_index as u8);
        // Half an LSB of rounding (plus float slack); the quaternion's w = 1 is clamped to 32767 (one LSB).
        roundtrip_check(&est, &d, CLASSIC_POS_SCALE * 0.5 + 1e-12, CLASSIC_QUAT_SCALE * 1.01, CLASSIC_QUALITY_SCALE * 0.5 + 1e-6);
    }

    #[test]
    fn fd_roundtrip_within_resolution(est in arb_estimate(), tick_index in any::<u64>(), base in 0u16..=MAX_BASE_ID) {
        let mut pose = EncodedPose::default();
        PoseEncoder { base_id: base, fd: true }
            .encode_into(&PoseFields::from_estimate(&est, tick_index), &mut pose)
            .unwrap();
        prop_assert_eq!(pose.frames().len(), 1);
        let d = Assembler::new(base).push(&pose.frames()[0]).unwrap().unwrap();
        prop_assert_eq!(d.t_us, Some(est.t_us));
        prop_assert_eq!(d.tick_index_low32, Some(tick_index as u32));
        roundtrip_check(&est, &d, FD_POS_SCALE * 0.5 + 1e-12, FD_QUAT_SCALE * 1.01, FD_QUALITY_SCALE * 0.5 + 1e-6);
    }

    #[test]
    fn arbitrary_frames_never_panic(id in 0u32..0x800, fd in any::<bool>(), data in proptest::collection::vec(any::<u8>(), 0..=64)) {
        let frame = if fd { CanFrame::fd(id, false, 1, &data) } else { CanFrame::classic(id, false, &data) };
        if let Some(frame) = frame {
            let _ = decode_classic(0x300, &frame);
            let _ = decode_fd(0x300, &frame);
            let mut asm = Assembler::new(0x300);
            let _ = asm.push(&frame);
        }
    }

    #[test]
    fn arbitrary_text_into_candump_parser_never_panics(text in "\\PC{0,120}", bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = candump::parse_log(&text);
        let _ = candump::parse_log(&String::from_utf8_lossy(&bytes));
        let _ = candump::parse_line(&format!("(1.5) can0 {text}"), 1);
        let _ = candump::parse_line(&format!("(1.5) can0 123#{text}"), 1);
        let _ = candump::parse_line(&format!("(1.5) can0 123##{text}"), 1);
    }

    #[test]
    fn candump_roundtrip(id in 0u32..0x800, fd in any::<bool>(), flags in 0u8..4, secs in 0u64..4_000_000_000, micros in 0u32..1_000_000, n in 0usize..16) {
        let data: Vec<u8> = (0..FD_LENGTHS[n]).map(|i| (i as u8).wrapping_mul(31)).collect();
        let frame = if fd { CanFrame::fd(id, false, flags, &data) } else { CanFrame::classic(id, false, &data[..data.len().min(8)]) }.unwrap();
        let mut buf = Vec::new();
        candump::write_line(&mut buf, secs, micros, "vcan0", &frame).unwrap();
        let recs = candump::parse_log(std::str::from_utf8(&buf).unwrap()).unwrap();
        prop_assert_eq!(recs.len(), 1);
        prop_assert_eq!(recs[0].secs, secs);
        prop_assert_eq!(recs[0].micros, micros);
        prop_assert_eq!(&recs[0].iface, "vcan0");
        prop_assert_eq!(recs[0].frame, frame);
    }
}

fn golden_classic() -> [CanFrame; CLASSIC_FRAMES] {
    let mut pose = EncodedPose::default();
    PoseEncoder {
        base_id: 0x300,
        fd: false,
    }
    .encode_into(
        &PoseFields::from_estimate(&golden_estimate(), 0x1234),
        &mut pose,
    )
    .unwrap();
    pose.frames().try_into().unwrap()
}

#[test]
fn assembler_rejects_mixed_counters() {
    let a = golden_classic();
    let mut pose = EncodedPose::default();
    PoseEncoder {
        base_id: 0x300,
        fd: false,
    }
    .encode_into(
        &PoseFields::from_estimate(&golden_estimate(), 0x1235),
        &mut pose,
    )
    .unwrap();
    let b = pose.frames();
    let mut asm = Assembler::new(0x300);
    assert_eq!(asm.push(&a[0]), Ok(None));
    assert_eq!(asm.push(&a[1]), Ok(None));
    assert_eq!(asm.push(&a[2]), Ok(None));
    // The last frame comes from the next pose (counter 0x35): the counter-0x34 set is discarded, no pose.
    assert_eq!(
        asm.push(&b[3]),
        Err(DecodeError::CounterMismatch {
            object: 1,
            expected: 0x34,
            got: 0x35
        })
    );
    // Completing counter 0x35 yields that pose only when its own four frames are there.
    assert_eq!(asm.push(&b[0]), Ok(None));
    assert_eq!(asm.push(&b[1]), Ok(None));
    let pose = asm.push(&b[2]).unwrap().unwrap();
    assert_eq!(pose.counter, 0x35);
    assert_eq!(asm.counters().poses, 1);
    assert_eq!(asm.counters().discarded_sets, 1);
}

#[test]
fn assembler_rejects_bad_crc_and_wrong_frames() {
    let a = golden_classic();
    let mut asm = Assembler::new(0x300);
    // One flipped bit in the payload of frame 2.
    let mut data = a[2].data().to_vec();
    data[5] ^= 0x01;
    let corrupt = CanFrame::classic(a[2].id, false, &data).unwrap();
    assert!(matches!(
        asm.push(&corrupt),
        Err(DecodeError::BadCrc {
            id: 0x306,
            got: 0xE0,
            ..
        })
    ));
    // The same payload under another object's id fails the CRC too (the id is inside the CRC).
    let moved = CanFrame::classic(0x30A, false, a[2].data()).unwrap();
    assert!(matches!(
        asm.push(&moved),
        Err(DecodeError::BadCrc { id: 0x30A, .. })
    ));
    for f in &a[..3] {
        if f.id != 0x306 {
            assert_eq!(asm.push(f), Ok(None));
        }
    }
    // Without a valid frame 2 there is no pose; the good one completes the set.
    assert_eq!(asm.push(&a[3]), Ok(None));
    assert!(asm.push(&a[2]).unwrap().is_some());
    // Wrong length, unknown id, FD frame on a classic id.
    let short = CanFrame::classic(0x304, false, &a[0].data()[..7]).unwrap();
    assert_eq!(
        asm.push(&short),
        Err(DecodeError::WrongLength {
            id: 0x304,
            expected: 8,
            got: 7
        })
    );
    let unknown = CanFrame::classic(0x200, false, a[0].data()).unwrap();
    assert_eq!(
        asm.push(&unknown),
        Err(DecodeError::UnknownId { id: 0x200 })
    );
    let beyond = CanFrame::classic(0x300 + u32::from(ID_SPAN), false, a[0].data()).unwrap();
    assert_eq!(asm.push(&beyond), Err(DecodeError::UnknownId { id: 0x350 }));
    let fd = CanFrame::fd(0x304, false, 1, a[0].data()).unwrap();
    assert!(matches!(
        asm.push(&fd),
        Err(DecodeError::WrongFormat { id: 0x304, .. })
    ));
    assert_eq!(asm.counters().bad_frames, 6);
}

#[test]
fn decoder_checks_object_and_state_fields() {
    let a = golden_classic();
    // Frame 1 with object byte 2 (id says object 1), CRC recomputed so only the field is wrong.
    let mut d = a[1].data().to_vec();
    d[7] = 2;
    d[0] = frame_crc(0x305, &d[1..]);
    let f = CanFrame::classic(0x305, false, &d).unwrap();
    assert_eq!(
        decode_classic(0x300, &f),
        Err(DecodeError::ObjectMismatch {
            id: 0x305,
            from_id: 1,
            in_payload: 2
        })
    );
    d[7] = 1;
    d[6] = 3;
    d[0] = frame_crc(0x305, &d[1..]);
    let f = CanFrame::classic(0x305, false, &d).unwrap();
    assert_eq!(
        decode_classic(0x300, &f),
        Err(DecodeError::InvalidField {
            id: 0x305,
            field: "state",
            value: 3
        })
    );
}

#[test]
fn encoder_rejects_unencodable_poses() {
    let mut fields = PoseFields::from_estimate(&golden_estimate(), 1);
    let mut pose = EncodedPose::default();
    let classic = PoseEncoder {
        base_id: 0x300,
        fd: false,
    };
    fields.position[2] = 90.0;
    assert!(matches!(
        classic.encode_into(&fields, &mut pose),
        Err(EncodeError::OutOfRange {
            field: "position z",
            ..
        })
    ));
    // FD carries +-2147 m.
    assert!(
        PoseEncoder {
            base_id: 0x300,
            fd: true
        }
        .encode_into(&fields, &mut pose)
        .is_ok()
    );
    fields.position[2] = f64::NAN;
    assert!(matches!(
        classic.encode_into(&fields, &mut pose),
        Err(EncodeError::NotFinite { .. })
    ));
    fields.position[2] = 1.0;
    fields.object = MAX_OBJECTS;
    assert_eq!(
        classic.encode_into(&fields, &mut pose),
        Err(EncodeError::ObjectIndex {
            object: MAX_OBJECTS
        })
    );
    fields.object = 0;
    assert_eq!(
        PoseEncoder {
            base_id: MAX_BASE_ID + 1,
            fd: false
        }
        .encode_into(&fields, &mut pose),
        Err(EncodeError::BaseId {
            base_id: MAX_BASE_ID + 1
        })
    );
    assert!(
        PoseEncoder {
            base_id: MAX_BASE_ID,
            fd: false
        }
        .encode_into(&fields, &mut pose)
        .is_ok()
    );
    // The highest identifier of the highest base is still 11-bit.
    assert_eq!(u32::from(fd_id(MAX_BASE_ID, MAX_OBJECTS - 1)), 0x7FF);
}

#[test]
fn quaternion_sign_is_canonical() {
    let mut est = golden_estimate();
    est.pose.rotation =
        UnitQuaternion::new_unchecked(Quaternion::new(-FRAC_1_SQRT_2, 0.0, 0.0, -FRAC_1_SQRT_2));
    let mut fields_pos = [CanFrame::classic(0, false, &[]).unwrap(); CLASSIC_FRAMES];
    encode_classic(
        0x300,
        &PoseFields::from_estimate(&est, 0x1234),
        &mut fields_pos,
    )
    .unwrap();
    assert_eq!(fields_pos, golden_classic());
}

fn publish_ticks(sink: &mut dyn PoseSink, ticks: std::ops::Range<u64>, objects: usize) {
    let names: Vec<String> = (0..objects).map(|i| format!("obj{i}")).collect();
    for i in ticks {
        let t = tick(i);
        let ests: Vec<PoseEstimate> = (0..objects)
            .map(|o| PoseEstimate {
                object: o,
                t_us: t.t_us,
                ..golden_estimate()
            })
            .collect();
        let poses = TickPoses {
            tick: &t,
            estimates: &ests,
            objects: &names,
            decoded_at: Instant::now(),
        };
        sink.publish(&poses).unwrap();
    }
}

#[test]
fn memory_sink_shares_frames() {
    let mut sink = MemorySink::new(PoseEncoder {
        base_id: 0x300,
        fd: false,
    });
    let frames = sink.frames();
    publish_ticks(&mut sink, 0..3, 2);
    assert_eq!(frames.len(), 3 * 2 * CLASSIC_FRAMES);
    assert_eq!(sink.counters().published, 6);
    let mut asm = Assembler::new(0x300);
    let poses: Vec<DecodedPose> = frames
        .snapshot()
        .iter()
        .filter_map(|f| asm.push(f).unwrap())
        .collect();
    assert_eq!(poses.len(), 6);
    assert_eq!((poses[5].object, poses[5].counter), (1, 2));
}

#[test]
fn candump_sink_writes_a_parseable_log() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub/can.log");
    for fd in [false, true] {
        let mut sink = CandumpSink::create(&path, "vcan0", PoseEncoder { base_id: 0x300, fd })
            .unwrap()
            .with_clock(CandumpClock::Camera);
        publish_ticks(&mut sink, 10..14, 3);
        sink.flush().unwrap();
        assert_eq!(sink.counters().published, 12);
        let text = std::fs::read_to_string(&path).unwrap();
        let records = candump::parse_log(&text).unwrap();
        assert_eq!(records.len(), 12 * if fd { 1 } else { CLASSIC_FRAMES });
        // Camera clock: tick 10 is at 5.083330 s.
        assert_eq!((records[0].secs, records[0].micros), (5, 83_330));
        let mut asm = Assembler::new(0x300);
        let poses: Vec<_> = records
            .iter()
            .filter_map(|r| asm.push(&r.frame).unwrap())
            .collect();
        assert_eq!(poses.len(), 12);
        for p in &poses {
            assert!((p.position[0] - 0.12345).abs() < 1e-5);
        }
    }
}

#[test]
fn candump_parser_reports_line_errors() {
    let text = "(1.000001) can0 123#1122\n\n(2.5) can0 12#00\n";
    assert_eq!(
        candump::parse_log(text),
        Err(candump::CandumpError::Identifier {
            line: 3,
            id: "12".into()
        })
    );
    assert!(matches!(
        candump::parse_line("1.0 can0 123#00", 1),
        Err(candump::CandumpError::Timestamp { line: 1 })
    ));
    assert!(matches!(
        candump::parse_line("(1.0) can0 123#001", 4),
        Err(candump::CandumpError::Data { line: 4, .. })
    ));
    assert!(matches!(
        candump::parse_line("(1.0) can0 123##1001", 1),
        Err(candump::CandumpError::Data { .. })
    ));
    // 9 bytes is not an FD length.
    assert!(candump::parse_line("(1.0) can0 123##1001122334455667788", 1).is_err());
    // Extended ids, remote frames, and candump's raw-DLC suffix are understood.
    let r = candump::parse_line("(1.0) can0 12345678#R3", 1).unwrap();
    assert!(r.frame.extended && r.frame.remote && r.frame.len() == 3 && r.frame.id == 0x1234_5678);
    let r = candump::parse_line("(1.0) can0 123#0011223344556677_C", 1).unwrap();
    assert_eq!(
        r.frame.data(),
        &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]
    );
}

#[test]
fn socket_sink_says_interface_is_missing() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let err = SocketCanSink::open(
        "et6dnocan9",
        PoseEncoder {
            base_id: 0x300,
            fd: false,
        },
        8,
        rt.handle(),
    )
    .err()
    .expect("no such interface");
    assert!(matches!(err, CanError::NoSuchInterface { ref iface } if iface == "et6dnocan9"));
    let msg = err.to_string();
    assert!(
        msg.contains("`et6dnocan9` does not exist") && msg.contains("other sinks carry on"),
        "{msg}"
    );
    // Through the configuration: the candump sink is still created, the SocketCAN error is returned.
    let dir = tempfile::tempdir().unwrap();
    let config = CanConfig {
        interface: Some("et6dnocan9".into()),
        candump_log: Some(dir.path().join("c.log")),
        ..CanConfig::default()
    };
    let (sinks, errors) = config.build_sinks(rt.handle());
    assert_eq!(sinks.len(), 1);
    assert!(sinks[0].name().starts_with("candump:"));
    assert_eq!(errors.len(), 1);
}

#[test]
fn socket_sink_on_a_non_can_interface_is_an_error_not_a_panic() {
    // `lo` exists everywhere but is no CAN interface (and this kernel may have no CAN sockets at all).
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    for fd in [false, true] {
        let err = SocketCanSink::open("lo", PoseEncoder { base_id: 0x300, fd }, 8, rt.handle())
            .err()
            .expect("lo is not a CAN interface");
        let msg = err.to_string();
        assert!(
            msg.contains("`lo`") && msg.contains("other sinks carry on"),
            "{msg}"
        );
    }
}

/// A fake bus: records frames, fails the writes whose (0-based) number is in `fail`, can be held (blocked).
#[derive(Clone)]
struct FakeBus {
    written: Arc<Mutex<Vec<CanFrame>>>,
    writes: Arc<AtomicUsize>,
    opens: Arc<AtomicUsize>,
    fail: Arc<Mutex<Vec<usize>>>,
    gate: Arc<tokio::sync::Semaphore>,
}

impl Default for FakeBus {
    fn default() -> Self {
        Self {
            written: Arc::default(),
            writes: Arc::default(),
            opens: Arc::default(),
            fail: Arc::default(),
            gate: Arc::new(tokio::sync::Semaphore::new(0)),
        }
    }
}

impl FrameTransport for FakeBus {
    async fn write(&mut self, frame: &CanFrame) -> io::Result<()> {
        let permit = self
            .gate
            .acquire()
            .await
            .map_err(|_| io::Error::other("closed"))?;
        permit.forget();
        let n = self.writes.fetch_add(1, Ordering::SeqCst);
        if self.fail.lock().unwrap().contains(&n) {
            return Err(io::Error::from_raw_os_error(100)); // ENETDOWN, as bus-off reports it
        }
        self.written.lock().unwrap().push(*frame);
        Ok(())
    }
}

impl TransportOpener for FakeBus {
    type Transport = FakeBus;
    fn open(&mut self) -> io::Result<FakeBus> {
        self.opens.fetch_add(1, Ordering::SeqCst);
        Ok(self.clone())
    }
}

fn wait_until(what: &str, mut f: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(5);
    while !f() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn socket_sink_drops_oldest_and_never_blocks() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .unwrap();
    let bus = FakeBus::default(); // gate closed: the writer blocks on its first frame
    let encoder = PoseEncoder {
        base_id: 0x300,
        fd: true,
    };
    let mut sink = SocketCanSink::with_transport(
        "can:fake".into(),
        encoder,
        4,
        bus.clone(),
        Some(bus.clone()),
        rt.handle(),
    );
    publish_ticks(&mut sink, 0..1, 1);
    wait_until("writer to take the first pose", || sink.queued() == 0);
    let start = Instant::now();
    publish_ticks(&mut sink, 1..11, 1); // 10 poses into a queue of 4 while the bus is stuck
    assert!(
        start.elapsed() < Duration::from_millis(500),
        "publish blocked"
    );
    assert_eq!(sink.queued(), 4);
    assert_eq!(sink.counters().dropped, 6);
    bus.gate.add_permits(1000);
    wait_until("queue to drain", || sink.counters().published == 5);
    // The first pose and the newest four (ticks 7..=10) went out; ticks 1..=6 were dropped oldest-first.
    let counters: Vec<u8> = bus
        .written
        .lock()
        .unwrap()
        .iter()
        .map(|f| f.data()[1])
        .collect();
    assert_eq!(counters, [0, 7, 8, 9, 10]);
    assert_eq!(sink.counters().failed, 0);
}

#[test]
fn socket_sink_counts_write_errors_and_reopens() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .unwrap();
    let bus = FakeBus::default();
    bus.gate.add_permits(1000);
    *bus.fail.lock().unwrap() = vec![1, 2];
    let encoder = PoseEncoder {
        base_id: 0x300,
        fd: false,
    };
    let mut sink = SocketCanSink::with_transport(
        "can:fake".into(),
        encoder,
        16,
        bus.clone(),
        Some(bus.clone()),
        rt.handle(),
    );
    for i in 0..4 {
        publish_ticks(&mut sink, i..i + 1, 1);
        wait_until("pose handled", || {
            let c = sink.counters();
            c.published + c.failed == i + 1
        });
    }
    let c = sink.counters();
    // Write 1 fails (pose 0's second frame): pose 0 failed, socket dropped; after a backoff the socket is reopened
    // and write 2 fails (pose 1's first frame): pose 1 failed, reopened again; poses 2 and 3 go through.
    assert_eq!((c.published, c.failed, c.dropped), (2, 2, 0));
    let h = sink.health();
    assert_eq!(h.write_errors, 2);
    assert_eq!(h.bus_off, 2);
    assert_eq!(h.reopens, 2);
    assert!(h.connected);
    assert!(h.last_error.unwrap().contains("write failed"));
    assert_eq!(bus.opens.load(Ordering::SeqCst), 2);
    // Only complete, consistent sets reach the bus; the receiver assembles exactly the two good poses.
    let mut asm = Assembler::new(0x300);
    let frames = bus.written.lock().unwrap().clone();
    let poses = frames
        .iter()
        .filter_map(|f| asm.push(f).ok().flatten())
        .count();
    assert_eq!(poses, 2);
}

#[test]
fn config_defaults_and_validation() {
    let c: CanConfig = serde_json::from_str("{}").unwrap();
    assert_eq!(c, CanConfig::default());
    assert!(c.enabled && !c.fd && c.interface.is_none() && c.candump_log.is_none());
    assert_eq!((c.base_id, c.queue_len), (0x300, 64));
    let err = serde_json::from_str::<CanConfig>(r#"{"bitrate": 500000}"#)
        .unwrap_err()
        .to_string();
    assert!(err.contains("unknown field `bitrate`"), "{err}");
    let c: CanConfig = serde_json::from_str(
        r#"{"interface": "can1", "fd": true, "base_id": 1024, "queue_len": 8}"#,
    )
    .unwrap();
    assert!(c.validate(4).is_ok());
    assert_eq!(
        c.encoder(),
        PoseEncoder {
            base_id: 0x400,
            fd: true
        }
    );
    let bad = CanConfig {
        base_id: 0x7C0,
        ..CanConfig::default()
    }
    .validate(1)
    .unwrap_err()
    .to_string();
    assert!(
        bad.contains("can.base_id") && bad.contains("0x7C0"),
        "{bad}"
    );
    let bad = CanConfig::default()
        .validate(MAX_OBJECTS + 1)
        .unwrap_err()
        .to_string();
    assert!(bad.contains("at most 16"), "{bad}");
    assert!(
        CanConfig {
            queue_len: 0,
            ..CanConfig::default()
        }
        .validate(1)
        .is_err()
    );
    assert!(
        CanConfig {
            interface: Some("a/b".into()),
            ..CanConfig::default()
        }
        .validate(1)
        .is_err()
    );
}

#[test]
fn shipped_dbc_is_the_generated_one() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../config/can/eventtrack6d.dbc"
    );
    if std::env::var_os("ET6D_WRITE_DBC").is_some() {
        std::fs::write(path, super::dbc::default_dbc_text()).unwrap();
    }
    let shipped = std::fs::read_to_string(path).expect("config/can/eventtrack6d.dbc");
    assert!(
        shipped == super::dbc::default_dbc_text(),
        "config/can/eventtrack6d.dbc differs from dbc::default_dbc_text(); after changing the layout regenerate it \
         with `ET6D_WRITE_DBC=1 cargo test -p eventtrack6d --lib publish::can::tests::shipped_dbc`"
    );
}
