//! `geometry_msgs/msg/PoseStamped` in plain little-endian CDR: encoder, decoder and encoded length.

use crate::header::{Header, Pose, RosTime, pose_fields};
use crate::wire::{CdrReader, CdrWriter};
use crate::{CDR_LE_HEADER, CdrError};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// Bytes of a CDR-encoded PoseStamped after its frame id: 7 `f64` (position x, y, z; orientation x, y, z, w).
const POSE_BYTES: usize = 7 * 8;

/// A decoded `geometry_msgs/msg/PoseStamped`.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseStampedMsg {
    /// `header.stamp`.
    pub stamp: RosTime,
    /// `header.frame_id`: the frame the pose is expressed in (the camera frame for this tracker).
    pub frame_id: String,
    /// `pose.position` (x, y, z), metres.
    pub position: [f64; 3],
    /// `pose.orientation` as (x, y, z, w).
    pub orientation_xyzw: [f64; 4],
}

impl PoseStampedMsg {
    /// The pose as an isometry (`T_frame_obj`); the quaternion is normalised.
    pub fn to_isometry(&self) -> Isometry3<f64> {
        let [x, y, z, w] = self.orientation_xyzw;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let [px, py, pz] = self.position;
        Isometry3::from_parts(Translation3::new(px, py, pz), q)
    }
}

/// Encodes `geometry_msgs/msg/PoseStamped` into `out` (cleared first; its capacity is reused, so steady-state
/// encoding allocates nothing once `out` has grown to the message size).
///
/// Layout (offsets from the start, the 4-byte encapsulation header included; CDR alignment is counted from byte 4):
/// `0` header `00 01 00 00`; `4` `i32 sec`; `8` `u32 nanosec`; `12` `u32` frame_id length including NUL; `16`
/// frame_id bytes and NUL; zero padding to the next multiple of 8 (relative to byte 4); then 7 `f64`: position x, y,
/// z and orientation x, y, z, w.
pub fn encode_pose_stamped(
    out: &mut Vec<u8>,
    stamp: RosTime,
    frame_id: &str,
    position: [f64; 3],
    orientation_xyzw: [f64; 4],
) {
    let mut w = CdrWriter::new(out);
    stamp.write(&mut w);
    w.string(frame_id);
    Pose {
        position,
        orientation_xyzw,
    }
    .write(&mut w);
}

/// Encodes an isometry (`T_frame_obj`) as `geometry_msgs/msg/PoseStamped`; see [`encode_pose_stamped`].
pub fn encode_pose_stamped_isometry(
    out: &mut Vec<u8>,
    stamp: RosTime,
    frame_id: &str,
    pose: &Isometry3<f64>,
) {
    let (position, orientation) = pose_fields(pose);
    encode_pose_stamped(out, stamp, frame_id, position, orientation);
}

/// Decodes a CDR `geometry_msgs/msg/PoseStamped` as produced by [`encode_pose_stamped`] or by ROS 2 (rmw_zenoh,
/// little-endian). Never panics; bytes after the last field are ignored (as CDR readers do).
pub fn decode_pose_stamped(bytes: &[u8]) -> Result<PoseStampedMsg, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = Header::read(&mut r)?;
    let position = [
        r.f64("pose.position.x")?,
        r.f64("pose.position.y")?,
        r.f64("pose.position.z")?,
    ];
    let orientation_xyzw = [
        r.f64("pose.orientation.x")?,
        r.f64("pose.orientation.y")?,
        r.f64("pose.orientation.z")?,
        r.f64("pose.orientation.w")?,
    ];
    Ok(PoseStampedMsg {
        stamp: header.stamp,
        frame_id: header.frame_id,
        position,
        orientation_xyzw,
    })
}

/// Length in bytes of the CDR encoding of a PoseStamped with a frame id of `frame_id_len` bytes.
pub fn pose_stamped_encoded_len(frame_id_len: usize) -> usize {
    CDR_LE_HEADER.len() + (12 + frame_id_len + 1).next_multiple_of(8) + POSE_BYTES
}
