// Shared by the message targets: the round-trip property every ROS 2 decoder must have.
#![allow(dead_code)]

use ros2::CdrError;
use ros2::PoseStampedMsg;
use ros2::sensor::CameraInfo;
use ros2::tf::TransformStamped;
use ros2::vision::Detection3DArray;
use std::fmt::Debug;

/// `msg` decoded from `data`; `encoded` is the crate's encoding of `msg` and `again` what decoding `encoded` gave.
/// Checks that the encoding decodes to the same message, bit for bit (`floats` lists the message's floats, which
/// are compared by their bits, so that NaNs compare too), that encoding that again gives the same bytes, and that
/// the encoding is the input with its padding and encapsulation options zeroed: never longer than what decoded
/// (the decoders ignore trailing bytes), and equal to it wherever it is not zero.
pub fn check<T: PartialEq + Debug>(
    data: &[u8],
    msg: &T,
    encoded: &[u8],
    again: Result<T, CdrError>,
    encode: impl Fn(&mut Vec<u8>, &T),
    floats: impl Fn(&T) -> Vec<f64>,
) {
    assert!(
        encoded.len() <= data.len(),
        "the encoding ({} bytes) is longer than the input that decoded ({} bytes)",
        encoded.len(),
        data.len()
    );
    assert_eq!(encoded[..2], data[..2], "the encapsulation kind changed");
    for (i, (&e, &d)) in encoded.iter().zip(data).enumerate().skip(2) {
        assert!(
            e == d || e == 0,
            "byte {i} encoded as {e:#04x}, the input has {d:#04x}"
        );
    }
    let again = match again {
        Ok(m) => m,
        Err(e) => panic!("the encoding of {msg:?} does not decode: {e}"),
    };
    let bits = |m: &T| floats(m).into_iter().map(f64::to_bits).collect::<Vec<_>>();
    assert_eq!(
        bits(&again),
        bits(msg),
        "a float changed bits in the round trip"
    );
    if floats(msg).iter().any(|v| v.is_nan()) {
        // NaN != NaN: the bits matched above, the rest must print the same.
        assert_eq!(format!("{again:?}"), format!("{msg:?}"));
    } else {
        assert_eq!(&again, msg);
    }
    let mut twice = Vec::new();
    encode(&mut twice, &again);
    assert_eq!(twice, encoded, "the re-decoded message encodes differently");
}

/// For messages without floats.
pub fn no_floats<T>(_: &T) -> Vec<f64> {
    Vec::new()
}

pub fn pose_stamped_floats(m: &PoseStampedMsg) -> Vec<f64> {
    m.position
        .iter()
        .chain(&m.orientation_xyzw)
        .copied()
        .collect()
}

pub fn tf_floats(m: &Vec<TransformStamped>) -> Vec<f64> {
    m.iter()
        .flat_map(|t| t.translation.iter().chain(&t.rotation_xyzw))
        .copied()
        .collect()
}

pub fn detection3d_array_floats(m: &Detection3DArray) -> Vec<f64> {
    let mut v = Vec::new();
    for d in &m.detections {
        for h in &d.results {
            v.push(h.score);
            v.extend(h.pose.position.iter().chain(&h.pose.orientation_xyzw));
            v.extend(h.covariance);
        }
        v.extend(
            d.bbox_center
                .position
                .iter()
                .chain(&d.bbox_center.orientation_xyzw),
        );
        v.extend(d.bbox_size);
    }
    v
}

pub fn camera_info_floats(m: &CameraInfo) -> Vec<f64> {
    m.d.iter()
        .chain(&m.k)
        .chain(&m.r)
        .chain(&m.p)
        .copied()
        .collect()
}
