use super::*;
use nalgebra::Isometry3;
use proptest::prelude::*;

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Golden vector built by hand, field by field, for frame_id "world" (5 chars: exercises the padding).
#[test]
fn golden_pose_stamped_world() {
    let stamp = RosTime {
        sec: 1_700_000_000,
        nanosec: 123_456_789,
    };
    let position = [1.0, -2.5, 0.125];
    let orientation = [
        0.0,
        0.0,
        std::f64::consts::FRAC_1_SQRT_2,
        std::f64::consts::FRAC_1_SQRT_2,
    ];
    let mut out = Vec::new();
    encode_pose_stamped(&mut out, stamp, "world", position, orientation);

    let mut expected: Vec<u8> = Vec::new();
    // 0..4: encapsulation CDR_LE, options 0.
    expected.extend_from_slice(&[0x00, 0x01, 0x00, 0x00]);
    // 4..8 (body 0): stamp.sec = 1_700_000_000 = 0x6553_F100, little-endian.
    expected.extend_from_slice(&[0x00, 0xF1, 0x53, 0x65]);
    // 8..12 (body 4): stamp.nanosec = 123_456_789 = 0x075B_CD15.
    expected.extend_from_slice(&[0x15, 0xCD, 0x5B, 0x07]);
    // 12..16 (body 8): frame_id length 6 = "world" + NUL.
    expected.extend_from_slice(&[0x06, 0x00, 0x00, 0x00]);
    // 16..22 (body 12..18): "world\0".
    expected.extend_from_slice(b"world\0");
    // 22..28 (body 18..24): padding to 8-byte alignment of the body for the f64 that follow.
    expected.extend_from_slice(&[0; 6]);
    // 28..36 (body 24): position.x = 1.0 = 0x3FF0_0000_0000_0000.
    expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0xF0, 0x3F]);
    // 36..44: position.y = -2.5 = 0xC004_0000_0000_0000.
    expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0x04, 0xC0]);
    // 44..52: position.z = 0.125 = 0x3FC0_0000_0000_0000.
    expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0xC0, 0x3F]);
    // 52..60, 60..68: orientation.x = orientation.y = 0.0.
    expected.extend_from_slice(&[0; 16]);
    // 68..76, 76..84: orientation.z = orientation.w = sqrt(1/2) = 0x3FE6_A09E_667F_3BCD.
    expected.extend_from_slice(&[0xCD, 0x3B, 0x7F, 0x66, 0x9E, 0xA0, 0xE6, 0x3F]);
    expected.extend_from_slice(&[0xCD, 0x3B, 0x7F, 0x66, 0x9E, 0xA0, 0xE6, 0x3F]);
    assert_eq!(expected.len(), 84);
    assert_eq!(hex(&out), hex(&expected));
    assert_eq!(out.len(), pose_stamped_encoded_len(5));

    let msg = decode_pose_stamped(&out).unwrap();
    assert_eq!(msg.stamp, stamp);
    assert_eq!(msg.frame_id, "world");
    assert_eq!(msg.position, position);
    assert_eq!(msg.orientation_xyzw, orientation);
}

/// Golden vector for the default frame id "eventtrack6d_camera" (19 chars: the string ends aligned, no padding).
#[test]
fn golden_pose_stamped_default_frame() {
    let mut out = Vec::new();
    let stamp = RosTime {
        sec: -1,
        nanosec: 999_999_999,
    };
    encode_pose_stamped(
        &mut out,
        stamp,
        "eventtrack6d_camera",
        [0.0; 3],
        [0.0, 0.0, 0.0, 1.0],
    );
    // 4 header + 4 sec + 4 nanosec + 4 length + 20 string (body ends at 32, already 8-aligned) + 56 = 92.
    assert_eq!(out.len(), 92);
    assert_eq!(&out[4..8], &[0xFF; 4], "sec = -1 in two's complement");
    assert_eq!(&out[8..12], &999_999_999u32.to_le_bytes());
    assert_eq!(&out[12..16], &[20, 0, 0, 0]);
    assert_eq!(&out[16..36], b"eventtrack6d_camera\0");
    assert_eq!(
        &out[36..84],
        &[0; 48],
        "position and orientation x, y, z are zero"
    );
    assert_eq!(&out[84..92], &1.0f64.to_le_bytes(), "orientation.w");
}

/// Bytes produced by an independent CDR implementation (the `rosbags` Python package 0.11.9,
/// `serialize_cdr` with its ROS 2 Jazzy type store) for stamp 42 s 7 ns, frame "map_frame", position
/// (1.5, -2, 3.25), orientation (0, 0.6, 0, 0.8): decoded by ours, and reproduced byte for byte by our encoder.
#[test]
fn matches_an_independent_encoder() {
    let hex = "000100002a000000070000000a0000006d61705f6672616d65000000000000000000f83f\
               00000000000000c00000000000000a400000000000000000333333333333e33f\
               00000000000000009a9999999999e93f";
    let hex: String = hex.split_whitespace().collect();
    let bytes: Vec<u8> = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect();
    let msg = decode_pose_stamped(&bytes).unwrap();
    assert_eq!(
        msg.stamp,
        RosTime {
            sec: 42,
            nanosec: 7
        }
    );
    assert_eq!(msg.frame_id, "map_frame");
    assert_eq!(msg.position, [1.5, -2.0, 3.25]);
    assert_eq!(msg.orientation_xyzw, [0.0, 0.6, 0.0, 0.8]);
    let mut out = Vec::new();
    encode_pose_stamped(
        &mut out,
        msg.stamp,
        &msg.frame_id,
        msg.position,
        msg.orientation_xyzw,
    );
    assert_eq!(out, bytes);
}

#[test]
fn empty_frame_id_pads_to_8() {
    let mut out = Vec::new();
    encode_pose_stamped(
        &mut out,
        RosTime::default(),
        "",
        [1.0, 2.0, 3.0],
        [0.0, 0.0, 0.0, 1.0],
    );
    // body: 12 bytes + length-1 string "\0" = 13, padded to 16; f64s from byte 20.
    assert_eq!(&out[12..16], &[1, 0, 0, 0]);
    assert_eq!(&out[16..20], &[0, 0, 0, 0]);
    assert_eq!(&out[20..28], &1.0f64.to_le_bytes());
    assert_eq!(out.len(), 4 + 16 + 56);
    assert_eq!(decode_pose_stamped(&out).unwrap().frame_id, "");
}

#[test]
fn buffer_is_reused_without_growing() {
    let mut out = Vec::new();
    encode_pose_stamped(
        &mut out,
        RosTime::default(),
        "eventtrack6d_camera",
        [1.0; 3],
        [0.5; 4],
    );
    let (ptr, cap) = (out.as_ptr(), out.capacity());
    for i in 0..100 {
        encode_pose_stamped(
            &mut out,
            RosTime { sec: i, nanosec: 0 },
            "eventtrack6d_camera",
            [1.0; 3],
            [0.5; 4],
        );
    }
    assert_eq!((out.as_ptr(), out.capacity()), (ptr, cap));
}

#[test]
fn decoder_errors_are_specific() {
    let mut good = Vec::new();
    encode_pose_stamped(
        &mut good,
        RosTime::default(),
        "world",
        [0.0; 3],
        [0.0, 0.0, 0.0, 1.0],
    );

    assert!(matches!(
        decode_pose_stamped(&[0, 1]),
        Err(CdrError::Truncated { offset: 0, .. })
    ));
    let mut be = good.clone();
    be[1] = 0x00; // CDR_BE
    assert_eq!(
        decode_pose_stamped(&be),
        Err(CdrError::Encapsulation([0, 0, 0, 0]))
    );
    let mut zero = good.clone();
    zero[12..16].copy_from_slice(&0u32.to_le_bytes());
    assert_eq!(
        decode_pose_stamped(&zero),
        Err(CdrError::ZeroLengthString("header.frame_id"))
    );
    let mut no_nul = good.clone();
    no_nul[21] = b'!';
    assert_eq!(
        decode_pose_stamped(&no_nul),
        Err(CdrError::MissingNul("header.frame_id"))
    );
    let mut bad_utf8 = good.clone();
    bad_utf8[16] = 0xFF;
    assert_eq!(
        decode_pose_stamped(&bad_utf8),
        Err(CdrError::NotUtf8("header.frame_id"))
    );
    let mut huge = good.clone();
    huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        decode_pose_stamped(&huge),
        Err(CdrError::Truncated {
            field: "header.frame_id",
            ..
        })
    ));
    let err = decode_pose_stamped(&good[..good.len() - 1]).unwrap_err();
    assert_eq!(
        err,
        CdrError::Truncated {
            field: "pose.orientation.w",
            offset: 76,
            needed: 8,
            len: 83
        },
        "{err}"
    );
    assert!(err.to_string().contains("pose.orientation.w"));
}

#[test]
fn ros_time_splits_with_floor() {
    assert_eq!(
        RosTime::from_nanos(1_500_000_000).unwrap(),
        RosTime {
            sec: 1,
            nanosec: 500_000_000
        }
    );
    assert_eq!(
        RosTime::from_nanos(-1).unwrap(),
        RosTime {
            sec: -1,
            nanosec: 999_999_999
        }
    );
    assert_eq!(RosTime::from_nanos(-1).unwrap().as_nanos(), -1);
    assert!(matches!(
        RosTime::from_nanos(i64::MAX),
        Err(CdrError::TimeOutOfRange { .. })
    ));
    let max = i64::from(i32::MAX) * 1_000_000_000 + 999_999_999;
    assert_eq!(RosTime::from_nanos(max).unwrap().as_nanos(), max);
}

#[test]
fn golden_attachment() {
    let mut gid = [0u8; GID_LEN];
    for (i, g) in gid.iter_mut().enumerate() {
        *g = 0xA0 + i as u8;
    }
    let a = Attachment {
        sequence_number: 1,
        source_timestamp_ns: 0x0102_0304_0506_0708,
        gid,
    };
    let bytes = a.to_bytes();
    let expected: [u8; 33] = [
        // 0..8: sequence number 1, i64 little-endian.
        0x01, 0, 0, 0, 0, 0, 0, 0, //
        // 8..16: source timestamp 0x0102030405060708 ns, i64 little-endian.
        0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01, //
        // 16: zenoh-ext sequence length of the GID as a LEB128 varint: 16.
        0x10, //
        // 17..33: the 16 GID bytes in order.
        0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7, 0xA8, 0xA9, 0xAA, 0xAB, 0xAC, 0xAD, 0xAE,
        0xAF,
    ];
    // zenoh-ext's serializer (eclipse-zenoh 1.10.2, `z_serialize((Int64(1), Int64(0x0102030405060708),
    // [UInt8(0xA0), ..., UInt8(0xAF)]))`) gives exactly these 33 bytes.
    assert_eq!(bytes, expected);
    assert_eq!(Attachment::from_bytes(&bytes).unwrap(), a);
    assert_eq!(
        Attachment::from_bytes(&bytes[..32]),
        Err(CdrError::AttachmentLength { len: 32 })
    );
    let mut bad = bytes;
    bad[16] = 0x18;
    assert_eq!(
        Attachment::from_bytes(&bad),
        Err(CdrError::AttachmentGidLength(0x18))
    );
    let neg = Attachment {
        sequence_number: -2,
        source_timestamp_ns: -1,
        gid,
    };
    assert_eq!(
        &neg.to_bytes()[0..16],
        &[
            0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
            0xFF, 0xFF
        ]
    );
}

#[test]
fn golden_key_expressions() {
    assert_eq!(
        pose_stamped_key_expr(0, "eventtrack6d/mug/pose"),
        "0/eventtrack6d/mug/pose/geometry_msgs::msg::dds_::PoseStamped_/\
         RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8"
    );
    assert_eq!(
        pose_stamped_key_expr(0, "/eventtrack6d/mug/pose/"),
        pose_stamped_key_expr(0, "eventtrack6d/mug/pose"),
        "leading and trailing slashes are stripped"
    );
    assert!(pose_stamped_key_expr(42, "/a/pose").starts_with("42/a/pose/geometry_msgs::"));
    let node = RosNodeIdentity {
        domain_id: 0,
        zid: "1f2e3d4c5b6a79880011223344556677".into(),
        node_id: 0,
        enclave: "/".into(),
        namespace: "/".into(),
        name: "eventtrack6d".into(),
    };
    assert_eq!(
        node_liveliness_key_expr(&node),
        "@ros2_lv/0/1f2e3d4c5b6a79880011223344556677/0/0/NN/%/%/eventtrack6d"
    );
    assert_eq!(
        publisher_liveliness_key_expr(
            &node,
            3,
            "eventtrack6d/mug/pose",
            POSE_STAMPED_TYPE_NAME,
            POSE_STAMPED_TYPE_HASH,
            DEFAULT_QOS_KEY
        ),
        "@ros2_lv/0/1f2e3d4c5b6a79880011223344556677/0/3/MP/%/%/eventtrack6d/%eventtrack6d%mug%pose/\
         geometry_msgs::msg::dds_::PoseStamped_/\
         RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8/::,:,:,:,,"
    );
    let ns = RosNodeIdentity {
        namespace: "/robot/arm".into(),
        ..node
    };
    assert!(node_liveliness_key_expr(&ns).ends_with("/NN/%/%robot%arm/eventtrack6d"));
}

#[test]
fn name_checks() {
    assert!(check_name_token("mug_2").is_ok());
    assert!(check_name_token("2mug").unwrap_err().contains("digit"));
    assert!(check_name_token("a*b").unwrap_err().contains("'*'"));
    assert!(check_name_token("").is_err());
    assert!(check_name_path("/").is_ok());
    assert!(check_name_path("/robot/arm/").is_ok());
    assert!(check_name_path("robot//arm").is_err());
    assert!(check_name_path("robot/$arm").is_err());
}

#[test]
fn isometry_round_trip() {
    let pose = Isometry3::new(
        nalgebra::Vector3::new(0.1, -0.2, 0.7),
        nalgebra::Vector3::new(0.3, -1.1, 0.25),
    );
    let mut out = Vec::new();
    encode_pose_stamped_isometry(&mut out, RosTime { sec: 5, nanosec: 6 }, "cam", &pose);
    let back = decode_pose_stamped(&out).unwrap().to_isometry();
    assert!((back.translation.vector - pose.translation.vector).norm() < 1e-12);
    assert!(back.rotation.angle_to(&pose.rotation) < 1e-12);
}

proptest! {
    #[test]
    fn encode_decode_round_trip(
        sec in any::<i32>(),
        nanosec in 0u32..1_000_000_000,
        frame in "[a-zA-Z0-9_/]{0,40}",
        position in proptest::array::uniform3(-1e6f64..1e6),
        orientation in proptest::array::uniform4(-1.0f64..1.0),
    ) {
        let mut out = Vec::new();
        let stamp = RosTime { sec, nanosec };
        encode_pose_stamped(&mut out, stamp, &frame, position, orientation);
        prop_assert_eq!(out.len(), pose_stamped_encoded_len(frame.len()));
        prop_assert_eq!((out.len() - 4 - 56) % 8, 0);
        let msg = decode_pose_stamped(&out).unwrap();
        prop_assert_eq!(msg, PoseStampedMsg { stamp, frame_id: frame, position, orientation_xyzw: orientation });
    }

    #[test]
    fn decoder_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = decode_pose_stamped(&bytes);
        let _ = Attachment::from_bytes(&bytes);
    }

    #[test]
    fn decoder_never_panics_on_mutated_messages(
        frame in "[a-z]{0,12}",
        flips in proptest::collection::vec((0usize..100, any::<u8>()), 1..6),
        cut in 0usize..100,
    ) {
        let mut out = Vec::new();
        encode_pose_stamped(&mut out, RosTime::default(), &frame, [1.0; 3], [0.0, 0.0, 0.0, 1.0]);
        for (i, b) in flips {
            if let Some(x) = out.get_mut(i) {
                *x = b;
            }
        }
        out.truncate(cut.max(1));
        let _ = decode_pose_stamped(&out);
    }

    #[test]
    fn attachment_round_trip(seq in any::<i64>(), ts in any::<i64>(), gid in any::<[u8; 16]>()) {
        let a = Attachment { sequence_number: seq, source_timestamp_ns: ts, gid };
        prop_assert_eq!(Attachment::from_bytes(&a.to_bytes()).unwrap(), a);
    }
}
