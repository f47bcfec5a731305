//! The `ros2` crate's messages against an independent ROS 2 type system: the `rosbags` Python package
//! (`tests/ros2/rosbags_check.py`; installed by `.ci/setup`, `pip install rosbags==0.11.9`), whose typestore is ROS 2
//! Jazzy's plus vision_msgs 4.x, event_camera_msgs and std_srvs/Trigger from their .msg definitions.
//!
//! - Every type hash in `ros2::types::ALL` is the one rosbags computes from the type definitions (RIHS01).
//! - Every message type: our encoding read by rosbags gives every field back (floats to the bit); rosbags'
//!   encoding of the same message is byte for byte ours; our decoder reads rosbags' encoding back to the message.
//!   Strings of every length modulo 8 (and odd ones elsewhere) put each kind of alignment padding on the wire.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use eventtrack6d_tests::rosbags::{assert_fields, rosbags, rosbags_decode, script};
use ros2::diagnostic::{
    DiagnosticArray, DiagnosticStatus, decode_diagnostic_array, encode_diagnostic_array, level,
};
use ros2::sensor::{
    CameraInfo, EventPacket, Image, decode_camera_info, decode_event_packet, decode_image,
    encode_camera_info, encode_event_packet, encode_image,
};
use ros2::tf::{TransformStamped, decode_tf_message, encode_tf_message};
use ros2::trigger::{
    TriggerResponse, decode_trigger_request, decode_trigger_response, encode_trigger_request,
    encode_trigger_response,
};
use ros2::vision::{
    Detection3D, Detection3DArray, ObjectHypothesisWithPose, decode_detection3d_array,
    encode_detection3d_array,
};
use ros2::{Header, Pose, PoseStampedMsg, RosTime, decode_pose_stamped, encode_pose_stamped};
use serde_json::{Value, json};
use std::process::{Command, Stdio};

// --- the independent reader -------------------------------------------------------------------------------------

/// `msg` (the script's JSON form) encoded by rosbags as `ty`.
fn rosbags_encode(ty: &str, msg: &Value) -> Vec<u8> {
    rosbags(&["encode", ty], msg.to_string().as_bytes())
}

// --- comparing ---------------------------------------------------------------------------------------------------

/// rosbags' encoding equals ours byte for byte; otherwise the first difference, with the bytes around it.
fn assert_same_bytes(ty: &str, theirs: &[u8], ours: &[u8]) {
    if theirs == ours {
        return;
    }
    let at = theirs
        .iter()
        .zip(ours)
        .position(|(a, b)| a != b)
        .unwrap_or(theirs.len().min(ours.len()));
    let window = |b: &[u8]| {
        format!(
            "{:02x?}",
            &b[at.saturating_sub(8).min(b.len())..(at + 16).min(b.len())]
        )
    };
    panic!(
        "{ty}: rosbags encodes {} bytes, we {}; first difference at byte {at} (from the encapsulation header); \
         bytes from {}: rosbags {}, ours {}",
        theirs.len(),
        ours.len(),
        at.saturating_sub(8),
        window(theirs),
        window(ours)
    );
}

/// The whole check for one type: each message encoded by us is read by rosbags with every field as `to_json`
/// gives it; for the first `reverse` messages, rosbags encodes that JSON to our bytes exactly and `read_back`
/// (our decoder) recovers the message from rosbags' bytes.
fn check_both_ways<M>(
    ty: &str,
    msgs: &[M],
    reverse: usize,
    encode: impl Fn(&M) -> Vec<u8>,
    to_json: impl Fn(&M) -> Value,
    read_back: impl Fn(&[u8], &M),
) {
    let ours: Vec<Vec<u8>> = msgs.iter().map(&encode).collect();
    let decoded = rosbags_decode(ty, &ours);
    for (i, (m, d)) in msgs.iter().zip(&decoded).enumerate() {
        assert_fields(d, &to_json(m), &format!("{ty} #{i}"));
    }
    for (m, bytes) in msgs.iter().zip(&ours).take(reverse) {
        let theirs = rosbags_encode(ty, &to_json(m));
        assert_same_bytes(ty, &theirs, bytes);
        read_back(&theirs, m);
    }
}

fn encoded(f: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut out = Vec::new();
    f(&mut out);
    out
}

// --- JSON forms of the shared pieces ------------------------------------------------------------------------------

fn time_json(t: RosTime) -> Value {
    json!({"sec": t.sec, "nanosec": t.nanosec})
}

fn header_json(h: &Header) -> Value {
    json!({"stamp": time_json(h.stamp), "frame_id": h.frame_id})
}

fn vec3_json(v: [f64; 3]) -> Value {
    json!({"x": v[0], "y": v[1], "z": v[2]})
}

fn quat_json(q: [f64; 4]) -> Value {
    json!({"x": q[0], "y": q[1], "z": q[2], "w": q[3]})
}

fn pose_json(p: &Pose) -> Value {
    json!({"position": vec3_json(p.position), "orientation": quat_json(p.orientation_xyzw)})
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// A frame id of `n` characters (`n` modulo 8 picks the padding after it).
fn frame(n: usize) -> String {
    "camera_optical_frame_0123456789"
        .chars()
        .cycle()
        .take(n)
        .collect()
}

/// Awkward floats: not exactly representable in decimal, tiny, huge, negative zero, subnormal, extremes.
const FLOATS: [f64; 12] = [
    0.1,
    -1.0 / 3.0,
    1e-7,
    -0.0,
    6.02214076e23,
    5e-324,
    f64::MAX,
    f64::MIN_POSITIVE,
    std::f64::consts::PI,
    -2.5e-5,
    1e16,
    123_456.789_012_345_68,
];

fn float(i: usize) -> f64 {
    FLOATS[i % FLOATS.len()]
}

fn pose(seed: usize) -> Pose {
    Pose {
        position: [float(seed), float(seed + 1), float(seed + 2)],
        // Any four numbers: the wire does not care whether they are a unit quaternion.
        orientation_xyzw: [float(seed + 3), float(seed + 4), 0.5, float(seed + 5)],
    }
}

// --- the tests ------------------------------------------------------------------------------------------------------

#[test]
fn type_hashes_are_the_ones_rosbags_computes_from_the_definitions() {
    let names: Vec<&str> = ros2::types::ALL.iter().map(|t| t.name).collect();
    let mut args = vec!["hashes"];
    args.extend(&names);
    let out: Value = serde_json::from_slice(&rosbags(&args, b"")).unwrap();
    for t in ros2::types::ALL {
        assert_eq!(
            out[t.name].as_str(),
            Some(t.hash),
            "{}: rosbags computes {}, ros2::types has {}",
            t.name,
            out[t.name],
            t.hash
        );
        // The key-expression name is the ROS name in DDS form.
        let [pkg, kind, name] = t.name.split('/').collect::<Vec<_>>()[..] else {
            panic!("{}: not package/kind/Type", t.name);
        };
        assert_eq!(t.key_name, format!("{pkg}::{kind}::dds_::{name}_"));
    }
    assert_eq!(out.as_object().unwrap().len(), ros2::types::ALL.len());
}

#[test]
fn pose_stamped_both_ways() {
    // Frame ids of 0..=8 characters: every padding before the 8-aligned pose.
    let msgs: Vec<PoseStampedMsg> = (0..=8)
        .map(|n| {
            let p = pose(n);
            PoseStampedMsg {
                stamp: RosTime {
                    sec: 1_700_000_000 + n as i32,
                    nanosec: 999_999_999 - n as u32,
                },
                frame_id: frame(n),
                position: p.position,
                orientation_xyzw: p.orientation_xyzw,
            }
        })
        .chain([PoseStampedMsg {
            stamp: RosTime {
                sec: -1,
                nanosec: 0,
            },
            frame_id: "ü/ß".into(),
            position: [0.0; 3],
            orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
        }])
        .collect();
    check_both_ways(
        "geometry_msgs/msg/PoseStamped",
        &msgs,
        3,
        |m| {
            encoded(|o| {
                encode_pose_stamped(o, m.stamp, &m.frame_id, m.position, m.orientation_xyzw)
            })
        },
        |m| {
            json!({
                "header": header_json(&Header::new(m.stamp, &m.frame_id)),
                "pose": pose_json(&Pose { position: m.position, orientation_xyzw: m.orientation_xyzw }),
            })
        },
        |b, m| assert_eq!(&decode_pose_stamped(b).unwrap(), m),
    );
}

fn transform(i: usize, parent: usize, child: usize) -> TransformStamped {
    let p = pose(i);
    TransformStamped {
        header: Header::new(
            RosTime {
                sec: 12 + i as i32,
                nanosec: 345_678 * i as u32,
            },
            &frame(parent),
        ),
        child_frame_id: frame(child),
        translation: p.position,
        rotation_xyzw: p.orientation_xyzw,
    }
}

#[test]
fn tf_message_both_ways() {
    let msgs = vec![
        vec![transform(0, 5, 3), transform(1, 1, 6)],
        vec![transform(2, 7, 0), transform(3, 0, 7)],
        vec![],
    ];
    check_both_ways(
        "tf2_msgs/msg/TFMessage",
        &msgs,
        2,
        |m| encoded(|o| encode_tf_message(o, m)),
        |m| {
            let transforms: Vec<Value> = m
                .iter()
                .map(|t| {
                    json!({
                        "header": header_json(&t.header),
                        "child_frame_id": t.child_frame_id,
                        "transform": {
                            "translation": vec3_json(t.translation),
                            "rotation": quat_json(t.rotation_xyzw),
                        },
                    })
                })
                .collect();
            json!({ "transforms": transforms })
        },
        |b, m| assert_eq!(&decode_tf_message(b).unwrap(), m),
    );
}

fn detection(i: usize, hypotheses: usize) -> Detection3D {
    Detection3D {
        header: Header::new(
            RosTime {
                sec: 40 + i as i32,
                nanosec: 7 * i as u32,
            },
            &frame(2 * i + 1),
        ),
        results: (0..hypotheses)
            .map(|k| ObjectHypothesisWithPose {
                class_id: frame(3 + k + i),
                score: float(i + k + 7),
                pose: pose(i + k),
                covariance: std::array::from_fn(|j| float(j + k) / (j as f64 - 2.5)),
            })
            .collect(),
        bbox_center: pose(i + 4),
        bbox_size: [0.071, 0.123, float(i + 2)],
        id: format!("obj{i}-x"),
    }
}

#[test]
fn detection3d_array_both_ways() {
    let msgs = vec![
        Detection3DArray {
            header: Header::new(RosTime { sec: 3, nanosec: 1 }, &frame(5)),
            detections: vec![detection(0, 1), detection(1, 2)],
        },
        Detection3DArray {
            header: Header::new(RosTime { sec: 0, nanosec: 0 }, ""),
            detections: vec![detection(2, 0), detection(3, 1)],
        },
        Detection3DArray {
            header: Header::new(RosTime { sec: 9, nanosec: 9 }, &frame(6)),
            detections: vec![],
        },
    ];
    check_both_ways(
        "vision_msgs/msg/Detection3DArray",
        &msgs,
        2,
        |m| encoded(|o| encode_detection3d_array(o, m)),
        |m| {
            let detections: Vec<Value> = m
                .detections
                .iter()
                .map(|d| {
                    let results: Vec<Value> = d
                        .results
                        .iter()
                        .map(|h| {
                            json!({
                                "hypothesis": {"class_id": h.class_id, "score": h.score},
                                "pose": {"pose": pose_json(&h.pose), "covariance": h.covariance.to_vec()},
                            })
                        })
                        .collect();
                    json!({
                        "header": header_json(&d.header),
                        "results": results,
                        "bbox": {"center": pose_json(&d.bbox_center), "size": vec3_json(d.bbox_size)},
                        "id": d.id,
                    })
                })
                .collect();
            json!({"header": header_json(&m.header), "detections": detections})
        },
        |b, m| assert_eq!(&decode_detection3d_array(b).unwrap(), m),
    );
}

#[test]
fn diagnostic_array_both_ways() {
    let status = |lvl: u8, name: &str, values: &[(&str, &str)]| DiagnosticStatus {
        level: lvl,
        name: name.into(),
        message: format!("{name} is {lvl}"),
        hardware_id: frame(lvl as usize * 3 + 1),
        values: values
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect(),
    };
    let msgs = vec![
        DiagnosticArray {
            header: Header::new(
                RosTime {
                    sec: 5,
                    nanosec: 50,
                },
                &frame(3),
            ),
            status: vec![
                status(
                    level::OK,
                    "eventtrack6d: can",
                    &[("quality", "0.93"), ("state", "tracking"), ("x", "")],
                ),
                status(level::WARN, "eventtrack6d: box", &[("quality", "0.4")]),
            ],
        },
        DiagnosticArray {
            header: Header::new(RosTime { sec: 6, nanosec: 0 }, ""),
            status: vec![
                status(level::ERROR, "a", &[]),
                status(level::STALE, "odd name", &[("k", "vv"), ("kkk", "v")]),
            ],
        },
    ];
    check_both_ways(
        "diagnostic_msgs/msg/DiagnosticArray",
        &msgs,
        2,
        |m| encoded(|o| encode_diagnostic_array(o, m)),
        |m| {
            let status: Vec<Value> = m
                .status
                .iter()
                .map(|s| {
                    let values: Vec<Value> = s
                        .values
                        .iter()
                        .map(|(k, v)| json!({"key": k, "value": v}))
                        .collect();
                    json!({
                        "level": s.level,
                        "name": s.name,
                        "message": s.message,
                        "hardware_id": s.hardware_id,
                        "values": values,
                    })
                })
                .collect();
            json!({"header": header_json(&m.header), "status": status})
        },
        |b, m| assert_eq!(&decode_diagnostic_array(b).unwrap(), m),
    );
}

#[test]
fn event_packet_both_ways() {
    let raw: Vec<u8> = (0..13u8).map(|i| i.wrapping_mul(37) ^ 0xa5).collect();
    let msgs = vec![
        EventPacket {
            header: Header::new(
                RosTime {
                    sec: 1_700_000_001,
                    nanosec: 123,
                },
                &frame(3),
            ),
            height: 720,
            width: 1280,
            seq: 42,
            time_base: u64::MAX - 1,
            encoding: "evt3".into(),
            is_bigendian: false,
            events: &raw,
        },
        EventPacket {
            header: Header::new(RosTime { sec: 2, nanosec: 0 }, &frame(8)),
            height: 480,
            width: 640,
            seq: 1 << 40,
            time_base: 0,
            encoding: "mono".into(),
            is_bigendian: true,
            events: &raw[..7],
        },
        EventPacket {
            header: Header::new(RosTime { sec: 0, nanosec: 1 }, ""),
            height: 0,
            width: 0,
            seq: 0,
            time_base: 7,
            encoding: "trigger".into(),
            is_bigendian: false,
            events: &[],
        },
    ];
    check_both_ways(
        "event_camera_msgs/msg/EventPacket",
        &msgs,
        2,
        |m| encoded(|o| encode_event_packet(o, m)),
        |m| {
            json!({
                "header": header_json(&m.header),
                "height": m.height,
                "width": m.width,
                "seq": m.seq,
                "time_base": m.time_base,
                "encoding": m.encoding,
                "is_bigendian": m.is_bigendian,
                "events": hex(m.events),
            })
        },
        |b, m| assert_eq!(&decode_event_packet(b).unwrap(), m),
    );
}

#[test]
fn image_16uc1_both_ways() {
    // 5 x 3 depth image, 16-bit little-endian millimetres.
    let depth: Vec<u8> = (0..15u16)
        .flat_map(|i| (1000 + 257 * i).to_le_bytes())
        .collect();
    let msgs = vec![
        Image {
            header: Header::new(
                RosTime {
                    sec: 77,
                    nanosec: 500_000_000,
                },
                "camera_depth_optical_frame",
            ),
            height: 3,
            width: 5,
            encoding: "16UC1".into(),
            is_bigendian: 0,
            step: 10,
            data: &depth,
        },
        Image {
            header: Header::new(RosTime { sec: 1, nanosec: 2 }, &frame(1)),
            height: 1,
            width: 3,
            encoding: "16UC1".into(),
            is_bigendian: 0,
            step: 6,
            data: &depth[..6],
        },
    ];
    check_both_ways(
        "sensor_msgs/msg/Image",
        &msgs,
        2,
        |m| encoded(|o| encode_image(o, m)),
        |m| {
            json!({
                "header": header_json(&m.header),
                "height": m.height,
                "width": m.width,
                "encoding": m.encoding,
                "is_bigendian": m.is_bigendian,
                "step": m.step,
                "data": hex(m.data),
            })
        },
        |b, m| assert_eq!(&decode_image(b).unwrap(), m),
    );
}

#[test]
fn camera_info_both_ways() {
    let info = |frame_id: &str, model: &str, d: Vec<f64>, rectify: bool| CameraInfo {
        header: Header::new(
            RosTime {
                sec: 77,
                nanosec: 500_000_001,
            },
            frame_id,
        ),
        height: 480,
        width: 640,
        distortion_model: model.into(),
        d,
        k: [615.123, 0.0, 320.5, 0.0, 615.987, 240.25, 0.0, 0.0, 1.0],
        r: std::array::from_fn(|i| if i % 4 == 0 { 1.0 } else { float(i) }),
        p: std::array::from_fn(|i| float(i + 3)),
        binning_x: 1,
        binning_y: 2,
        roi: [3, 5, 101, 203],
        roi_do_rectify: rectify,
    };
    let msgs = vec![
        info(
            "camera_color_optical_frame",
            "plumb_bob",
            vec![0.1, -0.25, 1e-3, -2e-4, 0.0],
            true,
        ),
        info(
            &frame(4),
            "rational_polynomial",
            (0..8).map(float).collect(),
            false,
        ),
        info("", "", vec![], false),
    ];
    check_both_ways(
        "sensor_msgs/msg/CameraInfo",
        &msgs,
        2,
        |m| encoded(|o| encode_camera_info(o, m)),
        |m| {
            json!({
                "header": header_json(&m.header),
                "height": m.height,
                "width": m.width,
                "distortion_model": m.distortion_model,
                "d": m.d,
                "k": m.k.to_vec(),
                "r": m.r.to_vec(),
                "p": m.p.to_vec(),
                "binning_x": m.binning_x,
                "binning_y": m.binning_y,
                "roi": {
                    "x_offset": m.roi[0],
                    "y_offset": m.roi[1],
                    "height": m.roi[2],
                    "width": m.roi[3],
                    "do_rectify": m.roi_do_rectify,
                },
            })
        },
        |b, m| assert_eq!(&decode_camera_info(b).unwrap(), m),
    );
}

#[test]
fn trigger_both_ways() {
    let msgs = vec![
        TriggerResponse {
            success: true,
            message: "recording started".into(),
        },
        TriggerResponse {
            success: false,
            message: "no".into(),
        },
        TriggerResponse {
            success: true,
            message: String::new(),
        },
    ];
    check_both_ways(
        "std_srvs/srv/Trigger_Response",
        &msgs,
        2,
        |m| encoded(|o| encode_trigger_response(o, m)),
        |m| json!({"success": m.success, "message": m.message}),
        |b, m| assert_eq!(&decode_trigger_response(b).unwrap(), m),
    );
    check_both_ways(
        "std_srvs/srv/Trigger_Request",
        &[()],
        1,
        |()| encoded(encode_trigger_request),
        |()| json!({"structure_needs_at_least_one_member": 0}),
        |b, ()| decode_trigger_request(b).unwrap(),
    );
}

/// The comparison itself sees a wrong field: a check that always passed would prove nothing.
#[test]
fn a_wrong_field_is_reported() {
    let m = TriggerResponse {
        success: true,
        message: "abc".into(),
    };
    let ours = encoded(|o| encode_trigger_response(o, &m));
    let decoded = rosbags_decode("std_srvs/srv/Trigger_Response", &[ours]);
    let wrong = [
        json!({"success": false, "message": "abc"}),
        json!({"success": true, "message": "abd"}),
        json!({"success": true}),
    ];
    for w in wrong {
        let caught = std::panic::catch_unwind(|| assert_fields(&decoded[0], &w, "t"));
        assert!(caught.is_err(), "{w} passed against {}", decoded[0]);
    }
    let p = pose(0);
    let bytes = encoded(|o| {
        encode_pose_stamped(o, RosTime::default(), "f", p.position, p.orientation_xyzw)
    });
    let decoded = rosbags_decode("geometry_msgs/msg/PoseStamped", &[bytes]);
    let mut off_by_one_ulp = p;
    off_by_one_ulp.position[0] = f64::from_bits(p.position[0].to_bits() + 1);
    let w = json!({
        "header": header_json(&Header::new(RosTime::default(), "f")),
        "pose": pose_json(&off_by_one_ulp),
    });
    let caught = std::panic::catch_unwind(|| assert_fields(&decoded[0], &w, "p"));
    assert!(caught.is_err(), "one ulp off passed");
}

/// Bad input makes the script say what is wrong and exit with 2.
#[test]
fn the_script_refuses_bad_input_clearly() {
    let run = |args: &[&str]| {
        Command::new("python3")
            .arg(script())
            .args(args)
            .stdin(Stdio::null())
            .output()
            .unwrap()
    };
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.cdr");
    std::fs::write(&junk, [0u8, 1, 0, 0, 0xff, 0xff, 0xff, 0x7f]).unwrap();
    let junk = junk.to_str().unwrap();
    for (args, says) in [
        (vec!["hashes", "nope_msgs/msg/Nope"], "unknown type"),
        (vec!["decode", "nope_msgs/msg/Nope", junk], "unknown type"),
        (
            vec!["decode", "sensor_msgs/msg/Image", "/nonexistent/x.cdr"],
            "cannot read",
        ),
        (
            vec!["decode", "std_srvs/srv/Trigger_Response", junk],
            "not a CDR",
        ),
    ] {
        let out = run(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
