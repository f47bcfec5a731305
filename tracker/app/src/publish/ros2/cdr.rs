//! `geometry_msgs/msg/PoseStamped` in plain little-endian CDR: encoder, decoder and encoded length.

use super::*;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// A `builtin_interfaces/msg/Time`: seconds and nanoseconds since the ROS time epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct RosTime {
    /// Whole seconds (may be negative).
    pub sec: i32,
    /// Nanoseconds within the second, `0..1_000_000_000`.
    pub nanosec: u32,
}

impl RosTime {
    /// Splits a time in nanoseconds into seconds and a non-negative nanosecond part (floor division, as ROS does).
    pub fn from_nanos(nanos: i64) -> Result<Self, CdrError> {
        let sec = nanos.div_euclid(1_000_000_000);
        let nanosec = nanos.rem_euclid(1_000_000_000);
        let sec = i32::try_from(sec).map_err(|_| CdrError::TimeOutOfRange {
            nanos: nanos.into(),
        })?;
        // rem_euclid of a positive modulus is in 0..1e9, which fits u32.
        Ok(Self {
            sec,
            nanosec: nanosec as u32,
        })
    }

    /// The time in nanoseconds.
    pub fn as_nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }
}

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

/// Position and (x, y, z, w) orientation of an isometry, as they go on the wire.
pub fn pose_fields(pose: &Isometry3<f64>) -> ([f64; 3], [f64; 4]) {
    let t = &pose.translation.vector;
    let q = pose.rotation.quaternion();
    ([t.x, t.y, t.z], [q.i, q.j, q.k, q.w])
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
    out.clear();
    out.extend_from_slice(&CDR_LE_HEADER);
    out.extend_from_slice(&stamp.sec.to_le_bytes());
    out.extend_from_slice(&stamp.nanosec.to_le_bytes());
    // Frame ids are short configuration strings; saturate rather than panic on an absurd length.
    let len = u32::try_from(frame_id.len() + 1).unwrap_or(u32::MAX);
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(frame_id.as_bytes());
    out.push(0);
    let body = out.len() - CDR_LE_HEADER.len();
    let padded = body.next_multiple_of(8);
    out.resize(CDR_LE_HEADER.len() + padded, 0);
    for v in position.iter().chain(orientation_xyzw.iter()) {
        out.extend_from_slice(&v.to_le_bytes());
    }
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

/// Reads little-endian CDR fields with alignment counted from the end of the encapsulation header.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, field: &'static str, n: usize, align: usize) -> Result<&'a [u8], CdrError> {
        let body = self.pos - CDR_LE_HEADER.len();
        let start = CDR_LE_HEADER.len() + body.next_multiple_of(align);
        let truncated = CdrError::Truncated {
            field,
            offset: start,
            needed: n,
            len: self.bytes.len(),
        };
        let end = start.checked_add(n).ok_or_else(|| truncated.clone())?;
        let slice = self.bytes.get(start..end).ok_or(truncated)?;
        self.pos = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        let s = self.take(field, N, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.array::<8>(field)?))
    }
}

/// Decodes a CDR `geometry_msgs/msg/PoseStamped` as produced by [`encode_pose_stamped`] or by ROS 2 (rmw_zenoh,
/// little-endian). Never panics; bytes after the last field are ignored (as CDR readers do).
pub fn decode_pose_stamped(bytes: &[u8]) -> Result<PoseStampedMsg, CdrError> {
    let header: [u8; 4] =
        bytes
            .get(..4)
            .and_then(|h| h.try_into().ok())
            .ok_or(CdrError::Truncated {
                field: "encapsulation header",
                offset: 0,
                needed: 4,
                len: bytes.len(),
            })?;
    if header[..2] != CDR_LE_HEADER[..2] {
        return Err(CdrError::Encapsulation(header));
    }
    let mut r = Reader { bytes, pos: 4 };
    let sec = i32::from_le_bytes(r.array::<4>("header.stamp.sec")?);
    let nanosec = u32::from_le_bytes(r.array::<4>("header.stamp.nanosec")?);
    let len = u32::from_le_bytes(r.array::<4>("header.frame_id length")?) as usize;
    if len == 0 {
        return Err(CdrError::ZeroLengthString);
    }
    let s = r.take("header.frame_id", len, 1)?;
    let (nul, text) = s.split_last().ok_or(CdrError::ZeroLengthString)?;
    if *nul != 0 {
        return Err(CdrError::MissingNul);
    }
    let frame_id = std::str::from_utf8(text)
        .map_err(|_| CdrError::NotUtf8)?
        .to_owned();
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
        stamp: RosTime { sec, nanosec },
        frame_id,
        position,
        orientation_xyzw,
    })
}

/// Length in bytes of the CDR encoding of a PoseStamped with a frame id of `frame_id_len` bytes.
pub fn pose_stamped_encoded_len(frame_id_len: usize) -> usize {
    CDR_LE_HEADER.len() + (12 + frame_id_len + 1).next_multiple_of(8) + POSE_BYTES
}
