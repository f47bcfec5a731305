//! Round trips, field layouts and malformed input for the messages beside PoseStamped.

use super::diagnostic::*;
use super::sensor::*;
use super::tf::*;
use super::trigger::*;
use super::vision::*;
use super::*;
use proptest::prelude::*;

fn header(sec: i32, nanosec: u32, frame: &str) -> Header {
    Header::new(RosTime { sec, nanosec }, frame)
}

#[test]
fn event_packet_fields_sit_where_cdr_puts_them() {
    let events = [0x01u8, 0x80, 0x02, 0x60];
    let p = EventPacket {
        header: header(7, 9, "cam"),
        height: 720,
        width: 1280,
        seq: 42,
        time_base: 5,
        encoding: "evt3".into(),
        is_bigendian: false,
        events: &events,
    };
    let mut out = Vec::new();
    encode_event_packet(&mut out, &p);
    // header: 4 encapsulation, sec 4..8, nanosec 8..12, frame length 12..16, "cam\0" 16..20; height 20..24,
    // width 24..28, seq 28..36 (byte 28 is 24 bytes into the body: already 8-aligned), time_base 36..44,
    // encoding length 44..48, "evt3\0" 48..53, is_bigendian 53, events count at 56 (4-aligned), bytes 60..64.
    assert_eq!(out.len(), 64);
    assert_eq!(&out[20..24], &720u32.to_le_bytes());
    assert_eq!(&out[28..36], &42u64.to_le_bytes());
    assert_eq!(&out[48..53], b"evt3\0");
    assert_eq!(out[53], 0);
    assert_eq!(&out[56..60], &4u32.to_le_bytes());
    assert_eq!(&out[60..64], &events);
    assert_eq!(decode_event_packet(&out).unwrap(), p);
    let mut bad_bool = out.clone();
    bad_bool[53] = 2;
    assert_eq!(
        decode_event_packet(&bad_bool),
        Err(CdrError::NotBool {
            field: "is_bigendian",
            value: 2
        })
    );
    let mut huge = out.clone();
    huge[56..60].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        decode_event_packet(&huge),
        Err(CdrError::SequenceLength {
            field: "events",
            ..
        })
    ));
}

#[test]
fn an_empty_trigger_request_and_a_response_read_back() {
    let mut out = Vec::new();
    encode_trigger_request(&mut out);
    assert_eq!(out, [0, 1, 0, 0, 0]);
    assert_eq!(decode_trigger_request(&out), Ok(()));
    assert_eq!(decode_trigger_request(&out[..4]), Ok(()));
    assert!(decode_trigger_request(&[0, 0, 0, 0]).is_err());
    let r = TriggerResponse {
        success: true,
        message: "reset 2 objects".into(),
    };
    encode_trigger_response(&mut out, &r);
    // success at 4, message length at 8 (4-aligned), text from 12.
    assert_eq!(out[4], 1);
    assert_eq!(&out[8..12], &16u32.to_le_bytes());
    assert_eq!(decode_trigger_response(&out).unwrap(), r);
}

fn name() -> impl Strategy<Value = String> {
    "[a-z_/]{0,12}"
}

fn finite() -> impl Strategy<Value = f64> {
    -1e6f64..1e6
}

fn pose() -> impl Strategy<Value = Pose> {
    (
        prop::array::uniform3(finite()),
        prop::array::uniform4(finite()),
    )
        .prop_map(|(p, q)| Pose {
            position: p,
            orientation_xyzw: q,
        })
}

fn hdr() -> impl Strategy<Value = Header> {
    (any::<i32>(), 0u32..1_000_000_000, name()).prop_map(|(s, n, f)| header(s, n, &f))
}

proptest! {
    #[test]
    fn tf_messages_round_trip(items in prop::collection::vec((hdr(), name(), pose()), 0..5)) {
        let t: Vec<TransformStamped> = items
            .into_iter()
            .map(|(header, child_frame_id, p)| TransformStamped {
                header,
                child_frame_id,
                translation: p.position,
                rotation_xyzw: p.orientation_xyzw,
            })
            .collect();
        let mut out = Vec::new();
        encode_tf_message(&mut out, &t);
        prop_assert_eq!(decode_tf_message(&out).unwrap(), t);
    }

    #[test]
    fn detection_arrays_round_trip(
        h in hdr(),
        dets in prop::collection::vec((hdr(), name(), finite(), pose(), pose(), prop::array::uniform3(finite())), 0..4),
    ) {
        let msg = Detection3DArray {
            header: h,
            detections: dets
                .into_iter()
                .map(|(header, id, score, p, c, size)| Detection3D {
                    header,
                    results: vec![ObjectHypothesisWithPose {
                        class_id: id.clone(),
                        score,
                        pose: p,
                        covariance: [score; 36],
                    }],
                    bbox_center: c,
                    bbox_size: size,
                    id,
                })
                .collect(),
        };
        let mut out = Vec::new();
        encode_detection3d_array(&mut out, &msg);
        prop_assert_eq!(decode_detection3d_array(&out).unwrap(), msg);
    }

    #[test]
    fn diagnostic_arrays_round_trip(
        h in hdr(),
        st in prop::collection::vec((0u8..4, name(), name(), name(), prop::collection::vec((name(), name()), 0..4)), 0..4),
    ) {
        let msg = DiagnosticArray {
            header: h,
            status: st
                .into_iter()
                .map(|(level, name, message, hardware_id, values)| DiagnosticStatus {
                    level,
                    name,
                    message,
                    hardware_id,
                    values,
                })
                .collect(),
        };
        let mut out = Vec::new();
        encode_diagnostic_array(&mut out, &msg);
        prop_assert_eq!(decode_diagnostic_array(&out).unwrap(), msg);
    }

    #[test]
    fn images_and_camera_infos_round_trip(
        h in hdr(),
        (w, rows) in (0u32..8, 0u32..8),
        enc in "[0-9A-Z]{0,6}",
        d in prop::collection::vec(finite(), 0..8),
        k in prop::array::uniform9(finite()),
    ) {
        let data: Vec<u8> = (0..w * rows * 2).map(|i| i as u8).collect();
        let img = Image { header: h.clone(), height: rows, width: w, encoding: enc.clone(), is_bigendian: 0, step: 2 * w, data: &data };
        let mut out = Vec::new();
        encode_image(&mut out, &img);
        prop_assert_eq!(decode_image(&out).unwrap(), img);
        let info = CameraInfo {
            header: h,
            height: rows,
            width: w,
            distortion_model: enc,
            d,
            k,
            r: k,
            p: [k[0]; 12],
            binning_x: 1,
            binning_y: 2,
            roi: [1, 2, 3, 4],
            roi_do_rectify: true,
        };
        encode_camera_info(&mut out, &info);
        prop_assert_eq!(decode_camera_info(&out).unwrap(), info);
    }

    #[test]
    fn event_packets_round_trip(h in hdr(), seq in any::<u64>(), events in prop::collection::vec(any::<u8>(), 0..64)) {
        let p = EventPacket { header: h, height: 720, width: 1280, seq, time_base: 0, encoding: "evt3".into(), is_bigendian: false, events: &events };
        let mut out = Vec::new();
        encode_event_packet(&mut out, &p);
        prop_assert_eq!(decode_event_packet(&out).unwrap(), p);
    }

    #[test]
    fn no_decoder_panics_on_arbitrary_bytes(mut bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        if bytes.len() >= 2 {
            bytes[0] = 0;
            bytes[1] = 1;
        }
        let _ = decode_tf_message(&bytes);
        let _ = decode_detection3d_array(&bytes);
        let _ = decode_diagnostic_array(&bytes);
        let _ = decode_event_packet(&bytes);
        let _ = decode_image(&bytes);
        let _ = decode_camera_info(&bytes);
        let _ = decode_trigger_response(&bytes);
    }
}
