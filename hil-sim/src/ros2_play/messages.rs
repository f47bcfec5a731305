//! The messages `ros2-play` publishes, as realsense-ros and metavision_driver fill them, encoded in CDR.

use super::Ros2PlayError;
use drivers::recording::CameraIntrinsics;
use ros2::sensor::{CameraInfo, EventPacket, Image};
use ros2::{Header, RosTime};

/// `header.stamp` of a message about stream time `t_us`: `offset_ns + 1000 * t_us`, as a ROS time.
pub fn stamp(offset_ns: i64, t_us: i64) -> Result<RosTime, Ros2PlayError> {
    let ns = t_us
        .checked_mul(1000)
        .and_then(|ns| ns.checked_add(offset_ns));
    ns.and_then(|ns| RosTime::from_nanos(ns).ok())
        .ok_or(Ros2PlayError::Stamp { t_us, offset_ns })
}

/// The fields of every `EventPacket` but its header, sequence number and bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventCamera {
    /// Sensor width, pixels.
    pub width: u32,
    /// Sensor height, pixels.
    pub height: u32,
}

/// An `event_camera_msgs/msg/EventPacket` carrying `events` (raw EVT 3.0), encoded.
pub fn event_packet(camera: EventCamera, header: Header, seq: u64, events: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(events.len() + 96);
    ros2::sensor::encode_event_packet(
        &mut out,
        &EventPacket {
            header,
            height: camera.height,
            width: camera.width,
            seq,
            time_base: 0,
            encoding: "evt3".into(),
            is_bigendian: false,
            events,
        },
    );
    out
}

/// The `16UC1` bytes (millimetres, little-endian, row-major) of a depth image stored in units of `scale_m` metres.
/// Millimetre units (0.001, the recordings' default) pass through unchanged, so a reader gets the stored frame bit
/// for bit; other units are converted to the nearest millimetre (saturating at 65535 mm), 0 staying 0 (invalid).
pub fn depth_16uc1(units: &[u16], scale_m: f64) -> Vec<u8> {
    let millimetres = is_millimetres(scale_m);
    let mut out = Vec::with_capacity(units.len() * 2);
    for &u in units {
        let mm = if millimetres {
            u
        } else {
            (f64::from(u) * scale_m * 1000.0).round().min(65535.0) as u16
        };
        out.extend_from_slice(&mm.to_le_bytes());
    }
    out
}

/// Whether depth units of `scale_m` metres are millimetres (so [`depth_16uc1`] passes them through).
pub fn is_millimetres(scale_m: f64) -> bool {
    (scale_m * 1000.0 - 1.0).abs() < 1e-12
}

/// A `sensor_msgs/msg/Image` of `16UC1` depth (`data` from [`depth_16uc1`]), encoded.
pub fn depth_image(camera: &CameraIntrinsics, header: Header, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + 96);
    ros2::sensor::encode_image(
        &mut out,
        &Image {
            header,
            height: camera.height,
            width: camera.width,
            encoding: "16UC1".into(),
            is_bigendian: 0,
            step: camera.width * 2,
            data,
        },
    );
    out
}

/// The `sensor_msgs/msg/CameraInfo` of `camera`: K and P from its pinhole model, its distortion as `plumb_bob`
/// (up to 5 coefficients, padded with zeros to 5) or `rational_polynomial` (6 to 8, padded to 8), R the identity,
/// no binning, no region of interest.
pub fn camera_info(camera: &CameraIntrinsics, header: Header) -> CameraInfo {
    let (fx, fy, cx, cy) = (camera.fx, camera.fy, camera.cx, camera.cy);
    let (model, len) = if camera.distortion.len() <= 5 {
        ("plumb_bob", 5)
    } else {
        ("rational_polynomial", 8.max(camera.distortion.len()))
    };
    let mut d = camera.distortion.clone();
    d.resize(len, 0.0);
    CameraInfo {
        header,
        height: camera.height,
        width: camera.width,
        distortion_model: model.into(),
        d,
        k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        binning_x: 0,
        binning_y: 0,
        roi: [0; 4],
        roi_do_rectify: false,
    }
}

/// [`camera_info`], encoded.
pub fn camera_info_bytes(camera: &CameraIntrinsics, header: Header) -> Vec<u8> {
    let mut out = Vec::with_capacity(512);
    ros2::sensor::encode_camera_info(&mut out, &camera_info(camera, header));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(distortion: Vec<f64>) -> CameraIntrinsics {
        CameraIntrinsics {
            width: 4,
            height: 2,
            fx: 420.5,
            fy: 421.0,
            cx: 2.1,
            cy: 0.9,
            distortion,
        }
    }

    #[test]
    fn millimetres_pass_through_and_other_units_round_to_millimetres() {
        assert_eq!(depth_16uc1(&[0, 1, 65535], 0.001), [0, 0, 1, 0, 255, 255]);
        assert_eq!(
            depth_16uc1(&[0, 14, 15, 60000], 0.0001),
            [0, 0, 1, 0, 2, 0, 112, 23]
        );
        assert_eq!(depth_16uc1(&[2000], 0.1), [255, 255]);
    }

    #[test]
    fn camera_info_follows_realsense_ros() {
        let h = Header::new(RosTime { sec: 3, nanosec: 4 }, "camera_depth_optical_frame");
        let i = camera_info(&camera(vec![]), h.clone());
        assert_eq!(i.distortion_model, "plumb_bob");
        assert_eq!(i.d, [0.0; 5]);
        assert_eq!(i.k, [420.5, 0.0, 2.1, 0.0, 421.0, 0.9, 0.0, 0.0, 1.0]);
        assert_eq!(i.p[..4], [420.5, 0.0, 2.1, 0.0]);
        let i = camera_info(&camera(vec![0.1; 6]), h.clone());
        assert_eq!(i.distortion_model, "rational_polynomial");
        assert_eq!(i.d, [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0]);
        let decoded = ros2::sensor::decode_camera_info(&camera_info_bytes(&camera(vec![]), h));
        assert_eq!(decoded.unwrap().width, 4);
    }

    #[test]
    fn stamps_are_offset_plus_microseconds_and_overflow_is_an_error() {
        let t = stamp(1_700_000_000_000_000_000, 1_500_001).unwrap();
        assert_eq!(t.as_nanos(), 1_700_000_001_500_001_000);
        assert!(stamp(i64::MAX, 1).is_err());
        assert!(stamp(0, i64::MAX).is_err());
    }
}
