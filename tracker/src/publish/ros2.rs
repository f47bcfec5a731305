//! ROS 2 wire conventions for publishing poses through zenoh so that ROS 2 nodes running `rmw_zenoh_cpp` receive
//! them unchanged. Pure functions, no zenoh: the [`super::zenoh`] sink uses them, tests and receivers decode with them.
//!
//! - [`encode_pose_stamped`] / [`decode_pose_stamped`]: `geometry_msgs/msg/PoseStamped` in plain CDR, little-endian
//!   (encapsulation header `00 01 00 00`; alignment counted from the first byte after that header).
//! - [`pose_stamped_key_expr`]: the zenoh key expression rmw_zenoh derives for a topic,
//!   `<domain>/<topic without leading/trailing '/'>/<type name>/<type hash>`.
//! - [`Attachment`]: the 33 bytes rmw_zenoh attaches to every sample (sequence number, source timestamp, GID);
//!   rmw_zenoh subscribers drop samples without it.
//! - [`node_liveliness_key_expr`] / [`publisher_liveliness_key_expr`]: the liveliness tokens through which the
//!   ROS 2 graph (`ros2 node list`, `ros2 topic list`) discovers a node and its publishers.
//!
//! Layouts follow rmw_zenoh_cpp's `attachment_helpers.cpp`, `liveliness_utils.cpp`, `rmw_node_data.cpp`,
//! `rmw_publisher_data.cpp` and `qos.cpp` (see `docs/zenoh-ros2.md`).

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// ROS 2 type name of `geometry_msgs/msg/PoseStamped` as rmw_zenoh writes it into key expressions.
pub const POSE_STAMPED_TYPE_NAME: &str = "geometry_msgs::msg::dds_::PoseStamped_";

/// RIHS01 type hash of `geometry_msgs/msg/PoseStamped` (ROS 2 Jazzy and later), as rmw_zenoh writes it into keys.
pub const POSE_STAMPED_TYPE_HASH: &str =
    "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8";

/// CDR encapsulation header for little-endian plain CDR (`CDR_LE`, options 0).
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Size in bytes of rmw_zenoh's sample attachment.
pub const ATTACHMENT_LEN: usize = 33;

/// Size in bytes of a ROS 2 GID as rmw_zenoh stores it (`RMW_GID_STORAGE_SIZE`).
pub const GID_LEN: usize = 16;

/// Admin-space prefix of rmw_zenoh's liveliness tokens.
pub const LIVELINESS_ADMIN_SPACE: &str = "@ros2_lv";

/// QoS component of a liveliness token when every policy equals rmw_zenoh's default (reliable, volatile,
/// keep-last with depth 42, infinite deadline / lifespan / lease, automatic liveliness): each field is left empty.
pub const DEFAULT_QOS_KEY: &str = "::,:,:,:,,";

/// Bytes of a CDR-encoded PoseStamped after its frame id: 7 `f64` (position x, y, z; orientation x, y, z, w).
const POSE_BYTES: usize = 7 * 8;

/// Why bytes are not a valid CDR `PoseStamped` or rmw_zenoh attachment.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// The input ended before a field was complete.
    #[error("truncated: {field} needs {needed} bytes at offset {offset}, but the input has {len}")]
    Truncated {
        /// Field being read.
        field: &'static str,
        /// Byte offset (from the start of the input, header included) where the field starts.
        offset: usize,
        /// Bytes the field needs.
        needed: usize,
        /// Total input length.
        len: usize,
    },
    /// The encapsulation header is not little-endian plain CDR.
    #[error(
        "unsupported CDR encapsulation {0:02x?} (expected 00 01 00 00, little-endian plain CDR)"
    )]
    Encapsulation([u8; 4]),
    /// A string length of 0 (CDR strings count their terminating NUL, so the minimum is 1).
    #[error("frame_id: string length is 0 (CDR string lengths include the terminating NUL)")]
    ZeroLengthString,
    /// A string's last byte is not NUL.
    #[error("frame_id: string is not NUL-terminated")]
    MissingNul,
    /// A string contains bytes that are not UTF-8.
    #[error("frame_id: string is not valid UTF-8")]
    NotUtf8,
    /// A timestamp that does not fit ROS 2's `builtin_interfaces/Time` (`int32` seconds).
    #[error("time {nanos} ns is outside the range of builtin_interfaces/Time (int32 seconds)")]
    TimeOutOfRange {
        /// The time, nanoseconds.
        nanos: i128,
    },
    /// An attachment of the wrong size.
    #[error("attachment: {len} bytes, expected {ATTACHMENT_LEN}")]
    AttachmentLength {
        /// Length received.
        len: usize,
    },
    /// An attachment whose GID length prefix is not 16.
    #[error("attachment: GID length prefix is {0:#04x}, expected 0x10 (16 bytes)")]
    AttachmentGidLength(u8),
}

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

/// rmw_zenoh's per-sample attachment.
///
/// Wire layout (33 bytes, zenoh-ext serialization as in rmw_zenoh's `AttachmentData::serialize_to_zbytes`):
/// `0..8` sequence number `i64` LE; `8..16` source timestamp `i64` LE (ns since the Unix epoch, system clock);
/// `16` the GID's sequence length as a LEB128 varint, always `0x10`; `17..33` the 16 GID bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Attachment {
    /// Per-publisher sequence number; rmw_zenoh starts at 1 and increments by 1 per sample.
    pub sequence_number: i64,
    /// Publication time, nanoseconds since the Unix epoch (system clock).
    pub source_timestamp_ns: i64,
    /// The publisher's GID.
    pub gid: [u8; GID_LEN],
}

impl Attachment {
    /// The 33 wire bytes.
    pub fn to_bytes(&self) -> [u8; ATTACHMENT_LEN] {
        let mut b = [0u8; ATTACHMENT_LEN];
        b[0..8].copy_from_slice(&self.sequence_number.to_le_bytes());
        b[8..16].copy_from_slice(&self.source_timestamp_ns.to_le_bytes());
        b[16] = GID_LEN as u8;
        b[17..33].copy_from_slice(&self.gid);
        b
    }

    /// Parses the 33 wire bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CdrError> {
        let b: &[u8; ATTACHMENT_LEN] = bytes
            .try_into()
            .map_err(|_| CdrError::AttachmentLength { len: bytes.len() })?;
        if b[16] != GID_LEN as u8 {
            return Err(CdrError::AttachmentGidLength(b[16]));
        }
        let mut seq = [0u8; 8];
        seq.copy_from_slice(&b[0..8]);
        let mut ts = [0u8; 8];
        ts.copy_from_slice(&b[8..16]);
        let mut gid = [0u8; GID_LEN];
        gid.copy_from_slice(&b[17..33]);
        Ok(Self {
            sequence_number: i64::from_le_bytes(seq),
            source_timestamp_ns: i64::from_le_bytes(ts),
            gid,
        })
    }
}

/// Fully qualified ROS topic name: exactly one leading `/`, no trailing `/` (`eventtrack6d/a/pose` ->
/// `/eventtrack6d/a/pose`).
pub fn fully_qualified_topic(topic: &str) -> String {
    format!("/{}", topic.trim_matches('/'))
}

/// The zenoh key expression rmw_zenoh uses for a topic's data: `<domain>/<topic>/<type name>/<type hash>` with the
/// topic's leading and trailing `/` removed.
pub fn topic_key_expr(domain_id: u32, topic: &str, type_name: &str, type_hash: &str) -> String {
    format!(
        "{domain_id}/{}/{type_name}/{type_hash}",
        topic.trim_matches('/')
    )
}

/// The rmw_zenoh data key expression of a `geometry_msgs/msg/PoseStamped` topic.
pub fn pose_stamped_key_expr(domain_id: u32, topic: &str) -> String {
    topic_key_expr(
        domain_id,
        topic,
        POSE_STAMPED_TYPE_NAME,
        POSE_STAMPED_TYPE_HASH,
    )
}

/// rmw_zenoh's name mangling for liveliness key components: every `/` becomes `%`.
pub fn mangle_name(name: &str) -> String {
    name.replace('/', "%")
}

/// Identity of the ROS 2 node that a zenoh session presents to the ROS graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RosNodeIdentity {
    /// ROS domain id (`ROS_DOMAIN_ID`).
    pub domain_id: u32,
    /// The zenoh session id as zenoh prints it (`Session::zid().to_string()`).
    pub zid: String,
    /// Node entity id, unique within the session.
    pub node_id: u64,
    /// Security enclave, `/` by default.
    pub enclave: String,
    /// Node namespace, `/` for the root namespace.
    pub namespace: String,
    /// Node name.
    pub name: String,
}

impl RosNodeIdentity {
    fn prefix(&self, entity_id: u64, kind: &str) -> String {
        format!(
            "{LIVELINESS_ADMIN_SPACE}/{}/{}/{}/{entity_id}/{kind}/{}/{}/{}",
            self.domain_id,
            self.zid,
            self.node_id,
            mangle_name(&self.enclave),
            mangle_name(&self.namespace),
            mangle_name(&self.name),
        )
    }
}

/// Liveliness token of a node (entity kind `NN`; the entity id is the node id):
/// `@ros2_lv/<domain>/<zid>/<node id>/<node id>/NN/<enclave>/<namespace>/<name>`, each name mangled.
pub fn node_liveliness_key_expr(node: &RosNodeIdentity) -> String {
    node.prefix(node.node_id, "NN")
}

/// Liveliness token of a publisher (entity kind `MP`):
/// `@ros2_lv/<domain>/<zid>/<node id>/<entity id>/MP/<enclave>/<namespace>/<node name>/<topic>/<type>/<hash>/<qos>`,
/// where the topic is fully qualified and every name mangled (`/` -> `%`), and `qos` is rmw_zenoh's QoS string
/// ([`DEFAULT_QOS_KEY`] for the default profile).
pub fn publisher_liveliness_key_expr(
    node: &RosNodeIdentity,
    entity_id: u64,
    topic: &str,
    type_name: &str,
    type_hash: &str,
    qos: &str,
) -> String {
    format!(
        "{}/{}/{}/{}/{qos}",
        node.prefix(entity_id, "MP"),
        mangle_name(&fully_qualified_topic(topic)),
        mangle_name(type_name),
        mangle_name(type_hash),
    )
}

/// Checks that `name` is a valid ROS 2 name token (letters, digits and `_`, not starting with a digit), so that it
/// can appear in a topic name and in a zenoh key expression. Returns what is wrong otherwise.
pub fn check_name_token(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("is empty".into());
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        return Err("starts with a digit".into());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        return Err(format!(
            "contains {c:?} (only ASCII letters, digits and '_' are allowed)"
        ));
    }
    Ok(())
}

/// Checks a topic prefix or namespace made of `/`-separated name tokens (leading/trailing `/` ignored; `/` alone
/// or empty is the root and is valid).
pub fn check_name_path(path: &str) -> Result<(), String> {
    let trimmed = path.trim_matches('/');
    if trimmed.is_empty() {
        return Ok(());
    }
    for token in trimmed.split('/') {
        check_name_token(token).map_err(|e| format!("component {token:?} {e}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
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
        assert_eq!(decode_pose_stamped(&zero), Err(CdrError::ZeroLengthString));
        let mut no_nul = good.clone();
        no_nul[21] = b'!';
        assert_eq!(decode_pose_stamped(&no_nul), Err(CdrError::MissingNul));
        let mut bad_utf8 = good.clone();
        bad_utf8[16] = 0xFF;
        assert_eq!(decode_pose_stamped(&bad_utf8), Err(CdrError::NotUtf8));
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
            0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7, 0xA8, 0xA9, 0xAA, 0xAB, 0xAC, 0xAD,
            0xAE, 0xAF,
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
}
