//! What the ROS 2 source receives: the three subscriptions on their rmw_zenoh keys (with the liveliness tokens
//! that show them in the ROS 2 graph), each sample decoded and checked on zenoh's thread and handed to the source
//! thread through a bounded queue (a full queue makes zenoh wait: nothing is dropped here), and the conversion of
//! depth images into depth frames.

use crate::publish::ros2::sensor::{
    CameraInfo, decode_camera_info, decode_event_packet, decode_image,
};
use crate::publish::ros2::{self, EntityKind, RosNodeIdentity, types};
use drivers::recording::{CameraIntrinsics, DepthFrame};
use std::sync::mpsc::SyncSender;
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Subscriber;

/// Turns a sample's payload into what the source thread receives.
type Handler = Box<dyn Fn(&[u8]) -> Ros2Input + Send + Sync>;

/// Samples waiting for the source thread at most.
pub const INPUT_QUEUE_LEN: usize = 4096;

/// One received sample.
#[derive(Debug)]
pub enum Ros2Input {
    /// An `EventPacket` with `evt3` bytes.
    Events {
        /// `seq`.
        seq: u64,
        /// `header.stamp`, nanoseconds.
        stamp_ns: i64,
        /// The EVT3 bytes.
        bytes: Vec<u8>,
    },
    /// A depth image, converted.
    Depth {
        /// `header.stamp`, nanoseconds.
        stamp_ns: i64,
        /// The frame, metres.
        frame: Box<DepthFrame>,
    },
    /// A `CameraInfo` of the depth camera.
    Info(Box<CameraInfo>),
    /// A sample that cannot be used: which kind (a short key for the counters) and why.
    Unusable {
        /// Counter key, e.g. `events: encoding`.
        kind: String,
        /// What is wrong.
        message: String,
    },
}

/// The sizes the samples must have.
#[derive(Debug, Clone)]
pub struct Expected {
    /// Event camera width and height, pixels.
    pub events: (u32, u32),
    /// Depth camera width and height, pixels.
    pub depth: (u32, u32),
}

/// The declared subscriptions; undeclared when dropped.
pub struct Subscriptions {
    _subscribers: Vec<Subscriber<()>>,
    _tokens: Vec<LivelinessToken>,
}

/// The three topics to read.
pub struct Topics<'a> {
    /// EventPacket topic.
    pub events: &'a str,
    /// Depth Image topic.
    pub depth: &'a str,
    /// CameraInfo topic.
    pub camera_info: &'a str,
}

/// Subscribes to the three topics as entities 1..=3 of `node`, sending what arrives into `tx`.
pub fn subscribe(
    session: &zenoh::Session,
    node: &RosNodeIdentity,
    topics: &Topics<'_>,
    expected: Expected,
    tx: SyncSender<Ros2Input>,
) -> Result<Subscriptions, String> {
    let mut subscribers = Vec::new();
    let mut tokens = Vec::new();
    let mut token = |entity: u64, topic: &str, ty: &ros2::RosType| -> Result<(), String> {
        let key = ros2::entity_liveliness_key_expr(
            node,
            entity,
            EntityKind::Subscription,
            topic,
            ty,
            ros2::DEFAULT_QOS_KEY,
        );
        tokens.push(
            session
                .liveliness()
                .declare_token(key.clone())
                .wait()
                .map_err(|e| {
                    format!("zenoh: could not declare the liveliness token {key:?}: {e}")
                })?,
        );
        Ok(())
    };
    let declare = |topic: &str, ty: &ros2::RosType, handle: Handler| {
        let key = ros2::typed_key_expr(node.domain_id, topic, ty);
        let tx = tx.clone();
        session
            .declare_subscriber(key.clone())
            .callback(move |sample| {
                // The source thread has stopped when this fails; nothing is left to tell.
                let _ = tx.send(handle(&sample.payload().to_bytes()));
            })
            .wait()
            .map_err(|e| format!("zenoh: could not subscribe to {key:?}: {e}"))
    };
    let ev = expected.clone();
    subscribers.push(declare(
        topics.events,
        &types::EVENT_PACKET,
        Box::new(move |b| event_packet(b, &ev)),
    )?);
    token(1, topics.events, &types::EVENT_PACKET)?;
    let dp = expected.clone();
    subscribers.push(declare(
        topics.depth,
        &types::IMAGE,
        Box::new(move |b| depth_image(b, &dp)),
    )?);
    token(2, topics.depth, &types::IMAGE)?;
    subscribers.push(declare(
        topics.camera_info,
        &types::CAMERA_INFO,
        Box::new(camera_info),
    )?);
    token(3, topics.camera_info, &types::CAMERA_INFO)?;
    Ok(Subscriptions {
        _subscribers: subscribers,
        _tokens: tokens,
    })
}

fn unusable(kind: &str, message: String) -> Ros2Input {
    Ros2Input::Unusable {
        kind: kind.to_owned(),
        message,
    }
}

/// An `EventPacket`, checked: CDR, encoding `evt3`, little-endian, the event camera's size.
fn event_packet(bytes: &[u8], expected: &Expected) -> Ros2Input {
    let p = match decode_event_packet(bytes) {
        Ok(p) => p,
        Err(e) => return unusable("events: not an EventPacket", e.to_string()),
    };
    if p.encoding != "evt3" {
        return unusable(
            "events: encoding",
            format!(
                "encoding {:?} (only evt3 is read: set metavision_driver's encoding to evt3)",
                p.encoding
            ),
        );
    }
    if p.is_bigendian {
        return unusable(
            "events: big-endian",
            "is_bigendian is true (EVT 3.0 words are little-endian)".into(),
        );
    }
    if (p.width, p.height) != expected.events {
        return unusable(
            "events: size",
            format!(
                "{}x{} pixels, the calibration's event camera is {}x{}",
                p.width, p.height, expected.events.0, expected.events.1
            ),
        );
    }
    Ros2Input::Events {
        seq: p.seq,
        stamp_ns: p.header.stamp.as_nanos(),
        bytes: p.events.to_vec(),
    }
}

/// A depth `Image`, checked and converted to metres: `16UC1` millimetres or `32FC1` metres (either byte order),
/// the depth camera's size, rows of `step` bytes. Non-finite or negative depths are invalid (0).
fn depth_image(bytes: &[u8], expected: &Expected) -> Ros2Input {
    let m = match decode_image(bytes) {
        Ok(m) => m,
        Err(e) => return unusable("depth: not an Image", e.to_string()),
    };
    let (w, h) = (m.width, m.height);
    if (w, h) != expected.depth {
        return unusable(
            "depth: size",
            format!(
                "{w}x{h} pixels, the calibration's depth camera is {}x{}",
                expected.depth.0, expected.depth.1
            ),
        );
    }
    let bpp = match m.encoding.as_str() {
        "16UC1" | "mono16" => 2usize,
        "32FC1" => 4,
        other => {
            return unusable(
                "depth: encoding",
                format!("encoding {other:?} (depth is read as 16UC1 millimetres or 32FC1 metres)"),
            );
        }
    };
    let (w, h, step) = (w as usize, h as usize, m.step as usize);
    if step < w * bpp || m.data.len() < step * h {
        return unusable(
            "depth: data",
            format!(
                "step {step} and {} data bytes do not hold {w}x{h} pixels of {bpp} bytes",
                m.data.len()
            ),
        );
    }
    let big = m.is_bigendian != 0;
    let mut depth_m = Vec::with_capacity(w * h);
    for row in m.data.chunks_exact(step).take(h) {
        for px in row[..w * bpp].chunks_exact(bpp) {
            let v = if bpp == 2 {
                let u = if big {
                    u16::from_be_bytes([px[0], px[1]])
                } else {
                    u16::from_le_bytes([px[0], px[1]])
                };
                f32::from(u) * 0.001
            } else {
                let b = [px[0], px[1], px[2], px[3]];
                let f = if big {
                    f32::from_be_bytes(b)
                } else {
                    f32::from_le_bytes(b)
                };
                if f.is_finite() && f > 0.0 { f } else { 0.0 }
            };
            depth_m.push(v);
        }
    }
    Ros2Input::Depth {
        stamp_ns: m.header.stamp.as_nanos(),
        frame: Box::new(DepthFrame {
            index: 0,
            width: w as u32,
            height: h as u32,
            depth_m,
        }),
    }
}

fn camera_info(bytes: &[u8]) -> Ros2Input {
    match decode_camera_info(bytes) {
        Ok(info) => Ros2Input::Info(Box::new(info)),
        Err(e) => unusable("camera_info: not a CameraInfo", e.to_string()),
    }
}

/// Why a `CameraInfo` disagrees with the calibration's depth camera (size, or fx, fy, cx, cy by more than a
/// hundredth of a pixel), if it does.
pub fn camera_info_mismatch(info: &CameraInfo, depth: &CameraIntrinsics) -> Option<String> {
    if (info.width, info.height) != (depth.width, depth.height) {
        return Some(format!(
            "CameraInfo is {}x{}, the calibration's depth camera {}x{}",
            info.width, info.height, depth.width, depth.height
        ));
    }
    let k = info.k;
    let pairs = [
        ("fx", k[0], depth.fx),
        ("fy", k[4], depth.fy),
        ("cx", k[2], depth.cx),
        ("cy", k[5], depth.cy),
    ];
    pairs
        .iter()
        .find(|(_, got, want)| (got - want).abs() > 0.01 || !got.is_finite())
        .map(|(name, got, want)| {
            format!("CameraInfo {name} = {got}, the calibration's depth camera has {want}")
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::publish::ros2::sensor::{Image, encode_image};
    use crate::publish::ros2::{Header, RosTime};

    fn image(encoding: &str, big: u8, step: u32, data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        encode_image(
            &mut out,
            &Image {
                header: Header::new(RosTime { sec: 1, nanosec: 2 }, "d"),
                height: 2,
                width: 2,
                encoding: encoding.into(),
                is_bigendian: big,
                step,
                data,
            },
        );
        out
    }

    #[test]
    fn depth_images_become_metres_or_are_refused_with_the_reason() {
        let expected = Expected {
            events: (8, 8),
            depth: (2, 2),
        };
        // 16UC1 with a padded row: 1000 mm, 0, 250 mm, 65535 mm.
        let mut data = Vec::new();
        for (a, b) in [(1000u16, 0u16), (250, 65535)] {
            data.extend_from_slice(&a.to_le_bytes());
            data.extend_from_slice(&b.to_le_bytes());
            data.extend_from_slice(&[9, 9]);
        }
        let Ros2Input::Depth { stamp_ns, frame } =
            depth_image(&image("16UC1", 0, 6, &data), &expected)
        else {
            panic!("refused")
        };
        assert_eq!(stamp_ns, 1_000_000_002);
        assert_eq!(frame.depth_m, vec![1.0, 0.0, 0.25, 65.535]);
        let f: Vec<u8> = [0.5f32, f32::NAN, -1.0, 2.0]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        let Ros2Input::Depth { frame, .. } = depth_image(&image("32FC1", 1, 8, &f), &expected)
        else {
            panic!("refused")
        };
        assert_eq!(frame.depth_m, vec![0.5, 0.0, 0.0, 2.0]);
        for (bytes, kind) in [
            (image("rgb8", 0, 6, &[0; 12]), "depth: encoding"),
            (image("16UC1", 0, 2, &[0; 8]), "depth: data"),
            (image("16UC1", 0, 4, &[0; 7]), "depth: data"),
            (vec![0, 1, 0, 0, 1], "depth: not an Image"),
        ] {
            match depth_image(&bytes, &expected) {
                Ros2Input::Unusable { kind: k, .. } => assert_eq!(k, kind),
                other => panic!("{other:?}"),
            }
        }
        let small = Expected {
            events: (8, 8),
            depth: (4, 2),
        };
        assert!(
            matches!(depth_image(&image("16UC1", 0, 4, &[0; 8]), &small), Ros2Input::Unusable { kind, .. } if kind == "depth: size")
        );
    }
}
